//! Stage 3: the refiner. Line-of-sight shortcutting of the A* cells (never cheaper
//! than the grid path's cost would allow), uniform resampling, clearance-preserving
//! Laplacian smoothing, then per-point terrain, curvature, head height and speed caps.

use plamo_scenes::Scene;
use serde::{Deserialize, Serialize};

use crate::astar::{CrawlBody, GridPath, SearchLimits, crawl_applies};
use crate::grid::{PlanGrid, crawl_body_clear, edge_cost, too_steep};
use crate::{Locomotion, PlannerSettings};

/// One point of a refined, timed path.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct PathPoint {
    /// World X \[m\].
    pub x: f64,
    /// World Y \[m\].
    pub y: f64,
    /// Terrain height under the point \[m\].
    pub ground: f64,
    /// Head height above the terrain \[m\].
    pub head_height: f64,
    /// Arc length from the path's start \[m\].
    pub s: f64,
    /// Unsigned curvature kappa \[1/m\].
    pub curvature: f64,
    /// Terrain slope along the path \[rad\].
    pub slope: f64,
    /// Speed cap from locomotion, head height and slope (no lateral limit) \[m/s\].
    pub v_cap: f64,
    /// Planned speed \[m/s\].
    pub v: f64,
    /// Planned time of passage, relative to the trajectory start \[s\].
    pub t: f64,
    /// Time held at rest before this point \[s\]: set on the second of two points at
    /// one place (a wait for an obstacle to pass), 0 elsewhere.
    #[serde(default)]
    pub wait: f64,
}

impl PathPoint {
    /// Absolute head height, the z the controller tracks \[m\].
    pub fn head_z(&self) -> f64 {
        self.ground + self.head_height
    }
}

/// What the refiner needs to check a point.
pub(crate) struct RefineCtx<'a> {
    pub scene: &'a Scene,
    pub grid: &'a PlanGrid,
    pub settings: &'a PlannerSettings,
    pub min_head: f32,
    pub limits: &'a SearchLimits,
}

impl RefineCtx<'_> {
    /// A point is usable when its nearest cell is passable (walls inflated by the
    /// character radius, headroom) and outside blocked discs. Clearance holds to within
    /// half a cell diagonal (0.07 m at 0.1 m cells).
    fn point_ok(&self, x: f64, y: f64) -> bool {
        let Some(c) = self.grid.cell_of(x, y) else {
            return false;
        };
        self.grid.passable(c, self.min_head)
            && self
                .limits
                .blocked_discs
                .iter()
                .all(|d| (x - d[0]).powi(2) + (y - d[1]).powi(2) > d[2] * d[2])
    }

    /// Whether a crawling body with its head at (x, y), heading `heading` \[rad\],
    /// clears the walls where the footprint rule applies (see
    /// [`PlannerSettings::crawl_body_length`]).
    fn body_ok(&self, x: f64, y: f64, heading: f64) -> bool {
        let g = self.grid;
        if !g.has_body_limits {
            return true;
        }
        let applies = match self.limits.crawl_body {
            CrawlBody::Off => false,
            CrawlBody::Zone => g.cell_of(x, y).is_some_and(|c| g.crawl_zone[c]),
            CrawlBody::Everywhere => true,
        };
        !applies || crawl_body_clear(self.scene, &g.wall_frames, self.settings, x, y, heading)
    }

    /// Whether the terrain at (x, y), heading `heading` \[rad\], is no steeper than
    /// `max_slope` over half `slope_baseline` behind and ahead, as the grid's edges
    /// (see `PlanGrid::build`).
    fn slope_ok(&self, x: f64, y: f64, heading: f64) -> bool {
        if self.settings.slope_baseline == 0.0 {
            return true;
        }
        let (sin, cos) = heading.sin_cos();
        let half = 0.5 * self.settings.slope_baseline;
        let m = (half / self.grid.resolution).round().max(1.0) as i32;
        let step = half / m as f64;
        let tan_max_slope = self.settings.max_slope.tan();
        // Samples from `k0` to `k1` steps along the heading from (x, y).
        let line = |k0: i32, k1: i32| {
            (k0..=k1).map(move |k| {
                let d = k as f64 * step;
                self.scene.height_at(x + d * cos, y + d * sin)
            })
        };
        !too_steep(tan_max_slope, line(-m, 0), step) && !too_steep(tan_max_slope, line(0, m), step)
    }

    /// Extra cost per metre over uneven ground in cell `c` (see
    /// [`PlannerSettings::crawl_relief_cost`] and `stand_relief_cost`).
    fn relief_at(&self, c: Option<usize>) -> f64 {
        let g = self.grid;
        if !g.has_relief {
            return 0.0;
        }
        let Some(c) = c else {
            return 0.0;
        };
        g.relief_weight(crawl_applies(g, self.limits.crawl_body, c, c)) * g.relief[c] as f64
    }

    /// Cost of the straight segment a-b with the A* edge cost, or `None` if it leaves
    /// the free space, crosses an infeasible slope or turns the crawling body into a
    /// wall.
    fn segment_cost(&self, a: [f64; 2], b: [f64; 2]) -> Option<f64> {
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        let heading = (b[1] - a[1]).atan2(b[0] - a[0]);
        let step = 0.5 * self.grid.resolution;
        let n = (len / step).ceil().max(1.0) as usize;
        let dxy = len / n as f64;
        let mut cost = 0.0;
        let mut h_prev = self.scene.height_at(a[0], a[1]);
        for k in 1..=n {
            let f = k as f64 / n as f64;
            let x = a[0] + (b[0] - a[0]) * f;
            let y = a[1] + (b[1] - a[1]) * f;
            if !self.point_ok(x, y) || !self.body_ok(x, y, heading) || !self.slope_ok(x, y, heading)
            {
                return None;
            }
            let h = self.scene.height_at(x, y);
            cost += edge_cost(self.settings, dxy.max(1e-9), h - h_prev)?;
            let cell = self.grid.cell_of(x, y);
            cost += dxy * self.relief_at(cell);
            if self.grid.has_head_cost
                && let Some(c) = cell
            {
                cost += dxy * self.limits.posture.head_cost(self.grid, c);
            }
            h_prev = h;
        }
        Some(cost)
    }
}

/// Greedy line-of-sight shortcutting: from each anchor jump to the farthest later
/// cell visible from it whose straight cost does not exceed the grid path's cost
/// between them (so a shortcut never cuts over a hill the slope cost avoided).
pub(crate) fn shortcut(ctx: &RefineCtx, pts: &[[f64; 2]], cost_to: &[f64]) -> Vec<[f64; 2]> {
    let last = pts.len() - 1;
    let mut out = vec![pts[0]];
    let mut a = 0;
    while a < last {
        let mut best = a + 1;
        let mut misses = 0;
        for j in a + 2..=last {
            let ok = ctx
                .segment_cost(pts[a], pts[j])
                .is_some_and(|c| c <= (cost_to[j] - cost_to[a]) * 1.02 + 1e-9);
            if ok {
                best = j;
                misses = 0;
            } else {
                misses += 1;
                if misses > 20 {
                    break;
                }
            }
        }
        out.push(pts[best]);
        a = best;
    }
    out
}

/// Points at uniform arc-length spacing (about `ds`) along a polyline, both ends kept.
pub(crate) fn resample(poly: &[[f64; 2]], ds: f64) -> Vec<[f64; 2]> {
    let mut cum = vec![0.0];
    for w in poly.windows(2) {
        let l = ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt();
        cum.push(cum.last().unwrap() + l);
    }
    let total = *cum.last().unwrap();
    if total <= 0.0 {
        return vec![poly[0]];
    }
    let n = (total / ds).ceil().max(1.0) as usize;
    let mut out = Vec::with_capacity(n + 1);
    let mut seg = 0;
    for k in 0..=n {
        let s = total * k as f64 / n as f64;
        while seg + 1 < cum.len() - 1 && cum[seg + 1] < s {
            seg += 1;
        }
        let l = cum[seg + 1] - cum[seg];
        let f = if l > 0.0 {
            ((s - cum[seg]) / l).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (p, q) = (poly[seg], poly[seg + 1]);
        out.push([p[0] + (q[0] - p[0]) * f, p[1] + (q[1] - p[1]) * f]);
    }
    out
}

/// Laplacian smoothing; a move is kept only if the point stays usable and both its
/// segments stay traversable. Ends are fixed.
pub(crate) fn smooth(ctx: &RefineCtx, pts: &mut [[f64; 2]], iterations: usize) {
    let n = pts.len();
    if n < 3 {
        return;
    }
    for _ in 0..iterations {
        for i in 1..n - 1 {
            let p = pts[i];
            let m = [
                0.5 * (pts[i - 1][0] + pts[i + 1][0]),
                0.5 * (pts[i - 1][1] + pts[i + 1][1]),
            ];
            let q = [p[0] + 0.5 * (m[0] - p[0]), p[1] + 0.5 * (m[1] - p[1])];
            let heading = (pts[i + 1][1] - pts[i - 1][1]).atan2(pts[i + 1][0] - pts[i - 1][0]);
            if ctx.point_ok(q[0], q[1])
                && ctx.body_ok(q[0], q[1], heading)
                && ctx.slope_ok(q[0], q[1], heading)
            {
                pts[i] = q;
            }
        }
    }
}

/// Menger curvature of three points \[1/m\].
fn menger(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    let ab = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
    let bc = ((c[0] - b[0]).powi(2) + (c[1] - b[1]).powi(2)).sqrt();
    let ca = ((a[0] - c[0]).powi(2) + (a[1] - c[1]).powi(2)).sqrt();
    let cross = ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
    let d = ab * bc * ca;
    if d <= 1e-12 { 0.0 } else { 2.0 * cross / d }
}

/// Head height allowed by ceilings near (x, y), from the lowest top whose footprint
/// is within the character radius: its height minus `stoop_margin` where that leaves
/// room to stand, else the crouch height where that stays `head_margin` under it,
/// else the crawl height (or less, `head_margin` below a lower top) \[m above
/// terrain\]. A top low enough to crawl under (head below `crawl_switch_height`)
/// counts from `crawl_body_length` away: the get-down (a squat, hands reaching
/// ahead) must be over before the body reaches the top, or the head and shoulders
/// hit its edge. With `crawl_reach_along_path` that distance is left to [`annotate`],
/// which measures it along the path.
pub(crate) fn head_limit(scene: &Scene, s: &PlannerSettings, x: f64, y: f64, ground: f64) -> f64 {
    scene
        .tops
        .iter()
        .filter_map(|t| {
            let headroom = t.z_bottom - ground;
            // The controller keeps its head near the height asked when standing,
            // crouching or crawling, not in between (`stoop_margin`).
            let lim = if headroom - s.stoop_margin >= s.stand_height {
                headroom - s.stoop_margin
            } else if headroom - s.head_margin >= s.crouch_height - 1e-9 {
                s.crouch_height
            } else {
                (headroom - s.head_margin).min(s.crawl_height)
            };
            let reach = if lim < s.crawl_switch_height && !s.crawl_reach_along_path {
                s.crawl_body_length.max(s.character_radius)
            } else {
                s.character_radius
            };
            (t.footprint.signed_distance(x, y) <= reach).then_some(lim)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Largest rise between neighbouring terrain samples within `half` of (x, y) \[m\]:
/// a stair's riser or a bump shows, a smooth slope's rise per cell stays small.
fn step_near(scene: &Scene, x: f64, y: f64, half: f64) -> f64 {
    let t = &scene.terrain;
    let Some((ci, cj)) = t.cell_of(x, y) else {
        return 0.0;
    };
    let k = (half / t.resolution).ceil() as isize;
    let (ci, cj) = (ci as isize, cj as isize);
    let mut step = 0.0f64;
    for j in cj - k..=cj + k {
        for i in ci - k..=ci + k {
            let h = t.sample(i, j);
            step = step
                .max((t.sample(i + 1, j) - h).abs())
                .max((t.sample(i, j + 1) - h).abs());
        }
    }
    step
}

/// Fill terrain, curvature, head height and speed caps for uniformly spaced points.
pub(crate) fn annotate(
    scene: &Scene,
    s: &PlannerSettings,
    form: Locomotion,
    pts: &[[f64; 2]],
) -> Vec<PathPoint> {
    let n = pts.len();
    let mut out: Vec<PathPoint> = Vec::with_capacity(n);
    let mut arc = 0.0;
    for (i, p) in pts.iter().enumerate() {
        if i > 0 {
            let q = pts[i - 1];
            arc += ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
        }
        out.push(PathPoint {
            x: p[0],
            y: p[1],
            ground: scene.height_at(p[0], p[1]),
            s: arc,
            ..Default::default()
        });
    }
    let ds = if n > 1 {
        arc / (n - 1) as f64
    } else {
        s.path_spacing
    };
    let w = ((0.5 * s.curvature_window / ds.max(1e-9)).round() as usize).max(1);
    for i in 0..n {
        if n >= 3 {
            let a = i.saturating_sub(w);
            let c = (i + w).min(n - 1);
            out[i].curvature = if c > a + 1 {
                let b = (a + c) / 2;
                menger(pts[a], pts[b], pts[c])
            } else {
                0.0
            };
        }
        let a = i.saturating_sub(1);
        let c = (i + 1).min(n - 1);
        let dsa = out[c].s - out[a].s;
        out[i].slope = if dsa > 0.0 {
            ((out[c].ground - out[a].ground) / dsa).abs().atan()
        } else {
            0.0
        };
    }
    // Head height: the form's height, capped under ceilings, then limited in rate so
    // the head goes down before a low top and comes back up after it.
    let want = s.head_height(form);
    for p in out.iter_mut() {
        p.head_height = want.min(head_limit(scene, s, p.x, p.y, p.ground));
    }
    if s.crawl_reach_along_path {
        crawl_along_path(s, &mut out);
    }
    for i in 1..n {
        let lim = out[i - 1].head_height + s.head_height_rate * (out[i].s - out[i - 1].s);
        out[i].head_height = out[i].head_height.min(lim);
    }
    for i in (0..n.saturating_sub(1)).rev() {
        let lim = out[i + 1].head_height + s.head_height_rate * (out[i + 1].s - out[i].s);
        out[i].head_height = out[i].head_height.min(lim);
    }
    for p in out.iter_mut() {
        let mut v = s.speed_cap_at_height(form, p.head_height);
        if p.head_height < s.crawl_switch_height {
            v = v.min(s.crawl_speed);
            if p.curvature > 0.0 {
                v = v.min(s.crawl_turn_rate / p.curvature);
            }
        }
        if s.stand_step_speed > 0.0
            && form != Locomotion::Crawl
            && p.head_height >= s.crawl_switch_height
            && step_near(scene, p.x, p.y, s.crawl_half_width) > s.stand_step_height
        {
            v = v.min(s.stand_step_speed);
        }
        p.v_cap = v / (1.0 + s.slope_speed_gain * p.slope.tan());
    }
    // Where the form changes, the body gets down or up nearly on the spot.
    let mut change_from = Vec::new();
    if out
        .first()
        .is_some_and(|p| p.head_height < s.crawl_switch_height)
    {
        change_from.push(0.0);
    }
    for i in 1..n {
        let (a, b) = (out[i - 1].head_height, out[i].head_height);
        let down = a >= s.crawl_switch_height && b < s.crawl_switch_height;
        let up = a <= s.stand_switch_height && b > s.stand_switch_height;
        if down || up {
            change_from.push(out[i].s);
        }
    }
    for s0 in change_from {
        for p in out.iter_mut() {
            if p.s >= s0 && p.s <= s0 + s.form_change_length {
                p.v_cap = p.v_cap.min(s.form_change_speed);
            }
        }
    }
    out
}

/// A crawl under a top starts `crawl_body_length` of path before the head reaches it
/// (the get-down is over before the body gets there) and lasts that long after the
/// head leaves it (the body trails the head): each point takes the lowest crawl limit
/// within that arc length. A path that only passes near a low top, or ends at a
/// landmark beside one, keeps its form.
fn crawl_along_path(s: &PlannerSettings, out: &mut [PathPoint]) {
    let crawls: Vec<(f64, f64)> = out
        .iter()
        .filter(|p| p.head_height < s.crawl_switch_height)
        .map(|p| (p.s, p.head_height))
        .collect();
    if crawls.is_empty() {
        return;
    }
    for p in out.iter_mut() {
        let lo = crawls.partition_point(|c| c.0 < p.s - s.crawl_body_length);
        for &(_, h) in crawls[lo..]
            .iter()
            .take_while(|c| c.0 <= p.s + s.crawl_body_length)
        {
            p.head_height = p.head_height.min(h);
        }
    }
}

/// Refine an A* path into uniformly spaced, annotated points. `start` replaces the
/// first cell centre when it is usable (the character's exact position).
pub(crate) fn refine(
    ctx: &RefineCtx,
    form: Locomotion,
    path: &GridPath,
    start: Option<[f64; 2]>,
) -> Vec<PathPoint> {
    let mut pts: Vec<[f64; 2]> = path.cells.iter().map(|&c| ctx.grid.position(c)).collect();
    if let Some(p) = start
        && ctx.point_ok(p[0], p[1])
    {
        pts[0] = p;
    }
    let poly = if pts.len() > 2 {
        shortcut(ctx, &pts, &path.cost_to)
    } else {
        pts
    };
    let ds = ctx.settings.path_spacing;
    let mut dense = if poly.len() == 1 {
        poly
    } else {
        resample(&poly, ds)
    };
    smooth(ctx, &mut dense, ctx.settings.smoothing_iterations);
    let dense = if dense.len() > 1 {
        resample(&dense, ds)
    } else {
        dense
    };
    annotate(ctx.scene, ctx.settings, form, &dense)
}
