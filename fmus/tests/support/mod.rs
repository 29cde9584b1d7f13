//! The host route shared by the fmu-runner bit-identity test and the FMU overhead
//! example: `plamo.fmu` packaged and loaded like a third-party FMU, a ball the host
//! rolls across the default route, and the in-process lockstep of the same route.
//! Each test target uses a part of it.
#![allow(dead_code)]

use std::collections::HashMap;

use fmu_runner::{Fmu, FmuInstance, FmuLibrary, fmi2Type};
use plamo::fmu_package::{find_library, package_all};
use plamo::lockstep::Lockstep;
use plamo::lockstep::external::{PARKED_SAMPLE, in_process_with_external};
use plamo::spec::{ParamFiles, RunSpec};
use plamo_controller::ControllerSettings;
use plamo_interfaces::ObstacleSample;
use plamo_physics::BackendKind;
use plamo_scenes::ObstacleShape;

/// The FMU's default route (fmu-runner has no string API): rapier completes it.
pub const INSTRUCTIONS: &str = "Walk from the fountain to the sandbox";
/// A communication step that is no multiple of the 1/30 s control step, accumulated
/// the way hosts do \[s\].
pub const HOST_STEP: f64 = 0.01;

/// The host's ball: rolls along +x across the route (fountain (4, 14) to sandbox
/// (4, 4)) at y = 9, passing x = 4 at t = 5 s.
pub fn ball(t: f64) -> ObstacleSample {
    ObstacleSample {
        position: [-1.0 + t, 9.0, 0.3],
        velocity: [1.0, 0.0, 0.0],
    }
}

/// The four host obstacles at time `t`: the ball in slot 2, the others parked.
pub fn externals(t: f64) -> [ObstacleSample; 4] {
    [PARKED_SAMPLE, ball(t), PARKED_SAMPLE, PARKED_SAMPLE]
}

/// Package the built FMU library into a fresh folder named after `tag`, then unpack
/// and load the FMU of `model` (`plamo`, `plamo-planner`) as a co-simulation FMU.
/// Returns it and the folder, which is deleted when the caller drops it.
pub fn load_fmu(model: &str, tag: &str) -> (FmuLibrary, tempfile::TempDir) {
    let library = find_library().expect("cargo builds libplamo_fmu.so first");
    let dir = tempfile::Builder::new()
        .prefix(&format!("plamo-{tag}-"))
        .tempdir()
        .expect("a temporary folder");
    let packaged = package_all(&library, dir.path(), &[]).expect("package");
    let path = &packaged
        .iter()
        .find(|p| p.model_name == model)
        .unwrap_or_else(|| panic!("{model}.fmu packaged"))
        .path;
    let fmu = Fmu::unpack(path)
        .expect("unpack")
        .load(fmi2Type::fmi2CoSimulation)
        .expect("load");
    (fmu, dir)
}

/// Set the ball's inputs for the step starting at `t`.
pub fn set_ball(inst: &FmuInstance<&FmuLibrary>, fmu: &FmuLibrary, t: f64) {
    let vars = fmu.variables();
    let b = ball(t);
    let m: HashMap<_, _> = [
        (&vars["obstacle[2].x"], b.position[0]),
        (&vars["obstacle[2].y"], b.position[1]),
        (&vars["obstacle[2].z"], b.position[2]),
        (&vars["obstacle[2].vx"], b.velocity[0]),
        (&vars["obstacle[2].vy"], b.velocity[1]),
        (&vars["obstacle[2].vz"], b.velocity[2]),
    ]
    .into_iter()
    .collect();
    inst.set_reals(&m).expect("ball inputs");
}

/// Instantiate `plamo.fmu` with `seed` and the ball active at t = 0, initialised.
pub fn start_instance(fmu: &FmuLibrary, seed: i32) -> FmuInstance<&FmuLibrary> {
    let vars = fmu.variables();
    let inst = FmuInstance::instantiate(fmu, false).expect("instantiate");
    inst.setup_experiment(0.0, None, None).expect("setup");
    inst.enter_initialization_mode().expect("init");
    inst.set_integers(&[(&vars["seed"], seed)].into_iter().collect())
        .expect("seed");
    inst.set_booleans(&[(&vars["obstacle[2].active"], 1)].into_iter().collect())
        .expect("active");
    set_ball(&inst, fmu, 0.0);
    inst.exit_initialization_mode().expect("exit init");
    inst
}

/// The same route in the in-process lockstep with the FMU's four host-obstacle slots
/// (radius 0.3 m, the FMU's default), and its instruction count.
pub fn route_lockstep(seed: u64) -> (Lockstep, usize) {
    route_lockstep_with(seed, ParamFiles::default())
}

/// [`route_lockstep`] with parameter files.
pub fn route_lockstep_with(seed: u64, params: ParamFiles) -> (Lockstep, usize) {
    let spec = RunSpec {
        scene: "playground".into(),
        instructions: vec![INSTRUCTIONS.into()],
        backend: BackendKind::Rapier,
        seed,
        params,
    };
    let scene = spec.load_scene().expect("playground");
    let count = plamo_planner::parse_instructions(INSTRUCTIONS, &scene)
        .expect("route")
        .len();
    let links =
        in_process_with_external(&spec, &scene, &[ObstacleShape::Sphere { radius: 0.3 }; 4])
            .expect("links");
    let ls = Lockstep::start(links, scene, &[count], &ControllerSettings::default(), 1e6)
        .expect("lockstep");
    (ls, count)
}
