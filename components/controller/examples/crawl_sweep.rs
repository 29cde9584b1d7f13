//! Crawl sweep: falls, XY/Z error and residual of the crawl (hands and knees) per
//! engine, terrain and speed; every rollout starts standing, so the get-down is
//! part of it.
//!
//! `cargo run --release -p plamo-controller --features mujoco --example crawl_sweep --
//! [engines] [speeds] [head height m] [seconds] [runs] [straight|arc]`
use std::error::Error;

use plamo_controller::{
    ArcPath, ControllerSettings, CrawlParams, GaitParams, HeadPath, MetricsSummary,
    ModelBasedController, StraightPath, flat_scene, run_path,
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
    for &engine in &engines {
        for &speed in &speeds {
            let ms: Vec<MetricsSummary> = (0..runs)
                .into_par_iter()
                .map(|r| {
                    let mut policy = ModelBasedController::with_all_params(
                        GaitParams::default(),
                        crawl,
                        settings.clone(),
                    )
                    .unwrap();
                    let start = [0.37 * r as f64, 0.1 * (r % 3) as f64 - 0.1];
                    let scene = flat_scene(speed * duration + 10.0);
                    let path: Box<dyn HeadPath> = if arc {
                        Box::new(ArcPath {
                            start,
                            speed,
                            head_height: head,
                            straight: 2.0,
                            radius: if r % 2 == 0 { 3.0 } else { -3.0 },
                        })
                    } else {
                        Box::new(StraightPath {
                            start,
                            speed,
                            head_height: head,
                        })
                    };
                    run_path(
                        engine,
                        &scene,
                        path.as_ref(),
                        duration,
                        &mut policy,
                        &settings,
                    )
                    .unwrap()
                })
                .collect();
            let k = runs as f64;
            let mean = |f: &dyn Fn(&MetricsSummary) -> f64| ms.iter().map(f).sum::<f64>() / k;
            println!(
                "{engine:?} {speed:.2} m/s: falls/run {:.2} xy {:.3} (max {:.2}) z {:.3} residual {:.3} (peak {:.3}) dir {:.3}",
                mean(&|m| f64::from(m.falls)),
                mean(&|m| m.xy_err_mean),
                ms.iter().map(|m| m.xy_err_max).fold(0.0, f64::max),
                mean(&|m| m.z_err_mean),
                mean(&|m| m.residual_force_mean),
                ms.iter().map(|m| m.residual_force_peak).fold(0.0, f64::max),
                mean(&|m| m.mean_reward.dir),
            );
        }
    }
    Ok(())
}

/// One straight rollout, printing the head, pelvis and contacts every 0.25 s.
fn trace(
    engine: BackendKind,
    speed: f64,
    head: f64,
    duration: f64,
    settings: &ControllerSettings,
) -> Result<(), Box<dyn Error>> {
    use plamo_controller::{
        Action, HumanoidSnapshot, NUM_WAYPOINTS, Observation, Policy, WAYPOINT_SPACING, Waypoint,
    };
    use plamo_physics::{HumanoidPose, PhysicsSettings, create_backend};
    let crawl = match std::env::var_os("PLAMO_CRAWL_PARAMS") {
        Some(p) => CrawlParams::load(std::path::Path::new(&p))?,
        None => CrawlParams::default(),
    };
    let mut policy =
        ModelBasedController::with_all_params(GaitParams::default(), crawl, settings.clone())?;
    let scene = flat_scene(speed * duration + 10.0);
    let path = StraightPath {
        start: [0.0, 0.0],
        speed,
        head_height: head,
    };
    let mut physics = create_backend(engine, &scene, &PhysicsSettings::default())?;
    physics.reset(&HumanoidPose::standing_on(&scene.terrain, 0.0, 0.0, 0.0))?;
    let mut obs = Observation::new(ModelBasedController::LAYOUT);
    let mut action = Action::zeros(ModelBasedController::LAYOUT.num_joints);
    let mut plan = [Waypoint::default(); NUM_WAYPOINTS];
    let steps = (duration * 30.0) as usize;
    for c in 0..steps {
        let t = c as f64 / 30.0;
        let state = physics.state().clone();
        for (i, w) in plan.iter_mut().enumerate() {
            *w = path.at(&scene, t + WAYPOINT_SPACING * (i + 1) as f64);
        }
        obs.update(&HumanoidSnapshot::from(&state), &plan, &scene)?;
        policy.act(&obs, &mut action)?;
        if c % 8 == 0 {
            let b = &state.body_pos;
            let w = policy.last_wrench();
            println!(
                "{engine:?} t {t:5.2} head {:5.2} {:5.2} pelvis z {:4.2} pitch {:5.2} roll {:5.2} knees {:4.2} {:4.2} hands {:4.2} {:4.2} feet {:4.2} {:4.2} F {:5.0} {:5.0} {:5.0} T {:4.0} {:4.0} {:4.0} crawl {}",
                state.head[0] - path.at(&scene, t).x,
                state.head[2],
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
        }
        physics.set_action(
            &action.pd_targets,
            action.root_wrench.map(|w| plamo_physics::RootWrench {
                force: w.force,
                torque: w.torque,
            }),
        )?;
        physics.step_n(4)?;
    }
    Ok(())
}
