//! Closed loop in rapier (the default engine): the default model-based controller
//! walks straight paths at 1.0 and 1.5 m/s and an arc on flat ground without falling,
//! keeps up with the plan (bounded head XY error against the moving plan point: at
//! 1.5 m/s it still lags, see RESULTS.md) and turns with the path.

use plamo_controller::{
    ArcPath, ControllerSettings, HeadPath, MetricsSummary, ModelBasedController, RampedPath,
    START_ACCEL, StraightPath, flat_scene, run_path, top_scene,
};
use plamo_physics::BackendKind;

fn settings() -> ControllerSettings {
    ControllerSettings {
        body_mass: plamo_physics::humanoid::total_mass(),
        ..Default::default()
    }
}

fn rollout(path: &dyn HeadPath, length: f64, duration: f64) -> MetricsSummary {
    let settings = settings();
    let mut policy = ModelBasedController::new(settings.clone()).unwrap();
    let scene = flat_scene(length);
    let m = run_path(
        BackendKind::Rapier,
        &scene,
        path,
        duration,
        &mut policy,
        &settings,
    )
    .unwrap();
    eprintln!("{}", serde_json::to_string_pretty(&m).unwrap());
    assert!(m.residual_force_peak <= settings.residual_force_cap + 1e-9);
    m
}

#[test]
fn straight_walk_at_1_and_1_5_m_per_s_does_not_fall_in_rapier() {
    for (speed, xy_max) in [(1.0, XY_1_0), (1.5, XY_1_5)] {
        let path = StraightPath {
            start: [0.0, 0.0],
            speed,
            head_height: 1.47,
        };
        let duration = 10.0;
        let m = rollout(&path, speed * duration + 5.0, duration);
        assert_eq!(m.falls, 0, "fell at {speed} m/s");
        // Speed tracking: the head stays near the plan point that moves at `speed`.
        assert!(
            m.xy_err_mean < xy_max,
            "xy error {} at {speed} m/s",
            m.xy_err_mean
        );
        // Paper Table 2, walk on flat: Z 0.21 m.
        assert!(m.z_err_mean < 0.21, "z error {}", m.z_err_mean);
        assert!(
            m.residual_force_mean <= RESIDUAL,
            "residual {}",
            m.residual_force_mean
        );
    }
}

#[test]
fn walk_turns_along_an_arc_in_rapier() {
    // 3 m straight, then a left turn of radius 5 m: 1.3 rad in 12 s. (At 1.0 m/s one
    // start in six falls once; see RESULTS.md.)
    let path = ArcPath {
        start: [0.0, 0.0],
        speed: 0.8,
        head_height: 1.47,
        straight: 3.0,
        radius: 5.0,
    };
    let duration = 12.0;
    let m = rollout(&path, 15.0, duration);
    assert_eq!(m.falls, 0, "fell on the arc");
    assert!(m.xy_err_mean < ARC_XY, "xy error {}", m.xy_err_mean);
    // Heading: the path reward's direction term exp(-c_dir * err^2) averages high only
    // if the body turns with the path.
    assert!(
        m.mean_reward.dir > ARC_DIR,
        "direction reward {}",
        m.mean_reward.dir
    );
}

// Bounds: the shipped parameters measure XY 0.13 / 0.84 m, residual 0.12 / 0.20 m*g
// (1.0 / 1.5 m/s), arc XY 0.08 m and direction reward 0.90; margins on top.
const XY_1_0: f64 = 0.25;
const XY_1_5: f64 = 1.1;
const RESIDUAL: f64 = 0.22;
const ARC_XY: f64 = 0.2;
const ARC_DIR: f64 = 0.8;

/// A crouch-walk (head 0.8 m at 1 m/s) passes under a 0.9 m top: the planner's crouch
/// under such a top (`crouch_height` + `head_margin`). The crouch holds its head about
/// 0.1 m over the plan's, so its head's sphere met the top's edge and the body stood
/// wedged there (most of the random tours' collisions); under a top the plan passes
/// beneath, the pelvis goes down until the head's sphere fits. Measured: largest XY
/// error 0.30 m; without the pelvis going down 5.1 m (stuck at the edge).
#[test]
fn crouch_walk_passes_under_a_0_9_m_top_in_rapier() {
    let settings = settings();
    let mut policy = ModelBasedController::new(settings.clone()).unwrap();
    let path = RampedPath {
        line: StraightPath {
            start: [0.0, 0.0],
            speed: 1.0,
            head_height: 0.8,
        },
        accel: START_ACCEL,
    };
    let scene = top_scene(10.0, 0.9);
    let m = run_path(
        BackendKind::Rapier,
        &scene,
        &path,
        8.0,
        &mut policy,
        &settings,
    )
    .unwrap();
    assert_eq!(m.falls, 0, "fell under the top");
    assert!(
        m.xy_err_max < 1.0,
        "held up at the top: largest xy error {}",
        m.xy_err_max
    );
}
