//! The backend trait, the runtime selector and the one constructor callers use.

use std::fmt;
use std::str::FromStr;

use plamo_interfaces::Tick;
use plamo_scenes::{ObstacleState, Scene};

use crate::{
    HumanoidPose, HumanoidState, ParseBackendKindError, PhysicsError, PhysicsSettings, RootWrench,
};

/// Which physics engine simulates the world (`--physics rapier|mujoco`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum BackendKind {
    /// rapier3d 0.36, pure Rust, reduced-coordinate multibody (the default).
    #[default]
    Rapier,
    /// MuJoCo 3.17.0 through mujoco-rs (cargo feature `mujoco`).
    Mujoco,
}

impl BackendKind {
    /// Every kind, in the order `--help` lists them.
    pub const ALL: [BackendKind; 2] = [BackendKind::Rapier, BackendKind::Mujoco];

    /// The lower-case name used on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            BackendKind::Rapier => "rapier",
            BackendKind::Mujoco => "mujoco",
        }
    }

    /// Whether this build includes the backend.
    pub fn is_available(self) -> bool {
        match self {
            BackendKind::Rapier => true,
            BackendKind::Mujoco => cfg!(feature = "mujoco"),
        }
    }
}

impl fmt::Display for BackendKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for BackendKind {
    type Err = ParseBackendKindError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "rapier" => Ok(BackendKind::Rapier),
            "mujoco" => Ok(BackendKind::Mujoco),
            _ => Err(ParseBackendKindError {
                given: s.to_string(),
            }),
        }
    }
}

/// One physics world: the scene plus `settings.humanoids` humanoids, stepped at
/// [`plamo_interfaces::PHYSICS_DT`]. World frame, Z up, metres, radians.
///
/// Time starts at tick 0 when the backend is created and only moves forward;
/// dynamic obstacles are kinematic and sit at `motion.state_at(tick / 120)`.
/// Every humanoid starts standing at the origin region until `reset_humanoid`.
///
/// Contract shared by both implementations (checked by the conformance suite):
/// - `set_action_for` holds PD targets and a root wrench until the next call;
///   targets outside the joint limits are clamped, wrenches are scaled into
///   `PhysicsSettings::max_root_{force,torque}`; NaN/infinite inputs or a wrong
///   length are errors and leave the previous action in place.
/// - A PD target means the same joint angle in both backends (see [`crate::humanoid`]).
/// - The same inputs give bit-identical states, run after run.
/// - A state no humanoid can have after a step (non-finite or impossibly fast,
///   [`crate::HumanoidState::unphysical`]) is [`PhysicsError::Diverged`]; the world
///   then refuses to step until every humanoid is reset.
pub trait PhysicsBackend: Send {
    /// Which engine this is.
    fn kind(&self) -> BackendKind;
    /// Humanoids in the world.
    fn num_humanoids(&self) -> usize;
    /// Current tick: the number of steps taken since creation.
    fn tick(&self) -> Tick;
    /// Put humanoid `index` at `pose`, at rest, with PD targets equal to the pose's
    /// joint angles and no root wrench.
    fn reset_humanoid(&mut self, index: usize, pose: &HumanoidPose) -> Result<(), PhysicsError>;
    /// Set humanoid `index`'s PD targets (\[rad\], [`crate::JOINT_NAMES`] order,
    /// length [`crate::NUM_JOINTS`]) and optional root wrench.
    fn set_action_for(
        &mut self,
        index: usize,
        targets: &[f64],
        root_wrench: Option<RootWrench>,
    ) -> Result<(), PhysicsError>;
    /// Advance the world by one step of 1/120 s.
    fn step(&mut self) -> Result<(), PhysicsError>;
    /// State of humanoid `index` after the last step or reset.
    fn humanoid_state(&self, index: usize) -> Result<&HumanoidState, PhysicsError>;
    /// Dynamic obstacle states, in `scene.dynamic` order, at the current tick.
    fn obstacles(&self) -> &[ObstacleState];
    /// From the current tick on, move dynamic obstacle `index` (in `scene.dynamic`
    /// order) from `state.position` at the constant `state.velocity` instead of by
    /// its scene motion, until driven again: how an FMU host's ball or car enters the
    /// world. It stays kinematic and pushes what it hits. A jump of more than 1 m
    /// within one step (a host placing it) moves it without a sweep.
    fn drive_obstacle(&mut self, index: usize, state: ObstacleState) -> Result<(), PhysicsError>;

    /// [`Self::reset_humanoid`] for humanoid 0.
    fn reset(&mut self, pose: &HumanoidPose) -> Result<(), PhysicsError> {
        self.reset_humanoid(0, pose)
    }
    /// [`Self::set_action_for`] humanoid 0.
    fn set_action(
        &mut self,
        targets: &[f64],
        root_wrench: Option<RootWrench>,
    ) -> Result<(), PhysicsError> {
        self.set_action_for(0, targets, root_wrench)
    }
    /// State of humanoid 0.
    fn state(&self) -> &HumanoidState {
        // Every world has at least one humanoid (validated in `PhysicsSettings`).
        self.humanoid_state(0).expect("humanoid 0 always exists")
    }
    /// `n` steps; stops at the first error.
    fn step_n(&mut self, n: usize) -> Result<(), PhysicsError> {
        for _ in 0..n {
            self.step()?;
        }
        Ok(())
    }
}

/// Build a world for `scene` with the chosen engine. The one code path for callers:
/// `create_backend(args.physics, &scene, &PhysicsSettings::default())`.
pub fn create_backend(
    kind: BackendKind,
    scene: &Scene,
    settings: &PhysicsSettings,
) -> Result<Box<dyn PhysicsBackend>, PhysicsError> {
    settings.validate()?;
    match kind {
        BackendKind::Rapier => Ok(Box::new(crate::rapier::RapierBackend::new(
            scene, settings,
        )?)),
        #[cfg(feature = "mujoco")]
        BackendKind::Mujoco => Ok(Box::new(crate::mujoco::MujocoBackend::new(
            scene, settings,
        )?)),
        #[cfg(not(feature = "mujoco"))]
        BackendKind::Mujoco => Err(PhysicsError::Unavailable {
            kind,
            reason: "built without the `mujoco` feature of plamo-physics \
                     (run scripts/install-mujoco.sh, then build with --features plamo-physics/mujoco)",
        }),
    }
}
