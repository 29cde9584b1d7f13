//! Forward kinematics of the humanoid from a recorded frame (pelvis pose + joint
//! angles), composing hinges exactly as both physics backends do (see
//! `plamo_physics::humanoid`): child = parent * offset * hinge_1(q_1) * hinge_2(q_2) ...

use plamo_physics::humanoid::{BODIES, JOINTS};
use plamo_physics::{NUM_BODIES, NUM_JOINTS};

/// A rigid pose: position \[m\] and unit quaternion (x, y, z, w).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyPose {
    /// Position.
    pub pos: [f64; 3],
    /// Orientation.
    pub rot: [f64; 4],
}

/// Quaternion product a * b, (x, y, z, w).
pub(crate) fn qmul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let [ax, ay, az, aw] = a;
    let [bx, by, bz, bw] = b;
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

/// Rotate v by the unit quaternion q.
pub(crate) fn qrot(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let [x, y, z, w] = q;
    // v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z)
    let c = [
        y * v[2] - z * v[1],
        z * v[0] - x * v[2],
        x * v[1] - y * v[0],
    ];
    let cc = [
        y * c[2] - z * c[1],
        z * c[0] - x * c[2],
        x * c[1] - y * c[0],
    ];
    [
        v[0] + 2.0 * (w * c[0] + cc[0]),
        v[1] + 2.0 * (w * c[1] + cc[1]),
        v[2] + 2.0 * (w * c[2] + cc[2]),
    ]
}

/// Unit quaternion of a rotation by `angle` about a unit `axis`.
pub(crate) fn qaxis(axis: [f64; 3], angle: f64) -> [f64; 4] {
    let (s, c) = (0.5 * angle).sin_cos();
    [axis[0] * s, axis[1] * s, axis[2] * s, c]
}

pub(crate) fn qnormalize(q: [f64; 4]) -> [f64; 4] {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    if n > 0.0 {
        q.map(|c| c / n)
    } else {
        [0.0, 0.0, 0.0, 1.0]
    }
}

/// Each body's rotation relative to its parent frame (the product of its hinges);
/// the pelvis gets the identity (its world orientation is the root's).
pub fn local_rotations(joints: &[f64; NUM_JOINTS]) -> [[f64; 4]; NUM_BODIES] {
    let mut out = [[0.0, 0.0, 0.0, 1.0]; NUM_BODIES];
    for (b, body) in BODIES.iter().enumerate() {
        for &j in body.joints {
            out[b] = qmul(out[b], qaxis(JOINTS[j].axis.unit(), joints[j]));
        }
    }
    out
}

/// World poses of all bodies, in `BODY_NAMES` order.
pub fn body_poses(
    root: [f64; 3],
    quat: [f64; 4],
    joints: &[f64; NUM_JOINTS],
) -> [BodyPose; NUM_BODIES] {
    let local = local_rotations(joints);
    let mut out = [BodyPose {
        pos: root,
        rot: qnormalize(quat),
    }; NUM_BODIES];
    for (b, body) in BODIES.iter().enumerate() {
        let Some(p) = body.parent else { continue };
        let parent = out[p];
        let o = qrot(parent.rot, body.offset);
        out[b] = BodyPose {
            pos: [
                parent.pos[0] + o[0],
                parent.pos[1] + o[1],
                parent.pos[2] + o[2],
            ],
            rot: qmul(parent.rot, local[b]),
        };
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use plamo_physics::humanoid::{STANDING_HEAD_HEIGHT, STANDING_PELVIS_HEIGHT};
    use plamo_physics::{HEAD, HEAD_OFFSET};

    #[test]
    fn rest_pose_puts_the_head_at_standing_height() {
        let p = body_poses(
            [1.0, 2.0, STANDING_PELVIS_HEIGHT],
            [0.0, 0.0, 0.0, 1.0],
            &[0.0; NUM_JOINTS],
        );
        let h = p[HEAD];
        let head = qrot(h.rot, HEAD_OFFSET);
        assert!((h.pos[2] + head[2] - STANDING_HEAD_HEIGHT).abs() < 1e-12);
        assert!((h.pos[0] - 1.0).abs() < 1e-12 && (h.pos[1] - 2.0).abs() < 1e-12);
    }

    #[test]
    fn spine_pitch_leans_the_head_forward() {
        // Positive Y rotation turns +Z towards +X: the upright torso leans forward.
        let mut q = [0.0; NUM_JOINTS];
        q[plamo_physics::humanoid::joint_index("spine_y").unwrap()] = 0.5;
        let p = body_poses([0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0], &q);
        assert!(p[HEAD].pos[0] > 0.1, "{:?}", p[HEAD].pos);
    }
}
