//! Closed loop, the same suite for every engine built in (rapier always, MuJoCo with
//! the `mujoco` feature): from standing, the default controller gets down on hands and
//! knees when the plan asks for a 0.4 m head, crawls a straight path, an arc and under
//! a 0.6 m ceiling without falling, and stands up again when the plan rises;
//! bit-identical reruns.

use plamo_controller::{
    Action, ArcPath, ControllerSettings, HeadPath, MetricsSummary, ModelBasedController,
    Observation, RisingPath, StraightPath, control_step, flat_scene, run_path,
};
use plamo_physics::{BackendKind, HumanoidPose, PhysicsSettings, create_backend};

/// The crawl speed the gait follows closely (it lags beyond ~0.75 m/s).
const SPEED: f64 = 0.5;

fn settings() -> ControllerSettings {
    ControllerSettings {
        body_mass: plamo_physics::humanoid::total_mass(),
        ..Default::default()
    }
}

/// What each engine's crawl must reach (measured figures in the comments).
struct Bounds {
    /// Mean head XY error on the straight path and the arc \[m\]. Measured: rapier
    /// 0.37 m straight, 0.46 m on the arc (it lags the plan; the lower crawl that clears
    /// a 0.6 m ceiling lags more than the 0.33-0.35 m before); MuJoCo 0.12-0.22 m.
    xy: f64,
    /// Radius of the arc \[m\] (MuJoCo fell once at 3 m).
    arc_radius: f64,
    /// Least direction reward on the arc. Measured: rapier 0.64; MuJoCo 0.32 (its
    /// heading lags the turn).
    arc_dir: f64,
    /// Mean head XY error under the 0.6 m ceiling \[m\]. Measured: rapier 0.64 m
    /// (0.94 m with the taller crawl of 24d140b, held by the ceiling); MuJoCo 0.91 m
    /// (1.15 m before: the back still grazes the ceiling and the crawl slows under it).
    xy_under_ceiling: f64,
}

fn bounds(kind: BackendKind) -> Bounds {
    match kind {
        BackendKind::Rapier => Bounds {
            xy: 0.5,
            arc_radius: 3.0,
            arc_dir: 0.6,
            xy_under_ceiling: 0.75,
        },
        BackendKind::Mujoco => Bounds {
            xy: 0.3,
            arc_radius: 4.0,
            arc_dir: 0.3,
            xy_under_ceiling: 1.0,
        },
    }
}

fn crawl(kind: BackendKind, path: &dyn HeadPath, duration: f64) -> MetricsSummary {
    crawl_in(kind, &flat_scene(SPEED * duration + 5.0), path, duration)
}

/// A flat bench with a 0.6 m ceiling over x in [2.5, 4.5] m (the playground's tunnel
/// height), 2 m wide.
fn ceiling_scene(length: f64) -> plamo_scenes::Scene {
    let mut scene = flat_scene(length);
    scene.tops.push(plamo_scenes::TopObstacle {
        name: "tunnel".into(),
        footprint: plamo_scenes::Footprint::axis_aligned([3.5, 0.0], [1.0, 1.0]),
        z_bottom: 0.6,
        z_top: 0.8,
    });
    scene
}

fn crawl_in(
    kind: BackendKind,
    scene: &plamo_scenes::Scene,
    path: &dyn HeadPath,
    duration: f64,
) -> MetricsSummary {
    let settings = settings();
    let mut policy = ModelBasedController::new(settings.clone()).unwrap();
    let m = run_path(kind, scene, path, duration, &mut policy, &settings).unwrap();
    eprintln!("{}", serde_json::to_string_pretty(&m).unwrap());
    m
}

fn check(kind: BackendKind, m: &MetricsSummary, what: &str) {
    assert_eq!(m.falls, 0, "{kind}: fell {what}");
    // Errors include the first ~2 s, the get-down from a standing start (head 1.47 m).
    // Measured Z 0.10-0.12 m.
    let xy = bounds(kind).xy;
    assert!(
        m.xy_err_mean < xy,
        "{kind}: xy error {} {what}",
        m.xy_err_mean
    );
    assert!(m.z_err_mean < 0.15, "z error {} {what}", m.z_err_mean);
    // Measured 0.08-0.12 m*g with the shipped parameters.
    assert!(
        m.residual_force_mean <= 0.15,
        "residual {} {what}",
        m.residual_force_mean
    );
    assert!(m.residual_force_peak <= settings().residual_force_cap + 1e-9);
}

fn line() -> StraightPath {
    StraightPath {
        start: [0.0, 0.0],
        speed: SPEED,
        head_height: 0.4,
    }
}

pub fn gets_down_and_crawls_a_straight_path(kind: BackendKind) {
    check(kind, &crawl(kind, &line(), 10.0), "on the straight path");
}

pub fn crawls_an_arc(kind: BackendKind) {
    let b = bounds(kind);
    let path = ArcPath {
        start: [0.0, 0.0],
        speed: SPEED,
        head_height: 0.4,
        straight: 2.0,
        radius: b.arc_radius,
    };
    let m = crawl(kind, &path, 12.0);
    check(kind, &m, "on the arc");
    assert!(
        m.mean_reward.dir > b.arc_dir,
        "{kind}: direction reward {}",
        m.mean_reward.dir
    );
}

pub fn crawl_rollouts_are_bit_identical(kind: BackendKind) {
    let a = serde_json::to_string(&crawl(kind, &line(), 4.0)).unwrap();
    let b = serde_json::to_string(&crawl(kind, &line(), 4.0)).unwrap();
    assert_eq!(a, b, "{kind}");
}

pub fn stands_up_when_the_plan_rises(kind: BackendKind) {
    let path = RisingPath {
        line: line(),
        up_at: 5.0,
    };
    let scene = flat_scene(10.0);
    let mut physics = create_backend(kind, &scene, &PhysicsSettings::default()).unwrap();
    physics
        .reset(&HumanoidPose::standing_on(&scene.terrain, 0.0, 0.0, 0.0))
        .unwrap();
    let mut policy = ModelBasedController::new(settings()).unwrap();
    let mut obs = Observation::new(ModelBasedController::LAYOUT);
    let mut action = Action::zeros(ModelBasedController::LAYOUT.num_joints);
    let mut crawled = false;
    for c in 0..(9 * 30) {
        let t = c as f64 / 30.0;
        let state = physics.state().clone();
        if (3.5..4.5).contains(&t) {
            assert!(
                state.head[2] < 0.6,
                "{kind}: head {} m at {t} s: not crawling",
                state.head[2]
            );
            crawled |= policy.is_crawling();
        }
        control_step(
            physics.as_mut(),
            &state,
            &path,
            &scene,
            t,
            &mut policy,
            &mut obs,
            &mut action,
        )
        .unwrap();
    }
    assert!(crawled, "{kind}: never in the crawl gait");
    let head = physics.state().head[2];
    assert!(!policy.is_crawling(), "{kind}: still in the crawl gait");
    assert!(head > 1.2, "{kind}: head {head} m after getting up");
}

pub fn crawls_under_a_0_6_m_ceiling(kind: BackendKind) {
    // The back must clear the ceiling: a crawl whose back scrapes it is held by the
    // friction (the playground's tunnel stopped the taller crawl for 80 s).
    let m = crawl_in(kind, &ceiling_scene(12.0), &line(), 12.0);
    assert_eq!(m.falls, 0, "{kind}: fell under the ceiling");
    let xy = bounds(kind).xy_under_ceiling;
    assert!(
        m.xy_err_mean < xy,
        "{kind}: xy error {} under the ceiling",
        m.xy_err_mean
    );
}

/// The suite for one engine.
macro_rules! crawl_suite {
    ($module:ident, $kind:expr) => {
        mod $module {
            use super::*;
            #[test]
            fn gets_down_and_crawls_a_straight_path() {
                super::gets_down_and_crawls_a_straight_path($kind);
            }
            #[test]
            fn crawls_an_arc() {
                super::crawls_an_arc($kind);
            }
            #[test]
            fn crawl_rollouts_are_bit_identical() {
                super::crawl_rollouts_are_bit_identical($kind);
            }
            #[test]
            fn stands_up_when_the_plan_rises() {
                super::stands_up_when_the_plan_rises($kind);
            }
            #[test]
            fn crawls_under_a_0_6_m_ceiling() {
                super::crawls_under_a_0_6_m_ceiling($kind);
            }
        }
    };
}

crawl_suite!(rapier, BackendKind::Rapier);
#[cfg(feature = "mujoco")]
crawl_suite!(mujoco, BackendKind::Mujoco);
