//! Shared contracts between PlaMo components: simulated time, the component trait,
//! and (added with the orchestrator) the `#[repr(C)]` messages exchanged over iceoryx2.
//!
//! Nothing here knows about transport: a component implements [`Component`] and is
//! stepped the same way in-process and behind an iceoryx2 server.
#![warn(missing_docs)]

mod component;
mod timing;

pub use component::{Component, ComponentError, Outcome};
pub use timing::{CONTROL_DT, CONTROL_HZ, PHYSICS_DT, PHYSICS_HZ, PHYSICS_STEPS_PER_CONTROL, Tick};
