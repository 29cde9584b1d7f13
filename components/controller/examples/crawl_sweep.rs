//! Crawl sweep: falls, XY/Z error and residual of the crawl (hands and knees) per
//! engine, terrain and speed; every rollout starts standing, so the get-down is
//! part of it.
//!
//! `cargo run --release -p plamo-controller --features mujoco --example crawl_sweep --
//! [engines] [speeds] [head height m] [seconds] [runs] [straight|arc|drop|rise|crouch|turn|corner@D|trace]
//! [terrains: flat,slope,rough,stairs,ceiling]` (the sloped, rough and stair strips
//! are the builtin `terrain-*` scenes `plamo eval locomotion` uses, from x 5, y 3;
//! `ceiling` is flat with the crawl suite's 0.6 m ceiling; `stairs@A`: 0.12 m x 0.42 m
//! stairs rising towards A degrees from the path, from x 5, y 6; `ledge@H`: a ledge H m
//! up across the path at x 4, from x 0, `ledge_scene`). `drop`: the plan walks at
//! the given speed (head 1.47 m, from rest at 1 m/s^2) and drops to the crawl's head
//! height and 1 m/s at 4 s, the get-down from a walk. `rise`: straight, the plan rises
//! to a standing head at 5 s (the get-up; a crawler still down counts as fallen).
//! `crouch`: straight, the plan rises to a crouch-walk's 0.8 m head at 5 s (the fall
//! rule's bar is the crawl's 0.2 m throughout). `turn`: the plan crawls off at a right angle to the standing body's heading (left
//! in even runs, right in odd ones), as where a walk leg ends at a landmark and the
//! crawl leg heads elsewhere. `corner@D`: straight for 6 s of the speed, then on at
//! that speed D degrees to the left (even runs) or right (odd ones) from a corner
//! (`TurnPath`), as a crawl lagging its plan meets a crawl leg that heads off from a
//! landmark (run it for ~11 s: the strips are 6 m wide). `PLAMO_SWEEP_HOLD=S`: the plan
//! waits S seconds (straight paths), moving its point at rest to where the crawl's
//! head ends after the get-down (0.7 m ahead of the standing head), so the errors measure the crawl's tracking, not
//! the get-down's lag behind a plan that left at once. `PLAMO_PHYSICS_PARAMS=FILE`: physics
//! settings other than the defaults (a `--physics-params` file), for an A/B on one binary.
//! `PLAMO_SWEEP_LENGTH=M`: built scenes (flat, ceiling, ledge) M m long (the crawl suite's
//! ledge is 12 m). `PLAMO_SWEEP_PER_RUN=1`: a line per run too. In `trace`,
//! `PLAMO_TRACE_CONTACTS=1` lists the bodies touching the terrain.
use std::error::Error;

use plamo_controller::{
    ArcPath, ControllerSettings, CrawlParams, DropPath, FallBody, GaitParams, HeadPath,
    MetricsSummary, ModelBasedController, RisingPath, START_ACCEL, StraightPath, TurnPath,
    ceiling_scene, flat_scene, ledge_scene, run_path_with, staggered_start,
};
use plamo_physics::BackendKind;
use rayon::prelude::*;

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or(default.into());
    let engines: Vec<BackendKind> = arg(0, "rapier,mujoco")
        .split(',')
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let speeds: Vec<f64> = arg(1, "0.5,1.0")
        .split(',')
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let head: f64 = arg(2, "0.4").parse()?;
    let duration: f64 = arg(3, "10").parse()?;
    let runs: usize = arg(4, "4").parse()?;
    let arc = arg(5, "straight") == "arc";
    let drop = arg(5, "straight") == "drop";
    let rise = arg(5, "straight") == "rise";
    let turn = arg(5, "straight") == "turn";
    let corner: Option<f64> = arg(5, "straight")
        .strip_prefix("corner@")
        .map(|deg| deg.parse::<f64>().map(f64::to_radians))
        .transpose()?;
    let crouch = arg(5, "straight") == "crouch";
    let settings = ControllerSettings {
        body_mass: plamo_physics::humanoid::total_mass(),
        ..Default::default()
    };
    if arg(5, "") == "trace" {
        for &engine in &engines {
            trace(engine, speeds[0], head, duration, &settings)?;
        }
        return Ok(());
    }
    let crawl = match std::env::var_os("PLAMO_CRAWL_PARAMS") {
        Some(p) => CrawlParams::load(std::path::Path::new(&p))?,
        None => CrawlParams::default(),
    };
    let hold: f64 = match std::env::var("PLAMO_SWEEP_HOLD") {
        Ok(v) => v.parse()?,
        Err(_) => 0.0,
    };
    let per_run = std::env::var_os("PLAMO_SWEEP_PER_RUN").is_some();
    let terrains: Vec<String> = arg(6, "flat").split(',').map(String::from).collect();
    let physics = physics_settings()?;
    for terrain in &terrains {
        for &engine in &engines {
            for &speed in &speeds {
                // One scene for the cell's runs: they differ only in where they start.
                let (scene, origin) = terrain_scene(terrain, scene_length(speed, duration)?)?;
                let ms: Vec<Option<MetricsSummary>> = (0..runs)
                    .into_par_iter()
                    .map(|r| {
                        let mut policy = ModelBasedController::with_all_params(
                            GaitParams::default(),
                            crawl,
                            settings.clone(),
                        )
                        .unwrap();
                        let start = staggered_start(origin, r);
                        let path: Box<dyn HeadPath> = if drop {
                            Box::new(DropPath {
                                start,
                                walk_speed: speed,
                                crawl_speed: 1.0,
                                head_height: head,
                                drop_at: 4.0,
                            })
                        } else if rise {
                            Box::new(RisingPath {
                                line: StraightPath {
                                    start,
                                    speed,
                                    head_height: head,
                                },
                                up_at: 5.0,
                            })
                        } else if crouch {
                            Box::new(CrouchPath {
                                line: StraightPath {
                                    start,
                                    speed,
                                    head_height: head,
                                },
                                up_at: 5.0,
                            })
                        } else if let Some(angle) = corner {
                            Box::new(TurnPath {
                                start,
                                speed,
                                corner_speed: speed,
                                head_height: head,
                                first: 6.0 * speed,
                                turn: if r % 2 == 0 { angle } else { -angle },
                                accel: START_ACCEL,
                            })
                        } else if turn {
                            Box::new(SidePath {
                                start,
                                speed,
                                head_height: head,
                                side: if r % 2 == 0 { 1.0 } else { -1.0 },
                            })
                        } else if arc {
                            Box::new(ArcPath {
                                start,
                                speed,
                                head_height: head,
                                straight: 2.0,
                                radius: if r % 2 == 0 { 3.0 } else { -3.0 },
                            })
                        } else {
                            Box::new(HeldPath {
                                line: StraightPath {
                                    start,
                                    speed,
                                    head_height: head,
                                },
                                hold,
                            })
                        };
                        // A rollout the engine gives up on (rapier's body spun past
                        // 100 rad/s with some crawl gains) is counted, not fatal.
                        run_path_with(
                            engine,
                            &physics,
                            &scene,
                            path.as_ref(),
                            duration,
                            &mut policy,
                            &settings,
                        )
                        .map_err(|e| eprintln!("{terrain} {engine:?} {speed:.2} m/s run {r}: {e}"))
                        .ok()
                    })
                    .collect();
                let diverged = ms.iter().filter(|m| m.is_none()).count();
                if per_run {
                    for (r, m) in ms.iter().enumerate() {
                        if let Some(m) = m {
                            println!(
                                "  run {r}: falls {} xy {:.3} (max {:.2})",
                                m.falls, m.xy_err_mean, m.xy_err_max
                            );
                        }
                    }
                }
                let ms: Vec<MetricsSummary> = ms.into_iter().flatten().collect();
                println!(
                    "{terrain} {engine:?} {speed:.2} m/s: {}{}",
                    MetricsSummary::sweep_row(&ms),
                    if diverged > 0 {
                        format!(" diverged {diverged}")
                    } else {
                        String::new()
                    }
                );
            }
        }
    }
    Ok(())
}

/// `PLAMO_PHYSICS_PARAMS`: a TOML table of `PhysicsSettings` fields (as `plamo run
/// --physics-params`), the rest default.
fn physics_settings() -> Result<plamo_physics::PhysicsSettings, Box<dyn Error>> {
    Ok(match std::env::var_os("PLAMO_PHYSICS_PARAMS") {
        Some(p) => toml::from_str(&std::fs::read_to_string(p)?)?,
        None => plamo_physics::PhysicsSettings::default(),
    })
}

/// Stairs (0.12 m x 0.42 m, the random scenes' steps) rising towards `angle` degrees
/// from +X, the straight paths' direction: a path across them at an angle has one
/// side of the body a tread above the other.
fn oblique_stairs(angle: f64) -> plamo_scenes::Scene {
    let text = format!(
        "name = \"stairs-at-{angle}\"\ndescription = \"stairs crossed at {angle} degrees\"\n\
         [terrain]\nsize = [40.0, 12.0]\n[[terrain.tiles]]\n\
         area = {{ min = [0.0, 0.0], max = [40.0, 12.0] }}\n\
         generator = {{ kind = \"stairs\", step_height = 0.12, step_depth = 0.42, \
         direction_deg = {angle}, symmetric = true }}\n"
    );
    plamo_scenes::from_toml_str(&text, "oblique stairs").unwrap()
}

/// The scene of a terrain name (see the module docs) and where its runs start; flat
/// ground and the ceiling are `length` \[m\] long.
fn terrain_scene(
    terrain: &str,
    length: f64,
) -> Result<(plamo_scenes::Scene, [f64; 2]), Box<dyn Error>> {
    Ok(if terrain == "flat" {
        (flat_scene(length), [0.0, 0.0])
    } else if terrain == "ceiling" {
        (ceiling_scene(length), [0.0, 0.0])
    } else if let Some(angle) = terrain.strip_prefix("stairs@") {
        (oblique_stairs(angle.parse()?), [5.0, 6.0])
    } else if let Some(h) = terrain.strip_prefix("ledge@") {
        (ledge_scene(length, h.parse()?), [0.0, 0.0])
    } else {
        (
            plamo_scenes::builtin(&format!("terrain-{terrain}"))?,
            [5.0, 3.0],
        )
    })
}

/// A straight plan that waits `hold` seconds at its start, moving its point (at rest)
/// to where the crawl's head ends after the get-down.
struct HeldPath {
    line: StraightPath,
    hold: f64,
}

impl HeadPath for HeldPath {
    fn point(&self, scene: &plamo_scenes::Scene, t: f64) -> plamo_controller::Waypoint {
        let mut w = self.line.at(scene, t - self.hold);
        if self.hold > 0.0 {
            // The head ends ~0.7 m ahead of the standing head after the get-down.
            let s = (t / self.hold).clamp(0.0, 1.0);
            w.x += 0.7 * s * s * (3.0 - 2.0 * s);
        }
        if t < self.hold {
            w.v = 0.0;
        }
        w
    }
    fn direction(&self, _t: f64) -> [f64; 2] {
        [1.0, 0.0]
    }
    fn head_height(&self) -> f64 {
        self.line.head_height
    }
}

/// A straight crawl plan whose head rises to a crouch-walk's 0.8 m at `up_at`: a
/// crawl leg followed by a crouch-walk leg. The fall rule holds the head to the
/// crawl's bar (0.2 m) throughout, the crouch-walk part included (as the crawl suite's
/// `stands_up_into_a_crouch_walk`).
struct CrouchPath {
    line: StraightPath,
    up_at: f64,
}

impl HeadPath for CrouchPath {
    fn point(&self, scene: &plamo_scenes::Scene, t: f64) -> plamo_controller::Waypoint {
        let mut w = self.line.at(scene, t);
        if t >= self.up_at {
            w.z += 0.8 - self.line.head_height;
        }
        w
    }
    fn direction(&self, _t: f64) -> [f64; 2] {
        [1.0, 0.0]
    }
    fn head_height(&self) -> f64 {
        // The fall rule's bar is the crawl's (0.2 m) throughout: with the crouch-walk's
        // (0.3 m) a crawl whose head dipped counted as fallen before it stood up.
        self.line.head_height
    }
}

/// A straight plan along +Y (`side` 1) or -Y (-1), at right angles to the standing
/// body's heading (+X).
struct SidePath {
    start: [f64; 2],
    speed: f64,
    head_height: f64,
    side: f64,
}

impl HeadPath for SidePath {
    fn point(&self, scene: &plamo_scenes::Scene, t: f64) -> plamo_controller::Waypoint {
        let (x, y) = (
            self.start[0],
            self.start[1] + self.side * self.speed * t.max(0.0),
        );
        plamo_controller::Waypoint {
            x,
            y,
            z: scene.height_at(x, y) + self.head_height,
            v: self.speed,
        }
    }
    fn direction(&self, _t: f64) -> [f64; 2] {
        [0.0, self.side]
    }
    fn head_height(&self) -> f64 {
        self.head_height
    }
}

/// Length of a built scene \[m\]: `PLAMO_SWEEP_LENGTH`, else what the run needs and
/// 10 m more. The crawl suite's ledge is 12 m long; another length is another height
/// grid, and rapier's contacts (and the rollout) differ with it.
fn scene_length(speed: f64, duration: f64) -> Result<f64, Box<dyn Error>> {
    Ok(match std::env::var("PLAMO_SWEEP_LENGTH") {
        Ok(v) => v.parse()?,
        Err(_) => speed * duration + 10.0,
    })
}

/// One straight rollout, printing the head, pelvis and contacts every 0.25 s.
fn trace(
    engine: BackendKind,
    speed: f64,
    head: f64,
    duration: f64,
    settings: &ControllerSettings,
) -> Result<(), Box<dyn Error>> {
    use plamo_controller::{Action, Observation, control_step};
    use plamo_physics::{HumanoidPose, create_backend};
    let crawl = match std::env::var_os("PLAMO_CRAWL_PARAMS") {
        Some(p) => CrawlParams::load(std::path::Path::new(&p))?,
        None => CrawlParams::default(),
    };
    let mut policy =
        ModelBasedController::with_all_params(GaitParams::default(), crawl, settings.clone())?;
    let terrain = std::env::var("PLAMO_TRACE_TERRAIN").unwrap_or_else(|_| "flat".into());
    let (scene, origin) = terrain_scene(&terrain, scene_length(speed, duration)?)?;
    // Start offsets as in the sweep's run `PLAMO_TRACE_RUN` (default 0).
    let r: usize = std::env::var("PLAMO_TRACE_RUN")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    let start = staggered_start(origin, r);
    // `PLAMO_TRACE_DROP_AT`: walk at `speed` and drop to the crawl then (see `drop`).
    // `PLAMO_TRACE_TURN=1` (or -1): crawl off at a right angle (see `turn`).
    // `PLAMO_TRACE_CROUCH_AT`: rise to a crouch-walk's head then (see `crouch`).
    let turn: Option<f64> = std::env::var("PLAMO_TRACE_TURN")
        .ok()
        .map(|v| v.parse())
        .transpose()?;
    let line = StraightPath {
        start,
        speed,
        head_height: head,
    };
    let path: Box<dyn HeadPath> = match std::env::var("PLAMO_TRACE_DROP_AT") {
        _ if turn.is_some() => Box::new(SidePath {
            start,
            speed,
            head_height: head,
            side: turn.unwrap_or(1.0).signum(),
        }),
        Ok(v) => Box::new(DropPath {
            start,
            walk_speed: speed,
            crawl_speed: 1.0,
            head_height: head,
            drop_at: v.parse()?,
        }),
        Err(_) if std::env::var_os("PLAMO_TRACE_CROUCH_AT").is_some() => Box::new(CrouchPath {
            line,
            up_at: std::env::var("PLAMO_TRACE_CROUCH_AT")?.parse()?,
        }),
        Err(_) if std::env::var_os("PLAMO_SWEEP_HOLD").is_some() => Box::new(HeldPath {
            line,
            hold: std::env::var("PLAMO_SWEEP_HOLD")?.parse()?,
        }),
        Err(_) => Box::new(RisingPath {
            line,
            up_at: std::env::var("PLAMO_TRACE_UP_AT")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(f64::INFINITY),
        }),
    };
    let mut physics = create_backend(engine, &scene, &physics_settings()?)?;
    physics.reset(&HumanoidPose::standing_on(
        &scene.terrain,
        start[0],
        start[1],
        0.0,
    ))?;
    let mut obs = Observation::new(ModelBasedController::LAYOUT);
    let mut action = Action::zeros(ModelBasedController::LAYOUT.num_joints);
    let steps = (duration * 30.0) as usize;
    for c in 0..steps {
        let t = c as f64 / 30.0;
        let state = physics.state().clone();
        let ground = settings.fall_ground(&scene, &FallBody::of(&state));
        if settings.is_fallen(state.head[2] - ground, path.head_height()) {
            println!(
                "{engine:?} t {t:5.2} FALLEN (head {:.2} m above the ground)",
                state.head[2] - ground
            );
        }
        // The trace below reads this step's observation and action.
        control_step(
            physics.as_mut(),
            &state,
            path.as_ref(),
            &scene,
            t,
            &mut policy,
            &mut obs,
            &mut action,
        )?;
        if c % 8 == 0 && std::env::var_os("PLAMO_TRACE_COM").is_some() {
            use plamo_physics::humanoid::{BODIES, shape_mass};
            let m: Vec<f64> = BODIES
                .iter()
                .map(|b| b.shapes.iter().map(shape_mass).sum())
                .collect();
            let total: f64 = m.iter().sum();
            let com: f64 = obs
                .body_pos
                .iter()
                .zip(&m)
                .map(|(p, m)| p[0] * m)
                .sum::<f64>()
                / total;
            let x = |i: usize| obs.body_pos[i][0];
            let q = &obs.joint_pos;
            let tg = &action.pd_targets;
            println!(
                "  right arm q {:5.2} {:5.2} {:5.2} target {:5.2} {:5.2} {:5.2} spine {:5.2}/{:5.2} hip_y {:5.2}/{:5.2} knee {:5.2}/{:5.2}",
                q[6], q[7], q[9], tg[6], tg[7], tg[9], q[1], tg[1], q[15], tg[15], q[17], tg[17]
            );
            println!(
                "  com x {com:5.2} knees {:5.2} {:5.2} hands {:5.2} {:5.2} feet {:5.2} {:5.2} pelvis-head {:5.2} ankle {:5.2}/{:5.2}",
                x(10),
                x(13),
                x(5),
                x(8),
                x(11),
                x(14),
                obs.head_pos[0],
                q[18],
                tg[18]
            );
        }
        if c % std::env::var("PLAMO_TRACE_EVERY")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(8)
            == 0
        {
            let b = &state.body_pos;
            let w = policy.last_wrench();
            println!(
                "{engine:?} t {t:5.2} head {:5.2} {:5.2} {:5.2} yaw {:5.2} v {:5.2} {:5.2} pelvis z {:4.2} pitch {:5.2} roll {:5.2} knees {:4.2} {:4.2} hands {:4.2} {:4.2} feet {:4.2} {:4.2} F {:5.0} {:5.0} {:5.0} T {:4.0} {:4.0} {:4.0} crawl {}",
                state.head[0] - path.point(&scene, t).x,
                state.head[1] - path.point(&scene, t).y,
                state.head[2],
                state.heading(),
                obs.root_lin_vel[0],
                obs.root_lin_vel[1],
                state.root_position[2],
                (-obs.root_rotation[2]).asin(),
                obs.root_rotation[5].asin(),
                b[10][2],
                b[13][2],
                b[5][2],
                b[8][2],
                b[11][2],
                b[14][2],
                w.force[0],
                w.force[1],
                w.force[2],
                w.torque[0],
                w.torque[1],
                w.torque[2],
                policy.is_crawling(),
            );
            if std::env::var_os("PLAMO_TRACE_CONTACTS").is_some() {
                let touching: Vec<&str> = (0..plamo_physics::NUM_BODIES)
                    .filter(|&i| state.terrain_contact[i])
                    .map(|i| plamo_physics::BODY_NAMES[i])
                    .collect();
                println!(
                    "  x {:5.2} touching {}",
                    state.root_position[0],
                    touching.join(" ")
                );
            }
        }
    }
    Ok(())
}
