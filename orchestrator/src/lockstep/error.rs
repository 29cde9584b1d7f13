//! Errors of a run, separate from its outcome (reached, fell, timed out).

use plamo_interfaces::ComponentError;

use crate::ipc::IpcError;

/// Why a run stopped before its end.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// A component's own step failed (in-process).
    #[error("{component} failed at tick {tick}: {source}")]
    Component {
        /// Which component instance (`physics`, `planner-0`, ...).
        component: String,
        /// The tick.
        tick: u64,
        /// Its error.
        #[source]
        source: ComponentError,
    },
    /// The transport to a component process failed (it died, hung or erred).
    #[error(transparent)]
    Ipc(#[from] IpcError),
    /// A component answered with a message stamped for another tick or agent.
    #[error("{component}: expected a message for tick {expected}, got tick {got}")]
    WrongTick {
        /// Which component instance.
        component: String,
        /// The tick asked for.
        expected: u64,
        /// The tick answered.
        got: u64,
    },
    /// The run could not be set up (scene, planner, physics, processes).
    #[error("setting up the run: {0}")]
    Setup(String),
}
