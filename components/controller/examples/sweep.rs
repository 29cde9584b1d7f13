//! Walk sweep: mean falls, XY/Z error and residual over several start offsets per
//! engine and speed (straight path, or an arc with `arc`), on flat ground or one of
//! `plamo eval locomotion`'s terrain strips.
//!
//! `cargo run --release -p plamo-controller --features mujoco --example sweep --
//! [engines] [speeds] [head height m] [seconds] [runs] [straight|arc] [flat|slope|rough|stairs]`
//!
//! On a strip the runs start where `plamo eval locomotion` starts them (0.37 m apart
//! along the strip, 0.1 m apart sideways) and stop before its 30 m end.
use std::error::Error;

use plamo_controller::{
    ArcPath, ControllerSettings, GaitParams, HeadPath, MetricsSummary, ModelBasedController,
    RUN_STAGGER, RampedPath, START_ACCEL, STRIP_LENGTH, StraightPath, flat_scene, run_path,
    staggered_start, terrain_scene,
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
    let speeds: Vec<f64> = arg(1, "1.0,1.5")
        .split(',')
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let head: f64 = arg(2, "1.47").parse()?;
    let duration: f64 = arg(3, "10").parse()?;
    let runs: usize = arg(4, "4").parse()?;
    let arc = match arg(5, "straight").as_str() {
        "straight" => false,
        "arc" => true,
        other => return Err(format!("path `{other}`: expected straight or arc").into()),
    };
    let terrain = arg(6, "flat");
    // The strip (and where runs start on it) is eval locomotion's; checked once here.
    let (strip, strip_start) = terrain_scene(&terrain)?;
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
    for &engine in &engines {
        for &speed in &speeds {
            let results: Vec<_> = (0..runs)
                .into_par_iter()
                .map(|r| {
                    let mut policy =
                        ModelBasedController::with_params(params, settings.clone()).unwrap();
                    let start = staggered_start(strip_start, r);
                    let (scene, duration) = if terrain == "flat" {
                        (flat_scene(speed * duration + 10.0), duration)
                    } else {
                        // A strip is 30 m long from its start.
                        (
                            strip.clone(),
                            duration.min((STRIP_LENGTH - RUN_STAGGER * r as f64) / speed),
                        )
                    };
                    let path: Box<dyn HeadPath> = if arc {
                        Box::new(ArcPath {
                            start,
                            speed,
                            head_height: head,
                            straight: 3.0,
                            radius: if r % 2 == 0 { 5.0 } else { -5.0 },
                        })
                    } else {
                        // From rest, like the tuner's and Table 2's paths.
                        Box::new(RampedPath {
                            line: StraightPath {
                                start,
                                speed,
                                head_height: head,
                            },
                            accel: START_ACCEL,
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
