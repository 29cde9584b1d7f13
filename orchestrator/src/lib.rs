//! The PlaMo orchestrator: runs planner, controller and physics in lockstep.
#![warn(missing_docs)]
