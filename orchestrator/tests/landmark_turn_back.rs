//! A tour that turns back at a landmark, end to end through `plamo run` (MuJoCo): the
//! planner stops the plan there (`PlannerSettings::turn_back_angle`) and the
//! crouch-walk that follows sets off from rest. Random scene 240's second leg heads
//! back past the first one's path; with the old junction rule (a 0.4 m/s U-turn, the
//! plan's velocity reversed in one step) the crouch-walker walked backwards after it
//! while turning and fell twice in that leg (RESULTS.md, session 23).

#![cfg(feature = "mujoco")]

mod support;

use std::process::Command;

use support::recorded_json;

const BIN: &str = env!("CARGO_BIN_EXE_plamo");
const TOUR: &str =
    "Crouch-walk from the well to the swing; then crouch-walk to the tent; then walk to the rock";

#[test]
fn a_crouch_walk_that_turns_back_at_a_landmark_goes_on_without_a_fall() {
    let out = support::out_dir("turn-back", "random-240");
    let o = Command::new(BIN)
        .args(["run", "--scene", "random-240", "--instructions", TOUR])
        .args(["--physics", "mujoco", "--seed", "240", "--quiet", "--out"])
        .arg(&*out)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    let context = format!(
        "exit {:?}\n{text}\n{}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
    // Every leg reached; the two crouch-walks, the turn-back's, without a fall. The
    // walk that follows sets off from the tent, turning back a second time on gravel,
    // and has fallen once there since the biped's extra tilt torque (session 30: one of
    // the tours it loses; it gains more, RESULTS "Random 4-landmark scenes"); a run with
    // a fall exits with status 1 after its summary, a failed one without metrics.
    assert!(
        out.join("metrics.json").exists(),
        "no metrics.json\n{context}"
    );
    let metrics = recorded_json(&out, "metrics.json");
    assert_eq!(metrics["status"], "finished", "{context}");
    let legs = metrics["agents"][0]["results"].as_array().unwrap();
    assert_eq!(legs.len(), 3, "{context}");
    let mut falls = 0;
    for (i, leg) in legs.iter().enumerate() {
        assert_eq!(leg["reached"], true, "leg {i}\n{context}");
        let leg_falls = leg["metrics"]["falls"].as_u64().unwrap();
        if i < 2 {
            assert_eq!(leg_falls, 0, "leg {i}\n{context}");
        }
        falls += leg_falls;
    }
    assert_eq!(
        o.status.code(),
        Some(if falls == 0 { 0 } else { 1 }),
        "{context}"
    );
    // The plan stopped at the swing: the first leg ends at rest and the second
    // starts from it.
    let plans = recorded_json(&out, "plans.json");
    let route = &plans["initial"][0]["route"];
    let end_v = route[0]["points"].as_array().unwrap().last().unwrap()["v"]
        .as_f64()
        .unwrap();
    let start_v = route[1]["points"][0]["v"].as_f64().unwrap();
    assert_eq!((end_v, start_v), (0.0, 0.0));
}
