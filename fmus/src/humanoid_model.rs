//! `plamo.fmu`: the whole humanoid. Planner, controller and physics run in the
//! orchestrator's in-process lockstep (120 Hz physics, 30 Hz control) whatever the
//! host's communication step; the host can drive up to [`EXTERNAL_OBSTACLES`]
//! obstacles (a ball, a car) that the planner re-plans around and the humanoid
//! collides with (kinematic bodies in the physics world, moved from each sample at
//! its velocity).
//!
//! Timing: a communication step to host time t runs every control step that ends at
//! or before t (with a relative tolerance of 1e-9, so a host's 0.009999999999999998
//! counts as 0.01); a step that ends between two control steps leaves the outputs at
//! the last control step before it, and the next step catches up. Inputs are held
//! over a step (zero-order hold): the obstacle states the host set before fmi2DoStep
//! apply to every control step inside it. Once every instruction is done the run
//! stops: later steps keep the outputs as they were at arrival.

use plamo::lockstep::external::{PARKED_SAMPLE, in_process_with_external};
use plamo::lockstep::{Lockstep, StepStatus};
use plamo::spec::RunSpec;
use plamo_controller::ControllerSettings;
use plamo_interfaces::{ObstacleSample, PHYSICS_HZ, PHYSICS_STEPS_PER_CONTROL};
use plamo_physics::{BackendKind, JOINT_NAMES};
use plamo_planner::FLAG_FINISHED;
use plamo_scenes::ObstacleShape;

use crate::instance::{Model, ModelContext, Value};
use crate::resources::{ParamFile, param_files, resolve_scene, text};
use crate::spec::{ModelSpec, VarType, Variable};

/// GUID of the humanoid FMU.
pub const GUID: &str = "{9b1f2c47-3e8d-4a6b-8c15-706c616d6f31}";

/// External obstacles a host can drive (each with an `active` switch).
pub const EXTERNAL_OBSTACLES: usize = 4;

/// Simulated-time limit of the lockstep \[s\]: the host's stop time decides.
const MAX_SECONDS: f64 = 1.0e6;

/// The parameter files the whole humanoid takes.
const PARAM_FILES: [ParamFile; 4] = [
    ParamFile::Planner,
    ParamFile::Gait,
    ParamFile::Crawl,
    ParamFile::Physics,
];

const OBSTACLE_FIELDS: [(&str, &str, &str); 6] = [
    ("x", "m", "centre x"),
    ("y", "m", "centre y"),
    ("z", "m", "centre z"),
    ("vx", "m/s", "velocity x"),
    ("vy", "m/s", "velocity y"),
    ("vz", "m/s", "velocity z"),
];

/// The variable table.
pub fn spec() -> ModelSpec {
    let mut v = vec![
        Variable::parameter(
            "scene",
            VarType::String,
            "playground",
            "built-in scene name, or a scene file path (relative paths are looked up in the FMU's resources/ first)",
        ),
        Variable::parameter(
            "instructions",
            VarType::String,
            "Walk from the fountain to the sandbox",
            "instructions; the first must say where the humanoid starts ('from the <landmark>')",
        ),
        Variable::parameter(
            "physics",
            VarType::String,
            "rapier",
            "physics engine: rapier, or mujoco when this binary was built with it",
        ),
        Variable::parameter(
            "seed",
            VarType::Integer,
            "0",
            "seed of the start-heading perturbation (>= 0)",
        ),
        Variable::parameter(
            "obstacle_radius",
            VarType::Real,
            "0.3",
            "radius of the host-driven obstacles, spheres for the planner and physics [m]",
        ),
    ];
    v.extend(PARAM_FILES.map(ParamFile::variable));
    for k in 1..=EXTERNAL_OBSTACLES {
        v.push(Variable::input(
            format!("obstacle[{k}].active"),
            VarType::Boolean,
            "false",
            None,
            format!("host obstacle {k} is present (false: ignored)"),
        ));
        for (field, unit, what) in OBSTACLE_FIELDS {
            v.push(Variable::real_input(
                format!("obstacle[{k}].{field}"),
                0.0,
                Some(unit),
                format!("host obstacle {k}: {what}"),
            ));
        }
    }
    let real = |name: &str, unit: &'static str, what: &str| {
        Variable::output(name, VarType::Real, Some(unit), what)
    };
    for axis in ["x", "y", "z"] {
        v.push(real(&format!("head.{axis}"), "m", &format!("head {axis}")));
    }
    for axis in ["x", "y", "z"] {
        v.push(real(
            &format!("root.{axis}"),
            "m",
            &format!("root (pelvis) {axis}"),
        ));
    }
    for c in ["qx", "qy", "qz", "qw"] {
        v.push(real(
            &format!("root.{c}"),
            "1",
            &format!("root orientation quaternion, component {}", &c[1..]),
        ));
    }
    v.push(real("speed", "m/s", "horizontal speed of the root"));
    for j in JOINT_NAMES {
        v.push(real(&format!("joint.{j}"), "rad", &format!("angle of {j}")));
    }
    v.extend([
        Variable::output(
            "instruction",
            VarType::Integer,
            None,
            "index of the instruction being executed (0-based; = instruction_count when done)",
        ),
        Variable::output(
            "instruction_count",
            VarType::Integer,
            None,
            "number of instructions",
        ),
        Variable::output(
            "progress",
            VarType::Real,
            Some("1"),
            "fraction of the current instruction's path covered",
        ),
        Variable::output(
            "done",
            VarType::Boolean,
            None,
            "every instruction's target was reached",
        ),
        Variable::output(
            "fallen",
            VarType::Boolean,
            None,
            "the humanoid was found fallen at the last control step (it is stood up again)",
        ),
        real(
            "xy_error",
            "m",
            "horizontal distance of the head from where the plan wanted it",
        ),
    ]);
    ModelSpec {
        model_name: "plamo",
        model_identifier: "plamo_fmu",
        guid: GUID,
        description: "PlaMo humanoid: scene-aware planner, controller and physics in lockstep, carrying out text instructions",
        variables: v,
    }
}

/// The `physics` parameter as a backend of this build.
pub fn backend(name: &str) -> Result<BackendKind, String> {
    let allowed: Vec<&str> = BackendKind::ALL
        .iter()
        .filter(|k| k.is_available())
        .map(|k| k.as_str())
        .collect();
    let kind: BackendKind = name.parse().map_err(|_| {
        format!(
            "parameter `physics` = {name:?}: unknown engine; allowed in this build: {}",
            allowed.join(", ")
        )
    })?;
    if !kind.is_available() {
        return Err(format!(
            "parameter `physics` = {name:?}: this FMU was built without the {kind} backend; allowed in this build: {}",
            allowed.join(", ")
        ));
    }
    Ok(kind)
}

/// Value references of one host obstacle: `active`, then x, y, z, vx, vy, vz.
type ObstacleVrs = [usize; 7];

struct HumanoidModel {
    lockstep: Lockstep,
    finished: bool,
    obstacles: [ObstacleVrs; EXTERNAL_OBSTACLES],
    first_output: usize,
    instruction_count: usize,
}

/// Build the lockstep run from the parameters.
pub fn build(
    spec: &ModelSpec,
    ctx: &ModelContext,
    values: &[Value],
) -> Result<Box<dyn Model>, String> {
    let vr = |n: &str| {
        spec.vr(n)
            .map(|v| v as usize)
            .ok_or_else(|| format!("internal: no variable {n}"))
    };
    let scene_name = text(values, spec, "scene");
    let scene = resolve_scene(&scene_name, ctx)?;
    let kind = backend(&text(values, spec, "physics"))?;
    let seed = match values[vr("seed")?] {
        Value::Integer(s) if s >= 0 => s as u64,
        Value::Integer(s) => return Err(format!("parameter `seed` = {s}: must be >= 0")),
        _ => return Err("internal: `seed` is not an Integer".into()),
    };
    let radius = match values[vr("obstacle_radius")?] {
        Value::Real(r) if r > 0.0 && r.is_finite() => r,
        Value::Real(r) => {
            return Err(format!(
                "parameter `obstacle_radius` = {r}: must be a positive number of metres"
            ));
        }
        _ => return Err("internal: `obstacle_radius` is not a Real".into()),
    };
    let run = RunSpec {
        scene: scene_name,
        instructions: vec![text(values, spec, "instructions")],
        backend: kind,
        seed,
        params: param_files(&PARAM_FILES, values, spec, ctx)?,
    };
    let shapes = [ObstacleShape::Sphere { radius }; EXTERNAL_OBSTACLES];
    let links = in_process_with_external(&run, &scene, &shapes).map_err(|e| e.to_string())?;
    let count = plamo_planner::parse_instructions(&run.instructions[0], &scene)
        .map_err(|e| format!("parameter `instructions`: {e}"))?
        .len();
    let lockstep = Lockstep::start(
        links,
        scene,
        &[count],
        &ControllerSettings::default(),
        MAX_SECONDS,
    )
    .map_err(|e| e.to_string())?;
    let mut obstacles = [[0; 7]; EXTERNAL_OBSTACLES];
    for (k, o) in obstacles.iter_mut().enumerate() {
        o[0] = vr(&format!("obstacle[{}].active", k + 1))?;
        for (i, (field, _, _)) in OBSTACLE_FIELDS.iter().enumerate() {
            o[i + 1] = vr(&format!("obstacle[{}].{field}", k + 1))?;
        }
    }
    Ok(Box::new(HumanoidModel {
        lockstep,
        finished: false,
        obstacles,
        first_output: vr("head.x")?,
        instruction_count: count,
    }))
}

/// The host obstacles as the lockstep takes them: every slot, inactive ones parked.
pub fn obstacle_samples(
    values: &[Value],
    vrs: &[ObstacleVrs; EXTERNAL_OBSTACLES],
) -> [ObstacleSample; EXTERNAL_OBSTACLES] {
    let real = |vr: usize| match values[vr] {
        Value::Real(x) => x,
        _ => 0.0,
    };
    vrs.map(|o| {
        if values[o[0]] != Value::Boolean(true) {
            return PARKED_SAMPLE;
        }
        ObstacleSample {
            position: [real(o[1]), real(o[2]), real(o[3])],
            velocity: [real(o[4]), real(o[5]), real(o[6])],
        }
    })
}

/// Every output of the humanoid FMU, in variable-table order from `head.x`, as the
/// lockstep stands now. Shared by the FMU and the tests' in-process reference.
pub fn outputs(ls: &Lockstep, finished: bool, instruction_count: usize) -> Vec<Value> {
    let s = &ls.world().agents[0];
    let plan = &ls.plans()[0];
    let mut out = Vec::with_capacity(12 + JOINT_NAMES.len() + 6);
    out.extend(s.head_position.map(Value::Real));
    out.extend(s.root_position.map(Value::Real));
    out.extend(s.root_orientation.map(Value::Real));
    let v = s.root_linear_velocity;
    out.push(Value::Real((v[0] * v[0] + v[1] * v[1]).sqrt()));
    out.extend(
        s.joint_angles[..JOINT_NAMES.len()]
            .iter()
            .map(|a| Value::Real(*a)),
    );
    let done = finished || plan.flags & FLAG_FINISHED != 0;
    out.push(Value::Integer(plan.instruction as i32));
    out.push(Value::Integer(instruction_count as i32));
    out.push(Value::Real(plan.progress));
    out.push(Value::Boolean(done));
    out.push(Value::Boolean(ls.fall_verdicts()[0]));
    out.push(Value::Real(ls.xy_error(0)));
    out
}

/// Control steps the lockstep owes to reach `t` seconds after the start (with `t`
/// already carrying the caller's tolerance): every step that ends at or before `t`.
pub fn due_tick(t: f64) -> u64 {
    (t * PHYSICS_HZ as f64).floor() as u64
}

impl Model for HumanoidModel {
    fn advance(&mut self, t: f64, values: &mut [Value]) -> Result<(), String> {
        let samples = obstacle_samples(values, &self.obstacles);
        self.lockstep
            .set_external_obstacles(&samples)
            .map_err(|e| e.to_string())?;
        let due = due_tick(t);
        let per = PHYSICS_STEPS_PER_CONTROL as u64;
        while !self.finished && self.lockstep.tick().0 + per <= due {
            match self.lockstep.step().map_err(|e| e.to_string())? {
                StepStatus::Running => {}
                StepStatus::Finished | StepStatus::TimedOut => self.finished = true,
            }
        }
        for (i, x) in outputs(&self.lockstep, self.finished, self.instruction_count)
            .into_iter()
            .enumerate()
        {
            values[self.first_output + i] = x;
        }
        Ok(())
    }
}
