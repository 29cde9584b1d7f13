//! Stage 6b: letting a dynamic obstacle pass. The plan keeps its path, comes to rest
//! short of where the obstacle is predicted to cross it, waits until the sweep finds
//! the way clear, and goes on.
//!
//! Not in the paper, whose re-plan only detours. A* has no time dimension: it blocks
//! the obstacle's way for a while (`obstacle_sweep`) and goes around it, which a
//! crawler at 0.3-0.7 m/s cannot do in time when a ball at up to 2 m/s crosses its
//! path (random tours, session 48: 26 of the tours lost in 2000 had touched the ball).

use crate::dynamic::{External, Prediction, predict_conflict_with};
use crate::{Conflict, PathPoint, PlannerSettings, Trajectory};
use plamo_scenes::Scene;

/// How far apart the hold points tried are, back from the obstacle's way \[m\].
const HOLD_STEP: f64 = 0.25;
/// How many hold points are tried.
const HOLD_TRIES: usize = 8;
/// How finely the wait is chosen \[s\].
const WAIT_STEP: f64 = 0.5;

/// `old` from `now` on, brought to rest at its arc length `s_hold`, held there for
/// `wait` seconds, then going on at `old`'s speeds: it brakes at no more than
/// `decel` and starts again at no more than `accel` \[m/s^2\]. `None` when it cannot
/// stop there (`s_hold` behind the plan at `now`, or too close at its speed). Waits
/// `old` held before are dropped; arc length starts at 0 at `now`.
pub(crate) fn hold(
    old: &Trajectory,
    now: f64,
    s_hold: f64,
    wait: f64,
    decel: f64,
    accel: f64,
) -> Option<Trajectory> {
    let here = old.sample_at(now);
    let (s0, v0) = (here.s, here.speed);
    if old.points.is_empty() || s_hold < s0 || v0 * v0 > 2.0 * decel * (s_hold - s0) + 1e-12 {
        return None;
    }
    let mut pts = vec![PathPoint {
        v: v0,
        ..old.point_at_s(s0)
    }];
    let mut push = |p: PathPoint| {
        if p.s > pts.last().map_or(f64::NEG_INFINITY, |q: &PathPoint| q.s) {
            pts.push(p);
        }
    };
    for p in old.points.iter().filter(|p| p.s < s_hold) {
        push(*p);
    }
    let stop = old.point_at_s(s_hold);
    push(stop);
    for p in old.points.iter().filter(|p| p.s > s_hold) {
        push(*p);
    }
    let k_hold = pts.iter().position(|p| p.s >= s_hold)?;
    for p in pts.iter_mut().skip(1) {
        let room = if p.s <= s_hold {
            2.0 * decel * (s_hold - p.s)
        } else {
            2.0 * accel * (p.s - s_hold)
        };
        p.v = p.v.min(room.max(0.0).sqrt());
    }
    // A second point where the first stops: the wait is the time between them.
    pts.insert(
        k_hold + 1,
        PathPoint {
            wait,
            ..pts[k_hold]
        },
    );
    // Two points at rest with road between them would never be left.
    if pts
        .windows(2)
        .any(|w| w[1].s > w[0].s && w[0].v + w[1].v <= 1e-9)
    {
        return None;
    }
    for p in &mut pts {
        p.s -= s0;
    }
    Some(Trajectory::new(now, pts))
}

/// A plan that keeps `old`'s path and lets the obstacle of `conflict` pass: it
/// stops as close before the obstacle's way as the sweep allows and waits as
/// briefly as it can (at most `max_wait`), such that the sweep, keeping
/// `wait_margin` more from the obstacle, finds no conflict until `collision_horizon`
/// after it goes on, nor on the `collision_lookahead` metres past its stop. `None`
/// when no such wait exists or waiting is off (`max_wait` 0).
#[allow(clippy::too_many_arguments)]
pub fn plan_wait(
    old: &Trajectory,
    conflict: &Conflict,
    scene: &Scene,
    external: External,
    s: &PlannerSettings,
    now: f64,
    head: Option<[f64; 2]>,
    how: Prediction,
) -> Option<Trajectory> {
    if s.max_wait <= 0.0 {
        return None;
    }
    let here = old.sample_at(now);
    let s_min = here.s + here.speed * here.speed / (2.0 * s.wait_deceleration);
    let s_conflict = old.sample_at(conflict.time).s;
    let mut sweep = s.clone();
    sweep.obstacle_margin += s.wait_margin;
    let clear = conflict.radius_xy + s.character_radius + sweep.obstacle_margin;
    let waits = (s.max_wait / WAIT_STEP).floor() as usize;
    for k in 0..HOLD_TRIES {
        let s_hold = s_conflict - clear - k as f64 * HOLD_STEP;
        let last = s_hold <= s_min;
        let s_hold = s_hold.max(s_min);
        for j in 1..=waits {
            let wait = j as f64 * WAIT_STEP;
            let tr = hold(old, now, s_hold, wait, s.wait_deceleration, s.a_max)?;
            let k_go = tr.points.iter().position(|p| p.wait > 0.0)?;
            let go = tr.start_time + tr.points[k_go].t;
            // As far past the stop as the sweep looks ahead of a moving plan.
            let past = tr.time_at_s(tr.points[k_go].s + s.collision_lookahead);
            sweep.collision_horizon = (go + s.collision_horizon).max(past) - now;
            match predict_conflict_with(&tr, scene, external, &sweep, now, head, how) {
                None => return Some(tr),
                // Hit before it goes on: waiting longer there does not help.
                Some(c) if c.time <= go => break,
                Some(_) => {}
            }
        }
        if last {
            break;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 20 m straight east at 2 m/s.
    fn straight() -> Trajectory {
        let pts = (0..=200)
            .map(|i| PathPoint {
                x: i as f64 * 0.1,
                s: i as f64 * 0.1,
                head_height: 1.47,
                v_cap: 2.0,
                v: 2.0,
                ..Default::default()
            })
            .collect();
        Trajectory::new(0.0, pts)
    }

    #[test]
    fn a_held_plan_stops_waits_and_goes_on_along_the_same_path() {
        let old = straight();
        // At t = 1 the plan is at s = 2, going 2 m/s: 2 m of braking at 1 m/s^2.
        let tr = hold(&old, 1.0, 6.0, 1.5, 1.0, 0.5).unwrap();
        assert_eq!(tr.start_time, 1.0);
        assert_eq!(tr.points[0].x, 2.0);
        let k = tr.points.iter().position(|p| p.wait > 0.0).unwrap();
        let (stop, go) = (tr.points[k - 1], tr.points[k]);
        assert_eq!((stop.x, stop.v, go.x, go.v), (6.0, 0.0, 6.0, 0.0));
        assert!((go.t - stop.t - 1.5).abs() < 1e-12);
        // At rest for the whole wait.
        for f in [0.01, 0.5, 0.99] {
            let w = tr.sample_at(1.0 + stop.t + f * 1.5);
            assert!(
                (w.position[0] - 6.0).abs() < 1e-12 && w.speed == 0.0,
                "{w:?}"
            );
        }
        // Braking no harder than asked: v^2 = 2 b (6 - x) on the way in.
        for p in tr.points.iter().take(k - 1) {
            assert!(p.v * p.v <= 2.0 * (6.0 - p.x) + 1e-9, "{p:?}");
        }
        // The same path to its end, which it reaches later than without the wait.
        assert_eq!(tr.points.last().unwrap().x, 20.0);
        assert!(tr.end_time() > old.end_time() + 1.5);
        // Too close to stop at 2 m/s, or behind the plan: no such plan.
        assert!(hold(&old, 1.0, 3.5, 1.0, 1.0, 0.5).is_none());
        assert!(hold(&old, 1.0, 1.0, 1.0, 1.0, 0.5).is_none());
    }
}
