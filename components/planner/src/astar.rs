//! Stage 2: A* on the 8-connected planning grid, goal = the nearest cell of a set.

use crate::alt::AltLandmarks;
use crate::grid::{DIRS, PlanGrid};

/// Cells A* must not enter (dynamic obstacles at their predicted positions) and an
/// optional window (i0, j0, i1, j1), inclusive, that bounds a local search.
#[derive(Debug, Clone, Default)]
pub struct SearchLimits {
    /// Discs (x, y, radius) \[m\] the path must stay out of.
    pub blocked_discs: Vec<[f64; 3]>,
    /// Inclusive cell window.
    pub window: Option<(usize, usize, usize, usize)>,
    /// Where the crawling body's footprint must fit the step's heading
    /// ([`PlanGrid::body_fits`]).
    pub crawl_body: CrawlBody,
    /// The leg's posture, for the cost of lowering the head under tops
    /// ([`PlanGrid::head_cost`]).
    pub posture: Posture,
}

/// How a leg carries its head, as far as tops cost it something to pass under.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Posture {
    /// Crawling (or no cost asked for): a top costs nothing.
    #[default]
    Crawl,
    /// Crouch-walking: a top it must crawl under costs `crawl_zone_cost`.
    Crouch,
    /// Walking, running, sprinting: a top it must crouch under costs
    /// `stoop_zone_cost`, one it must crawl under `crawl_zone_cost`.
    Standing,
}

impl Posture {
    /// The posture of a leg in `form`.
    pub fn of(form: crate::Locomotion) -> Self {
        use crate::Locomotion::*;
        match form {
            Crawl => Self::Crawl,
            CrouchWalk => Self::Crouch,
            Walk | Run | Sprint => Self::Standing,
        }
    }

    /// Extra cost per metre at cell `c` of `g` for this posture \[1\].
    #[inline]
    pub(crate) fn head_cost(self, g: &PlanGrid, c: usize) -> f64 {
        match self {
            Self::Crawl => 0.0,
            Self::Crouch => f64::from(g.head_cost[0][c]),
            Self::Standing => f64::from(g.head_cost[1][c]),
        }
    }
}

/// Where a search keeps the crawling body's footprint clear of walls.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum CrawlBody {
    /// Nowhere (the fallback when the footprint leaves no path).
    Off,
    /// In the grid's crawl zone (under and around low tops).
    #[default]
    Zone,
    /// Everywhere: the whole leg is crawled.
    Everywhere,
}

impl SearchLimits {
    fn allows(&self, g: &PlanGrid, c: usize) -> bool {
        let (i, j) = (c % g.nx, c / g.nx);
        if let Some((i0, j0, i1, j1)) = self.window
            && (i < i0 || i > i1 || j < j0 || j > j1)
        {
            return false;
        }
        if self.blocked_discs.is_empty() {
            return true;
        }
        let [x, y] = g.position(c);
        self.blocked_discs
            .iter()
            .all(|d| (x - d[0]).powi(2) + (y - d[1]).powi(2) > d[2] * d[2])
    }
}

/// Whether a step from `a` to `b` in direction `DIRS[d]` keeps the crawling body
/// clear of walls at both ends (at `b` only when `a` is the start, where the body
/// already is however it lies), when the rule applies there.
#[inline]
pub(crate) fn body_step_ok(
    g: &PlanGrid,
    rule: CrawlBody,
    a: usize,
    b: usize,
    d: usize,
    a_is_start: bool,
) -> bool {
    let applies = crawl_applies(g, rule, a, b);
    let bit = 1u8 << d;
    !applies || (g.body_fits[b] & bit != 0 && (a_is_start || g.body_fits[a] & bit != 0))
}

/// Whether the character crawls on the step from `a` to `b` under `rule`.
#[inline]
pub(crate) fn crawl_applies(g: &PlanGrid, rule: CrawlBody, a: usize, b: usize) -> bool {
    match rule {
        CrawlBody::Off => false,
        CrawlBody::Zone => g.crawl_zone[a] || g.crawl_zone[b],
        CrawlBody::Everywhere => true,
    }
}

/// Length of a step in direction `DIRS[d]` \[m\].
#[inline]
fn step_length(g: &PlanGrid, d: usize) -> f64 {
    if d % 4 >= 2 {
        g.resolution * std::f64::consts::SQRT_2
    } else {
        g.resolution
    }
}

/// Extra cost of a step from `a` to `b` (direction `DIRS[d]`) over uneven ground:
/// its length times `per_metre` ([`PlanGrid::relief_weight`]) times the relief at
/// both ends (mean) \[m\].
#[inline]
pub(crate) fn relief_cost(g: &PlanGrid, per_metre: f64, a: usize, b: usize, d: usize) -> f64 {
    step_length(g, d) * per_metre * 0.5 * (g.relief[a] + g.relief[b]) as f64
}

/// Extra cost of a step from `a` to `b` (direction `DIRS[d]`) where a top makes a
/// leg of `posture` lower its head: its length times the mean of both ends'
/// [`PlanGrid::head_cost`] \[m\].
#[inline]
pub(crate) fn head_cost(g: &PlanGrid, posture: Posture, a: usize, b: usize, d: usize) -> f64 {
    step_length(g, d) * 0.5 * (posture.head_cost(g, a) + posture.head_cost(g, b))
}

/// A found path: cells from start to goal and its cost.
#[derive(Debug, Clone)]
pub struct GridPath {
    /// Cell indices, start first.
    pub cells: Vec<usize>,
    /// Cumulative cost at each cell \[m\].
    pub cost_to: Vec<f64>,
}

/// A* lower bound on the cost from a cell to the nearest of a goal set.
///
/// Every edge costs at least `sqrt(dxy^2 + dh^2) + k |dh|` with
/// `k = PlanGrid::climb_cost_lower_bound`. Summed over a path, the 3D lengths are at
/// least `sqrt(D^2 + H^2)` (triangle inequality) and the climb terms at least `k H`,
/// where `D` is the octile distance and `H` the height difference to the goals (to
/// their bounding box and height interval, so the bound holds for every goal at once).
/// Both terms change by at most the edge's share along an edge, so the bound is
/// consistent as well as admissible; it is shrunk by 1e-6 relative so that the `f32`
/// rounding of stored edge costs cannot break that.
#[derive(Debug, Clone, Copy)]
pub struct Heuristic {
    lo: [usize; 2],
    hi: [usize; 2],
    h_lo: f64,
    h_hi: f64,
    res: f64,
    k: f64,
}

impl Heuristic {
    /// The bound to `goals` (cells outside the grid are ignored), `None` without goals.
    pub fn new(g: &PlanGrid, goals: &[usize]) -> Option<Self> {
        let mut it = goals.iter().copied().filter(|&c| c < g.len());
        let first = it.next()?;
        let ij = |c: usize| [c % g.nx, c / g.nx];
        let mut h = Self {
            lo: ij(first),
            hi: ij(first),
            h_lo: g.height[first],
            h_hi: g.height[first],
            res: g.resolution,
            k: g.climb_cost_lower_bound,
        };
        for c in it {
            h.include(g, c);
        }
        Some(h)
    }

    fn include(&mut self, g: &PlanGrid, c: usize) {
        let [i, j] = [c % g.nx, c / g.nx];
        self.lo = [self.lo[0].min(i), self.lo[1].min(j)];
        self.hi = [self.hi[0].max(i), self.hi[1].max(j)];
        self.h_lo = self.h_lo.min(g.height[c]);
        self.h_hi = self.h_hi.max(g.height[c]);
    }

    /// The bound at cell (i, j) of terrain height `z` \[m\].
    #[inline]
    pub fn at(&self, i: usize, j: usize, z: f64) -> f64 {
        let dx = self.lo[0]
            .saturating_sub(i)
            .max(i.saturating_sub(self.hi[0])) as f64;
        let dy = self.lo[1]
            .saturating_sub(j)
            .max(j.saturating_sub(self.hi[1])) as f64;
        let (a, b) = if dx > dy { (dx, dy) } else { (dy, dx) };
        let d = self.res * ((a - b) + b * std::f64::consts::SQRT_2);
        let dz = (self.h_lo - z).max(z - self.h_hi).max(0.0);
        ((d * d + dz * dz).sqrt() + self.k * dz) * (1.0 - 1e-6)
    }

    /// Whether (i, j) lies in the goals' bounding box.
    #[inline]
    fn in_box(&self, i: usize, j: usize) -> bool {
        (self.lo[0]..=self.hi[0]).contains(&i) && (self.lo[1]..=self.hi[1]).contains(&j)
    }

    /// The bound at cell `c` of grid `g`.
    #[inline]
    pub fn at_cell(&self, g: &PlanGrid, c: usize) -> f64 {
        self.at(c % g.nx, c / g.nx, g.height[c])
    }
}

/// Per-cell search state, 16 bytes so four share a cache line.
#[derive(Debug, Default, Clone, Copy)]
struct Node {
    /// Cost from the start \[m\].
    g: f64,
    /// `gen` = open (`g`, `pos` and the parent valid), `gen + 1` = closed, anything
    /// else = unseen.
    stamp: u32,
    /// Index in the open heap while open.
    pos: u32,
}

/// Reusable A* buffers (generation-stamped, so a search costs nothing to reset).
#[derive(Debug, Default, Clone)]
pub struct AStar {
    gen_: u32,
    node: Vec<Node>,
    /// Direction index (into `DIRS`) of the step that reached each open/closed cell.
    parent_dir: Vec<u8>,
    goal: Vec<u32>,
    heap: OpenHeap,
    /// Nodes expanded by the last search.
    pub expanded: usize,
}

impl AStar {
    /// Search from `start` to the nearest (by cost) of `goals` over edges passable at
    /// head height `min_head`, with the consistent [`Heuristic`]: the returned path is
    /// a cheapest one.
    pub fn search(
        &mut self,
        g: &PlanGrid,
        start: usize,
        goals: &[usize],
        min_head: f32,
        limits: &SearchLimits,
    ) -> Option<GridPath> {
        self.search_with(g, start, goals, min_head, limits, None)
    }

    /// [`Self::search`], with the bound also raised to the landmarks' (ALT) bound
    /// where `alt` is given and was built for `g` (otherwise it is not used). The
    /// path's cost is the same cheapest cost; among equally cheap paths the one found
    /// may differ from [`Self::search`]'s.
    pub fn search_with(
        &mut self,
        g: &PlanGrid,
        start: usize,
        goals: &[usize],
        min_head: f32,
        limits: &SearchLimits,
        alt: Option<&AltLandmarks>,
    ) -> Option<GridPath> {
        let n = g.len();
        if self.node.len() != n {
            self.node = vec![Node::default(); n];
            self.parent_dir = vec![0; n];
            self.goal = vec![0; n];
            self.gen_ = 0;
        }
        // Two stamps per search (open, closed); 0 stays "unseen".
        self.gen_ = match self.gen_.checked_add(2) {
            Some(x) if x < u32::MAX => x,
            _ => {
                self.node.fill(Node::default());
                self.goal.fill(0);
                1
            }
        };
        let (open, closed) = (self.gen_, self.gen_ + 1);
        self.expanded = 0;
        let mut heur: Option<Heuristic> = None;
        for &c in goals {
            if c < n && limits.allows(g, c) {
                self.goal[c] = open;
                match heur.as_mut() {
                    Some(h) => h.include(g, c),
                    None => heur = Heuristic::new(g, &[c]),
                }
            }
        }
        let heur = heur?;
        if start >= n {
            return None;
        }
        let alt = alt
            .filter(|a| a.fits(g) && !a.is_empty())
            .map(|a| a.query(start, goals));
        let offsets: [isize; 8] = std::array::from_fn(|d| g.offset(d));
        let nx = g.nx;
        self.heap.clear();
        let mut h0 = heur.at_cell(g, start);
        if let Some(a) = &alt {
            h0 = h0.max(a.at(start));
        }
        self.node[start] = Node {
            g: 0.0,
            stamp: open,
            pos: 0,
        };
        self.heap
            .push_or_decrease(h0.to_bits(), start as u32, &mut self.node);
        while let Some(cu) = self.heap.pop(&mut self.node) {
            let c = cu as usize;
            let nc = &mut self.node[c];
            nc.stamp = closed;
            let gc = nc.g;
            self.expanded += 1;
            let (ci, cj) = (c % nx, c / nx);
            if heur.in_box(ci, cj) && self.goal[c] == open {
                return Some(self.reconstruct(g, start, c));
            }
            let edges = &g.edges[c];
            for d in 0..8 {
                let w = edges[d];
                if w == f32::INFINITY {
                    continue;
                }
                // A finite cost implies the neighbour is on the grid.
                let b = c.wrapping_add_signed(offsets[d]);
                let mut gb = gc + w as f64;
                if g.has_relief {
                    // A leg with no cost for its posture (standing, by default) skips it.
                    let w = g.relief_weight(crawl_applies(g, limits.crawl_body, c, b));
                    if w > 0.0 {
                        gb += relief_cost(g, w, c, b, d);
                    }
                }
                if g.has_head_cost {
                    gb += head_cost(g, limits.posture, c, b, d);
                }
                let nb = &mut self.node[b];
                // A closed cell is re-opened when reached cheaper: the ALT bound
                // is admissible but, through the f32 rounding of its distances,
                // consistent only to a few micrometres (never for `Heuristic`).
                if nb.stamp == closed && gb >= nb.g {
                    continue;
                }
                if g.has_tops && g.edge_for(c, d, min_head).is_none() {
                    continue;
                }
                if g.has_body_limits && !body_step_ok(g, limits.crawl_body, c, b, d, c == start) {
                    continue;
                }
                if nb.stamp == open || nb.stamp == closed {
                    if gb >= nb.g {
                        continue;
                    }
                } else if !limits.allows(g, b) {
                    // Closed at -inf so the check runs once per search and the
                    // cell is never re-opened.
                    nb.stamp = closed;
                    nb.g = f64::NEG_INFINITY;
                    continue;
                }
                if nb.stamp != open {
                    nb.stamp = open;
                    nb.pos = u32::MAX;
                }
                nb.g = gb;
                self.parent_dir[b] = d as u8;
                let (di, dj) = DIRS[d];
                let mut hb = heur.at(
                    ci.wrapping_add_signed(di),
                    cj.wrapping_add_signed(dj),
                    g.height[b],
                );
                if let Some(a) = &alt {
                    hb = hb.max(a.at(b));
                }
                self.heap
                    .push_or_decrease((gb + hb).to_bits(), b as u32, &mut self.node);
            }
        }
        None
    }

    fn reconstruct(&self, g: &PlanGrid, start: usize, goal: usize) -> GridPath {
        let mut cells = vec![goal];
        let mut c = goal;
        while c != start {
            // Step back against the direction that reached `c`.
            let d = self.parent_dir[c] as usize;
            c = c.wrapping_add_signed(-g.offset(d));
            cells.push(c);
        }
        cells.reverse();
        let cost_to = cells.iter().map(|&c| self.node[c].g).collect();
        GridPath { cells, cost_to }
    }
}

/// The open set: a 4-ary min-heap on the bit patterns of non-negative `f64` keys
/// (which order like the numbers), indexed by cell through `Node::pos`, so an
/// improved cell moves up in place instead of being pushed again. The heap then holds
/// only the frontier, never stale entries.
#[derive(Debug, Clone, Default)]
struct OpenHeap {
    items: Vec<(u64, u32)>,
}

impl OpenHeap {
    const ARITY: usize = 4;

    fn clear(&mut self) {
        self.items.clear();
    }

    /// Insert `cell` with `key`, or lower its key when `node[cell].pos` is valid.
    #[inline]
    fn push_or_decrease(&mut self, key: u64, cell: u32, node: &mut [Node]) {
        let p = node[cell as usize].pos as usize;
        let at = if p < self.items.len() && self.items[p].1 == cell {
            self.items[p].0 = key;
            p
        } else {
            self.items.push((key, cell));
            self.items.len() - 1
        };
        self.sift_up(at, node);
    }

    #[inline]
    fn pop(&mut self, node: &mut [Node]) -> Option<u32> {
        let top = self.items.first()?.1;
        let last = self.items.pop()?;
        if !self.items.is_empty() {
            self.items[0] = last;
            self.sift_down(0, node);
        }
        Some(top)
    }

    #[inline]
    fn sift_up(&mut self, mut i: usize, node: &mut [Node]) {
        let it = self.items[i];
        while i > 0 {
            let p = (i - 1) / Self::ARITY;
            if self.items[p].0 <= it.0 {
                break;
            }
            self.items[i] = self.items[p];
            node[self.items[i].1 as usize].pos = i as u32;
            i = p;
        }
        self.items[i] = it;
        node[it.1 as usize].pos = i as u32;
    }

    #[inline]
    fn sift_down(&mut self, mut i: usize, node: &mut [Node]) {
        let it = self.items[i];
        let n = self.items.len();
        loop {
            let first = i * Self::ARITY + 1;
            if first >= n {
                break;
            }
            let mut m = first;
            for k in first + 1..(first + Self::ARITY).min(n) {
                if self.items[k].0 < self.items[m].0 {
                    m = k;
                }
            }
            if self.items[m].0 >= it.0 {
                break;
            }
            self.items[i] = self.items[m];
            node[self.items[i].1 as usize].pos = i as u32;
            i = m;
        }
        self.items[i] = it;
        node[it.1 as usize].pos = i as u32;
    }
}

#[cfg(test)]
mod tests {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;

    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::PlannerSettings;
    use crate::synthetic::{flat_scene, hills_scene, pyramid_scene};

    /// Cost to the nearest goal from every cell: multi-source Dijkstra from the goals
    /// (the graph is symmetric) over cells `limits` allows, the reference A* must
    /// match.
    fn dijkstra_to(
        g: &PlanGrid,
        goals: &[usize],
        min_head: f32,
        limits: &SearchLimits,
    ) -> Vec<f64> {
        let mut dist = vec![f64::INFINITY; g.len()];
        let mut heap = BinaryHeap::new();
        for &c in goals {
            if limits.allows(g, c) {
                dist[c] = 0.0;
                heap.push(Reverse((0u64, c)));
            }
        }
        while let Some(Reverse((k, c))) = heap.pop() {
            if f64::from_bits(k) > dist[c] {
                continue;
            }
            for d in 0..8 {
                if let Some((b, w)) = g.edge_for(c, d, min_head) {
                    let nb = dist[c] + w as f64;
                    if nb < dist[b] && limits.allows(g, b) {
                        dist[b] = nb;
                        heap.push(Reverse((nb.to_bits(), b)));
                    }
                }
            }
        }
        dist
    }

    fn landmark_goals(
        scene: &plamo_scenes::Scene,
        g: &PlanGrid,
        goal: &str,
        min_head: f32,
    ) -> Vec<usize> {
        scene
            .landmark_cells(scene.landmark(goal).unwrap())
            .into_iter()
            .map(|(i, j)| j * g.nx + i)
            .filter(|&c| g.passable(c, min_head))
            .collect()
    }

    /// A* from `start` (with and, when given, without landmarks) against the
    /// Dijkstra cost `dc`; returns whether a path was checked.
    #[allow(clippy::too_many_arguments)]
    fn check_start(
        g: &PlanGrid,
        astar: &mut AStar,
        alt: Option<&AltLandmarks>,
        start: usize,
        goals: &[usize],
        min_head: f32,
        limits: &SearchLimits,
        dc: f64,
    ) -> bool {
        let mut found_any = false;
        for a in [None, alt] {
            match astar.search_with(g, start, goals, min_head, limits, a) {
                Some(p) => {
                    let cost = *p.cost_to.last().unwrap();
                    assert!(
                        (cost - dc).abs() <= 1e-9 * dc.max(1.0),
                        "start {start}, landmarks {}: A* {cost} vs Dijkstra {dc}",
                        a.is_some()
                    );
                    assert!(goals.contains(p.cells.last().unwrap()));
                    // The path is made of edges A* may use and its costs add up.
                    for (k, w) in p.cells.windows(2).enumerate() {
                        let d = (0..8)
                            .find(|&d| {
                                g.edge_for(w[0], d, min_head)
                                    .is_some_and(|(b, _)| b == w[1])
                            })
                            .expect("path steps along passable edges");
                        let (_, wc) = g.edge_for(w[0], d, min_head).unwrap();
                        assert_eq!(p.cost_to[k + 1], p.cost_to[k] + wc as f64);
                        assert!(limits.allows(g, w[1]));
                    }
                    found_any = true;
                }
                None => assert!(
                    dc.is_infinite(),
                    "start {start}: A* found nothing, Dijkstra {dc}"
                ),
            }
        }
        found_any
    }

    fn check_exact(scene: &plamo_scenes::Scene, s: &PlannerSettings, goal: &str, min_head: f32) {
        let g = PlanGrid::build(scene, s);
        let goals = landmark_goals(scene, &g, goal, min_head);
        let limits = SearchLimits::default();
        let dist = dijkstra_to(&g, &goals, min_head, &limits);
        let heur = Heuristic::new(&g, &goals).unwrap();
        let alt = AltLandmarks::build(&g, 6);
        let mut astar = AStar::default();
        let mut checked = 0;
        for (c, &dc) in dist.iter().enumerate() {
            let h = heur.at_cell(&g, c);
            if dc.is_finite() {
                assert!(h <= dc, "inadmissible at {c}: {h} > {dc}");
                // The landmark bound, with the landmarks a query from `c` picks.
                let ha = alt.query(c, &goals).at(c);
                assert!(ha <= dc, "landmark bound inadmissible at {c}: {ha} > {dc}");
            }
            for d in 0..8 {
                if let Some((b, w)) = g.edge_for(c, d, min_head) {
                    let hb = heur.at_cell(&g, b);
                    assert!(h <= w as f64 + hb, "inconsistent on {c} -> {b}");
                }
            }
            // A* from a spread of starts.
            if c % 197 == 0
                && g.passable(c, min_head)
                && check_start(&g, &mut astar, Some(&alt), c, &goals, min_head, &limits, dc)
            {
                checked += 1;
            }
        }
        assert!(checked > 10, "only {checked} starts checked");
    }

    /// A random scene: rough hills with sharp steps (removed edges), walls, low
    /// ceilings, and a goal landmark of random size.
    fn random_scene(rng: &mut ChaCha8Rng) -> plamo_scenes::Scene {
        use plamo_scenes::{Footprint, HeightGrid, Landmark, Region, Scene, TopObstacle, Wall};
        let (w, h) = (rng.random_range(4.0..9.0), rng.random_range(4.0..9.0));
        let mut t = HeightGrid::flat([0.0, 0.0], [w, h], 0.1, 0.0);
        let amp: f64 = rng.random_range(0.0..1.5);
        let (fx, fy, ph): (f64, f64, f64) = (
            rng.random_range(0.3..2.0),
            rng.random_range(0.3..2.0),
            rng.random_range(0.0..6.0),
        );
        let steps: Vec<([f64; 2], f64)> = (0..rng.random_range(0..4))
            .map(|_| {
                (
                    [rng.random_range(0.0..w), rng.random_range(0.0..h)],
                    rng.random_range(0.5..2.0),
                )
            })
            .collect();
        for j in 0..t.ny {
            for i in 0..t.nx {
                let [x, y] = t.position(i, j);
                let mut z = amp * (x * fx + ph).sin() * (y * fy).cos();
                for &(ctr, r) in &steps {
                    if (x - ctr[0]).abs().max((y - ctr[1]).abs()) < r {
                        z += 0.4;
                    }
                }
                t.heights[j * t.nx + i] = z;
            }
        }
        let boxes = |rng: &mut ChaCha8Rng| {
            let c = [rng.random_range(0.0..w), rng.random_range(0.0..h)];
            let half = [rng.random_range(0.1..1.5), rng.random_range(0.1..1.5)];
            Footprint::axis_aligned(c, half)
        };
        let walls = (0..rng.random_range(0..4))
            .map(|_| Wall {
                name: "wall".into(),
                footprint: boxes(rng),
                z_min: -5.0,
                z_max: 5.0,
            })
            .collect();
        let tops = (0..rng.random_range(0..3))
            .map(|_| {
                let z = rng.random_range(0.3..2.5);
                TopObstacle {
                    name: "roof".into(),
                    footprint: boxes(rng),
                    z_bottom: z,
                    z_top: z + 0.2,
                }
            })
            .collect();
        let goal = Landmark {
            name: "goal".into(),
            region: Region::Circle {
                center: [
                    rng.random_range(0.5..w - 0.5),
                    rng.random_range(0.5..h - 0.5),
                ],
                radius: rng.random_range(0.05..1.0),
            },
        };
        Scene {
            name: "random".into(),
            description: String::new(),
            terrain: t,
            walls,
            dynamic: vec![],
            tops,
            landmarks: vec![goal],
        }
    }

    #[test]
    fn astar_with_and_without_landmarks_equals_dijkstra_on_random_grids() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut checked = 0;
        for case in 0..24 {
            let scene = random_scene(&mut rng);
            // Half the cases keep off the steps' cliffs, which cuts grids apart.
            let s = PlannerSettings {
                slope_preference_c: [0.0, 0.5, 1.0, 4.0][case % 4],
                cliff_clearance: [0.0, 0.3][(case / 4) % 2],
                ..PlannerSettings::default()
            };
            let min_head = [0.5f32, 0.9, 1.6][case % 3];
            let g = PlanGrid::build(&scene, &s);
            let goals = landmark_goals(&scene, &g, "goal", min_head);
            if goals.is_empty() {
                continue;
            }
            let alt = AltLandmarks::build(&g, 1 + case % 8);
            let mut astar = AStar::default();
            // Every third case also blocks a disc and bounds the search to a window.
            let limits = if case % 3 == 2 {
                let (nx, ny) = (g.nx, g.ny);
                SearchLimits {
                    blocked_discs: vec![[
                        rng.random_range(0.0..nx as f64 * 0.1),
                        rng.random_range(0.0..ny as f64 * 0.1),
                        rng.random_range(0.2..1.5),
                    ]],
                    window: Some((
                        rng.random_range(0..nx / 3),
                        rng.random_range(0..ny / 3),
                        rng.random_range(2 * nx / 3..nx),
                        rng.random_range(2 * ny / 3..ny),
                    )),
                    crawl_body: CrawlBody::Off,
                    posture: Posture::Crawl,
                }
            } else {
                // Dijkstra knows nothing of the crawling body's footprint, a rule
                // on top of the grid (tested in tests/crawl_gap.rs).
                SearchLimits {
                    crawl_body: CrawlBody::Off,
                    ..SearchLimits::default()
                }
            };
            let dist = dijkstra_to(&g, &goals, min_head, &limits);
            for _ in 0..25 {
                let c = rng.random_range(0..g.len());
                if g.passable(c, min_head)
                    && limits.allows(&g, c)
                    && check_start(
                        &g,
                        &mut astar,
                        Some(&alt),
                        c,
                        &goals,
                        min_head,
                        &limits,
                        dist[c],
                    )
                {
                    checked += 1;
                }
            }
        }
        assert!(checked > 200, "only {checked} searches found a path");
    }

    #[test]
    fn landmark_search_is_deterministic() {
        let scene = hills_scene(120, 3.0);
        let g = PlanGrid::build(&scene, &PlannerSettings::default());
        let a1 = AltLandmarks::build(&g, 5);
        let a2 = AltLandmarks::build(&g, 5);
        assert_eq!(a1.cells, a2.cells);
        let goals = landmark_goals(&scene, &g, "ne", 0.5);
        let start = g.cell_of(2.0, 2.0).unwrap();
        let limits = SearchLimits::default();
        let p1 = AStar::default()
            .search_with(&g, start, &goals, 0.5, &limits, Some(&a1))
            .unwrap();
        let mut reused = AStar::default();
        reused.search(&g, g.cell_of(6.0, 1.0).unwrap(), &goals, 0.5, &limits);
        let p2 = reused
            .search_with(&g, start, &goals, 0.5, &limits, Some(&a2))
            .unwrap();
        assert_eq!(p1.cells, p2.cells);
        assert_eq!(p1.cost_to, p2.cost_to);
    }

    #[test]
    fn landmarks_cut_expansions_on_hills() {
        // The point of the landmarks: far fewer cells expanded for the same cost.
        let scene = hills_scene(300, 3.0);
        let g = PlanGrid::build(&scene, &PlannerSettings::default());
        let alt = AltLandmarks::build(&g, 8);
        let goals = landmark_goals(&scene, &g, "ne", 0.5);
        let start = g.cell_of(2.0, 2.0).unwrap();
        let limits = SearchLimits::default();
        let mut astar = AStar::default();
        let plain = astar.search(&g, start, &goals, 0.5, &limits).unwrap();
        let e_plain = astar.expanded;
        let with = astar
            .search_with(&g, start, &goals, 0.5, &limits, Some(&alt))
            .unwrap();
        let e_alt = astar.expanded;
        assert!(
            (plain.cost_to.last().unwrap() - with.cost_to.last().unwrap()).abs() < 1e-9,
            "same cheapest cost"
        );
        assert!(
            e_alt * 5 < e_plain,
            "{e_alt} expansions with landmarks vs {e_plain} without"
        );
    }

    #[test]
    fn astar_cost_equals_dijkstra_on_hills() {
        let s = PlannerSettings::default();
        check_exact(&hills_scene(160, 3.0), &s, "ne", 0.5);
    }

    #[test]
    fn astar_cost_equals_dijkstra_on_a_steep_pyramid_with_high_c() {
        let s = PlannerSettings {
            slope_preference_c: 10.0,
            ..PlannerSettings::default()
        };
        check_exact(&pyramid_scene(2.0), &s, "east", 0.5);
    }

    #[test]
    fn astar_cost_equals_dijkstra_under_a_ceiling() {
        // Head height 1.2 m: the 0.9 m roof over the wall's gap blocks, so the car
        // is unreachable from the west half and A* must say so.
        let s = PlannerSettings::default();
        check_exact(&flat_scene(), &s, "car", 0.5);
        check_exact(&flat_scene(), &s, "car", 1.2);
    }
}
