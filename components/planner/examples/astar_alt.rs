//! A* on the 1000 x 1000 hills grid with and without ALT landmark bounds: build time
//! of the landmarks, expansions and time per query, and the path cost of each (they
//! must agree). Timing here is indicative; the figures in BENCHMARKS.md come from
//! `cargo bench -p plamo-planner --bench planner -- astar_1000`.
//!
//! `cargo run --release -p plamo-planner --example astar_alt [-- K...]`

use std::time::Instant;

use plamo_planner::synthetic::hills_scene;
use plamo_planner::{AStar, AltLandmarks, PlanGrid, PlannerSettings, SearchLimits};

fn main() {
    let ks: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("landmark counts are integers"))
        .collect();
    let ks = if ks.is_empty() { vec![4, 8, 16] } else { ks };
    let scene = hills_scene(1000, 3.0);
    for c in [0.0, 1.0] {
        let s = PlannerSettings {
            slope_preference_c: c,
            ..PlannerSettings::default()
        };
        let grid = PlanGrid::build(&scene, &s);
        let start = grid.cell_of(2.0, 2.0).unwrap();
        let goals: Vec<usize> = scene
            .landmark_cells(scene.landmark("ne").unwrap())
            .into_iter()
            .map(|(i, j)| j * grid.nx + i)
            .collect();
        let limits = SearchLimits::default();
        let mut astar = AStar::default();
        let time = |astar: &mut AStar, alt: Option<&AltLandmarks>| {
            let mut best = f64::INFINITY;
            let mut cost = 0.0;
            for _ in 0..5 {
                let t = Instant::now();
                let p = astar
                    .search_with(&grid, start, &goals, 0.5, &limits, alt)
                    .unwrap();
                best = best.min(t.elapsed().as_secs_f64());
                cost = *p.cost_to.last().unwrap();
            }
            (best, cost, astar.expanded)
        };
        let (t, cost, e) = time(&mut astar, None);
        println!(
            "c = {c}: no landmarks: {:.1} ms, {e} expansions, cost {cost:.6} m",
            t * 1e3
        );
        for &k in &ks {
            let t0 = Instant::now();
            let alt = AltLandmarks::build(&grid, k);
            let tb = t0.elapsed().as_secs_f64();
            let (t, cost, e) = time(&mut astar, Some(&alt));
            println!(
                "c = {c}: {k} landmarks (built in {:.0} ms): {:.1} ms, {e} expansions, cost {cost:.6} m",
                tb * 1e3,
                t * 1e3
            );
        }
        // Interior queries: goals nowhere near a landmark, the harder case.
        let mut rng = 0x9e3779b97f4a7c15u64;
        let mut next = |m: usize| {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            (rng % m as u64) as usize
        };
        let pairs: Vec<(usize, usize)> = (0..20)
            .map(|_| {
                let a = (100 + next(800)) * grid.nx + 100 + next(800);
                let b = (100 + next(800)) * grid.nx + 100 + next(800);
                (a, b)
            })
            .collect();
        let alt = AltLandmarks::build(&grid, *ks.last().unwrap());
        for (name, alt) in [("none", None), ("alt", Some(&alt))] {
            let t = Instant::now();
            let (mut e, mut cost) = (0, 0.0);
            for &(a, b) in &pairs {
                let p = astar
                    .search_with(&grid, a, &[b], 0.5, &limits, alt)
                    .unwrap();
                e += astar.expanded;
                cost += p.cost_to.last().unwrap();
            }
            println!(
                "c = {c}: 20 interior pairs, landmarks {name}: {:.1} ms per query, {} expansions per query, total cost {cost:.6} m",
                t.elapsed().as_secs_f64() * 1e3 / 20.0,
                e / 20
            );
        }
    }
}
