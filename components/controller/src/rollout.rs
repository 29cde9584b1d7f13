//! Closed-loop rollouts: physics + observation + policy + metrics at 30/120 Hz, for
//! tests, examples and parameter tuning. The orchestrator runs the real lockstep; this
//! is the controller's own test bench on a straight constant-speed path (paper
//! Table 2's protocol) and on an arc (heading control).

use plamo_interfaces::PHYSICS_STEPS_PER_CONTROL;
use plamo_physics::{
    BackendKind, HEAD, HumanoidPose, HumanoidState, PhysicsBackend, PhysicsSettings, create_backend,
};
use plamo_scenes::{HeightGrid, Scene};

use crate::ModelBasedController;
use crate::error::Result;
use crate::fall_ground::FallBody;
use crate::metrics::{MetricsAccumulator, MetricsSummary, PathRewardWeights, StepSample};
use crate::observation::{
    HumanoidSnapshot, NUM_WAYPOINTS, Observation, WAYPOINT_SPACING, Waypoint,
};
use crate::policy::{Action, Policy};
use crate::settings::ControllerSettings;

impl From<&HumanoidState> for HumanoidSnapshot {
    fn from(s: &HumanoidState) -> Self {
        HumanoidSnapshot {
            root_pos: s.root_position,
            root_quat: s.root_quat,
            root_lin_vel: s.root_linvel,
            root_ang_vel: s.root_angvel,
            head_pos: s.head,
            joint_pos: s.joint_pos.to_vec(),
            joint_vel: s.joint_vel.to_vec(),
            body_pos: s.body_pos.to_vec(),
        }
    }
}

/// A straight path along +X at constant speed and head height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StraightPath {
    /// Start of the head path (x, y) \[m\].
    pub start: [f64; 2],
    /// Speed \[m/s\].
    pub speed: f64,
    /// Head height above the terrain \[m\].
    pub head_height: f64,
}

impl StraightPath {
    /// The plan's head point at time `t` \[s\] on `scene`.
    pub fn at(&self, scene: &Scene, t: f64) -> Waypoint {
        let x = self.start[0] + self.speed * t.max(0.0);
        let y = self.start[1];
        Waypoint {
            x,
            y,
            z: scene.height_at(x, y) + self.head_height,
            v: self.speed,
        }
    }
}

/// A straight path whose head height rises to standing (1.47 m) at `up_at` \[s\]: a
/// crawl or crouch that must get up again.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RisingPath {
    /// The path before it rises.
    pub line: StraightPath,
    /// When the head height rises \[s\].
    pub up_at: f64,
}

impl HeadPath for RisingPath {
    fn point(&self, scene: &Scene, t: f64) -> Waypoint {
        let mut w = self.line.at(scene, t);
        if t >= self.up_at {
            w.z += 1.47 - self.line.head_height;
        }
        w
    }
    fn direction(&self, _t: f64) -> [f64; 2] {
        [1.0, 0.0]
    }
    fn head_height(&self) -> f64 {
        self.line.head_height
    }
}

/// A straight plan along +X that walks from rest (accelerating at 1 m/s^2 to
/// `walk_speed`, head 1.47 m) and, from `drop_at`, goes on at `crawl_speed` with the
/// head at `head_height`: the get-down from a walk, as a tour's leg into a crawl (or a
/// crouch-walk) starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DropPath {
    /// Start of the head path (x, y) \[m\].
    pub start: [f64; 2],
    /// Speed of the walk before the drop \[m/s\].
    pub walk_speed: f64,
    /// Speed after the drop \[m/s\].
    pub crawl_speed: f64,
    /// Head height above the terrain after the drop \[m\].
    pub head_height: f64,
    /// When the head height drops \[s\].
    pub drop_at: f64,
}

impl DropPath {
    /// Distance along +X \[m\] and speed \[m/s\] at `t` \[s\].
    fn travel(&self, t: f64) -> (f64, f64) {
        // 1 m/s^2: the ramp lasts `walk_speed` seconds.
        let ramp = self.walk_speed;
        let walk = |t: f64| {
            if t < ramp {
                (0.5 * t * t, t)
            } else {
                (self.walk_speed * (t - 0.5 * ramp), self.walk_speed)
            }
        };
        let t = t.max(0.0);
        if t < self.drop_at {
            walk(t)
        } else {
            let (d, _) = walk(self.drop_at);
            (d + self.crawl_speed * (t - self.drop_at), self.crawl_speed)
        }
    }
}

impl HeadPath for DropPath {
    fn point(&self, scene: &Scene, t: f64) -> Waypoint {
        let (d, v) = self.travel(t);
        let (x, y) = (self.start[0] + d, self.start[1]);
        let head = if t < self.drop_at {
            plamo_physics::humanoid::STANDING_HEAD_HEIGHT
        } else {
            self.head_height
        };
        Waypoint {
            x,
            y,
            z: scene.height_at(x, y) + head,
            v,
        }
    }
    fn direction(&self, _t: f64) -> [f64; 2] {
        [1.0, 0.0]
    }
    fn head_height(&self) -> f64 {
        self.head_height
    }
}

/// Acceleration from rest of the bench paths (tuning, `plamo eval locomotion`)
/// \[m/s^2\]: a little below the gait's own rate limit (2.5 m/s^2), so a walker that
/// keeps up is not left behind by the start.
pub const START_ACCEL: f64 = 2.0;

/// A [`StraightPath`] that starts from rest: its speed rises at `accel` to the line's
/// speed, then stays. A standing humanoid cannot be at 4 m/s at t = 0: on the instant
/// path the lag of the start (v^2 / 2a behind, 3.2 m at 4 m/s with the gait's own
/// 2.5 m/s^2) stays for the whole run and hides the steady tracking error. The planner
/// ramps too (its a_max, 0.5 m/s^2 in the paper).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RampedPath {
    /// The path at full speed.
    pub line: StraightPath,
    /// Acceleration from rest \[m/s^2\], > 0.
    pub accel: f64,
}

impl RampedPath {
    /// Distance along the line \[m\] and speed \[m/s\] at time `t` \[s\].
    fn travel(&self, t: f64) -> (f64, f64) {
        let t = t.max(0.0);
        let v = self.line.speed;
        let t_ramp = v / self.accel;
        if t < t_ramp {
            (0.5 * self.accel * t * t, self.accel * t)
        } else {
            (v * t - 0.5 * v * t_ramp, v)
        }
    }
}

impl HeadPath for RampedPath {
    fn point(&self, scene: &Scene, t: f64) -> Waypoint {
        let (d, v) = self.travel(t);
        let (x, y) = (self.line.start[0] + d, self.line.start[1]);
        Waypoint {
            x,
            y,
            z: scene.height_at(x, y) + self.line.head_height,
            v,
        }
    }
    fn direction(&self, _t: f64) -> [f64; 2] {
        [1.0, 0.0]
    }
    fn head_height(&self) -> f64 {
        self.line.head_height
    }
}

/// A path that turns at a corner: along +X for `first` metres (from rest at `accel` up
/// to `speed`, braking at `accel` to `corner_speed` at the corner), then off at `turn`
/// \[rad\] (positive left), from `corner_speed` up to `speed` again. In the random
/// tours every landmark is such a corner and most legs turn back (2-3 rad); the
/// planner starts the new leg at about the speed the body arrives with (0.6-0.9 m/s
/// in the tours' crouch-walk legs), so the body has to reverse while the plan already
/// leads off sideways or behind it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TurnPath {
    /// Start of the head path (x, y) \[m\].
    pub start: [f64; 2],
    /// Speed between the ramps \[m/s\], > 0.
    pub speed: f64,
    /// Speed at the corner \[m/s\], in \[0, `speed`\].
    pub corner_speed: f64,
    /// Head height above the terrain \[m\].
    pub head_height: f64,
    /// Length of the first leg \[m\], at least `speed^2 / accel`.
    pub first: f64,
    /// Turn at the corner, positive to the left \[rad\].
    pub turn: f64,
    /// Acceleration and braking \[m/s^2\], > 0.
    pub accel: f64,
}

impl TurnPath {
    /// Time and distance it takes to go from `v0` to `v1` at `accel`.
    fn ramp(&self, v0: f64, v1: f64) -> (f64, f64) {
        let t = (v1 - v0).abs() / self.accel;
        (t, 0.5 * (v0 + v1) * t)
    }

    /// Position (x, y), speed and direction of travel \[rad\] at time `t`.
    fn pose(&self, t: f64) -> ([f64; 2], f64, f64) {
        let (v, a, vc) = (self.speed, self.accel, self.corner_speed);
        let t = t.max(0.0);
        let (t_up, d_up) = self.ramp(0.0, v);
        let (t_down, d_down) = self.ramp(vc, v);
        let t_cruise = (self.first - d_up - d_down).max(0.0) / v;
        let t1 = t_up + t_cruise + t_down;
        if t < t1 {
            let (s, vel) = if t < t_up {
                (0.5 * a * t * t, a * t)
            } else if t < t_up + t_cruise {
                (d_up + v * (t - t_up), v)
            } else {
                let r = t1 - t;
                (self.first - vc * r - 0.5 * a * r * r, vc + a * r)
            };
            return ([self.start[0] + s, self.start[1]], vel, 0.0);
        }
        let tau = t - t1;
        let (s, vel) = if tau < t_down {
            (vc * tau + 0.5 * a * tau * tau, vc + a * tau)
        } else {
            (d_down + v * (tau - t_down), v)
        };
        let (sin, cos) = self.turn.sin_cos();
        (
            [
                self.start[0] + self.first + s * cos,
                self.start[1] + s * sin,
            ],
            vel,
            self.turn,
        )
    }
}

impl HeadPath for TurnPath {
    fn point(&self, scene: &Scene, t: f64) -> Waypoint {
        let ([x, y], v, _) = self.pose(t);
        Waypoint {
            x,
            y,
            z: scene.height_at(x, y) + self.head_height,
            v,
        }
    }
    fn direction(&self, t: f64) -> [f64; 2] {
        let (_, _, h) = self.pose(t);
        [h.cos(), h.sin()]
    }
    fn head_height(&self) -> f64 {
        self.head_height
    }
}

/// A head path the rollout follows: the plan's point at time `t` and the path's
/// direction there.
pub trait HeadPath {
    /// The plan's head point at time `t` \[s\] on `scene`.
    fn point(&self, scene: &Scene, t: f64) -> Waypoint;
    /// Unit direction of travel (x, y) at time `t`.
    fn direction(&self, t: f64) -> [f64; 2];
    /// Requested head height above the terrain \[m\].
    fn head_height(&self) -> f64;
}

impl HeadPath for StraightPath {
    fn point(&self, scene: &Scene, t: f64) -> Waypoint {
        self.at(scene, t)
    }
    fn direction(&self, _t: f64) -> [f64; 2] {
        [1.0, 0.0]
    }
    fn head_height(&self) -> f64 {
        self.head_height
    }
}

/// A path along +X for `straight` metres, then a circular arc of `radius` (positive
/// turns left), at constant speed and head height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcPath {
    /// Start of the head path (x, y) \[m\].
    pub start: [f64; 2],
    /// Speed \[m/s\].
    pub speed: f64,
    /// Head height above the terrain \[m\].
    pub head_height: f64,
    /// Straight run before the turn \[m\].
    pub straight: f64,
    /// Turn radius, positive to the left \[m\].
    pub radius: f64,
}

impl ArcPath {
    /// Position (x, y) and heading \[rad\] after `s` metres.
    fn pose(&self, s: f64) -> ([f64; 2], f64) {
        let s = s.max(0.0);
        if s <= self.straight || self.radius == 0.0 {
            return ([self.start[0] + s, self.start[1]], 0.0);
        }
        let a = (s - self.straight) / self.radius;
        let (sin, cos) = a.sin_cos();
        (
            [
                self.start[0] + self.straight + self.radius * sin,
                self.start[1] + self.radius * (1.0 - cos),
            ],
            a,
        )
    }
}

impl HeadPath for ArcPath {
    fn point(&self, scene: &Scene, t: f64) -> Waypoint {
        let ([x, y], _) = self.pose(self.speed * t);
        Waypoint {
            x,
            y,
            z: scene.height_at(x, y) + self.head_height,
            v: self.speed,
        }
    }
    fn direction(&self, t: f64) -> [f64; 2] {
        let (_, h) = self.pose(self.speed * t);
        [h.cos(), h.sin()]
    }
    fn head_height(&self) -> f64 {
        self.head_height
    }
}

/// A flat scene long enough for a straight rollout of `length` metres along +X.
pub fn flat_scene(length: f64) -> Scene {
    Scene {
        name: "flat".into(),
        description: "controller test bench".into(),
        terrain: HeightGrid::flat([-5.0, -10.0], [length + 10.0, 20.0], 0.1, 0.0),
        walls: vec![],
        dynamic: vec![],
        tops: vec![],
        landmarks: vec![],
    }
}

/// A [`flat_scene`] with a 0.6 m ceiling (the playground's tunnel height) over x in
/// \[2.5, 4.5\] m, 2 m wide: the bench for crawling under a low top.
pub fn ceiling_scene(length: f64) -> Scene {
    top_scene(length, 0.6)
}

/// A [`flat_scene`] with a top `clearance` \[m\] over the ground, 0.2 m thick, over x
/// in \[2.5, 4.5\] m, 2 m wide.
pub fn top_scene(length: f64, clearance: f64) -> Scene {
    let mut scene = flat_scene(length);
    scene.tops.push(plamo_scenes::TopObstacle {
        name: "tunnel".into(),
        footprint: plamo_scenes::Footprint::axis_aligned([3.5, 0.0], [1.0, 1.0]),
        z_bottom: clearance,
        z_top: clearance + 0.2,
    });
    scene
}

/// A [`flat_scene`] with a ledge `height` \[m\] up across the path from x = 4 m on:
/// a random scene's slope or stair tile seen from its side, where the planner lets
/// paths cross steps up to its `max_step_height`. The bench for a crawl's step-up.
pub fn ledge_scene(length: f64, height: f64) -> Scene {
    let mut scene = flat_scene(length);
    scene.name = format!("ledge-{height}");
    let grid = &mut scene.terrain;
    for j in 0..grid.ny {
        for i in 0..grid.nx {
            if grid.position(i, j)[0] >= LEDGE_AT - 1e-9 {
                grid.heights[j * grid.nx + i] = height;
            }
        }
    }
    scene
}

/// Where [`ledge_scene`]'s ledge rises, along +X \[m\].
pub const LEDGE_AT: f64 = 4.0;

/// Length of the built-in terrain strips from where a run starts on them \[m\]
/// (`terrain-*` scenes, x 5 -> 35 m; see [`crate::terrain_scene`]).
pub const STRIP_LENGTH: f64 = 30.0;

/// How much further along +X each run of a sweep starts \[m\]: every run meets the
/// terrain at another phase of its steps.
pub const RUN_STAGGER: f64 = 0.37;

/// Where run `r` of a sweep starts from `origin`: [`RUN_STAGGER`] further along +X
/// per run and -0.1, 0 or 0.1 m sideways in turn.
pub fn staggered_start(origin: [f64; 2], r: usize) -> [f64; 2] {
    [
        origin[0] + RUN_STAGGER * r as f64,
        origin[1] + 0.1 * (r % 3) as f64 - 0.1,
    ]
}

/// Runs `policy` along `path` for `duration` \[s\] with the chosen physics engine. A
/// fall is counted, and the humanoid is put back standing on the plan's current
/// point (ProtoMotions-style reset).
pub fn run_straight(
    backend: BackendKind,
    scene: &Scene,
    path: StraightPath,
    duration: f64,
    policy: &mut dyn Policy,
    settings: &ControllerSettings,
) -> Result<MetricsSummary> {
    run_path(backend, scene, &path, duration, policy, settings)
}

/// Runs `policy` along any [`HeadPath`] (see [`run_straight`]).
pub fn run_path(
    backend: BackendKind,
    scene: &Scene,
    path: &dyn HeadPath,
    duration: f64,
    policy: &mut dyn Policy,
    settings: &ControllerSettings,
) -> Result<MetricsSummary> {
    let physics = PhysicsSettings::default();
    run_path_with(backend, &physics, scene, path, duration, policy, settings)
}

/// [`run_path`] with physics settings other than the defaults.
pub fn run_path_with(
    backend: BackendKind,
    physics: &PhysicsSettings,
    scene: &Scene,
    path: &dyn HeadPath,
    duration: f64,
    policy: &mut dyn Policy,
    settings: &ControllerSettings,
) -> Result<MetricsSummary> {
    let mut physics = create_backend(backend, scene, physics)?;
    let start = path.point(scene, 0.0);
    physics.reset(&HumanoidPose::standing_on(
        &scene.terrain,
        start.x,
        start.y,
        0.0,
    ))?;
    policy.reset();
    let mut obs = Observation::new(ModelBasedController::LAYOUT);
    let mut action = Action::zeros(ModelBasedController::LAYOUT.num_joints);
    let mut metrics =
        MetricsAccumulator::new(PathRewardWeights::default(), settings.body_weight(), vec![]);
    let steps = (duration * plamo_interfaces::CONTROL_HZ as f64).round() as u64;
    for c in 0..steps {
        let t = c as f64 / plamo_interfaces::CONTROL_HZ as f64;
        let state = physics.state().clone();
        let ground = settings.fall_ground(scene, &FallBody::of(&state));
        let fallen = settings.is_fallen(state.head[2] - ground, path.head_height());
        let target = path.point(scene, t);
        let dir = path.direction(t);
        let max_other = state
            .body_pos
            .iter()
            .enumerate()
            .filter(|(b, _)| *b != HEAD)
            .map(|(_, p)| p[2])
            .fold(f64::NEG_INFINITY, f64::max);
        let heading = state.heading();
        metrics.push(&StepSample {
            t,
            head: state.head,
            target: [target.x, target.y, target.z],
            head_dir: [heading.cos(), heading.sin(), 0.0],
            path_dir: [dir[0], dir[1], 0.0],
            max_other_body_z: max_other,
            fallen,
            residual: action.root_wrench,
        });
        if fallen {
            physics.reset(&HumanoidPose::standing_on(
                &scene.terrain,
                target.x,
                target.y,
                dir[1].atan2(dir[0]),
            ))?;
            policy.reset();
            continue;
        }
        control_step(
            physics.as_mut(),
            &state,
            path,
            scene,
            t,
            policy,
            &mut obs,
            &mut action,
        )?;
    }
    Ok(metrics.summary())
}

/// One control step at time `t` \[s\] of a humanoid in `state`: the plan's next
/// waypoints from `path`, the observation, the policy's action (left in `obs` and
/// `action`), applied to `physics` for one control period.
#[allow(clippy::too_many_arguments)]
pub fn control_step(
    physics: &mut dyn PhysicsBackend,
    state: &HumanoidState,
    path: &dyn HeadPath,
    scene: &Scene,
    t: f64,
    policy: &mut dyn Policy,
    obs: &mut Observation,
    action: &mut Action,
) -> Result<()> {
    let mut plan = [Waypoint::default(); NUM_WAYPOINTS];
    for (i, w) in plan.iter_mut().enumerate() {
        *w = path.point(scene, t + WAYPOINT_SPACING * (i + 1) as f64);
    }
    obs.update(&HumanoidSnapshot::from(state), &plan, scene)?;
    policy.act(obs, action)?;
    physics.set_action(
        &action.pd_targets,
        action.root_wrench.map(|w| plamo_physics::RootWrench {
            force: w.force,
            torque: w.torque,
        }),
    )?;
    physics.step_n(PHYSICS_STEPS_PER_CONTROL as usize)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramped_path_starts_from_rest_and_joins_the_line() {
        let scene = flat_scene(100.0);
        let line = StraightPath {
            start: [1.0, 2.0],
            speed: 4.0,
            head_height: 1.47,
        };
        let p = RampedPath { line, accel: 2.0 };
        assert_eq!(p.point(&scene, 0.0).x, 1.0);
        assert_eq!(p.point(&scene, 0.0).v, 0.0);
        // Continuous where the ramp ends (t = 2 s, 4 m travelled).
        let (a, b) = (p.point(&scene, 2.0 - 1e-9), p.point(&scene, 2.0 + 1e-9));
        assert!((a.x - 5.0).abs() < 1e-6 && (b.x - 5.0).abs() < 1e-6);
        // Then at the line's speed, v^2 / 2a = 4 m behind the instant path.
        let late = p.point(&scene, 10.0);
        assert!((late.x - (line.at(&scene, 10.0).x - 4.0)).abs() < 1e-9);
        assert_eq!(late.v, 4.0);
        assert_eq!(late.z, 1.47);
    }

    #[test]
    fn drop_path_walks_then_lowers_the_head_without_a_jump_in_place() {
        let scene = flat_scene(100.0);
        let p = DropPath {
            start: [0.0, 1.0],
            walk_speed: 1.5,
            crawl_speed: 0.8,
            head_height: 0.4,
            drop_at: 3.0,
        };
        // 1.5 s up at 1 m/s^2 (1.125 m), then 1.5 s at 1.5 m/s: 3.375 m at the drop.
        let (a, b) = (p.point(&scene, 3.0 - 1e-9), p.point(&scene, 3.0 + 1e-9));
        assert!((a.x - 3.375).abs() < 1e-6 && (b.x - 3.375).abs() < 1e-6);
        assert_eq!(a.z, plamo_physics::humanoid::STANDING_HEAD_HEIGHT);
        assert_eq!((a.v, b.v), (1.5, 0.8));
        assert_eq!(b.z, 0.4);
        assert!((p.point(&scene, 5.0).x - (3.375 + 1.6)).abs() < 1e-9);
        assert_eq!(p.point(&scene, 5.0).y, 1.0);
    }

    #[test]
    fn turn_path_slows_into_its_corner_and_leaves_at_the_turn() {
        let scene = flat_scene(100.0);
        let p = TurnPath {
            start: [0.0, 0.0],
            speed: 1.0,
            corner_speed: 0.5,
            head_height: 0.8,
            first: 3.0,
            turn: 3.0,
            accel: 2.0,
        };
        // Up in 0.5 s (0.25 m), down to 0.5 m/s in 0.25 s (0.1875 m): at the corner
        // after 0.5 + 2.5625 + 0.25 s.
        let t1 = 0.5 + (3.0 - 0.25 - 0.1875) + 0.25;
        let (a, b) = (p.point(&scene, t1 - 1e-9), p.point(&scene, t1 + 1e-9));
        assert!(
            (a.x - 3.0).abs() < 1e-6 && (b.x - 3.0).abs() < 1e-6,
            "{a:?} {b:?}"
        );
        assert!((a.v - 0.5).abs() < 1e-6 && (b.v - 0.5).abs() < 1e-6);
        assert_eq!(p.direction(t1 - 0.1), [1.0, 0.0]);
        let d = p.direction(t1 + 0.1);
        assert!((d[0] - 3f64.cos()).abs() < 1e-12 && (d[1] - 3f64.sin()).abs() < 1e-12);
        // Back at full speed along the new leg.
        let late = p.point(&scene, t1 + 2.0);
        assert_eq!(late.v, 1.0);
        let run = 0.1875 + 1.75;
        assert!((late.x - (3.0 + run * 3f64.cos())).abs() < 1e-9);
        assert!((late.y - run * 3f64.sin()).abs() < 1e-9);
    }
}
