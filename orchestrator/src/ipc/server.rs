//! The generic component server: one per component process. It knows nothing about
//! which component it serves; it calls the same `step` the in-process run calls.

use std::fmt::Debug;
use std::time::{Duration, Instant};

use iceoryx2::node::NodeView;
use iceoryx2::prelude::*;
use plamo_interfaces::{Component, ServiceNames, Tick};

use super::envelope::{Envelope, EnvelopeKind};
use super::error::IpcError;
use super::setup::{Channels, IpcSettings};

/// The orchestrator's node name; components watch for it.
pub const ORCHESTRATOR_NODE: &str = "plamo-orchestrator";

/// Tick value of the ready handshake frame (no real tick reaches it).
pub const READY_TICK: u64 = u64::MAX;

/// A busy component looks for a termination request (SIGTERM/SIGINT) every this
/// many requests, an idle one every wait slice: `Node::wait` is a nanosleep, too
/// costly to pay on every request of a fast lockstep.
const TERMINATION_EVERY: u64 = 64;

/// How often a component repeats its ready frame in its first [`READY_FAST_FOR`]
/// while no request came, then once per wait slice.
const READY_REPEAT: Duration = Duration::from_millis(1);

/// How long a component repeats its ready frame every [`READY_REPEAT`]: an
/// orchestrator that opened its link after the component's first frame (one started
/// by hand before it) hears from it within a millisecond, and a component waiting
/// longer for its turn (`--attach`) does not send a thousand frames a second.
const READY_FAST_FOR: Duration = Duration::from_millis(200);

/// How often an idle component looks for its orchestrator.
const LIVENESS_EVERY: u32 = 4;

fn orchestrator_alive(cfg: &Config) -> bool {
    let mut alive = false;
    let _ = Node::<ipc::Service>::list(cfg, |state| {
        if let NodeState::Alive(view) = &state
            && view
                .details()
                .as_ref()
                .is_some_and(|d| d.name().as_str() == ORCHESTRATOR_NODE)
        {
            alive = true;
            return CallbackProgression::Stop;
        }
        CallbackProgression::Continue
    });
    alive
}

/// Serve `component` on `names` until the orchestrator says shutdown (Ok), dies, or
/// the process is asked to terminate (Err). Announces readiness, with `identity`
/// (what run the component was built for; the orchestrator checks it), until the
/// first request arrives, because frames sent before the peer's ports exist are lost.
pub fn serve<C>(
    component: &mut C,
    node: &Node<ipc::Service>,
    names: &ServiceNames,
    settings: &IpcSettings,
    identity: &str,
) -> Result<u64, IpcError>
where
    C: Component,
    C::Input: ZeroCopySend + Copy + Debug + Default + 'static,
    C::Output: ZeroCopySend + Copy + Debug + Default + 'static,
{
    let ch: Channels<C::Output, C::Input> = Channels::open(
        node,
        &names.response,
        &names.request,
        &names.response_event,
        &names.request_event,
    )?;
    let mut served = 0u64;
    let mut idle_slices = 0u32;
    let mut idle_since = Instant::now();
    let started = idle_since;
    ch.send(Envelope::ready(READY_TICK, identity))?;
    loop {
        // Until the first request the orchestrator may not have its ports yet:
        // announce again (it drops the duplicates).
        let wait = if served == 0 && started.elapsed() < READY_FAST_FOR {
            READY_REPEAT.min(settings.slice)
        } else {
            settings.slice
        };
        let Some(frame) = ch.receive_within(wait)? else {
            if served == 0 {
                ch.send(Envelope::ready(READY_TICK, identity))?;
            }
            // A wake-up without a frame (the notification of one already taken) is
            // not a slice of idleness.
            if idle_since.elapsed() < settings.slice / 2 {
                continue;
            }
            idle_since = Instant::now();
            if node.wait(Duration::ZERO).is_err() {
                return Err(IpcError::Shutdown);
            }
            idle_slices += 1;
            if idle_slices.is_multiple_of(LIVENESS_EVERY) && !orchestrator_alive(node.config()) {
                return Err(IpcError::PeerDied {
                    component: "orchestrator".into(),
                    tick: 0,
                    detail: format!("no live `{ORCHESTRATOR_NODE}` node in this run"),
                });
            }
            continue;
        };
        idle_slices = 0;
        idle_since = Instant::now();
        if served.is_multiple_of(TERMINATION_EVERY) && node.wait(Duration::ZERO).is_err() {
            return Err(IpcError::Shutdown);
        }
        match frame.kind() {
            Some(EnvelopeKind::Data) => {
                let mut out = C::Output::default();
                let reply = match component.step(Tick(frame.tick), &frame.payload, &mut out) {
                    Ok(_) => Envelope::new(EnvelopeKind::Data, frame.tick, out),
                    Err(e) => Envelope::error(frame.tick, &e.to_string()),
                };
                ch.send(reply)?;
                served += 1;
            }
            Some(EnvelopeKind::Shutdown) => return Ok(served),
            _ => {
                ch.send(Envelope::error(
                    frame.tick,
                    &format!("{}: malformed request (kind {})", C::NAME, frame.kind),
                ))?;
            }
        }
    }
}
