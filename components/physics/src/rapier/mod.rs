//! The rapier backend: rapier3d 0.36 (f32), reduced-coordinate multibody humanoids,
//! a Z-up world (gravity along -Z).
//!
//! - `world.rs`: terrain height field, walls, ceilings, kinematic obstacles.
//! - `humanoid.rs`: the multibody humanoid, PD through implicit joint springs.

mod humanoid;
mod world;

use std::panic::{AssertUnwindSafe, catch_unwind};

use plamo_interfaces::{PHYSICS_DT, Tick};
use plamo_scenes::{ObstacleState, Scene};
use rapier3d::prelude::*;

use crate::obstacles::ObstacleMotions;
use crate::state::sanitize_action;
use crate::{
    BackendKind, HumanoidPose, HumanoidState, PhysicsBackend, PhysicsError, PhysicsSettings,
    RootWrench,
};
use humanoid::RapierHumanoid;
use world::SceneHandles;
#[cfg(feature = "mujoco")]
pub(crate) use world::validate_terrain;

/// The rapier implementation of [`PhysicsBackend`].
pub struct RapierBackend {
    world: PhysicsWorld,
    settings: PhysicsSettings,
    handles: SceneHandles,
    humanoids: Vec<RapierHumanoid>,
    states: Vec<HumanoidState>,
    obstacles: Vec<ObstacleState>,
    motions: ObstacleMotions,
    tick: Tick,
    /// Set when a step diverged; cleared when every humanoid has been reset since.
    diverged: Vec<bool>,
}

impl RapierBackend {
    /// Build the world for `scene`; humanoid `i` starts standing on the terrain at
    /// (scene-origin + 1 m + 1.5 m * i, centre y), facing +X. Callers normally `reset`.
    pub fn new(scene: &Scene, settings: &PhysicsSettings) -> Result<Self, PhysicsError> {
        settings.validate()?;
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::new(0.0, 0.0, -settings.gravity as f32);
        world.integration_parameters.dt = PHYSICS_DT as f32;
        world.integration_parameters.num_solver_iterations = settings.rapier_solver_iterations;
        // One compliance for every contact, as MuJoCo has one `solref` (see the setting).
        let hz = settings.rapier_contact_hz as f32;
        world
            .integration_parameters
            .contact_softness
            .natural_frequency = hz;
        world
            .integration_parameters
            .static_contact_softness
            .natural_frequency = hz;
        let handles = world::build_scene(&mut world, scene, settings)?;
        let mut humanoids = Vec::with_capacity(settings.humanoids);
        for i in 0..settings.humanoids {
            let pose = default_pose(scene, i);
            humanoids.push(RapierHumanoid::build(
                &mut world,
                &pose,
                settings.friction,
                settings.rapier_root_torque_per_step,
            ));
        }
        let motions = ObstacleMotions::new(scene);
        let obstacles = motions.states_at(0.0).collect();
        let mut backend = Self {
            world,
            settings: settings.clone(),
            handles,
            states: vec![HumanoidState::default(); humanoids.len()],
            diverged: vec![false; humanoids.len()],
            humanoids,
            obstacles,
            motions,
            tick: Tick(0),
        };
        for i in 0..backend.humanoids.len() {
            backend.read_state(i);
        }
        Ok(backend)
    }

    fn read_state(&mut self, i: usize) {
        self.humanoids[i].read_state(&self.world, self.handles.terrain, &mut self.states[i]);
    }
}

/// One contact point the solver saw between a humanoid's body and the scene at the
/// last step ([`RapierBackend::body_contacts`]): what holds a foot against sliding
/// and turning (rapier has no torsional friction, so only the tangential friction at
/// these points resists a yaw torque).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactPoint {
    /// Index of the solver manifold (a contact plane) among the body's manifolds.
    pub manifold: usize,
    /// The point on the body, in the body's frame \[m\].
    pub local: [f64; 3],
    /// Separation along the normal (negative: penetration) \[m\].
    pub dist: f64,
    /// Normal impulse applied at the last step \[N s\].
    pub impulse: f64,
    /// Tangential (friction) impulse applied at the last step, its magnitude \[N s\].
    pub tangent_impulse: f64,
    /// The manifold's contact normal, world frame, pointing away from the body.
    pub normal: [f64; 3],
}

impl RapierBackend {
    /// Every contact point the constraint solver used at the last step between body
    /// `body` ([`crate::BODY_NAMES`] order) of humanoid `index` and the scene, and the
    /// number of per-subshape manifolds the narrow phase produced before rapier merged
    /// those of one plane into its solver's clusters (at most 4 points each); none for
    /// a body index past the last. A diagnostic for the physics examples (`foot_yaw_hold`);
    /// the controller never reads it.
    pub fn body_contacts(
        &self,
        index: usize,
        body: usize,
    ) -> Result<(Vec<ContactPoint>, usize), PhysicsError> {
        PhysicsError::check_index(index, self.humanoids.len())?;
        Ok(self.humanoids[index].body_contacts(&self.world, body))
    }
}

/// Where humanoid `i` stands when the world is created.
pub(crate) fn default_pose(scene: &Scene, i: usize) -> HumanoidPose {
    let (lo, hi) = scene.terrain.bounds();
    let x = (lo[0] + 1.0 + 1.5 * i as f64).min(hi[0]);
    let y = 0.5 * (lo[1] + hi[1]);
    HumanoidPose::standing_on(&scene.terrain, x, y, 0.0)
}

impl PhysicsBackend for RapierBackend {
    fn kind(&self) -> BackendKind {
        BackendKind::Rapier
    }

    fn num_humanoids(&self) -> usize {
        self.humanoids.len()
    }

    fn tick(&self) -> Tick {
        self.tick
    }

    fn reset_humanoid(&mut self, index: usize, pose: &HumanoidPose) -> Result<(), PhysicsError> {
        PhysicsError::check_index(index, self.humanoids.len())?;
        pose.validate()?;
        self.humanoids[index].remove(&mut self.world);
        self.humanoids[index] = RapierHumanoid::build(
            &mut self.world,
            pose,
            self.settings.friction,
            self.settings.rapier_root_torque_per_step,
        );
        self.diverged[index] = false;
        self.read_state(index);
        Ok(())
    }

    fn set_action_for(
        &mut self,
        index: usize,
        targets: &[f64],
        root_wrench: Option<RootWrench>,
    ) -> Result<(), PhysicsError> {
        PhysicsError::check_index(index, self.humanoids.len())?;
        let (targets, wrench) = sanitize_action(
            targets,
            root_wrench,
            self.settings.max_root_force,
            self.settings.max_root_torque,
        )?;
        let h = &mut self.humanoids[index];
        h.targets = targets;
        h.wrench = wrench;
        Ok(())
    }

    fn step(&mut self) -> Result<(), PhysicsError> {
        if self.diverged.iter().any(|d| *d) {
            return Err(PhysicsError::still_diverged(BackendKind::Rapier, self.tick));
        }
        let t_next = self.tick.advanced(1).seconds();
        world::drive_obstacles(&mut self.world, &self.motions, &self.handles, t_next);
        for h in &mut self.humanoids {
            h.apply_controls(&mut self.world);
        }
        // rapier may panic on a degenerate state; report it as a divergence.
        let world = &mut self.world;
        let stepped = catch_unwind(AssertUnwindSafe(|| world.step()));
        self.tick = self.tick.advanced(1);
        if stepped.is_err() {
            self.diverged.iter_mut().for_each(|d| *d = true);
            return Err(PhysicsError::diverged(
                BackendKind::Rapier,
                self.tick,
                "rapier panicked inside the step",
            ));
        }
        for (o, s) in self
            .obstacles
            .iter_mut()
            .zip(self.motions.states_at(t_next))
        {
            *o = s;
        }
        let quarantined = !self.world.quarantine().is_empty();
        let mut bad = None;
        for i in 0..self.humanoids.len() {
            self.read_state(i);
            let why = if quarantined {
                Some("rapier quarantined a body".to_string())
            } else {
                self.states[i].unphysical()
            };
            if let Some(why) = why {
                self.diverged[i] = true;
                bad.get_or_insert((i, why));
            }
        }
        match bad {
            Some((i, why)) => Err(PhysicsError::diverged(
                BackendKind::Rapier,
                self.tick,
                format!("humanoid {i}: {why}"),
            )),
            None => Ok(()),
        }
    }

    fn humanoid_state(&self, index: usize) -> Result<&HumanoidState, PhysicsError> {
        PhysicsError::check_index(index, self.humanoids.len())?;
        Ok(&self.states[index])
    }

    fn obstacles(&self) -> &[ObstacleState] {
        &self.obstacles
    }

    fn drive_obstacle(&mut self, index: usize, state: ObstacleState) -> Result<(), PhysicsError> {
        self.motions.drive(index, state, self.tick.seconds())
    }
}
