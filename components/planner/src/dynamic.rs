//! Stage 6: dynamic obstacles. Predict each obstacle's motion, sweep the character's
//! capsule along the timed plan against it (parry3d time-of-impact shape casts, one
//! linear cast per `collision_dt` slice), and report the first predicted contact
//! within the horizon (paper: 1.5 s).

use parry3d::math::{Pose, Rot3, Vec3};
use parry3d::query::{ShapeCastOptions, cast_shapes};
use parry3d::shape::{Ball, Capsule, Cuboid, Shape};
use plamo_scenes::{ObstacleShape, ObstacleState, Scene};
use serde::{Deserialize, Serialize};

use crate::{PlannerSettings, Trajectory};

/// A predicted collision between the plan and a dynamic obstacle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Conflict {
    /// Index of the obstacle in `scene.dynamic`.
    pub obstacle: usize,
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

fn v3(p: [f64; 3]) -> Vec3 {
    Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)
}

/// Shape and pose of obstacle `k` in state `st` (boxes yaw with the velocity).
fn obstacle_shape(scene: &Scene, k: usize, st: &ObstacleState) -> (Box<dyn Shape>, Pose) {
    match scene.dynamic[k].shape {
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

/// The first predicted contact between the plan and any obstacle in
/// \[now, now + horizon\], closer than `obstacle_margin`.
pub fn predict_conflict(
    traj: &Trajectory,
    scene: &Scene,
    s: &PlannerSettings,
    now: f64,
    how: Prediction,
) -> Option<Conflict> {
    if scene.dynamic.is_empty() || traj.points.is_empty() {
        return None;
    }
    let dt = s.collision_dt;
    let steps = (s.collision_horizon / dt).ceil() as usize;
    let r = s.character_radius;
    let mut best: Option<Conflict> = None;
    for k in 0..scene.dynamic.len() {
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
            let oa = predict(scene, how, now, k, t0);
            let ob = predict(scene, how, now, k, t0 + dt);
            let vo = [
                (ob.position[0] - oa.position[0]) / dt,
                (ob.position[1] - oa.position[1]) / dt,
                (ob.position[2] - oa.position[2]) / dt,
            ];
            let (shape, pose_o) = obstacle_shape(scene, k, &oa);
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
                shape.as_ref(),
                opts,
            )
            .ok()
            .flatten();
            if let Some(h) = hit {
                let t = t0 + h.time_of_impact as f64;
                let o = predict(scene, how, now, k, t);
                let p = traj.sample_at(t);
                if best.is_some_and(|b| b.time <= t) {
                    break;
                }
                best = Some(Conflict {
                    obstacle: k,
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
