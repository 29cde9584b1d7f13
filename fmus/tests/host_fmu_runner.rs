//! The planner FMU imported by a real FMI 2.0 host written in Rust (fmu-runner): the
//! packaged .fmu is unpacked, loaded and stepped like any third-party FMU, with a host
//! that moves its own character along the waypoints the FMU hands out.

use std::collections::HashMap;

use fmu_runner::FmuInstance;

mod support;
use support::load_fmu;

#[test]
fn a_host_character_following_the_planner_fmu_reaches_every_landmark() {
    let (fmu, _out) = load_fmu("plamo-planner", "fmu-runner");
    let vars = fmu.variables();
    let var = |n: &str| {
        vars.get(n)
            .unwrap_or_else(|| panic!("variable {n} in modelDescription.xml"))
    };
    let inst = FmuInstance::instantiate(&fmu, false).unwrap();

    // Defaults: playground, "Run from the tree to the car, then crawl to the bench".
    // The character starts at the tree.
    let mut head = [3.5, 26.0, 1.47];
    let set_head = |head: [f64; 3]| {
        let m: HashMap<_, _> = [
            (var("character.x"), head[0]),
            (var("character.y"), head[1]),
            (var("character.z"), head[2]),
        ]
        .into_iter()
        .collect();
        inst.set_reals(&m).unwrap();
    };
    inst.setup_experiment(0.0, None, None).unwrap();
    inst.enter_initialization_mode().unwrap();
    set_head(head);
    inst.exit_initialization_mode().unwrap();

    // Step like FMPy does (sizes such as 0.009999999999999998 accumulate error).
    let dt = 0.1_f64 / 3.0 * 3.0;
    let mut t = 0.0;
    let mut done = false;
    let mut max_instruction = 0;
    while t < 150.0 {
        let wp = inst
            .get_reals(&[
                var("waypoint[1].x"),
                var("waypoint[1].y"),
                var("waypoint[1].z"),
            ])
            .unwrap();
        let target = [
            wp[var("waypoint[1].x")],
            wp[var("waypoint[1].y")],
            wp[var("waypoint[1].z")],
        ];
        // A simple host character: cover the way to the 0.5 s-ahead waypoint in 0.5 s.
        for k in 0..3 {
            head[k] += (target[k] - head[k]) * (dt / 0.5);
        }
        set_head(head);
        inst.do_step(t, dt, true).unwrap();
        t += dt;
        let ints = inst.get_integers(&[var("instruction")]).unwrap();
        max_instruction = max_instruction.max(ints[var("instruction")]);
        let flags = inst.get_booleans(&[var("done")]).unwrap();
        if flags[var("done")] != 0 {
            done = true;
            break;
        }
    }
    assert!(
        done,
        "the planner never reported done; reached instruction {max_instruction} by t = {t:.1} s"
    );
    assert_eq!(max_instruction, 2, "both instructions were worked through");
}
