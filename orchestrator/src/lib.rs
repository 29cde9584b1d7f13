//! The PlaMo orchestrator: runs planner, controller and physics in lockstep, and the
//! pictures and recordings the `plamo` CLI writes.
#![warn(missing_docs)]

pub mod eval;
pub mod export;
pub mod fmu_package;
pub mod ipc;
pub mod lockstep;
pub mod processes;
pub mod progress;
pub mod record;
pub mod seeds;
pub mod spec;
pub mod tune_tours;
pub mod viz;
