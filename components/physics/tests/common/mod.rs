//! Scenes and motions shared by the physics tests, built programmatically.
#![allow(dead_code)]

use plamo_physics::{NUM_JOINTS, humanoid::joint_index};
use plamo_scenes::{
    DynamicObstacle, Footprint, HeightGrid, Motion, ObstacleShape, Scene, TopObstacle,
};

pub fn scene(name: &str, terrain: HeightGrid) -> Scene {
    Scene {
        name: name.into(),
        description: String::new(),
        terrain,
        walls: vec![],
        dynamic: vec![],
        tops: vec![],
        landmarks: vec![],
    }
}

/// 6 x 6 m flat ground at z = 0, centred on the origin.
pub fn flat() -> Scene {
    scene("flat", HeightGrid::flat([-3.0, -3.0], [6.0, 6.0], 0.1, 0.0))
}

fn shaped(name: &str, f: impl Fn(f64, f64) -> f64) -> Scene {
    let mut g = HeightGrid::flat([-3.0, -3.0], [6.0, 6.0], 0.1, 0.0);
    for j in 0..g.ny {
        for i in 0..g.nx {
            let [x, y] = g.position(i, j);
            g.heights[j * g.nx + i] = f(x, y);
        }
    }
    scene(name, g)
}

/// A 10 degree slope rising along +X.
pub fn slope() -> Scene {
    shaped("slope", |x, _| x * 10f64.to_radians().tan())
}

/// Gravel: +-3 cm pseudo-random bumps (fixed hash, no RNG state).
pub fn gravel() -> Scene {
    shaped("gravel", |x, y| {
        let h = ((x * 12.9898 + y * 78.233).sin() * 43758.5453).fract();
        0.03 * (2.0 * h.abs() - 1.0)
    })
}

/// Stairs rising along +X: 15 cm risers, 30 cm treads; the humanoid lands across a step edge.
pub fn stairs() -> Scene {
    shaped("stairs", |x, _| {
        0.15 * ((x + 0.1) / 0.3).floor().clamp(-5.0, 5.0)
    })
}

/// A 0.6 x 1.2 x 1.0 m box sliding along -X at 1 m/s towards the origin from x = 2.
pub fn pushing_box() -> Scene {
    let mut s = flat();
    s.dynamic.push(DynamicObstacle {
        name: "cart".into(),
        shape: ObstacleShape::Box {
            half_extents: [0.3, 0.6, 0.5],
        },
        motion: Motion::Linear {
            from: [2.0, 0.0, 0.55],
            to: [-2.0, 0.0, 0.55],
            speed: 1.0,
        },
    });
    s
}

/// A 0.3 m ball parked 1000 m below the ground: a slot a host drives.
pub fn parked_ball() -> Scene {
    let mut s = flat();
    s.dynamic.push(DynamicObstacle {
        name: "host-ball".into(),
        shape: ObstacleShape::Sphere { radius: 0.3 },
        motion: Motion::Linear {
            from: [0.0, 0.0, -1000.0],
            to: [0.0, 0.0, -1000.0],
            speed: 1.0,
        },
    });
    s
}

/// A ceiling whose underside is at `z_bottom`, covering x in [x0, x0 + 2], |y| < 1.
pub fn ceiling(x0: f64, z_bottom: f64) -> Scene {
    let mut s = flat();
    s.tops.push(TopObstacle {
        name: "ceiling".into(),
        footprint: Footprint::axis_aligned([x0 + 1.0, 0.0], [1.0, 1.0]),
        z_bottom,
        z_top: z_bottom + 0.3,
    });
    s
}

/// PD targets of a 0.5 Hz squat at time t, with a(t) = 0.5 (1 - cos(pi t)) / 2 (0 to
/// 0.5 rad): hips flex by a, knees by 2 a and ankles dorsiflex by a (shank and thigh
/// tilt by a each way, so the pelvis moves down over the ankles), and the spine leans
/// forward by 0.3 a (0.15 rad at the bottom) to keep the centre of mass over the middle
/// of the feet, which extend 6.5 cm behind and 15.5 cm in front of the ankle. The knees
/// bend to 1 rad and the head drops ~11 cm. Measured over 60 s (30 cycles): without
/// the lean both engines drift backwards and fall within 3 s (MuJoCo) to 5 s; with a
/// lean of 0.2-0.4 a both stand, MuJoCo's pelvis creeping forward by 10-15 cm and
/// rapier's by 2 cm.
pub fn squat_targets(t: f64) -> [f64; NUM_JOINTS] {
    let a = 0.5 * 0.5 * (1.0 - (std::f64::consts::PI * t).cos());
    let mut q = [0.0; NUM_JOINTS];
    for side in ["right", "left"] {
        q[joint_index(&format!("{side}_hip_y")).unwrap()] = -a;
        q[joint_index(&format!("{side}_knee")).unwrap()] = 2.0 * a;
        q[joint_index(&format!("{side}_ankle_y")).unwrap()] = -a;
    }
    q[joint_index("spine_y").unwrap()] = 0.3 * a;
    q
}
