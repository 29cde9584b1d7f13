//! How a humanoid lay when the fall rule first judged it fallen, read from the world
//! state of that step: the experiments break their falls down by it, so a change to
//! the controller can be aimed at the kind of fall that loses the most tours.
//!
//! Up to session 34 the fall rule judged the head from the ground under it, so a
//! crawler on its knees and forearms whose head passed over a tread ahead was judged
//! by that tread while its pelvis was still at crawl height: *head-over-step* tells
//! that kind apart from a body that rolled over or went down forward or backward.
//! Since then a body still up is judged from its lowest point
//! ([`plamo_controller::fall_ground`]), and a head over a step is a fall only where
//! it came within the rule's bar of the body's lowest point too.

use plamo_scenes::Scene;

/// Smallest pelvis roll taken as rolled over \[rad\]: the roll from which the fall
/// rule no longer judges the body as up ([`plamo_controller::fall_ground`]).
pub const ROLLED_FROM: f64 = plamo_controller::fall_ground::UP_ROLL;
/// Least rise of the ground under the head above the ground under the pelvis for a
/// head over a step \[m\]: the random scenes' risers are 0.08-0.15 m.
pub const STEP_UNDER_HEAD: f64 = 0.08;
/// Least height of the pelvis above the ground under it for a body still up on its
/// limbs \[m\] (as the fall rule's, [`plamo_controller::fall_ground`]).
pub const PELVIS_UP: f64 = plamo_controller::fall_ground::UP_PELVIS;

/// What the posture is read from: the humanoid's root and head (world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FallPose {
    /// Root (pelvis) position \[m\].
    pub root: [f64; 3],
    /// Root orientation as a unit quaternion (x, y, z, w).
    pub orientation: [f64; 4],
    /// Head position \[m\].
    pub head: [f64; 3],
}

/// Posture at a fall, in the order it is tested.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum FallPosture {
    /// The pelvis rolled past [`ROLLED_FROM`].
    Rolled,
    /// Up on its limbs, the head over ground at least [`STEP_UNDER_HEAD`] higher than
    /// the ground under the pelvis.
    HeadOverStep,
    /// Down with the head ahead of the pelvis along its heading.
    Forward,
    /// Down with the head behind the pelvis.
    Backward,
}

impl FallPosture {
    /// Every posture, in the order tables show them.
    pub const ALL: [FallPosture; 4] = [
        Self::Rolled,
        Self::HeadOverStep,
        Self::Forward,
        Self::Backward,
    ];

    /// The name the experiments write ("head-over-step").
    pub fn name(self) -> &'static str {
        match self {
            Self::Rolled => "rolled",
            Self::HeadOverStep => "head-over-step",
            Self::Forward => "forward",
            Self::Backward => "backward",
        }
    }

    /// The posture named `name` ([`FallPosture::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The posture of a humanoid in pose `s` in `scene`.
    pub fn of(scene: &Scene, s: &FallPose) -> Self {
        let [x, y, z, w] = s.orientation;
        let roll = plamo_controller::pelvis_roll([w, x, y, z]);
        let forward = [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + z * w)];
        let (r, h) = (s.root, s.head);
        let under_root = scene.height_at(r[0], r[1]);
        if roll.abs() >= ROLLED_FROM {
            Self::Rolled
        } else if r[2] - under_root >= PELVIS_UP
            && scene.height_at(h[0], h[1]) - under_root >= STEP_UNDER_HEAD
        {
            Self::HeadOverStep
        } else if (h[0] - r[0]) * forward[0] + (h[1] - r[1]) * forward[1] >= 0.0 {
            Self::Forward
        } else {
            Self::Backward
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A humanoid with its pelvis at `root` turned by `quat` (x, y, z, w) and its
    /// head at `head`.
    fn body(root: [f64; 3], quat: [f64; 4], head: [f64; 3]) -> FallPose {
        FallPose {
            root,
            orientation: quat,
            head,
        }
    }

    /// A rotation by `angle` about the unit `axis`, as (x, y, z, w).
    fn about(axis: [f64; 3], angle: f64) -> [f64; 4] {
        let (s, c) = (0.5 * angle).sin_cos();
        [axis[0] * s, axis[1] * s, axis[2] * s, c]
    }

    #[test]
    fn each_posture_is_told_from_the_pelvis_and_the_ground_under_the_head() {
        let stairs = plamo_scenes::builtin("terrain-stairs").expect("built-in scene");
        let flat = plamo_scenes::builtin("playground").expect("built-in scene");
        // Find where the flight rises by a riser ahead (+x) of a crawler's pelvis.
        let y = 0.0;
        let x = (0..400)
            .map(|i| f64::from(i) * 0.05)
            .find(|&x| stairs.height_at(x + 0.5, y) - stairs.height_at(x, y) >= 0.1)
            .expect("the stairs scene rises somewhere along y = 0");
        let g = stairs.height_at(x, y);
        let crawl_pitch = about([0.0, 1.0, 0.0], 0.9);
        let head = [x + 0.5, y, stairs.height_at(x + 0.5, y) + 0.18];
        let up = body([x, y, g + 0.48], crawl_pitch, head);
        assert_eq!(FallPosture::of(&stairs, &up), FallPosture::HeadOverStep);
        // The same body with its pelvis on the ground has gone down forward.
        let down = body([x, y, g + 0.2], crawl_pitch, head);
        assert_eq!(FallPosture::of(&stairs, &down), FallPosture::Forward);
        // Rolled past the bar, whatever the ground does, and also while pitched.
        let (fx, fy) = (20.0, 20.0);
        let h0 = flat.height_at(fx, fy);
        for axis in [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]] {
            let q = about(axis, ROLLED_FROM + 0.1);
            let s = body([fx, fy, h0 + 0.5], q, [fx + 0.5, fy, h0 + 0.1]);
            assert_eq!(FallPosture::of(&flat, &s), FallPosture::Rolled);
        }
        let q = about([1.0, 0.0, 0.0], ROLLED_FROM - 0.1);
        let s = body([fx, fy, h0 + 0.5], q, [fx + 0.5, fy, h0 + 0.1]);
        assert_eq!(FallPosture::of(&flat, &s), FallPosture::Forward);
        // Heading +y (yawed a quarter turn): a head at -y is behind the pelvis.
        let yawed = about([0.0, 0.0, 1.0], std::f64::consts::FRAC_PI_2);
        let s = body([fx, fy, h0 + 0.2], yawed, [fx, fy - 0.6, h0 + 0.1]);
        assert_eq!(FallPosture::of(&flat, &s), FallPosture::Backward);
        let s = body([fx, fy, h0 + 0.2], yawed, [fx, fy + 0.6, h0 + 0.1]);
        assert_eq!(FallPosture::of(&flat, &s), FallPosture::Forward);
    }

    #[test]
    fn names_read_back() {
        for p in FallPosture::ALL {
            assert_eq!(FallPosture::from_name(p.name()), Some(p));
        }
        assert_eq!(FallPosture::from_name("sideways"), None);
    }
}
