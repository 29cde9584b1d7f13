//! Kinematic dynamic obstacles: pose as a pure function of time, shared by both
//! backends so they move obstacles identically.

use plamo_scenes::{DynamicObstacle, ObstacleShape, ObstacleState, Scene};

use crate::PhysicsError;

/// Pose of a dynamic obstacle at time `t` \[s\] by its scene motion: centre and yaw
/// \[rad\] (see [`yaw_of`]).
pub(crate) fn obstacle_pose(ob: &DynamicObstacle, t: f64) -> (ObstacleState, f64) {
    let s = ob.motion.state_at(t);
    let yaw = yaw_of(ob.shape, &s);
    (s, yaw)
}

/// A box's yaw follows its horizontal velocity (0 when still); a sphere never turns.
fn yaw_of(shape: ObstacleShape, s: &ObstacleState) -> f64 {
    match shape {
        ObstacleShape::Box { .. } if s.velocity[0] != 0.0 || s.velocity[1] != 0.0 => {
            s.velocity[1].atan2(s.velocity[0])
        }
        _ => 0.0,
    }
}

/// How each of a world's dynamic obstacles moves: by its scene motion until a host
/// drives it ([`crate::PhysicsBackend::drive_obstacle`]), then from the host's last
/// sample at that sample's constant velocity (a zero-order hold of the velocity, so a
/// host sampling slower than physics still moves the body smoothly).
#[derive(Debug, Clone)]
pub(crate) struct ObstacleMotions {
    obstacles: Vec<DynamicObstacle>,
    /// The host's sample and the time it holds from \[s\].
    driven: Vec<Option<(ObstacleState, f64)>>,
}

impl ObstacleMotions {
    pub(crate) fn new(scene: &Scene) -> Self {
        Self {
            obstacles: scene.dynamic.clone(),
            driven: vec![None; scene.dynamic.len()],
        }
    }

    /// From time `t0` on, obstacle `index` moves from `state.position` at
    /// `state.velocity`.
    pub(crate) fn drive(
        &mut self,
        index: usize,
        state: ObstacleState,
        t0: f64,
    ) -> Result<(), PhysicsError> {
        let n = self.obstacles.len();
        let slot = self
            .driven
            .get_mut(index)
            .ok_or_else(|| PhysicsError::InvalidScene {
                reason: format!(
                    "no dynamic obstacle {index} to drive: the scene has {n} (indices 0..{n})"
                ),
            })?;
        for (field, values) in [
            ("obstacle.position", state.position),
            ("obstacle.velocity", state.velocity),
        ] {
            if let Some((i, v)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(PhysicsError::NonFinite {
                    field,
                    index: i,
                    value: *v,
                });
            }
        }
        *slot = Some((state, t0));
        Ok(())
    }

    /// Pose of obstacle `k` at time `t` \[s\]: centre and yaw \[rad\].
    pub(crate) fn pose(&self, k: usize, t: f64) -> (ObstacleState, f64) {
        let ob = &self.obstacles[k];
        match self.driven[k] {
            None => obstacle_pose(ob, t),
            Some((s, t0)) => {
                let dt = t - t0;
                let s = ObstacleState {
                    position: [0, 1, 2].map(|i| s.position[i] + s.velocity[i] * dt),
                    velocity: s.velocity,
                };
                (s, yaw_of(ob.shape, &s))
            }
        }
    }

    /// Every obstacle's state at time `t` \[s\], in scene order.
    pub(crate) fn states_at(&self, t: f64) -> impl Iterator<Item = ObstacleState> + '_ {
        (0..self.obstacles.len()).map(move |k| self.pose(k, t).0)
    }
}
