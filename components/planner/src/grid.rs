//! The planning grid: terrain samples (every `grid_stride`-th), wall clearance,
//! headroom, and precomputed 8-connected edge costs (all eight of a cell side by side,
//! so a search reads one cache line per expanded cell).

use plamo_scenes::{FootprintFrame, Scene};

use crate::PlannerSettings;

/// Offsets of the 8 neighbours; `DIRS[d + 4]` is the opposite of `DIRS[d]`.
pub(crate) const DIRS: [(isize, isize); 8] = [
    (1, 0),
    (0, 1),
    (1, 1),
    (-1, 1),
    (-1, 0),
    (0, -1),
    (-1, -1),
    (1, -1),
];

/// The 8-connected planning graph over the terrain.
#[derive(Debug, Clone)]
pub struct PlanGrid {
    /// World XY of cell (0, 0) \[m\].
    pub origin: [f64; 2],
    /// Cell size \[m\].
    pub resolution: f64,
    /// Cells along X.
    pub nx: usize,
    /// Cells along Y.
    pub ny: usize,
    /// Terrain height per cell \[m\].
    pub height: Vec<f64>,
    /// Headroom (ceiling minus terrain) per cell, `f32::INFINITY` under open sky \[m\].
    pub headroom: Vec<f32>,
    /// Whether the cell is clear of walls by at least the character radius.
    pub free: Vec<bool>,
    /// Whether any cell has a ceiling (lets searches skip headroom checks).
    pub has_tops: bool,
    /// Per cell, bit `d` set when the crawling body (head here, heading `DIRS[d]`,
    /// `crawl_body_length` behind the head, `crawl_half_width` each side) clears
    /// every wall; all bits set far from walls.
    pub body_fits: Vec<u8>,
    /// Cells where the character crawls whatever its leg's form: under a top that
    /// puts the head below `crawl_switch_height`, or within `crawl_body_length` of
    /// one.
    pub crawl_zone: Vec<bool>,
    /// The scene's walls with their rotations worked out, for footprint checks.
    pub wall_frames: Vec<FootprintFrame>,
    /// Whether any cell's `body_fits` is not all set (lets searches skip the check).
    pub has_body_limits: bool,
    /// Relief under a body per cell, crawling or not: highest minus lowest terrain
    /// within `crawl_half_width` + one cell (a square) \[m\].
    pub relief: Vec<f32>,
    /// Whether any cell has relief (lets searches skip the cost).
    pub has_relief: bool,
    /// `PlannerSettings::crawl_relief_cost` \[1/m\].
    pub relief_cost: f64,
    /// `PlannerSettings::stand_relief_cost` \[1/m\].
    pub stand_relief_cost: f64,
    /// Extra cost per metre of path \[1\] where a top makes a leg lower its head
    /// below its form's (`PlannerSettings::crawl_zone_cost`, `stoop_zone_cost`),
    /// by [`Posture`](crate::Posture): index 0 a crouch-walk leg, 1 a standing
    /// one. Empty when both costs are off.
    pub head_cost: [Vec<f32>; 2],
    /// Whether any cell has a `head_cost` (lets searches skip it).
    pub has_head_cost: bool,
    /// Edge cost per cell and direction `DIRS[d]`, `INFINITY` when the edge is off
    /// the grid or removed (wall, corner cut, infeasible slope) \[m\].
    pub edges: Vec<[f32; 8]>,
    /// Lower bound on an edge's cost per metre of height change on top of its 3D
    /// length: `height_cost + slope_preference_c` (the preference term
    /// `dxy * (e^(c * slope) - 1)` is at least `c * |dh|`) \[1\].
    pub climb_cost_lower_bound: f64,
}

/// Whether terrain sampled `step` \[m\] apart along a line (`heights`, half
/// `slope_baseline` long) is steeper than `max_slope` (`tan_max_slope` = its tangent)
/// once its largest single step is taken out: a stair's riser or a ledge (which the
/// per-edge rule lets through up to `max_step_height`) between level ground leaves
/// the window level, a hillside that rises at every sample does not. Fewer than three
/// samples are never too steep (the per-edge rule alone judges them).
#[inline]
pub(crate) fn too_steep(tan_max_slope: f64, heights: impl Iterator<Item = f64>, step: f64) -> bool {
    let (mut first, mut last, mut n) = (0.0, 0.0, 0usize);
    let (mut up, mut down) = (0.0f64, 0.0f64);
    for h in heights {
        if n == 0 {
            first = h;
        } else {
            up = up.max(h - last);
            down = down.min(h - last);
        }
        last = h;
        n += 1;
    }
    if n < 3 {
        return false;
    }
    let rise = last - first;
    let rest = if rise >= 0.0 { rise - up } else { rise - down };
    rest.abs() > tan_max_slope * (n - 2) as f64 * step
}

/// Cost of one edge: 3D length + height cost + terrain preference (paper 5.2).
/// `None` when the slope is infeasible.
pub(crate) fn edge_cost(s: &PlannerSettings, dxy: f64, dh: f64) -> Option<f64> {
    edge_cost_with(s, s.max_slope.tan(), dxy, dh)
}

/// [`edge_cost`] with `tan(max_slope)` computed once by the caller.
#[inline]
fn edge_cost_with(s: &PlannerSettings, tan_max_slope: f64, dxy: f64, dh: f64) -> Option<f64> {
    let adh = dh.abs();
    let slope = adh / dxy;
    if slope > tan_max_slope && adh > s.max_step_height {
        return None;
    }
    let len = (dxy * dxy + dh * dh).sqrt();
    let pref = if s.slope_preference_c == 0.0 {
        0.0
    } else {
        dxy * ((s.slope_preference_c * slope).exp() - 1.0)
    };
    Some(len + s.height_cost * adh + pref)
}

/// Whether a crawling body with its head at (x, y) and heading `heading` \[rad\]
/// clears every wall of `scene` by `crawl_half_width`, and so does the line it is
/// about to crawl along: samples every 0.1 m from `crawl_body_length` ahead of the
/// head to `crawl_body_length` behind it. The line ahead makes a path enter a narrow
/// gap on a straight lead-in a body long, so a crawler that tracks its path to a
/// few decimetres is lined up with the gap before its head reaches it.
/// `walls` are the scene's walls' [`FootprintFrame`]s ([`PlanGrid::wall_frames`]).
pub(crate) fn crawl_body_clear(
    scene: &Scene,
    walls: &[FootprintFrame],
    s: &PlannerSettings,
    x: f64,
    y: f64,
    heading: f64,
) -> bool {
    let (sin, cos) = heading.sin_cos();
    let w = s.crawl_half_width;
    let n = ((2.0 * s.crawl_body_length) / 0.1).ceil().max(1.0) as usize;
    let t = &scene.terrain;
    let lo = [t.origin[0] + w, t.origin[1] + w];
    let hi = [
        t.origin[0] + (t.nx - 1) as f64 * t.resolution - w,
        t.origin[1] + (t.ny - 1) as f64 * t.resolution - w,
    ];
    let point = |k: usize| {
        let back = s.crawl_body_length * (2.0 * k as f64 / n as f64 - 1.0);
        (x - back * cos, y - back * sin)
    };
    // The terrain's edge is a drop: a body over it falls off the world.
    (0..=n).all(|k| {
        let (px, py) = point(k);
        (lo[0]..=hi[0]).contains(&px) && (lo[1]..=hi[1]).contains(&py)
    }) && walls
        .iter()
        // Most walls are further than a body length away: one bound each, not a
        // distance per point (the refiner asks this at every sample of a crawl).
        .filter(|wall| !wall.clear_of_disc(x, y, s.crawl_body_length, w))
        .all(|wall| {
            (0..=n).all(|k| {
                let (px, py) = point(k);
                wall.signed_distance(px, py) >= w
            })
        })
}

/// Clear `free` (a grid of `nx` x `ny` cells `res` apart from `t`'s origin) within
/// `cliff_clearance` of every cliff of `t`: the midpoint of two neighbouring terrain
/// samples whose heights differ by more than `max_step_height`.
fn keep_off_cliffs(
    t: &plamo_scenes::HeightGrid,
    s: &PlannerSettings,
    free: &mut [bool],
    [nx, ny]: [usize; 2],
    res: f64,
) {
    let r = s.cliff_clearance;
    let reach = (r / res).ceil() as isize;
    let h = |i: usize, j: usize| t.heights[j * t.nx + i];
    for j in 0..t.ny {
        for i in 0..t.nx {
            for (di, dj) in [(1, 0), (0, 1)] {
                let (i2, j2) = (i + di, j + dj);
                if i2 >= t.nx || j2 >= t.ny || (h(i2, j2) - h(i, j)).abs() <= s.max_step_height {
                    continue;
                }
                let mx = t.origin[0] + (i as f64 + 0.5 * di as f64) * t.resolution;
                let my = t.origin[1] + (j as f64 + 0.5 * dj as f64) * t.resolution;
                let ci = ((mx - t.origin[0]) / res).round() as isize;
                let cj = ((my - t.origin[1]) / res).round() as isize;
                for gj in (cj - reach).max(0)..=(cj + reach).min(ny as isize - 1) {
                    for gi in (ci - reach).max(0)..=(ci + reach).min(nx as isize - 1) {
                        let x = t.origin[0] + gi as f64 * res;
                        let y = t.origin[1] + gj as f64 * res;
                        if (x - mx).hypot(y - my) < r {
                            free[gj as usize * nx + gi as usize] = false;
                        }
                    }
                }
            }
        }
    }
}

impl PlanGrid {
    /// Extra cost per metre per metre of relief \[1/m\]: `crawl_relief_cost` where the
    /// character crawls, `stand_relief_cost` where it does not.
    #[inline]
    pub(crate) fn relief_weight(&self, crawled: bool) -> f64 {
        if crawled {
            self.relief_cost
        } else {
            self.stand_relief_cost
        }
    }

    /// Build the grid for a scene.
    pub fn build(scene: &Scene, s: &PlannerSettings) -> Self {
        let t = &scene.terrain;
        let k = s.grid_stride;
        let nx = (t.nx - 1) / k + 1;
        let ny = (t.ny - 1) / k + 1;
        let res = t.resolution * k as f64;
        let n = nx * ny;
        let mut height = vec![0.0; n];
        for j in 0..ny {
            for i in 0..nx {
                height[j * nx + i] = t.heights[(j * k) * t.nx + i * k];
            }
        }
        let origin = t.origin;
        let pos = |i: usize, j: usize| [origin[0] + i as f64 * res, origin[1] + j as f64 * res];
        // Cells covered by an axis-aligned box, clamped to the grid.
        let cover = |lo: [f64; 2], hi: [f64; 2]| {
            let i0 = ((lo[0] - origin[0]) / res).floor().max(0.0) as usize;
            let j0 = ((lo[1] - origin[1]) / res).floor().max(0.0) as usize;
            let i1 = (((hi[0] - origin[0]) / res).ceil().max(0.0) as usize).min(nx - 1);
            let j1 = (((hi[1] - origin[1]) / res).ceil().max(0.0) as usize).min(ny - 1);
            (i0, j0, i1, j1)
        };
        let r = s.character_radius;
        let mut free = vec![true; n];
        for w in &scene.walls {
            let (lo, hi) = w.footprint.aabb();
            let (i0, j0, i1, j1) = cover([lo[0] - r, lo[1] - r], [hi[0] + r, hi[1] + r]);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let [x, y] = pos(i, j);
                    if w.footprint.signed_distance(x, y) < r {
                        free[j * nx + i] = false;
                    }
                }
            }
        }
        if s.cliff_clearance > 0.0 {
            keep_off_cliffs(t, s, &mut free, [nx, ny], res);
        }
        let mut headroom = vec![f32::INFINITY; n];
        for top in &scene.tops {
            let (lo, hi) = top.footprint.aabb();
            let (i0, j0, i1, j1) = cover(lo, hi);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let [x, y] = pos(i, j);
                    if top.footprint.contains(x, y) {
                        let c = j * nx + i;
                        let hr = (top.z_bottom - height[c]) as f32;
                        headroom[c] = headroom[c].min(hr);
                    }
                }
            }
        }
        let wall_frames: Vec<FootprintFrame> =
            scene.walls.iter().map(|w| w.footprint.frame()).collect();
        let mut body_fits = vec![u8::MAX; n];
        let reach = s.crawl_body_length + 2.0 * s.crawl_half_width;
        let body_bits = |x: f64, y: f64| {
            let mut bits = 0u8;
            for (d, &(di, dj)) in DIRS.iter().enumerate() {
                if crawl_body_clear(scene, &wall_frames, s, x, y, (dj as f64).atan2(di as f64)) {
                    bits |= 1 << d;
                }
            }
            bits
        };
        // Near the terrain's edge and near walls.
        let edge = (reach / res).ceil() as usize;
        for j in 0..ny {
            for i in 0..nx {
                let c = j * nx + i;
                if free[c] && (i < edge || j < edge || i + edge >= nx || j + edge >= ny) {
                    let [x, y] = pos(i, j);
                    body_fits[c] = body_bits(x, y);
                }
            }
        }
        for w in &scene.walls {
            let (lo, hi) = w.footprint.aabb();
            let (i0, j0, i1, j1) = cover(
                [lo[0] - reach, lo[1] - reach],
                [hi[0] + reach, hi[1] + reach],
            );
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let c = j * nx + i;
                    if !free[c] || body_fits[c] != u8::MAX {
                        continue;
                    }
                    let [x, y] = pos(i, j);
                    body_fits[c] = body_bits(x, y);
                }
            }
        }
        let has_body_limits = body_fits.iter().any(|&b| b != u8::MAX);
        // A head limited below the crawl switch means crawling, and the body trails
        // the head by its length.
        let crawl_head = (s.crawl_switch_height + s.head_margin) as f32;
        // Cells within `radius` of a cell whose headroom is below `below`. The
        // nearest such cell to a cell outside them has a side neighbour outside them
        // (a step from any other towards the cell comes closer), so only those cells'
        // discs are drawn: a top's rim, not its whole area.
        let near_tops = |below: f32, radius: f64| {
            let low = |i: isize, j: isize| {
                i < 0 || j < 0 || i >= nx as isize || j >= ny as isize || {
                    headroom[j as usize * nx + i as usize] < below
                }
            };
            let mut near = vec![false; n];
            let rr = (radius / res).ceil() as isize;
            for (c, &hr) in headroom.iter().enumerate() {
                if hr >= below {
                    continue;
                }
                near[c] = true;
                let (ci, cj) = ((c % nx) as isize, (c / nx) as isize);
                if low(ci - 1, cj) && low(ci + 1, cj) && low(ci, cj - 1) && low(ci, cj + 1) {
                    continue;
                }
                for dj in -rr..=rr {
                    for di in -rr..=rr {
                        let (i, j) = (ci + di, cj + dj);
                        if i >= 0
                            && j >= 0
                            && (i as usize) < nx
                            && (j as usize) < ny
                            && di * di + dj * dj <= rr * rr
                        {
                            near[j as usize * nx + i as usize] = true;
                        }
                    }
                }
            }
            near
        };
        let crawl_zone = near_tops(crawl_head, s.crawl_body_length);
        // The plan's head comes down within `crawl_body_length` of a top to crawl
        // under and within `character_radius` of one to crouch under
        // (`refine::head_limit`); a route that skirted those edges would dip under
        // wherever smoothing moved it a few centimetres, so it pays from a character
        // radius further out.
        let head_cost = if s.crawl_zone_cost > 0.0 || s.stoop_zone_cost > 0.0 {
            let crawl = near_tops(crawl_head, s.crawl_body_length + s.character_radius);
            let stoop = near_tops(
                (s.stand_height + s.stoop_margin) as f32,
                2.0 * s.character_radius,
            );
            let (kc, ks) = (s.crawl_zone_cost as f32, s.stoop_zone_cost as f32);
            let crouch_leg = crawl.iter().map(|&c| if c { kc } else { 0.0 }).collect();
            let standing_leg = crawl
                .iter()
                .zip(&stoop)
                .map(|(&c, &st)| match (c, st) {
                    (true, _) => kc,
                    (false, true) => ks,
                    _ => 0.0,
                })
                .collect();
            [crouch_leg, standing_leg]
        } else {
            [Vec::new(), Vec::new()]
        };
        // Relief: separable sliding max and min over a square window.
        let k = ((s.crawl_half_width / res).ceil() as usize + 1).max(1);
        let mut hi_x = vec![0.0f64; n];
        let mut lo_x = vec![0.0f64; n];
        for j in 0..ny {
            for i in 0..nx {
                let (a, b) = (i.saturating_sub(k), (i + k).min(nx - 1));
                let row = &height[j * nx + a..=j * nx + b];
                hi_x[j * nx + i] = row.iter().copied().fold(f64::MIN, f64::max);
                lo_x[j * nx + i] = row.iter().copied().fold(f64::MAX, f64::min);
            }
        }
        let mut relief = vec![0.0f32; n];
        for j in 0..ny {
            let (a, b) = (j.saturating_sub(k), (j + k).min(ny - 1));
            for i in 0..nx {
                let (mut h, mut l) = (f64::MIN, f64::MAX);
                for jj in a..=b {
                    h = h.max(hi_x[jj * nx + i]);
                    l = l.min(lo_x[jj * nx + i]);
                }
                relief[j * nx + i] = (h - l) as f32;
            }
        }
        let has_relief = (s.crawl_relief_cost > 0.0 || s.stand_relief_cost > 0.0)
            && relief.iter().any(|&r| r > 0.0);
        let mut edges = vec![[f32::INFINITY; 8]; n];
        let tan_max_slope = s.max_slope.tan();
        for (d, &(di, dj)) in DIRS[..4].iter().enumerate() {
            let dxy = res * ((di * di + dj * dj) as f64).sqrt();
            // The slope is measured over two windows of half `slope_baseline` each, one
            // ending with the edge and one starting with it (one window over the
            // whole baseline reads a ridge crossed within it as level): `w` cells each.
            let w = ((0.5 * s.slope_baseline / dxy).round() as isize).max(1);
            for j in 0..ny {
                let j2 = j as isize + dj;
                if j2 < 0 || j2 >= ny as isize {
                    continue;
                }
                for i in 0..nx {
                    let i2 = i as isize + di;
                    if i2 < 0 || i2 >= nx as isize {
                        continue;
                    }
                    let a = j * nx + i;
                    let b = j2 as usize * nx + i2 as usize;
                    if !free[a] || !free[b] {
                        continue;
                    }
                    if di != 0 && dj != 0 {
                        // No corner cutting: both orthogonal neighbours must be free.
                        let c1 = j * nx + i2 as usize;
                        let c2 = j2 as usize * nx + i;
                        if !free[c1] || !free[c2] {
                            continue;
                        }
                    }
                    // The heights of cells `k0..=k1` steps along the edge from `a`
                    // (clamped to the grid).
                    let height = &height;
                    let line = |k0: isize, k1: isize| {
                        (k0..=k1).map(move |k| {
                            let ci = (i as isize + k * di).clamp(0, nx as isize - 1) as usize;
                            let cj = (j as isize + k * dj).clamp(0, ny as isize - 1) as usize;
                            height[cj * nx + ci]
                        })
                    };
                    if s.slope_baseline > 0.0
                        && (too_steep(tan_max_slope, line(1 - w, 1), dxy)
                            || too_steep(tan_max_slope, line(0, w), dxy))
                    {
                        continue;
                    }
                    if let Some(w) = edge_cost_with(s, tan_max_slope, dxy, height[b] - height[a]) {
                        edges[a][d] = w as f32;
                        edges[b][d + 4] = w as f32;
                    }
                }
            }
        }
        let has_tops = headroom.iter().any(|h| h.is_finite());
        let has_head_cost = head_cost.iter().flatten().any(|&k| k > 0.0);
        Self {
            origin,
            resolution: res,
            nx,
            ny,
            height,
            has_tops,
            body_fits,
            wall_frames,
            crawl_zone,
            has_body_limits,
            relief,
            has_relief,
            relief_cost: s.crawl_relief_cost,
            stand_relief_cost: s.stand_relief_cost,
            head_cost,
            has_head_cost,
            headroom,
            free,
            edges,
            climb_cost_lower_bound: s.height_cost + s.slope_preference_c,
        }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.nx * self.ny
    }

    /// Whether the grid has no cells (never, for a valid scene).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// World XY of a cell index.
    pub fn position(&self, c: usize) -> [f64; 2] {
        [
            self.origin[0] + (c % self.nx) as f64 * self.resolution,
            self.origin[1] + (c / self.nx) as f64 * self.resolution,
        ]
    }

    /// The cell nearest to (x, y), if on the grid.
    pub fn cell_of(&self, x: f64, y: f64) -> Option<usize> {
        let fi = ((x - self.origin[0]) / self.resolution).round();
        let fj = ((y - self.origin[1]) / self.resolution).round();
        (fi >= 0.0 && fj >= 0.0 && (fi as usize) < self.nx && (fj as usize) < self.ny)
            .then(|| fj as usize * self.nx + fi as usize)
    }

    /// Whether a cell can be occupied with head height at least `min_head` \[m\]
    /// (plus the head margin, already folded into `min_head` by callers).
    #[inline]
    pub fn passable(&self, c: usize, min_head: f32) -> bool {
        self.free[c] && self.headroom[c] >= min_head
    }

    /// Cost of the edge from `a` in direction `d` (index into `DIRS`), and the
    /// neighbour, or `None` when the edge is off-grid or removed.
    #[inline]
    pub fn edge(&self, a: usize, d: usize) -> Option<(usize, f32)> {
        let w = self.edges[a][d];
        // A finite cost implies the neighbour is on the grid.
        w.is_finite()
            .then(|| (a.wrapping_add_signed(self.offset(d)), w))
    }

    /// Index offset of the neighbour in direction `DIRS[d]`.
    #[inline]
    pub(crate) fn offset(&self, d: usize) -> isize {
        let (di, dj) = DIRS[d];
        dj * self.nx as isize + di
    }

    /// Like [`Self::edge`], and both ends (and, diagonally, both corner cells) are
    /// passable at head height `min_head`.
    #[inline]
    pub fn edge_for(&self, a: usize, d: usize, min_head: f32) -> Option<(usize, f32)> {
        let (b, w) = self.edge(a, d)?;
        if self.headroom[b] < min_head {
            return None;
        }
        if d == 2 || d == 3 || d == 6 || d == 7 {
            let (ai, aj) = (a % self.nx, a / self.nx);
            let (bi, bj) = (b % self.nx, b / self.nx);
            if self.headroom[aj * self.nx + bi] < min_head
                || self.headroom[bj * self.nx + ai] < min_head
            {
                return None;
            }
        }
        Some((b, w))
    }
}
