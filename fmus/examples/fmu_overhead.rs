//! What the FMI layer costs: the default `plamo.fmu` route (fountain to sandbox, a
//! ball rolling across it) stepped through fmu-runner at a 0.01 s communication step,
//! reading every output at every communication point, against the same route run by
//! the in-process lockstep, in one process, alternating, median of the rounds.
//!
//! `cargo build --release -p plamo-fmu && cargo run --release -p plamo-fmu --example fmu_overhead [ROUNDS]`

use std::collections::HashMap;
use std::time::Instant;

use fmu_runner::model_description::{Causality, ScalarVariable, SignalType};
use fmu_runner::{Fmu, FmuInstance, fmi2Type};
use plamo::fmu_package::{find_library, package_all};
use plamo::lockstep::external::{PARKED_SAMPLE, in_process_with_external};
use plamo::lockstep::{Lockstep, StepStatus};
use plamo::spec::RunSpec;
use plamo_controller::ControllerSettings;
use plamo_interfaces::ObstacleSample;
use plamo_physics::BackendKind;
use plamo_scenes::ObstacleShape;

const INSTRUCTIONS: &str = "Walk from the fountain to the sandbox";
const HOST_STEP: f64 = 0.01;
const STOP: f64 = 25.0;

fn ball(t: f64) -> ObstacleSample {
    ObstacleSample {
        position: [-1.0 + t, 9.0, 0.3],
        velocity: [1.0, 0.0, 0.0],
    }
}

/// The in-process lockstep over the route; returns (stepping seconds, control steps).
fn in_process() -> (f64, u64) {
    let spec = RunSpec {
        scene: "playground".into(),
        instructions: vec![INSTRUCTIONS.into()],
        backend: BackendKind::Rapier,
        seed: 0,
    };
    let scene = spec.load_scene().expect("playground");
    let count = plamo_planner::parse_instructions(INSTRUCTIONS, &scene)
        .expect("route")
        .len();
    let links =
        in_process_with_external(&spec, &scene, &[ObstacleShape::Sphere { radius: 0.3 }; 4])
            .expect("links");
    let mut ls = Lockstep::start(links, scene, &[count], &ControllerSettings::default(), 1e6)
        .expect("lockstep");
    let start = Instant::now();
    let (mut t, mut finished) = (0.0_f64, false);
    while !finished && t < STOP {
        ls.set_external_obstacles(&[PARKED_SAMPLE, ball(t), PARKED_SAMPLE, PARKED_SAMPLE])
            .expect("obstacles");
        let end = t + HOST_STEP;
        while !finished && (ls.tick().0 + 4) as f64 / 120.0 <= end + 1e-9 {
            finished = ls.step().expect("step") != StepStatus::Running;
        }
        t = end;
    }
    (start.elapsed().as_secs_f64(), ls.tick().0 / 4)
}

/// The same route through fmu-runner; returns (stepping seconds, communication points).
fn through_fmu(fmu: &fmu_runner::FmuLibrary) -> (f64, u64) {
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
    let inst = FmuInstance::instantiate(fmu, false).expect("instantiate");
    inst.setup_experiment(0.0, None, None).expect("setup");
    inst.enter_initialization_mode().expect("init");
    inst.set_booleans(&[(var("obstacle[2].active"), 1)].into_iter().collect())
        .expect("active");
    let set_ball = |t: f64| {
        let b = ball(t);
        let m: HashMap<_, _> = [
            (var("obstacle[2].x"), b.position[0]),
            (var("obstacle[2].y"), b.position[1]),
            (var("obstacle[2].z"), b.position[2]),
            (var("obstacle[2].vx"), b.velocity[0]),
            (var("obstacle[2].vy"), b.velocity[1]),
            (var("obstacle[2].vz"), b.velocity[2]),
        ]
        .into_iter()
        .collect();
        inst.set_reals(&m).expect("ball");
    };
    set_ball(0.0);
    inst.exit_initialization_mode().expect("exit init");
    let done = var("done");
    let start = Instant::now();
    let (mut t, mut points) = (0.0_f64, 0);
    while t < STOP {
        set_ball(t);
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
    let library = find_library().expect("build the FMU library first");
    let dir = std::env::temp_dir().join(format!("plamo-fmu-overhead-{}", std::process::id()));
    let packaged = package_all(&library, &dir, &[]).expect("package");
    let path = &packaged
        .iter()
        .find(|p| p.model_name == "plamo")
        .expect("plamo.fmu")
        .path;
    let fmu = Fmu::unpack(path)
        .expect("unpack")
        .load(fmi2Type::fmi2CoSimulation)
        .expect("load");
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
    let _ = std::fs::remove_dir_all(&dir);
}
