//! PlaMo's dynamic path planner (paper section 4.1).
//!
//! Stages, one module each: instruction parsing ([`parse_instructions`]), slope-aware
//! A* on the terrain grid (`astar`, with connected-component labels in
//! `connectivity` so unreachable targets fail fast), the refiner (`refine`: line of
//! sight, smoothing, head height under ceilings), the minimum-time speed profile
//! ([`solve_speed_qp`], checked against the exact [`forward_backward`] oracle), timing
//! ([`Trajectory::sample_at`], [`Trajectory::next_waypoints`]) and re-planning around
//! dynamic obstacles ([`predict_conflict`]). [`Planner`] ties them together and is
//! stepped with the humanoid's state. All parameters live in [`PlannerSettings`].
//!
//! Pure computation: no transport, no clocks, deterministic.
#![warn(missing_docs)]

mod alt;
mod astar;
mod component;
mod connectivity;
mod dynamic;
mod error;
mod grid;
mod instructions;
mod planner;
mod refine;
mod settings;
mod speed_oracle;
mod speed_qp;
pub mod synthetic;
mod timing;
mod wait;

pub use alt::{ALT_ACTIVE, AltLandmarks};
pub use astar::{AStar, CrawlBody, GridPath, Heuristic, Posture, SearchLimits};
pub use component::{FLAG_FINISHED, FLAG_INFEASIBLE, FLAG_REPLANNED, PlannerComponent};
pub use connectivity::{BLOCKED, Components};
pub use dynamic::{
    Conflict, External, ExternalObstacle, Prediction, predict, predict_conflict,
    predict_conflict_with,
};
pub use error::{PlanError, SpeedFailure, UnreachableReason};
pub use grid::PlanGrid;
pub use instructions::{
    Instruction, Locomotion, Source, VALID_VERBS, instruction_forms, parse_instructions,
};
pub use planner::{
    PlanStatus, Planner, PlannerInput, PlannerOutput, Progress, ReplanReason, START_HEADING_SPAN,
};
pub use refine::PathPoint;
pub use settings::PlannerSettings;
pub use speed_oracle::{SpeedProblem, forward_backward, travel_time};
pub use speed_qp::{solve_speed_qp, solve_speed_socp};
pub use timing::{Trajectory, Waypoint};
pub use wait::plan_wait;

#[cfg(test)]
pub(crate) mod test_scenes {
    pub use crate::synthetic::*;
}
