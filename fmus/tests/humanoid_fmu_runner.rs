//! `plamo.fmu` imported by a real FMI 2.0 host written in Rust (fmu-runner): the
//! packaged archive is unpacked, loaded and stepped like any third-party FMU while
//! the host drives a ball across the humanoid's route. Every output at every
//! communication point must equal, bit for bit, an in-process lockstep run of the
//! same route fed the same ball.

use std::collections::HashMap;

use fmu_runner::model_description::{Causality, ScalarVariable, SignalType};
use fmu_runner::{FmuInstance, FmuLibrary};
use plamo::lockstep::external::PARKED_SAMPLE;
use plamo::lockstep::{Lockstep, StepStatus};
use plamo_physics::JOINT_NAMES;
use plamo_planner::FLAG_FINISHED;

mod support;
use support::{HOST_STEP, externals, load_fmu, route_lockstep, set_ball, start_instance};

const STOP: f64 = 20.0;
/// When the ball has crossed the route (t = 7 s) \[ticks\].
const COMPARE_TICK: u64 = 7 * 120;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Out {
    Real(u64),
    Int(i32),
    Bool(bool),
}

/// Every output of the reference run, by name, as the lockstep stands now.
fn reference_outputs(ls: &Lockstep, finished: bool, count: usize) -> HashMap<String, Out> {
    let s = &ls.world().agents[0];
    let plan = &ls.plans()[0];
    let mut m = HashMap::new();
    let mut real = |n: String, x: f64| {
        m.insert(n, Out::Real(x.to_bits()));
    };
    for (i, a) in ["x", "y", "z"].iter().enumerate() {
        real(format!("head.{a}"), s.head_position[i]);
        real(format!("root.{a}"), s.root_position[i]);
    }
    for (i, c) in ["qx", "qy", "qz", "qw"].iter().enumerate() {
        real(format!("root.{c}"), s.root_orientation[i]);
    }
    let v = s.root_linear_velocity;
    real("speed".into(), (v[0] * v[0] + v[1] * v[1]).sqrt());
    for (j, name) in JOINT_NAMES.iter().enumerate() {
        real(format!("joint.{name}"), s.joint_angles[j]);
    }
    real("progress".into(), plan.progress);
    real("xy_error".into(), ls.xy_error(0));
    m.insert("instruction".into(), Out::Int(plan.instruction as i32));
    m.insert("instruction_count".into(), Out::Int(count as i32));
    m.insert(
        "done".into(),
        Out::Bool(finished || plan.flags & FLAG_FINISHED != 0),
    );
    m.insert("fallen".into(), Out::Bool(ls.fallen()[0]));
    m
}

fn fmu_outputs(
    inst: &FmuInstance<&FmuLibrary>,
    outputs: &[&ScalarVariable],
) -> HashMap<String, Out> {
    let pick = |ty: fn(&SignalType) -> bool| -> Vec<&ScalarVariable> {
        outputs
            .iter()
            .copied()
            .filter(|v| ty(&v.signal_type))
            .collect()
    };
    let mut m = HashMap::new();
    for (v, x) in inst
        .get_reals(&pick(|t| matches!(t, SignalType::Real(_))))
        .unwrap()
    {
        m.insert(v.name.clone(), Out::Real(x.to_bits()));
    }
    for (v, x) in inst
        .get_integers(&pick(|t| matches!(t, SignalType::Integer(_))))
        .unwrap()
    {
        m.insert(v.name.clone(), Out::Int(x));
    }
    for (v, x) in inst
        .get_booleans(&pick(|t| matches!(t, SignalType::Boolean(_))))
        .unwrap()
    {
        m.insert(v.name.clone(), Out::Bool(x != 0));
    }
    m
}

#[test]
fn fmu_runner_outputs_equal_the_in_process_lockstep_bit_for_bit() {
    let (fmu, _dir) = load_fmu("plamo", "humanoid-fmu");
    let vars = fmu.variables();
    let mut outputs: Vec<&ScalarVariable> = vars
        .values()
        .filter(|v| matches!(v.causality, Causality::Output))
        .collect();
    outputs.sort_by_key(|v| v.value_reference);
    assert_eq!(outputs.len(), 11 + JOINT_NAMES.len() + 6);

    // The in-process reference: the same spec, the same lockstep, the same ball.
    let (mut reference, count) = route_lockstep(3);
    let inst = start_instance(&fmu, 3);
    reference.set_external_obstacles(&externals(0.0)).unwrap();

    let (mut t, mut finished, mut points, mut max_instruction) = (0.0_f64, false, 0, 0);
    // Digest of the reference at COMPARE_TICK or where it finishes, whichever comes
    // first, to show the ball reached the planner.
    let mut digest_with_ball = None;
    loop {
        let expected = reference_outputs(&reference, finished, count);
        let got = fmu_outputs(&inst, &outputs);
        assert_eq!(got.len(), expected.len(), "every output is compared");
        for (name, e) in &expected {
            assert_eq!(
                got.get(name),
                Some(e),
                "output {name} at t = {t} s (communication point {points})"
            );
        }
        if let Some(Out::Int(i)) = got.get("instruction") {
            max_instruction = max_instruction.max(*i);
        }
        if got.get("done") == Some(&Out::Bool(true)) || t >= STOP {
            break;
        }
        // Host: set the inputs for the coming step, then step.
        set_ball(&inst, &fmu, t);
        inst.do_step(t, HOST_STEP, true).unwrap();
        reference.set_external_obstacles(&externals(t)).unwrap();
        let end = t + HOST_STEP;
        while !finished && (reference.tick().0 + 4) as f64 / 120.0 <= end + 1e-9 {
            match reference.step().unwrap() {
                StepStatus::Running => {}
                _ => finished = true,
            }
            if digest_with_ball.is_none() && (finished || reference.tick().0 >= COMPARE_TICK) {
                digest_with_ball = Some(reference.digest());
            }
        }
        t = end;
        points += 1;
    }
    assert!(
        max_instruction as usize == count,
        "the humanoid finished its route within {STOP} s (instruction {max_instruction} of {count} at t = {t:.2} s)"
    );
    assert!(points > 500, "{points} communication points compared");
    drop(inst);
    // A finished run stays finished: stepping it again changes nothing (it used to
    // re-plan on every call without advancing, so a loop on its tick never ended).
    assert!(finished, "the reference finished with the FMU");
    let (tick, digest) = (reference.tick().0, reference.digest());
    assert_eq!(reference.step().unwrap(), StepStatus::Finished);
    assert_eq!(reference.tick().0, tick);
    assert!(reference.digest() == digest, "a finished run changed");

    // Physics does not collide with host obstacles, so the ball can only change the
    // run through the planner's re-planning: without it the run must differ.
    let (mut no_ball, _) = route_lockstep(3);
    no_ball.set_external_obstacles(&[PARKED_SAMPLE; 4]).unwrap();
    // The same stopping rule as the reference's: a route that finishes earlier stops
    // there (stepping a finished lockstep again does not advance its tick).
    while no_ball.tick().0 < COMPARE_TICK {
        if no_ball.step().unwrap() != StepStatus::Running {
            break;
        }
    }
    let digest_with_ball = digest_with_ball.expect("the reference ran to its compare point");
    assert_ne!(
        no_ball.digest(),
        digest_with_ball,
        "the host's ball changed nothing: it never reached the planner"
    );
}
