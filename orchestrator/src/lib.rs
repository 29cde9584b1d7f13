//! The PlaMo orchestrator: runs planner, controller and physics in lockstep, and the
//! pictures and recordings the `plamo` CLI writes.
#![warn(missing_docs)]

pub mod ipc;
pub mod viz;
