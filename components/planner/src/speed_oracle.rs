//! The exact forward-backward speed profile: the test oracle for the QP.
//!
//! In b = v^2 the constraints are box bounds 0 <= b_i <= b_max_i, optional upper
//! bounds b_0 <= b_start and b_{N-1} <= b_end, and difference bounds
//! -2 |a_min| ds_i <= b_{i+1} - b_i <= 2 a_max ds_i. The feasible set is closed
//! under pointwise maximum and travel time decreases in every b_i, so the unique
//! optimum is the pointwise-largest feasible profile, which one forward pass
//! (acceleration) and one backward pass (deceleration) compute exactly in O(N).

use crate::{PlanError, SpeedFailure};

/// A minimum-time speed problem on a fixed path, in b = v^2 (Lipp & Boyd 2014).
#[derive(Debug, Clone, PartialEq)]
pub struct SpeedProblem {
    /// Segment lengths ds_i between point i and i+1 \[m\], N-1 values, > 0.
    pub ds: Vec<f64>,
    /// Upper bound on b_i = v_i^2 at every point \[m^2/s^2\], N values, >= 0.
    pub b_max: Vec<f64>,
    /// Upper bound on b_0 (the current speed squared), if any \[m^2/s^2\].
    pub b_start: Option<f64>,
    /// Upper bound on b_{N-1}, if any \[m^2/s^2\].
    pub b_end: Option<f64>,
    /// a_max \[m/s^2\], > 0.
    pub accel: f64,
    /// |a_min| \[m/s^2\], > 0.
    pub decel: f64,
}

impl SpeedProblem {
    pub(crate) fn check(&self) -> Result<(), PlanError> {
        let n = self.b_max.len();
        let bad = n == 0
            || self.ds.len() + 1 != n
            || self.ds.iter().any(|d| !(d.is_finite() && *d > 0.0))
            || self.b_max.iter().any(|b| !(b.is_finite() && *b >= 0.0))
            || !(self.accel > 0.0 && self.decel > 0.0)
            || self.b_start.is_some_and(|b| b.is_nan() || b < 0.0)
            || self.b_end.is_some_and(|b| b.is_nan() || b < 0.0);
        if bad {
            return Err(PlanError::Speed(SpeedFailure::BadProblem));
        }
        Ok(())
    }

    /// Effective upper bound at point i (b_max with the start/end bounds folded in).
    pub(crate) fn upper(&self, i: usize) -> f64 {
        let n = self.b_max.len();
        let mut u = self.b_max[i];
        if i == 0
            && let Some(b) = self.b_start
        {
            u = u.min(b);
        }
        if i == n - 1
            && let Some(b) = self.b_end
        {
            u = u.min(b);
        }
        u
    }
}

/// The exact optimum b_i by the forward-backward passes.
pub fn forward_backward(p: &SpeedProblem) -> Result<Vec<f64>, PlanError> {
    p.check()?;
    let n = p.b_max.len();
    let mut b: Vec<f64> = (0..n).map(|i| p.upper(i)).collect();
    for i in 0..n - 1 {
        b[i + 1] = b[i + 1].min(b[i] + 2.0 * p.accel * p.ds[i]);
    }
    for i in (0..n - 1).rev() {
        b[i] = b[i].min(b[i + 1] + 2.0 * p.decel * p.ds[i]);
    }
    Ok(b)
}

/// Travel time of a profile: sum of 2 ds_i / (sqrt(b_i) + sqrt(b_{i+1})) \[s\]
/// (exact for constant acceleration on each segment); infinite if a segment has
/// zero speed at both ends.
pub fn travel_time(ds: &[f64], b: &[f64]) -> f64 {
    ds.iter()
        .enumerate()
        .map(|(i, d)| 2.0 * d / (b[i].max(0.0).sqrt() + b[i + 1].max(0.0).sqrt()))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accelerates_cruises_and_brakes_for_a_slow_point() {
        let n = 201;
        let mut b_max = vec![16.0; n];
        b_max[150] = 1.0;
        let p = SpeedProblem {
            ds: vec![0.1; n - 1],
            b_max,
            b_start: Some(0.0),
            b_end: None,
            accel: 0.5,
            decel: 0.1,
        };
        let b = forward_backward(&p).unwrap();
        assert_eq!(b[0], 0.0);
        assert!((b[10] - 1.0).abs() < 1e-12); // 2 * 0.5 * 1.0 m
        assert_eq!(b[150], 1.0);
        assert!((b[140] - 1.2).abs() < 1e-12); // 1 + 2 * 0.1 * 1.0 m
        for i in 0..n - 1 {
            assert!(b[i + 1] - b[i] <= 2.0 * 0.5 * 0.1 + 1e-12);
            assert!(b[i] - b[i + 1] <= 2.0 * 0.1 * 0.1 + 1e-12);
        }
        assert!(travel_time(&p.ds, &b).is_finite());
    }
}
