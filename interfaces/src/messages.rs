//! The `#[repr(C)]` messages components exchange, in shared memory when they run as
//! separate processes and by reference in-process. Fixed-capacity arrays with counts,
//! no pointers, every message stamped with its tick.
//!
//! Several humanoids share one world: physics messages carry every agent, planner and
//! controller messages carry one agent's data and its index.

use iceoryx2_bb_derive_macros::ZeroCopySend;
use iceoryx2_bb_elementary_traits::zero_copy_send::ZeroCopySend;

/// Most actuated joints a humanoid may have.
pub const MAX_JOINTS: usize = 48;
/// Most rigid bodies a humanoid may have.
pub const MAX_BODIES: usize = 24;
/// Most humanoids in one world.
pub const MAX_AGENTS: usize = 8;
/// Most dynamic obstacles (scene-driven plus externally driven) in one world.
pub const MAX_OBSTACLES: usize = 16;
/// Plan waypoints the controller sees (paper 4.2: the next 5 s, 10 samples).
pub const PLAN_WAYPOINTS: usize = 10;
/// Time between plan waypoints \[s\].
pub const PLAN_WAYPOINT_DT: f64 = 0.5;
/// Samples of the controller's local height map (8 x 8 spanning 0.8 m).
pub const HEIGHT_MAP_SAMPLES: usize = 64;

/// Kinematic state of one humanoid as physics reports it. World frame, Z up.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[repr(C)]
#[type_name("plamo::HumanoidState")]
pub struct HumanoidState {
    /// Root (pelvis) position \[m\].
    pub root_position: [f64; 3],
    /// Root orientation as a unit quaternion (x, y, z, w).
    pub root_orientation: [f64; 4],
    /// Root linear velocity \[m/s\].
    pub root_linear_velocity: [f64; 3],
    /// Root angular velocity \[rad/s\].
    pub root_angular_velocity: [f64; 3],
    /// Head position \[m\].
    pub head_position: [f64; 3],
    /// Valid entries of `joint_angles` / `joint_velocities`.
    pub joint_count: u32,
    /// Valid entries of `body_positions`.
    pub body_count: u32,
    /// Joint angles \[rad\], in the humanoid's documented joint order.
    pub joint_angles: [f64; MAX_JOINTS],
    /// Joint velocities \[rad/s\].
    pub joint_velocities: [f64; MAX_JOINTS],
    /// Every body's world position \[m\], in the humanoid's body order.
    pub body_positions: [[f64; 3]; MAX_BODIES],
    /// Bit b set: body b touches something other than itself.
    pub body_contacts: u32,
    /// Non-zero when the humanoid has fallen (per the physics' fall rule).
    pub fallen: u32,
}

impl Default for HumanoidState {
    fn default() -> Self {
        Self {
            root_position: [0.0; 3],
            root_orientation: [0.0, 0.0, 0.0, 1.0],
            root_linear_velocity: [0.0; 3],
            root_angular_velocity: [0.0; 3],
            head_position: [0.0; 3],
            joint_count: 0,
            body_count: 0,
            joint_angles: [0.0; MAX_JOINTS],
            joint_velocities: [0.0; MAX_JOINTS],
            body_positions: [[0.0; 3]; MAX_BODIES],
            body_contacts: 0,
            fallen: 0,
        }
    }
}

impl HumanoidState {
    /// The valid entries of `body_positions` (a count past the array is cut to it).
    pub fn bodies(&self) -> &[[f64; 3]] {
        &self.body_positions[..(self.body_count as usize).min(self.body_positions.len())]
    }
}

/// Position and velocity of one dynamic obstacle.
#[derive(Debug, Clone, Copy, PartialEq, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("plamo::ObstacleSample")]
pub struct ObstacleSample {
    /// Centre \[m\].
    pub position: [f64; 3],
    /// Velocity \[m/s\].
    pub velocity: [f64; 3],
}

/// What physics reports after stepping to `tick`.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[repr(C)]
#[type_name("plamo::PhysicsOutput")]
pub struct PhysicsOutput {
    /// The tick this state belongs to.
    pub tick: u64,
    /// Valid entries of `agents`.
    pub agent_count: u32,
    /// Valid entries of `obstacles`.
    pub obstacle_count: u32,
    /// Each humanoid's state.
    pub agents: [HumanoidState; MAX_AGENTS],
    /// Each dynamic obstacle's state, scene obstacles first, then external ones.
    pub obstacles: [ObstacleSample; MAX_OBSTACLES],
}

impl Default for PhysicsOutput {
    fn default() -> Self {
        Self {
            tick: 0,
            agent_count: 0,
            obstacle_count: 0,
            agents: [HumanoidState::default(); MAX_AGENTS],
            obstacles: [ObstacleSample::default(); MAX_OBSTACLES],
        }
    }
}

/// [`AgentAction::command`]: drive the joints to `pd_targets` (and apply the wrench).
pub const ACTION_TRACK: u32 = 1;
/// [`AgentAction::command`]: put the humanoid back at rest in the pose
/// [`AgentAction::reset`] describes (how the orchestrator recovers a fallen humanoid);
/// targets and wrench are ignored.
pub const ACTION_RESET: u32 = 2;
/// [`ResetPose::form`]: standing in the rest pose, feet on the ground.
pub const RESET_STAND: u32 = 1;
/// [`ResetPose::form`]: on hands and knees (head ~0.4 m), for a plan that crawls or
/// a top overhead.
pub const RESET_CRAWL: u32 = 2;

/// Layout version of the messages: 2 added [`AgentAction::reset`] (the reset's
/// place, heading and form; version 1 reset in place, standing). Both ends of an IPC
/// link must agree; iceoryx2 refuses a service whose payload size differs.
pub const MESSAGE_LAYOUT_VERSION: u32 = 2;

/// Where and how an [`ACTION_RESET`] puts a humanoid back.
#[derive(Debug, Clone, Copy, PartialEq, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("plamo::ResetPose")]
pub struct ResetPose {
    /// Pelvis origin x, y \[m\]; physics puts the body on the terrain there.
    pub position: [f64; 2],
    /// Heading about +Z \[rad\] (0 faces +X).
    pub yaw: f64,
    /// [`RESET_STAND`] or [`RESET_CRAWL`]; 0 (a zeroed request) is refused.
    pub form: u32,
    /// Zero; keeps the layout free of padding.
    pub reserved: u32,
}
/// [`PhysicsInput::mode`]: step nothing, report the world at its current tick (the
/// orchestrator's first read). Zero, so a zeroed input can never move the world.
pub const PHYSICS_OBSERVE: u32 = 0;
/// [`PhysicsInput::mode`]: apply every agent's action and take four 1/120 s steps.
pub const PHYSICS_STEP: u32 = 1;

/// One humanoid's actuation for the next control period.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[repr(C)]
#[type_name("plamo::AgentAction")]
pub struct AgentAction {
    /// The control tick this action was computed at.
    pub tick: u64,
    /// Index of the humanoid.
    pub agent: u32,
    /// Valid entries of `pd_targets`.
    pub joint_count: u32,
    /// What to do: [`ACTION_TRACK`] or [`ACTION_RESET`]; 0 (a zeroed action) is
    /// refused, so an action nobody filled in is an error, not a silent reset.
    pub command: u32,
    /// Zero; keeps the layout free of padding.
    pub reserved: u32,
    /// PD target angle per joint \[rad\].
    pub pd_targets: [f64; MAX_JOINTS],
    /// Residual root wrench, world frame: force \[N\] then torque \[N m\]; zeros when
    /// the policy uses none.
    pub root_wrench: [f64; 6],
    /// With [`ACTION_RESET`]: the pose to put the humanoid back in (ignored otherwise).
    pub reset: ResetPose,
}

impl Default for AgentAction {
    fn default() -> Self {
        Self {
            tick: 0,
            agent: 0,
            joint_count: 0,
            command: 0,
            reserved: 0,
            pd_targets: [0.0; MAX_JOINTS],
            root_wrench: [0.0; 6],
            reset: ResetPose::default(),
        }
    }
}

/// Physics input for one control period: every humanoid's action, plus obstacles
/// driven from outside (an FMU host's car or ball).
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[repr(C)]
#[type_name("plamo::PhysicsInput")]
pub struct PhysicsInput {
    /// The control tick; physics steps from here to `tick + 4`.
    pub tick: u64,
    /// Valid entries of `actions`.
    pub agent_count: u32,
    /// Valid entries of `external_obstacles`.
    pub external_count: u32,
    /// [`PHYSICS_OBSERVE`] (the default) or [`PHYSICS_STEP`].
    pub mode: u32,
    /// Zero; keeps the layout free of padding.
    pub reserved: u32,
    /// One action per humanoid.
    pub actions: [AgentAction; MAX_AGENTS],
    /// Externally driven obstacles' states for this period.
    pub external_obstacles: [ObstacleSample; MAX_OBSTACLES],
}

impl Default for PhysicsInput {
    fn default() -> Self {
        Self {
            tick: 0,
            agent_count: 0,
            external_count: 0,
            mode: PHYSICS_OBSERVE,
            reserved: 0,
            actions: [AgentAction::default(); MAX_AGENTS],
            external_obstacles: [ObstacleSample::default(); MAX_OBSTACLES],
        }
    }
}

/// One planned sample: head position and speed at a time.
#[derive(Debug, Clone, Copy, PartialEq, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("plamo::PlanWaypoint")]
pub struct PlanWaypoint {
    /// Head position \[m\].
    pub position: [f64; 3],
    /// Planned speed \[m/s\].
    pub speed: f64,
}

/// The planner's answer for one agent at a control tick.
#[derive(Debug, Clone, Copy, PartialEq, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("plamo::PlanMessage")]
pub struct PlanMessage {
    /// The control tick.
    pub tick: u64,
    /// Index of the humanoid.
    pub agent: u32,
    /// Index of the instruction being executed.
    pub instruction: u32,
    /// Number of instructions.
    pub instruction_count: u32,
    /// Bit 0: all instructions done; bit 1: re-planned this tick; bit 2: infeasible.
    pub flags: u32,
    /// Progress along the current instruction's path, 0..1.
    pub progress: f64,
    /// Requested head height of the current locomotion \[m\].
    pub form_height: f64,
    /// The next waypoints, `PLAN_WAYPOINT_DT` apart, starting one step ahead.
    pub waypoints: [PlanWaypoint; PLAN_WAYPOINTS],
}

/// Planner input: the world as physics last reported it.
pub type PlannerInput = PhysicsOutput;

/// Controller input for one agent: its state, its plan and the terrain around it.
#[derive(Debug, Clone, Copy, PartialEq, Default, ZeroCopySend)]
#[repr(C)]
#[type_name("plamo::ControllerInput")]
pub struct ControllerInput {
    /// The control tick.
    pub tick: u64,
    /// Index of the humanoid.
    pub agent: u32,
    /// Padding kept explicit so the layout is the same on every platform.
    pub reserved: u32,
    /// The humanoid's state at `tick`.
    pub state: HumanoidState,
    /// The current plan.
    pub plan: PlanMessage,
}

/// Controller output: one agent's action.
pub type ControllerOutput = AgentAction;

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_zero_copy<T: ZeroCopySend>() {}

    #[test]
    fn messages_are_shared_memory_types_of_bounded_size() {
        assert_zero_copy::<PhysicsInput>();
        assert_zero_copy::<PhysicsOutput>();
        assert_zero_copy::<PlanMessage>();
        assert_zero_copy::<ControllerInput>();
        // Fixed layout: sizes are part of the IPC contract; a change must be deliberate.
        assert_eq!(
            core::mem::size_of::<HumanoidState>(),
            8 * (3 + 4 + 3 + 3 + 3) + 8 + 8 * 96 + 8 * 72 + 8
        );
        assert!(core::mem::size_of::<PhysicsOutput>() < 16 * 1024);
        // Layout version 2 (MESSAGE_LAYOUT_VERSION): the reset pose ends the action.
        assert_eq!(MESSAGE_LAYOUT_VERSION, 2);
        assert_eq!(core::mem::size_of::<ResetPose>(), 32);
        assert_eq!(
            core::mem::size_of::<AgentAction>(),
            8 + 4 * 4 + 8 * MAX_JOINTS + 8 * 6 + 32
        );
    }
}
