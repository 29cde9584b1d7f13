//! Errors of the IPC transport, separate from what a component reports.

use std::time::Duration;

/// Why a remote call or a component server failed.
#[derive(Debug, thiserror::Error)]
pub enum IpcError {
    /// iceoryx2 refused to create or open something.
    #[error("iceoryx2: {what} failed: {detail}")]
    Setup {
        /// What was being created or opened.
        what: String,
        /// iceoryx2's error.
        detail: String,
    },
    /// The peer did not answer in time.
    #[error("{component} did not answer within {timeout:?} (tick {tick})")]
    Timeout {
        /// Which component.
        component: String,
        /// The tick waited for.
        tick: u64,
        /// How long we waited.
        timeout: Duration,
    },
    /// The peer process died.
    #[error("{component} died (detected while waiting for tick {tick}): {detail}")]
    PeerDied {
        /// Which component (or "orchestrator").
        component: String,
        /// The tick waited for.
        tick: u64,
        /// How it was noticed.
        detail: String,
    },
    /// The peer answered for another tick.
    #[error("{component}: expected a response for tick {expected}, got tick {got}")]
    WrongTick {
        /// Which component.
        component: String,
        /// The tick the request carried.
        expected: u64,
        /// The tick the response carried.
        got: u64,
    },
    /// The peer sent a frame we cannot interpret.
    #[error("{component}: malformed frame (kind {kind})")]
    Malformed {
        /// Which component.
        component: String,
        /// The raw kind value.
        kind: u32,
    },
    /// The component's own step failed; the text is its error.
    #[error("{component} failed at tick {tick}: {message}")]
    Component {
        /// Which component.
        component: String,
        /// The tick.
        tick: u64,
        /// The component's error message.
        message: String,
    },
    /// A component started by hand was started for another run than this one.
    #[error(
        "{component} was started for another run: it has `{got}`, this run is `{expected}`; \
         start it with the command this run printed"
    )]
    Mismatch {
        /// Which component.
        component: String,
        /// This run's identity.
        expected: String,
        /// The component's.
        got: String,
    },
    /// The orchestrator asked the component to stop.
    #[error("shutdown requested")]
    Shutdown,
}

/// Wrap any iceoryx2 error as [`IpcError::Setup`].
pub(crate) fn setup<E: std::fmt::Debug>(what: impl Into<String>) -> impl FnOnce(E) -> IpcError {
    let what = what.into();
    move |e| IpcError::Setup {
        what,
        detail: format!("{e:?}"),
    }
}
