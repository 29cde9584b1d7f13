//! A run leg whose straight line crosses a wall through a 1 m gap under a 0.6 m
//! ceiling at about 40 degrees (the playground's tunnel, built in code): the plan must
//! suit a crawler, a body ~1.3 m long on hands and knees that gets down and up nearly
//! on the spot and turns slowly.

use plamo_planner::{PathPoint, Planner, PlannerSettings, Trajectory};
use plamo_scenes::{Footprint, HeightGrid, Landmark, Region, Scene, TopObstacle, Wall};

const WALL_X: f64 = 9.0;
const GAP_Y: f64 = 20.3;

fn wall(name: &str, y0: f64, y1: f64) -> Wall {
    Wall {
        name: name.into(),
        footprint: Footprint::axis_aligned([WALL_X, 0.5 * (y0 + y1)], [0.15, 0.5 * (y1 - y0)]),
        z_min: -1.0,
        z_max: 1.8,
    }
}

fn tunnel_scene() -> Scene {
    let circle = |name: &str, c: [f64; 2], r: f64| Landmark {
        name: name.into(),
        region: Region::Circle {
            center: c,
            radius: r,
        },
    };
    Scene {
        name: "tunnel".into(),
        description: "a fence with a 1 m gap under a 0.6 m ceiling".into(),
        terrain: HeightGrid::flat([0.0, 0.0], [20.0, 30.0], 0.1, 0.0),
        walls: vec![
            wall("fence-north", GAP_Y + 0.5, 30.0),
            wall("fence-south", 10.0, GAP_Y - 0.5),
        ],
        dynamic: vec![],
        tops: vec![TopObstacle {
            name: "tunnel".into(),
            footprint: Footprint::axis_aligned([WALL_X, GAP_Y + 0.1], [2.0, 0.8]),
            z_bottom: 0.6,
            z_top: 0.9,
        }],
        landmarks: vec![
            circle("tree", [3.5, 26.0], 1.2),
            circle("car", [15.0, 14.0], 1.0),
        ],
    }
}

/// The run's plan, crawling through the gap: the fence ends at y = 10, and with
/// the default `crawl_zone_cost` the run goes around it instead (tests/crawl_zone.rs).
fn plan(settings: PlannerSettings) -> Trajectory {
    let p = Planner::new(
        tunnel_scene(),
        "run from the tree to the car",
        [3.5, 26.0],
        PlannerSettings {
            crawl_zone_cost: 0.0,
            ..settings
        },
    )
    .unwrap();
    p.route()[0].clone()
}

/// Largest angle between the path and the wall's normal (X) over the points whose
/// head is within `reach` of the wall's plane \[deg\].
fn worst_crossing_angle(t: &Trajectory, reach: f64) -> f64 {
    let pts = &t.points;
    (1..pts.len())
        .filter(|&i| (pts[i].x - WALL_X).abs() <= reach)
        .map(|i| {
            let (dx, dy) = (pts[i].x - pts[i - 1].x, pts[i].y - pts[i - 1].y);
            dy.abs().atan2(dx.abs()).to_degrees()
        })
        .fold(0.0, f64::max)
}

fn distance_to_tunnel(p: &PathPoint) -> f64 {
    tunnel_scene().tops[0].footprint.signed_distance(p.x, p.y)
}

#[test]
fn a_diagonal_gap_is_crossed_on_a_straight_lead_in() {
    let t = plan(PlannerSettings::default());
    // Through the gap.
    assert!(
        t.points
            .iter()
            .any(|p| (p.x - WALL_X).abs() < 0.1 && (p.y - GAP_Y).abs() < 0.3)
    );
    // Without the crawling body's footprint (a body of no length) the same route
    // cuts the gap at about 40 degrees.
    let bare = plan(PlannerSettings {
        crawl_body_length: 0.01,
        ..Default::default()
    });
    let bare_angle = worst_crossing_angle(&bare, 0.6);
    assert!(bare_angle > 35.0, "bare crossing {bare_angle:.1} deg");
    let angle = worst_crossing_angle(&t, 0.6);
    assert!(
        angle < 30.0,
        "crossing {angle:.1} deg from square (bare {bare_angle:.1})"
    );
    // Deterministic.
    assert_eq!(t, plan(PlannerSettings::default()));
}

#[test]
fn the_crawl_through_the_gap_is_down_before_the_tunnel_and_slow() {
    let s = PlannerSettings::default();
    let t = plan(s.clone());
    let pts = &t.points;
    // Crawling (head below the switch) from a body length before the tunnel on.
    for p in pts
        .iter()
        .filter(|p| distance_to_tunnel(p) <= s.crawl_body_length)
    {
        assert!(
            p.head_height < s.crawl_switch_height,
            "head {:.2} m at ({:.2}, {:.2}), {:.2} m from the tunnel",
            p.head_height,
            p.x,
            p.y,
            distance_to_tunnel(p)
        );
    }
    let crawl: Vec<&PathPoint> = pts
        .iter()
        .filter(|p| p.head_height < s.crawl_switch_height)
        .collect();
    assert!(!crawl.is_empty());
    for p in &crawl {
        // A crawl's top speed, and its turn rate.
        assert!(p.v <= s.crawl_speed + 1e-9, "{:.2} m/s crawling", p.v);
        assert!(
            p.v * p.curvature <= s.crawl_turn_rate + 1e-6,
            "turning {:.2} rad/s at ({:.2}, {:.2})",
            p.v * p.curvature,
            p.x,
            p.y
        );
    }
    // Slow where the body gets down and where it gets up again.
    let first_down = pts
        .iter()
        .position(|p| p.head_height < s.crawl_switch_height)
        .unwrap();
    assert!(pts[first_down].v <= s.form_change_speed + 1e-9);
    let first_up = (first_down..pts.len())
        .find(|&i| pts[i].head_height > s.stand_switch_height)
        .expect("stands up after the tunnel");
    assert!(pts[first_up].v <= s.form_change_speed + 1e-9);
}

/// A 0.12 m step (x >= 10) beside a crawl leg whose straight line runs 0.1 m from
/// its edge.
fn step_scene() -> Scene {
    let mut terrain = HeightGrid::flat([0.0, 0.0], [20.0, 20.0], 0.1, 0.0);
    for j in 0..terrain.ny {
        for i in 0..terrain.nx {
            if terrain.position(i, j)[0] >= 10.0 - 1e-9 {
                terrain.heights[j * terrain.nx + i] = 0.12;
            }
        }
    }
    let circle = |name: &str, c: [f64; 2]| Landmark {
        name: name.into(),
        region: Region::Circle {
            center: c,
            radius: 0.5,
        },
    };
    Scene {
        name: "step".into(),
        description: "a crawl along a step's edge".into(),
        terrain,
        walls: vec![],
        dynamic: vec![],
        tops: vec![],
        landmarks: vec![circle("car", [9.9, 2.0]), circle("bench", [9.9, 18.0])],
    }
}

/// Mean distance of the path of `form` ("crawl", "walk") from the step's edge over
/// its middle (y in 6..14) \[m\].
fn mean_edge_distance(form: &str, settings: PlannerSettings) -> f64 {
    let p = Planner::new(
        step_scene(),
        &format!("{form} from the car to the bench"),
        [9.9, 2.0],
        settings,
    )
    .unwrap();
    let mid: Vec<f64> = p.route()[0]
        .points
        .iter()
        .filter(|q| (6.0..=14.0).contains(&q.y))
        .map(|q| (q.x - 10.0).abs())
        .collect();
    mid.iter().sum::<f64>() / mid.len() as f64
}

#[test]
fn a_crawl_keeps_off_a_step_edge() {
    let along = mean_edge_distance(
        "crawl",
        PlannerSettings {
            crawl_relief_cost: 0.0,
            ..Default::default()
        },
    );
    assert!(along < 0.25, "without the relief cost: {along:.2} m");
    let off = mean_edge_distance("crawl", PlannerSettings::default());
    assert!(
        off >= 0.45,
        "{off:.2} m from the edge (without the cost {along:.2})"
    );
}

#[test]
fn a_walk_keeps_off_a_step_edge_with_the_stand_relief_cost() {
    let with = |stand_relief_cost| {
        mean_edge_distance(
            "walk",
            PlannerSettings {
                stand_relief_cost,
                ..Default::default()
            },
        )
    };
    // The crawl's cost alone leaves a walk on its straight line.
    let along = with(0.0);
    assert!(along < 0.25, "without the stand relief cost: {along:.2} m");
    let off = with(8.0);
    assert!(
        off >= 0.45,
        "{off:.2} m from the edge (without the cost {along:.2})"
    );
}
