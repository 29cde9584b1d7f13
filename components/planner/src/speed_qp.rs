//! Stage 4: minimum travel time along the refined path, solved with Clarabel.
//!
//! Lipp & Boyd's convex form in b_i = v_i^2. Travel time
//! T = sum 2 ds_i / (sqrt(b_i) + sqrt(b_{i+1})) is convex in b; the standard conic
//! reformulation adds c_i <= sqrt(b_i) and d_i >= 1 / (c_i + c_{i+1}) and minimises
//! sum 2 ds_i d_i, which is linear. With x = \[b (N), c (N), d (N-1)\]:
//!
//! * b_i <= b_max_i (speed range: locomotion top speed capped by head height and
//!   slope, and the lateral limit b_i * kappa_i <= a_lat), -b_i <= 0;
//! * b_{i+1} - b_i <= 2 a_max ds_i and b_i - b_{i+1} <= 2 |a_min| ds_i;
//! * c_i^2 <= b_i as the cone ||(2 c_i, b_i - 1)|| <= b_i + 1;
//! * d_i (c_i + c_{i+1}) >= 1 as the cone ||(2, u - d_i)|| <= u + d_i,
//!   u = c_i + c_{i+1}.
//!
//! At the optimum c_i = sqrt(b_i) and d_i = 1 / (c_i + c_{i+1}), so the objective
//! equals the travel time exactly; no approximation is made.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SecondOrderConeT, SolverStatus,
    SupportedConeT,
};

use crate::speed_oracle::SpeedProblem;
use crate::{PlanError, SpeedFailure};

/// Solve the speed problem; returns b_i = v_i^2 at every point.
pub fn solve_speed_qp(p: &SpeedProblem) -> Result<Vec<f64>, PlanError> {
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
        put(row, ib + i, -1.0, &mut ri, &mut ci);
        bv.push(0.0);
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
    let settings = DefaultSettings {
        verbose: false,
        max_iter: 200,
        ..DefaultSettings::default()
    };
    let mut solver = DefaultSolver::new(&pm, &q, &a, &bv, &cones, settings)
        .map_err(|_| PlanError::Speed(SpeedFailure::BadProblem))?;
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {}
        SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
            return Err(PlanError::Speed(SpeedFailure::Infeasible));
        }
        _ => return Err(PlanError::Speed(SpeedFailure::NotConverged)),
    }
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
        let bq = solve_speed_qp(&p).unwrap();
        let bo = forward_backward(&p).unwrap();
        let (tq, to) = (travel_time(&p.ds, &bq), travel_time(&p.ds, &bo));
        assert!((tq - to).abs() / to < 1e-3, "qp {tq} oracle {to}");
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
            let bo = forward_backward(&p).unwrap();
            let (tq, to) = (travel_time(&p.ds, &bq), travel_time(&p.ds, &bo));
            prop_assert!((tq - to).abs() / to < 0.01, "qp {} oracle {}", tq, to);
            for i in 0..n - 1 {
                prop_assert!(bq[i + 1] - bq[i] <= 2.0 * accel * ds + 1e-5);
                prop_assert!(bq[i] - bq[i + 1] <= 2.0 * decel * ds + 1e-5);
            }
        }
    }
}
