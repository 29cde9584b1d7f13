//! Closed loop in MuJoCo: the default model-based controller walks a straight path at
//! 1.0 and 1.5 m/s and an arc on flat ground without falling and tracks the head path.
#![cfg(feature = "mujoco")]

use plamo_controller::{
    ArcPath, ControllerSettings, ModelBasedController, StraightPath, flat_scene, run_path,
    run_straight,
};
use plamo_physics::BackendKind;

#[test]
fn straight_walk_at_1_and_1_5_m_per_s_does_not_fall_in_mujoco() {
    for speed in [1.0, 1.5] {
        walk(speed);
    }
}

fn walk(speed: f64) {
    let settings = ControllerSettings {
        body_mass: plamo_physics::humanoid::total_mass(),
        ..Default::default()
    };
    let mut policy = ModelBasedController::new(settings.clone()).unwrap();
    let path = StraightPath {
        start: [0.0, 0.0],
        speed,
        head_height: 1.47,
    };
    let duration = 10.0;
    let scene = flat_scene(path.speed * duration + 5.0);
    let m = run_straight(
        BackendKind::Mujoco,
        &scene,
        path,
        duration,
        &mut policy,
        &settings,
    )
    .unwrap();
    eprintln!("{}", serde_json::to_string_pretty(&m).unwrap());
    assert_eq!(m.falls, 0, "fell at {speed} m/s");
    // Paper Table 2, walk on flat: XY 0.24 m, Z 0.21 m. Measured XY 0.05 / 0.16 m.
    assert!(m.xy_err_mean < 0.25, "xy error {}", m.xy_err_mean);
    assert!(m.z_err_mean < 0.1, "z error {}", m.z_err_mean);
    // Measured 0.069 / 0.106 m*g with the shipped parameters: at 1 m/s within the
    // issue's 10% goal.
    let residual_max = if speed <= 1.0 { 0.09 } else { 0.13 };
    assert!(
        m.residual_force_mean <= residual_max,
        "residual {} at {speed} m/s",
        m.residual_force_mean
    );
    assert!(m.residual_force_peak <= settings.residual_force_cap + 1e-9);
}

#[test]
fn walk_turns_along_an_arc_in_mujoco() {
    let settings = ControllerSettings {
        body_mass: plamo_physics::humanoid::total_mass(),
        ..Default::default()
    };
    let mut policy = ModelBasedController::new(settings.clone()).unwrap();
    // 3 m straight, then a right turn of radius 5 m.
    let path = ArcPath {
        start: [0.0, 0.0],
        speed: 1.0,
        head_height: 1.47,
        straight: 3.0,
        radius: -5.0,
    };
    let scene = flat_scene(15.0);
    let m = run_path(
        BackendKind::Mujoco,
        &scene,
        &path,
        12.0,
        &mut policy,
        &settings,
    )
    .unwrap();
    eprintln!("{}", serde_json::to_string_pretty(&m).unwrap());
    assert_eq!(m.falls, 0, "fell on the arc");
    // Measured XY 0.06 m, direction reward 0.89.
    assert!(m.xy_err_mean < 0.2, "xy error {}", m.xy_err_mean);
    assert!(
        m.mean_reward.dir > 0.75,
        "direction reward {}",
        m.mean_reward.dir
    );
}

#[test]
fn crouch_walk_at_1_m_per_s_does_not_fall_in_mujoco() {
    let settings = ControllerSettings {
        body_mass: plamo_physics::humanoid::total_mass(),
        ..Default::default()
    };
    let mut policy = ModelBasedController::new(settings.clone()).unwrap();
    let path = StraightPath {
        start: [0.0, 0.0],
        speed: 1.0,
        head_height: 0.8,
    };
    let scene = flat_scene(15.0);
    let m = run_straight(
        BackendKind::Mujoco,
        &scene,
        path,
        10.0,
        &mut policy,
        &settings,
    )
    .unwrap();
    eprintln!("{}", serde_json::to_string_pretty(&m).unwrap());
    assert_eq!(m.falls, 0, "fell crouch-walking");
    assert!(m.xy_err_mean < 0.2, "xy error {}", m.xy_err_mean);
    // The shipped crouch gets the head down to ~1.05 m of the requested 0.8 m (Z
    // 0.26 m measured; the paper reaches 0.03 m): this bounds the regression, not the
    // goal.
    assert!(m.z_err_mean < 0.3, "z error {}", m.z_err_mean);
}
