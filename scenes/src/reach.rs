//! Reachability on the terrain grid: a flood fill that the scene checks use to make
//! sure every landmark can be reached (at least by crawling). The planner may reuse
//! it, or replace it with its own A* graph.

use std::collections::VecDeque;

use crate::Scene;

/// The rules of a passable move between grid cells.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReachRules {
    /// Smallest free height under a ceiling \[m\] (default 0.5: crawling).
    pub min_headroom: f64,
    /// Largest height difference between neighbouring cells \[m\] (default 0.2).
    pub max_step: f64,
}

impl Default for ReachRules {
    fn default() -> Self {
        Self {
            min_headroom: 0.5,
            max_step: 0.2,
        }
    }
}

/// Per-cell passability of a scene's terrain grid, `cells[j * nx + i]`: not inside a
/// wall and enough headroom under any ceiling.
pub fn passable_cells(scene: &Scene, rules: &ReachRules) -> Vec<bool> {
    let g = &scene.terrain;
    let mut pass = vec![true; g.nx * g.ny];
    let mut mark = |lo: [f64; 2], hi: [f64; 2], f: &dyn Fn(usize, f64, f64) -> bool| {
        let r = g.resolution;
        let i0 = ((lo[0] - g.origin[0]) / r).floor().max(0.0) as usize;
        let j0 = ((lo[1] - g.origin[1]) / r).floor().max(0.0) as usize;
        let i1 = (((hi[0] - g.origin[0]) / r).ceil().max(0.0) as usize).min(g.nx - 1);
        let j1 = (((hi[1] - g.origin[1]) / r).ceil().max(0.0) as usize).min(g.ny - 1);
        for j in j0..=j1 {
            for i in i0..=i1 {
                let [x, y] = g.position(i, j);
                let k = j * g.nx + i;
                if f(k, x, y) {
                    pass[k] = false;
                }
            }
        }
    };
    for w in &scene.walls {
        let (lo, hi) = w.footprint.aabb();
        mark(lo, hi, &|_, x, y| w.footprint.contains(x, y));
    }
    for t in &scene.tops {
        let (lo, hi) = t.footprint.aabb();
        mark(lo, hi, &|k, x, y| {
            t.footprint.contains(x, y) && t.z_bottom - g.heights[k] < rules.min_headroom
        });
    }
    pass
}

/// Cells reachable from `starts` (grid indices (i, j)) by 8-connected moves between
/// passable cells whose heights differ by at most `rules.max_step`; a diagonal move
/// also needs both cells beside it passable (no corner cutting). Returns
/// `reached[j * nx + i]`.
pub fn flood_fill(scene: &Scene, rules: &ReachRules, starts: &[(usize, usize)]) -> Vec<bool> {
    let pass = passable_cells(scene, rules);
    flood_fill_with(scene, rules, &pass, starts)
}

fn flood_fill_with(
    scene: &Scene,
    rules: &ReachRules,
    pass: &[bool],
    starts: &[(usize, usize)],
) -> Vec<bool> {
    let g = &scene.terrain;
    let (nx, ny) = (g.nx as isize, g.ny as isize);
    let mut seen = vec![false; g.nx * g.ny];
    let mut queue = VecDeque::new();
    for &(i, j) in starts {
        let k = j * g.nx + i;
        if i < g.nx && j < g.ny && pass[k] && !seen[k] {
            seen[k] = true;
            queue.push_back((i as isize, j as isize));
        }
    }
    let idx = |i: isize, j: isize| (j * nx + i) as usize;
    let step_ok = |a: usize, b: usize| (g.heights[a] - g.heights[b]).abs() <= rules.max_step;
    while let Some((i, j)) = queue.pop_front() {
        let here = idx(i, j);
        for (di, dj) in [
            (1, 0),
            (-1, 0),
            (0, 1),
            (0, -1),
            (1, 1),
            (1, -1),
            (-1, 1),
            (-1, -1),
        ] {
            let (a, b) = (i + di, j + dj);
            if a < 0 || b < 0 || a >= nx || b >= ny {
                continue;
            }
            let there = idx(a, b);
            if seen[there] || !pass[there] || !step_ok(here, there) {
                continue;
            }
            if di != 0 && dj != 0 {
                let (s1, s2) = (idx(a, j), idx(i, b));
                if !pass[s1] || !pass[s2] || !step_ok(here, s1) || !step_ok(here, s2) {
                    continue;
                }
            }
            seen[there] = true;
            queue.push_back((a, b));
        }
    }
    seen
}

/// Whether `to` can be reached from `from` (world XY \[m\]) under the default
/// [`ReachRules`]. Points off the terrain are unreachable.
pub fn reachable(scene: &Scene, from: [f64; 2], to: [f64; 2]) -> bool {
    let g = &scene.terrain;
    let (Some(a), Some(b)) = (g.cell_of(from[0], from[1]), g.cell_of(to[0], to[1])) else {
        return false;
    };
    flood_fill(scene, &ReachRules::default(), &[a])[b.1 * g.nx + b.0]
}

/// Check that every landmark can be reached from the first one; on failure returns
/// the pair (0, k) of landmark indices that is not connected.
pub fn landmarks_connected(scene: &Scene, rules: &ReachRules) -> Result<(), (usize, usize)> {
    let Some(first) = scene.landmarks.first() else {
        return Ok(());
    };
    let g = &scene.terrain;
    let reached = flood_fill(scene, rules, &scene.landmark_cells(first));
    for (k, l) in scene.landmarks.iter().enumerate().skip(1) {
        if !scene
            .landmark_cells(l)
            .iter()
            .any(|&(i, j)| reached[j * g.nx + i])
        {
            return Err((0, k));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Footprint, HeightGrid, TopObstacle, Wall};

    fn scene() -> Scene {
        Scene {
            name: "t".into(),
            description: String::new(),
            terrain: HeightGrid::flat([0.0, 0.0], [10.0, 4.0], 0.1, 0.0),
            walls: vec![],
            dynamic: vec![],
            tops: vec![],
            landmarks: vec![],
        }
    }

    fn wall_across(x: f64) -> Wall {
        Wall {
            name: "w".into(),
            footprint: Footprint::axis_aligned([x, 2.0], [0.1, 2.5]),
            z_min: -0.1,
            z_max: 2.0,
        }
    }

    #[test]
    fn a_wall_across_the_strip_cuts_it() {
        let mut s = scene();
        assert!(reachable(&s, [1.0, 1.0], [9.0, 3.0]));
        s.walls.push(wall_across(5.0));
        assert!(!reachable(&s, [1.0, 1.0], [9.0, 3.0]));
        assert!(reachable(&s, [1.0, 1.0], [4.0, 3.0]));
    }

    #[test]
    fn a_one_cell_thick_diagonal_wall_does_not_leak() {
        let mut s = scene();
        // Cells on the diagonal i == j blocked by tiny walls: corners only touch.
        for k in 0..41 {
            let p = s.terrain.position(k, k);
            s.walls.push(Wall {
                name: String::new(),
                footprint: Footprint::axis_aligned(p, [0.04, 0.04]),
                z_min: 0.0,
                z_max: 1.0,
            });
        }
        // (0.2, 3.8) is above the diagonal, (3.8, 0.2) below, and the diagonal runs
        // to the top edge at x = 4.
        assert!(!reachable(&s, [0.2, 3.8], [3.8, 0.2]));
    }

    #[test]
    fn low_ceilings_block_below_the_headroom_rule_only() {
        let mut s = scene();
        let top = |z_bottom| TopObstacle {
            name: "t".into(),
            footprint: Footprint::axis_aligned([5.0, 2.0], [1.0, 2.5]),
            z_bottom,
            z_top: z_bottom + 0.2,
        };
        s.tops.push(top(0.6));
        assert!(
            reachable(&s, [1.0, 1.0], [9.0, 3.0]),
            "0.6 m: crawl through"
        );
        s.tops[0] = top(0.4);
        assert!(!reachable(&s, [1.0, 1.0], [9.0, 3.0]), "0.4 m: too low");
    }

    #[test]
    fn steps_higher_than_the_rule_block() {
        let mut s = scene();
        for j in 0..s.terrain.ny {
            for i in 50..s.terrain.nx {
                s.terrain.heights[j * s.terrain.nx + i] = 0.25;
            }
        }
        assert!(!reachable(&s, [1.0, 1.0], [9.0, 3.0]));
        let lenient = ReachRules {
            max_step: 0.3,
            ..ReachRules::default()
        };
        let a = s.terrain.cell_of(1.0, 1.0).unwrap();
        let (i, j) = s.terrain.cell_of(9.0, 3.0).unwrap();
        assert!(flood_fill(&s, &lenient, &[a])[j * s.terrain.nx + i]);
        assert!(!reachable(&s, [1.0, 1.0], [20.0, 3.0]), "off the terrain");
    }
}
