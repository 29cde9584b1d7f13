//! Where a fallen humanoid is put back (the reset request of the control phase).
//!
//! A reset goes **on the plan**: where the humanoid lies if that is within
//! [`ON_PLAN`] of its plan (or of the plan's line behind its first waypoint: a body
//! that lags is on its plan) and clear, else the nearest point of the plan's waypoint
//! polyline (the next 5 s) whose place is clear, searching ahead along the plan,
//! then back. **Clear** means the body's footprint in that form keeps
//! [`WALL_MARGIN`] from every wall, stays on the terrain, and fits under every top
//! over it. The **form** is the plan's there: on hands and knees where the plan's
//! head height asks for a crawl ([`Posture::for_head_height`]) or where a top leaves
//! no room to stand, standing otherwise (the controller crouches from there). The
//! humanoid **faces along the plan** (its current heading where the plan does not
//! move).
//!
//! **No loops.** A humanoid that falls again within [`SAME_SPOT`] of where a series of
//! falls began is reset [`ADVANCE`] further along its plan per repeat, so a place it
//! cannot get past (a step it trips on, a get-down it cannot make) is left behind
//! after a few falls instead of hundreds; every fall still counts in the metrics. The
//! run is not ended: it may still reach its landmarks, and the fall count already
//! marks the tour as failed.
//!
//! Moving obstacles are not avoided (they move on within a second). Everything here
//! reads the interface messages and the scene only, so in-process and multi-process
//! runs reset identically.

use plamo_interfaces::{HumanoidState, PlanMessage, RESET_CRAWL, RESET_STAND, ResetPose};
use plamo_physics::Posture;
use plamo_physics::humanoid::STANDING_HEAD_HEIGHT;
use plamo_scenes::Scene;

/// Farthest the root may be from its plan for a reset where it lies \[m\].
pub(crate) const ON_PLAN: f64 = 0.5;
/// Step of the search along the plan for a clear place \[m\].
const SEARCH_STEP: f64 = 0.1;
/// A fall within this distance of the fall that began a series counts as one more
/// at the same spot \[m\].
pub(crate) const SAME_SPOT: f64 = 1.5;
/// How much further along the plan each repeated fall at the same spot puts the
/// reset \[m\].
pub(crate) const ADVANCE: f64 = 0.5;
/// Clearance a reset body keeps from walls \[m\].
const WALL_MARGIN: f64 = 0.05;
/// Free height a standing body needs \[m\]: the head's top (1.57 m) and a margin.
const STAND_HEADROOM: f64 = STANDING_HEAD_HEIGHT + 0.15;
/// Free height the crawl pose needs \[m\]: its back is ~0.56 m up (the planner keeps
/// crawls under tops of at least 0.6 m).
const CRAWL_HEADROOM: f64 = 0.58;
/// Radius of a standing body's footprint around the root \[m\].
const STAND_RADIUS: f64 = 0.3;
/// The crawl pose's footprint, heading frame: from the feet behind the root to the
/// head in front, and half its width \[m\] (`HumanoidPose::crawling_on`).
const CRAWL_BACK: f64 = 0.42;
const CRAWL_FRONT: f64 = 0.6;
const CRAWL_HALF_WIDTH: f64 = 0.3;
/// How far the crawl pose's head is ahead of its root \[m\]: a crawl reset onto a plan
/// point puts the head there.
const CRAWL_HEAD_AHEAD: f64 = 0.49;
/// How far inside the terrain's edge a reset that finds no clear place on the plan
/// puts the root \[m\]: the crawl pose's footprint reaches 0.67 m from its root at any
/// heading. Put back on the edge itself, a crawl that had wandered off the terrain
/// slid off again within 0.6 s, 129 times (a crawl-only tour, RESULTS "Crawl",
/// session 20).
const EDGE_MARGIN: f64 = 0.7;

/// One agent's reset history: the series of falls at one spot.
#[derive(Debug, Clone, Default)]
pub(crate) struct Recovery {
    /// Root XY of the fall that began the current series.
    anchor: Option<[f64; 2]>,
    /// Falls after that one within [`SAME_SPOT`] of it.
    repeats: u32,
}

/// The plan's waypoint polyline with arc lengths.
struct Polyline {
    /// (x, y, head height above the ground) per waypoint.
    points: Vec<[f64; 3]>,
    /// Arc length at each point \[m\].
    s: Vec<f64>,
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn heading(q: [f64; 4]) -> f64 {
    // Message quaternion (x, y, z, w): yaw of the rotated +X axis.
    let [x, y, z, w] = q;
    (2.0 * (x * y + w * z)).atan2(1.0 - 2.0 * (y * y + z * z))
}

impl Polyline {
    fn new(scene: &Scene, plan: &PlanMessage) -> Self {
        let points: Vec<[f64; 3]> = plan
            .waypoints
            .iter()
            .map(|w| {
                let [x, y, z] = w.position;
                [x, y, z - scene.height_at(x, y)]
            })
            .collect();
        let mut s = vec![0.0];
        for p in points.windows(2) {
            let last = s[s.len() - 1];
            s.push(last + dist([p[0][0], p[0][1]], [p[1][0], p[1][1]]));
        }
        Self { points, s }
    }

    fn length(&self) -> f64 {
        self.s[self.s.len() - 1]
    }

    /// Arc length of the point nearest to `p`, and its distance \[m\]. The first
    /// segment reaches back without end: the waypoints start 0.5 s ahead of the
    /// plan's "now", and a body that lags on the plan's line is on the plan (its arc
    /// length is then negative).
    fn nearest(&self, p: [f64; 2]) -> (f64, f64) {
        let mut best = (0.0, dist(p, [self.points[0][0], self.points[0][1]]));
        for i in 0..self.points.len() - 1 {
            let (a, b) = (self.points[i], self.points[i + 1]);
            let d = [b[0] - a[0], b[1] - a[1]];
            let len2 = d[0] * d[0] + d[1] * d[1];
            let t = if len2 > 0.0 {
                let t = ((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / len2;
                t.clamp(if i == 0 { f64::NEG_INFINITY } else { 0.0 }, 1.0)
            } else {
                0.0
            };
            let q = [a[0] + t * d[0], a[1] + t * d[1]];
            let e = dist(p, q);
            if e < best.1 {
                best = (self.s[i] + t * (self.s[i + 1] - self.s[i]), e);
            }
        }
        best
    }

    /// The point at arc length `s`: (x, y), head height above the ground, and the
    /// plan's direction there (`None` where the plan does not move).
    fn at(&self, s: f64) -> ([f64; 2], f64, Option<f64>) {
        let n = self.points.len();
        let i = (0..n - 1)
            .find(|&i| s <= self.s[i + 1])
            .unwrap_or(n.saturating_sub(2));
        let (a, b) = (self.points[i], self.points[(i + 1).min(n - 1)]);
        let len = self.s[(i + 1).min(n - 1)] - self.s[i];
        let t = if len > 0.0 {
            ((s - self.s[i]) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let xy = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
        let h = a[2] + t * (b[2] - a[2]);
        // The direction of the first moving segment from here on, else the last
        // moving one before.
        let moving = |k: usize| self.s[k + 1] - self.s[k] > 1e-3;
        let dir_of = |k: usize| {
            let (p, q) = (self.points[k], self.points[k + 1]);
            (q[1] - p[1]).atan2(q[0] - p[0])
        };
        let dir = (i..n - 1)
            .find(|&k| moving(k))
            .or_else(|| (0..i).rev().find(|&k| moving(k)))
            .map(dir_of);
        (xy, h, dir)
    }
}

/// Whether the body fits at root (x, y) with heading `yaw` in `form`.
fn clear(scene: &Scene, x: f64, y: f64, yaw: f64, form: u32) -> bool {
    let (sin, cos) = yaw.sin_cos();
    let to_world = |f: f64, l: f64| [x + cos * f - sin * l, y + sin * f + cos * l];
    let (samples, headroom): (Vec<[f64; 2]>, f64) = if form == RESET_CRAWL {
        let along = [-CRAWL_BACK, -0.1, 0.2, CRAWL_FRONT];
        let across = [-CRAWL_HALF_WIDTH, 0.0, CRAWL_HALF_WIDTH];
        (
            along
                .iter()
                .flat_map(|&f| across.iter().map(move |&l| (f, l)))
                .map(|(f, l)| to_world(f, l))
                .collect(),
            CRAWL_HEADROOM,
        )
    } else {
        let ring = (0..8).map(|k| {
            let a = k as f64 * std::f64::consts::FRAC_PI_4;
            to_world(STAND_RADIUS * a.cos(), STAND_RADIUS * a.sin())
        });
        (
            std::iter::once([x, y]).chain(ring).collect(),
            STAND_HEADROOM,
        )
    };
    samples.iter().all(|&[px, py]| {
        scene.terrain.contains(px, py)
            && scene.wall_clearance(px, py) > WALL_MARGIN
            && scene.headroom_at(px, py).is_none_or(|h| h >= headroom)
    })
}

/// Whether a standing body fits with its root at (x, y): on the terrain, clear of
/// walls, and under every top with room to stand.
pub(crate) fn stands_clear(scene: &Scene, x: f64, y: f64) -> bool {
    clear(scene, x, y, 0.0, RESET_STAND)
}

/// The form and root place for a plan point: a crawl puts its head on the point.
/// Standing where the plan stands unless a top leaves no room; `None` if neither
/// form fits.
fn place(scene: &Scene, xy: [f64; 2], h: f64, yaw: f64, at_root: bool) -> Option<(u32, [f64; 2])> {
    let crawl_root = if at_root {
        xy
    } else {
        [
            xy[0] - CRAWL_HEAD_AHEAD * yaw.cos(),
            xy[1] - CRAWL_HEAD_AHEAD * yaw.sin(),
        ]
    };
    let crawl = clear(scene, crawl_root[0], crawl_root[1], yaw, RESET_CRAWL)
        .then_some((RESET_CRAWL, crawl_root));
    if Posture::for_head_height(h) == Posture::Crawl {
        return crawl;
    }
    if clear(scene, xy[0], xy[1], yaw, RESET_STAND) {
        return Some((RESET_STAND, xy));
    }
    // Only a top may turn a standing plan into a crawl; next to a wall the crawl's
    // longer body fits no better, and the plan's form is kept elsewhere.
    let under_top = scene
        .headroom_near(xy[0], xy[1], STAND_RADIUS)
        .is_some_and(|r| r < STAND_HEADROOM);
    crawl.filter(|_| under_top)
}

impl Recovery {
    /// The reset pose for a humanoid found fallen in state `s` with plan `plan`, and
    /// the bookkeeping of falls at one spot (see the module docs).
    pub(crate) fn reset_pose(
        &mut self,
        scene: &Scene,
        s: &HumanoidState,
        plan: &PlanMessage,
    ) -> ResetPose {
        let root = [s.root_position[0], s.root_position[1]];
        match self.anchor {
            Some(a) if dist(a, root) < SAME_SPOT => self.repeats += 1,
            _ => {
                self.anchor = Some(root);
                self.repeats = 0;
            }
        }
        let own = heading(s.root_orientation);
        let own = if own.is_finite() { own } else { 0.0 };
        let line = Polyline::new(scene, plan);
        let (near, off) = line.nearest(root);
        let pose = |(form, p): (u32, [f64; 2]), yaw: f64| ResetPose {
            position: p,
            yaw,
            form,
            reserved: 0,
        };
        if self.repeats == 0 && off < ON_PLAN {
            let (_, h, dir) = line.at(near.max(0.0));
            let yaw = dir.unwrap_or(own);
            if let Some(p) = place(scene, root, h, yaw, true) {
                return pose(p, yaw);
            }
        }
        let start = (near.max(0.0) + ADVANCE * self.repeats as f64).min(line.length());
        let steps = (line.length() / SEARCH_STEP).ceil() as usize + 1;
        let ahead = (0..steps).map(|k| start + k as f64 * SEARCH_STEP);
        let back = (1..steps).map(|k| start - k as f64 * SEARCH_STEP);
        for at in ahead
            .take_while(|&a| a <= line.length() + 1e-9)
            .chain(back.take_while(|&a| a >= 0.0))
        {
            let (xy, h, dir) = line.at(at);
            let yaw = dir.unwrap_or(own);
            if let Some(p) = place(scene, xy, h, yaw, false) {
                return pose(p, yaw);
            }
        }
        // Nowhere on the plan is clear (a plan squeezed past a wall corner, or off the
        // terrain): where it lies, inside the terrain, in the plan's form.
        let (lo, hi) = scene.terrain.bounds();
        let inside = |v: f64, lo: f64, hi: f64| {
            if hi - lo > 2.0 * EDGE_MARGIN {
                v.clamp(lo + EDGE_MARGIN, hi - EDGE_MARGIN)
            } else {
                0.5 * (lo + hi)
            }
        };
        let xy = [inside(root[0], lo[0], hi[0]), inside(root[1], lo[1], hi[1])];
        let (_, h, dir) = line.at(near.max(0.0));
        let form = if Posture::for_head_height(h) == Posture::Crawl
            || scene
                .headroom_at(xy[0], xy[1])
                .is_some_and(|r| r < STAND_HEADROOM)
        {
            RESET_CRAWL
        } else {
            RESET_STAND
        };
        pose((form, xy), dir.unwrap_or(own))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plamo_interfaces::PlanWaypoint;
    use std::f64::consts::{FRAC_PI_2, PI};

    /// Flat 20 x 10 m ground at z 0.3, a wall along y 5.2..5.5 from x 2 to 18, and a
    /// 0.6 m top over x 12..16.
    fn scene() -> Scene {
        plamo_scenes::from_toml_str(
            r#"
name = "recover"
description = ""
[terrain]
size = [20.0, 10.0]
[[terrain.tiles]]
generator = { kind = "flat", height = 0.3 }
[[walls]]
name = "wall"
center = [10.0, 5.35]
size = [16.0, 0.3]
height = 2.0
[[tops]]
name = "top"
center = [14.0, 2.0]
size = [4.0, 3.0]
clearance = 0.6
thickness = 0.2
[[landmarks]]
name = "a"
region = { kind = "circle", center = [1.0, 2.0], radius = 0.5 }
"#,
            "recover test",
        )
        .unwrap()
    }

    /// A plan along +X at `y` from `x0`, 0.5 m apart, head `h` above the ground.
    fn plan(x0: f64, y: f64, h: f64) -> PlanMessage {
        let mut p = PlanMessage {
            form_height: h,
            ..Default::default()
        };
        for (i, w) in p.waypoints.iter_mut().enumerate() {
            *w = PlanWaypoint {
                position: [x0 + 0.5 * i as f64, y, 0.3 + h],
                speed: 1.0,
            };
        }
        p
    }

    fn lying(x: f64, y: f64, yaw: f64) -> HumanoidState {
        HumanoidState {
            root_position: [x, y, 0.45],
            root_orientation: [0.0, 0.0, (0.5 * yaw).sin(), (0.5 * yaw).cos()],
            ..Default::default()
        }
    }

    #[test]
    fn a_body_off_the_terrain_with_no_clear_plan_is_put_back_inside_its_edge() {
        let scene = scene();
        let mut r = Recovery::default();
        // Crawled off the terrain's edge (y < 0), its plan off the terrain too: the
        // fallback puts it inside, far enough for the crawl pose to lie on the terrain.
        let s = lying(8.0, -0.3, -FRAC_PI_2);
        let p = r.reset_pose(&scene, &s, &plan(8.0, -1.0, 0.4));
        assert_eq!(p.form, RESET_CRAWL);
        assert!(p.position[1] >= EDGE_MARGIN - 1e-9, "{:?}", p.position);
        for yaw in [0.0, FRAC_PI_2, PI, -FRAC_PI_2] {
            assert!(
                clear(&scene, p.position[0], p.position[1], yaw, RESET_CRAWL),
                "{:?} yaw {yaw}",
                p.position
            );
        }
    }

    #[test]
    fn a_clear_fall_on_the_plan_resets_where_it_lies_facing_along_the_plan() {
        let scene = scene();
        let mut r = Recovery::default();
        // Lagging 1 m behind the plan's first waypoint on its line, facing sideways.
        let p = r.reset_pose(&scene, &lying(5.0, 2.1, 1.5), &plan(6.0, 2.0, 1.47));
        assert_eq!((p.form, p.position), (RESET_STAND, [5.0, 2.1]));
        assert!(p.yaw.abs() < 1e-9, "{}", p.yaw);
        // The plan crawls there: on hands and knees.
        let mut r = Recovery::default();
        let p = r.reset_pose(&scene, &lying(5.0, 2.1, 0.0), &plan(6.0, 2.0, 0.4));
        assert_eq!((p.form, p.position), (RESET_CRAWL, [5.0, 2.1]));
    }

    #[test]
    fn a_fall_against_a_wall_resets_on_the_plan_clear_of_it() {
        let scene = scene();
        let mut r = Recovery::default();
        // Fell sideways against the wall, 0.8 m off a plan that keeps 0.7 m from it.
        let s = lying(6.0, 5.0, 0.0);
        let p = r.reset_pose(&scene, &s, &plan(6.0, 4.3, 1.47));
        assert_eq!(p.form, RESET_STAND);
        assert!((p.position[1] - 4.3).abs() < 1e-9, "{:?}", p.position);
        assert!(clear(
            &scene,
            p.position[0],
            p.position[1],
            p.yaw,
            RESET_STAND
        ));
        assert!(!clear(&scene, 6.0, 5.0, 0.0, RESET_STAND));
        // A crawl's longer body keeps clear too: facing along the wall it fits where a
        // crawl across the wall's line would not.
        assert!(clear(&scene, 6.0, 4.6, 0.0, RESET_CRAWL));
        assert!(!clear(&scene, 6.0, 4.6, FRAC_PI_2, RESET_CRAWL));
    }

    #[test]
    fn a_top_overhead_resets_on_hands_and_knees_even_on_a_standing_plan() {
        let scene = scene();
        let mut r = Recovery::default();
        // Under the 0.6 m top with a plan whose height already rose to standing.
        let p = r.reset_pose(&scene, &lying(14.0, 2.0, 0.0), &plan(14.2, 2.0, 1.47));
        assert_eq!(p.form, RESET_CRAWL);
        assert!(clear(
            &scene,
            p.position[0],
            p.position[1],
            p.yaw,
            RESET_CRAWL
        ));
        assert!(!clear(&scene, 14.0, 2.0, 0.0, RESET_STAND));
    }

    #[test]
    fn repeated_falls_at_one_spot_move_the_reset_along_the_plan() {
        let scene = scene();
        let mut r = Recovery::default();
        let pl = plan(3.0, 2.0, 1.47);
        let mut xs = vec![];
        for _ in 0..4 {
            // It keeps falling at x 3.2, each time 0.4 m past its last reset at most.
            xs.push(r.reset_pose(&scene, &lying(3.2, 2.0, 0.0), &pl).position[0]);
        }
        assert_eq!(xs[0], 3.2);
        for (k, x) in xs.iter().enumerate().skip(1) {
            assert!((x - (3.2 + ADVANCE * k as f64)).abs() < 1e-9, "{xs:?}");
        }
        // A fall elsewhere begins a new series: where it lies again.
        let far = 3.2 + SAME_SPOT + 0.1;
        let p = r.reset_pose(&scene, &lying(far, 2.0, 0.0), &plan(far, 2.0, 1.47));
        assert_eq!(p.position[0], far);
    }

    #[test]
    fn the_same_fall_gives_the_same_reset() {
        let scene = scene();
        let s = lying(6.3, 4.9, 0.4);
        let pl = plan(6.0, 4.3, 0.4);
        let a = Recovery::default().reset_pose(&scene, &s, &pl);
        let b = Recovery::default().reset_pose(&scene, &s, &pl);
        assert_eq!(a, b);
        let bits = |p: &ResetPose| {
            [
                p.position[0].to_bits(),
                p.position[1].to_bits(),
                p.yaw.to_bits(),
            ]
        };
        assert_eq!(bits(&a), bits(&b));
    }
}
