//! What the FMI layer costs: the default `plamo.fmu` route (fountain to sandbox, a
//! ball rolling across it) stepped through fmu-runner at a 0.01 s communication step,
//! reading every output at every communication point, against the same route run by
//! the in-process lockstep, in one process, alternating, median of the rounds.
//!
//! `cargo build --release -p plamo-fmu && cargo run --release -p plamo-fmu --example fmu_overhead [ROUNDS]`

use std::time::Instant;

use fmu_runner::FmuLibrary;
use fmu_runner::model_description::{Causality, ScalarVariable, SignalType};
use plamo::lockstep::StepStatus;

#[path = "../tests/support/mod.rs"]
mod support;
use support::{HOST_STEP, INSTRUCTIONS, externals, load_fmu, route_lockstep, set_ball};

/// Simulated-time limit of one route \[s\].
const STOP: f64 = 25.0;

/// The in-process lockstep over the route; returns (stepping seconds, control steps).
fn in_process() -> (f64, u64) {
    let (mut ls, _) = route_lockstep(0);
    let start = Instant::now();
    let (mut t, mut finished) = (0.0_f64, false);
    while !finished && t < STOP {
        ls.set_external_obstacles(&externals(t)).expect("obstacles");
        let end = t + HOST_STEP;
        while !finished && (ls.tick().0 + 4) as f64 / 120.0 <= end + 1e-9 {
            finished = ls.step().expect("step") != StepStatus::Running;
        }
        t = end;
    }
    (start.elapsed().as_secs_f64(), ls.tick().0 / 4)
}

/// The same route through fmu-runner; returns (stepping seconds, communication points).
fn through_fmu(fmu: &FmuLibrary) -> (f64, u64) {
    let vars = fmu.variables();
    let var = |n: &str| &vars[n];
    let outputs: Vec<&ScalarVariable> = vars
        .values()
        .filter(|v| matches!(v.causality, Causality::Output))
        .collect();
    let of = |f: fn(&SignalType) -> bool| -> Vec<&ScalarVariable> {
        outputs
            .iter()
            .copied()
            .filter(|v| f(&v.signal_type))
            .collect()
    };
    let (reals, ints, bools) = (
        of(|t| matches!(t, SignalType::Real(_))),
        of(|t| matches!(t, SignalType::Integer(_))),
        of(|t| matches!(t, SignalType::Boolean(_))),
    );
    let inst = support::start_instance(fmu, 0);
    let done = var("done");
    let start = Instant::now();
    let (mut t, mut points) = (0.0_f64, 0);
    while t < STOP {
        set_ball(&inst, fmu, t);
        inst.do_step(t, HOST_STEP, true).expect("step");
        t += HOST_STEP;
        points += 1;
        std::hint::black_box(inst.get_reals(&reals).expect("reals"));
        std::hint::black_box(inst.get_integers(&ints).expect("ints"));
        if inst.get_booleans(&bools).expect("bools")[done] != 0 {
            break;
        }
    }
    (start.elapsed().as_secs_f64(), points)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let rounds: usize = std::env::args()
        .nth(1)
        .map_or(7, |a| a.parse().expect("ROUNDS is a number"));
    let (fmu, _dir) = load_fmu("plamo", "fmu-overhead");
    let (mut a, mut b) = (Vec::new(), Vec::new());
    let (mut steps, mut points) = (0, 0);
    for _ in 0..rounds {
        let (s, n) = in_process();
        a.push(s);
        steps = n;
        let (s, n) = through_fmu(&fmu);
        b.push(s);
        points = n;
    }
    let (ta, tb) = (median(&mut a), median(&mut b));
    println!(
        "route: {INSTRUCTIONS} (ball crossing), {steps} control steps, {points} communication points of {HOST_STEP} s"
    );
    println!(
        "in-process lockstep: {:.1} ms (median of {rounds})",
        ta * 1e3
    );
    println!(
        "fmu-runner + plamo.fmu: {:.1} ms (median of {rounds}, every output read at every point)",
        tb * 1e3
    );
    println!("ratio FMU / in-process: {:.3}x", tb / ta);
}
