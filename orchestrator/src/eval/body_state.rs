//! What the humanoid's body was doing in the seconds before a fall, read from the
//! heights of its head and pelvis over the ground: down on its limbs, rising from
//! there, just risen, going down, or upright all along.
//!
//! The experiments' `fall_sites` name the plan's form, not the body's, and a crawl
//! lags its plan: replayed one by one, 25 of the 56 MuJoCo tours (seeds 0-999) whose
//! fall `runs.csv` filed under walk, run or crouch-walk had a body still down on
//! forearms and knees 1 s before it fell (session 45). This reads it from the body
//! alone, so it says the same for any policy (the model-based gaits or a network).

use std::collections::VecDeque;

use plamo_interfaces::CONTROL_DT;
use plamo_scenes::Scene;

use super::fall_posture::PELVIS_UP;

/// Head height over the ground under it below which the body is down \[m\]: a crawl
/// holds its head at ~0.4 m and the crouch-walk at ~0.85 m.
pub const DOWN_BELOW: f64 = 0.6;
/// How long before the fall the body's earlier state is read \[s\]: a get-up or a
/// get-down takes 1.5-2 s.
pub const EARLIER: f64 = 1.5;
/// How far back before the fall the body's later state is read \[s\]: it is up there
/// if it was not down ([`is_down`]) at some time in it. The fall itself takes the
/// head down through [`DOWN_BELOW`] to the fall rule's bar (0.3 m for a crouch-walk)
/// in less; read at one instant 0.25 s before, most crouch-walk falls read as a body
/// getting down.
pub const LATER: f64 = 0.75;
/// How far back a body upright at both reads counts as just risen when it was down
/// \[s\]: the biped's first steps after a get-up.
pub const RISEN_WITHIN: f64 = 3.0;

/// What the body was doing before a fall, in the order tables show them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum BodyState {
    /// Down ([`is_down`]) at [`EARLIER`] before the fall and all through the [`LATER`]
    /// before it: crawling, kneeling or still in a squat.
    Down,
    /// Down at [`EARLIER`], up within [`LATER`]: getting up.
    Rising,
    /// Up at both reads, but down at some time in the [`RISEN_WITHIN`] before the
    /// fall: the first steps after a get-up.
    Risen,
    /// Up at [`EARLIER`], down all through [`LATER`]: getting down, or sagging slowly.
    Lowering,
    /// Up all through the [`RISEN_WITHIN`] before the fall.
    Upright,
}

impl BodyState {
    /// Every state, in the order tables show them.
    pub const ALL: [BodyState; 5] = [
        Self::Down,
        Self::Rising,
        Self::Risen,
        Self::Lowering,
        Self::Upright,
    ];

    /// The name the experiments write ("rising").
    pub fn name(self) -> &'static str {
        match self {
            Self::Down => "down",
            Self::Rising => "rising",
            Self::Risen => "risen",
            Self::Lowering => "lowering",
            Self::Upright => "upright",
        }
    }

    /// The state named `name` ([`BodyState::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.name() == name)
    }
}

/// Whether the body was down, one sample per control step, over the last
/// [`RISEN_WITHIN`] seconds.
#[derive(Debug, Clone, Default)]
pub struct HeadTrack {
    /// Oldest first.
    down: VecDeque<bool>,
}

/// Control steps in `secs` \[-\].
fn steps(secs: f64) -> usize {
    (secs / CONTROL_DT).round() as usize
}

/// Whether a body with its pelvis at `root` and its head at `head` (world frame) in
/// `scene` is down: its head below [`DOWN_BELOW`] over the ground under it, or its
/// pelvis below [`PELVIS_UP`] over the ground under that (a body rolled onto its back
/// or side may lift its head above [`DOWN_BELOW`]; it is not getting up).
pub fn is_down(scene: &Scene, root: [f64; 3], head: [f64; 3]) -> bool {
    let over = |p: [f64; 3]| p[2] - scene.height_at(p[0], p[1]);
    over(head) < DOWN_BELOW || over(root) < PELVIS_UP
}

impl HeadTrack {
    /// Record one control step's pelvis and head positions (world frame) in `scene`.
    pub fn record(&mut self, scene: &Scene, root: [f64; 3], head: [f64; 3]) {
        if self.down.len() > steps(RISEN_WITHIN) {
            self.down.pop_front();
        }
        self.down.push_back(is_down(scene, root, head));
    }

    /// Forget the samples: after a fall the body is put back on its plan, and what it
    /// did before says nothing about the body that goes on.
    pub fn clear(&mut self) {
        self.down.clear();
    }

    /// What the body was doing before a fall judged in the step recorded last; a
    /// track shorter than a read's distance reads its oldest sample there. `None`
    /// without any sample.
    pub fn state(&self) -> Option<BodyState> {
        let n = self.down.len();
        if n == 0 {
            return None;
        }
        let earlier = self.down[n - steps(EARLIER).clamp(1, n)];
        let later = self.down.range(n - steps(LATER).clamp(1, n)..).all(|&d| d);
        Some(match (earlier, later) {
            (true, true) => BodyState::Down,
            (true, false) => BodyState::Rising,
            (false, true) => BodyState::Lowering,
            (false, false) => {
                let before = n.saturating_sub(steps(EARLIER));
                if self.down.iter().take(before).any(|&d| d) {
                    BodyState::Risen
                } else {
                    BodyState::Upright
                }
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A track of head heights `h(t)` over flat ground, one per control step for
    /// `secs` seconds (t from 0), the pelvis as a body on its limbs or feet holds it
    /// (0.45 m under a crawl's 0.4 m head, 0.95 m under a walk's 1.47 m).
    fn track(secs: f64, h: impl Fn(f64) -> f64) -> HeadTrack {
        track_with(secs, |t| {
            let h = h(t);
            (0.45 + (h - 0.4).max(0.0) * 0.5 / 1.07, h)
        })
    }

    /// A track of (pelvis, head) heights over flat ground.
    fn track_with(secs: f64, body: impl Fn(f64) -> (f64, f64)) -> HeadTrack {
        let flat = plamo_scenes::builtin("playground").expect("built-in scene");
        let (x, y) = (20.0, 20.0);
        let g = flat.height_at(x, y);
        let mut t = HeadTrack::default();
        for k in 0..steps(secs) {
            let (root, head) = body(k as f64 * CONTROL_DT);
            t.record(&flat, [x, y, g + root], [x + 0.3, y, g + head]);
        }
        t
    }

    /// A crouch-walk's 0.85 m head dropping at `rate` \[m/s\] from `start` \[s\].
    fn crouch_dropping(start: f64, rate: f64) -> impl Fn(f64) -> f64 {
        move |t: f64| 0.85 - rate * (t - start).max(0.0)
    }

    /// A get-up from a crawl's 0.4 m to a walk's 1.47 m over 2 s starting at `start`.
    fn get_up(start: f64) -> impl Fn(f64) -> f64 {
        move |t: f64| 0.4 + 1.07 * ((t - start) / 2.0).clamp(0.0, 1.0)
    }

    #[test]
    fn each_state_is_told_from_the_head_heights_before_the_fall() {
        assert_eq!(track(5.0, |_| 0.4).state(), Some(BodyState::Down));
        assert_eq!(track(5.0, |_| 1.47).state(), Some(BodyState::Upright));
        // 1.5 s into a 2 s get-up: down at the earlier read, up at the later.
        assert_eq!(track(5.0, get_up(3.5)).state(), Some(BodyState::Rising));
        // Up for a second after it: still within the risen window.
        assert_eq!(track(5.0, get_up(2.0)).state(), Some(BodyState::Risen));
        // Long after it: upright.
        assert_eq!(track(9.0, get_up(1.0)).state(), Some(BodyState::Upright));
        // A 1.5 s get-down from 1.47 m ending 1 s before the fall.
        let down = |t: f64| 1.47 - 1.07 * ((t - 2.5) / 1.5).clamp(0.0, 1.0);
        assert_eq!(track(5.0, down).state(), Some(BodyState::Lowering));
        // A crouch-walk (head 0.85 m) going over in its last 0.3 s: upright, not
        // getting down, though its head passed below DOWN_BELOW before the fall.
        let over = crouch_dropping(4.7, 2.0);
        assert_eq!(track(5.0, over).state(), Some(BodyState::Upright));
        // The same body sagging from 1.5 s before: getting down.
        let sag = crouch_dropping(3.5, 0.5);
        assert_eq!(track(5.0, sag).state(), Some(BodyState::Lowering));
        // A crawler rolled onto its back lifts its head above DOWN_BELOW for a moment
        // with its pelvis on the ground: still down.
        let rolled = |t: f64| if t < 4.3 { (0.45, 0.4) } else { (0.15, 0.65) };
        assert_eq!(track_with(5.0, rolled).state(), Some(BodyState::Down));
    }

    #[test]
    fn a_short_track_reads_its_oldest_sample_and_an_empty_one_nothing() {
        // 0.5 s of a crawl: both reads fall before the start and read the first sample.
        assert_eq!(track(0.5, |_| 0.4).state(), Some(BodyState::Down));
        assert_eq!(track(1.0, |t| 0.4 + t).state(), Some(BodyState::Rising));
        let mut t = track(5.0, |_| 0.4);
        t.clear();
        assert_eq!(t.state(), None);
    }

    #[test]
    fn the_track_keeps_only_the_risen_window() {
        // Down long ago, upright for the last RISEN_WITHIN + 0.5 s: upright.
        let t = track(10.0, |t| {
            if t < 10.0 - RISEN_WITHIN - 0.5 {
                0.4
            } else {
                1.47
            }
        });
        assert!(t.down.len() <= steps(RISEN_WITHIN) + 1);
        assert_eq!(t.state(), Some(BodyState::Upright));
    }

    #[test]
    fn names_read_back() {
        for s in BodyState::ALL {
            assert_eq!(BodyState::from_name(s.name()), Some(s));
        }
        assert_eq!(BodyState::from_name("sitting"), None);
    }
}
