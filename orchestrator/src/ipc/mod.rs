//! Components as separate processes over iceoryx2 shared memory.
//!
//! A component process runs [`serve`]: it waits for a request, calls the same
//! [`Component::step`](plamo_interfaces::Component::step) the in-process orchestrator
//! calls, and answers. The orchestrator holds one [`RemoteComponent`] per process.
//! Pub/sub carries the payloads, an event service per direction wakes the peer
//! (iceoryx2 pub/sub has no blocking receive), and waits happen in short slices so a
//! dead peer is noticed (a SIGKILLed process is not signalled).

mod affinity;
mod client;
mod envelope;
mod error;
mod liveness;
mod server;
mod setup;
mod stale;

pub use affinity::CorePin;
pub use client::RemoteComponent;
pub use envelope::{Envelope, EnvelopeKind};
pub use error::IpcError;
pub use liveness::{NodeRole, dead_nodes, end_run, remove_stale_resources};
pub use server::{ORCHESTRATOR_NODE, serve};
pub use setup::{Channels, FILE_PREFIX, IpcSettings, run_config};
pub use stale::{StaleRun, clean_stale_runs, run_files};
