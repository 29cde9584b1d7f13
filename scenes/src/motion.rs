//! Deterministic motion rules of dynamic obstacles. Position and velocity at time t
//! are a pure function of (rule, t): no integration state, so every component (and
//! every process) agrees on where an obstacle is.

use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Where a dynamic obstacle is and how fast it moves at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ObstacleState {
    /// Centre position \[m\].
    pub position: [f64; 3],
    /// Velocity \[m/s\].
    pub velocity: [f64; 3],
}

/// A motion rule.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Motion {
    /// Back and forth along the segment `from`-`to` at constant `speed`, bouncing at
    /// the ends. Starts at `from` moving towards `to`.
    Linear {
        /// One end \[m\].
        from: [f64; 3],
        /// The other end \[m\].
        to: [f64; 3],
        /// Speed \[m/s\], > 0.
        speed: f64,
    },
    /// A horizontal circle.
    Circle {
        /// Centre \[m\].
        center: [f64; 3],
        /// Radius \[m\], > 0.
        radius: f64,
        /// Period of one revolution \[s\], > 0; negative values are not allowed, use
        /// `clockwise`.
        period: f64,
        /// Starting angle \[rad\] from +X.
        #[serde(default)]
        phase: f64,
        /// Turn clockwise instead of counter-clockwise.
        #[serde(default)]
        clockwise: bool,
    },
    /// Along a closed polyline through `points` at constant `speed`.
    Waypoints {
        /// At least two points \[m\]; the last connects back to the first.
        points: Vec<[f64; 3]>,
        /// Speed \[m/s\], > 0.
        speed: f64,
    },
    /// A thrown ball: ballistic flight from `start` with `velocity`, bouncing on the
    /// horizontal plane z = `ground` with coefficient of restitution `restitution`;
    /// at rest after the bounces die out. When `period` is set the throw repeats
    /// every `period` seconds.
    Ball {
        /// Release position \[m\] (ball centre).
        start: [f64; 3],
        /// Release velocity \[m/s\].
        velocity: [f64; 3],
        /// Height of the plane the ball centre bounces on \[m\] (ground + radius).
        ground: f64,
        /// Vertical restitution in \[0, 1).
        #[serde(default = "default_restitution")]
        restitution: f64,
        /// Fraction of horizontal velocity kept at each bounce, in \[0, 1\].
        #[serde(default = "default_keep")]
        horizontal_keep: f64,
        /// Gravity \[m/s^2\], > 0.
        #[serde(default = "default_gravity")]
        gravity: f64,
        /// Repeat the throw every `period` seconds, if set.
        #[serde(default)]
        period: Option<f64>,
    },
}

fn default_restitution() -> f64 {
    0.6
}
fn default_keep() -> f64 {
    0.8
}
fn default_gravity() -> f64 {
    9.81
}

fn lerp3(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

fn dist3(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt()
}

fn scale3(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

fn dir3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    let d = dist3(a, b);
    if d == 0.0 {
        [0.0; 3]
    } else {
        scale3([b[0] - a[0], b[1] - a[1], b[2] - a[2]], 1.0 / d)
    }
}

impl Motion {
    /// State at simulated time `t` \[s\] (t < 0 is treated as 0).
    pub fn state_at(&self, t: f64) -> ObstacleState {
        let t = t.max(0.0);
        match self {
            Motion::Linear { from, to, speed } => {
                let len = dist3(*from, *to);
                if len == 0.0 {
                    return ObstacleState {
                        position: *from,
                        velocity: [0.0; 3],
                    };
                }
                let s = (speed * t) % (2.0 * len);
                let d = dir3(*from, *to);
                if s <= len {
                    ObstacleState {
                        position: lerp3(*from, *to, s / len),
                        velocity: scale3(d, *speed),
                    }
                } else {
                    ObstacleState {
                        position: lerp3(*to, *from, (s - len) / len),
                        velocity: scale3(d, -speed),
                    }
                }
            }
            Motion::Circle {
                center,
                radius,
                period,
                phase,
                clockwise,
            } => {
                let sign = if *clockwise { -1.0 } else { 1.0 };
                let w = sign * TAU / period;
                let a = phase + w * t;
                let (s, c) = a.sin_cos();
                ObstacleState {
                    position: [center[0] + radius * c, center[1] + radius * s, center[2]],
                    velocity: [-radius * w * s, radius * w * c, 0.0],
                }
            }
            Motion::Waypoints { points, speed } => {
                let n = points.len();
                let seg = |k: usize| (points[k], points[(k + 1) % n]);
                let total: f64 = (0..n).map(|k| dist3(seg(k).0, seg(k).1)).sum();
                if total == 0.0 {
                    return ObstacleState {
                        position: points[0],
                        velocity: [0.0; 3],
                    };
                }
                let mut s = (speed * t) % total;
                for k in 0..n {
                    let (a, b) = seg(k);
                    let l = dist3(a, b);
                    if s <= l && l > 0.0 {
                        return ObstacleState {
                            position: lerp3(a, b, s / l),
                            velocity: scale3(dir3(a, b), *speed),
                        };
                    }
                    s -= l;
                }
                ObstacleState {
                    position: points[0],
                    velocity: scale3(dir3(points[0], points[1 % n]), *speed),
                }
            }
            Motion::Ball {
                start,
                velocity,
                ground,
                restitution,
                horizontal_keep,
                gravity,
                period,
            } => {
                let t = match period {
                    Some(p) if *p > 0.0 => t % p,
                    _ => t,
                };
                ball_state(
                    *start,
                    *velocity,
                    *ground,
                    *restitution,
                    *horizontal_keep,
                    *gravity,
                    t,
                )
            }
        }
    }
}

/// Analytic bouncing ball: flight arcs between bounces, each bounce scaling the
/// vertical speed by `e` and the horizontal by `keep`.
fn ball_state(
    start: [f64; 3],
    v0: [f64; 3],
    ground: f64,
    e: f64,
    keep: f64,
    g: f64,
    t: f64,
) -> ObstacleState {
    let mut p = start;
    let mut v = v0;
    let mut t_left = t;
    // Bounded number of arcs: a bounce below 1 cm/s vertical ends the motion.
    for _ in 0..64 {
        // Time until the centre reaches `ground` while falling: solve
        // p.z + v.z t - g t^2 / 2 = ground for the positive root.
        let dz = p[2] - ground;
        let disc = v[2] * v[2] + 2.0 * g * dz.max(0.0);
        let t_hit = (v[2] + disc.sqrt()) / g;
        if t_left <= t_hit {
            let tt = t_left;
            return ObstacleState {
                position: [
                    p[0] + v[0] * tt,
                    p[1] + v[1] * tt,
                    p[2] + v[2] * tt - 0.5 * g * tt * tt,
                ],
                velocity: [v[0], v[1], v[2] - g * tt],
            };
        }
        t_left -= t_hit;
        p = [p[0] + v[0] * t_hit, p[1] + v[1] * t_hit, ground];
        let vz_hit = v[2] - g * t_hit;
        v = [v[0] * keep, v[1] * keep, -vz_hit * e];
        if v[2] < 0.01 {
            // Rolling: horizontal speed decays no further in this model; treat the ball as
            // coming to rest at the bounce point so obstacles never run away forever.
            return ObstacleState {
                position: p,
                velocity: [0.0; 3],
            };
        }
    }
    ObstacleState {
        position: p,
        velocity: [0.0; 3],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_bounces_between_ends() {
        let m = Motion::Linear {
            from: [0.0, 0.0, 0.5],
            to: [4.0, 0.0, 0.5],
            speed: 2.0,
        };
        assert_eq!(m.state_at(1.0).position, [2.0, 0.0, 0.5]);
        assert_eq!(m.state_at(1.0).velocity, [2.0, 0.0, 0.0]);
        let back = m.state_at(3.0);
        assert!((back.position[0] - 2.0).abs() < 1e-12);
        assert_eq!(back.velocity, [-2.0, 0.0, 0.0]);
        assert!((m.state_at(4.0).position[0]).abs() < 1e-12);
    }

    #[test]
    fn circle_velocity_is_tangent_and_matches_period() {
        let m = Motion::Circle {
            center: [1.0, 2.0, 0.3],
            radius: 2.0,
            period: 4.0,
            phase: 0.0,
            clockwise: false,
        };
        let s0 = m.state_at(0.0);
        assert_eq!(s0.position, [3.0, 2.0, 0.3]);
        assert!((s0.velocity[1] - 2.0 * TAU / 4.0).abs() < 1e-12);
        let s1 = m.state_at(1.0);
        assert!((s1.position[0] - 1.0).abs() < 1e-12 && (s1.position[1] - 4.0).abs() < 1e-12);
        let s4 = m.state_at(4.0);
        assert!((s4.position[0] - 3.0).abs() < 1e-9);
    }

    #[test]
    fn waypoint_loop_closes() {
        let m = Motion::Waypoints {
            points: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
            speed: 1.0,
        };
        let total = 2.0 + 2f64.sqrt();
        assert!((m.state_at(1.5).position[1] - 0.5).abs() < 1e-12);
        let back = m.state_at(total);
        assert!(back.position[0].abs() < 1e-9 && back.position[1].abs() < 1e-9);
    }

    #[test]
    fn ball_falls_bounces_and_rests() {
        let m = Motion::Ball {
            start: [0.0, 0.0, 2.0],
            velocity: [1.0, 0.0, 0.0],
            ground: 0.1,
            restitution: 0.5,
            horizontal_keep: 1.0,
            gravity: 9.81,
            period: None,
        };
        let t_hit = (2.0 * 1.9 / 9.81f64).sqrt();
        let at_hit = m.state_at(t_hit);
        assert!((at_hit.position[2] - 0.1).abs() < 1e-9);
        // Just after the bounce it moves up.
        assert!(m.state_at(t_hit + 0.01).velocity[2] > 0.0);
        // Never below the ground plane.
        for k in 0..500 {
            assert!(m.state_at(k as f64 * 0.01).position[2] >= 0.1 - 1e-9);
        }
        assert_eq!(m.state_at(100.0).velocity, [0.0; 3]);
    }
}
