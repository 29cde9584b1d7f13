//! Stage 4: minimum travel time along the refined path, solved with Clarabel.
//!
//! Variables b_i = v_i^2 (Lipp & Boyd 2014). Every constraint is linear in b:
//!
//! * 0 <= b_i <= b_max_i (speed range: the locomotion's top speed capped by head
//!   height v_max(z) and by slope; lateral acceleration b_i * kappa_i <= a_lat);
//! * b_{i+1} - b_i <= 2 a_max ds_i (acceleration) and
//!   b_i - b_{i+1} <= 2 |a_min| ds_i (deceleration; a_min < 0 by convention);
//! * b_0 <= v_0^2 (start no faster than now), optionally b_{N-1} <= b_end.
//!
//! Travel time T(b) = sum 2 ds_i / (sqrt(b_i) + sqrt(b_{i+1})) is convex and
//! strictly decreasing in every b_i. The feasible set is closed under pointwise
//! maximum, so it has a greatest element b*, which is feasible and >= every feasible
//! b component-wise; hence b* minimises T *and* every other strictly decreasing
//! objective. [`solve_speed_qp`] therefore solves the QP
//! min 1/2 sum (b_i - b_max_i)^2 over the same constraints: same optimum as the
//! time objective, N variables, no cones beyond the nonnegative orthant, and a
//! fraction of the cost. [`solve_speed_socp`] minimises T itself with the standard
//! conic reformulation (c_i <= sqrt(b_i) as ||(2 c_i, b_i - 1)|| <= b_i + 1 and
//! d_i (c_i + c_{i+1}) >= 1 as ||(2, c_i + c_{i+1} - d_i)|| <= c_i + c_{i+1} + d_i,
//! objective sum 2 ds_i d_i). Both are checked against the exact forward-backward
//! oracle (`speed_oracle`).

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SecondOrderConeT, SolverStatus,
    SupportedConeT,
};

use crate::speed_oracle::SpeedProblem;
use crate::{PlanError, SpeedFailure};

fn settings() -> DefaultSettings<f64> {
    DefaultSettings {
        verbose: false,
        max_iter: 200,
        tol_gap_abs: 1e-7,
        tol_gap_rel: 1e-7,
        tol_feas: 1e-7,
        iterative_refinement_enable: false,
        ..DefaultSettings::default()
    }
}

fn status_to_result(status: SolverStatus) -> Result<(), PlanError> {
    match status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => Ok(()),
        SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
            Err(PlanError::Speed(SpeedFailure::Infeasible))
        }
        _ => Err(PlanError::Speed(SpeedFailure::NotConverged)),
    }
}

/// Solve the speed problem as a QP (see the module doc); returns b_i = v_i^2.
pub fn solve_speed_qp(p: &SpeedProblem) -> Result<Vec<f64>, PlanError> {
    p.check()?;
    let n = p.b_max.len();
    if n == 1 {
        return Ok(vec![p.upper(0)]);
    }
    let upper: Vec<f64> = (0..n).map(|i| p.upper(i).max(0.0)).collect();
    // Scale b by the largest bound so the problem is O(1).
    let scale = upper.iter().fold(1e-9f64, |a, &b| a.max(b));
    let mut ri = Vec::with_capacity(6 * n);
    let mut ci = Vec::with_capacity(6 * n);
    let mut vi = Vec::with_capacity(6 * n);
    let mut bv = Vec::with_capacity(4 * n);
    let mut row = 0usize;
    for (i, u) in upper.iter().enumerate() {
        // b_i <= upper_i
        ri.push(row);
        ci.push(i);
        vi.push(1.0);
        bv.push(u / scale);
        row += 1;
        // No b_i >= 0 row: the optimum b* >= 0 is the greatest feasible point with
        // or without it, so it is never active.
    }
    for i in 0..n - 1 {
        // b_{i+1} - b_i <= 2 a_max ds_i
        ri.extend([row, row]);
        ci.extend([i + 1, i]);
        vi.extend([1.0, -1.0]);
        bv.push(2.0 * p.accel * p.ds[i] / scale);
        row += 1;
        // b_i - b_{i+1} <= 2 |a_min| ds_i
        ri.extend([row, row]);
        ci.extend([i, i + 1]);
        vi.extend([1.0, -1.0]);
        bv.push(2.0 * p.decel * p.ds[i] / scale);
        row += 1;
    }
    let a = CscMatrix::new_from_triplets(row, n, ri, ci, vi);
    let pm = CscMatrix::new_from_triplets(n, n, (0..n).collect(), (0..n).collect(), vec![1.0; n]);
    let q: Vec<f64> = upper.iter().map(|u| -u / scale).collect();
    let cones = [NonnegativeConeT(row)];
    let mut solver = DefaultSolver::new(&pm, &q, &a, &bv, &cones, settings())
        .map_err(|_| PlanError::Speed(SpeedFailure::BadProblem))?;
    solver.solve();
    status_to_result(solver.solution.status)?;
    let x = &solver.solution.x;
    Ok((0..n)
        .map(|i| (x[i] * scale).clamp(0.0, upper[i]))
        .collect())
}

/// Solve the speed problem in Lipp & Boyd's conic form (minimises travel time
/// directly); returns b_i = v_i^2 at every point. About 10x slower than
/// [`solve_speed_qp`] at N = 1000, kept as the literal time-objective formulation
/// and cross-checked against it and the oracle in tests.
pub fn solve_speed_socp(p: &SpeedProblem) -> Result<Vec<f64>, PlanError> {
    p.check()?;
    let n = p.b_max.len();
    if n == 1 {
        return Ok(vec![p.upper(0)]);
    }
    let m = n - 1;
    let nv = 2 * n + m;
    let (ib, ic, id) = (0, n, 2 * n);
    // Triplets (row, col, value) of A in A x + s = b_vec, s in the cones.
    let mut ri = Vec::with_capacity(12 * n);
    let mut ci = Vec::with_capacity(12 * n);
    let mut vi = Vec::with_capacity(12 * n);
    let mut bv = Vec::with_capacity(12 * n);
    let mut row = 0usize;
    let mut put = |r: usize, c: usize, v: f64, ri: &mut Vec<usize>, ci: &mut Vec<usize>| {
        ri.push(r);
        ci.push(c);
        vi.push(v);
    };
    // Nonnegative cone block: box and difference bounds.
    for i in 0..n {
        put(row, ib + i, 1.0, &mut ri, &mut ci);
        bv.push(p.upper(i).max(0.0));
        row += 1;
    }
    for i in 0..m {
        put(row, ib + i + 1, 1.0, &mut ri, &mut ci);
        put(row, ib + i, -1.0, &mut ri, &mut ci);
        bv.push(2.0 * p.accel * p.ds[i]);
        row += 1;
        put(row, ib + i, 1.0, &mut ri, &mut ci);
        put(row, ib + i + 1, -1.0, &mut ri, &mut ci);
        bv.push(2.0 * p.decel * p.ds[i]);
        row += 1;
    }
    let n_nonneg = row;
    let mut cones: Vec<SupportedConeT<f64>> = vec![NonnegativeConeT(n_nonneg)];
    // c_i <= sqrt(b_i): s = (b_i + 1, 2 c_i, b_i - 1) = bv - A x.
    for i in 0..n {
        put(row, ib + i, -1.0, &mut ri, &mut ci);
        bv.push(1.0);
        put(row + 1, ic + i, -2.0, &mut ri, &mut ci);
        bv.push(0.0);
        put(row + 2, ib + i, -1.0, &mut ri, &mut ci);
        bv.push(-1.0);
        row += 3;
        cones.push(SecondOrderConeT(3));
    }
    // d_i (c_i + c_{i+1}) >= 1: s = (u + d, 2, u - d).
    for i in 0..m {
        put(row, ic + i, -1.0, &mut ri, &mut ci);
        put(row, ic + i + 1, -1.0, &mut ri, &mut ci);
        put(row, id + i, -1.0, &mut ri, &mut ci);
        bv.push(0.0);
        bv.push(2.0);
        put(row + 2, ic + i, -1.0, &mut ri, &mut ci);
        put(row + 2, ic + i + 1, -1.0, &mut ri, &mut ci);
        put(row + 2, id + i, 1.0, &mut ri, &mut ci);
        bv.push(0.0);
        row += 3;
        cones.push(SecondOrderConeT(3));
    }
    let a = CscMatrix::new_from_triplets(row, nv, ri, ci, vi);
    let pm = CscMatrix::zeros((nv, nv));
    let mut q = vec![0.0; nv];
    for i in 0..m {
        q[id + i] = 2.0 * p.ds[i];
    }
    let mut solver = DefaultSolver::new(&pm, &q, &a, &bv, &cones, settings())
        .map_err(|_| PlanError::Speed(SpeedFailure::BadProblem))?;
    solver.solve();
    status_to_result(solver.solution.status)?;
    let x = &solver.solution.x;
    Ok((0..n).map(|i| x[ib + i].clamp(0.0, p.upper(i))).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::speed_oracle::{forward_backward, travel_time};
    use proptest::prelude::*;

    fn problem(caps: Vec<f64>, ds: f64, start: Option<f64>) -> SpeedProblem {
        SpeedProblem {
            ds: vec![ds; caps.len() - 1],
            b_max: caps,
            b_start: start,
            b_end: None,
            accel: 0.5,
            decel: 0.1,
        }
    }

    #[test]
    fn matches_the_oracle_on_a_slow_corner() {
        let mut caps = vec![16.0; 300];
        for c in caps.iter_mut().skip(140).take(20) {
            *c = 0.5;
        }
        let p = problem(caps, 0.1, Some(0.0));
        let bo = forward_backward(&p).unwrap();
        let to = travel_time(&p.ds, &bo);
        for b in [solve_speed_qp(&p).unwrap(), solve_speed_socp(&p).unwrap()] {
            let t = travel_time(&p.ds, &b);
            assert!((t - to).abs() / to < 1e-3, "solver {t} oracle {to}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        /// Random paths: random curvature bumps turned into lateral caps, random
        /// slope slowdowns, random start speed. The QP's travel time is within 1% of
        /// the exact forward-backward optimum.
        #[test]
        fn qp_within_one_percent_of_oracle(
            n in 20usize..400,
            ds in 0.05f64..0.3,
            v_top in 1.0f64..5.0,
            bumps in proptest::collection::vec((0.0f64..1.0, 0.05f64..2.0, 1usize..30), 0..6),
            v0 in proptest::option::of(0.0f64..5.0),
            accel in 0.2f64..2.0,
            decel in 0.05f64..2.0,
        ) {
            let mut caps = vec![v_top * v_top; n];
            for (pos, kappa, width) in bumps {
                let c = (pos * (n - 1) as f64) as usize;
                for cap in caps.iter_mut().skip(c.saturating_sub(width)).take(2 * width) {
                    *cap = cap.min(1.0 / kappa);
                }
            }
            let p = SpeedProblem {
                ds: vec![ds; n - 1],
                b_max: caps,
                b_start: v0.map(|v| v * v),
                b_end: None,
                accel,
                decel,
            };
            let bq = solve_speed_qp(&p).unwrap();
            let bs = solve_speed_socp(&p).unwrap();
            let bo = forward_backward(&p).unwrap();
            let (tq, ts, to) = (travel_time(&p.ds, &bq), travel_time(&p.ds, &bs), travel_time(&p.ds, &bo));
            prop_assert!((tq - to).abs() / to < 0.01, "qp {} oracle {}", tq, to);
            prop_assert!((ts - to).abs() / to < 0.01, "socp {} oracle {}", ts, to);
            for i in 0..n - 1 {
                prop_assert!(bq[i + 1] - bq[i] <= 2.0 * accel * ds + 1e-5);
                prop_assert!(bq[i] - bq[i + 1] <= 2.0 * decel * ds + 1e-5);
            }
        }
    }
}
