//! Walk sweep: mean falls, XY/Z error and residual over several start offsets per
//! engine and speed (straight path, or an arc with `arc`), on flat ground or one of
//! `plamo eval locomotion`'s terrain strips.
//!
//! `cargo run --release -p plamo-controller --features mujoco --example sweep --
//! [engines] [speeds] [head height m] [seconds] [runs] [straight|arc|turn] [flat|slope|rough|stairs|stairs-at-DEG|SCENE.toml]`
//!
//! On a strip the runs start where `plamo eval locomotion` starts them (0.37 m apart
//! along the strip, 0.1 m apart sideways) and stop before its 30 m end.
//! `stairs-at-DEG` is the stairs strip's 0.12 m x 0.4 m steps with their risers turned
//! DEG degrees off square to the path (random tours cross stairs at any angle):
//! `stairs-at-90` walks along a riser with one foot on each side of it, 45 and 60
//! climb and descend flights of five steps (1.2 m wide, flat ground beside them).
//! Walk 0.8 / 1.2 m/s, 16 runs, at HEAD 29965cf: falls per run 1.06 / 1.19 at 90,
//! 0.0 / 0.69 at 45, 0.12 / 1.0 at 60, against 0.06 / 0.31 on the square stairs strip.
//!
//! `turn`: 3 m along +X, then off at 120-180 degrees (left and right by turns), the path
//! slowing to 0.6 x the speed at the corner (`PLAMO_TURN_CORNER` sets the fraction), on
//! flat ground: a landmark of the random tours, where most legs turn back. Crouch-walk
//! 1 m/s, 48 runs of 10 s with the corner at full speed, gait of 28bee9f: 0.19 falls
//! per run (walk 1-1.5 m/s: 0).
//!
//! `PLAMO_TRACE=R` traces run R of the first engine and speed instead: the body's
//! state every 1/15 s over the 1.5 s before each fall (what the body did in the fall;
//! `PLAMO_TRACE_ALL=1`: all along).
use std::error::Error;

use plamo_controller::{
    Action, ArcPath, ControllerSettings, FallBody, GaitParams, HeadPath, MetricsSummary,
    ModelBasedController, Observation, Policy, RUN_STAGGER, RampedPath, START_ACCEL, STRIP_LENGTH,
    StraightPath, TurnPath, control_step, flat_scene, run_path, staggered_start, terrain_scene,
};
use plamo_physics::{BackendKind, FEET, HumanoidPose, PhysicsSettings, create_backend};
use plamo_scenes::Scene;
use rayon::prelude::*;

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or(default.into());
    let engines: Vec<BackendKind> = arg(0, "rapier,mujoco")
        .split(',')
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let speeds: Vec<f64> = arg(1, "1.0,1.5")
        .split(',')
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let head: f64 = arg(2, "1.47").parse()?;
    let duration: f64 = arg(3, "10").parse()?;
    let runs: usize = arg(4, "4").parse()?;
    let kind = arg(5, "straight");
    if !["straight", "arc", "turn"].contains(&kind.as_str()) {
        return Err(format!("path `{kind}`: expected straight, arc or turn").into());
    }
    let arc = kind == "arc";
    // `turn`: 3 m, then off at 120-180 degrees, left and right by turns, slowing to 0.6
    // x the speed at the corner (the random tours' landmarks, where most legs turn back
    // and the new leg starts at about the speed the body arrives with).
    let turn = kind == "turn";
    // PLAMO_TURN_CORNER=F: the corner speed as a fraction of the speed (default 0.6).
    let corner: f64 = match std::env::var("PLAMO_TURN_CORNER") {
        Ok(f) => f
            .parse()
            .ok()
            .filter(|c| (0.0..=1.0).contains(c))
            .ok_or_else(|| format!("PLAMO_TURN_CORNER `{f}`: expected a fraction in 0..=1"))?,
        Err(_) => 0.6,
    };
    let terrain = arg(6, "flat");
    if turn && terrain != "flat" {
        return Err(format!("path `turn` runs on flat ground, not `{terrain}`").into());
    }
    // The strip (and where runs start on it) is eval locomotion's; checked once here.
    // A scene file (`.toml`) or one of the stairs strips crossed at an angle stands in
    // for a strip: the same 30 m path from (5, 3).
    let (strip, strip_start) = if terrain.ends_with(".toml") {
        (
            plamo_scenes::load(std::path::Path::new(&terrain))?,
            [5.0, 3.0],
        )
    } else if let Some(deg) = terrain.strip_prefix("stairs-at-") {
        let deg: f64 = deg
            .parse()
            .ok()
            .filter(|d: &f64| (0.0..=90.0).contains(d))
            .ok_or_else(|| format!("terrain `{terrain}`: DEG must be degrees in 0..=90"))?;
        (angled_stairs(deg)?, [5.0, 3.0])
    } else {
        terrain_scene(&terrain)?
    };
    let mut settings = ControllerSettings {
        body_mass: plamo_physics::humanoid::total_mass(),
        ..Default::default()
    };
    // PLAMO_RESIDUAL_CAP=0.1 measures the gait under a smaller residual force cap.
    if let Some(cap) = std::env::var_os("PLAMO_RESIDUAL_CAP") {
        settings.residual_force_cap = cap.to_string_lossy().parse()?;
    }
    let params = match std::env::var_os("PLAMO_GAIT_PARAMS") {
        Some(p) => GaitParams::load(std::path::Path::new(&p))?,
        None => GaitParams::default(),
    };
    // Flat ground for a path of `length` m: an arc's 5 m circle reaches 10 m sideways,
    // the edge of `flat_scene` (a run past the half circle walked off it and counted
    // a fall).
    let ground = |length: f64| {
        let mut scene = flat_scene(length + 10.0);
        if arc || turn {
            scene.terrain = plamo_scenes::HeightGrid::flat([-15.0, -15.0], [30.0, 30.0], 0.1, 0.0);
        }
        scene
    };
    // Run r's path at `speed`: an arc, or a straight line from rest like the tuner's
    // and Table 2's paths.
    let make_path = |r: usize, speed: f64| -> Box<dyn HeadPath> {
        let start = staggered_start(strip_start, r);
        if turn {
            // Starts 0.05 m apart near the middle of the 30 m square (a strip's stagger
            // would walk 48 runs off it).
            let start = [-4.0 + 0.05 * (r % 10) as f64, 0.05 * (r / 10) as f64];
            let deg = 120.0 + 15.0 * (r / 2 % 5) as f64;
            let sign = if r.is_multiple_of(2) { 1.0 } else { -1.0 };
            Box::new(TurnPath {
                start,
                speed,
                corner_speed: corner * speed,
                head_height: head,
                first: 3.0,
                turn: sign * deg.to_radians(),
                accel: START_ACCEL,
            })
        } else if arc {
            Box::new(ArcPath {
                start,
                speed,
                head_height: head,
                straight: 3.0,
                radius: if r.is_multiple_of(2) { 5.0 } else { -5.0 },
            })
        } else {
            Box::new(RampedPath {
                line: StraightPath {
                    start,
                    speed,
                    head_height: head,
                },
                accel: START_ACCEL,
            })
        }
    };
    if let Some(r) = std::env::var_os("PLAMO_TRACE") {
        let r: usize = r.to_string_lossy().parse()?;
        let speed = speeds[0];
        let (scene, duration) = if terrain == "flat" {
            (ground(speed * duration), duration)
        } else {
            (
                strip.clone(),
                duration.min((STRIP_LENGTH - RUN_STAGGER * r as f64) / speed),
            )
        };
        let mut policy = ModelBasedController::with_params(params, settings.clone())?;
        let path = make_path(r, speed);
        return trace(
            engines[0],
            &scene,
            path.as_ref(),
            duration,
            &mut policy,
            &settings,
        );
    }
    for &engine in &engines {
        for &speed in &speeds {
            let results: Vec<_> = (0..runs)
                .into_par_iter()
                .map(|r| {
                    let mut policy =
                        ModelBasedController::with_params(params, settings.clone()).unwrap();
                    let (scene, duration) = if terrain == "flat" {
                        (ground(speed * duration), duration)
                    } else {
                        // A strip is 30 m long from its start.
                        (
                            strip.clone(),
                            duration.min((STRIP_LENGTH - RUN_STAGGER * r as f64) / speed),
                        )
                    };
                    let path = make_path(r, speed);
                    run_path(
                        engine,
                        &scene,
                        path.as_ref(),
                        duration,
                        &mut policy,
                        &settings,
                    )
                })
                .collect();
            // A run whose physics diverged is reported and left out of the means.
            let mut ms: Vec<MetricsSummary> = Vec::with_capacity(runs);
            for (r, m) in results.into_iter().enumerate() {
                match m {
                    Ok(m) => ms.push(m),
                    Err(e) => eprintln!("{engine:?} {terrain} {speed:.2} m/s run {r}: {e}"),
                }
            }
            // Per minute, as Table 2 reports falls (strip runs differ in length).
            let per_min = ms.iter().map(|m| f64::from(m.falls)).sum::<f64>()
                / ms.iter().map(|m| m.duration_s).sum::<f64>().max(1e-9)
                * 60.0;
            println!(
                "{engine:?} {terrain} head {head:.2} m {speed:.2} m/s: falls/min {per_min:.1} {}{}",
                MetricsSummary::sweep_row(&ms),
                if ms.len() < runs {
                    format!(" ({} of {runs} runs diverged)", runs - ms.len())
                } else {
                    String::new()
                }
            );
        }
    }
    Ok(())
}

/// A 40 m x 6 m strip whose stairs rise towards `deg` degrees from the path (+x):
/// at 90 the path (y = 3 +- 0.1) runs along a riser; below it, four flights of five
/// steps up and down on 1.2 m wide tiles (narrow, so that where a tile's steps have
/// already begun beside the path it enters over one or two risers at most).
fn angled_stairs(deg: f64) -> Result<Scene, Box<dyn Error>> {
    let tiles = if deg >= 89.9 {
        // Risers every 0.4 m from y = 0.2: one at y = 3.
        format!(
            "[[terrain.tiles]]\narea = {{ min = [7.0, 0.2], max = [35.0, 6.0] }}\n\
             generator = {{ kind = \"stairs\", step_height = 0.12, step_depth = 0.4, direction_deg = {deg:.1} }}\n"
        )
    } else {
        [7.0, 14.0, 21.0, 28.0]
            .map(|x0| {
                format!(
                    "[[terrain.tiles]]\narea = {{ min = [{x0:.1}, 2.4], max = [{:.1}, 3.6] }}\n\
                     generator = {{ kind = \"stairs\", step_height = 0.12, step_depth = 0.4, steps = 5, \
                     symmetric = true, direction_deg = {deg:.1} }}\n",
                    x0 + 7.0
                )
            })
            .concat()
    };
    let text = format!("name = \"stairs-at-{deg}\"\n[terrain]\nsize = [40.0, 6.0]\n{tiles}");
    Ok(plamo_scenes::from_toml_str(&text, "stairs-at")?)
}

/// Pitch of a body's x axis below the horizontal, + forward \[rad\], from `[w, x, y, z]`.
fn pitch_of(q: [f64; 4]) -> f64 {
    let [w, x, y, z] = q;
    (-(2.0 * (x * z - w * y))).clamp(-1.0, 1.0).asin()
}

/// The run of `path` with a line per 1/15 s kept for the 1.5 s before each fall.
fn trace(
    engine: BackendKind,
    scene: &Scene,
    path: &dyn HeadPath,
    duration: f64,
    policy: &mut ModelBasedController,
    settings: &ControllerSettings,
) -> Result<(), Box<dyn Error>> {
    let mut physics = create_backend(engine, scene, &PhysicsSettings::default())?;
    let p0 = path.point(scene, 0.0);
    physics.reset(&HumanoidPose::standing_on(&scene.terrain, p0.x, p0.y, 0.0))?;
    policy.reset();
    let mut obs = Observation::new(ModelBasedController::LAYOUT);
    let mut action = Action::zeros(ModelBasedController::LAYOUT.num_joints);
    let mut lines: std::collections::VecDeque<String> = Default::default();
    // PLAMO_TRACE_ALL=1: every line, not only those before a fall.
    let all = std::env::var_os("PLAMO_TRACE_ALL").is_some();
    println!(
        "t, x pelvis, ground, slope, pelvis h, pitch, vx, vz, head h, lag, heading err, foot R (dx, h)*, foot L (dx, h)* (* in contact), knees, contact"
    );
    for c in 0..(duration * 30.0) as usize {
        let t = c as f64 / 30.0;
        let s = physics.state().clone();
        let g = |x: f64, y: f64| scene.height_at(x, y);
        let [px, py, pz] = s.root_position;
        let ground = g(px, py);
        let head_h = s.head[2] - settings.fall_ground(scene, &FallBody::of(&s));
        let target = path.point(scene, t);
        let fallen = settings.is_fallen(head_h, path.head_height());
        let foot = |f: usize| {
            let p = s.body_pos[FEET[f]];
            // `*`: the foot touches the ground.
            let down = if s.contact[FEET[f]] { "*" } else { " " };
            format!("({:5.2},{:5.2}){down}", p[0] - px, p[2] - g(p[0], p[1]))
        };
        let knee = |n: &str| s.joint_pos[plamo_physics::humanoid::joint_index(n).unwrap()];
        if c.is_multiple_of(2) || fallen {
            lines.push_back(format!(
                "{t:6.2}{} {px:6.2} {ground:5.2} {:5.2} {:5.2} {:5.2} {:5.2} {:5.2} {head_h:5.2} {:5.2} {:5.2} {} {} {:5.2},{:5.2} {}{}",
                if policy.is_crawling() { "c" } else { " " },
                (g(px + 0.4, py) - g(px - 0.4, py)) / 0.8,
                pz - ground,
                pitch_of(s.root_quat),
                s.root_linvel[0],
                s.root_linvel[2],
                target.x - s.head[0],
                {
                    let d = path.direction(t);
                    let e = d[1].atan2(d[0]) - s.heading();
                    (e + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
                        - std::f64::consts::PI
                },
                foot(0),
                foot(1),
                knee("right_knee"),
                knee("left_knee"),
                (0..plamo_physics::NUM_BODIES)
                    .filter(|&b| s.contact[b] && !FEET.contains(&b))
                    .map(|b| plamo_physics::BODY_NAMES[b])
                    .collect::<Vec<_>>()
                    .join(","),
                if fallen { " FALL" } else { "" },
            ));
            if all {
                println!("{}", lines.pop_back().unwrap_or_default());
            }
            if lines.len() > 23 {
                lines.pop_front();
            }
        }
        if fallen {
            for l in lines.drain(..) {
                println!("{l}");
            }
            println!();
            physics.reset(&HumanoidPose::standing_on(
                &scene.terrain,
                target.x,
                target.y,
                0.0,
            ))?;
            policy.reset();
            continue;
        }
        control_step(
            physics.as_mut(),
            &s,
            path,
            scene,
            t,
            policy,
            &mut obs,
            &mut action,
        )?;
    }
    Ok(())
}
