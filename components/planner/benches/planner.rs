//! Planner benchmarks, each next to a baseline measured in the same run:
//! A* (with and without the per-grid ALT landmark bounds, whose precomputation is
//! a group of its own) vs the `pathfinding` crate's astar on the same graph, the
//! same on 20 interior start/goal pairs, the connectivity check
//! vs an exhaustive A* for an unreachable target, the QP vs the forward-backward
//! oracle, a full 4-instruction plan on the playground, and a dynamic re-plan.
//!
//! `cargo bench -p plamo-planner --bench planner`

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use plamo_planner::synthetic::{ball_scene, hills_scene};
use plamo_planner::{
    AStar, AltLandmarks, Components, External, Heuristic, PlanGrid, Planner, PlannerSettings,
    Prediction, SearchLimits, SpeedProblem, forward_backward, plan_wait, predict_conflict,
    solve_speed_qp, solve_speed_socp,
};
use plamo_scenes::{Footprint, Wall, builtin};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const MIN_HEAD: f32 = 0.5;
/// Landmarks of the ALT bound in the A* benches.
const ALT_K: usize = 8;

fn hills() -> (plamo_scenes::Scene, PlanGrid, usize, Vec<usize>) {
    let scene = hills_scene(1000, 3.0);
    let s = PlannerSettings::default();
    let grid = PlanGrid::build(&scene, &s);
    let start = grid.cell_of(2.0, 2.0).unwrap();
    let goals: Vec<usize> = scene
        .landmark_cells(scene.landmark("ne").unwrap())
        .into_iter()
        .map(|(i, j)| j * grid.nx + i)
        .collect();
    (scene, grid, start, goals)
}

fn bench_astar(c: &mut Criterion) {
    let (_scene, grid, start, goals) = hills();
    let mut astar = AStar::default();
    let limits = SearchLimits::default();
    let alt = AltLandmarks::build(&grid, ALT_K);
    let mut g = c.benchmark_group("astar_1000x1000_hills");
    g.sample_size(20);
    g.bench_function("plamo_astar_alt8", |b| {
        b.iter(|| {
            black_box(
                astar
                    .search_with(&grid, start, &goals, MIN_HEAD, &limits, Some(&alt))
                    .unwrap(),
            )
        })
    });
    eprintln!("plamo_astar_alt8: {} expansions", astar.expanded);
    g.bench_function("plamo_astar", |b| {
        b.iter(|| {
            black_box(
                astar
                    .search(&grid, start, &goals, MIN_HEAD, &limits)
                    .unwrap(),
            )
        })
    });
    eprintln!("plamo_astar: {} expansions", astar.expanded);
    // Baseline: pathfinding::astar on the same edges, costs in micrometres (it needs
    // an Ord cost), same heuristic (octile distance + height difference to the goals).
    let heur = Heuristic::new(&grid, &goals).unwrap();
    let mut is_goal = vec![false; grid.len()];
    for &c in &goals {
        is_goal[c] = true;
    }
    let grid = &grid;
    g.bench_function("pathfinding_astar_baseline", |b| {
        b.iter(|| {
            let r = pathfinding::directed::astar::astar(
                &start,
                |&c| {
                    (0..8).filter_map(move |d| {
                        grid.edge_for(c, d, MIN_HEAD)
                            .map(|(n, w)| (n, (w as f64 * 1e6) as u64))
                    })
                },
                |&c| (heur.at_cell(grid, c) * 1e6) as u64,
                |&c| is_goal[c],
            );
            black_box(r.unwrap())
        })
    });
    g.finish();
}

/// The precomputation ALT needs, once per grid (not part of any query above).
fn bench_alt_build(c: &mut Criterion) {
    let (_scene, grid, _, _) = hills();
    let mut g = c.benchmark_group("alt_landmarks_build_1000x1000");
    g.sample_size(10);
    g.bench_function("alt8_build_per_grid", |b| {
        b.iter(|| black_box(AltLandmarks::build(&grid, ALT_K)))
    });
    g.finish();
}

/// 20 fixed start/goal pairs inside the hills grid (at least 10 m from its rim,
/// where the landmarks are): the ALT bound is far looser than for the corner-to-
/// corner query, the harder case for it. One iteration = the 20 searches.
fn bench_astar_interior(c: &mut Criterion) {
    let (_scene, grid, _, _) = hills();
    let alt = AltLandmarks::build(&grid, ALT_K);
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut cell = || {
        let i = rng.random_range(100..900);
        let j = rng.random_range(100..900);
        j * grid.nx + i
    };
    let pairs: Vec<(usize, usize)> = (0..20).map(|_| (cell(), cell())).collect();
    let mut astar = AStar::default();
    let limits = SearchLimits::default();
    let mut g = c.benchmark_group("astar_1000x1000_hills_20_interior_pairs");
    g.sample_size(10);
    for (name, a) in [("plamo_astar_alt8", Some(&alt)), ("plamo_astar", None)] {
        g.bench_function(name, |b| {
            b.iter(|| {
                for &(s, t) in &pairs {
                    black_box(astar.search_with(&grid, s, &[t], MIN_HEAD, &limits, a));
                }
            })
        });
    }
    g.finish();
}

fn bench_unreachable(c: &mut Criterion) {
    let mut scene = hills_scene(1000, 3.0);
    let size = 99.9;
    // Cage the "ne" landmark.
    let (cx, cy) = (size - 2.0, size - 2.0);
    for (ctr, half) in [
        ([cx, cy + 1.5], [1.7, 0.2]),
        ([cx, cy - 1.5], [1.7, 0.2]),
        ([cx - 1.5, cy], [0.2, 1.7]),
        ([cx + 1.5, cy], [0.2, 1.7]),
    ] {
        scene.walls.push(Wall {
            name: "cage".into(),
            footprint: Footprint::axis_aligned(ctr, half),
            z_min: -1.0,
            z_max: 5.0,
        });
    }
    let s = PlannerSettings::default();
    let grid = PlanGrid::build(&scene, &s);
    let comps = Components::build(&grid, MIN_HEAD);
    let start = grid.cell_of(2.0, 2.0).unwrap();
    let goals: Vec<usize> = scene
        .landmark_cells(scene.landmark("ne").unwrap())
        .into_iter()
        .map(|(i, j)| j * grid.nx + i)
        .filter(|&c| grid.passable(c, MIN_HEAD))
        .collect();
    assert!(!comps.connected(start, &goals));
    let mut g = c.benchmark_group("unreachable_1000x1000");
    g.sample_size(10);
    g.bench_function("connectivity_check", |b| {
        b.iter(|| black_box(comps.connected(start, &goals)))
    });
    let mut astar = AStar::default();
    let limits = SearchLimits::default();
    g.bench_function("exhaustive_astar_baseline", |b| {
        b.iter(|| {
            black_box(
                astar
                    .search(&grid, start, &goals, MIN_HEAD, &limits)
                    .is_none(),
            )
        })
    });
    g.finish();
}

fn bench_speed(c: &mut Criterion) {
    let n = 1000;
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut caps: Vec<f64> = vec![16.0; n];
    for _ in 0..8 {
        let c0 = rng.random_range(0..n);
        let kappa: f64 = rng.random_range(0.1..2.0);
        for cap in caps.iter_mut().skip(c0.saturating_sub(15)).take(30) {
            *cap = cap.min(1.0 / kappa);
        }
    }
    let p = SpeedProblem {
        ds: vec![0.1; n - 1],
        b_max: caps,
        b_start: Some(0.0),
        b_end: None,
        accel: 0.5,
        decel: 0.1,
    };
    let mut g = c.benchmark_group("speed_n1000");
    g.bench_function("clarabel_qp", |b| {
        b.iter(|| black_box(solve_speed_qp(&p).unwrap()))
    });
    g.bench_function("clarabel_socp_time_objective", |b| {
        b.iter(|| black_box(solve_speed_socp(&p).unwrap()))
    });
    g.bench_function("forward_backward_baseline", |b| {
        b.iter(|| black_box(forward_backward(&p).unwrap()))
    });
    g.finish();
}

const ROUTE: &str = "Run from the tree to the car, then crawl to the bench then walk to the swing then sprint to the fountain";

fn bench_full_plan(c: &mut Criterion) {
    let scene = builtin("playground").unwrap();
    let start = scene.landmark("tree").unwrap().region.center();
    let s = PlannerSettings::default();
    let mut planner = Planner::new(scene.clone(), ROUTE, start, s.clone()).unwrap();
    let mut g = c.benchmark_group("playground_4_instructions");
    g.sample_size(20);
    g.bench_function("plan_route_grid_built", |b| {
        b.iter(|| black_box(planner.plan_route(start).unwrap()))
    });
    g.bench_function("planner_new_incl_grid_and_labels", |b| {
        b.iter(|| black_box(Planner::new(scene.clone(), ROUTE, start, s.clone()).unwrap()))
    });
    // Baseline: the same without the cost of lowering the head under tops (no
    // per-cell cost maps, the paper's routes through the tunnel).
    let no_head_cost = PlannerSettings {
        crawl_zone_cost: 0.0,
        stoop_zone_cost: 0.0,
        ..s.clone()
    };
    let mut bare = Planner::new(scene.clone(), ROUTE, start, no_head_cost.clone()).unwrap();
    g.bench_function("plan_route_grid_built_no_head_cost", |b| {
        b.iter(|| black_box(bare.plan_route(start).unwrap()))
    });
    g.bench_function("planner_new_no_head_cost", |b| {
        b.iter(|| {
            black_box(Planner::new(scene.clone(), ROUTE, start, no_head_cost.clone()).unwrap())
        })
    });
    g.finish();
}

fn bench_replan(c: &mut Criterion) {
    let s = PlannerSettings::default();
    let probe = Planner::new(
        ball_scene(100.0),
        "run from the a to the b",
        [2.0, 5.0],
        s.clone(),
    )
    .unwrap();
    let x_meet = probe.route()[0].sample_at(7.5).position[0];
    let scene = ball_scene(x_meet);
    let mut planner = Planner::new(
        scene.clone(),
        "run from the a to the b",
        [2.0, 5.0],
        s.clone(),
    )
    .unwrap();
    let old = planner.route()[0].clone();
    let (now, conflict) = (0..600)
        .find_map(|k| {
            let t = k as f64 / 30.0;
            predict_conflict(&old, &scene, &s, t, Prediction::Rules).map(|c| (t, c))
        })
        .unwrap();
    let w = old.sample_at(now);
    let from = [w.position[0], w.position[1]];
    let mut g = c.benchmark_group("dynamic_replan");
    g.bench_function("local_replan", |b| {
        b.iter(|| {
            black_box(
                planner
                    .replan_around(&old, conflict, from, now, Prediction::Rules)
                    .unwrap(),
            )
        })
    });
    g.bench_function("wait_for_ball", |b| {
        b.iter(|| {
            black_box(
                plan_wait(
                    &old,
                    &conflict,
                    &scene,
                    External::NONE,
                    &s,
                    now,
                    Some(from),
                    Prediction::Rules,
                )
                .unwrap(),
            )
        })
    });
    g.bench_function("collision_check_1_5s", |b| {
        b.iter(|| black_box(predict_conflict(&old, &scene, &s, now, Prediction::Rules)))
    });
    g.finish();
}

criterion_group!(
    benches,
    bench_astar,
    bench_alt_build,
    bench_astar_interior,
    bench_unreachable,
    bench_speed,
    bench_full_plan,
    bench_replan
);
criterion_main!(benches);
