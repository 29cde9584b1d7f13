//! Shared contracts between PlaMo components: simulated time, the component trait,
//! the `#[repr(C)]` messages exchanged over iceoryx2, and per-run service naming.
//!
//! Nothing here is transport: a component implements [`Component`] over these
//! messages and is stepped the same way in-process and behind an iceoryx2 server.
#![warn(missing_docs)]

mod component;
mod messages;
mod naming;
mod timing;

pub use component::{Component, ComponentError, Outcome};
pub use messages::{
    ACTION_RESET, ACTION_TRACK, AgentAction, ControllerInput, ControllerOutput, HEIGHT_MAP_SAMPLES,
    HumanoidState, MAX_AGENTS, MAX_BODIES, MAX_JOINTS, MAX_OBSTACLES, MESSAGE_LAYOUT_VERSION,
    ObstacleSample, PHYSICS_OBSERVE, PHYSICS_STEP, PLAN_WAYPOINT_DT, PLAN_WAYPOINTS, PhysicsInput,
    PhysicsOutput, PlanMessage, PlanWaypoint, PlannerInput, RESET_CRAWL, RESET_STAND, ResetPose,
};
pub use naming::{ComponentKind, RunId, ServiceNames};
pub use timing::{CONTROL_DT, CONTROL_HZ, PHYSICS_DT, PHYSICS_HZ, PHYSICS_STEPS_PER_CONTROL, Tick};
