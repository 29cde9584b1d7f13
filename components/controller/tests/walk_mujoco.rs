//! Closed loop in MuJoCo: the default model-based controller walks a straight path at
//! 1.0-2.0 m/s, crouch-walks at 1 and 2 m/s and walks an arc on flat ground without
//! falling and tracks the head path, walks up and down stairs, and crouch-walks up and
//! down the slope and stairs strips. Straight paths start
//! from rest at [`START_ACCEL`], as in tuning and `plamo eval locomotion`.
#![cfg(feature = "mujoco")]

use plamo_controller::{
    ArcPath, ControllerSettings, MetricsSummary, ModelBasedController, RUN_STAGGER, RampedPath,
    START_ACCEL, STRIP_LENGTH, StraightPath, flat_scene, run_path, staggered_start, terrain_scene,
};
use plamo_physics::BackendKind;

#[test]
fn straight_walk_at_1_to_2_m_per_s_does_not_fall_in_mujoco() {
    for speed in [1.0, 1.5, 2.0] {
        walk(speed);
    }
}

/// A 10 s straight run from rest at `speed` with the head at `head_height`.
fn straight(speed: f64, head_height: f64) -> (MetricsSummary, ControllerSettings) {
    let settings = ControllerSettings {
        body_mass: plamo_physics::humanoid::total_mass(),
        ..Default::default()
    };
    let mut policy = ModelBasedController::new(settings.clone()).unwrap();
    let path = RampedPath {
        line: StraightPath {
            start: [0.0, 0.0],
            speed,
            head_height,
        },
        accel: START_ACCEL,
    };
    let duration = 10.0;
    let scene = flat_scene(speed * duration + 5.0);
    let m = run_path(
        BackendKind::Mujoco,
        &scene,
        &path,
        duration,
        &mut policy,
        &settings,
    )
    .unwrap();
    eprintln!("{}", serde_json::to_string_pretty(&m).unwrap());
    (m, settings)
}

fn walk(speed: f64) {
    let (m, settings) = straight(speed, 1.47);
    assert_eq!(m.falls, 0, "fell at {speed} m/s");
    // Paper Table 2, walk on flat: XY 0.24 m, Z 0.21 m. Measured XY 0.03-0.08 m,
    // Z 0.09-0.10 m.
    assert!(m.xy_err_mean < 0.15, "xy error {}", m.xy_err_mean);
    assert!(m.z_err_mean < 0.13, "z error {}", m.z_err_mean);
    // The goal: walk at 1-2 m/s on flat ground with a mean residual force of at
    // most 10% of body weight (measured 0.087-0.092 m*g).
    assert!(
        m.residual_force_mean <= 0.10,
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
fn crouch_walk_at_1_and_2_m_per_s_does_not_fall_in_mujoco() {
    for speed in [1.0, 2.0] {
        let (m, _) = straight(speed, 0.8);
        assert_eq!(m.falls, 0, "fell crouch-walking at {speed} m/s");
        // Measured XY 0.08-0.10 m, Z 0.10 m (paper Table 2, crouch-walk at 2 m/s on
        // flat: 0.20 / 0.03 m).
        assert!(
            m.xy_err_mean < 0.2,
            "xy error {} at {speed} m/s",
            m.xy_err_mean
        );
        assert!(
            m.z_err_mean < 0.15,
            "z error {} at {speed} m/s",
            m.z_err_mean
        );
    }
}

/// Runs from rest at each of `speeds` with the head at `head` \[m\] along `plamo eval
/// locomotion`'s `terrain` strip, from `starts` staggered starts each, for up to 20 s
/// (the sweep example's runs: `sweep mujoco SPEEDS HEAD 20 STARTS straight TERRAIN`).
fn strip_runs(terrain: &str, head: f64, speeds: &[f64], starts: usize) -> Vec<MetricsSummary> {
    let settings = ControllerSettings {
        body_mass: plamo_physics::humanoid::total_mass(),
        ..Default::default()
    };
    let (scene, start) = terrain_scene(terrain).unwrap();
    let mut runs = Vec::new();
    for &speed in speeds {
        for r in 0..starts {
            let mut policy = ModelBasedController::new(settings.clone()).unwrap();
            let path = RampedPath {
                line: StraightPath {
                    start: staggered_start(start, r),
                    speed,
                    head_height: head,
                },
                accel: START_ACCEL,
            };
            let duration = ((STRIP_LENGTH - RUN_STAGGER * r as f64) / speed).min(20.0);
            let m = run_path(
                BackendKind::Mujoco,
                &scene,
                &path,
                duration,
                &mut policy,
                &settings,
            )
            .unwrap();
            eprintln!(
                "{terrain} head {head} m, {speed} m/s, start {r}: {}",
                MetricsSummary::sweep_row(std::slice::from_ref(&m))
            );
            assert!(m.residual_force_peak <= settings.residual_force_cap + 1e-9);
            runs.push(m);
        }
    }
    runs
}

/// Falls summed and mean XY error over `runs`.
fn falls_and_xy(runs: &[MetricsSummary]) -> (u32, f64) {
    let falls = runs.iter().map(|m| m.falls).sum();
    let xy = runs.iter().map(|m| m.xy_err_mean).sum::<f64>() / runs.len() as f64;
    (falls, xy)
}

/// Walks the stairs strip (flights of 0.12 m x 0.4 m steps up and down) at 1 and
/// 1.5 m/s from four starts each: up to 30 m, over one to two and a half flights.
#[test]
fn walk_climbs_and_descends_stairs_in_mujoco() {
    let (falls, xy) = falls_and_xy(&strip_runs("stairs", 1.47, &[1.0, 1.5], 4));
    // Measured 2 falls and a mean XY error of 0.10 m; the gait before the terrain-aware
    // footholds fell 49 times, 0.27 m.
    assert!(falls <= 10, "{falls} falls on the stairs");
    assert!(xy < 0.2, "mean xy error {xy} on the stairs");
}

/// Crouch-walks (head 0.8 m) up and down the slope strip and the stairs strip at 1 and
/// 2 m/s (Table 2's speed), four starts each.
#[test]
fn crouch_walk_climbs_and_descends_slope_and_stairs_in_mujoco() {
    let (falls, xy) = falls_and_xy(&strip_runs("slope", 0.8, &[1.0, 2.0], 4));
    // Measured 0 falls, XY 0.08 m; the crouch section before its terrain tuning 2 falls,
    // 0.12 m, and before that, when a crouch down the slope went down for a crawl, 3
    // falls, 0.90 m.
    assert!(falls <= 1, "{falls} crouch falls on the slope");
    assert!(xy < 0.15, "mean crouch xy error {xy} on the slope");
    let (falls, xy) = falls_and_xy(&strip_runs("stairs", 0.8, &[1.0, 2.0], 4));
    // Measured (session 48) 6 falls, all at 2 m/s, XY 0.24 m: since the swing foot
    // lands by arrival (session 47) it falls less (8 falls before, 6 of them at 2 m/s)
    // but two of the 2 m/s starts fall at the first flight and lag 0.4-0.7 m from there
    // (0.17 m before); before the terrain tuning 15 falls, 0.28 m; before the crawl
    // switch's fix 22 falls, 1.15 m.
    assert!(falls <= 11, "{falls} crouch falls on the stairs");
    assert!(xy < 0.3, "mean crouch xy error {xy} on the stairs");
}
