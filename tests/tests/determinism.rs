//! The determinism contract (DESIGN "Lockstep"): the same scene, instructions, seed
//! and backend give a bit-identical trajectory. Each run folds every world state's
//! bits into a digest and keeps every control tick's state; two in-process runs
//! must agree on both, for rapier and (feature `mujoco`) MuJoCo. In-process against
//! multi-process is checked through the `plamo` binary in `orchestrator/tests/run_cli.rs`.

use plamo::lockstep::{Lockstep, StepStatus};
use plamo::spec::RunSpec;
use plamo_controller::ControllerSettings;
use plamo_interfaces::PhysicsOutput;
use plamo_physics::BackendKind;

const ROUTE: &str = "Run from the tree to the car, then crawl to the bench";

/// Run `spec` for `seconds` of simulated time; the digest and every world state.
fn run(spec: &RunSpec, seconds: f64) -> (u64, Vec<PhysicsOutput>) {
    let scene = spec.load_scene().unwrap();
    let links = spec.in_process(&scene).unwrap();
    let counts = vec![2; spec.agents()];
    let mut ls = Lockstep::start(
        links,
        scene,
        &counts,
        &ControllerSettings::default(),
        seconds,
    )
    .unwrap();
    let mut states = vec![*ls.world()];
    while ls.step().unwrap() == StepStatus::Running {
        states.push(*ls.world());
    }
    (ls.digest().value(), states)
}

fn spec(backend: BackendKind, seed: u64, agents: usize) -> RunSpec {
    RunSpec {
        scene: "playground".into(),
        instructions: vec![ROUTE.into(); agents],
        backend,
        seed,
        params: Default::default(),
    }
}

fn same_twice(backend: BackendKind) {
    let s = spec(backend, 3, 2);
    let (da, a) = run(&s, 2.0);
    let (db, b) = run(&s, 2.0);
    assert_eq!(a.len(), 61, "2 s at 30 Hz plus tick 0");
    assert_eq!(da, db);
    // Bit for bit, state by state (PartialEq on f64 would accept -0.0 == 0.0).
    for (x, y) in a.iter().zip(&b) {
        for (p, q) in x.agents.iter().zip(&y.agents) {
            let bits = |s: &plamo_interfaces::HumanoidState| -> Vec<u64> {
                s.root_position
                    .iter()
                    .chain(&s.root_orientation)
                    .chain(&s.head_position)
                    .chain(&s.joint_angles)
                    .chain(&s.joint_velocities)
                    .map(|v| v.to_bits())
                    .collect()
            };
            assert_eq!(bits(p), bits(q), "tick {}", x.tick);
        }
    }
    // The humanoid moved, so the comparison is not of two frozen worlds.
    let start = a[0].agents[0].head_position;
    let end = a.last().unwrap().agents[0].head_position;
    assert!((end[0] - start[0]).hypot(end[1] - start[1]) > 0.2);
    // A different seed gives a different trajectory.
    let (dc, _) = run(&spec(backend, 4, 2), 2.0);
    assert_ne!(da, dc);
}

#[test]
fn rapier_runs_twice_bit_identically() {
    same_twice(BackendKind::Rapier);
}

#[cfg(feature = "mujoco")]
#[test]
fn mujoco_runs_twice_bit_identically() {
    same_twice(BackendKind::Mujoco);
}
