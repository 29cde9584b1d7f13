//! Straight constant-speed walk with the model-based controller; prints the metrics.
//!
//! `cargo run -p plamo-controller --example walk -- [rapier|mujoco] [speed m/s]
//! [head height m] [seconds] [residual force cap, fraction of m*g] [torque cap N m]`

use std::error::Error;

use plamo_controller::{
    ControllerSettings, GaitParams, ModelBasedController, StraightPath, flat_scene, run_straight,
};

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or(default.into());
    let backend = arg(0, "rapier").parse()?;
    let speed: f64 = arg(1, "1.0").parse()?;
    let head_height: f64 = arg(2, "1.47").parse()?;
    let duration: f64 = arg(3, "10").parse()?;
    let settings = ControllerSettings {
        body_mass: plamo_physics::humanoid::total_mass(),
        residual_force_cap: arg(4, "0.25").parse()?,
        residual_torque_cap: arg(5, "60").parse()?,
        ..Default::default()
    };
    // PLAMO_GAIT_PARAMS=path.toml overrides the built-in parameters.
    let params = match std::env::var_os("PLAMO_GAIT_PARAMS") {
        Some(p) => GaitParams::load(std::path::Path::new(&p))?,
        None => GaitParams::default(),
    };
    let mut policy = ModelBasedController::with_params(params, settings.clone())?;
    let path = StraightPath {
        start: [0.0, 0.0],
        speed,
        head_height,
    };
    let scene = flat_scene(speed * duration + 5.0);
    let summary = run_straight(backend, &scene, path, duration, &mut policy, &settings)?;
    println!("{}", serde_json::to_string_pretty(&summary)?);
    Ok(())
}
