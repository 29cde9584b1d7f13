//! The conformance suite: the same tests, generic over `PhysicsBackend`, run for
//! every backend built in (rapier always, MuJoCo with the `mujoco` feature).

mod common;

use plamo_physics::{
    BackendKind, FEET, HumanoidPose, NUM_JOINTS, PhysicsBackend, PhysicsError, PhysicsSettings,
    Posture, RootWrench, create_backend, detect_fall,
};
use plamo_scenes::{ObstacleState, Scene};

fn backend(kind: BackendKind, scene: &Scene) -> Box<dyn PhysicsBackend> {
    create_backend(kind, scene, &PhysicsSettings::default()).expect("backend builds")
}

fn stand_pose(scene: &Scene, x: f64, y: f64) -> HumanoidPose {
    HumanoidPose::standing_on(&scene.terrain, x, y, 0.0)
}

/// Hold the rest pose for `steps`; returns the lowest head height seen.
fn hold(b: &mut dyn PhysicsBackend, steps: usize) -> f64 {
    let mut lowest = f64::INFINITY;
    for _ in 0..steps {
        b.set_action(&[0.0; NUM_JOINTS], None).unwrap();
        b.step().unwrap();
        lowest = lowest.min(b.state().head[2]);
    }
    lowest
}

/// The "stable at 120 Hz for 60 s standing".
pub fn stands_for_sixty_seconds(kind: BackendKind) {
    let scene = common::flat();
    let mut b = backend(kind, &scene);
    b.reset(&stand_pose(&scene, 0.0, 0.0)).unwrap();
    let lowest = hold(b.as_mut(), 60 * 120);
    let s = b.state();
    assert!(lowest > 1.3, "{kind}: head dropped to {lowest}");
    assert!(
        s.terrain_contact[FEET[0]] && s.terrain_contact[FEET[1]],
        "{kind}: both feet on the ground"
    );
    assert_eq!(detect_fall(s, Posture::Upright, 0.0), None);
    assert!(
        (s.root_position[0].abs() + s.root_position[1].abs()) < 0.1,
        "{kind}: drifted {:?}",
        s.root_position
    );
}

pub fn drop_settles(kind: BackendKind, scene: Scene) {
    let mut b = backend(kind, &scene);
    let mut pose = stand_pose(&scene, 0.0, 0.0);
    pose.root_position[2] += 0.3;
    b.reset(&pose).unwrap();
    // Every step is checked for NaN by the backend (`step` would return Diverged).
    // Passive PD has no balance feedback, so on rough ground the humanoid may topple;
    // what must hold is that it comes to rest on the terrain, not in it.
    for _ in 0..720 {
        b.set_action(&[0.0; NUM_JOINTS], None).unwrap();
        b.step().unwrap();
        let s = b.state();
        for (bi, p) in s.body_pos.iter().enumerate() {
            let ground = scene.terrain.height_at(p[0], p[1]);
            assert!(
                p[2] > ground - 0.02,
                "{kind} on {}: {} sank to {:.3} (ground {ground:.3})",
                scene.name,
                plamo_physics::BODY_NAMES[bi],
                p[2]
            );
        }
    }
    let s = b.state().clone();
    assert!(s.is_finite());
    let speed = s.root_linvel.iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!(
        speed < 0.2,
        "{kind} on {}: still moving at {speed} m/s",
        scene.name
    );
    assert!(
        s.terrain_contact.iter().any(|c| *c),
        "{kind} on {}: resting on the terrain",
        scene.name
    );
}

pub fn kinematic_obstacle_pushes(kind: BackendKind) {
    let scene = common::pushing_box();
    let mut b = backend(kind, &scene);
    b.reset(&stand_pose(&scene, 0.0, 0.0)).unwrap();
    let mut touched = false;
    for _ in 0..300 {
        b.set_action(&[0.0; NUM_JOINTS], None).unwrap();
        b.step().unwrap();
        touched |= b.state().contact.iter().any(|c| *c) && b.obstacles()[0].position[0] < 0.7;
    }
    let s = b.state();
    // The obstacle follows its rule exactly.
    let expected = scene.dynamic[0].motion.state_at(b.tick().seconds());
    assert_eq!(b.obstacles()[0], expected);
    assert!(touched, "{kind}: the box touched the humanoid");
    assert!(
        s.root_position[0] < -0.3,
        "{kind}: pushed back to x = {}",
        s.root_position[0]
    );
}

/// A host-driven obstacle: placed from its parking spot without flinging anything,
/// moved at its sample's velocity, and pushing the humanoid it runs into.
pub fn driven_obstacle_pushes(kind: BackendKind) {
    let scene = common::parked_ball();
    let mut b = backend(kind, &scene);
    b.reset(&stand_pose(&scene, 0.0, 0.0)).unwrap();
    let start = [-2.4, 0.0, 0.9];
    let velocity = [2.0, 0.0, 0.0];
    let sample = ObstacleState {
        position: start,
        velocity,
    };
    let e = b.drive_obstacle(1, sample).unwrap_err();
    assert!(
        matches!(e, PhysicsError::InvalidScene { .. }),
        "{kind}: {e}"
    );
    assert!(
        e.to_string().contains("no dynamic obstacle 1"),
        "{kind}: {e}"
    );
    let mut nan = sample;
    nan.velocity[2] = f64::NAN;
    let e = b.drive_obstacle(0, nan).unwrap_err();
    assert!(matches!(e, PhysicsError::NonFinite { .. }), "{kind}: {e}");

    let t0 = b.tick().seconds();
    b.drive_obstacle(0, sample).unwrap();
    // 0.4 s: the ball has jumped up from z = -1000 m and rolls in, still 1.3 m away.
    hold(b.as_mut(), 48);
    let still = b.state();
    assert!(
        still.root_position[0].abs() < 0.05 && still.root_linvel.iter().all(|v| v.abs() < 0.2),
        "{kind}: placing the ball disturbed the humanoid: root {:?}, velocity {:?}",
        still.root_position,
        still.root_linvel
    );
    let mut touched = false;
    for _ in 0..132 {
        b.set_action(&[0.0; NUM_JOINTS], None).unwrap();
        b.step().unwrap();
        touched |= b.state().contact.iter().any(|c| *c) && b.obstacles()[0].position[0] > -0.6;
        let dt = b.tick().seconds() - t0;
        let expected = [0, 1, 2].map(|i| start[i] + velocity[i] * dt);
        let got = b.obstacles()[0].position;
        assert!(
            (0..3).all(|i| (got[i] - expected[i]).abs() < 1e-9),
            "{kind}: ball at {got:?}, driven to {expected:?}"
        );
    }
    assert!(touched, "{kind}: the ball never touched the humanoid");
    let s = b.state();
    assert!(
        s.root_position[0] > 0.3 || s.head[2] < 1.0,
        "{kind}: the ball did not push the humanoid (root {:?}, head {:?})",
        s.root_position,
        s.head
    );
}

pub fn ceiling_blocks_upright_humanoid(kind: BackendKind) {
    // Pushed forward into a ceiling at 1.2 m: the head (top at 1.57 m) cannot pass under.
    let scene = common::ceiling(0.5, 1.2);
    let mut b = backend(kind, &scene);
    b.reset(&stand_pose(&scene, 0.0, 0.0)).unwrap();
    let push = RootWrench {
        force: [250.0, 0.0, 0.0],
        torque: [0.0; 3],
    };
    let mut hit = false;
    for _ in 0..240 {
        b.set_action(&[0.0; NUM_JOINTS], Some(push)).unwrap();
        b.step().unwrap();
        let s = b.state();
        if s.head[0] > 0.5 + 0.05 {
            assert!(
                s.head[2] < 1.2,
                "{kind}: head at {:?} passed through the ceiling",
                s.head
            );
        }
        hit |= s.contact[plamo_physics::HEAD] || s.contact[1];
    }
    assert!(hit, "{kind}: head or torso touched the ceiling");

    // Lifted straight up into a ceiling at 1.62 m: the head stops under it.
    let scene = common::ceiling(-1.0, 1.62);
    let mut b = backend(kind, &scene);
    b.reset(&stand_pose(&scene, 0.0, 0.0)).unwrap();
    let lift = RootWrench {
        force: [0.0, 0.0, 1500.0],
        torque: [0.0; 3],
    };
    let mut highest: f64 = 0.0;
    for _ in 0..120 {
        b.set_action(&[0.0; NUM_JOINTS], Some(lift)).unwrap();
        b.step().unwrap();
        highest = highest.max(b.state().head[2]);
    }
    // Head sphere radius 0.10: its centre stays below 1.52 (+ contact slop).
    assert!(highest < 1.55, "{kind}: head centre reached {highest}");
    assert!(
        b.state().contact[plamo_physics::HEAD],
        "{kind}: head touches the ceiling"
    );
}

fn squat_run(kind: BackendKind, steps: usize) -> Vec<plamo_physics::HumanoidState> {
    let scene = common::flat();
    let mut b = backend(kind, &scene);
    b.reset(&stand_pose(&scene, 0.0, 0.0)).unwrap();
    let mut out = Vec::with_capacity(steps);
    for k in 0..steps {
        b.set_action(&common::squat_targets(k as f64 / 120.0), None)
            .unwrap();
        b.step().unwrap();
        out.push(b.state().clone());
    }
    out
}

/// The "stable under a 0.5 Hz squat": 60 s, 30 cycles, every step `Ok` (a
/// non-finite state is an error), the head never below 1.25 m (lowest measured 1.36 m
/// in both engines; 1.0 m means a fall) and back up at the top of each cycle, feet
/// within 0.3 m of where they started (measured: MuJoCo 0.10-0.15 m, rapier 0.02 m).
pub fn squats_for_sixty_seconds(kind: BackendKind) {
    let run = squat_run(kind, 60 * 120);
    for (k, s) in run.iter().enumerate() {
        assert!(s.is_finite(), "{kind}: non-finite state at step {k}");
        assert!(
            s.head[2] > 1.25,
            "{kind}: head at {:.3} m at t = {:.2} s",
            s.head[2],
            k as f64 / 120.0
        );
        // Top of each cycle (t = 2 n s): standing up again.
        if k % 240 == 239 {
            assert!(s.head[2] > 1.4, "{kind}: not back up at step {k}");
        }
    }
    let last = run.last().unwrap();
    for f in FEET {
        let [x, y, _] = last.body_pos[f];
        assert!(
            x.hypot(y) < 0.3,
            "{kind}: foot {f} moved to ({x:.3}, {y:.3})"
        );
    }
}

pub fn deterministic(kind: BackendKind) {
    let a = squat_run(kind, 240);
    let b = squat_run(kind, 240);
    for (k, (x, y)) in a.iter().zip(&b).enumerate() {
        assert_eq!(x.bits(), y.bits(), "{kind}: runs differ at step {k}");
    }
}

pub fn squat_tracks_targets(kind: BackendKind) {
    let run = squat_run(kind, 240);
    let knee = plamo_physics::humanoid::joint_index("left_knee").unwrap();
    let mut worst: f64 = 0.0;
    for (k, s) in run.iter().enumerate().skip(60) {
        let target = common::squat_targets(k as f64 / 120.0)[knee];
        worst = worst.max((s.joint_pos[knee] - target).abs());
        assert!(s.head[2] > 1.0, "{kind}: fell during the squat");
    }
    // PD lag under body weight: measured ~0.21 rad in both engines at the fastest bend.
    assert!(worst < 0.3, "{kind}: knee tracking error {worst} rad");
    let lowest = run.iter().map(|s| s.head[2]).fold(f64::INFINITY, f64::min);
    assert!(
        lowest < 1.40,
        "{kind}: the squat lowers the head (lowest {lowest})"
    );
    assert!(
        run.last().unwrap().head[2] > 1.4,
        "{kind}: back up after one cycle"
    );
}

pub fn bad_input_is_an_error(kind: BackendKind) {
    let scene = common::flat();
    let mut b = backend(kind, &scene);
    b.reset(&stand_pose(&scene, 0.0, 0.0)).unwrap();
    let mut t = [0.0; NUM_JOINTS];
    t[3] = f64::NAN;
    assert!(matches!(
        b.set_action(&t, None),
        Err(PhysicsError::NonFinite { index: 3, .. })
    ));
    assert!(matches!(
        b.set_action(&[0.0; 5], None),
        Err(PhysicsError::WrongActionLength {
            expected: NUM_JOINTS,
            got: 5
        })
    ));
    let nan_wrench = RootWrench {
        force: [0.0, f64::INFINITY, 0.0],
        torque: [0.0; 3],
    };
    assert!(matches!(
        b.set_action(&[0.0; NUM_JOINTS], Some(nan_wrench)),
        Err(PhysicsError::NonFinite { .. })
    ));
    let mut pose = stand_pose(&scene, 0.0, 0.0);
    pose.yaw = f64::NAN;
    assert!(matches!(
        b.reset(&pose),
        Err(PhysicsError::NonFinite { .. })
    ));
    assert!(matches!(
        b.reset_humanoid(7, &stand_pose(&scene, 0.0, 0.0)),
        Err(PhysicsError::NoSuchHumanoid { .. })
    ));
    assert!(b.humanoid_state(1).is_err());
    // Out-of-limit targets are clamped into the joint range: the knee stops at its limit.
    let knee = plamo_physics::humanoid::joint_index("right_knee").unwrap();
    let mut t = [0.0; NUM_JOINTS];
    t[knee] = -3.0;
    b.set_action(&t, None).unwrap();
    b.step_n(60).unwrap();
    assert!(
        b.state().joint_pos[knee] > -0.05 - 0.05,
        "{kind}: knee {}",
        b.state().joint_pos[knee]
    );
    assert!(b.state().is_finite());
}

pub fn divergence_is_an_error_not_a_panic(kind: BackendKind) {
    let scene = common::flat();
    let settings = PhysicsSettings {
        max_root_force: 1e300,
        max_root_torque: 1e300,
        ..PhysicsSettings::default()
    };
    let mut b = create_backend(kind, &scene, &settings).unwrap();
    let w = RootWrench {
        force: [1e300, 0.0, 1e300],
        torque: [1e300, 1e300, 0.0],
    };
    b.set_action(&[0.0; NUM_JOINTS], Some(w)).unwrap();
    let mut diverged = false;
    for _ in 0..10 {
        match b.step() {
            Ok(()) => assert!(b.state().is_finite()),
            Err(PhysicsError::Diverged { .. }) => {
                diverged = true;
                break;
            }
            Err(e) => panic!("{kind}: unexpected error {e}"),
        }
    }
    assert!(diverged, "{kind}: a 1e300 N push diverges");
    // Refuses to continue until reset, then runs again.
    assert!(matches!(b.step(), Err(PhysicsError::Diverged { .. })));
    b.reset(&stand_pose(&scene, 0.0, 0.0)).unwrap();
    b.set_action(&[0.0; NUM_JOINTS], None).unwrap();
    b.step_n(10).unwrap();
    assert!(b.state().is_finite());
}

pub fn several_humanoids_share_a_world(kind: BackendKind) {
    let scene = common::flat();
    let settings = PhysicsSettings {
        humanoids: 3,
        ..PhysicsSettings::default()
    };
    let mut b = create_backend(kind, &scene, &settings).unwrap();
    assert_eq!(b.num_humanoids(), 3);
    for i in 0..3 {
        b.reset_humanoid(i, &stand_pose(&scene, -1.0 + i as f64, 0.5 * i as f64))
            .unwrap();
    }
    for _ in 0..240 {
        for i in 0..3 {
            b.set_action_for(i, &[0.0; NUM_JOINTS], None).unwrap();
        }
        b.step().unwrap();
    }
    for i in 0..3 {
        let s = b.humanoid_state(i).unwrap();
        assert!(s.head[2] > 1.3, "{kind}: humanoid {i} fell");
        assert!((s.root_position[0] - (-1.0 + i as f64)).abs() < 0.1);
    }
}

macro_rules! conformance {
    ($module:ident, $kind:expr) => {
        mod $module {
            use super::*;
            #[test]
            fn stands_for_sixty_seconds() {
                super::stands_for_sixty_seconds($kind);
            }
            #[test]
            fn squats_for_sixty_seconds() {
                super::squats_for_sixty_seconds($kind);
            }
            #[test]
            fn drop_settles_on_flat() {
                super::drop_settles($kind, common::flat());
            }
            #[test]
            fn drop_settles_on_slope() {
                super::drop_settles($kind, common::slope());
            }
            #[test]
            fn drop_settles_on_gravel() {
                super::drop_settles($kind, common::gravel());
            }
            #[test]
            fn drop_settles_on_stairs() {
                super::drop_settles($kind, common::stairs());
            }
            #[test]
            fn kinematic_obstacle_pushes() {
                super::kinematic_obstacle_pushes($kind);
            }
            #[test]
            fn driven_obstacle_pushes() {
                super::driven_obstacle_pushes($kind);
            }
            #[test]
            fn ceiling_blocks_upright_humanoid() {
                super::ceiling_blocks_upright_humanoid($kind);
            }
            #[test]
            fn deterministic() {
                super::deterministic($kind);
            }
            #[test]
            fn squat_tracks_targets() {
                super::squat_tracks_targets($kind);
            }
            #[test]
            fn bad_input_is_an_error() {
                super::bad_input_is_an_error($kind);
            }
            #[test]
            fn divergence_is_an_error_not_a_panic() {
                super::divergence_is_an_error_not_a_panic($kind);
            }
            #[test]
            fn several_humanoids_share_a_world() {
                super::several_humanoids_share_a_world($kind);
            }
        }
    };
}

conformance!(rapier, BackendKind::Rapier);
#[cfg(feature = "mujoco")]
conformance!(mujoco, BackendKind::Mujoco);

#[test]
fn backend_kind_parses_and_lists_valid_values() {
    assert_eq!("rapier".parse::<BackendKind>(), Ok(BackendKind::Rapier));
    assert_eq!("mujoco".parse::<BackendKind>(), Ok(BackendKind::Mujoco));
    let e = "bullet".parse::<BackendKind>().unwrap_err().to_string();
    assert!(
        e.contains("bullet") && e.contains("rapier") && e.contains("mujoco"),
        "{e}"
    );
    assert_eq!(BackendKind::default(), BackendKind::Rapier);
}

#[cfg(not(feature = "mujoco"))]
#[test]
fn mujoco_without_the_feature_is_a_typed_error() {
    let r = create_backend(
        BackendKind::Mujoco,
        &common::flat(),
        &PhysicsSettings::default(),
    );
    assert!(matches!(r, Err(PhysicsError::Unavailable { .. })));
}

#[test]
fn invalid_settings_are_rejected() {
    let s = PhysicsSettings {
        rapier_solver_iterations: 0,
        ..PhysicsSettings::default()
    };
    assert!(matches!(
        create_backend(BackendKind::Rapier, &common::flat(), &s),
        Err(PhysicsError::InvalidSettings {
            field: "rapier_solver_iterations",
            ..
        })
    ));
    for hz in [0.0, f64::NAN, 5000.0] {
        let s = PhysicsSettings {
            rapier_contact_hz: hz,
            ..PhysicsSettings::default()
        };
        assert!(matches!(
            create_backend(BackendKind::Rapier, &common::flat(), &s),
            Err(PhysicsError::InvalidSettings {
                field: "rapier_contact_hz",
                ..
            })
        ));
    }
}
