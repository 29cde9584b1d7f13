//! Closed loop in MuJoCo: from standing, the default controller gets down on hands and
//! knees when the plan asks for a 0.4 m head and crawls a straight path and an arc
//! without falling; bit-identical reruns. (Getting up again works in rapier, see
//! crawl_rapier.rs; in MuJoCo the sit-back into the squat does not get the feet under
//! the body yet, see RESULTS.md "## Crawl".)
#![cfg(feature = "mujoco")]

use plamo_controller::{
    ArcPath, ControllerSettings, HeadPath, MetricsSummary, ModelBasedController, StraightPath,
    flat_scene, run_path,
};
use plamo_physics::BackendKind;

/// The crawl speed the gait follows closely (it lags beyond ~0.75 m/s).
const SPEED: f64 = 0.5;

fn settings() -> ControllerSettings {
    ControllerSettings {
        body_mass: plamo_physics::humanoid::total_mass(),
        ..Default::default()
    }
}

fn crawl(path: &dyn HeadPath, duration: f64) -> MetricsSummary {
    let settings = settings();
    let mut policy = ModelBasedController::new(settings.clone()).unwrap();
    let scene = flat_scene(SPEED * duration + 5.0);
    let m = run_path(
        BackendKind::Mujoco,
        &scene,
        path,
        duration,
        &mut policy,
        &settings,
    )
    .unwrap();
    eprintln!("{}", serde_json::to_string_pretty(&m).unwrap());
    m
}

fn check(m: &MetricsSummary, what: &str) {
    assert_eq!(m.falls, 0, "fell {what}");
    // Errors include the first ~2 s, the get-down from a standing start (head 1.47 m).
    // Measured XY 0.33-0.35 m in rapier (it lags the plan), 0.13-0.15 m in MuJoCo;
    // Z 0.10-0.12 m in both.
    assert!(m.xy_err_mean < 0.3, "xy error {} {what}", m.xy_err_mean);
    assert!(m.z_err_mean < 0.15, "z error {} {what}", m.z_err_mean);
    // Measured 0.08-0.12 m*g with the shipped parameters.
    assert!(
        m.residual_force_mean <= 0.15,
        "residual {} {what}",
        m.residual_force_mean
    );
    assert!(m.residual_force_peak <= settings().residual_force_cap + 1e-9);
}

#[test]
fn gets_down_and_crawls_a_straight_path_in_mujoco() {
    let path = StraightPath {
        start: [0.0, 0.0],
        speed: SPEED,
        head_height: 0.4,
    };
    check(&crawl(&path, 10.0), "on the straight path");
}

#[test]
fn crawls_an_arc_in_mujoco() {
    let path = ArcPath {
        start: [0.0, 0.0],
        speed: SPEED,
        head_height: 0.4,
        straight: 2.0,
        radius: 4.0,
    };
    let m = crawl(&path, 12.0);
    check(&m, "on the arc");
    // Measured 0.40 (the heading lags the turn by ~0.2 rad in MuJoCo; rapier 0.9).
    assert!(
        m.mean_reward.dir > 0.3,
        "direction reward {}",
        m.mean_reward.dir
    );
}

#[test]
fn crawl_rollouts_are_bit_identical_in_mujoco() {
    let path = StraightPath {
        start: [0.0, 0.0],
        speed: SPEED,
        head_height: 0.4,
    };
    let a = serde_json::to_string(&crawl(&path, 4.0)).unwrap();
    let b = serde_json::to_string(&crawl(&path, 4.0)).unwrap();
    assert_eq!(a, b);
}
