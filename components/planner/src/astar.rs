//! Stage 2: A* on the 8-connected planning grid, goal = the nearest cell of a set.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use crate::grid::{DIRS, PlanGrid};

/// Cells A* must not enter (dynamic obstacles at their predicted positions) and an
/// optional window (i0, j0, i1, j1), inclusive, that bounds a local search.
#[derive(Debug, Clone, Default)]
pub struct SearchLimits {
    /// Discs (x, y, radius) \[m\] the path must stay out of.
    pub blocked_discs: Vec<[f64; 3]>,
    /// Inclusive cell window.
    pub window: Option<(usize, usize, usize, usize)>,
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

/// A found path: cells from start to goal and its cost.
#[derive(Debug, Clone)]
pub struct GridPath {
    /// Cell indices, start first.
    pub cells: Vec<usize>,
    /// Cumulative cost at each cell \[m\].
    pub cost_to: Vec<f64>,
}

/// Reusable A* buffers (generation-stamped, so a search costs nothing to reset).
#[derive(Debug, Default, Clone)]
pub struct AStar {
    gen_: u32,
    stamp: Vec<u32>,
    goal: Vec<u32>,
    closed: Vec<u32>,
    g: Vec<f64>,
    parent: Vec<u32>,
    heap: BinaryHeap<Reverse<(u64, u32)>>,
    /// Nodes expanded by the last search.
    pub expanded: usize,
}

impl AStar {
    /// Search from `start` to the nearest (by cost) of `goals` over edges passable at
    /// head height `min_head`. The heuristic is the octile distance to the goals'
    /// bounding box, admissible because every edge costs at least its XY length.
    pub fn search(
        &mut self,
        g: &PlanGrid,
        start: usize,
        goals: &[usize],
        min_head: f32,
        limits: &SearchLimits,
    ) -> Option<GridPath> {
        let n = g.len();
        if self.stamp.len() != n {
            self.stamp = vec![0; n];
            self.goal = vec![0; n];
            self.closed = vec![0; n];
            self.g = vec![0.0; n];
            self.parent = vec![0; n];
            self.gen_ = 0;
        }
        self.gen_ = self.gen_.wrapping_add(1);
        if self.gen_ == 0 {
            self.stamp.fill(0);
            self.goal.fill(0);
            self.closed.fill(0);
            self.gen_ = 1;
        }
        let gen_ = self.gen_;
        self.expanded = 0;
        let (mut lo_i, mut lo_j, mut hi_i, mut hi_j) = (usize::MAX, usize::MAX, 0, 0);
        let mut any_goal = false;
        for &c in goals {
            if c < n && limits.allows(g, c) {
                self.goal[c] = gen_;
                any_goal = true;
                let (i, j) = (c % g.nx, c / g.nx);
                lo_i = lo_i.min(i);
                lo_j = lo_j.min(j);
                hi_i = hi_i.max(i);
                hi_j = hi_j.max(j);
            }
        }
        if !any_goal || start >= n {
            return None;
        }
        let res = g.resolution;
        let h = |c: usize| -> f64 {
            let (i, j) = (c % g.nx, c / g.nx);
            let dx = lo_i.saturating_sub(i).max(i.saturating_sub(hi_i)) as f64;
            let dy = lo_j.saturating_sub(j).max(j.saturating_sub(hi_j)) as f64;
            let (a, b) = if dx > dy { (dx, dy) } else { (dy, dx) };
            res * ((a - b) + b * std::f64::consts::SQRT_2)
        };
        self.heap.clear();
        self.stamp[start] = gen_;
        self.g[start] = 0.0;
        self.parent[start] = start as u32;
        self.heap.push(Reverse((h(start).to_bits(), start as u32)));
        while let Some(Reverse((_, cu))) = self.heap.pop() {
            let c = cu as usize;
            if self.closed[c] == gen_ {
                continue;
            }
            self.closed[c] = gen_;
            self.expanded += 1;
            if self.goal[c] == gen_ {
                return Some(self.reconstruct(g, start, c));
            }
            let gc = self.g[c];
            let (ci, cj) = ((c % g.nx) as isize, (c / g.nx) as isize);
            for (d, &(di, dj)) in DIRS.iter().enumerate() {
                let (bi, bj) = (ci + di, cj + dj);
                if bi < 0 || bj < 0 || bi >= g.nx as isize || bj >= g.ny as isize {
                    continue;
                }
                let b = bj as usize * g.nx + bi as usize;
                let w = if d < 4 {
                    g.cost[d][c]
                } else {
                    g.cost[d - 4][b]
                };
                if !w.is_finite() || self.closed[b] == gen_ {
                    continue;
                }
                if g.has_tops && g.edge_for(c, d, min_head).is_none() {
                    continue;
                }
                let nb = gc + w as f64;
                if self.stamp[b] != gen_ || nb < self.g[b] {
                    if self.stamp[b] != gen_ && !limits.allows(g, b) {
                        // Mark as closed so the check runs once per search.
                        self.closed[b] = gen_;
                        continue;
                    }
                    self.stamp[b] = gen_;
                    self.g[b] = nb;
                    self.parent[b] = c as u32;
                    self.heap.push(Reverse(((nb + h(b)).to_bits(), b as u32)));
                }
            }
        }
        None
    }

    fn reconstruct(&self, _g: &PlanGrid, start: usize, goal: usize) -> GridPath {
        let mut cells = vec![goal];
        let mut c = goal;
        while c != start {
            c = self.parent[c] as usize;
            cells.push(c);
        }
        cells.reverse();
        let cost_to = cells.iter().map(|&c| self.g[c]).collect();
        GridPath { cells, cost_to }
    }
}
