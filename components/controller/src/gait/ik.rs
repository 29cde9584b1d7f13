//! Two-segment leg inverse kinematics in the pelvis frame.
//!
//! Joint conventions (plamo-physics `humanoid`): the hip is hinges X, Y, Z; a positive
//! hip X moves the foot towards +Y, a positive hip Y moves it backwards (flexion is
//! negative), a positive knee flexes, a positive ankle Y points the toes down.

/// Leg segment lengths \[m\].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegGeometry {
    /// Hip to knee.
    pub thigh: f64,
    /// Knee to ankle.
    pub shin: f64,
}

/// Hip X, hip Y and knee angles \[rad\] that put the ankle at `p` (relative to the
/// hip, pelvis frame). Out-of-reach targets are pulled in along the same direction.
pub fn leg_ik(g: &LegGeometry, p: [f64; 3]) -> [f64; 3] {
    let hip_x = p[1].atan2(-p[2]);
    let down = (p[1] * p[1] + p[2] * p[2]).sqrt();
    let reach_max = (g.thigh + g.shin) * 0.999;
    let reach_min = (g.thigh - g.shin).abs() + 0.05;
    let d = (p[0] * p[0] + down * down)
        .sqrt()
        .clamp(reach_min, reach_max);
    let alpha = p[0].atan2(down);
    let cos_knee = (g.thigh * g.thigh + g.shin * g.shin - d * d) / (2.0 * g.thigh * g.shin);
    let knee = std::f64::consts::PI - cos_knee.clamp(-1.0, 1.0).acos();
    let cos_beta = (g.thigh * g.thigh + d * d - g.shin * g.shin) / (2.0 * g.thigh * d);
    let beta = cos_beta.clamp(-1.0, 1.0).acos();
    [hip_x, -(alpha + beta), knee]
}

/// Ankle position relative to the hip for hip X, hip Y, knee angles (forward
/// kinematics of [`leg_ik`], hip Z = 0).
pub fn leg_fk(g: &LegGeometry, q: [f64; 3]) -> [f64; 3] {
    let [hx, hy, k] = q;
    // In the plane after hip X: thigh and shin as pitch rotations of (0, 0, -L).
    let x = -g.thigh * hy.sin() - g.shin * (hy + k).sin();
    let z = -g.thigh * hy.cos() - g.shin * (hy + k).cos();
    // Rotate the plane by hip X: (0, y', z') -> Rx(hx).
    [x, -z * hx.sin(), z * hx.cos()]
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: LegGeometry = LegGeometry {
        thigh: 0.41,
        shin: 0.39,
    };

    #[test]
    fn ik_inverts_fk_and_knee_bends_forward() {
        for p in [
            [0.0, 0.0, -0.75],
            [0.2, 0.05, -0.7],
            [-0.25, -0.08, -0.65],
            [0.1, 0.1, -0.5],
        ] {
            let q = leg_ik(&G, p);
            let back = leg_fk(&G, q);
            for i in 0..3 {
                assert!((back[i] - p[i]).abs() < 1e-9, "{p:?} -> {q:?} -> {back:?}");
            }
            assert!(q[2] > 0.0, "knee flexes positively");
        }
        // A foot ahead of the hip needs hip flexion (negative hip Y).
        assert!(leg_ik(&G, [0.3, 0.0, -0.7])[1] < 0.0);
        // Out of reach: straight leg, no NaN.
        let q = leg_ik(&G, [0.0, 0.0, -2.0]);
        assert!(q.iter().all(|v| v.is_finite()) && q[2] < 0.1);
    }
}
