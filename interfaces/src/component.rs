//! The one component trait. The orchestrator owns schedule and transport; a component
//! sees only ticks and messages, so the same `step` runs in-process and over IPC.

use crate::Tick;

/// What a step did, separate from errors (which are bad input or broken invariants).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// The step ran; keep going.
    Continue,
    /// The component has nothing more to do (e.g. the planner finished the last
    /// instruction).
    Finished,
}

/// Errors every component can report through the transport, whatever it is.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum ComponentError {
    /// The input was stamped with a tick other than the one the component expected.
    #[error("{component}: expected input for tick {expected}, got tick {got}")]
    WrongTick {
        /// Component name.
        component: &'static str,
        /// The tick the component was waiting for.
        expected: u64,
        /// The tick the message carried.
        got: u64,
    },
    /// The input held a value outside its documented range (NaN, wrong length, ...).
    #[error("{component}: invalid input `{field}`: {reason}")]
    InvalidInput {
        /// Component name.
        component: &'static str,
        /// Which input field.
        field: &'static str,
        /// What was wrong and what is allowed.
        reason: String,
    },
    /// The component failed internally (physics diverged, planner found no path, ...).
    #[error("{component}: {reason}")]
    Failed {
        /// Component name.
        component: &'static str,
        /// What failed.
        reason: String,
    },
}

/// A PlaMo component (planner, controller, physics).
pub trait Component {
    /// The message the component reads each step.
    type Input;
    /// The message the component writes each step.
    type Output;
    /// Short stable name used in errors, logs and service names.
    const NAME: &'static str;

    /// Advance one step at `tick`, reading `input` and overwriting `output`.
    fn step(
        &mut self,
        tick: Tick,
        input: &Self::Input,
        output: &mut Self::Output,
    ) -> Result<Outcome, ComponentError>;
}
