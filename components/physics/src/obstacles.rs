//! Kinematic dynamic obstacles: pose as a pure function of time, shared by both
//! backends so they move obstacles identically.

use plamo_scenes::{DynamicObstacle, ObstacleShape, ObstacleState};

/// Pose of a dynamic obstacle at time `t` \[s\]: centre and yaw \[rad\]. A box's yaw
/// follows its horizontal velocity (0 when still); a sphere never turns.
pub(crate) fn obstacle_pose(ob: &DynamicObstacle, t: f64) -> (ObstacleState, f64) {
    let s = ob.motion.state_at(t);
    let yaw = match ob.shape {
        ObstacleShape::Box { .. } if s.velocity[0] != 0.0 || s.velocity[1] != 0.0 => {
            s.velocity[1].atan2(s.velocity[0])
        }
        _ => 0.0,
    };
    (s, yaw)
}
