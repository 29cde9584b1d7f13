//! `plamo-planner.fmu`: the planner alone, for hosts that move their own character.
//! Inputs are the character's head position; outputs are the next waypoints and the
//! planned speed, updated at the control rate (30 Hz) whatever the host's step.

use plamo_planner::{PlanStatus, Planner, PlannerInput};

use crate::instance::{Model, ModelContext, Value};
use crate::resources::{ParamFile, param_files, planner_settings, resolve_scene, text};
use crate::spec::{ModelSpec, VarType, Variable};

/// Waypoints exposed (paper 4.2: 10 samples, 0.5 s apart).
pub const WAYPOINTS: usize = 10;
/// Physics ticks per control step and ticks per second (see plamo-interfaces).
const TICKS_PER_CONTROL: u64 = 4;
const TICKS_PER_SECOND: f64 = 120.0;

/// GUID of the planner-only FMU.
pub const GUID: &str = "{5d3c8a1e-7f0b-4c1e-9a52-706c616e6e72}";

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
            "Run from the tree to the car, then crawl to the bench",
            "instructions, e.g. 'Run from the tree to the car, then crawl to the bench'",
        ),
        Variable::parameter(
            "terrain_preference",
            VarType::Real,
            "1.0",
            "slope preference c of the A* cost e^(c*slope)-1 (0 = shortest path); it overrides `slope_preference_c` of a planner parameter file",
        ),
        ParamFile::Planner.variable(),
        Variable::real_input(
            "character.x",
            0.0,
            Some("m"),
            "head position x of the host's character",
        ),
        Variable::real_input(
            "character.y",
            0.0,
            Some("m"),
            "head position y of the host's character",
        ),
        Variable::real_input(
            "character.z",
            0.0,
            Some("m"),
            "head position z of the host's character",
        ),
    ];
    for k in 1..=WAYPOINTS {
        for (axis, unit, what) in [
            ("x", "m", "x"),
            ("y", "m", "y"),
            ("z", "m", "head height z"),
            ("speed", "m/s", "speed"),
        ] {
            v.push(Variable::output(
                format!("waypoint[{k}].{axis}"),
                VarType::Real,
                Some(unit),
                format!("planned {what} {:.1} s ahead", k as f64 * 0.5),
            ));
        }
    }
    v.extend([
        Variable::output(
            "speed",
            VarType::Real,
            Some("m/s"),
            "planned speed at the current time",
        ),
        Variable::output(
            "instruction",
            VarType::Integer,
            None,
            "index of the instruction being executed (0-based)",
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
            "infeasible",
            VarType::Boolean,
            None,
            "the current target cannot be reached from the character's position",
        ),
        Variable::output(
            "replanned",
            VarType::Boolean,
            None,
            "the plan was rebuilt during the last step",
        ),
    ]);
    ModelSpec {
        model_name: "plamo-planner",
        model_identifier: "plamo_fmu",
        guid: GUID,
        description: "PlaMo scene-aware path planner: instructions to timed head waypoints with speed",
        variables: v,
    }
}

fn real(values: &[Value], vr: u32) -> f64 {
    match values[vr as usize] {
        Value::Real(x) => x,
        _ => f64::NAN,
    }
}

struct PlannerModel {
    planner: Planner,
    next_tick: u64,
    input_vr: [u32; 3],
    first_output: u32,
    last_head: Option<[f64; 3]>,
}

/// Build the planner from the parameters and the character's initial position.
pub fn build(
    spec: &ModelSpec,
    ctx: &ModelContext,
    values: &[Value],
) -> Result<Box<dyn Model>, String> {
    let vr = |n: &str| {
        spec.vr(n)
            .ok_or_else(|| format!("internal: no variable {n}"))
    };
    let scene = resolve_scene(&text(values, spec, "scene"), ctx)?;
    let files = param_files(&[ParamFile::Planner], values, spec, ctx)?;
    let settings = plamo_planner::PlannerSettings {
        slope_preference_c: real(values, vr("terrain_preference")?),
        ..planner_settings(&files)?
    };
    let input_vr = [vr("character.x")?, vr("character.y")?, vr("character.z")?];
    let start = [real(values, input_vr[0]), real(values, input_vr[1])];
    let planner = Planner::new(scene, &text(values, spec, "instructions"), start, settings)
        .map_err(|e| format!("parameter `instructions`: {e}"))?;
    Ok(Box::new(PlannerModel {
        planner,
        next_tick: 0,
        input_vr,
        first_output: vr("waypoint[1].x")?,
        last_head: None,
    }))
}

impl Model for PlannerModel {
    fn advance(&mut self, t: f64, values: &mut [Value]) -> Result<(), String> {
        let head = self.input_vr.map(|vr| real(values, vr));
        let mut replanned = false;
        let mut last = None;
        while self.next_tick as f64 / TICKS_PER_SECOND <= t {
            let dt = TICKS_PER_CONTROL as f64 / TICKS_PER_SECOND;
            let velocity = match self.last_head {
                Some(p) => [
                    (head[0] - p[0]) / dt,
                    (head[1] - p[1]) / dt,
                    (head[2] - p[2]) / dt,
                ],
                None => [0.0; 3],
            };
            let input = PlannerInput {
                head,
                root: head,
                velocity,
                obstacles: Vec::new(),
            };
            let out = self
                .planner
                .plan_step(plamo_interfaces::Tick(self.next_tick), &input)
                .map_err(|e| {
                    format!(
                        "planner at t = {:.3} s: {e}",
                        self.next_tick as f64 / TICKS_PER_SECOND
                    )
                })?;
            replanned |= out.replanned.is_some();
            self.last_head = Some(head);
            self.next_tick += TICKS_PER_CONTROL;
            last = Some(out);
        }
        let Some(out) = last else { return Ok(()) };
        let mut vr = self.first_output as usize;
        for k in 0..WAYPOINTS {
            let w = out.waypoints.get(k).or(out.waypoints.last());
            let (p, s) = w.map_or(([f64::NAN; 3], 0.0), |w| (w.position, w.speed));
            for x in [p[0], p[1], p[2], s] {
                values[vr] = Value::Real(x);
                vr += 1;
            }
        }
        let now_speed = out
            .trajectory
            .sample_at((self.next_tick - TICKS_PER_CONTROL) as f64 / TICKS_PER_SECOND)
            .speed;
        values[vr] = Value::Real(now_speed);
        values[vr + 1] = Value::Integer(out.progress.index as i32);
        values[vr + 2] = Value::Integer(self.planner.instructions().len() as i32);
        values[vr + 3] = Value::Real(out.progress.fraction);
        values[vr + 4] = Value::Boolean(out.status == PlanStatus::Finished);
        values[vr + 5] = Value::Boolean(matches!(out.status, PlanStatus::Infeasible { .. }));
        values[vr + 6] = Value::Boolean(replanned);
        Ok(())
    }
}
