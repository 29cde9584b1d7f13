//! The humanoid: one description, the single source for both backends.
//!
//! The model is data ([`BODIES`], [`JOINTS`]): the MuJoCo backend writes MJCF from it
//! ([`crate::humanoid_mjcf`]) and the rapier backend builds a reduced-coordinate
//! multibody from it, so both simulate the same bodies, shapes, masses (density
//! 1000 kg/m^3), hinge axes, limits, gains and armature.
//!
//! # Conventions
//! - World and body frames are Z-up, metres, radians. In the rest pose (all joint
//!   angles 0) every body frame is aligned with the pelvis frame; the humanoid faces
//!   +X with its left side at +Y.
//! - Every joint is a hinge about its body's local X, Y or Z axis (right-hand rule).
//!   A ball joint is three hinges applied in order (X, then Y, then Z: child =
//!   parent * offset * Rx(qx) * Ry(qy) * Rz(qz)); the ankle is Y (pitch) then X (roll).
//!   Both backends compose hinges this way, so a PD target means the same joint angle
//!   in both.
//! - Signs: a positive Y rotation turns +Z towards +X. For the upright spine that leans
//!   forward; for a hanging limb it swings the distal end backwards: hip flexion
//!   (thigh forward) and elbow flexion are negative, knee flexion is positive, positive
//!   ankle pitch points the toes down. A positive X rotation moves a hanging limb
//!   towards +Y (left): left-leg/arm abduction is positive, right is negative.
//!
//! Standing in the rest pose with the feet on z = 0 puts the pelvis origin at
//! [`STANDING_PELVIS_HEIGHT`] and the head centre at [`STANDING_HEAD_HEIGHT`]
//! (1.47 m). Total mass is about 69 kg.

/// Number of actuated hinge joints (the length of every action and joint vector).
pub const NUM_JOINTS: usize = 26;
/// Number of bodies (pelvis first, then depth-first in [`BODY_NAMES`] order).
pub const NUM_BODIES: usize = 15;

/// Joint order of actions (PD targets), joint angles and joint velocities.
pub const JOINT_NAMES: [&str; NUM_JOINTS] = [
    "spine_x",
    "spine_y",
    "spine_z",
    "neck_x",
    "neck_y",
    "neck_z",
    "right_shoulder_x",
    "right_shoulder_y",
    "right_shoulder_z",
    "right_elbow",
    "left_shoulder_x",
    "left_shoulder_y",
    "left_shoulder_z",
    "left_elbow",
    "right_hip_x",
    "right_hip_y",
    "right_hip_z",
    "right_knee",
    "right_ankle_y",
    "right_ankle_x",
    "left_hip_x",
    "left_hip_y",
    "left_hip_z",
    "left_knee",
    "left_ankle_y",
    "left_ankle_x",
];

/// Body order of per-body outputs (positions, contact flags).
pub const BODY_NAMES: [&str; NUM_BODIES] = [
    "pelvis",
    "torso",
    "head",
    "right_upper_arm",
    "right_lower_arm",
    "right_hand",
    "left_upper_arm",
    "left_lower_arm",
    "left_hand",
    "right_thigh",
    "right_shin",
    "right_foot",
    "left_thigh",
    "left_shin",
    "left_foot",
];

/// Index of the pelvis (the root) in [`BODY_NAMES`].
pub const PELVIS: usize = 0;
/// Index of the head body in [`BODY_NAMES`].
pub const HEAD: usize = 2;
/// Indices of the hands in [`BODY_NAMES`] (right, left).
pub const HANDS: [usize; 2] = [5, 8];
/// Indices of the feet in [`BODY_NAMES`] (right, left).
pub const FEET: [usize; 2] = [11, 14];
/// Indices of the shins in [`BODY_NAMES`] (right, left): the knees touch the ground
/// when crawling.
pub const SHINS: [usize; 2] = [10, 13];

/// Head reference point in the head body's frame \[m\]: the centre of the head sphere.
/// `HumanoidState::head` is this point in world coordinates.
pub const HEAD_OFFSET: [f64; 3] = [0.0, 0.0, 0.08];
/// Radius of the head sphere around [`HEAD_OFFSET`] \[m\].
pub const HEAD_RADIUS: f64 = 0.10;
/// Pelvis origin height above flat ground when standing in the rest pose \[m\].
pub const STANDING_PELVIS_HEIGHT: f64 = 0.93;
/// Head centre height above flat ground when standing in the rest pose \[m\].
pub const STANDING_HEAD_HEIGHT: f64 = 1.47;

/// Material density of every body geom \[kg/m^3\].
pub const DENSITY: f64 = 1000.0;
/// Joint armature (reflected rotor inertia) on every hinge \[kg m^2\].
pub const ARMATURE: f64 = 0.02;
/// Passive joint damping on every hinge \[N m s/rad\] (added to the PD `kd`).
pub const JOINT_DAMPING: f64 = 1.0;

/// A hinge axis in the body frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// Local X.
    X,
    /// Local Y.
    Y,
    /// Local Z.
    Z,
}

impl Axis {
    /// Index 0, 1, 2.
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
    /// Unit vector.
    pub fn unit(self) -> [f64; 3] {
        let mut v = [0.0; 3];
        v[self.index()] = 1.0;
        v
    }
}

/// A collision/mass shape attached to a body, in the body frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// Capsule between two points with a radius \[m\].
    Capsule {
        /// One end of the segment.
        from: [f64; 3],
        /// The other end.
        to: [f64; 3],
        /// Radius.
        radius: f64,
    },
    /// Sphere at a centre.
    Sphere {
        /// Centre.
        center: [f64; 3],
        /// Radius.
        radius: f64,
    },
    /// Axis-aligned box.
    Box {
        /// Centre.
        center: [f64; 3],
        /// Half extents.
        half_extents: [f64; 3],
    },
}

/// One rigid body of the humanoid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyDesc {
    /// Name (same as [`BODY_NAMES`]).
    pub name: &'static str,
    /// Parent body index, `None` for the pelvis (free root).
    pub parent: Option<usize>,
    /// Body origin in the parent frame at rest \[m\] (the joint anchor).
    pub offset: [f64; 3],
    /// Joints (indices into [`JOINTS`]) applied in order at the body origin.
    pub joints: &'static [usize],
    /// Geoms.
    pub shapes: &'static [Shape],
}

/// One hinge joint and its PD actuator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointDesc {
    /// Name (same as [`JOINT_NAMES`]).
    pub name: &'static str,
    /// Hinge axis in the body frame.
    pub axis: Axis,
    /// Lower and upper limit \[rad\].
    pub range: [f64; 2],
    /// PD stiffness \[N m/rad\].
    pub kp: f64,
    /// PD damping \[N m s/rad\].
    pub kd: f64,
    /// Torque limit of the actuator \[N m\].
    pub max_torque: f64,
}

const fn j(
    name: &'static str,
    axis: Axis,
    range: [f64; 2],
    kp: f64,
    kd: f64,
    max_torque: f64,
) -> JointDesc {
    JointDesc {
        name,
        axis,
        range,
        kp,
        kd,
        max_torque,
    }
}

use Axis::{X, Y, Z};

/// All hinge joints, in [`JOINT_NAMES`] order, with limits and PD gains (gains from
/// the MuJoCo walker prototype recorded in FIELD-NOTES).
///
/// Hips and knees have kd 60 and a 600 N m limit, not the prototype's kd 80 and
/// 400 N m: the actuator force is capped at `max_torque`, so a joint cannot turn faster
/// than about `max_torque / kd`, and 5 rad/s held a 2 m/s walk back (a run needs
/// 7-9 rad/s at the hip); now about 10 rad/s. Lower damping alone (kd 40-50 at 400 N m)
/// let the open-loop squat of the conformance suite fall in rapier.
pub const JOINTS: [JointDesc; NUM_JOINTS] = [
    j("spine_x", X, [-0.6, 0.6], 1000.0, 100.0, 500.0),
    j("spine_y", Y, [-0.5, 1.2], 1000.0, 100.0, 500.0),
    j("spine_z", Z, [-0.8, 0.8], 1000.0, 100.0, 500.0),
    j("neck_x", X, [-0.6, 0.6], 60.0, 6.0, 50.0),
    j("neck_y", Y, [-0.6, 0.9], 60.0, 6.0, 50.0),
    j("neck_z", Z, [-1.0, 1.0], 60.0, 6.0, 50.0),
    j("right_shoulder_x", X, [-3.0, 0.5], 150.0, 15.0, 120.0),
    j("right_shoulder_y", Y, [-3.0, 1.0], 150.0, 15.0, 120.0),
    j("right_shoulder_z", Z, [-1.5, 1.5], 150.0, 15.0, 120.0),
    j("right_elbow", Y, [-2.6, 0.05], 120.0, 12.0, 100.0),
    j("left_shoulder_x", X, [-0.5, 3.0], 150.0, 15.0, 120.0),
    j("left_shoulder_y", Y, [-3.0, 1.0], 150.0, 15.0, 120.0),
    j("left_shoulder_z", Z, [-1.5, 1.5], 150.0, 15.0, 120.0),
    j("left_elbow", Y, [-2.6, 0.05], 120.0, 12.0, 100.0),
    j("right_hip_x", X, [-1.0, 0.4], 800.0, 60.0, 600.0),
    j("right_hip_y", Y, [-2.4, 0.6], 800.0, 60.0, 600.0),
    j("right_hip_z", Z, [-0.8, 0.8], 800.0, 60.0, 600.0),
    j("right_knee", Y, [-0.05, 2.7], 800.0, 60.0, 600.0),
    j("right_ankle_y", Y, [-0.9, 0.9], 600.0, 60.0, 300.0),
    j("right_ankle_x", X, [-0.5, 0.5], 300.0, 30.0, 150.0),
    j("left_hip_x", X, [-0.4, 1.0], 800.0, 60.0, 600.0),
    j("left_hip_y", Y, [-2.4, 0.6], 800.0, 60.0, 600.0),
    j("left_hip_z", Z, [-0.8, 0.8], 800.0, 60.0, 600.0),
    j("left_knee", Y, [-0.05, 2.7], 800.0, 60.0, 600.0),
    j("left_ankle_y", Y, [-0.9, 0.9], 600.0, 60.0, 300.0),
    j("left_ankle_x", X, [-0.5, 0.5], 300.0, 30.0, 150.0),
];

const fn cap(from: [f64; 3], to: [f64; 3], radius: f64) -> Shape {
    Shape::Capsule { from, to, radius }
}

const UPPER_ARM: &[Shape] = &[cap([0.0, 0.0, -0.03], [0.0, 0.0, -0.24], 0.05)];
const LOWER_ARM: &[Shape] = &[cap([0.0, 0.0, -0.02], [0.0, 0.0, -0.20], 0.04)];
const HAND: &[Shape] = &[Shape::Sphere {
    center: [0.0, 0.0, -0.05],
    radius: 0.05,
}];
const THIGH: &[Shape] = &[cap([0.0, 0.0, -0.04], [0.0, 0.0, -0.36], 0.08)];
const SHIN: &[Shape] = &[cap([0.0, 0.0, -0.03], [0.0, 0.0, -0.33], 0.055)];
const FOOT: &[Shape] = &[Shape::Box {
    center: [0.045, 0.0, -0.035],
    half_extents: [0.11, 0.045, 0.035],
}];

const fn body(
    name: &'static str,
    parent: Option<usize>,
    offset: [f64; 3],
    joints: &'static [usize],
    shapes: &'static [Shape],
) -> BodyDesc {
    BodyDesc {
        name,
        parent,
        offset,
        joints,
        shapes,
    }
}

/// All bodies in [`BODY_NAMES`] order; a parent always comes before its children.
pub const BODIES: [BodyDesc; NUM_BODIES] = [
    body(
        "pelvis",
        None,
        [0.0, 0.0, STANDING_PELVIS_HEIGHT],
        &[],
        &[cap([0.0, -0.07, 0.0], [0.0, 0.07, 0.0], 0.10)],
    ),
    body(
        "torso",
        Some(PELVIS),
        [0.0, 0.0, 0.10],
        &[0, 1, 2],
        &[
            cap([0.0, 0.0, 0.02], [0.0, 0.0, 0.20], 0.10),
            cap([0.0, -0.08, 0.28], [0.0, 0.08, 0.28], 0.11),
        ],
    ),
    body(
        "head",
        Some(1),
        [0.0, 0.0, 0.36],
        &[3, 4, 5],
        &[Shape::Sphere {
            center: HEAD_OFFSET,
            radius: HEAD_RADIUS,
        }],
    ),
    body(
        "right_upper_arm",
        Some(1),
        [0.0, -0.19, 0.33],
        &[6, 7, 8],
        UPPER_ARM,
    ),
    body(
        "right_lower_arm",
        Some(3),
        [0.0, 0.0, -0.28],
        &[9],
        LOWER_ARM,
    ),
    body("right_hand", Some(4), [0.0, 0.0, -0.24], &[], HAND),
    body(
        "left_upper_arm",
        Some(1),
        [0.0, 0.19, 0.33],
        &[10, 11, 12],
        UPPER_ARM,
    ),
    body(
        "left_lower_arm",
        Some(6),
        [0.0, 0.0, -0.28],
        &[13],
        LOWER_ARM,
    ),
    body("left_hand", Some(7), [0.0, 0.0, -0.24], &[], HAND),
    body(
        "right_thigh",
        Some(PELVIS),
        [0.0, -0.09, -0.06],
        &[14, 15, 16],
        THIGH,
    ),
    body("right_shin", Some(9), [0.0, 0.0, -0.41], &[17], SHIN),
    body("right_foot", Some(10), [0.0, 0.0, -0.39], &[18, 19], FOOT),
    body(
        "left_thigh",
        Some(PELVIS),
        [0.0, 0.09, -0.06],
        &[20, 21, 22],
        THIGH,
    ),
    body("left_shin", Some(12), [0.0, 0.0, -0.41], &[23], SHIN),
    body("left_foot", Some(13), [0.0, 0.0, -0.39], &[24, 25], FOOT),
];

/// Index of a joint by name.
pub fn joint_index(name: &str) -> Option<usize> {
    JOINT_NAMES.iter().position(|n| *n == name)
}

/// Index of a body by name.
pub fn body_index(name: &str) -> Option<usize> {
    BODY_NAMES.iter().position(|n| *n == name)
}

/// Mass of one shape at [`DENSITY`] \[kg\].
pub fn shape_mass(shape: &Shape) -> f64 {
    use std::f64::consts::PI;
    let v = match *shape {
        Shape::Capsule { from, to, radius } => {
            let l =
                ((to[0] - from[0]).powi(2) + (to[1] - from[1]).powi(2) + (to[2] - from[2]).powi(2))
                    .sqrt();
            PI * radius * radius * l + 4.0 / 3.0 * PI * radius.powi(3)
        }
        Shape::Sphere { radius, .. } => 4.0 / 3.0 * PI * radius.powi(3),
        Shape::Box {
            half_extents: h, ..
        } => 8.0 * h[0] * h[1] * h[2],
    };
    v * DENSITY
}

/// Total mass of the humanoid \[kg\].
pub fn total_mass() -> f64 {
    BODIES
        .iter()
        .flat_map(|b| b.shapes.iter())
        .map(shape_mass)
        .sum()
}

/// Clamp a joint target into the joint's range.
pub fn clamp_to_range(joint: usize, q: f64) -> f64 {
    let [lo, hi] = JOINTS[joint].range;
    q.clamp(lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_are_consistent() {
        for (i, jd) in JOINTS.iter().enumerate() {
            assert_eq!(jd.name, JOINT_NAMES[i]);
            assert!(jd.range[0] < 0.0 + 1e-9 || jd.range[0] <= 0.0);
            assert!(jd.range[0] < jd.range[1]);
            assert!(
                jd.range[0] <= 0.0 && jd.range[1] >= 0.0,
                "{} rest pose in range",
                jd.name
            );
        }
        let mut seen = [false; NUM_JOINTS];
        for (i, b) in BODIES.iter().enumerate() {
            assert_eq!(b.name, BODY_NAMES[i]);
            if let Some(p) = b.parent {
                assert!(p < i);
            }
            for &jj in b.joints {
                assert!(!seen[jj]);
                seen[jj] = true;
            }
        }
        assert!(seen.iter().all(|s| *s));
        // Joint order follows body order, so qpos order matches JOINT_NAMES.
        let order: Vec<usize> = BODIES
            .iter()
            .flat_map(|b| b.joints.iter().copied())
            .collect();
        assert_eq!(order, (0..NUM_JOINTS).collect::<Vec<_>>());
    }

    #[test]
    fn mass_and_heights() {
        let m = total_mass();
        assert!((65.0..75.0).contains(&m), "mass {m}");
        // Head: pelvis 0.93 + torso 0.10 + neck 0.36 + offset 0.08.
        let head = STANDING_PELVIS_HEIGHT + 0.10 + 0.36 + HEAD_OFFSET[2];
        assert!((head - STANDING_HEAD_HEIGHT).abs() < 1e-9);
        // Foot soles at z = 0.
        let ankle = STANDING_PELVIS_HEIGHT - 0.06 - 0.41 - 0.39;
        assert!((ankle - 0.07).abs() < 1e-9);
    }
}
