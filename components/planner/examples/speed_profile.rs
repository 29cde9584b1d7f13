//! Minimum-time speed over a 100 m path with three slow corners: the QP and the
//! time-objective SOCP (both Clarabel) against the exact forward-backward profile.
//!
//! `cargo run --release -p plamo-planner --example speed_profile`

use std::time::Instant;

use plamo_planner::{
    SpeedProblem, forward_backward, solve_speed_qp, solve_speed_socp, travel_time,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n = 1000;
    // Speed caps squared [m^2/s^2]: 4 m/s, with three corners where the lateral limit
    // a_lat / kappa allows 1 m/s.
    let mut b_max = vec![16.0; n];
    for corner in [250, 500, 750] {
        for b in b_max.iter_mut().skip(corner - 10).take(20) {
            *b = 1.0;
        }
    }
    let problem = SpeedProblem {
        ds: vec![0.1; n - 1], // 0.1 m spacing
        b_max,
        b_start: Some(0.0), // from rest
        b_end: None,
        accel: 0.5, // a_max [m/s^2]
        decel: 0.1, // |a_min| [m/s^2]
    };
    let t0 = Instant::now();
    let qp = solve_speed_qp(&problem)?;
    let t_qp = t0.elapsed();
    let t0 = Instant::now();
    let socp = solve_speed_socp(&problem)?;
    let t_socp = t0.elapsed();
    let t0 = Instant::now();
    let fb = forward_backward(&problem)?;
    let t_fb = t0.elapsed();
    println!(
        "QP:               travel time {:.3} s, solved in {:.2} ms",
        travel_time(&problem.ds, &qp),
        t_qp.as_secs_f64() * 1e3
    );
    println!(
        "SOCP (time obj.): travel time {:.3} s, solved in {:.2} ms",
        travel_time(&problem.ds, &socp),
        t_socp.as_secs_f64() * 1e3
    );
    println!(
        "forward-backward: travel time {:.3} s, computed in {:.3} ms",
        travel_time(&problem.ds, &fb),
        t_fb.as_secs_f64() * 1e3
    );
    Ok(())
}
