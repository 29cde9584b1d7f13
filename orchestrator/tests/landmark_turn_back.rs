//! A tour that turns back at a landmark, end to end through `plamo run` (MuJoCo): the
//! planner stops the plan there (`PlannerSettings::turn_back_angle`) and the
//! crouch-walk that follows sets off from rest. Random scene 240's second leg heads
//! back past the first one's path; with the old junction rule (a 0.4 m/s U-turn, the
//! plan's velocity reversed in one step) the crouch-walker walked backwards after it
//! while turning and fell twice in that leg (RESULTS.md, session 23).

#![cfg(feature = "mujoco")]

mod support;

use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_plamo");
const TOUR: &str =
    "Crouch-walk from the well to the swing; then crouch-walk to the tent; then walk to the rock";

#[test]
fn a_crouch_walk_that_turns_back_at_a_landmark_finishes_the_tour_without_a_fall() {
    let out = support::out_dir("turn-back", "random-240");
    let o = Command::new(BIN)
        .args(["run", "--scene", "random-240", "--instructions", TOUR])
        .args(["--physics", "mujoco", "--seed", "240", "--quiet", "--out"])
        .arg(&*out)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "exit {:?}\n{text}\n{}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
    // Every leg reached, none with a fall.
    let legs: Vec<&str> = text.lines().filter(|l| l.contains("agent 0 [")).collect();
    assert_eq!(legs.len(), 3, "{text}");
    for leg in &legs {
        assert!(leg.contains("[ok]") && leg.contains("falls 0"), "{leg}");
    }
    // The plan stopped at the swing: the first leg ends at rest and the second
    // starts from it.
    let plans: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("plans.json")).unwrap()).unwrap();
    let route = &plans["initial"][0]["route"];
    let end_v = route[0]["points"].as_array().unwrap().last().unwrap()["v"]
        .as_f64()
        .unwrap();
    let start_v = route[1]["points"][0]["v"].as_f64().unwrap();
    assert_eq!((end_v, start_v), (0.0, 0.0));
}
