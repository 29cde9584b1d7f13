//! Fall detection as a pure function of the state, shared by physics tests, the
//! controller and the evaluation.

use crate::{BODY_NAMES, FEET, HEAD, HumanoidState, NUM_BODIES};

/// The locomotion form a humanoid is asked to hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Posture {
    /// Walking or running, head about 1.47 m above the ground.
    Upright,
    /// Crouch-walking, head about 0.8 m.
    Crouch,
    /// Crawling on hands and knees, head about 0.4 m.
    Crawl,
}

impl Posture {
    /// The posture whose nominal head height is nearest to a requested head height
    /// above ground \[m\]: above 1.2 upright, above 0.6 crouch, else crawl.
    pub fn for_head_height(h: f64) -> Self {
        if h > 1.2 {
            Posture::Upright
        } else if h > 0.6 {
            Posture::Crouch
        } else {
            Posture::Crawl
        }
    }

    /// Head height above the ground below which the humanoid has fallen \[m\].
    pub fn min_head_height(self) -> f64 {
        match self {
            Posture::Upright => 0.9,
            Posture::Crouch => 0.45,
            Posture::Crawl => 0.15,
        }
    }

    /// Whether a body may touch the terrain in this posture.
    pub fn allows_terrain_contact(self, body: usize) -> bool {
        match self {
            Posture::Upright | Posture::Crouch => FEET.contains(&body),
            Posture::Crawl => body != HEAD,
        }
    }
}

/// Why a humanoid counts as fallen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FallReason {
    /// The head is below the posture's minimum height above the ground.
    HeadTooLow {
        /// Head height above the ground \[m\].
        height: f64,
        /// The posture's minimum \[m\].
        min: f64,
    },
    /// A body that must not touch the terrain in this posture does.
    BodyContact {
        /// The body's name ([`BODY_NAMES`]).
        body: &'static str,
    },
}

/// `Some(reason)` if the humanoid has fallen. `ground_under_head` is the terrain
/// height under the head's XY (e.g. `scene.terrain.height_at(head.x, head.y)`).
pub fn detect_fall(
    state: &HumanoidState,
    posture: Posture,
    ground_under_head: f64,
) -> Option<FallReason> {
    let height = state.head[2] - ground_under_head;
    let min = posture.min_head_height();
    if height.is_nan() || height < min {
        return Some(FallReason::HeadTooLow { height, min });
    }
    (0..NUM_BODIES)
        .find(|&b| state.terrain_contact[b] && !posture.allows_terrain_contact(b))
        .map(|b| FallReason::BodyContact {
            body: BODY_NAMES[b],
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn head_height_and_contacts() {
        let mut s = HumanoidState {
            head: [0.0, 0.0, 1.5],
            ..HumanoidState::default()
        };
        assert_eq!(detect_fall(&s, Posture::Upright, 0.0), None);
        assert!(matches!(
            detect_fall(&s, Posture::Upright, 0.7),
            Some(FallReason::HeadTooLow { .. })
        ));
        s.terrain_contact[FEET[0]] = true;
        assert_eq!(detect_fall(&s, Posture::Upright, 0.0), None);
        s.terrain_contact[crate::HANDS[0]] = true;
        assert_eq!(
            detect_fall(&s, Posture::Upright, 0.0),
            Some(FallReason::BodyContact { body: "right_hand" })
        );
        assert_eq!(detect_fall(&s, Posture::Crawl, 0.0), None);
        assert_eq!(Posture::for_head_height(1.47), Posture::Upright);
        assert_eq!(Posture::for_head_height(0.4), Posture::Crawl);
    }
}
