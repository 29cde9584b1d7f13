//! Small quaternion/vector helpers (`[w, x, y, z]` quaternions, f64).

/// Rotation about +Z by `yaw`.
pub fn quat_from_yaw(yaw: f64) -> [f64; 4] {
    let (s, c) = (0.5 * yaw).sin_cos();
    [c, 0.0, 0.0, s]
}

/// Rotate `v` by the unit quaternion `q`.
pub fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let [w, x, y, z] = q;
    let u = [x, y, z];
    let t = cross(u, v).map(|c| 2.0 * c);
    let ut = cross(u, t);
    [
        v[0] + w * t[0] + ut[0],
        v[1] + w * t[1] + ut[1],
        v[2] + w * t[2] + ut[2],
    ]
}

/// Cross product.
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `p + rotate(q, v)`.
pub fn transform(p: [f64; 3], q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let r = rotate(q, v);
    [p[0] + r[0], p[1] + r[1], p[2] + r[2]]
}

/// Scale `v` down to norm `max` if it is longer.
pub fn clamp_norm(v: [f64; 3], max: f64) -> [f64; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if n > max && n > 0.0 {
        v.map(|c| c * max / n)
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yaw_rotation() {
        let r = rotate(quat_from_yaw(std::f64::consts::FRAC_PI_2), [1.0, 0.0, 0.0]);
        assert!(r[0].abs() < 1e-12 && (r[1] - 1.0).abs() < 1e-12);
        assert_eq!(clamp_norm([3.0, 4.0, 0.0], 1.0), [0.6, 0.8, 0.0]);
    }
}
