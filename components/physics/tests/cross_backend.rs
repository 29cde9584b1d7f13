//! rapier and MuJoCo simulate the same humanoid: the same PD squat gives head-height
//! trajectories that agree. Needs both backends (`--features mujoco`).
#![cfg(feature = "mujoco")]

mod common;

use plamo_physics::{BackendKind, HumanoidPose, PhysicsSettings, create_backend};

/// Head heights of five squat cycles (10 s at 120 Hz) on flat ground.
fn head_heights(kind: BackendKind) -> Vec<f64> {
    let scene = common::flat();
    let mut b = create_backend(kind, &scene, &PhysicsSettings::default()).unwrap();
    b.reset(&HumanoidPose::standing(0.0, 0.0, 0.0, 0.0))
        .unwrap();
    (0..1200)
        .map(|k| {
            b.set_action(&common::squat_targets(k as f64 / 120.0), None)
                .unwrap();
            b.step().unwrap();
            b.state().head[2]
        })
        .collect()
}

/// Measured over five cycles of the balanced squat (`common::squat_targets`): RMS
/// 0.8 mm, max 2.7 mm, squat depth 0.110 m (rapier, f32, implicit springs) vs 0.112 m
/// (MuJoCo, implicitfast position servos). Tolerance: RMS < 5 mm, max < 1 cm (a
/// humanoid that drifts, stumbles or falls in one engine only breaks it).
#[test]
fn squat_head_heights_agree_across_backends() {
    let r = head_heights(BackendKind::Rapier);
    let m = head_heights(BackendKind::Mujoco);
    let diffs: Vec<f64> = r.iter().zip(&m).map(|(a, b)| a - b).collect();
    let rms = (diffs.iter().map(|d| d * d).sum::<f64>() / diffs.len() as f64).sqrt();
    let max = diffs.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    let depth = |h: &[f64]| h[0] - h.iter().cloned().fold(f64::INFINITY, f64::min);
    println!(
        "head height rapier vs MuJoCo: RMS {:.4} m, max {:.4} m; squat depth rapier {:.3} m, MuJoCo {:.3} m",
        rms,
        max,
        depth(&r),
        depth(&m)
    );
    assert!(
        depth(&r) > 0.05 && depth(&m) > 0.05,
        "the squat moves the head"
    );
    assert!(rms < 0.005, "RMS {rms}");
    assert!(max < 0.01, "max {max}");
}

/// The same model, read back the same way: at rest both backends place every body
/// within a few millimetres of each other.
#[test]
fn rest_pose_body_positions_agree() {
    let scene = common::flat();
    let mk = |kind| {
        let mut b = create_backend(kind, &scene, &PhysicsSettings::default()).unwrap();
        let mut pose = HumanoidPose::standing(0.3, -0.2, 0.0, 0.7);
        pose.joints[plamo_physics::humanoid::joint_index("left_knee").unwrap()] = 0.5;
        pose.joints[plamo_physics::humanoid::joint_index("right_shoulder_x").unwrap()] = -0.4;
        pose.joints[plamo_physics::humanoid::joint_index("spine_y").unwrap()] = 0.2;
        b.reset(&pose).unwrap();
        b.state().clone()
    };
    let r = mk(BackendKind::Rapier);
    let m = mk(BackendKind::Mujoco);
    for (a, b) in r
        .body_pos
        .iter()
        .zip(&m.body_pos)
        .chain([(&r.head, &m.head)])
    {
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() < 1e-4, "{a:?} vs {b:?}");
        }
    }
    for (a, b) in r.joint_pos.iter().zip(&m.joint_pos) {
        assert!((a - b).abs() < 1e-5);
    }
}
