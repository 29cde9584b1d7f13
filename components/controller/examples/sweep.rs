//! Walk sweep: mean falls, XY/Z error and residual over several start offsets per
//! engine and speed (straight path, or an arc with `arc`).
//!
//! `cargo run --release -p plamo-controller --features mujoco --example sweep --
//! [engines] [speeds] [head height m] [seconds] [runs] [straight|arc]`
use std::error::Error;

use plamo_controller::{
    ArcPath, ControllerSettings, GaitParams, HeadPath, MetricsSummary, ModelBasedController,
    RampedPath, START_ACCEL, StraightPath, flat_scene, run_path,
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
    let arc = arg(5, "straight") == "arc";
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
            let ms: Vec<MetricsSummary> = (0..runs)
                .into_par_iter()
                .map(|r| {
                    let mut policy =
                        ModelBasedController::with_params(params, settings.clone()).unwrap();
                    let start = [0.37 * r as f64, 0.1 * (r % 3) as f64 - 0.1];
                    let scene = flat_scene(speed * duration + 10.0);
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
                    .unwrap()
                })
                .collect();
            println!(
                "{engine:?} {speed:.2} m/s: {}",
                MetricsSummary::sweep_row(&ms)
            );
        }
    }
    Ok(())
}
