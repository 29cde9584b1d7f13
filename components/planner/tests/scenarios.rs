//! Done-when scenarios of the planner, on scenes built in code.

use plamo_interfaces::Tick;
use plamo_planner::synthetic::{ball_scene, flat_scene, pyramid_scene, slalom_scene};
use plamo_planner::{
    External, ExternalObstacle, PlanError, PlanStatus, Planner, PlannerInput, PlannerOutput,
    PlannerSettings, Prediction, ReplanReason, Trajectory, UnreachableReason, predict_conflict,
    predict_conflict_with,
};
use plamo_scenes::{Footprint, ObstacleShape, ObstacleState, Region, Scene, Wall};

fn max_ground(t: &Trajectory) -> f64 {
    t.points.iter().map(|p| p.ground).fold(f64::MIN, f64::max)
}

#[test]
fn pyramid_large_c_detours_and_c_zero_goes_over() {
    let scene = pyramid_scene(2.0);
    let over = Planner::new(
        scene.clone(),
        "walk from the west to the east",
        [6.0, 15.0],
        PlannerSettings {
            slope_preference_c: 0.0,
            ..Default::default()
        },
    )
    .unwrap();
    let around = Planner::new(
        scene,
        "walk from the west to the east",
        [6.0, 15.0],
        PlannerSettings {
            slope_preference_c: 10.0,
            ..Default::default()
        },
    )
    .unwrap();
    let (o, a) = (&over.route()[0], &around.route()[0]);
    assert!(
        max_ground(o) > 1.5,
        "c = 0 should climb: max ground {}",
        max_ground(o)
    );
    assert!(
        max_ground(a) < 0.3,
        "large c should detour: max ground {}",
        max_ground(a)
    );
    assert!(a.length() > o.length() + 2.0);
}

#[test]
fn slalom_slows_before_each_turn_and_respects_the_lateral_limit() {
    let s = PlannerSettings::default();
    let p = Planner::new(
        slalom_scene(),
        "run from the start to the finish",
        [2.0, 5.0],
        s.clone(),
    )
    .unwrap();
    let t = &p.route()[0];
    for q in &t.points {
        assert!(
            q.v * q.v * q.curvature <= s.a_lat * 1.001 + 1e-6,
            "lateral {} at s {}",
            q.v * q.v * q.curvature,
            q.s
        );
        assert!(q.v <= s.run_speed + 1e-9);
    }
    // Each wall passage is a turn: the path crosses x = 8, 16, 24, 32. Find the
    // curvature peak near each and check the speed there is below the speed a few
    // metres earlier and within the lateral cap.
    for x_wall in [8.0, 16.0, 24.0, 32.0] {
        let near: Vec<_> = t
            .points
            .iter()
            .filter(|q| (q.x - x_wall).abs() < 3.0)
            .collect();
        let apex = near
            .iter()
            .max_by(|a, b| a.curvature.total_cmp(&b.curvature))
            .unwrap();
        assert!(
            apex.curvature > 0.2,
            "a turn at x {x_wall}: kappa {}",
            apex.curvature
        );
        let before: f64 = t
            .points
            .iter()
            .filter(|q| q.s < apex.s && q.s > apex.s - 6.0)
            .map(|q| q.v)
            .fold(0.0, f64::max);
        assert!(
            before > apex.v + 0.02,
            "slows before the turn at x {x_wall}: before {before} apex {}",
            apex.v
        );
    }
}

fn assert_fits_under_ceilings(scene: &Scene, t: &Trajectory, margin: f64) {
    for q in &t.points {
        if let Some(c) = scene.ceiling_at(q.x, q.y) {
            assert!(
                q.head_z() <= c - margin + 1e-9,
                "head {} under ceiling {} at ({}, {})",
                q.head_z(),
                c,
                q.x,
                q.y
            );
        }
    }
    // Between points too (the controller interpolates).
    for k in 0..2000 {
        let w = t.sample_at(t.start_time + t.duration() * k as f64 / 2000.0);
        if let Some(c) = scene.ceiling_at(w.position[0], w.position[1]) {
            assert!(w.position[2] <= c - margin + 1e-6);
        }
    }
}

#[test]
fn plans_fit_under_every_ceiling() {
    let scene = flat_scene();
    let s = PlannerSettings::default();
    let p = Planner::new(
        scene.clone(),
        "Run from the tree to the car, then crawl to the bench then walk to the swing then sprint to the tree",
        [3.0, 3.0],
        s.clone(),
    )
    .unwrap();
    assert_eq!(p.route().len(), 4);
    let mut under = 0;
    for t in p.route() {
        assert_fits_under_ceilings(&scene, t, s.head_margin);
        // 0.9 m: too low to stand under `stoop_margin`, room for a crouch
        // `head_margin` under it.
        for q in t
            .points
            .iter()
            .filter(|q| scene.ceiling_at(q.x, q.y).is_some())
        {
            assert!(q.head_height <= s.crouch_height + 1e-9, "{q:?}");
            under += usize::from(q.head_height > s.crawl_switch_height);
        }
    }
    assert!(
        under > 10,
        "the route does not cross the 0.9 m roof crouched"
    );
}

#[test]
fn a_body_on_its_feet_keeps_the_stoop_margin_under_a_roof() {
    let mut scene = flat_scene();
    scene.tops[0].z_bottom = 1.2;
    let s = PlannerSettings::default();
    let p = Planner::new(
        scene.clone(),
        "Walk from the car to the swing",
        [25.0, 15.0],
        s.clone(),
    )
    .unwrap();
    let mut under = 0;
    for q in p.route()[0].points.iter() {
        if scene.ceiling_at(q.x, q.y).is_some() {
            // 1.2 - 0.25 = 0.95 m leaves room for a crouch, not a crawl.
            assert!((q.head_height - s.crouch_height).abs() < 1e-9, "{q:?}");
            under += 1;
        }
    }
    assert!(under > 10, "the walk does not pass under the roof");
}

#[test]
fn legs_end_inside_their_landmarks() {
    let scene = flat_scene();
    let text = "Walk from the tree to the bench, then walk to the car, then crawl to the swing";
    let depths = |goal_depth: f64| -> Vec<f64> {
        let s = PlannerSettings {
            goal_depth,
            ..Default::default()
        };
        let p = Planner::new(scene.clone(), text, [3.0, 3.0], s).unwrap();
        p.route()
            .iter()
            .zip(["bench", "car", "swing"])
            .map(|(t, target)| {
                let Region::Circle { center, radius } = scene.landmark(target).unwrap().region
                else {
                    panic!("{target} is a circle")
                };
                let end = t.points.last().unwrap();
                radius - (end.x - center[0]).hypot(end.y - center[1])
            })
            .collect()
    };
    // Circles of radius 0.5 and 0.8: 0.4 m inside, within a grid cell.
    let deep = depths(0.4);
    assert!(deep.iter().all(|&d| d >= 0.3), "{deep:?}");
    // 0 ends a leg on the region's edge, as A* first meets it.
    let edge = depths(0.0);
    assert!(edge.iter().any(|&d| d < 0.15), "{edge:?}");
}

#[test]
fn unreachable_target_fails_fast_naming_the_instruction() {
    let mut scene = flat_scene();
    // Box in the bench.
    for (c, h) in [
        ([25.0, 4.5], [1.5, 0.2]),
        ([25.0, 1.5], [1.5, 0.2]),
        ([23.5, 3.0], [0.2, 1.5]),
        ([26.5, 3.0], [0.2, 1.5]),
    ] {
        scene.walls.push(Wall {
            name: "cage".into(),
            footprint: Footprint::axis_aligned(c, h),
            z_min: -1.0,
            z_max: 2.0,
        });
    }
    let err = Planner::new(
        scene,
        "walk to the car then run to the bench",
        [3.0, 3.0],
        PlannerSettings::default(),
    )
    .unwrap_err();
    match &err {
        PlanError::Unreachable {
            index,
            target,
            reason,
            ..
        } => {
            assert_eq!(*index, 1);
            assert_eq!(target, "bench");
            assert_eq!(*reason, UnreachableReason::Disconnected);
        }
        other => panic!("{other:?}"),
    }
    assert!(err.to_string().contains("instruction 1"));
}

/// The runner of the corridor crosses the line of a ball rolling across it (along +Y,
/// 2 m/s, at y = 5 when t = 2.5 + 5k s), put where the runner's plan is at t = 7.5 s
/// so that they would meet; the humanoid follows the current plan exactly for 12 s.
/// Returns the obstacle re-plans (with the time each was made) and the closest
/// approach of head and ball \[m\].
fn cross_a_rolling_ball(s: &PlannerSettings) -> (Vec<(f64, ReplanReason)>, f64) {
    let probe = Planner::new(
        ball_scene(100.0),
        "run from the a to the b",
        [2.0, 5.0],
        s.clone(),
    )
    .unwrap();
    let x_meet = probe.route()[0].sample_at(7.5).position[0];
    let scene = ball_scene(x_meet);
    let plan = probe.route()[0].clone();
    let mut p = Planner::new(
        scene.clone(),
        "run from the a to the b",
        [2.0, 5.0],
        s.clone(),
    )
    .unwrap();
    assert!(
        (0..300).any(
            |k| predict_conflict(&plan, &scene, s, k as f64 / 30.0, Prediction::Rules).is_some()
        ),
        "the unmodified plan runs into the ball"
    );
    let mut replans = vec![];
    let mut min_gap = f64::INFINITY;
    let mut tick = 0u64;
    while tick < 120 * 12 {
        let now = tick as f64 / 120.0;
        let w = p
            .current()
            .map_or(plan.sample_at(now), |c| c.sample_at(now));
        let input = PlannerInput {
            head: w.position,
            root: [w.position[0], w.position[1], 1.0],
            velocity: [w.speed, 0.0, 0.0],
            obstacles: vec![],
        };
        let out = p.plan_step(Tick(tick), &input).unwrap();
        assert!(
            !matches!(out.status, PlanStatus::Infeasible { .. }),
            "{:?}",
            out.status
        );
        if let Some(r @ (ReplanReason::Obstacle(_) | ReplanReason::Wait(_))) = out.replanned {
            replans.push((now, r));
            let tr = p.current().unwrap();
            assert!(
                predict_conflict(tr, &scene, s, now, Prediction::Rules).is_none(),
                "the new plan is clear of the ball at t = {now}"
            );
        }
        let b = scene.dynamic[0].motion.state_at(now).position;
        min_gap = min_gap.min((b[0] - w.position[0]).hypot(b[1] - w.position[1]));
        tick += 4;
    }
    (replans, min_gap)
}

#[test]
fn dynamic_replan_avoids_a_ball_crossing_the_path() {
    // Detours only, as in the paper.
    let s = PlannerSettings {
        max_wait: 0.0,
        ..Default::default()
    };
    let (replans, min_gap) = cross_a_rolling_ball(&s);
    assert!(!replans.is_empty(), "re-planned around the ball");
    assert!(
        replans
            .iter()
            .all(|(_, r)| matches!(r, ReplanReason::Obstacle(_))),
        "max_wait 0 never waits: {replans:?}"
    );
    // Ball radius 0.3 + character radius 0.3.
    assert!(min_gap > 0.6, "closest approach {min_gap} m");
}

#[test]
fn a_plan_that_waits_lets_the_ball_pass_and_goes_on() {
    // The ball crosses the runner's line 2 m/s across a straight path: stopping
    // short of its line for a moment costs less than a detour behind it.
    let s = PlannerSettings::default();
    let (replans, min_gap) = cross_a_rolling_ball(&s);
    let Some(&(t, ReplanReason::Wait(c))) = replans.first() else {
        panic!("the first obstacle re-plan waits: {replans:?}");
    };
    assert!(
        t < c.time,
        "waits before the predicted contact at {}",
        c.time
    );
    assert!(min_gap > 0.6, "closest approach {min_gap} m");
}

#[test]
fn with_obstacle_sweep_the_detour_passes_behind_a_crossing_ball() {
    // The ball of the test above, its line where the runner's plan meets it.
    let probe = Planner::new(
        ball_scene(100.0),
        "run from the a to the b",
        [2.0, 5.0],
        PlannerSettings::default(),
    )
    .unwrap();
    let x_meet = probe.route()[0].sample_at(7.5).position[0];
    let scene = ball_scene(x_meet);
    // Which side of the ball the first detour crosses its line on, relative to the
    // way the ball moves (> 0: ahead of it, < 0: behind it).
    let side = |sweep: f64| {
        let s = PlannerSettings {
            obstacle_sweep: sweep,
            max_wait: 0.0,
            ..Default::default()
        };
        let mut p = Planner::new(scene.clone(), "run from the a to the b", [2.0, 5.0], s).unwrap();
        let mut tick = 0;
        loop {
            assert!(tick < 120 * 12, "no re-plan around the ball");
            let out = step_on_plan(&mut p, tick);
            if let Some(ReplanReason::Obstacle(c)) = out.replanned {
                let tr = p.current().unwrap();
                let q = tr
                    .points
                    .iter()
                    .min_by(|a, b| (a.x - x_meet).abs().total_cmp(&(b.x - x_meet).abs()))
                    .unwrap();
                let vy = scene.dynamic[0].motion.state_at(c.time).velocity[1];
                return (q.y - c.obstacle_position[1]) * vy.signum();
            }
            tick += 4;
        }
    };
    let swept = side(3.0);
    assert!(swept < -0.6, "behind the ball by {swept} m");
    // Blocked only where the ball is at the conflict, the detour goes ahead of it:
    // the case the sweep is for.
    let point = side(0.0);
    assert!(point > 0.6, "ahead of the ball by {point} m");
}

#[test]
fn obstacle_sweep_leaves_a_way_past_an_obstacle_coming_head_on() {
    // A box the host reports rolling straight at the runner along the corridor: its
    // swept way covers the runner, who must still find a way past it.
    let s = PlannerSettings {
        obstacle_sweep: 3.0,
        ..Default::default()
    };
    let mut p = Planner::new(empty_corridor(), "run from the a to the b", [2.0, 5.0], s).unwrap();
    let cart = ExternalObstacle {
        shape: ObstacleShape::Box {
            half_extents: [0.5, 0.4, 0.5],
        },
        state: ObstacleState {
            position: [20.0, 5.0, 0.5],
            velocity: [-1.5, 0.0, 0.0],
        },
    };
    p.set_external_obstacles(0.0, &[cart]).unwrap();
    let (mut tick, mut replanned, mut finished) = (0, false, false);
    let mut min_gap = f64::INFINITY;
    while tick < 120 * 40 {
        let now = tick as f64 / 120.0;
        let out = step_on_plan(&mut p, tick);
        assert!(
            !matches!(out.status, PlanStatus::Infeasible { .. }),
            "t = {now}: {:?}",
            out.status
        );
        replanned |= matches!(out.replanned, Some(ReplanReason::Obstacle(_)));
        let w = p.current().unwrap().sample_at(now);
        let o = cart.state_at(0.0, now).position;
        min_gap = min_gap.min((w.position[0] - o[0]).hypot(w.position[1] - o[1]));
        if out.status == PlanStatus::Finished {
            finished = true;
            break;
        }
        tick += 4;
    }
    assert!(replanned, "re-planned around the box");
    assert!(finished, "reached b past the box");
    // The box's half-diagonal 0.64 m + character radius 0.3 m.
    assert!(min_gap > 0.64 + 0.3, "closest approach {min_gap} m");
}

#[test]
fn stepping_reaches_every_target_in_order() {
    let scene = flat_scene();
    let mut p = Planner::new(
        scene,
        "walk to the bench then crawl to the car",
        [3.0, 3.0],
        PlannerSettings::default(),
    )
    .unwrap();
    let mut tick = 0u64;
    let mut reached = vec![];
    let mut last_status = PlanStatus::Following;
    while tick < 120 * 400 {
        let now = tick as f64 / 120.0;
        let w = match p.current() {
            Some(c) => c.sample_at(now),
            None => p.route()[0].sample_at(now),
        };
        let out = p
            .plan_step(
                Tick(tick),
                &PlannerInput {
                    head: w.position,
                    velocity: [w.speed, 0.0, 0.0],
                    ..Default::default()
                },
            )
            .unwrap();
        assert_eq!(out.waypoints.len(), 10);
        if out.progress.reached {
            reached.push(out.progress.index);
        }
        last_status = out.status.clone();
        if out.status == PlanStatus::Finished {
            break;
        }
        tick += 4;
    }
    assert_eq!(last_status, PlanStatus::Finished);
    assert_eq!(reached, vec![1, 2]);
}

#[test]
fn landmark_bounds_leave_routes_and_ceilings_unchanged() {
    // ALT only speeds A* up: the same cheapest grid paths (up to ties, which the
    // refiner smooths alike), so the same route lengths, and still under every roof.
    let scene = flat_scene();
    let text = "Run from the tree to the car, then crawl to the bench then walk to the swing then sprint to the tree";
    let plain = Planner::new(scene.clone(), text, [3.0, 3.0], PlannerSettings::default()).unwrap();
    let s = PlannerSettings {
        alt_landmarks: 6,
        ..Default::default()
    };
    let alt = Planner::new(scene.clone(), text, [3.0, 3.0], s.clone()).unwrap();
    for (a, b) in plain.route().iter().zip(alt.route()) {
        assert_fits_under_ceilings(&scene, b, s.head_margin);
        let (la, lb) = (a.length(), b.length());
        assert!((la - lb).abs() < 0.01 * la, "route lengths {la} vs {lb}");
    }
    let pyramid = |alt_landmarks| {
        let p = Planner::new(
            pyramid_scene(2.0),
            "walk from the west to the east",
            [6.0, 15.0],
            PlannerSettings {
                slope_preference_c: 10.0,
                alt_landmarks,
                ..Default::default()
            },
        )
        .unwrap();
        (p.route()[0].length(), max_ground(&p.route()[0]))
    };
    let (l0, g0) = pyramid(0);
    let (l8, g8) = pyramid(8);
    assert!((l0 - l8).abs() < 0.01 * l0, "pyramid detour {l0} vs {l8}");
    assert!(
        g8 < 0.2 && (g0 - g8).abs() < 0.05,
        "detours alike: {g0} vs {g8}"
    );
    let err = Planner::new(
        scene,
        text,
        [3.0, 3.0],
        PlannerSettings {
            alt_landmarks: 33,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(err.to_string().contains("alt_landmarks"), "{err}");
}

/// The 30 m x 10 m corridor of `ball_scene` without its ball: only the host's
/// obstacles move here.
fn empty_corridor() -> Scene {
    let mut scene = ball_scene(0.0);
    scene.dynamic.clear();
    scene
}

fn still(shape: ObstacleShape, x: f64, y: f64) -> ExternalObstacle {
    ExternalObstacle {
        shape,
        state: ObstacleState {
            position: [x, y, 0.7],
            velocity: [0.0; 3],
        },
    }
}

/// One planner step at `tick` with the humanoid exactly on the current plan.
fn step_on_plan(p: &mut Planner, tick: u64) -> PlannerOutput {
    let now = tick as f64 / 120.0;
    let w = match p.current() {
        Some(c) => c.sample_at(now),
        None => p.route()[0].sample_at(now),
    };
    p.plan_step(
        Tick(tick),
        &PlannerInput {
            head: w.position,
            velocity: [w.speed, 0.0, 0.0],
            ..Default::default()
        },
    )
    .unwrap()
}

#[test]
fn host_obstacle_appearing_mid_run_is_avoided() {
    let s = PlannerSettings::default();
    let mut p = Planner::new(
        empty_corridor(),
        "run from the a to the b",
        [2.0, 5.0],
        s.clone(),
    )
    .unwrap();
    let car = ObstacleShape::Box {
        half_extents: [1.0, 0.6, 0.7],
    };
    let mut tick = 0;
    let mut appeared = None;
    let mut replanned = false;
    let mut finished = false;
    let mut min_gap = f64::INFINITY;
    while tick < 120 * 60 {
        let now = tick as f64 / 120.0;
        if appeared.is_none() && now >= 3.0 {
            // A parked car appears on the path 2.5 m ahead of the runner.
            let tr = p.current().unwrap();
            let ahead = tr.sample_at(now).s + 2.5;
            let q = *tr.points.iter().find(|q| q.s >= ahead).unwrap();
            p.set_external_obstacles(now, &[still(car, q.x, q.y)])
                .unwrap();
            appeared = Some([q.x, q.y]);
        }
        let out = step_on_plan(&mut p, tick);
        assert!(
            !matches!(out.status, PlanStatus::Infeasible { .. }),
            "{:?}",
            out.status
        );
        if let Some(ReplanReason::Obstacle(c)) = out.replanned {
            // Numbered after the scene's obstacles (none here).
            assert_eq!(c.obstacle, 0);
            replanned = true;
        }
        if let Some(o) = appeared {
            let w = p.current().unwrap().sample_at(now);
            min_gap = min_gap.min((w.position[0] - o[0]).hypot(w.position[1] - o[1]));
        }
        if out.status == PlanStatus::Finished {
            finished = true;
            break;
        }
        tick += 4;
    }
    assert!(replanned, "re-planned around the car");
    assert!(finished, "reached b past the car");
    // The car's half-diagonal 1.17 m + character radius 0.3 m.
    assert!(min_gap > 1.17 + 0.3, "closest approach {min_gap} m");
}

#[test]
fn host_obstacle_on_the_target_is_reported_not_a_panic() {
    let s = PlannerSettings::default();
    let mut p = Planner::new(
        empty_corridor(),
        "run from the a to the b",
        [2.0, 5.0],
        s.clone(),
    )
    .unwrap();
    // A ball of 1.5 m radius parked on landmark b (radius 0.5 m at (28, 5)).
    let ball = ObstacleShape::Sphere { radius: 1.5 };
    p.set_external_obstacles(0.0, &[still(ball, 28.0, 5.0)])
        .unwrap();
    let mut tick = 0;
    let mut occupied = None;
    while tick < 120 * 30 {
        let out = step_on_plan(&mut p, tick);
        if let PlanStatus::Infeasible { index, reason } = out.status {
            occupied = Some((index, reason));
            break;
        }
        assert_ne!(
            out.status,
            PlanStatus::Finished,
            "cannot finish inside the ball"
        );
        tick += 4;
    }
    let (index, reason) = occupied.expect("the occupied target is reported");
    assert_eq!(index, 0);
    assert_eq!(reason, UnreachableReason::TargetOccupied { obstacle: 0 });
    assert!(reason.to_string().contains("obstacle 0"), "{reason}");
    // The plan kept stays out of the ball until the step that reported it.
    let kept = p.current().unwrap();
    let now = tick as f64 / 120.0;
    let w = kept.sample_at(now);
    assert!((w.position[0] - 28.0).hypot(w.position[1] - 5.0) > 1.5);
    // The host moves the ball away: the next steps plan to the target again.
    p.set_external_obstacles(now, &[still(ball, 28.0, 9.0)])
        .unwrap();
    let out = step_on_plan(&mut p, tick + 4);
    assert!(
        !matches!(out.status, PlanStatus::Infeasible { .. }),
        "{:?}",
        out.status
    );
}

#[test]
fn host_obstacle_covering_the_character_is_reported() {
    let s = PlannerSettings::default();
    let mut p = Planner::new(
        empty_corridor(),
        "run from the a to the b",
        [2.0, 5.0],
        s.clone(),
    )
    .unwrap();
    step_on_plan(&mut p, 0);
    // A 12 m box lands on the runner: no free cell within reach.
    let slab = ObstacleShape::Box {
        half_extents: [6.0, 6.0, 0.5],
    };
    p.set_external_obstacles(1.0 / 30.0, &[still(slab, 2.5, 5.0)])
        .unwrap();
    let out = step_on_plan(&mut p, 4);
    assert_eq!(
        out.status,
        PlanStatus::Infeasible {
            index: 0,
            reason: UnreachableReason::StartOccupied { obstacle: 0 }
        }
    );
}

#[test]
fn bad_host_obstacles_are_rejected_naming_the_obstacle() {
    let mut p = Planner::new(
        empty_corridor(),
        "run from the a to the b",
        [2.0, 5.0],
        PlannerSettings::default(),
    )
    .unwrap();
    let ok = still(ObstacleShape::Sphere { radius: 0.3 }, 10.0, 5.0);
    let mut nan = ok;
    nan.state.position[1] = f64::NAN;
    let err = p.set_external_obstacles(0.0, &[ok, nan]).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("obstacle 1") && msg.contains("position"),
        "{msg}"
    );
    let flat = still(
        ObstacleShape::Box {
            half_extents: [1.0, 0.0, 1.0],
        },
        10.0,
        5.0,
    );
    let msg = p
        .set_external_obstacles(0.0, &[flat])
        .unwrap_err()
        .to_string();
    assert!(msg.contains("obstacle 0") && msg.contains("> 0"), "{msg}");
    let msg = p
        .set_external_obstacles(f64::INFINITY, &[ok])
        .unwrap_err()
        .to_string();
    assert!(msg.contains("time"), "{msg}");
    // Observed states of scene obstacles are checked too.
    let err = p
        .plan_step(
            Tick(0),
            &PlannerInput {
                head: [2.0, 5.0, 1.47],
                obstacles: vec![ObstacleState {
                    position: [1.0, f64::INFINITY, 0.0],
                    velocity: [0.0; 3],
                }],
                ..Default::default()
            },
        )
        .unwrap_err();
    assert!(err.to_string().contains("scene obstacle 0"), "{err}");
    // Rejected sets leave the previous one in place.
    assert!(p.external_obstacles().is_empty());
    p.set_external_obstacles(0.0, &[ok]).unwrap();
    assert_eq!(p.external_obstacles(), &[ok]);
}

/// The pyramid scene's 40 m x 30 m yard with the ground height `ground(x, y)` \[m\].
fn yard(ground: impl Fn(f64, f64) -> f64) -> Scene {
    let mut s = pyramid_scene(0.0);
    let t = &mut s.terrain;
    for j in 0..t.ny {
        for i in 0..t.nx {
            let [x, y] = t.position(i, j);
            t.heights[j * t.nx + i] = ground(x, y);
        }
    }
    s
}

/// The yard flat, but for a berm 0.6 m high across it at x = 20 with faces of
/// `face_deg`, from y = 0 to 26: the way round is through the gap at y 26-30, 7.6 m
/// longer than straight over.
fn berm_scene(face_deg: f64) -> Scene {
    yard(|x, y| {
        if y <= 26.0 {
            (0.6 - (x - 20.0).abs() * face_deg.to_radians().tan()).max(0.0)
        } else {
            0.0
        }
    })
}

#[test]
fn a_face_steeper_than_max_slope_is_walked_around() {
    // Whether the path crosses the berm (x = 20) rather than going round its end.
    let over = |face_deg: f64, slope_baseline: f64| {
        let p = Planner::new(
            berm_scene(face_deg),
            "walk from the west to the east",
            [6.0, 15.0],
            PlannerSettings {
                slope_baseline,
                ..Default::default()
            },
        )
        .unwrap();
        let t = &p.route()[0];
        let at = t
            .points
            .iter()
            .min_by(|a, b| (a.x - 20.0).abs().total_cmp(&(b.x - 20.0).abs()))
            .unwrap();
        at.y < 25.0
    };
    let baseline = PlannerSettings::default().slope_baseline;
    // A 20 degree berm is crossed ...
    assert!(over(20.0, baseline));
    // ... a 60 degree one (max_slope is 40) is not, though it rises 0.17 m per 0.1 m
    // cell: each cell alone is a step under max_step_height, so judged edge by edge
    // (slope_baseline 0) it is crossed.
    assert!(!over(60.0, baseline));
    assert!(over(60.0, 0.0));
}

#[test]
fn a_step_on_a_slope_is_still_a_step() {
    // The yard rises at 20 degrees from x = 18, with a 0.15 m step across it at x = 20
    // (a stair on a ramp, the random scenes' highest riser): no way round. With the
    // ramp's 0.036 m in the step's cell it stays under `max_step_height`.
    let scene = yard(|x, _| {
        let step = if x >= 20.0 { 0.15 } else { 0.0 };
        (x - 18.0).max(0.0) * 20f64.to_radians().tan() + step
    });
    // Over half a baseline the step and the ramp together rise 41 degrees; the step
    // taken out, 20.
    let p = Planner::new(
        scene,
        "walk from the west to the east",
        [6.0, 15.0],
        PlannerSettings::default(),
    );
    assert!(p.is_ok(), "{:?}", p.err());
}

#[test]
fn a_path_keeps_off_a_cliff_as_off_a_wall() {
    // North of y = 15.25 the yard is a plateau 0.4 m up (above max_step_height, so no
    // edge climbs it); the straight way from west to east runs 0.25 m from its foot.
    let scene = yard(|_, y| if y > 15.25 { 0.4 } else { 0.0 });
    let closest = |cliff_clearance: f64| {
        let p = Planner::new(
            scene.clone(),
            "walk from the west to the east",
            [6.0, 15.0],
            PlannerSettings {
                cliff_clearance,
                ..Default::default()
            },
        )
        .unwrap();
        p.route()[0]
            .points
            .iter()
            .filter(|q| (8.0..32.0).contains(&q.x))
            .map(|q| (15.25 - q.y).abs())
            .fold(f64::INFINITY, f64::min)
    };
    let clear = PlannerSettings::default().cliff_clearance;
    assert!(clear >= 0.3);
    // Clearance holds to within half a cell diagonal, as for walls.
    let d = closest(clear);
    assert!(d >= clear - 0.08, "{d} m from the cliff");
    let d = closest(0.0);
    assert!(d < 0.26, "without the clearance: {d} m from the cliff");
}

/// The first leg's plan across the ball corridor (its ball out of the way) in form
/// `verb`, with default settings.
fn corridor_plan(verb: &str) -> Trajectory {
    let instructions = format!("{verb} from the a to the b");
    let planner = Planner::new(
        ball_scene(100.0),
        &instructions,
        [2.0, 5.0],
        PlannerSettings::default(),
    )
    .unwrap();
    planner.route()[0].clone()
}

/// Whether the collision sweep finds a conflict at any control step of the 2 s before
/// `meet`, with the head `lag` metres of path behind the plan.
fn conflict_before(
    plan: &Trajectory,
    scene: &Scene,
    s: &PlannerSettings,
    meet: f64,
    lag: f64,
) -> bool {
    (0..60).any(|k| {
        let now = meet - 2.0 + k as f64 / 30.0;
        // The head where the path is `lag` metres short of the plan's point.
        let at = plan.sample_at_s(plan.sample_at(now).s - lag).position;
        let head = (lag > 0.0).then_some([at[0], at[1]]);
        predict_conflict_with(plan, scene, External::NONE, s, now, head, Prediction::Rules)
            .is_some()
    })
}

#[test]
fn the_sweep_covers_a_crawlers_body_behind_its_head() {
    // The corridor's ball crosses y = 5 at t = 7.5 s (radius 0.3, 2 m/s), on a line
    // 0.9 m behind where the crawl's head is then: the head has crossed it well
    // before (crawls are slower than 1 m/s) and keeps 0.8 m off the ball, the
    // trunk and legs (`crawl_body_length`, 1.3 m behind the head) have not.
    let meet = 7.5;
    let plan = corridor_plan("crawl");
    let w = plan.sample_at(meet);
    assert!(w.head_height < 0.45, "crawling by then: {w:?}");
    let scene = ball_scene(w.position[0] - 0.9);
    let s = PlannerSettings::default();
    assert!(
        conflict_before(&plan, &scene, &s, meet, 0.0),
        "the body behind the head meets the ball"
    );
    // A crawl no longer than the capsule's radius: the capsule at the head only.
    let head_only = PlannerSettings {
        crawl_body_length: s.character_radius,
        ..Default::default()
    };
    assert!(
        !conflict_before(&plan, &scene, &head_only, meet, 0.0),
        "the head alone passed before the ball"
    );
    // A walker's body is under its head: the setting changes nothing for a walk.
    let walk = corridor_plan("walk");
    for behind in [0.3, 0.9, 1.5] {
        let scene = ball_scene(walk.sample_at(meet).position[0] - behind);
        assert_eq!(
            conflict_before(&walk, &scene, &s, meet, 0.0),
            conflict_before(&walk, &scene, &head_only, meet, 0.0),
            "a walk with the ball's line {behind} m behind its head"
        );
    }
}

#[test]
fn the_sweep_follows_a_head_that_lags_its_plan() {
    // A walk whose plan crosses the ball's line 0.75 s before the ball: a head on
    // the plan passes 1 m off it, one 1.5 m behind the plan meets it.
    let meet = 7.5;
    let s = PlannerSettings::default();
    let plan = corridor_plan("walk");
    let w = plan.sample_at(meet);
    assert!(w.speed > 1.5, "walking at full speed by then: {w:?}");
    let scene = ball_scene(w.position[0] - 1.5);
    assert!(
        !conflict_before(&plan, &scene, &s, meet, 0.0),
        "a head on its plan passes first"
    );
    assert!(
        conflict_before(&plan, &scene, &s, meet, 1.5),
        "a head 1.5 m behind meets the ball"
    );
    let plan_only = PlannerSettings {
        lag_sweep_max: 0.0,
        ..Default::default()
    };
    assert!(
        !conflict_before(&plan, &scene, &plan_only, meet, 1.5),
        "lag_sweep_max 0 sweeps the plan only"
    );
    // The lag the planner measures: how far along the path the plan is ahead of a head.
    let back = plan.sample_at_s(w.s - 1.5);
    let lag = plan.lag_at(meet, back.position[0], back.position[1]);
    assert!((lag - 1.5).abs() < 0.1, "lag {lag}");
}

/// A crawl along the corridor and the corridor's ball crossing its way where its
/// plan is at 7.5 s: the crawl's start plan and the scene.
fn a_crawl_meets_the_ball() -> (Trajectory, Scene) {
    let probe = Planner::new(
        ball_scene(100.0),
        "crawl from the a to the b",
        [2.0, 5.0],
        PlannerSettings::default(),
    )
    .unwrap();
    let plan = probe.route()[0].clone();
    let scene = ball_scene(plan.sample_at(7.5).position[0]);
    (plan, scene)
}

#[test]
fn the_sweep_looks_as_far_ahead_as_a_slow_crawl_needs() {
    // At 5 s the paper's 1.5 s horizon ends with the ball still 2 m off.
    let (plan, scene) = a_crawl_meets_the_ball();
    let now = 5.0;
    let s = PlannerSettings::default();
    let c = predict_conflict(&plan, &scene, &s, now, Prediction::Rules)
        .expect("the crossing is within the crawl's next 3 m");
    assert!(
        c.time > now + s.collision_horizon,
        "found beyond the paper's horizon: {c:?}"
    );
    let paper = PlannerSettings {
        collision_lookahead: 0.0,
        ..Default::default()
    };
    assert_eq!(
        predict_conflict(&plan, &scene, &paper, now, Prediction::Rules),
        None,
        "1.5 s alone misses it"
    );
}

#[test]
fn beyond_the_papers_horizon_a_crawler_only_waits() {
    // The crawler on its plan from the start.
    let (_, scene) = a_crawl_meets_the_ball();
    // The obstacle re-plans of 10 s on the plan: (time, reason).
    let replans = |s: PlannerSettings| {
        let mut p =
            Planner::new(scene.clone(), "crawl from the a to the b", [2.0, 5.0], s).unwrap();
        (0..120 * 10)
            .step_by(4)
            .filter_map(|tick| {
                let r = step_on_plan(&mut p, tick).replanned;
                let now = tick as f64 / 120.0;
                match r {
                    Some(r @ (ReplanReason::Obstacle(_) | ReplanReason::Wait(_))) => Some((now, r)),
                    _ => None,
                }
            })
            .collect::<Vec<_>>()
    };
    let horizon = PlannerSettings::default().collision_horizon;
    let waits = replans(PlannerSettings::default());
    match waits.first() {
        Some(&(now, ReplanReason::Wait(c))) => assert!(
            c.time > now + horizon,
            "waits before the paper's horizon sees the ball: {waits:?}"
        ),
        other => panic!("the first re-plan waits: {other:?}"),
    }
    // Without waiting, the look-ahead's conflicts are left until they come within the
    // horizon: no detour that far ahead.
    let detours = replans(PlannerSettings {
        max_wait: 0.0,
        ..Default::default()
    });
    assert!(!detours.is_empty(), "detours once within the horizon");
    for (now, r) in &detours {
        let ReplanReason::Obstacle(c) = r else {
            panic!("max_wait 0 never waits: {r:?}");
        };
        assert!(c.time <= now + horizon + 1e-9, "{now}: {c:?}");
    }
}

/// Where each lag re-plan's path starts, for a humanoid held still with its head at
/// `head` and its root at `root` for 20 s of a walk down the empty corridor.
fn lag_replan_starts(settings: PlannerSettings, head: [f64; 2], root: [f64; 2]) -> Vec<[f64; 2]> {
    let mut p = Planner::new(empty_corridor(), "walk from the a to the b", head, settings).unwrap();
    let mut starts = Vec::new();
    for tick in 0..120 * 20 {
        let out = p
            .plan_step(
                Tick(tick),
                &PlannerInput {
                    head: [head[0], head[1], 1.5],
                    root: [root[0], root[1], 0.9],
                    ..Default::default()
                },
            )
            .unwrap();
        if out.replanned == Some(ReplanReason::Lag) {
            let first = &p.current().unwrap().points[0];
            starts.push([first.x, first.y]);
        }
    }
    starts
}

#[test]
fn a_head_held_where_it_lagged_before_is_replanned_from_the_root() {
    // The head 0.4 m ahead of the root, as a body pinned at a wall's end leans past it.
    let (head, root) = ([2.4, 5.0], [2.0, 5.0]);
    let near = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-6;
    let on = PlannerSettings {
        stuck_distance: 0.3,
        ..Default::default()
    };
    let starts = lag_replan_starts(on, head, root);
    assert!(starts.len() >= 3, "lag re-plans: {starts:?}");
    // The first lag re-plan has nothing to compare with: from the head.
    assert!(near(starts[0], head), "{starts:?}");
    // Every later one finds the head where it was: from the root.
    assert!(starts[1..].iter().all(|&s| near(s, root)), "{starts:?}");
    let off = lag_replan_starts(
        PlannerSettings {
            stuck_distance: 0.0,
            ..Default::default()
        },
        head,
        root,
    );
    assert!(
        off.iter().all(|&s| near(s, head)),
        "stuck_distance 0: {off:?}"
    );
}
