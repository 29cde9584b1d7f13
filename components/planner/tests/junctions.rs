//! Where one leg ends at its landmark and the next begins, the route's speed is
//! continuous and no faster than the corner there (a bend of `corner_length`) and a
//! form change allow: a tour that turns back at a landmark slows down for it, one
//! that goes straight on does not.

use plamo_planner::{Planner, PlannerSettings, Trajectory};
use plamo_scenes::builtin;

fn route(text: &str) -> Vec<Trajectory> {
    route_with(text, PlannerSettings::default())
}

fn route_with(text: &str, settings: PlannerSettings) -> Vec<Trajectory> {
    let scene = builtin("playground").unwrap();
    let first = text.split(" from the ").nth(1).unwrap();
    let name = first.split(' ').next().unwrap();
    let start = scene.landmark(name).unwrap().region.center();
    Planner::new(scene, text, start, settings)
        .unwrap()
        .route()
        .to_vec()
}

fn junction(r: &[Trajectory]) -> (f64, f64) {
    let end = r[0].points.last().unwrap().v;
    let start = r[1].points.first().unwrap().v;
    (end, start)
}

#[test]
fn a_u_turn_at_a_landmark_slows_down_and_straight_on_does_not() {
    let s = PlannerSettings::default();
    // Fountain (4, 14) -> sandbox (4, 4) -> fountain: back the way it came.
    let back = route("Walk from the fountain to the sandbox, then walk to the fountain");
    let (end, start) = junction(&back);
    assert!((end - start).abs() < 1e-3, "speed jumps {end} -> {start}");
    let u_turn = (s.a_lat * s.corner_length / (0.75 * std::f64::consts::PI)).sqrt();
    assert!(
        end <= u_turn + 1e-6,
        "U-turn taken at {end} m/s (at most {u_turn})"
    );
    // Sandbox (4, 4) -> fountain (4, 14) -> tree (3.5, 26): straight on.
    let on = route("Walk from the sandbox to the fountain, then walk to the tree");
    let (end, start) = junction(&on);
    assert!((end - start).abs() < 1e-3, "speed jumps {end} -> {start}");
    assert!(end > 1.0, "a straight junction slowed to {end} m/s");
}

#[test]
fn a_form_change_at_a_landmark_is_taken_slowly() {
    let s = PlannerSettings::default();
    let r = route("Walk from the tree to the swing, then crawl to the bench");
    let (end, start) = junction(&r);
    assert!((end - start).abs() < 1e-3, "speed jumps {end} -> {start}");
    assert!(
        end <= s.form_change_speed + 1e-6,
        "walk -> crawl at {end} m/s"
    );
    // The walk leg is timed to slow down for it: its time grows against the same
    // leg planned alone.
    let alone = route("Walk from the tree to the swing");
    assert!(r[0].end_time() > alone[0].end_time() + 0.5);
}

#[test]
fn a_turn_back_beyond_turn_back_angle_meets_at_rest() {
    let back = "Walk from the fountain to the sandbox, then walk to the fountain";
    let on = "Walk from the sandbox to the fountain, then walk to the tree";
    let bend_only = PlannerSettings {
        turn_back_angle: std::f64::consts::PI,
        ..PlannerSettings::default()
    };
    // Back the way it came (about pi, above the default 2 rad): the walk stops at the
    // sandbox and sets off from rest, later than the bend rule alone lets it.
    let (stopped, slow) = (route(back), route_with(back, bend_only.clone()));
    assert_eq!(junction(&stopped), (0.0, 0.0));
    assert!(junction(&slow).0 > 0.1, "{:?}", junction(&slow));
    assert!(stopped[1].end_time() > slow[1].end_time());
    // Straight on: the setting changes nothing.
    let (a, b) = (route(on), route_with(on, bend_only));
    assert_eq!(junction(&a), junction(&b));
    assert_eq!(a[1].end_time(), b[1].end_time());
}
