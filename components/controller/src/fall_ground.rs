//! The ground a head's height is judged from by the fall rule.
//!
//! The fall rule ([`ControllerSettings::is_fallen`]) compares the head's height above
//! the ground with the requested height. Measured from the ground right under the
//! head, a crawler up on its knees and forearms whose head passes over a stair's tread
//! ahead reads as low as the riser is high (0.08-0.15 m in the random scenes; 0.12-0.26
//! m in the 24 crawl falls on stairs replayed in session 31), and is judged fallen with
//! its pelvis at crawl height and the body level. ProtoMotions' path follower, the
//! paper's code, measures the head from the body's lowest point instead. Here the lower
//! of the two counts, and only while the body is still up: a pelvis at least
//! [`UP_PELVIS`] above the ground under it and rolled less than [`UP_ROLL`]. A body
//! that went down or over, or is falling past the terrain, is judged from the ground
//! under its head as before.

use plamo_scenes::Scene;

use crate::ControllerSettings;

/// Least height of the pelvis above the ground under it for a body still up on its
/// limbs \[m\]: a crawl's pelvis rides at ~0.45-0.55 m, a crouch-walk's ~0.6.
pub const UP_PELVIS: f64 = 0.3;

/// Smallest pelvis roll taken as rolled over \[rad\]: 20 of 24 crawl falls on stairs
/// replayed in session 31 were under 0.4 rad, upright with the head over a tread;
/// session 23 read a roll-over as past 0.8 rad (RESULTS.md "Crawl").
pub const UP_ROLL: f64 = 0.6;

/// What the fall rule reads of a humanoid (world frame).
#[derive(Debug, Clone, Copy)]
pub struct FallBody<'a> {
    /// Head centre \[m\].
    pub head: [f64; 3],
    /// Pelvis origin \[m\].
    pub pelvis: [f64; 3],
    /// Pelvis orientation, `[w, x, y, z]`.
    pub pelvis_quat: [f64; 4],
    /// Every body's origin \[m\].
    pub bodies: &'a [[f64; 3]],
}

impl<'a> FallBody<'a> {
    /// What the fall rule reads of a physics state.
    pub fn of(state: &'a plamo_physics::HumanoidState) -> Self {
        Self {
            head: state.head,
            pelvis: state.root_position,
            pelvis_quat: state.root_quat,
            bodies: &state.body_pos,
        }
    }

    /// What the fall rule reads of a state message (its quaternion is `(x, y, z, w)`).
    pub fn of_message(state: &'a plamo_interfaces::HumanoidState) -> Self {
        let [x, y, z, w] = state.root_orientation;
        Self {
            head: state.head_position,
            pelvis: state.root_position,
            pelvis_quat: [w, x, y, z],
            bodies: state.bodies(),
        }
    }
}

/// Roll of a pelvis with orientation `q` (`[w, x, y, z]`) \[rad\]: the angle its
/// left axis rises above the horizontal, whatever its pitch and heading.
pub fn pelvis_roll(q: [f64; 4]) -> f64 {
    let [w, x, y, z] = q;
    (2.0 * (y * z + x * w)).clamp(-1.0, 1.0).asin()
}

impl ControllerSettings {
    /// The ground height the head of `body` is judged from \[m\] (module docs).
    pub fn fall_ground(&self, scene: &Scene, body: &FallBody) -> f64 {
        let [hx, hy, _] = body.head;
        let under_head = scene.height_at(hx, hy);
        if !self.fall_from_lowest_body {
            return under_head;
        }
        let lowest = body.bodies.iter().map(|p| p[2]).fold(under_head, f64::min);
        // On even ground no body is below the ground under the head: the posture
        // decides nothing there.
        if lowest == under_head {
            return under_head;
        }
        let [px, py, pz] = body.pelvis;
        let up = pz - scene.height_at(px, py) >= self.fall_up_pelvis
            && pelvis_roll(body.pelvis_quat).abs() < self.fall_up_roll;
        if up { lowest } else { under_head }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rotation by `angle` about the unit `axis`, as `[w, x, y, z]`.
    fn about(axis: [f64; 3], angle: f64) -> [f64; 4] {
        let (s, c) = (0.5 * angle).sin_cos();
        [c, axis[0] * s, axis[1] * s, axis[2] * s]
    }

    #[test]
    fn roll_is_read_whatever_the_heading_and_pitch() {
        let q = about([1.0, 0.0, 0.0], 0.5);
        assert!((pelvis_roll(q) - 0.5).abs() < 1e-12);
        // Turned 90 degrees first: the roll is about the body's own forward axis.
        let yaw = about([0.0, 0.0, 1.0], std::f64::consts::FRAC_PI_2);
        let [w1, x1, y1, z1] = yaw;
        let [w2, x2, y2, z2] = q;
        let q = [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ];
        assert!((pelvis_roll(q) - 0.5).abs() < 1e-12);
        assert!(pelvis_roll(about([0.0, 1.0, 0.0], 0.9)).abs() < 1e-12);
    }

    /// A crawler whose knees are on the flight's lower tread and whose head is over
    /// the next one is judged from its knees while it is up, from the tread under its
    /// head once its pelvis sinks or it rolls, and always with the rule switched off.
    #[test]
    fn a_head_over_a_tread_is_judged_from_the_knees_while_the_body_is_up() {
        let scene = plamo_scenes::builtin("terrain-stairs").expect("built-in scene");
        let y = 0.0;
        // A riser between a pelvis 0.5 m behind the head and the head.
        let x = (0..600)
            .map(|i| 5.0 + i as f64 * 0.05)
            .find(|&x| scene.height_at(x + 0.5, y) - scene.height_at(x, y) > 0.1)
            .expect("a riser on the stairs strip");
        let low = scene.height_at(x, y);
        let high = scene.height_at(x + 0.5, y);
        let knee = [x - 0.2, y, low + 0.05];
        let bodies = [[x, y, low + 0.5], knee, [x + 0.5, y, high + 0.3]];
        let level = [1.0, 0.0, 0.0, 0.0];
        let body = |pelvis_z: f64, q: [f64; 4]| FallBody {
            head: [x + 0.5, y, high + 0.3],
            pelvis: [x, y, low + pelvis_z],
            pelvis_quat: q,
            bodies: &bodies,
        };
        let s = ControllerSettings::default();
        assert_eq!(s.fall_ground(&scene, &body(0.5, level)), knee[2]);
        assert_eq!(s.fall_ground(&scene, &body(0.2, level)), high);
        let rolled = about([1.0, 0.0, 0.0], 0.8);
        assert_eq!(s.fall_ground(&scene, &body(0.5, rolled)), high);
        let off = ControllerSettings {
            fall_from_lowest_body: false,
            ..Default::default()
        };
        assert_eq!(off.fall_ground(&scene, &body(0.5, level)), high);
        // On even ground the body's points are above it: the ground under the head.
        let flat = plamo_scenes::builtin("terrain-flat").expect("built-in scene");
        let g = flat.height_at(x + 0.5, y);
        let bodies = [[x, y, g + 0.5], [x - 0.2, y, g + 0.05]];
        let b = FallBody {
            head: [x + 0.5, y, g + 0.3],
            pelvis: [x, y, g + 0.5],
            pelvis_quat: level,
            bodies: &bodies,
        };
        assert_eq!(s.fall_ground(&flat, &b), g);
    }
}
