//! The plan's path behind its first observed waypoint, so a body that lags its timed
//! plan can steer along the path instead of straight at a point on it.
//!
//! The observation carries the plan only from t + 0.5 s on, relative to the head. A
//! crawl that lags ~1 m steers at a waypoint past a corner and cuts it: on the
//! playground its shoulder caught the hedge's end where the plan turned 0.5 m clear
//! of it (RESULTS "Crawl", session 17). The observation has no world position, so
//! the trace lives in an odometry frame: the root's velocity integrated in the world
//! heading, which drifts by millimetres over the few seconds kept.

use std::collections::VecDeque;

use plamo_interfaces::CONTROL_DT;

use crate::math::{from_heading_frame, to_heading_frame};
use crate::observation::Observation;

/// Seconds of the plan's past first waypoints kept \[s\].
const TRACE_SECONDS: f64 = 4.0;

/// Points kept: one per control step.
const TRACE_LEN: usize = (TRACE_SECONDS / CONTROL_DT) as usize;

/// A first waypoint further than this from the one a step before starts a new trace
/// \[m\]: a timed plan moves it by at most its speed times a step (0.13 m at 4 m/s);
/// a re-plan or a reset on the plan moves it further.
const JUMP: f64 = 0.5;

/// Where [`PlanTrace::pursuit`] steers, heading frame relative to the head \[m\].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Pursuit {
    /// The point to move towards.
    pub(crate) toward: [f64; 2],
    /// The point to face.
    pub(crate) face: [f64; 2],
}

/// The plan's recent first waypoints in an odometry frame (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct PlanTrace {
    /// Root position, odometry frame \[m\].
    odom: [f64; 2],
    /// Head position, odometry frame \[m\].
    head: [f64; 2],
    /// Heading of the last observation \[rad\].
    heading: f64,
    /// The plan's first waypoint at each step, oldest first, odometry frame \[m\].
    points: VecDeque<[f64; 2]>,
}

impl Default for PlanTrace {
    fn default() -> Self {
        Self {
            odom: [0.0; 2],
            head: [0.0; 2],
            heading: 0.0,
            points: VecDeque::with_capacity(TRACE_LEN + 1),
        }
    }
}

/// A heading-frame XY vector in the world (odometry) frame.
fn to_world(heading: f64, [x, y]: [f64; 2]) -> [f64; 2] {
    let [wx, wy, _] = from_heading_frame(heading, [x, y, 0.0]);
    [wx, wy]
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn lerp(a: [f64; 2], b: [f64; 2], u: f64) -> [f64; 2] {
    [a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])]
}

impl PlanTrace {
    /// Forgets the trace (a new plan, a reset, a gait taking over).
    pub(crate) fn clear(&mut self) {
        self.points.clear();
    }

    /// Moves the odometry by the root's velocity over one control step and records
    /// the plan's first waypoint.
    pub(crate) fn record(&mut self, obs: &Observation) {
        let [vx, vy, _] = obs.root_lin_vel;
        let v = to_world(obs.heading, [vx, vy]);
        self.odom = [
            self.odom[0] + v[0] * CONTROL_DT,
            self.odom[1] + v[1] * CONTROL_DT,
        ];
        self.heading = obs.heading;
        let h = to_world(obs.heading, [obs.head_pos[0], obs.head_pos[1]]);
        self.head = [self.odom[0] + h[0], self.odom[1] + h[1]];
        let q = self.world(obs.waypoints[0]);
        if self.points.back().is_some_and(|&last| dist(last, q) > JUMP) {
            self.points.clear();
        }
        self.points.push_back(q);
        if self.points.len() > TRACE_LEN {
            self.points.pop_front();
        }
    }

    /// A waypoint (heading frame, relative to the head) in the odometry frame.
    fn world(&self, w: [f64; 3]) -> [f64; 2] {
        let d = to_world(self.heading, [w[0], w[1]]);
        [self.head[0] + d[0], self.head[1] + d[1]]
    }

    /// Where a lagging body steers, heading frame relative to the head \[m\]: the point
    /// `lookahead` along the path beyond the path's point nearest the head, no further
    /// than the first waypoint (to move towards), and the point twice as far, no further
    /// than the second (to face). With the body within the lookahead of that waypoint
    /// along the path each is the waypoint itself; lagging further, a point on the path
    /// between the body and it. `None` until two points are recorded.
    pub(crate) fn pursuit(&self, obs: &Observation, lookahead: f64) -> Option<Pursuit> {
        let n = self.points.len();
        if n < 2 {
            return None;
        }
        let point = |i: usize| {
            if i < n {
                self.points[i]
            } else {
                self.world(obs.waypoints[i - n + 1])
            }
        };
        // Nearest point over the trace's segments; the latest of equals (a plan that
        // stood still recorded one point many times). The facing point may also start
        // on the segment from the first waypoint to the second.
        let mut best = (f64::INFINITY, n - 1, 0.0);
        for i in 0..n - 1 {
            best = self.nearer(best, i, point(i), point(i + 1));
        }
        let past_first = self.nearer(best, n - 1, point(n - 1), point(n));
        let ahead = |(_, mut i, u): (f64, usize, f64), lookahead: f64, last: usize| {
            let mut at = lerp(point(i), point(i + 1), u);
            let mut left = lookahead;
            while i < last {
                let next = point(i + 1);
                let d = dist(at, next);
                if d >= left {
                    at = lerp(at, next, left / d);
                    break;
                }
                left -= d;
                at = next;
                i += 1;
            }
            let [x, y, _] = to_heading_frame(
                self.heading,
                [at[0] - self.head[0], at[1] - self.head[1], 0.0],
            );
            [x, y]
        };
        Some(Pursuit {
            toward: ahead(best, lookahead, n - 1),
            face: ahead(past_first, 2.0 * lookahead, n),
        })
    }

    /// `best` (distance to the head, segment, position along it) or segment `i` from
    /// `a` to `b`, whichever comes nearer the head; `i` on a tie.
    fn nearer(
        &self,
        best: (f64, usize, f64),
        i: usize,
        a: [f64; 2],
        b: [f64; 2],
    ) -> (f64, usize, f64) {
        let ab = [b[0] - a[0], b[1] - a[1]];
        let l2 = ab[0] * ab[0] + ab[1] * ab[1];
        let u = if l2 > 1e-12 {
            (((self.head[0] - a[0]) * ab[0] + (self.head[1] - a[1]) * ab[1]) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let d = dist(lerp(a, b, u), self.head);
        if d <= best.0 { (d, i, u) } else { best }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::observation::{NUM_WAYPOINTS, ObservationLayout};
    use plamo_physics::NUM_JOINTS;
    use plamo_physics::humanoid::BODIES;

    fn layout() -> ObservationLayout {
        ObservationLayout {
            num_joints: NUM_JOINTS,
            num_bodies: BODIES.len(),
        }
    }

    /// An observation of a body at `head` (world, heading 0, root = head) and at rest,
    /// whose plan's waypoints are `plan(k)` (world) for k = 0..10.
    fn observe(obs: &mut Observation, head: [f64; 2], plan: impl Fn(usize) -> [f64; 2]) {
        obs.heading = 0.0;
        obs.head_pos = [0.0; 3];
        obs.root_lin_vel = [0.0; 3];
        for k in 0..NUM_WAYPOINTS {
            let p = plan(k);
            obs.waypoints[k] = [p[0] - head[0], p[1] - head[1], 0.0];
        }
    }

    #[test]
    fn a_lagging_body_pursues_the_path_round_a_corner_not_the_waypoint_past_it() {
        let mut obs = Observation::new(layout());
        let mut trace = PlanTrace::default();
        // The plan goes +x along y = 0 to (2, 0), then turns +y; it moves 0.1 m a
        // step. The body stands still at the origin (odometry stays 0).
        let along = |s: f64| if s <= 2.0 { [s, 0.0] } else { [2.0, s - 2.0] };
        for step in 0..30 {
            let s0 = 0.1 * step as f64;
            observe(&mut obs, [0.0, 0.0], |k| along(s0 + 0.5 * k as f64));
            trace.record(&obs);
        }
        // First waypoint now at s = 2.9, i.e. (2, 0.9): aiming at it cuts the corner.
        let p = trace.pursuit(&obs, 0.5).unwrap().toward;
        assert!((p[0] - 0.5).abs() < 1e-9 && p[1].abs() < 1e-9, "{p:?}");
        // Near the end of the path it is the waypoint itself.
        observe(&mut obs, [2.0, 0.7], |k| along(2.9 + 0.5 * k as f64));
        let mut near = trace.clone();
        near.head = [2.0, 0.7];
        let p = near.pursuit(&obs, 0.5).unwrap().toward;
        assert!(
            (p[0] - 0.0).abs() < 1e-9 && (p[1] - 0.2).abs() < 1e-9,
            "{p:?}"
        );
        // A re-plan that moves the first waypoint far starts a new trace.
        observe(&mut obs, [0.0, 0.0], |k| [-1.0, 0.5 * k as f64]);
        trace.record(&obs);
        assert!(trace.pursuit(&obs, 0.5).is_none());
    }

    #[test]
    fn odometry_follows_the_root_velocity_in_the_world_heading() {
        let mut obs = Observation::new(layout());
        let mut trace = PlanTrace::default();
        obs.heading = std::f64::consts::FRAC_PI_2;
        obs.root_lin_vel = [1.0, 0.0, 0.0];
        for _ in 0..30 {
            trace.record(&obs);
        }
        assert!(trace.odom[0].abs() < 1e-9 && (trace.odom[1] - 1.0).abs() < 1e-9);
    }
}
