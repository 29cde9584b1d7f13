//! Stage 6: dynamic obstacles. Predict each obstacle's motion, sweep the character's
//! capsule along the timed plan against it (parry3d time-of-impact shape casts, one
//! linear cast per `collision_dt` slice), and report the first predicted contact
//! within the horizon (paper: 1.5 s).
//!
//! Obstacles come from the scene (motion rules, or observed states in scene order)
//! and from the host ([`ExternalObstacle`]: e.g. a car a co-simulation host drives,
//! unknown to the scene, which can appear, move and vanish at any step).

use parry3d::math::{Pose, Rot3, Vec3};
use parry3d::query::{ShapeCastOptions, cast_shapes};
use parry3d::shape::{Ball, Capsule, Cuboid, Shape};
use plamo_scenes::{ObstacleShape, ObstacleState, Scene};
use serde::{Deserialize, Serialize};

use crate::{PlannerSettings, Trajectory};

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

/// The first predicted contact between the plan and any scene obstacle in
/// \[now, now + horizon\], closer than `obstacle_margin`.
pub fn predict_conflict(
    traj: &Trajectory,
    scene: &Scene,
    s: &PlannerSettings,
    now: f64,
    how: Prediction,
) -> Option<Conflict> {
    predict_conflict_with(traj, scene, External::NONE, s, now, how)
}

/// [`predict_conflict`] over the scene's obstacles and then the host's `external`
/// ones (their conflicts are numbered after the scene's).
pub fn predict_conflict_with(
    traj: &Trajectory,
    scene: &Scene,
    external: External,
    s: &PlannerSettings,
    now: f64,
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
    let steps = (s.collision_horizon / dt).ceil() as usize;
    let r = s.character_radius;
    let mut best: Option<Conflict> = None;
    for k in 0..nd + external.obstacles.len() {
        for step in 0..steps {
            let t0 = now + step as f64 * dt;
            if best.is_some_and(|b| b.time <= t0) {
                break;
            }
            let a = traj.sample_at(t0);
            let b = traj.sample_at(t0 + dt);
            let (ga, gb) = (a.position[2] - a.head_height, b.position[2] - b.head_height);
            // Vertical capsule from the ground to the head.
            let half = (0.5 * a.head_height - r).max(0.0);
            let capsule = Capsule::new_z(half as f32, r as f32);
            let ca = [
                a.position[0],
                a.position[1],
                ga + 0.5 * a.head_height.max(2.0 * r),
            ];
            let cb = [
                b.position[0],
                b.position[1],
                gb + 0.5 * b.head_height.max(2.0 * r),
            ];
            let vc = [
                (cb[0] - ca[0]) / dt,
                (cb[1] - ca[1]) / dt,
                (cb[2] - ca[2]) / dt,
            ];
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
            let hit = cast_shapes(
                &Pose::from_translation(v3(ca)),
                v3(vc),
                &capsule,
                &pose_o,
                v3(vo),
                shape_o.as_ref(),
                opts,
            )
            .ok()
            .flatten();
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
