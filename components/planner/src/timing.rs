//! Stage 5: from (x, y, z, v) along the path to waypoints at fixed time steps
//! (paper appendix: the controller reads the next 5 s as 10 samples 0.5 s apart).
//!
//! Each segment is travelled at constant acceleration, so its duration is
//! 2 ds / (v_i + v_{i+1}) and the arc length at time tau into it is
//! v_i tau + a tau^2 / 2; positions are then interpolated linearly in arc length.

use serde::{Deserialize, Serialize};

use crate::PathPoint;

/// A timed sample of the plan.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Waypoint {
    /// Absolute simulated time \[s\].
    pub t: f64,
    /// Head position x, y and absolute head z \[m\].
    pub position: [f64; 3],
    /// Head height above the terrain \[m\].
    pub head_height: f64,
    /// Planned speed \[m/s\].
    pub speed: f64,
    /// Arc length along the path \[m\].
    pub s: f64,
}

/// A refined path with speeds and passage times, starting at `start_time`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Trajectory {
    /// Absolute time of the first point \[s\].
    pub start_time: f64,
    /// Points with `v` and `t` (relative to `start_time`) filled.
    pub points: Vec<PathPoint>,
}

impl Trajectory {
    /// Build from points with speeds set; fills the passage times. A point at the
    /// same arc length as the one before it is reached `wait` seconds after it.
    pub fn new(start_time: f64, mut points: Vec<PathPoint>) -> Self {
        let mut t = 0.0;
        if let Some(p) = points.first_mut() {
            p.t = 0.0;
        }
        for i in 1..points.len() {
            let ds = points[i].s - points[i - 1].s;
            let vs = points[i - 1].v + points[i].v;
            t += if ds <= 0.0 {
                points[i].wait
            } else if vs > 1e-9 {
                2.0 * ds / vs
            } else {
                f64::INFINITY
            };
            points[i].t = t;
        }
        Self { start_time, points }
    }

    /// Total duration \[s\].
    pub fn duration(&self) -> f64 {
        self.points.last().map_or(0.0, |p| p.t)
    }

    /// Path length \[m\].
    pub fn length(&self) -> f64 {
        self.points.last().map_or(0.0, |p| p.s)
    }

    /// Time of arrival at the end, absolute \[s\].
    pub fn end_time(&self) -> f64 {
        self.start_time + self.duration()
    }

    fn waypoint(p: &PathPoint, t: f64) -> Waypoint {
        Waypoint {
            t,
            position: [p.x, p.y, p.head_z()],
            head_height: p.head_height,
            speed: p.v,
            s: p.s,
        }
    }

    /// The plan at absolute time `t`: before the start the first point, after the
    /// end the last point at rest.
    pub fn sample_at(&self, t: f64) -> Waypoint {
        let Some(first) = self.points.first() else {
            return Waypoint {
                t,
                ..Default::default()
            };
        };
        let tr = t - self.start_time;
        if tr <= 0.0 {
            return Self::waypoint(first, t);
        }
        let last = self.points.last().unwrap();
        if tr >= last.t {
            let mut w = Self::waypoint(last, t);
            w.speed = 0.0;
            return w;
        }
        // First point with p.t > tr; the segment is (i - 1, i).
        let i = self.points.partition_point(|p| p.t <= tr).max(1);
        let (a, b) = (&self.points[i - 1], &self.points[i]);
        let ds = b.s - a.s;
        let tau = tr - a.t;
        let acc = if ds > 0.0 {
            (b.v * b.v - a.v * a.v) / (2.0 * ds)
        } else {
            0.0
        };
        let s_in = (a.v * tau + 0.5 * acc * tau * tau).clamp(0.0, ds);
        let f = if ds > 0.0 { s_in / ds } else { 0.0 };
        let mut w = Self::between(a, b, f, t, a.s + s_in);
        w.speed = (a.v + acc * tau).max(0.0);
        w
    }

    /// The waypoint a share `f` of the way from `a` to `b`, at time `t` and arc
    /// length `s`, with `a`'s speed.
    fn between(a: &PathPoint, b: &PathPoint, f: f64, t: f64, s: f64) -> Waypoint {
        let lerp = |u: f64, v: f64| u + (v - u) * f;
        let head = lerp(a.head_height, b.head_height);
        Waypoint {
            t,
            position: [
                lerp(a.x, b.x),
                lerp(a.y, b.y),
                lerp(a.ground, b.ground) + head,
            ],
            head_height: head,
            speed: a.v,
            s,
        }
    }

    /// `n` waypoints at t + dt, t + 2 dt, ..., t + n dt (paper: n = 10, dt = 0.5 s).
    pub fn next_waypoints(&self, t: f64, n: usize, dt: f64) -> Vec<Waypoint> {
        (1..=n).map(|k| self.sample_at(t + k as f64 * dt)).collect()
    }

    /// Direction of the path's first `span` metres, from its first point to the point
    /// that far along it (or its end) \[rad\]; `None` for a path shorter than a
    /// centimetre.
    pub fn heading_over(&self, span: f64) -> Option<f64> {
        let first = self.points.first()?;
        let along = self
            .points
            .iter()
            .find(|p| p.s - first.s >= span)
            .or(self.points.last())?;
        let (dx, dy) = (along.x - first.x, along.y - first.y);
        (dx.hypot(dy) >= 0.01).then(|| dy.atan2(dx))
    }

    /// The path at arc length `s` (clamped to the path): position, head height and
    /// arc length; `t` and `speed` are those of the point before it.
    pub fn sample_at_s(&self, s: f64) -> Waypoint {
        let Some((a, b, f, s)) = self.segment_at_s(s) else {
            return Waypoint::default();
        };
        match b {
            Some(b) => Self::between(a, b, f, self.start_time + a.t, s),
            None => Self::waypoint(a, self.start_time + a.t),
        }
    }

    /// The path point at arc length `s` (clamped to the path), every field
    /// interpolated between its neighbours; `t` is 0, for [`Trajectory::new`] to
    /// fill, and so is `wait` but at the path's end, which is its last point as it is.
    pub(crate) fn point_at_s(&self, s: f64) -> PathPoint {
        let Some((a, b, f, s)) = self.segment_at_s(s) else {
            return PathPoint::default();
        };
        let Some(b) = b else {
            return PathPoint { t: 0.0, ..*a };
        };
        let lerp = |u: f64, v: f64| u + (v - u) * f;
        PathPoint {
            x: lerp(a.x, b.x),
            y: lerp(a.y, b.y),
            ground: lerp(a.ground, b.ground),
            head_height: lerp(a.head_height, b.head_height),
            s,
            curvature: lerp(a.curvature, b.curvature),
            slope: lerp(a.slope, b.slope),
            v_cap: lerp(a.v_cap, b.v_cap),
            v: lerp(a.v, b.v),
            t: 0.0,
            wait: 0.0,
        }
    }

    /// Where arc length `s` (clamped to the path) lies: the point before it, the one
    /// after it (none at the path's end), the share of the way between them and the
    /// clamped `s`. `None` for an empty path.
    fn segment_at_s(&self, s: f64) -> Option<(&PathPoint, Option<&PathPoint>, f64, f64)> {
        let first = self.points.first()?;
        let last = self.points.last()?;
        let s = s.clamp(first.s, last.s);
        let i = self
            .points
            .partition_point(|p| p.s <= s)
            .clamp(1, self.points.len());
        let a = &self.points[i - 1];
        let b = self.points.get(i);
        let f = match b {
            Some(b) if b.s > a.s => (s - a.s) / (b.s - a.s),
            _ => 0.0,
        };
        Some((a, b, f, s))
    }

    /// Absolute time \[s\] at which the plan first reaches arc length `s`: the start
    /// time before the path, the end time beyond it.
    pub fn time_at_s(&self, s: f64) -> f64 {
        let i = self.points.partition_point(|p| p.s < s);
        if i == 0 || i == self.points.len() {
            return self.start_time + self.points.get(i).map_or(self.duration(), |p| p.t);
        }
        let (a, b) = (&self.points[i - 1], &self.points[i]);
        let ds = b.s - a.s;
        let acc = (b.v * b.v - a.v * a.v) / (2.0 * ds);
        let s_in = s - a.s;
        // s_in = v tau + acc tau^2 / 2, on a segment travelled at constant acceleration.
        let tau = if acc.abs() < 1e-12 {
            if a.v > 1e-12 {
                s_in / a.v
            } else {
                f64::INFINITY
            }
        } else {
            let d = a.v * a.v + 2.0 * acc * s_in;
            (d.max(0.0).sqrt() - a.v) / acc
        };
        self.start_time + a.t + tau.clamp(0.0, b.t - a.t)
    }

    /// How far along the path \[m\] the plan at time `now` is ahead of the path point
    /// nearest (x, y): the head's lag, 0 where it is ahead.
    pub fn lag_at(&self, now: f64, x: f64, y: f64) -> f64 {
        self.closest_point(x, y).map_or(0.0, |(i, _)| {
            (self.sample_at(now).s - self.points[i].s).max(0.0)
        })
    }

    /// Index of the path point nearest to (x, y) and its distance \[m\].
    pub fn closest_point(&self, x: f64, y: f64) -> Option<(usize, f64)> {
        self.points
            .iter()
            .enumerate()
            .map(|(i, p)| (i, (p.x - x).powi(2) + (p.y - y).powi(2)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, d)| (i, d.sqrt()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight(v: &[f64]) -> Trajectory {
        let pts = v
            .iter()
            .enumerate()
            .map(|(i, &v)| PathPoint {
                x: i as f64,
                s: i as f64,
                head_height: 1.47,
                v,
                ..Default::default()
            })
            .collect();
        Trajectory::new(10.0, pts)
    }

    /// A path 0.5 m north, then east: its first metre heads between the two, a
    /// shorter span north, a path of one point nowhere.
    #[test]
    fn the_heading_is_that_of_the_paths_first_span() {
        let pt = |x: f64, y: f64, s: f64| PathPoint {
            x,
            y,
            s,
            v: 1.0,
            ..Default::default()
        };
        let tr = Trajectory::new(
            0.0,
            vec![
                pt(0.0, 0.0, 0.0),
                pt(0.0, 0.5, 0.5),
                pt(0.5, 0.5, 1.0),
                pt(3.0, 0.5, 3.5),
            ],
        );
        let h = tr.heading_over(1.0).unwrap();
        assert!((h - std::f64::consts::FRAC_PI_4).abs() < 1e-12, "{h}");
        let h = tr.heading_over(0.4).unwrap();
        assert!((h - std::f64::consts::FRAC_PI_2).abs() < 1e-12, "{h}");
        // Longer than the path: to its end.
        let h = tr.heading_over(10.0).unwrap();
        assert!((h - 0.5f64.atan2(3.0)).abs() < 1e-12, "{h}");
        assert_eq!(
            Trajectory::new(0.0, vec![pt(1.0, 1.0, 0.0)]).heading_over(1.0),
            None
        );
    }

    #[test]
    fn constant_speed_samples_are_evenly_spaced() {
        let tr = straight(&[2.0; 11]);
        assert!((tr.duration() - 5.0).abs() < 1e-12);
        let w = tr.next_waypoints(10.0, 10, 0.5);
        assert_eq!(w.len(), 10);
        for (k, wp) in w.iter().enumerate() {
            assert!((wp.position[0] - (k as f64 + 1.0)).abs() < 1e-9);
            assert!((wp.position[2] - 1.47).abs() < 1e-12);
        }
        // Past the end: hold the last point at rest.
        let end = tr.sample_at(100.0);
        assert_eq!(end.position[0], 10.0);
        assert_eq!(end.speed, 0.0);
    }

    #[test]
    fn time_at_s_inverts_sample_at() {
        let v: Vec<f64> = (0..21).map(|i| 0.5 + 0.1 * i as f64).collect();
        let tr = straight(&v);
        for k in 1..40 {
            let t = 10.0 + 0.25 * k as f64;
            let w = tr.sample_at(t);
            assert!((tr.time_at_s(w.s) - t).abs() < 1e-9, "t {t}");
        }
        assert_eq!(tr.time_at_s(-1.0), 10.0);
        assert_eq!(tr.time_at_s(99.0), tr.end_time());
    }

    #[test]
    fn accelerating_from_rest_follows_s_equals_half_a_t_squared() {
        // b = 2 a s with a = 0.5: v_i = sqrt(i).
        let v: Vec<f64> = (0..21).map(|i| (i as f64).sqrt()).collect();
        let tr = straight(&v);
        for k in 1..8 {
            let t = k as f64 * 0.5;
            let w = tr.sample_at(10.0 + t);
            assert!((w.s - 0.25 * t * t).abs() < 1e-9, "t {t}: s {}", w.s);
            assert!((w.speed - 0.5 * t).abs() < 1e-9);
        }
    }
}
