//! Metrics every run computes: the paper's path reward r_tau (4.2), head tracking
//! errors (Table 2's XY-err / Z-err), falls, landmark success, completion time and the
//! size of the residual root wrench.
//!
//! Feed a [`MetricsAccumulator`] one [`StepSample`] per control step (30 Hz) and read
//! a [`MetricsSummary`] at the end.
//!
//! # The path reward, term by term
//!
//! With the head at `s` and the plan's head point for the same time at `tau`:
//! - position: `exp(-c_pos * |tau_xy - s_xy|^2)`, `c_pos = 2` \[1/m^2\];
//! - height: `exp(-c_height * (tau_z - s_z)^2)`, `c_height = 10` \[1/m^2\];
//! - direction: `exp(-c_dir * (dyaw^2 + dpitch^2))`, `c_dir = 20` \[1/rad^2\], where
//!   dyaw / dpitch compare the head's facing direction with the path's direction of
//!   travel (yaw wrapped to (-pi, pi]); when the plan does not move (no direction)
//!   the term is 1;
//! - body: `c_body * (z_head - max_{b != head} z_b)`, `c_body = 0.1` \[1/m\], as written
//!   in the paper (positive when the head is the highest point).
//!
//! `r_tau` is their sum (at most 3 plus the body term). ProtoMotions' path follower
//! averages position and height; we keep the paper's sum and also report each term.
//!
//! # Lag and drift
//!
//! The XY error is split along the plan's direction of travel at the same time: the
//! along-track part is schedule (the head behind or ahead of its point), the
//! cross-track part is the head off the route. A constant-speed path the humanoid
//! follows exactly but slower has all of its XY error along the track.

use serde::{Deserialize, Serialize};

use crate::math::{norm3, wrap_angle};
use crate::policy::RootWrench;

/// Coefficients of r_tau (paper 4.2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PathRewardWeights {
    /// c_pos \[1/m^2\], paper: 2.
    pub c_pos: f64,
    /// c_height \[1/m^2\], paper: 10.
    pub c_height: f64,
    /// c_dir \[1/rad^2\], paper: 20.
    pub c_dir: f64,
    /// c_body \[1/m\], paper: 0.1.
    pub c_body: f64,
}

impl Default for PathRewardWeights {
    fn default() -> Self {
        Self {
            c_pos: 2.0,
            c_height: 10.0,
            c_dir: 20.0,
            c_body: 0.1,
        }
    }
}

/// The terms of r_tau at one step.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct RewardTerms {
    /// Position term, in (0, 1].
    pub pos: f64,
    /// Height term, in (0, 1].
    pub height: f64,
    /// Direction term, in (0, 1].
    pub dir: f64,
    /// Body term (signed).
    pub body: f64,
    /// r_tau = pos + height + dir + body.
    pub total: f64,
}

/// What the metrics need from one control step. World frame, metres, radians.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepSample {
    /// Simulated time \[s\].
    pub t: f64,
    /// Head position.
    pub head: [f64; 3],
    /// The plan's head position at time `t`.
    pub target: [f64; 3],
    /// The head's facing direction (any length; zero = unknown, term counts as 1).
    pub head_dir: [f64; 3],
    /// The plan's direction of travel at `t` (any length; zero = standing still).
    pub path_dir: [f64; 3],
    /// Highest Z of every body other than the head \[m\].
    pub max_other_body_z: f64,
    /// Whether the humanoid is fallen at this step (see
    /// [`crate::ControllerSettings::is_fallen`]).
    pub fallen: bool,
    /// Residual root wrench applied during this step, if any.
    pub residual: Option<RootWrench>,
}

/// Yaw and pitch \[rad\] of a direction, `None` for a zero vector.
fn yaw_pitch(d: [f64; 3]) -> Option<(f64, f64)> {
    let h = (d[0] * d[0] + d[1] * d[1]).sqrt();
    if h + d[2].abs() < 1e-9 {
        return None;
    }
    Some((d[1].atan2(d[0]), d[2].atan2(h)))
}

/// r_tau and its terms for one step.
pub fn path_reward(w: &PathRewardWeights, s: &StepSample) -> RewardTerms {
    let dx = s.target[0] - s.head[0];
    let dy = s.target[1] - s.head[1];
    let dz = s.target[2] - s.head[2];
    let pos = (-w.c_pos * (dx * dx + dy * dy)).exp();
    let height = (-w.c_height * dz * dz).exp();
    let dir = match (yaw_pitch(s.path_dir), yaw_pitch(s.head_dir)) {
        (Some((py, pp)), Some((hy, hp))) => {
            let dyaw = wrap_angle(py - hy);
            let dpitch = pp - hp;
            (-w.c_dir * (dyaw * dyaw + dpitch * dpitch)).exp()
        }
        _ => 1.0,
    };
    let body = w.c_body * (s.head[2] - s.max_other_body_z);
    RewardTerms {
        pos,
        height,
        dir,
        body,
        total: pos + height + dir + body,
    }
}

/// End-of-run metrics (serialisable into reports).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct MetricsSummary {
    /// Control steps recorded.
    pub steps: u64,
    /// Simulated time from the first to the last sample \[s\].
    pub duration_s: f64,
    /// Mean r_tau and mean of each term.
    pub mean_reward: RewardTerms,
    /// Mean horizontal head error against the plan at the same time \[m\].
    pub xy_err_mean: f64,
    /// Largest horizontal head error \[m\].
    pub xy_err_max: f64,
    /// Mean along-track part of the XY error, signed: positive while the head is
    /// behind its plan point \[m\]. Over the steps on which the plan moves (see
    /// [`Self::moving_steps`]).
    #[serde(default)]
    pub lag_mean: f64,
    /// Mean absolute cross-track part of the XY error: how far the head is off the
    /// route, whatever the schedule \[m\]. Over the same steps as `lag_mean`.
    #[serde(default)]
    pub cross_track_mean: f64,
    /// Steps on which the plan's direction of travel had a horizontal part (the
    /// steps `lag_mean` and `cross_track_mean` average over).
    #[serde(default)]
    pub moving_steps: u64,
    /// Mean absolute head height error \[m\].
    pub z_err_mean: f64,
    /// Largest absolute head height error \[m\].
    pub z_err_max: f64,
    /// Fall events (transitions from standing to fallen).
    pub falls: u32,
    /// Fraction of steps spent fallen \[-\].
    pub fallen_fraction: f64,
    /// Landmarks reached, in order, with the time they were reached \[s\].
    pub landmarks_reached: Vec<(String, f64)>,
    /// Landmarks the run had to reach.
    pub landmarks_expected: Vec<String>,
    /// Every expected landmark was reached.
    pub success: bool,
    /// Time the last expected landmark was reached \[s\], if it was.
    pub completion_time_s: Option<f64>,
    /// Steps on which a residual wrench was present.
    pub residual_steps: u64,
    /// Mean residual force over all steps, fraction of body weight m*g \[-\].
    pub residual_force_mean: f64,
    /// Peak residual force, fraction of body weight \[-\].
    pub residual_force_peak: f64,
    /// Mean residual torque magnitude over all steps \[N m\].
    pub residual_torque_mean: f64,
    /// Peak residual torque magnitude \[N m\].
    pub residual_torque_peak: f64,
}

impl MetricsSummary {
    /// One row of a sweep over several runs: mean falls per run, mean XY error (and the
    /// worst), mean Z error, mean residual force (and the peak, fraction of m*g) and
    /// the mean heading term of the path reward.
    pub fn sweep_row(runs: &[Self]) -> String {
        let k = runs.len().max(1) as f64;
        let mean = |f: &dyn Fn(&Self) -> f64| runs.iter().map(f).sum::<f64>() / k;
        let max = |f: &dyn Fn(&Self) -> f64| runs.iter().map(f).fold(0.0, f64::max);
        format!(
            "falls/run {:.2} xy {:.3} (max {:.2}) z {:.3} residual {:.3} (peak {:.3}) torque {:.1} N m dir {:.3}",
            mean(&|m| f64::from(m.falls)),
            mean(&|m| m.xy_err_mean),
            max(&|m| m.xy_err_max),
            mean(&|m| m.z_err_mean),
            mean(&|m| m.residual_force_mean),
            max(&|m| m.residual_force_peak),
            mean(&|m| m.residual_torque_mean),
            mean(&|m| m.mean_reward.dir),
        )
    }
}

/// Accumulates [`StepSample`]s of one run.
#[derive(Debug, Clone)]
pub struct MetricsAccumulator {
    weights: PathRewardWeights,
    body_weight: f64,
    expected: Vec<String>,
    reached: Vec<(String, f64)>,
    steps: u64,
    t_first: f64,
    t_last: f64,
    reward: RewardTerms,
    xy_sum: f64,
    xy_max: f64,
    lag_sum: f64,
    cross_sum: f64,
    moving_steps: u64,
    z_sum: f64,
    z_max: f64,
    falls: u32,
    fallen_steps: u64,
    was_fallen: bool,
    residual_steps: u64,
    force_sum: f64,
    force_peak: f64,
    torque_sum: f64,
    torque_peak: f64,
}

impl MetricsAccumulator {
    /// A new accumulator. `body_weight` is m*g \[N\]; `expected_landmarks` are the
    /// landmarks the run must reach for success (empty: success = no landmark needed).
    pub fn new(
        weights: PathRewardWeights,
        body_weight: f64,
        expected_landmarks: Vec<String>,
    ) -> Self {
        Self {
            weights,
            body_weight,
            expected: expected_landmarks,
            reached: Vec::new(),
            steps: 0,
            t_first: 0.0,
            t_last: 0.0,
            reward: RewardTerms::default(),
            xy_sum: 0.0,
            xy_max: 0.0,
            lag_sum: 0.0,
            cross_sum: 0.0,
            moving_steps: 0,
            z_sum: 0.0,
            z_max: 0.0,
            falls: 0,
            fallen_steps: 0,
            was_fallen: false,
            residual_steps: 0,
            force_sum: 0.0,
            force_peak: 0.0,
            torque_sum: 0.0,
            torque_peak: 0.0,
        }
    }

    /// Records one control step; returns its reward terms.
    pub fn push(&mut self, s: &StepSample) -> RewardTerms {
        if self.steps == 0 {
            self.t_first = s.t;
        }
        self.t_last = s.t;
        self.steps += 1;
        let r = path_reward(&self.weights, s);
        self.reward.pos += r.pos;
        self.reward.height += r.height;
        self.reward.dir += r.dir;
        self.reward.body += r.body;
        self.reward.total += r.total;
        let (ex, ey) = (s.target[0] - s.head[0], s.target[1] - s.head[1]);
        // Not `hypot`: the summaries (and the tuner's costs) stay bit-identical to before.
        let xy = (ex.powi(2) + ey.powi(2)).sqrt();
        let dir_len = s.path_dir[0].hypot(s.path_dir[1]);
        if dir_len > 1e-9 {
            let (ux, uy) = (s.path_dir[0] / dir_len, s.path_dir[1] / dir_len);
            self.lag_sum += ex * ux + ey * uy;
            self.cross_sum += (ex * uy - ey * ux).abs();
            self.moving_steps += 1;
        }
        let z = (s.target[2] - s.head[2]).abs();
        self.xy_sum += xy;
        self.xy_max = self.xy_max.max(xy);
        self.z_sum += z;
        self.z_max = self.z_max.max(z);
        if s.fallen {
            self.fallen_steps += 1;
            if !self.was_fallen {
                self.falls += 1;
            }
        }
        self.was_fallen = s.fallen;
        if let Some(w) = s.residual {
            self.residual_steps += 1;
            let f = norm3(w.force) / self.body_weight;
            let tq = norm3(w.torque);
            self.force_sum += f;
            self.force_peak = self.force_peak.max(f);
            self.torque_sum += tq;
            self.torque_peak = self.torque_peak.max(tq);
        }
        r
    }

    /// Records that `name` was reached at time `t` \[s\] (repeats are ignored).
    pub fn landmark_reached(&mut self, name: &str, t: f64) {
        if !self.reached.iter().any(|(n, _)| n == name) {
            self.reached.push((name.to_string(), t));
        }
    }

    /// Fall events so far (the count [`Self::summary`] reports).
    pub fn falls(&self) -> u32 {
        self.falls
    }

    /// The summary so far.
    pub fn summary(&self) -> MetricsSummary {
        let n = self.steps.max(1) as f64;
        let mean = |x: f64| x / n;
        let per_moving = |x: f64| x / self.moving_steps.max(1) as f64;
        let success = self
            .expected
            .iter()
            .all(|e| self.reached.iter().any(|(n, _)| n == e));
        let completion_time_s = if success && !self.expected.is_empty() {
            self.reached
                .iter()
                .filter(|(n, _)| self.expected.contains(n))
                .map(|(_, t)| *t)
                .fold(None, |acc: Option<f64>, t| {
                    Some(acc.map_or(t, |a| a.max(t)))
                })
        } else {
            None
        };
        MetricsSummary {
            steps: self.steps,
            duration_s: self.t_last - self.t_first,
            mean_reward: RewardTerms {
                pos: mean(self.reward.pos),
                height: mean(self.reward.height),
                dir: mean(self.reward.dir),
                body: mean(self.reward.body),
                total: mean(self.reward.total),
            },
            xy_err_mean: mean(self.xy_sum),
            xy_err_max: self.xy_max,
            lag_mean: per_moving(self.lag_sum),
            cross_track_mean: per_moving(self.cross_sum),
            moving_steps: self.moving_steps,
            z_err_mean: mean(self.z_sum),
            z_err_max: self.z_max,
            falls: self.falls,
            fallen_fraction: mean(self.fallen_steps as f64),
            landmarks_reached: self.reached.clone(),
            landmarks_expected: self.expected.clone(),
            success,
            completion_time_s,
            residual_steps: self.residual_steps,
            residual_force_mean: mean(self.force_sum),
            residual_force_peak: self.force_peak,
            residual_torque_mean: mean(self.torque_sum),
            residual_torque_peak: self.torque_peak,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(t: f64, head: [f64; 3], target: [f64; 3]) -> StepSample {
        StepSample {
            t,
            head,
            target,
            head_dir: [1.0, 0.0, 0.0],
            path_dir: [1.0, 0.0, 0.0],
            max_other_body_z: head[2] - 0.1,
            fallen: false,
            residual: None,
        }
    }

    #[test]
    fn perfect_tracking_scores_three_plus_body_term() {
        let r = path_reward(
            &PathRewardWeights::default(),
            &sample(0.0, [1.0, 2.0, 1.47], [1.0, 2.0, 1.47]),
        );
        assert!((r.pos - 1.0).abs() < 1e-12 && (r.height - 1.0).abs() < 1e-12);
        assert!((r.dir - 1.0).abs() < 1e-12);
        assert!((r.body - 0.01).abs() < 1e-12);
        assert!((r.total - 3.01).abs() < 1e-12);
    }

    #[test]
    fn each_term_uses_its_coefficient() {
        let w = PathRewardWeights::default();
        let mut s = sample(0.0, [0.0, 0.0, 1.0], [0.5, 0.0, 1.2]);
        s.head_dir = [0.0, 1.0, 0.0]; // facing 90 degrees off the path
        let r = path_reward(&w, &s);
        assert!((r.pos - (-2.0f64 * 0.25).exp()).abs() < 1e-12);
        assert!((r.height - (-10.0f64 * 0.04).exp()).abs() < 1e-12);
        let dyaw = std::f64::consts::FRAC_PI_2;
        assert!((r.dir - (-20.0 * dyaw * dyaw).exp()).abs() < 1e-12);
        // Yaw wraps: -179 deg vs +179 deg is 2 deg apart.
        s.head_dir = [-1.0, 0.01, 0.0];
        s.path_dir = [-1.0, -0.01, 0.0];
        assert!(path_reward(&w, &s).dir > 0.99);
    }

    #[test]
    fn errors_falls_residual_and_success() {
        let mut acc = MetricsAccumulator::new(
            PathRewardWeights::default(),
            700.0,
            vec!["tree".into(), "car".into()],
        );
        let mut s = sample(0.0, [0.0, 0.0, 1.4], [0.3, 0.4, 1.5]);
        s.residual = Some(RootWrench {
            force: [70.0, 0.0, 0.0],
            torque: [0.0, 0.0, 10.0],
        });
        acc.push(&s);
        s.t = 1.0;
        s.fallen = true;
        s.residual = Some(RootWrench {
            force: [0.0, 210.0, 0.0],
            torque: [0.0, 0.0, 0.0],
        });
        acc.push(&s);
        s.t = 2.0;
        acc.push(&s); // still fallen: same fall
        s.t = 3.0;
        s.fallen = false;
        acc.push(&s);
        s.t = 4.0;
        s.fallen = true;
        s.residual = None;
        acc.push(&s);
        acc.landmark_reached("tree", 2.5);
        let m = acc.summary();
        assert_eq!(m.steps, 5);
        assert_eq!(m.falls, 2);
        assert!((m.xy_err_mean - 0.5).abs() < 1e-12);
        assert!((m.z_err_mean - 0.1).abs() < 1e-9);
        assert!((m.residual_force_peak - 0.3).abs() < 1e-12);
        assert!((m.residual_force_mean - (0.1 + 0.3 * 3.0) / 5.0).abs() < 1e-12);
        assert!((m.residual_torque_peak - 10.0).abs() < 1e-12);
        assert!(!m.success && m.completion_time_s.is_none());
        acc.landmark_reached("car", 3.5);
        acc.landmark_reached("car", 9.0);
        let m = acc.summary();
        assert!(m.success);
        assert_eq!(m.completion_time_s, Some(3.5));
        let json = serde_json::to_string(&m).unwrap();
        assert!(json.contains("residual_force_mean"));
    }

    #[test]
    fn xy_error_splits_into_lag_along_the_path_and_drift_across_it() {
        let mut acc = MetricsAccumulator::new(PathRewardWeights::default(), 700.0, vec![]);
        // Path heading +y: a head 0.3 m behind and 0.4 m to its side.
        let mut s = sample(0.0, [0.4, -0.3, 1.4], [0.0, 0.0, 1.4]);
        s.path_dir = [0.0, 2.0, 0.0];
        acc.push(&s);
        // Ahead of its point by 0.1 m, on the route.
        s.head = [0.0, 0.1, 1.4];
        acc.push(&s);
        // A plan standing still adds to the XY error only.
        s.head = [1.0, 0.0, 1.4];
        s.path_dir = [0.0, 0.0, 0.0];
        acc.push(&s);
        let m = acc.summary();
        assert_eq!(m.moving_steps, 2);
        assert!(
            (m.lag_mean - (0.3 - 0.1) / 2.0).abs() < 1e-12,
            "{}",
            m.lag_mean
        );
        assert!((m.cross_track_mean - 0.4 / 2.0).abs() < 1e-12);
        assert!((m.xy_err_mean - (0.5 + 0.1 + 1.0) / 3.0).abs() < 1e-12);
        // Older summaries without the split still read.
        let old = r#"{"steps":1,"duration_s":0,"mean_reward":{"pos":1,"height":1,"dir":1,"body":0,"total":3},"xy_err_mean":0,"xy_err_max":0,"z_err_mean":0,"z_err_max":0,"falls":0,"fallen_fraction":0,"landmarks_reached":[],"landmarks_expected":[],"success":true,"completion_time_s":null,"residual_steps":0,"residual_force_mean":0,"residual_force_peak":0,"residual_torque_mean":0,"residual_torque_peak":0}"#;
        let back: MetricsSummary = serde_json::from_str(old).unwrap();
        assert_eq!(back.moving_steps, 0);
    }
}
