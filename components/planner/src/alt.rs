//! ALT lower bounds (A*, Landmarks, Triangle inequality; Goldberg & Harrelson 2005)
//! for A* on large grids: exact costs from a few landmark cells to every cell,
//! computed once per grid, bound the remaining cost far more tightly than the
//! geometric [`crate::Heuristic`] where the slope preference makes hills expensive.
//!
//! The distances are taken over every finite edge of the grid, ignoring headroom.
//! A search at any head height, with any blocked discs or window, runs on a subgraph
//! of that graph, where costs can only be larger, so the bounds stay admissible for
//! every query. The graph is symmetric (`edges[a][d] == edges[b][d + 4]`), so for a
//! landmark `L` and goal set `T`: `cost(v, T) >= min_T d(L, t) - d(L, v)` and
//! `cost(v, T) >= d(L, v) - max_T d(L, t)`.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use crate::grid::PlanGrid;

/// Landmark distances for one grid. Build once per scene (a Dijkstra over the
/// whole grid per landmark, plus one to seed the selection), reuse for every query.
#[derive(Debug, Clone)]
pub struct AltLandmarks {
    /// Landmark cells, in selection order.
    pub cells: Vec<usize>,
    /// `dist[c * k + l]`: cost from landmark `l` to cell `c` (`INFINITY` where
    /// unreachable), `k = cells.len()`, interleaved so a cell's bounds share a cache
    /// line \[m\].
    dist: Vec<f32>,
    /// Relative error bound of the `f32` rounding of `dist`, times the largest
    /// finite distance: subtracted from every bound so it stays admissible \[m\].
    slack: f64,
    /// Grid size the distances belong to.
    n: usize,
}

/// Most landmarks one query uses (the ones with the best bound at its start).
pub const ALT_ACTIVE: usize = 4;

/// Single-source Dijkstra over every finite edge of `g`, in `f64`.
fn dijkstra_from(
    g: &PlanGrid,
    source: usize,
    dist: &mut [f64],
    heap: &mut BinaryHeap<Reverse<(u64, u32)>>,
) {
    dist.fill(f64::INFINITY);
    heap.clear();
    dist[source] = 0.0;
    heap.push(Reverse((0, source as u32)));
    let offsets: [isize; 8] = std::array::from_fn(|d| g.offset(d));
    while let Some(Reverse((k, c))) = heap.pop() {
        let c = c as usize;
        let dc = f64::from_bits(k);
        if dc > dist[c] {
            continue;
        }
        let edges = &g.edges[c];
        for d in 0..8 {
            let w = edges[d];
            if w == f32::INFINITY {
                continue;
            }
            let b = c.wrapping_add_signed(offsets[d]);
            let nb = dc + w as f64;
            if nb < dist[b] {
                dist[b] = nb;
                heap.push(Reverse((nb.to_bits(), b as u32)));
            }
        }
    }
}

impl AltLandmarks {
    /// Select `k` landmarks by farthest-point selection (each one the cell whose
    /// cost to the nearest landmark chosen so far is largest, which puts them on the
    /// grid's rim, behind the goals of most queries) and store their costs to every
    /// cell. Deterministic: ties go to the lowest cell index.
    pub fn build(g: &PlanGrid, k: usize) -> Self {
        let n = g.len();
        let mut out = Self {
            cells: Vec::with_capacity(k),
            dist: Vec::new(),
            slack: 0.0,
            n,
        };
        if n == 0 || k == 0 {
            return out;
        }
        // Seed: the cell with an edge nearest to the grid's centre.
        let centre = (g.ny / 2) * g.nx + g.nx / 2;
        let Some(seed) = (0..n)
            .filter(|&c| g.edges[c].iter().any(|w| w.is_finite()))
            .min_by_key(|&c| {
                let (i, j) = ((c % g.nx) as i64, (c / g.nx) as i64);
                let (ci, cj) = ((centre % g.nx) as i64, (centre / g.nx) as i64);
                ((i - ci).pow(2) + (j - cj).pow(2), c)
            })
        else {
            return out;
        };
        let mut heap = BinaryHeap::new();
        let mut d = vec![0.0; n];
        dijkstra_from(g, seed, &mut d, &mut heap);
        // Cost to the nearest chosen landmark, the selection's criterion; cells the
        // seed cannot reach stay out of it.
        let mut nearest = d.clone();
        out.dist = vec![f32::INFINITY; n * k];
        let mut max_finite: f64 = 0.0;
        for l in 0..k {
            let mut best = None;
            for (c, &v) in nearest.iter().enumerate() {
                if v.is_finite() && best.is_none_or(|(_, bv)| v > bv) {
                    best = Some((c, v));
                }
            }
            let Some((cell, v)) = best else { break };
            if v == 0.0 && l > 0 {
                break;
            }
            dijkstra_from(g, cell, &mut d, &mut heap);
            for (c, &v) in d.iter().enumerate() {
                out.dist[c * k + l] = v as f32;
                if v.is_finite() {
                    max_finite = max_finite.max(v);
                    nearest[c] = nearest[c].min(v);
                }
            }
            out.cells.push(cell);
        }
        if out.cells.len() < k {
            // Fewer distinct landmarks than asked (a tiny grid): repack.
            let m = out.cells.len();
            let dist = (0..n)
                .flat_map(|c| (0..m).map(move |l| (c, l)))
                .map(|(c, l)| out.dist[c * k + l])
                .collect();
            out.dist = dist;
        }
        // Rounding to f32 moves each stored cost by at most 2^-24 relative; a bound
        // is a difference of two of them.
        out.slack = 4.0 * max_finite * f32::EPSILON as f64;
        out
    }

    /// Number of landmarks.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// Whether these distances were built for a grid of `g`'s size.
    pub fn fits(&self, g: &PlanGrid) -> bool {
        self.n == g.len()
    }

    /// Cost from landmark `l` to cell `c` \[m\].
    pub fn distance(&self, l: usize, c: usize) -> f32 {
        self.dist[c * self.len() + l]
    }

    /// The bound data for one query from `start` to `goals` (cells on the grid),
    /// using the [`ALT_ACTIVE`] landmarks with the largest bound at the start.
    pub(crate) fn query(&self, start: usize, goals: &[usize]) -> AltQuery<'_> {
        let k = self.len();
        let mut cand: Vec<(f64, ActiveLandmark)> = Vec::with_capacity(k);
        for l in 0..k {
            let ds = self.distance(l, start) as f64;
            if !ds.is_finite() {
                continue;
            }
            let (mut tmin, mut tmax) = (f64::INFINITY, f64::NEG_INFINITY);
            for &t in goals {
                let v = self.distance(l, t) as f64;
                if v.is_finite() {
                    tmin = tmin.min(v);
                    tmax = tmax.max(v);
                }
            }
            if !tmin.is_finite() {
                continue;
            }
            let a = ActiveLandmark { l, tmin, tmax };
            cand.push((a.bound(ds), a));
        }
        // Stable sort: equal bounds keep landmark order, so the choice is fixed.
        cand.sort_by(|x, y| y.0.total_cmp(&x.0));
        let mut active = [ActiveLandmark::default(); ALT_ACTIVE];
        let m = cand.len().min(ALT_ACTIVE);
        for (a, (_, c)) in active.iter_mut().zip(&cand) {
            *a = *c;
        }
        AltQuery {
            alt: self,
            active,
            m,
        }
    }
}

#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct ActiveLandmark {
    l: usize,
    tmin: f64,
    tmax: f64,
}

impl ActiveLandmark {
    #[inline]
    fn bound(&self, d: f64) -> f64 {
        (self.tmin - d).max(d - self.tmax)
    }
}

/// One query's landmarks: those the start can reach (so every cell the search
/// touches has finite distances to them), best first.
#[derive(Debug, Clone, Copy)]
pub(crate) struct AltQuery<'a> {
    alt: &'a AltLandmarks,
    active: [ActiveLandmark; ALT_ACTIVE],
    m: usize,
}

impl AltQuery<'_> {
    /// Admissible lower bound on the cost from `c` to the goals (0 when no
    /// landmark applies) \[m\].
    #[inline]
    pub(crate) fn at(&self, c: usize) -> f64 {
        let k = self.alt.len();
        let row = &self.alt.dist[c * k..c * k + k];
        let mut h: f64 = 0.0;
        for a in &self.active[..self.m] {
            h = h.max(a.bound(row[a.l] as f64));
        }
        (h - self.alt.slack).max(0.0)
    }
}
