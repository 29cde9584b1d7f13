//! The done-when checks on the built-in scene files (pyramid, slalom, playground).

use plamo_planner::{Planner, PlannerSettings, Trajectory};
use plamo_scenes::{Scene, builtin};

fn plan(scene: &Scene, text: &str, start: [f64; 2], s: PlannerSettings) -> Vec<Trajectory> {
    Planner::new(scene.clone(), text, start, s)
        .unwrap()
        .route()
        .to_vec()
}

fn max_ground(t: &Trajectory) -> f64 {
    t.points.iter().map(|p| p.ground).fold(f64::MIN, f64::max)
}

#[test]
fn builtin_pyramid_detours_with_large_c_and_climbs_with_c_zero() {
    let scene = builtin("pyramid").unwrap();
    let start = scene.landmark("west").unwrap().region.center();
    let (hmin, hmax) = scene.terrain.height_range();
    let text = "walk from the west to the east";
    let over = plan(
        &scene,
        text,
        start,
        PlannerSettings {
            slope_preference_c: 0.0,
            ..Default::default()
        },
    );
    let around = plan(
        &scene,
        text,
        start,
        PlannerSettings {
            slope_preference_c: 10.0,
            ..Default::default()
        },
    );
    let top = hmin + 0.5 * (hmax - hmin);
    assert!(
        max_ground(&over[0]) > top,
        "c = 0 climbs: {}",
        max_ground(&over[0])
    );
    assert!(
        max_ground(&around[0]) < hmin + 0.1 * (hmax - hmin),
        "c = 10 detours: {}",
        max_ground(&around[0])
    );
}

#[test]
fn builtin_slalom_respects_the_lateral_limit_and_slows_into_turns() {
    let scene = builtin("slalom").unwrap();
    let s = PlannerSettings::default();
    let start = scene.landmark("start").unwrap().region.center();
    let t = &plan(&scene, "run from the start to the finish", start, s.clone())[0];
    for q in &t.points {
        assert!(q.v * q.v * q.curvature <= s.a_lat * 1.001 + 1e-6);
    }
    // At every sharp turn (kappa local maximum above 0.5 1/m) the speed is lower than
    // somewhere in the 6 m before it.
    let mut turns = 0;
    let p = &t.points;
    for i in 1..p.len() - 1 {
        let k = p[i].curvature;
        if k > 0.5 && k >= p[i - 1].curvature && k > p[i + 1].curvature {
            turns += 1;
            let before = p
                .iter()
                .filter(|q| q.s < p[i].s && q.s > p[i].s - 6.0)
                .map(|q| q.v)
                .fold(0.0, f64::max);
            assert!(
                before > p[i].v,
                "turn at s {}: v {} before {}",
                p[i].s,
                p[i].v,
                before
            );
        }
    }
    assert!(turns >= 4, "{turns} turns");
}

#[test]
fn every_playground_plan_fits_under_every_ceiling() {
    let scene = builtin("playground").unwrap();
    let s = PlannerSettings::default();
    let names = scene
        .landmark_names()
        .iter()
        .map(|n| n.to_string())
        .collect::<Vec<_>>();
    let verbs = ["run", "walk", "sprint", "walk crouching", "crawl"];
    let mut plans = 0;
    for (a, from) in names.iter().enumerate() {
        for (b, to) in names.iter().enumerate() {
            if a == b {
                continue;
            }
            let verb = verbs[(a + b) % verbs.len()];
            let text = format!("{verb} from the {from} to the {to}");
            let start = scene.landmark(from).unwrap().region.center();
            let Ok(p) = Planner::new(scene.clone(), &text, start, s.clone()) else {
                continue;
            };
            plans += 1;
            for t in p.route() {
                for k in 0..=4000 {
                    let w = t.sample_at(t.start_time + t.duration() * k as f64 / 4000.0);
                    if let Some(c) = scene.ceiling_at(w.position[0], w.position[1]) {
                        assert!(
                            w.position[2] <= c - s.head_margin + 1e-6,
                            "{text}: head {} under ceiling {c} at {:?}",
                            w.position[2],
                            w.position
                        );
                    }
                }
            }
        }
    }
    assert!(
        plans >= names.len() * (names.len() - 1) / 2,
        "{plans} plans"
    );
}

#[test]
fn stand_step_speed_caps_a_walk_on_the_stairs_and_nowhere_else() {
    let scene = builtin("terrain-stairs").unwrap();
    let start = scene.landmark("start").unwrap().region.center();
    let text = "walk from the start to the goal";
    // The default planner caps; 0 turns the cap off.
    let cap = PlannerSettings::default().stand_step_speed;
    assert!(cap > 0.0, "the cap is off by default");
    let capped = &plan(&scene, text, start, PlannerSettings::default())[0];
    let free = &plan(
        &scene,
        text,
        start,
        PlannerSettings {
            stand_step_speed: 0.0,
            ..Default::default()
        },
    )[0];
    // A riser lies under a point where the ground changes by more than a cell's
    // worth of a smooth slope between neighbouring path points.
    let on_riser = |t: &Trajectory, i: usize| {
        i > 0 && (t.points[i].ground - t.points[i - 1].ground).abs() > 0.08
    };
    let risers = (0..capped.points.len())
        .filter(|&i| on_riser(capped, i))
        .count();
    assert!(risers >= 10, "{risers} riser points");
    for (i, p) in capped.points.iter().enumerate() {
        if on_riser(capped, i) {
            assert!(p.v <= cap + 1e-6, "s {}: v {} on a riser", p.s, p.v);
        }
    }
    let top = |t: &Trajectory| t.points.iter().map(|p| p.v).fold(0.0, f64::max);
    assert!(
        top(capped) > cap + 0.3,
        "landings still faster: {}",
        top(capped)
    );
    let free_on_risers = (0..free.points.len())
        .filter(|&i| on_riser(free, i))
        .map(|i| free.points[i].v)
        .fold(0.0, f64::max);
    assert!(free_on_risers > cap + 0.2, "uncapped: {free_on_risers}");
}
