//! The FMUs' parameter files (`planner_params`, `gait_params`, `crawl_params`,
//! `physics_params`, as `plamo run --planner-params ...`): the humanoid FMU given them runs bit for bit as
//! the in-process lockstep given the same files, and not as with the built-in
//! parameters; a file shipped in resources/ is found by its name; a bad or missing
//! file fails initialisation with a message naming the parameter and what is wrong.
//! Driven through the same state machine the C entry points wrap (fmu-runner has no
//! string API; FMPy sets them in `fmpy_host.py`).

use std::ffi::CString;
use std::path::{Path, PathBuf};

use plamo::lockstep::external::PARKED_SAMPLE;
use plamo::lockstep::{Lockstep, StepStatus};
use plamo::spec::ParamFiles;
use plamo_fmu::humanoid_model::outputs;
use plamo_fmu::instance::{Instance, ModelContext, Value};
use plamo_fmu::models;

mod support;
use support::route_lockstep_with;

/// Control steps compared (4 s).
const STEPS: usize = 120;
const H: f64 = 1.0 / 30.0;

fn params_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../components/controller/params")
}

/// An initialised instance of `guid` with the String parameters `strings` and the
/// Real ones `reals`, or the message initialisation failed with.
fn start(
    guid: &str,
    strings: &[(&str, &str)],
    reals: &[(&str, f64)],
    resources: Option<PathBuf>,
) -> Result<Instance, String> {
    let (spec, factory) = models::by_guid(guid).expect("a GUID of this binary");
    let mut inst = Instance::new(spec, factory, ModelContext { resources });
    inst.setup_experiment(0.0).unwrap();
    inst.enter_initialization().unwrap();
    for (name, value) in strings {
        let vr = spec
            .vr(name)
            .unwrap_or_else(|| panic!("no variable {name}"));
        inst.set_string(vr, CString::new(*value).unwrap()).unwrap();
    }
    for (name, value) in reals {
        inst.set_real(&[spec.vr(name).unwrap()], &[*value]).unwrap();
    }
    inst.exit_initialization().map_err(|e| e.to_string())?;
    Ok(inst)
}

/// The humanoid FMU's outputs as the reference's `outputs` lists them.
fn fmu_outputs(inst: &Instance) -> Vec<Value> {
    let spec = inst.spec();
    let first = spec.vr("head.x").unwrap() as usize;
    spec.variables[first..]
        .iter()
        .enumerate()
        .map(|(k, v)| {
            let vr = [(first + k) as u32];
            match v.ty {
                plamo_fmu::spec::VarType::Real => {
                    let mut x = [0.0];
                    inst.get_real(&vr, &mut x).unwrap();
                    Value::Real(x[0])
                }
                plamo_fmu::spec::VarType::Integer => {
                    let mut x = [0];
                    inst.get_integer(&vr, &mut x).unwrap();
                    Value::Integer(x[0])
                }
                plamo_fmu::spec::VarType::Boolean => {
                    let mut x = [false];
                    inst.get_boolean(&vr, &mut x).unwrap();
                    Value::Boolean(x[0])
                }
                plamo_fmu::spec::VarType::String => unreachable!("no String outputs"),
            }
        })
        .collect()
}

/// Bit patterns, so that -0.0 and NaN compare as what they are.
fn bits(v: &[Value]) -> Vec<(u8, u64)> {
    v.iter()
        .map(|x| match x {
            Value::Real(r) => (0, r.to_bits()),
            Value::Integer(i) => (1, *i as u64),
            Value::Boolean(b) => (2, *b as u64),
            Value::String(_) => (3, 0),
        })
        .collect()
}

/// The head's path over `STEPS` control steps of the humanoid FMU, each step's
/// outputs checked against `reference` (when given) bit for bit.
fn run(inst: &mut Instance, mut reference: Option<(Lockstep, usize)>) -> Vec<[f64; 2]> {
    let mut head = Vec::new();
    let mut finished = false;
    for k in 0..STEPS {
        let got = fmu_outputs(inst);
        if let Some((ls, count)) = &reference {
            assert_eq!(
                bits(&got),
                bits(&outputs(ls, finished, *count)),
                "outputs at control step {k}"
            );
        }
        if let [Value::Real(x), Value::Real(y), ..] = got[..] {
            head.push([x, y]);
        }
        inst.do_step(k as f64 * H, H).unwrap();
        if let Some((ls, _)) = &mut reference {
            ls.set_external_obstacles(&[PARKED_SAMPLE; 4]).unwrap();
            if ls.step().unwrap() != StepStatus::Running {
                finished = true;
            }
        }
    }
    head
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn the_humanoid_fmu_with_parameter_files_runs_as_the_in_process_lockstep_given_them() {
    let dir = tempfile::tempdir().unwrap();
    // Slower walking (the built-in walk reaches 1 m/s in these 4 s), so the planner file shows in the path; the gait and crawl files
    // are copies of the shipped ones (rapier's built-in gait file: the FMU's physics is
    // rapier), read from where the parameter says.
    let planner = write(dir.path(), "slow.toml", "walk_speed = 0.6\n");
    let gait = dir.path().join("gait.toml");
    let crawl = dir.path().join("crawl.toml");
    std::fs::copy(params_dir().join("gait-rapier.toml"), &gait).unwrap();
    std::fs::copy(params_dir().join("crawl.toml"), &crawl).unwrap();
    // Stiffer contacts than the default 11 Hz.
    let physics = write(dir.path(), "stiff.toml", "rapier_contact_hz = 30.0\n");
    let files = ParamFiles {
        planner: Some(planner.clone()),
        gait: Some(gait.clone()),
        crawl: Some(crawl.clone()),
        physics: Some(physics.clone()),
    };
    let strings = [
        ("planner_params", planner.to_str().unwrap()),
        ("gait_params", gait.to_str().unwrap()),
        ("crawl_params", crawl.to_str().unwrap()),
        ("physics_params", physics.to_str().unwrap()),
    ];
    let mut inst = start(plamo_fmu::HUMANOID_GUID, &strings, &[], None).unwrap();
    let with_files = run(&mut inst, Some(route_lockstep_with(0, files)));
    let mut soft = start(plamo_fmu::HUMANOID_GUID, &strings[..3], &[], None).unwrap();
    assert_ne!(
        run(&mut soft, None),
        with_files,
        "the physics file changed nothing"
    );

    // Shipped in resources/ and named relative: the same run.
    let mut shipped = start(
        plamo_fmu::HUMANOID_GUID,
        &[
            ("planner_params", "slow.toml"),
            ("physics_params", "stiff.toml"),
        ],
        &[],
        Some(dir.path().to_path_buf()),
    )
    .unwrap();
    assert_eq!(
        run(&mut shipped, None),
        with_files,
        "planner and physics files in resources/"
    );

    let mut built_in = start(plamo_fmu::HUMANOID_GUID, &[], &[], None).unwrap();
    let default_path = run(&mut built_in, None);
    let travelled = |p: &[[f64; 2]]| {
        p.windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .sum::<f64>()
    };
    let (slow, fast) = (travelled(&with_files), travelled(&default_path));
    assert!(
        slow < 0.85 * fast,
        "with walk_speed = 0.6 the head travelled {slow:.2} m in 4 s, built in {fast:.2} m"
    );
}

#[test]
fn a_bad_or_missing_parameter_file_names_the_parameter_and_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let typo = write(dir.path(), "typo.toml", "walk_sped = 1.0\n");
    let mut gait = std::fs::read_to_string(params_dir().join("gait.toml")).unwrap();
    gait.push_str("foot_fwd_gian = 0.1\n");
    let bad_gait = write(dir.path(), "bad-gait.toml", &gait);
    let not_crawl = write(dir.path(), "not-crawl.toml", "walk_speed = 0.6\n");
    let bad_physics = write(dir.path(), "bad-physics.toml", "friction = -1.0\n");
    let cases = [
        (
            "planner_params",
            typo.to_str().unwrap(),
            vec!["planner_params", "walk_sped"],
        ),
        (
            "gait_params",
            bad_gait.to_str().unwrap(),
            vec!["gait_params", "foot_fwd_gian"],
        ),
        (
            "crawl_params",
            not_crawl.to_str().unwrap(),
            vec!["crawl_params", "walk_speed"],
        ),
        (
            "physics_params",
            bad_physics.to_str().unwrap(),
            vec!["physics_params", "friction", ">= 0"],
        ),
        (
            "planner_params",
            "no-such.toml",
            vec!["planner_params", "no-such.toml", "built-in"],
        ),
    ];
    for (param, value, needles) in cases {
        let e = start(plamo_fmu::HUMANOID_GUID, &[(param, value)], &[], None)
            .err()
            .unwrap_or_else(|| panic!("{param} = {value}: initialisation must fail"));
        for n in needles {
            assert!(
                e.contains(n),
                "{param} = {value}: {e:?} does not name {n:?}"
            );
        }
    }
    let e = start(
        plamo_fmu::PLANNER_GUID,
        &[("planner_params", typo.to_str().unwrap())],
        &[],
        None,
    )
    .err()
    .expect("the planner FMU refuses the typo too");
    assert!(
        e.contains("walk_sped") && e.contains("planner_params"),
        "{e}"
    );
}

#[test]
fn the_planner_fmu_plans_with_its_parameter_file() {
    let dir = tempfile::tempdir().unwrap();
    let slow = write(dir.path(), "slow.toml", "walk_speed = 0.6\n");
    let top_speed = |strings: &[(&str, &str)]| {
        let start_at = [
            ("character.x", 25.0),
            ("character.y", 5.0),
            ("character.z", 1.47),
        ];
        let mut strings = strings.to_vec();
        strings.push(("instructions", "walk from the car to the bench"));
        let inst = start(plamo_fmu::PLANNER_GUID, &strings, &start_at, None).unwrap();
        let spec = inst.spec();
        (1..=10)
            .map(|k| {
                let mut s = [0.0];
                inst.get_real(&[spec.vr(&format!("waypoint[{k}].speed")).unwrap()], &mut s)
                    .unwrap();
                s[0]
            })
            .fold(0.0, f64::max)
    };
    let built_in = top_speed(&[]);
    let with_file = top_speed(&[("planner_params", slow.to_str().unwrap())]);
    assert!(
        built_in > 0.9,
        "built-in walk reaches {built_in} m/s in 5 s"
    );
    assert!(
        with_file <= 0.6 + 1e-9 && with_file > 0.3,
        "with walk_speed = 0.6 the plan reaches {with_file} m/s"
    );
}
