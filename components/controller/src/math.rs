//! Small rotation helpers (quaternions are `[w, x, y, z]`, world frame, Z up).

use std::f64::consts::PI;

/// Rotation matrix (row-major) of a unit quaternion `[w, x, y, z]`.
pub(crate) fn quat_to_mat(q: [f64; 4]) -> [[f64; 3]; 3] {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let [w, x, y, z] = if n > 0.0 {
        [q[0] / n, q[1] / n, q[2] / n, q[3] / n]
    } else {
        [1.0, 0.0, 0.0, 0.0]
    };
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// Heading \[rad\] of a rotation: yaw of its forward (+X) axis projected on the ground.
pub(crate) fn heading_of(m: &[[f64; 3]; 3]) -> f64 {
    m[1][0].atan2(m[0][0])
}

/// Rotates a world vector into the heading frame (rotation by `-heading` about Z).
pub(crate) fn to_heading_frame(heading: f64, v: [f64; 3]) -> [f64; 3] {
    let (s, c) = heading.sin_cos();
    [c * v[0] + s * v[1], -s * v[0] + c * v[1], v[2]]
}

/// Rotates a heading-frame vector back into the world (rotation by `heading` about Z).
pub(crate) fn from_heading_frame(heading: f64, v: [f64; 3]) -> [f64; 3] {
    let (s, c) = heading.sin_cos();
    [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]]
}

/// 0 at `s` <= 0, 1 at `s` >= 1, cubic with zero slope at both ends between.
pub(crate) fn smoothstep(s: f64) -> f64 {
    let s = s.clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

/// How far `x` is past `from`, 0-1: 0 up to `from`, 1 from twice it, linear between;
/// 1 at any `x` when `from` is 0 (the ramp of a switch that starts at a threshold).
pub(crate) fn ramp_past(x: f64, from: f64) -> f64 {
    if from > 0.0 {
        (x / from - 1.0).clamp(0.0, 1.0)
    } else {
        1.0
    }
}

/// One step of a first-order low-pass: `x` moved towards `target` by `dt / tau` of the
/// gap (all of it once `dt >= tau`).
pub(crate) fn low_pass(x: f64, target: f64, dt: f64, tau: f64) -> f64 {
    x + (dt / tau).min(1.0) * (target - x)
}

/// Wraps an angle into (-pi, pi].
pub(crate) fn wrap_angle(a: f64) -> f64 {
    let mut a = (a + PI).rem_euclid(2.0 * PI) - PI;
    if a <= -PI {
        a += 2.0 * PI;
    }
    a
}

/// Euclidean norm of a 3-vector.
pub(crate) fn norm3(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// `a - b`.
pub(crate) fn sub3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `v` scaled down to length `max` if longer.
pub(crate) fn clamp_norm(v: [f64; 3], max: f64) -> [f64; 3] {
    let n = norm3(v);
    if n > max && n > 0.0 {
        v.map(|x| x * max / n)
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yaw_quaternion_gives_its_heading_and_frames_invert() {
        let yaw: f64 = 0.7;
        let q = [(yaw / 2.0).cos(), 0.0, 0.0, (yaw / 2.0).sin()];
        let m = quat_to_mat(q);
        assert!((heading_of(&m) - yaw).abs() < 1e-12);
        let v = [1.0, 2.0, 3.0];
        let back = from_heading_frame(yaw, to_heading_frame(yaw, v));
        for i in 0..3 {
            assert!((back[i] - v[i]).abs() < 1e-12);
        }
        // The forward axis of the body is +X in its own heading frame.
        let fwd = to_heading_frame(yaw, [m[0][0], m[1][0], m[2][0]]);
        assert!((fwd[0] - 1.0).abs() < 1e-12 && fwd[1].abs() < 1e-12);
    }

    #[test]
    fn wrap_angle_stays_in_range() {
        for k in -20..20 {
            let a = wrap_angle(k as f64 * 0.9);
            assert!(a > -PI && a <= PI);
            let turns = (k as f64 * 0.9 - a) / (2.0 * PI);
            assert!((turns - turns.round()).abs() < 1e-9);
        }
        assert!((wrap_angle(3.0 * PI) - PI).abs() < 1e-12);
    }
}
