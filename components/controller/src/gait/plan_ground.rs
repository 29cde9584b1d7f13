//! The ground beyond the local height map's front row, from the plan: the map reaches
//! 0.35 m ahead of the root, a running foot or a crawling hand lands further, and the
//! plan's waypoints carry the ground under them (`Observation::waypoint_ground`).

use super::map_plane::MAP_HALF;
use crate::observation::{NUM_WAYPOINTS, Observation};

/// The plan's waypoints ahead of the map, as forward distance and ground height.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PlanGround {
    /// Forward distance and ground height of the waypoints, in increasing distance,
    /// heading frame, heights relative to the ground under the root \[m\].
    ahead: [(f64, f64); NUM_WAYPOINTS],
    n: usize,
    /// Where the map the plan's ground extends ends, forward \[m\].
    from: f64,
}

impl PlanGround {
    /// Nothing ahead: the map's front row goes on.
    pub(crate) const NONE: Self = Self {
        ahead: [(0.0, 0.0); NUM_WAYPOINTS],
        n: 0,
        from: MAP_HALF,
    };

    /// The waypoints of `obs` ahead of the map's front row, each at least 5 cm
    /// further than the one before (a plan turning back or standing still adds
    /// nothing); with `straight_ahead` only those within 45 degrees of the heading (a
    /// plan off to the side has its ground elsewhere than under the body).
    pub(crate) fn new(obs: &Observation, straight_ahead: bool) -> Self {
        Self::from_edge(obs, straight_ahead, MAP_HALF)
    }

    /// As [`PlanGround::new`] for a map that reaches `from` \[m\] ahead of the root
    /// (the height map with the rows ahead of it, `Observation::reach_map`).
    pub(crate) fn from_edge(obs: &Observation, straight_ahead: bool, from: f64) -> Self {
        let mut g = Self { from, ..Self::NONE };
        let mut last = from;
        for (w, &h) in obs.waypoints.iter().zip(&obs.waypoint_ground) {
            // Waypoints are relative to the head; the map to the root.
            let x = w[0] + obs.head_pos[0];
            let y = w[1] + obs.head_pos[1];
            if x > last + 0.05 && (!straight_ahead || y.abs() <= x) {
                g.ahead[g.n] = (x, h);
                g.n += 1;
                last = x;
            }
        }
        g
    }

    /// Ground at forward distance `x` \[m\], given `edge`, the map's value there
    /// (clamped to the map): `edge` up to the front row, beyond it interpolated
    /// linearly to the waypoints' ground, beyond the last waypoint the last one's.
    pub(crate) fn extend(&self, x: f64, edge: f64) -> f64 {
        if x <= self.from {
            return edge;
        }
        let mut prev = (self.from, edge);
        for &(xw, gw) in &self.ahead[..self.n] {
            if x <= xw {
                return prev.1 + (gw - prev.1) * (x - prev.0) / (xw - prev.0);
            }
            prev = (xw, gw);
        }
        prev.1
    }
}
