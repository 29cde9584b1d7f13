//! Closed loop, the same suite for every engine built in (rapier always, MuJoCo with
//! the `mujoco` feature): from standing, the default controller gets down on forearms
//! and knees (`params/crawl.toml`) when the plan asks for a 0.4 m head, crawls a
//! straight path, an arc, the planner's 1 m/s and under a 0.6 m ceiling without
//! falling, climbs a 0.15 m ledge, follows a 1 m/s arc up a slope, turns back at a
//! corner on gravel and stairs, gets down from a
//! walk, and stands up again when the plan rises (a crawl that lags its plan: in the
//! open, not under a top); bit-identical reruns. MuJoCo also:
//! gravel and stairs, and crawling off at a right angle to the body after the
//! get-down. The hand-and-knee crawl that ships beside it (`params/crawl-hands.toml`):
//! a straight path in every engine, gravel and stairs in MuJoCo.

use plamo_controller::{
    Action, ArcPath, ControllerSettings, CrawlParams, GaitParams, HeadPath, MetricsSummary,
    ModelBasedController, Observation, RisingPath, StraightPath, Waypoint, ceiling_scene,
    control_step, flat_scene, run_path,
};
use plamo_physics::{
    BackendKind, HumanoidPose, HumanoidState, PhysicsBackend, PhysicsSettings, create_backend,
};

/// The crawl speed of most cases here.
const SPEED: f64 = 0.5;

fn settings() -> ControllerSettings {
    ControllerSettings {
        body_mass: plamo_physics::humanoid::total_mass(),
        ..Default::default()
    }
}

/// What each engine's crawl must reach (measured figures in the comments; the crawl on
/// forearms and knees, the built-in one since session 17; the hand crawl's before).
struct Bounds {
    /// Mean head XY error on the straight path and the arc \[m\]. Measured: rapier
    /// 0.16 m straight, 0.14 m on the arc; MuJoCo 0.19 / 0.15 m (the hand crawl's
    /// 0.09 / 0.10 and 0.10 / 0.11 m; 0.37-0.46 / 0.12-0.22 m before the slip
    /// compensation: the crawl lagged the plan).
    xy: f64,
    /// Radius of the arc \[m\] (MuJoCo's hand crawl fell once at 3 m).
    arc_radius: f64,
    /// Least direction reward on the arc. Measured: rapier 0.65, MuJoCo 0.82 (the hand
    /// crawl's 0.49 since rapier's root torque acts per step, session 14, and 0.75).
    arc_dir: f64,
    /// Mean head XY error at the planner's 1 m/s crawl, from standing \[m\]: the ~1.5-2 m
    /// the plan gains during the get-down, and since the crawl keeps to 0.7 m/s
    /// (`max_speed`; faster, it fell on rough ground, slopes and stairs) what it loses
    /// after. Measured: rapier 2.54 m, MuJoCo 2.60 m (the hand crawl's 2.43 / 2.34 m).
    xy_fast: f64,
    /// Falls allowed getting down from a 1.25 m/s walk (`gets_down_from_a_walk`).
    /// Measured here: rapier 1, MuJoCo 0 (the hand crawl's); crawl_sweep `drop`, 8
    /// runs: rapier 0.75, MuJoCo 0 per run (0.5 / 1.0 before the biped braked first).
    drop_falls: u32,
    /// Mean head XY error under the 0.6 m ceiling \[m\]. Measured: rapier 0.72 m, MuJoCo
    /// 0.86 m (the hand crawl's 1.01 / 1.11 m: its back grazed the ceiling and it
    /// slowed under it); a crawl stuck there would be metres behind.
    xy_under_ceiling: f64,
    /// Falls allowed standing up from the crawl into a crouch-walk
    /// (`stands_up_into_a_crouch_walk`). Measured: rapier 1, MuJoCo 0. Rapier's
    /// forearm crawl stands up to 1.37 m, then the crouch-walk that takes over rolls
    /// onto its side as it lowers to 0.8 m (the hand crawl's did not fall here; not
    /// fixed, RESULTS "Crawl", session 17).
    crouch_falls: u32,
}

fn bounds(kind: BackendKind) -> Bounds {
    match kind {
        BackendKind::Rapier => Bounds {
            xy: 0.25,
            arc_radius: 3.0,
            arc_dir: 0.5,
            xy_fast: 2.9,
            drop_falls: 1,
            xy_under_ceiling: 1.1,
            crouch_falls: 1,
        },
        BackendKind::Mujoco => Bounds {
            xy: 0.25,
            arc_radius: 4.0,
            arc_dir: 0.6,
            xy_fast: 2.9,
            drop_falls: 0,
            xy_under_ceiling: 1.1,
            crouch_falls: 0,
        },
    }
}

fn crawl(kind: BackendKind, path: &dyn HeadPath, duration: f64) -> MetricsSummary {
    crawl_in(kind, &flat_scene(SPEED * duration + 5.0), path, duration)
}

fn crawl_in(
    kind: BackendKind,
    scene: &plamo_scenes::Scene,
    path: &dyn HeadPath,
    duration: f64,
) -> MetricsSummary {
    crawl_with(kind, scene, path, duration, CrawlParams::default())
}

/// [`crawl_in`] with the crawl parameters `crawl`.
fn crawl_with(
    kind: BackendKind,
    scene: &plamo_scenes::Scene,
    path: &dyn HeadPath,
    duration: f64,
    crawl: CrawlParams,
) -> MetricsSummary {
    let settings = settings();
    let mut policy =
        ModelBasedController::with_all_params(GaitParams::default(), crawl, settings.clone())
            .unwrap();
    let m = run_path(kind, scene, path, duration, &mut policy, &settings).unwrap();
    eprintln!("{}", serde_json::to_string_pretty(&m).unwrap());
    m
}

/// Staggered start `r` on a terrain strip of `plamo eval locomotion` (from x 5, y 3).
fn strip_start(r: usize) -> [f64; 2] {
    plamo_controller::staggered_start([5.0, 3.0], r)
}

/// Falls of the built-in crawl in `kind` over `seconds` on `scene`, one rollout per
/// strip start `r` in `0..runs`, each on the path `path(strip_start(r), r)`.
fn strip_falls<P: HeadPath>(
    kind: BackendKind,
    scene: &plamo_scenes::Scene,
    runs: usize,
    seconds: f64,
    path: impl Fn([f64; 2], usize) -> P,
) -> Vec<u32> {
    (0..runs)
        .map(|r| crawl_in(kind, scene, &path(strip_start(r), r), seconds).falls)
        .collect()
}

fn check(kind: BackendKind, m: &MetricsSummary, what: &str) {
    check_within(kind, m, bounds(kind).xy, what);
}

/// Mean head Z error the hand crawl keeps to \[m\]. Errors include the first ~2 s, the
/// get-down from a standing start (head 1.47 m). Measured 0.10-0.12 m.
const HAND_Z_ERR: f64 = 0.15;

/// Mean head Z error the (forearm) crawl keeps to \[m\]: its head is at ~0.36 m, the
/// torso pitched head-down. Measured 0.15 m on the straight paths in both engines.
const Z_ERR: f64 = 0.18;

fn check_within(kind: BackendKind, m: &MetricsSummary, xy: f64, what: &str) {
    check_within_z(kind, m, xy, Z_ERR, what);
}

fn check_within_z(kind: BackendKind, m: &MetricsSummary, xy: f64, z: f64, what: &str) {
    assert_eq!(m.falls, 0, "{kind}: fell {what}");
    assert!(
        m.xy_err_mean < xy,
        "{kind}: xy error {} {what}",
        m.xy_err_mean
    );
    assert!(m.z_err_mean < z, "z error {} {what}", m.z_err_mean);
    // Measured 0.08-0.18 m*g with the shipped parameters (rapier at 1 m/s the most).
    assert!(
        m.residual_force_mean <= 0.2,
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

pub fn crawls_at_1_m_per_s(kind: BackendKind) {
    // The speed the planner asks of a crawl (the paper's).
    let path = StraightPath {
        start: [0.0, 0.0],
        speed: 1.0,
        head_height: 0.4,
    };
    let m = crawl_in(kind, &flat_scene(15.0), &path, 10.0);
    check_within(kind, &m, bounds(kind).xy_fast, "at 1 m/s");
}

/// A plan that walks (head 1.47 m) from rest at 1 m/s^2 up to `walk` and drops to a
/// 0.4 m crawl at 1 m/s at `drop_at` (the planner's switch from a walk to a crawl).
struct DropPath {
    walk: f64,
    drop_at: f64,
}

impl DropPath {
    fn travel(&self, t: f64) -> (f64, f64) {
        let walk = |t: f64| {
            if t < self.walk {
                (0.5 * t * t, t)
            } else {
                (self.walk * (t - 0.5 * self.walk), self.walk)
            }
        };
        let t = t.max(0.0);
        if t < self.drop_at {
            walk(t)
        } else {
            (walk(self.drop_at).0 + (t - self.drop_at), 1.0)
        }
    }
}

impl HeadPath for DropPath {
    fn point(&self, scene: &plamo_scenes::Scene, t: f64) -> Waypoint {
        let (x, v) = self.travel(t);
        let head = if t < self.drop_at { 1.47 } else { 0.4 };
        Waypoint {
            x,
            y: 0.0,
            z: scene.height_at(x, 0.0) + head,
            v,
        }
    }
    fn direction(&self, _t: f64) -> [f64; 2] {
        [1.0, 0.0]
    }
    fn head_height(&self) -> f64 {
        0.4
    }
}

pub fn gets_down_from_a_walk(kind: BackendKind) {
    // The biped brakes before the get-down; without that the MuJoCo humanoid pitched
    // onto its head before its hands were down.
    let path = DropPath {
        walk: 1.25,
        drop_at: 4.0,
    };
    let m = crawl_in(kind, &flat_scene(15.0), &path, 9.0);
    assert!(
        m.falls <= bounds(kind).drop_falls,
        "{kind}: fell {} times getting down from a walk",
        m.falls
    );
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
    let mut crawled = false;
    let (policy, end) = rising_crawl(kind, &flat_scene(10.0), &path, 9.0, |t, _, s, policy| {
        let head = s.head[2];
        if (3.5..4.5).contains(&t) {
            assert!(head < 0.6, "{kind}: head {head} m at {t} s: not crawling");
            crawled |= policy.is_crawling();
        }
    });
    assert!(crawled, "{kind}: never in the crawl gait");
    let head = end.head[2];
    assert!(!policy.is_crawling(), "{kind}: still in the crawl gait");
    assert!(head > 1.2, "{kind}: head {head} m after getting up");
}

/// Drives the default controller from standing at the origin of `scene` along `path`
/// for `duration` \[s\]; `each` sees the time \[s\], the head's lag behind the plan's
/// point along +X \[m\], the humanoid's state and the policy before every control step.
/// Returns the policy and the state after the last step.
fn rising_crawl(
    kind: BackendKind,
    scene: &plamo_scenes::Scene,
    path: &RisingPath,
    duration: f64,
    mut each: impl FnMut(f64, f64, &HumanoidState, &ModelBasedController),
) -> (ModelBasedController, HumanoidState) {
    let mut physics = create_backend(kind, scene, &PhysicsSettings::default()).unwrap();
    physics
        .reset(&HumanoidPose::standing_on(&scene.terrain, 0.0, 0.0, 0.0))
        .unwrap();
    let mut policy = ModelBasedController::new(settings()).unwrap();
    let steps = (duration * 30.0) as usize;
    drive(
        physics.as_mut(),
        scene,
        path,
        &mut policy,
        steps,
        |_, t, s, policy| each(t, path.point(scene, t).x - s.head[0], s, policy),
    );
    (policy, physics.state().clone())
}

/// A crawl at the planner's 1 m/s whose plan rises to a walk at `up_at` \[s\].
fn lagging_plan(up_at: f64) -> RisingPath {
    RisingPath {
        line: StraightPath {
            start: [0.0, 0.0],
            speed: 1.0,
            head_height: 0.4,
        },
        up_at,
    }
}

/// A crawl lags its 1 m/s plan; out in the open it stands up when the plan rises
/// however far behind it is. It kept crawling while the plan ran more than 0.6 m
/// ahead (the guard for a body still under a top), on walk legs of the random tours,
/// and fell there.
pub fn stands_up_in_the_open_however_far_it_lags(kind: BackendKind) {
    let up_at = 8.0;
    let mut lag_at_rise = 0.0;
    let mut stood = None;
    let scene = flat_scene(20.0);
    let (policy, _) = rising_crawl(
        kind,
        &scene,
        &lagging_plan(up_at),
        14.0,
        |t, lag, s, policy| {
            if t <= up_at {
                lag_at_rise = lag;
            } else if stood.is_none() && !policy.is_crawling() && s.head[2] > 1.2 {
                stood = Some(t);
            }
        },
    );
    // Past the old guard by a margin, so this case is the one it held down.
    assert!(lag_at_rise > 1.0, "{kind}: lag {lag_at_rise} m at the rise");
    let t = stood.unwrap_or_else(|| panic!("{kind}: still down 6 s after the plan rose"));
    assert!(
        t < up_at + 4.0,
        "{kind}: stood up {} s after the rise",
        t - up_at
    );
    assert!(!policy.is_crawling(), "{kind}: back in the crawl gait");
}

/// The same lagging crawl under a 0.6 m top (x 2.5-4.5 m) whose plan rises past the
/// top's end: the crawler stays down while it is under the top, where the lag guard
/// held it before the headroom let a lagging crawler up.
pub fn stays_down_under_a_top_while_it_lags(kind: BackendKind) {
    let up_at = 5.0;
    let mut under = 0;
    let scene = ceiling_scene(20.0);
    rising_crawl(kind, &scene, &lagging_plan(up_at), 10.0, |t, lag, s, _| {
        let [x, y, _] = s.root_position;
        if t > up_at && scene.ceiling_at(x, y).is_some() && lag > 0.6 {
            under += 1;
            assert!(
                s.head[2] < 0.6,
                "{kind}: head {} m under the top at {t} s (x {x} m)",
                s.head[2]
            );
        }
    });
    assert!(
        under > 30,
        "{kind}: {under} steps under the top behind a risen plan"
    );
}

/// Steps `policy` on `physics` along `path` for `steps` control steps at 30 Hz;
/// before step `c` `each` sees `c`, its time \[s\], the humanoid's state and the
/// policy.
fn drive(
    physics: &mut dyn PhysicsBackend,
    scene: &plamo_scenes::Scene,
    path: &dyn HeadPath,
    policy: &mut ModelBasedController,
    steps: usize,
    mut each: impl FnMut(usize, f64, &HumanoidState, &ModelBasedController),
) {
    let mut obs = Observation::new(ModelBasedController::LAYOUT);
    let mut action = Action::zeros(ModelBasedController::LAYOUT.num_joints);
    for c in 0..steps {
        let t = c as f64 / 30.0;
        let state = physics.state().clone();
        each(c, t, &state, policy);
        control_step(
            physics,
            &state,
            path,
            scene,
            t,
            policy,
            &mut obs,
            &mut action,
        )
        .unwrap();
    }
}

/// A plan that crawls (head 0.4 m) and at `up_at` goes on as a crouch-walk (head
/// 0.8 m), both at `SPEED`: the random tours' crawl leg followed by a crouch-walk leg.
struct CrouchAfterCrawl {
    start: [f64; 2],
    up_at: f64,
}

impl HeadPath for CrouchAfterCrawl {
    fn point(&self, scene: &plamo_scenes::Scene, t: f64) -> Waypoint {
        let [x0, y] = self.start;
        let x = x0 + SPEED * t.max(0.0);
        let head = if t < self.up_at { 0.4 } else { 0.8 };
        Waypoint {
            x,
            y,
            z: scene.height_at(x, y) + head,
            v: SPEED,
        }
    }
    fn direction(&self, _t: f64) -> [f64; 2] {
        [1.0, 0.0]
    }
    fn head_height(&self) -> f64 {
        0.4
    }
}

pub fn stands_up_into_a_crouch_walk(kind: BackendKind) {
    // Before `crouch_stand_above` the crawl stood up only for a plan above 1.1 m and
    // crawled the crouch-walk leg with its head at ~0.35 m, where the fall rule's bar
    // is 0.8 - 0.5 m.
    let settings = settings();
    let scene = flat_scene(12.0);
    let mut policy = ModelBasedController::new(settings.clone()).unwrap();
    let path = CrouchAfterCrawl {
        start: [0.0, 0.0],
        up_at: 6.0,
    };
    let m = run_path(kind, &scene, &path, 13.0, &mut policy, &settings).unwrap();
    let most = bounds(kind).crouch_falls;
    assert!(
        m.falls <= most,
        "{kind}: fell {} times (at most {most})",
        m.falls
    );
    assert!(
        !policy.is_crawling(),
        "{kind}: still crawling 7 s into the crouch-walk"
    );
}

/// A body put down on forearms and knees (a start boxed in by a low top, a fall's
/// reset under one) under a crouch-walk's 0.8 m plan: with `reset_kneeling_crawls` the
/// crawl takes it from the first step and gets up into the crouch-walk. The biped
/// gait, handed the kneeling body, straightened one leg and fell within a second
/// (MuJoCo's random-411 and random-899 at their starts).
pub fn gets_up_from_a_kneeling_start_into_a_crouch_walk(kind: BackendKind) {
    let scene = flat_scene(12.0);
    let mut physics = create_backend(kind, &scene, &PhysicsSettings::default()).unwrap();
    physics
        .reset(&HumanoidPose::crawling_on(&scene.terrain, 0.0, 0.0, 0.0))
        .unwrap();
    let crawl = CrawlParams {
        reset_kneeling_crawls: true,
        ..CrawlParams::default()
    };
    let mut policy =
        ModelBasedController::with_all_params(GaitParams::default(), crawl, settings()).unwrap();
    let path = StraightPath {
        start: [0.0, 0.0],
        speed: 0.3,
        head_height: 0.8,
    };
    let mut lowest_late = f64::INFINITY;
    drive(
        physics.as_mut(),
        &scene,
        &path,
        &mut policy,
        8 * 30,
        |c, t, s, policy| {
            let head = s.head[2];
            // After the first step.
            if c == 1 {
                assert!(
                    policy.is_crawling(),
                    "{kind}: the biped took the kneeling body"
                );
            }
            if t > 4.0 {
                lowest_late = lowest_late.min(head);
            }
        },
    );
    assert!(
        !policy.is_crawling(),
        "{kind}: still in the crawl gait after 8 s"
    );
    assert!(
        lowest_late > 0.6,
        "{kind}: head down to {lowest_late} m after 4 s (a crouch-walk's is ~0.8 m)"
    );
}

/// The crouch-walk after a crawl on the gravel strip (12 staggered starts, 12 s): the
/// get-up straightened its legs with the centre of mass ahead of the ankles and
/// tipped forward. Measured over the 12 starts: without `up_com_gain` MuJoCo 10,
/// rapier 11 falls; with it (the built-in file's 10 /s) 2 and 5, with and without
/// `roll_reach` alike. Four starts (until session 21) were too few to tell the
/// get-up's rate from which starts fell: the first four fell 0 / 1 times without
/// `roll_reach` and 2 / 3 with it (MuJoCo / rapier), out of the same 2 / 5 over 12.
pub fn stands_up_on_gravel_into_a_crouch_walk(kind: BackendKind) {
    let scene = plamo_scenes::builtin("terrain-rough").unwrap();
    let falls = strip_falls(kind, &scene, 12, 12.0, |start, _| CrouchAfterCrawl {
        start,
        up_at: 6.0,
    });
    let total: u32 = falls.iter().sum();
    let most = match kind {
        BackendKind::Rapier => 7,
        BackendKind::Mujoco => 4,
    };
    assert!(
        total <= most,
        "{kind}: {total} falls standing up on gravel over 12 starts (at most {most}): {falls:?}"
    );
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

pub fn crawls_on_its_hands(kind: BackendKind) {
    let m = crawl_with(kind, &flat_scene(10.0), &line(), 10.0, CrawlParams::hands());
    // The hand crawl (`params/crawl-hands.toml`, the built-in one until session 17) is
    // faster than the forearm crawl on flat ground and its head higher. `crawl_sweep`
    // flat 0.5 m/s, 16 and 8 runs: XY 0.07 / 0.10 m (MuJoCo / rapier).
    check_within_z(kind, &m, 0.2, HAND_Z_ERR, "on its hands");
}

/// The (forearm) crawl gets up a 0.15 m ledge (`ledge_scene`) at 0.5 m/s, from three
/// staggered starts, with at most one fall between them and at most one of them more
/// than 1.5 m behind its plan: the plan reaches the ledge at 8 s and its end 4 m past
/// it. The forearm crawl of session 15 stalled at the foot of every ledge from 0.1 m,
/// its knees against the face, and the plan ran away from it (here: 3.7-4.0 m behind at
/// 0.1 m). What climbs is `spine_pitch` 1.2 (the shoulders within an upper arm of the
/// ground) and `knee_step_up`. Measured (`PLAMO_SWEEP_LENGTH=12 crawl_sweep rapier 0.5
/// 0.4 16 16 straight ledge@0.15`, the starts here are its runs 0-2): with session 42's
/// get-down the largest XY error is 0.27-0.77 m in 15 of 16 runs and 1.52 m in run 1
/// (late up the ledge, no fall), no falls; before it 0.32-0.80 m in 15 runs and one
/// fall (2.74 m) in run 10. Without the step-up 4.20 m.
pub fn climbs_a_ledge(kind: BackendKind) {
    use plamo_controller::{ledge_scene, staggered_start};
    let settings = settings();
    let scene = ledge_scene(12.0, 0.15);
    let mut falls = Vec::new();
    let mut behind = Vec::new();
    for r in 0..3 {
        let path = StraightPath {
            start: staggered_start([0.0, 0.0], r),
            speed: SPEED,
            head_height: 0.4,
        };
        let mut policy = ModelBasedController::new(settings.clone()).unwrap();
        let m = run_path(kind, &scene, &path, 16.0, &mut policy, &settings).unwrap();
        falls.push(m.falls);
        behind.push(m.xy_err_max);
    }
    let stalled = behind.iter().filter(|&&b| b >= 1.5).count();
    assert!(
        stalled <= 1,
        "{kind}: {stalled} of 3 runs fell 1.5 m or more behind the plan at the ledge: {behind:?}"
    );
    let total: u32 = falls.iter().sum();
    assert!(total <= 1, "{kind}: {total} falls at the ledge: {falls:?}");
}

/// Falls allowed to the forearm crawl on [`pursues_the_path_round_an_arc_on_a_slope`].
/// Measured (`crawl_sweep ENGINE 1.0 0.4 12 2 arc slope`): rapier 2, MuJoCo 0 with
/// `pursuit` 0.5 m; without it (`pursuit` 0) 9 and 7.
fn arc_slope_falls(kind: BackendKind) -> u32 {
    match kind {
        BackendKind::Rapier => 3,
        BackendKind::Mujoco => 1,
    }
}

/// The forearm crawl on the slope strip follows a 1 m/s arc (radius 3 m, left and
/// right, 12 s): it keeps to ~0.7 m/s and lags metres, and making for the first
/// waypoint it cut inside the arc, turning ever sharper, and rolled over. With
/// `pursuit` it follows the path itself.
pub fn pursues_the_path_round_an_arc_on_a_slope(kind: BackendKind) {
    let scene = plamo_scenes::builtin("terrain-slope").unwrap();
    let falls = strip_falls(kind, &scene, 2, 12.0, |start, r| ArcPath {
        start,
        speed: 1.0,
        head_height: 0.4,
        straight: 2.0,
        radius: if r % 2 == 0 { 3.0 } else { -3.0 },
    });
    let total: u32 = falls.iter().sum();
    assert!(
        total <= arc_slope_falls(kind),
        "{kind}: {total} falls on the arc up the slope (at most {}): {falls:?}",
        arc_slope_falls(kind)
    );
}

/// The crawl on the gravel and stair strips meets a plan that turns back 170 degrees
/// at 1 m/s (left and right, two staggered starts each, 11 s): it lags its plan by
/// ~1.5 m and finds the path heading off behind it, as where a crawl leg starts at a
/// landmark. Sweeping its limbs sideways at the plan's speed while it yawed, it rolled
/// over a forearm: measured (`crawl_sweep ENGINE 1.0 0.4 11 4 corner@170
/// rough,stairs`) rapier 2, MuJoCo 1 falls without `realign_above`, 0 and 0 with it
/// at 1 rad (the built-in file).
pub fn turns_back_at_a_corner_on_gravel_and_stairs(kind: BackendKind) {
    use plamo_controller::{START_ACCEL, TurnPath};
    let mut falls = Vec::new();
    for terrain in ["terrain-rough", "terrain-stairs"] {
        let scene = plamo_scenes::builtin(terrain).unwrap();
        let turns = strip_falls(kind, &scene, 4, 11.0, |start, r| TurnPath {
            start,
            speed: 1.0,
            corner_speed: 1.0,
            head_height: 0.4,
            first: 6.0,
            turn: if r % 2 == 0 { 170f64 } else { -170.0 }.to_radians(),
            accel: START_ACCEL,
        });
        falls.extend(turns.into_iter().enumerate().map(|(r, f)| (terrain, r, f)));
    }
    let total: u32 = falls.iter().map(|f| f.2).sum();
    assert_eq!(total, 0, "{kind}: falls turning back: {falls:?}");
}

/// Falls allowed to the hand crawl in MuJoCo over 16 rollouts of 10 s on the gravel and stair strips of
/// `plamo eval locomotion` (straight, 0.5 and 1 m/s, four staggered starts each, from
/// standing). Measured: 3 (0 / 1 on gravel, 1 / 1 on stairs) since roll first from
/// 0.25 rad (595d9d0), 6 before it (0 / 3, 1 / 2; 5 on an older tree), 8 with
/// `ground_ahead` on top (2 / 2, 1 / 3; the same protocol as `crawl_sweep mujoco
/// 0.5,1.0 0.4 10 4 straight rough,stairs`); 9 with the crawl of 6719f45, which went
/// up to 1.05 m/s (0 / 2, 3 / 4).
#[cfg(feature = "mujoco")]
const HAND_TERRAIN_FALLS: u32 = 6;

/// Falls of the (forearm) crawl under [`HAND_TERRAIN_FALLS`]' protocol. Measured: 0
/// (`crawl_sweep` with the forearm crawl's parameters, 16 runs per
/// cell: 0 on gravel and stairs at 0.5 and 1 m/s, against the hand crawl's 12). Since
/// session 16 (`knee_step_up`, `spine_pitch` 1.2) it climbs the stairs strip, 0.6 m
/// behind a 0.5 m/s plan; before, it stalled at the first riser.
#[cfg(feature = "mujoco")]
const TERRAIN_FALLS: u32 = 1;

/// Falls per rollout of `crawl` in MuJoCo on the gravel and stair strips of `plamo
/// eval locomotion` (straight, 0.5 and 1 m/s, four staggered starts each, from
/// standing, 10 s): (terrain, speed, run, falls).
#[cfg(feature = "mujoco")]
fn terrain_falls(crawl: CrawlParams) -> Vec<(&'static str, f64, usize, u32)> {
    let mut falls = Vec::new();
    for terrain in ["rough", "stairs"] {
        let scene = plamo_scenes::builtin(&format!("terrain-{terrain}")).unwrap();
        for speed in [0.5, 1.0] {
            for r in 0..4 {
                let path = StraightPath {
                    start: strip_start(r),
                    speed,
                    head_height: 0.4,
                };
                let m = crawl_with(BackendKind::Mujoco, &scene, &path, 10.0, crawl);
                falls.push((terrain, speed, r, m.falls));
            }
        }
    }
    falls
}

/// [`terrain_falls`] of `crawl` sum to at most `bound`.
#[cfg(feature = "mujoco")]
fn assert_terrain_falls(crawl: CrawlParams, bound: u32, what: &str) {
    let falls = terrain_falls(crawl);
    let total: u32 = falls.iter().map(|f| f.3).sum();
    assert!(
        total <= bound,
        "{total} falls on gravel and stairs{what} (at most {bound}): {falls:?}"
    );
}

#[cfg(feature = "mujoco")]
#[test]
fn mujoco_crawls_gravel_and_stairs_on_its_hands() {
    assert_terrain_falls(CrawlParams::hands(), HAND_TERRAIN_FALLS, " on the hands");
}

#[cfg(feature = "mujoco")]
#[test]
fn mujoco_crawls_gravel_and_stairs() {
    assert_terrain_falls(CrawlParams::default(), TERRAIN_FALLS, "");
}

/// A straight crawl plan at right angles to the standing body's heading (+X): along
/// +Y (`side` 1) or -Y (-1), as where a walk leg ends at a landmark and the crawl leg
/// heads elsewhere.
#[cfg(feature = "mujoco")]
struct SidePath {
    start: [f64; 2],
    speed: f64,
    side: f64,
}

#[cfg(feature = "mujoco")]
impl HeadPath for SidePath {
    fn point(&self, scene: &plamo_scenes::Scene, t: f64) -> Waypoint {
        let (x, y) = (
            self.start[0],
            self.start[1] + self.side * self.speed * t.max(0.0),
        );
        Waypoint {
            x,
            y,
            z: scene.height_at(x, y) + 0.4,
            v: self.speed,
        }
    }
    fn direction(&self, _t: f64) -> [f64; 2] {
        [0.0, self.side]
    }
    fn head_height(&self) -> f64 {
        0.4
    }
}

/// Falls allowed in MuJoCo over 4 rollouts of 8 s that get down on gravel or stairs and
/// crawl off at 1 m/s at right angles to the body (left and right). Measured: 1; 10
/// before the crawl kept its sideways speed to `max_side_speed` (it stepped sideways
/// at the plan's speed and rolled over a hand or knee; the random tours' falls at a
/// crawl leg's start were mostly this).
#[cfg(feature = "mujoco")]
const TURN_FALLS: u32 = 3;

#[cfg(feature = "mujoco")]
#[test]
fn mujoco_gets_down_and_crawls_off_at_a_right_angle() {
    let mut falls = Vec::new();
    for terrain in ["rough", "stairs"] {
        let scene = plamo_scenes::builtin(&format!("terrain-{terrain}")).unwrap();
        let sides = strip_falls(BackendKind::Mujoco, &scene, 2, 8.0, |start, r| SidePath {
            start,
            speed: 1.0,
            side: if r % 2 == 0 { 1.0 } else { -1.0 },
        });
        falls.extend(sides.into_iter().enumerate().map(|(r, f)| (terrain, r, f)));
    }
    let total: u32 = falls.iter().map(|f| f.2).sum();
    assert!(
        total <= TURN_FALLS,
        "{total} falls crawling off at a right angle (at most {TURN_FALLS}): {falls:?}"
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
            fn crawls_at_1_m_per_s() {
                super::crawls_at_1_m_per_s($kind);
            }
            #[test]
            fn gets_down_from_a_walk() {
                super::gets_down_from_a_walk($kind);
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
            fn stands_up_in_the_open_however_far_it_lags() {
                super::stands_up_in_the_open_however_far_it_lags($kind);
            }
            #[test]
            fn stays_down_under_a_top_while_it_lags() {
                super::stays_down_under_a_top_while_it_lags($kind);
            }
            #[test]
            fn stands_up_into_a_crouch_walk() {
                super::stands_up_into_a_crouch_walk($kind);
            }
            #[test]
            fn gets_up_from_a_kneeling_start_into_a_crouch_walk() {
                super::gets_up_from_a_kneeling_start_into_a_crouch_walk($kind);
            }
            #[test]
            fn stands_up_on_gravel_into_a_crouch_walk() {
                super::stands_up_on_gravel_into_a_crouch_walk($kind);
            }
            #[test]
            fn crawls_under_a_0_6_m_ceiling() {
                super::crawls_under_a_0_6_m_ceiling($kind);
            }
            #[test]
            fn crawls_on_its_hands() {
                super::crawls_on_its_hands($kind);
            }
            #[test]
            fn climbs_a_ledge() {
                super::climbs_a_ledge($kind);
            }
            #[test]
            fn pursues_the_path_round_an_arc_on_a_slope() {
                super::pursues_the_path_round_an_arc_on_a_slope($kind);
            }
            #[test]
            fn turns_back_at_a_corner_on_gravel_and_stairs() {
                super::turns_back_at_a_corner_on_gravel_and_stairs($kind);
            }
        }
    };
}

crawl_suite!(rapier, BackendKind::Rapier);
#[cfg(feature = "mujoco")]
crawl_suite!(mujoco, BackendKind::Mujoco);

/// The crawl tuned on the tours (`params/crawl-tours.toml`, session 27) ships beside the
/// built-in one: it loads, and on flat ground it crawls without falls and lags its plan
/// more than the built-in crawl (the trade its header states: slower, fewer falls on
/// the tours).
#[cfg(feature = "mujoco")]
#[test]
fn the_tours_tuned_crawl_ships_beside_it_and_lags_more() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("params/crawl-tours.toml");
    let tours = CrawlParams::load(&path).unwrap();
    assert_ne!(tours, CrawlParams::default());
    let scene = flat_scene(10.0);
    let m = crawl_with(BackendKind::Mujoco, &scene, &line(), 10.0, tours);
    let built_in = crawl_with(
        BackendKind::Mujoco,
        &scene,
        &line(),
        10.0,
        CrawlParams::default(),
    );
    assert_eq!(m.falls, 0, "{m:#?}");
    assert!(
        m.xy_err_mean > built_in.xy_err_mean,
        "tours-tuned {} m, built-in {} m",
        m.xy_err_mean,
        built_in.xy_err_mean
    );
}

/// The faster crawl (`params/crawl-fast.toml`, session 41) ships beside the built-in
/// one: it loads, lets the crawl go faster, and on flat ground at the paper's 1 m/s it
/// crawls without falls and keeps closer to its plan than the built-in 0.7 m/s crawl in
/// both engines (what the file is for; its header has the tours' cost of it).
#[test]
fn the_fast_crawl_ships_beside_it_and_keeps_up_at_1_m_per_s() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("params/crawl-fast.toml");
    let fast = CrawlParams::load(&path).unwrap();
    assert!(
        fast.max_speed > CrawlParams::default().max_speed + 0.3,
        "{fast:#?}"
    );
    let scene = flat_scene(20.0);
    let path = StraightPath {
        speed: 1.0,
        ..line()
    };
    let engines = [BackendKind::Rapier, BackendKind::Mujoco];
    for kind in engines.into_iter().filter(|k| k.is_available()) {
        let m = crawl_with(kind, &scene, &path, 10.0, fast);
        let built_in = crawl_with(kind, &scene, &path, 10.0, CrawlParams::default());
        assert_eq!(m.falls, 0, "{kind:?}: {m:#?}");
        assert!(
            // Measured: rapier 0.98 against 2.46 m, MuJoCo 1.26 against 2.53 (the built-in
            // with session 42's 1 s get-down; 2.66 and 2.72 with the 1.5 s one).
            m.xy_err_mean < 0.6 * built_in.xy_err_mean,
            "{kind:?}: fast {} m, built-in {} m",
            m.xy_err_mean,
            built_in.xy_err_mean
        );
    }
}
