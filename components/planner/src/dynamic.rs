//! Stage 6: dynamic obstacles. Predict each obstacle's motion, sweep the character's
//! capsule along the timed plan against it (parry3d time-of-impact shape casts, one
//! linear cast per `collision_dt` slice), and report the first predicted contact
//! within the horizon (paper: 1.5 s; longer for a slow plan, `collision_lookahead`).
//!
//! Obstacles come from the scene (motion rules, or observed states in scene order)
//! and from the host ([`ExternalObstacle`]: e.g. a car a co-simulation host drives,
//! unknown to the scene, which can appear, move and vanish at any step).

use parry3d::math::{Pose, Rot3, Vec3};
use parry3d::query::{ShapeCastOptions, cast_shapes};
use parry3d::shape::{Ball, Capsule, Cuboid, Shape};
use plamo_scenes::{ObstacleShape, ObstacleState, Scene};
use serde::{Deserialize, Serialize};

use crate::{PlannerSettings, Trajectory, Waypoint};

/// A predicted collision between the plan and a dynamic obstacle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Conflict {
    /// Index of the obstacle: into `scene.dynamic`, or `scene.dynamic.len() + j` for
    /// external obstacle `j`.
    pub obstacle: usize,
    /// The obstacle's radius in XY (its footprint's bounding circle) \[m\].
    #[serde(default)]
    pub radius_xy: f64,
    /// Predicted time of contact, absolute \[s\].
    pub time: f64,
    /// Obstacle centre at that time \[m\].
    pub obstacle_position: [f64; 3],
    /// Character (plan) position at that time \[m\] (head x, y; terrain z).
    pub plan_position: [f64; 3],
}

/// How obstacle motion is predicted.
#[derive(Debug, Clone, Copy)]
pub enum Prediction<'a> {
    /// From the scene's motion rules (exact for scene obstacles).
    Rules,
    /// From observed states at `now`, extrapolated at constant velocity.
    Observed(&'a [ObstacleState]),
}

/// An obstacle the host reports that the scene does not know: its shape and its state
/// observed at some time, predicted at constant velocity from then on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ExternalObstacle {
    /// Shape (a box yaws with its velocity).
    pub shape: ObstacleShape,
    /// Observed centre and velocity.
    pub state: ObstacleState,
}

impl ExternalObstacle {
    /// Why this obstacle cannot be used, if it cannot: non-finite numbers or a
    /// non-positive size.
    pub fn check(&self) -> Result<(), String> {
        let st = &self.state;
        if !st.position.iter().all(|v| v.is_finite()) {
            return Err(format!("position must be finite, got {:?}", st.position));
        }
        if !st.velocity.iter().all(|v| v.is_finite()) {
            return Err(format!("velocity must be finite, got {:?}", st.velocity));
        }
        let ok = match self.shape {
            ObstacleShape::Sphere { radius } => radius.is_finite() && radius > 0.0,
            ObstacleShape::Box { half_extents } => {
                half_extents.iter().all(|h| h.is_finite() && *h > 0.0)
            }
        };
        if !ok {
            return Err(format!(
                "shape sizes must be finite and > 0, got {:?}",
                self.shape
            ));
        }
        Ok(())
    }

    /// State at absolute time `t`, observed at `observed` \[s\].
    pub fn state_at(&self, observed: f64, t: f64) -> ObstacleState {
        let s = self.state;
        let dt = t - observed;
        ObstacleState {
            position: std::array::from_fn(|i| s.position[i] + s.velocity[i] * dt),
            velocity: s.velocity,
        }
    }
}

/// The host's obstacles and the time their states were observed \[s\].
#[derive(Debug, Clone, Copy)]
pub struct External<'a> {
    /// The obstacles.
    pub obstacles: &'a [ExternalObstacle],
    /// When their states were observed \[s\].
    pub observed: f64,
}

impl External<'_> {
    /// No external obstacles.
    pub const NONE: External<'static> = External {
        obstacles: &[],
        observed: 0.0,
    };
}

/// Predicted state of obstacle `k` at absolute time `t`.
pub fn predict(scene: &Scene, how: Prediction, now: f64, k: usize, t: f64) -> ObstacleState {
    match how {
        Prediction::Observed(states) if k < states.len() => {
            let s = states[k];
            let dt = t - now;
            ObstacleState {
                position: [
                    s.position[0] + s.velocity[0] * dt,
                    s.position[1] + s.velocity[1] * dt,
                    s.position[2] + s.velocity[2] * dt,
                ],
                velocity: s.velocity,
            }
        }
        _ => scene.dynamic[k].motion.state_at(t),
    }
}

/// Predicted state at absolute time `t` of obstacle `k`, numbered as in [`Conflict`]:
/// the scene's first, then the host's `external` ones.
pub fn predict_any(
    scene: &Scene,
    external: External,
    how: Prediction,
    now: f64,
    k: usize,
    t: f64,
) -> ObstacleState {
    match k.checked_sub(scene.dynamic.len()) {
        None => predict(scene, how, now, k, t),
        Some(j) => external.obstacles[j].state_at(external.observed, t),
    }
}

fn v3(p: [f64; 3]) -> Vec3 {
    Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)
}

/// Shape and pose of an obstacle in state `st` (boxes yaw with the velocity).
fn obstacle_shape(shape: ObstacleShape, st: &ObstacleState) -> (Box<dyn Shape>, Pose) {
    match shape {
        ObstacleShape::Sphere { radius } => (
            Box::new(Ball::new(radius as f32)),
            Pose::from_translation(v3(st.position)),
        ),
        ObstacleShape::Box { half_extents } => {
            let yaw = if st.velocity[0].abs() + st.velocity[1].abs() > 1e-9 {
                st.velocity[1].atan2(st.velocity[0])
            } else {
                0.0
            };
            let mut pose = Pose::from_translation(v3(st.position));
            pose.rotation = Rot3::from_rotation_z(yaw as f32);
            (Box::new(Cuboid::new(v3(half_extents))), pose)
        }
    }
}

/// How far ahead \[s\] the sweep looks from `now`: `collision_horizon`, or longer
/// where the plan takes longer to cover `collision_lookahead`.
pub(crate) fn sweep_horizon(traj: &Trajectory, s: &PlannerSettings, now: f64) -> f64 {
    if s.collision_lookahead <= 0.0 {
        return s.collision_horizon;
    }
    let ahead = traj.sample_at(now).s + s.collision_lookahead;
    s.collision_horizon.max(traj.time_at_s(ahead) - now)
}

/// The first predicted contact between the plan and any scene obstacle in
/// \[now, now + horizon\] (`collision_horizon`, or as long as the plan takes to cover
/// `collision_lookahead`), closer than `obstacle_margin`; the plan is taken as the
/// body's, with nothing behind its head ([`predict_conflict_with`] for a lagging
/// or crawling body).
pub fn predict_conflict(
    traj: &Trajectory,
    scene: &Scene,
    s: &PlannerSettings,
    now: f64,
    how: Prediction,
) -> Option<Conflict> {
    predict_conflict_with(traj, scene, External::NONE, s, now, None, how)
}

/// [`predict_conflict`] over the scene's obstacles and then the host's `external`
/// ones (their conflicts are numbered after the scene's), for a head at `head` (x, y)
/// that may lag the plan at `now` ([`Trajectory::lag_at`]; `None`: on the plan).
///
/// The character is a vertical capsule from the ground to the head, swept along the
/// plan and, behind each plan point, along the path as far as the head lags it (at
/// most `lag_sweep_max`) and as far as a crawling body lies behind its head, one
/// capsule every character radius. A crawl's body (`crawl_body_length`, head to
/// feet) is covered where the plan's head is at `crawl_height`, blended to none at
/// `crouch_height`: the capsule at the head alone missed the crawler's trunk and
/// legs, which balls crossing behind the head rolled over (random tours, session 48).
pub fn predict_conflict_with(
    traj: &Trajectory,
    scene: &Scene,
    external: External,
    s: &PlannerSettings,
    now: f64,
    head: Option<[f64; 2]>,
    how: Prediction,
) -> Option<Conflict> {
    let nd = scene.dynamic.len();
    if nd + external.obstacles.len() == 0 || traj.points.is_empty() {
        return None;
    }
    let shape = |k: usize| match k.checked_sub(nd) {
        None => scene.dynamic[k].shape,
        Some(j) => external.obstacles[j].shape,
    };
    let state = |k: usize, t: f64| predict_any(scene, external, how, now, k, t);
    let dt = s.collision_dt;
    let steps = (sweep_horizon(traj, s, now) / dt).ceil() as usize;
    let r = s.character_radius;
    // Measured only with obstacles to sweep against (a scan of the whole path).
    let lag = head.map_or(0.0, |[x, y]| traj.lag_at(now, x, y).min(s.lag_sweep_max));
    // How far behind a plan point's head its body lies: a crawl's length less the
    // capsule's radius at `crawl_height`, none from `crouch_height` up.
    let body_behind = |head: f64| {
        let span = (s.crouch_height - s.crawl_height).max(1e-9);
        let lying = ((s.crouch_height - head) / span).clamp(0.0, 1.0);
        lying * (s.crawl_body_length - r).max(0.0)
    };
    // The capsule's centre for a plan sample: on the ground under the head, half
    // the head's height up.
    let centre = |w: &Waypoint| {
        let ground = w.position[2] - w.head_height;
        [
            w.position[0],
            w.position[1],
            ground + 0.5 * w.head_height.max(2.0 * r),
        ]
    };
    let mut best: Option<Conflict> = None;
    for k in 0..nd + external.obstacles.len() {
        for step in 0..steps {
            let t0 = now + step as f64 * dt;
            if best.is_some_and(|b| b.time <= t0) {
                break;
            }
            let a = traj.sample_at(t0);
            let b = traj.sample_at(t0 + dt);
            let oa = state(k, t0);
            let ob = state(k, t0 + dt);
            let vo = [
                (ob.position[0] - oa.position[0]) / dt,
                (ob.position[1] - oa.position[1]) / dt,
                (ob.position[2] - oa.position[2]) / dt,
            ];
            let (shape_o, pose_o) = obstacle_shape(shape(k), &oa);
            let opts = ShapeCastOptions {
                max_time_of_impact: dt as f32,
                target_distance: s.obstacle_margin as f32,
                stop_at_penetration: true,
                compute_impact_geometry_on_penetration: false,
            };
            // The plan point, then the path behind it every character radius.
            let behind = lag + body_behind(a.head_height);
            let n_back = (behind / r).ceil() as usize;
            let hit = (0..=n_back).find_map(|j| {
                let back = (j as f64 * r).min(behind);
                let (pa, pb) = if j == 0 {
                    (a, b)
                } else {
                    (traj.sample_at_s(a.s - back), traj.sample_at_s(b.s - back))
                };
                let half = (0.5 * pa.head_height - r).max(0.0);
                let capsule = Capsule::new_z(half as f32, r as f32);
                let (ca, cb) = (centre(&pa), centre(&pb));
                let vc = [
                    (cb[0] - ca[0]) / dt,
                    (cb[1] - ca[1]) / dt,
                    (cb[2] - ca[2]) / dt,
                ];
                cast_shapes(
                    &Pose::from_translation(v3(ca)),
                    v3(vc),
                    &capsule,
                    &pose_o,
                    v3(vo),
                    shape_o.as_ref(),
                    opts,
                )
                .ok()
                .flatten()
            });
            if let Some(h) = hit {
                let t = t0 + h.time_of_impact as f64;
                let o = state(k, t);
                let p = traj.sample_at(t);
                if best.is_some_and(|b| b.time <= t) {
                    break;
                }
                best = Some(Conflict {
                    obstacle: k,
                    radius_xy: shape(k).bounding_radius_xy(),
                    time: t,
                    obstacle_position: o.position,
                    plan_position: [p.position[0], p.position[1], p.position[2] - p.head_height],
                });
                break;
            }
        }
    }
    best
}
