//! Physics settings: one flat struct, units and defaults on every field.

use crate::PhysicsError;

/// Settings shared by both backends. Every field documents its unit and default;
/// [`PhysicsSettings::validate`] checks ranges (called by [`crate::create_backend`]).
///
/// Deserializes from a TOML table naming only the fields to change (`plamo run
/// --physics-params`); unknown fields are refused. `humanoids` is not read from a
/// file: the physics component sets it from the agents' placements.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PhysicsSettings {
    /// Number of humanoids in the world (default 1). Humanoids collide with the
    /// scene but not with each other (batched rollouts share one world).
    #[serde(skip)]
    pub humanoids: usize,
    /// Gravity magnitude along -Z \[m/s^2\] (default 9.81).
    pub gravity: f64,
    /// Coulomb friction coefficient of every contact (default 1.0).
    pub friction: f64,
    /// rapier: solver iterations per step (default 4, rapier's own default), which
    /// rapier 0.36 runs as that many substeps of `dt / n`, each re-integrating the
    /// multibody (the servo springs too) and solving contacts and joint limits once.
    /// CPU per step is about linear in it: 1.6x that of 2 at 4, 2.95x at 8.
    /// BENCHMARKS.md "rapier solver settings": the random tours' falls over 40 scenes
    /// are 205 at 2, 118 at 4 (the crouch-walk's 133, 65) and 82 at 8 (70 without
    /// the servo's substep compensation); Table 2's crouch-walk falls per minute
    /// (flat/slope/rough/stairs) 14/12/16/10 at 2, 4/0/6/10 at 4, 4/4/8/10 at 8.
    /// 1 falls in the controller's walk tests. Cheaper knobs (internal PGS
    /// iterations, contact stiffness, no contact recycling) did not help.
    pub rapier_solver_iterations: usize,
    /// rapier: natural frequency of every contact's soft constraint \[Hz\] (default 11;
    /// rapier's own defaults are 60 against fixed geometry and 30 between moving
    /// bodies, both with damping ratio 10, which is kept). MuJoCo's contacts (default
    /// `solref` 0.02 s, `solimp` 0.9-0.95) leave a loaded foot far more compliance than
    /// rapier's 60 Hz, and the feet's compliance sets how the body sways over its
    /// ankles: a standing humanoid pushed at the pelvis (150 N for 0.1 s) peaks at a
    /// pitch of 0.102 rad in MuJoCo, 0.073 rad in rapier at 60 Hz and 0.084 rad at
    /// 11 Hz (pitch over 3 s: RMS difference 0.049 rad at 60 Hz, 0.013 at 11 Hz; 8, 10,
    /// 12 and 14 Hz: 0.022, 0.007, 0.018, 0.026, and on another grid alignment 12 Hz
    /// is best and 10 Hz worse, 11 Hz good on both). A gait tuned in MuJoCo fell in its
    /// crouch-walk on the stiffer feet (BENCHMARKS.md "rapier contact compliance").
    /// Cross-backend test `pushed_standing_sway_agrees_across_backends`. Costs nothing.
    pub rapier_contact_hz: f64,
    /// rapier: the root wrench's torque acts in its step only (default true; false
    /// is the behaviour before session 14, kept to replay older figures). rapier
    /// 0.36's `reset_forces` clears only `add_force`'s force; `add_torque`'s torque
    /// stays until `reset_torques`, so with false every step's root torque is added to
    /// the sum of all before it, where the trait holds a wrench until the next call.
    /// Floating without gravity under 10 N m of yaw torque the pelvis turns at 2.45
    /// rad/s after 0.5 s in MuJoCo, 2.41 with this and 30.7 without (`foot_yaw_hold
    /// free`; tests in `tests/root_torque.rs`); the controllers' residual torque
    /// (capped at 60 N m a step) acted as its own integral, and the crouch-walk's spin
    /// in rapier was that sum. RESULTS.md "Rapier's root torque was summed over the
    /// steps (session 13)" and "the crawl under the torque per step (session 14)".
    pub rapier_root_torque_per_step: bool,
    /// rapier: the terrain height field corrects contact normals at its triangles'
    /// inner edges (parry's `FIX_INTERNAL_EDGES`; default false). Without it a foot or
    /// knee sliding over a tile's seam can meet the next triangle's edge and get a
    /// sideways push (a "ghost" collision) that a smooth surface would not give.
    /// Measured (RESULTS.md "Rapier's height field without ghost edges", session 25):
    /// rapier tours, seeds 0-199, 114 -> 114 of 200 (first falls on rough ground
    /// 34 -> 19, on stairs 24 -> 28, flat 11 -> 18); Table 2 mixed. Off: no gain.
    pub rapier_fix_internal_edges: bool,
    /// MuJoCo: maximum constraint-solver (Newton) iterations per step (default 50;
    /// MuJoCo's own default is 100, it converges in a few).
    pub mujoco_solver_iterations: usize,
    /// Bound on the root residual force \[N\] (default 2000, ~3 m g). Larger requests
    /// are scaled down to this norm (documented clamping, not an error).
    pub max_root_force: f64,
    /// Bound on the root residual torque \[N m\] (default 1000). Larger requests are
    /// scaled down to this norm.
    pub max_root_torque: f64,
    /// Thickness of the terrain below its lowest sample \[m\] (default 1.0): the
    /// height field's solid base.
    pub terrain_base: f64,
}

impl Default for PhysicsSettings {
    fn default() -> Self {
        Self {
            humanoids: 1,
            gravity: 9.81,
            friction: 1.0,
            rapier_solver_iterations: 4,
            rapier_contact_hz: 11.0,
            rapier_root_torque_per_step: true,
            rapier_fix_internal_edges: false,
            mujoco_solver_iterations: 50,
            max_root_force: 2000.0,
            max_root_torque: 1000.0,
            terrain_base: 1.0,
        }
    }
}

impl PhysicsSettings {
    /// Check every field against its documented range.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        let bad = |field: &'static str, reason: &str| {
            Err(PhysicsError::InvalidSettings {
                field,
                reason: reason.to_string(),
            })
        };
        if !(1..=64).contains(&self.humanoids) {
            return bad("humanoids", "must be in 1..=64");
        }
        if !(self.gravity.is_finite() && self.gravity >= 0.0) {
            return bad("gravity", "must be finite and >= 0");
        }
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return bad("friction", "must be finite and >= 0");
        }
        if !(1..=64).contains(&self.rapier_solver_iterations) {
            return bad("rapier_solver_iterations", "must be in 1..=64");
        }
        if !(self.rapier_contact_hz.is_finite() && (1.0..=1000.0).contains(&self.rapier_contact_hz))
        {
            return bad("rapier_contact_hz", "must be finite and in 1..=1000");
        }
        if !(1..=1000).contains(&self.mujoco_solver_iterations) {
            return bad("mujoco_solver_iterations", "must be in 1..=1000");
        }
        if !(self.max_root_force.is_finite() && self.max_root_force >= 0.0) {
            return bad("max_root_force", "must be finite and >= 0");
        }
        if !(self.max_root_torque.is_finite() && self.max_root_torque >= 0.0) {
            return bad("max_root_torque", "must be finite and >= 0");
        }
        if !(self.terrain_base.is_finite() && self.terrain_base > 0.0) {
            return bad("terrain_base", "must be finite and > 0");
        }
        Ok(())
    }
}
