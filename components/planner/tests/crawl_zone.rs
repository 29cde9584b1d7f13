//! A leg whose straight line runs under a 3 m x 3 m top, at 0.6 m (a crawl there) or
//! 0.9 m (a crouch): with `crawl_zone_cost` and `stoop_zone_cost` a walk goes around
//! the top, a leg already that low is not affected, and where no way leads around
//! the route still goes under it. A walk into a landmark half under a low top ends
//! in its open half with `stand_at_goal`.

use plamo_planner::{PlanGrid, Planner, PlannerSettings, Trajectory};
use plamo_scenes::{Footprint, HeightGrid, Landmark, Region, Scene, TopObstacle, Wall};

/// A 24 m x 12 m flat field, landmarks west (3, 6) and east (21, 6), a top over
/// (12, 6) `clearance` \[m\] above the ground; with `fenced`, walls from the top's
/// north and south sides to the field's edges leave the way under it the only one.
fn field(clearance: f64, fenced: bool) -> Scene {
    let circle = |name: &str, c: [f64; 2]| Landmark {
        name: name.into(),
        region: Region::Circle {
            center: c,
            radius: 1.0,
        },
    };
    let wall = |name: &str, y0: f64, y1: f64| Wall {
        name: name.into(),
        footprint: Footprint::axis_aligned([12.0, 0.5 * (y0 + y1)], [0.15, 0.5 * (y1 - y0)]),
        z_min: -1.0,
        z_max: 2.0,
    };
    Scene {
        name: "field".into(),
        description: "a low top across the straight line between two landmarks".into(),
        terrain: HeightGrid::flat([0.0, 0.0], [24.0, 12.0], 0.1, 0.0),
        walls: if fenced {
            vec![wall("north", 7.5, 12.0), wall("south", 0.0, 4.5)]
        } else {
            vec![]
        },
        dynamic: vec![],
        tops: vec![TopObstacle {
            name: "shed".into(),
            footprint: Footprint::axis_aligned([12.0, 6.0], [1.5, 1.5]),
            z_bottom: clearance,
            z_top: clearance + 0.2,
        }],
        landmarks: vec![circle("west", [3.0, 6.0]), circle("east", [21.0, 6.0])],
    }
}

fn plan(scene: Scene, form: &str, zone_cost: f64) -> Trajectory {
    let settings = PlannerSettings {
        crawl_zone_cost: zone_cost,
        stoop_zone_cost: zone_cost,
        ..Default::default()
    };
    plan_with(scene, form, settings)
}

/// The leg from west to east in `form` with `settings`.
fn plan_with(scene: Scene, form: &str, settings: PlannerSettings) -> Trajectory {
    let p = Planner::new(
        scene,
        &format!("{form} from the west to the east"),
        [3.0, 6.0],
        settings,
    )
    .unwrap();
    p.route()[0].clone()
}

fn lowest_head(t: &Trajectory) -> f64 {
    t.points
        .iter()
        .map(|p| p.head_height)
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn a_walk_goes_around_a_low_top_when_crawling_costs() {
    let through = plan(field(0.6, false), "walk", 0.0);
    assert!(
        lowest_head(&through) < 0.6,
        "without the cost the walk crawls under the top: lowest head {:.2} m",
        lowest_head(&through)
    );
    let around = plan(field(0.6, false), "walk", 2.0);
    assert!(
        lowest_head(&around) > 1.4,
        "with the cost the walk stays on its feet: lowest head {:.2} m",
        lowest_head(&around)
    );
    // A detour, not a wander: longer, but by less than the crawl zone is wide.
    let (l0, l1) = (through.length(), around.length());
    assert!(l1 > l0 && l1 < l0 + 4.0, "lengths {l0:.2} -> {l1:.2} m");
    // And faster: the crawl and its get-down and get-up are gone.
    assert!(
        around.duration() < through.duration(),
        "durations {:.1} -> {:.1} s",
        through.duration(),
        around.duration()
    );
}

#[test]
fn a_crawl_leg_is_not_charged_for_crawling() {
    assert_eq!(
        plan(field(0.6, false), "crawl", 0.0),
        plan(field(0.6, false), "crawl", 2.0)
    );
}

#[test]
fn with_no_way_around_the_walk_still_crawls_under() {
    let t = plan(field(0.6, true), "walk", 2.0);
    assert!(
        lowest_head(&t) < 0.6,
        "lowest head {:.2} m",
        lowest_head(&t)
    );
    assert_eq!(t, plan(field(0.6, true), "walk", 2.0));
}

#[test]
fn a_walk_goes_around_a_top_it_would_crouch_under_and_a_crouch_walk_does_not() {
    let through = plan(field(0.9, false), "walk", 0.0);
    let lowest = lowest_head(&through);
    assert!(
        (0.75..0.85).contains(&lowest),
        "without the cost the walk crouches under the top: lowest head {lowest:.2} m"
    );
    let around = plan(field(0.9, false), "walk", 2.0);
    assert!(
        lowest_head(&around) > 1.4,
        "with the cost the walk stays upright: lowest head {:.2} m",
        lowest_head(&around)
    );
    assert!(around.length() < through.length() + 3.0);
    assert_eq!(
        plan(field(0.9, false), "crouch-walk", 0.0),
        plan(field(0.9, false), "crouch-walk", 2.0)
    );
}

/// The crawl zone drawn from the tops' rims equals every low cell's disc drawn
/// (the plain rule), for tops of several sizes, one over the field's edge.
#[test]
fn the_crawl_zone_is_every_low_cells_disc() {
    let mut scene = field(0.6, false);
    for (k, (c, half)) in [([2.0, 2.0], [2.5, 1.0]), ([18.0, 9.0], [0.3, 2.0])]
        .into_iter()
        .enumerate()
    {
        scene.tops.push(TopObstacle {
            name: format!("extra{k}"),
            footprint: Footprint::axis_aligned(c, half),
            z_bottom: 0.5,
            z_top: 0.7,
        });
    }
    let s = PlannerSettings::default();
    let g = PlanGrid::build(&scene, &s);
    let low = (s.crawl_switch_height + s.head_margin) as f32;
    let rr = (s.crawl_body_length / g.resolution).ceil() as isize;
    let (nx, ny) = (g.nx as isize, g.ny as isize);
    let mut want = vec![false; g.len()];
    for (c, _) in g.headroom.iter().enumerate().filter(|(_, h)| **h < low) {
        let (ci, cj) = (c as isize % nx, c as isize / nx);
        for j in (cj - rr).max(0)..(cj + rr + 1).min(ny) {
            for i in (ci - rr).max(0)..(ci + rr + 1).min(nx) {
                if (i - ci).pow(2) + (j - cj).pow(2) <= rr * rr {
                    want[(j * nx + i) as usize] = true;
                }
            }
        }
    }
    assert!(want.iter().filter(|&&z| z).count() > 1000);
    assert!(g.crawl_zone == want);
}

fn plan_along_path(scene: Scene, form: &str, along_path: bool) -> Trajectory {
    let settings = PlannerSettings {
        crawl_zone_cost: 0.0,
        stoop_zone_cost: 0.0,
        crawl_reach_along_path: along_path,
        // The goal where the old rule puts it (with it on, it moves out of the zone).
        stand_at_goal: false,
        ..Default::default()
    };
    plan_with(scene, form, settings)
}

#[test]
fn with_crawl_reach_along_path_a_walk_ending_beside_a_low_top_stays_on_its_feet() {
    // The shed moved beside the east landmark: its edge 0.9 m north of the landmark's
    // centre, so the leg ends within a crawler's body length of it but never under it.
    let mut scene = field(0.6, false);
    scene.tops[0].footprint = Footprint::axis_aligned([21.0, 7.4], [1.5, 0.5]);
    let near = plan_along_path(scene.clone(), "walk", false);
    assert!(
        lowest_head(&near) < 0.6,
        "measured from the top, the walk crawls beside it: lowest head {:.2} m",
        lowest_head(&near)
    );
    let along = plan_along_path(scene, "walk", true);
    assert!(
        lowest_head(&along) > 1.4,
        "measured along the path, it walks to the end: lowest head {:.2} m",
        lowest_head(&along)
    );
}

#[test]
fn with_crawl_reach_along_path_the_head_is_down_a_body_length_before_the_top() {
    // Fenced: the walk must pass under the shed (x 10.5-13.5).
    let t = plan_along_path(field(0.6, true), "walk", true);
    let s = PlannerSettings::default();
    let edge = t
        .points
        .iter()
        .find(|p| p.x >= 10.5 - s.character_radius)
        .unwrap()
        .s;
    let before: Vec<_> = t
        .points
        .iter()
        .filter(|p| p.s >= edge - s.crawl_body_length + 0.05 && p.s <= edge)
        .collect();
    assert!(!before.is_empty());
    for p in before {
        assert!(
            p.head_height < s.crawl_switch_height,
            "{:.2} m before the top's edge the head is at {:.2} m",
            edge - p.s,
            p.head_height
        );
    }
    assert!(lowest_head(&t) < 0.6);
}

/// The walk from the west into the east landmark, whose north half lies under a
/// 0.6 m top (y 6-10), with `stand_at_goal` as given.
fn plan_into_half_covered(stand_at_goal: bool) -> Trajectory {
    let mut scene = field(0.6, false);
    scene.tops[0].footprint = Footprint::axis_aligned([21.0, 8.0], [2.0, 2.0]);
    // Without the zone costs, which would keep the goal off the top's edge too.
    let settings = PlannerSettings {
        stand_at_goal,
        crawl_zone_cost: 0.0,
        stoop_zone_cost: 0.0,
        ..Default::default()
    };
    plan_with(scene, "walk", settings)
}

#[test]
fn with_stand_at_goal_a_walk_into_a_landmark_half_under_a_low_top_ends_on_its_feet() {
    let anywhere = plan_into_half_covered(false);
    let end = anywhere.points.last().unwrap();
    assert!(
        end.head_height < 0.6,
        "ending at the nearest deep cell, by the top's edge, the walk crawls: head {:.2} m \
         at ({:.2}, {:.2})",
        end.head_height,
        end.x,
        end.y
    );
    let standing = plan_into_half_covered(true);
    let end = standing.points.last().unwrap();
    assert!(
        lowest_head(&standing) > 1.4,
        "the walk ends in the landmark's open half, never crawling: lowest head {:.2} m, \
         end ({:.2}, {:.2})",
        lowest_head(&standing),
        end.x,
        end.y
    );
    assert!(
        (end.x - 21.0).hypot(end.y - 6.0) <= 1.0 - PlannerSettings::default().goal_depth + 0.1,
        "still {:.2} m deep in the landmark: ({:.2}, {:.2})",
        PlannerSettings::default().goal_depth,
        end.x,
        end.y
    );
}
