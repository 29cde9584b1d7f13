//! `plamo run`: the product's main job. Planner, controller and physics run in
//! lockstep on a scene (in this process, or each in its own process with
//! `--processes`) until every agent has carried out its instructions or
//! `--max-seconds` of simulated time have passed; a summary per instruction follows.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use plamo::progress::Progress;
use plamo_interfaces::RunId;
use plamo_physics::BackendKind;
use serde::Serialize;

use plamo::ipc::IpcSettings;
use plamo::lockstep::{InstructionReport, Lockstep, StepStatus, median_p99, pace};
use plamo::processes::{Launch, ProcessRun, component_args};
use plamo::record::Recorder;
use plamo::spec::{ParamFiles, RunSpec};
use plamo::viz::{ColorBar, MapOverlay, OverlayMarker, OverlayPath, render_map};

/// What decides a run's result; shared by `plamo run` and `plamo component`.
#[derive(Debug, Clone, Args)]
pub struct SpecArgs {
    /// Built-in scene name or path to a scene file.
    #[arg(long)]
    scene: String,
    /// Instructions; give it once for every agent, or once per agent.
    #[arg(long, required = true)]
    instructions: Vec<String>,
    /// Physics engine: rapier, or mujoco (build with `--features mujoco`).
    #[arg(long, default_value = "rapier")]
    physics: BackendKind,
    /// Seed of the start-heading perturbation.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Number of humanoids (default: one per `--instructions`).
    #[arg(long)]
    agents: Option<usize>,
    /// Biped gait parameter file, e.g. from `plamo tune` (default: the built-in one).
    #[arg(long)]
    gait_params: Option<PathBuf>,
    /// Crawl parameter file, e.g. from `plamo tune --form crawl` (default: the
    /// built-in one).
    #[arg(long)]
    crawl_params: Option<PathBuf>,
    /// Planner parameter file: a TOML table of planner settings (see
    /// `PlannerSettings`; fields left out keep their defaults).
    #[arg(long)]
    planner_params: Option<PathBuf>,
    /// Physics parameter file: a TOML table of physics settings (see
    /// `PhysicsSettings`: friction, solver iterations, contact stiffness...; fields
    /// left out keep their defaults).
    #[arg(long)]
    physics_params: Option<PathBuf>,
}

impl SpecArgs {
    /// The run spec, one instruction text per agent.
    pub fn to_spec(&self) -> anyhow::Result<RunSpec> {
        let n = self.agents.unwrap_or(self.instructions.len());
        let max = plamo_interfaces::MAX_AGENTS;
        if !(1..=max).contains(&n) {
            anyhow::bail!("--agents {n}: must be in 1..={max}");
        }
        let instructions = match self.instructions.len() {
            1 => vec![self.instructions[0].clone(); n],
            m if m == n => self.instructions.clone(),
            m => anyhow::bail!(
                "{m} --instructions for {n} agents: give one for all or one per agent"
            ),
        };
        // A bad parameter file fails here, before any component process starts.
        if let Some(f) = &self.planner_params {
            plamo::spec::load_planner_settings(f).map_err(anyhow::Error::msg)?;
        }
        if let Some(f) = &self.physics_params {
            plamo::spec::load_physics_settings(f).map_err(anyhow::Error::msg)?;
        }
        plamo::spec::ControllerParams::load(
            self.gait_params.as_deref(),
            self.crawl_params.as_deref(),
        )
        .map_err(anyhow::Error::msg)?;
        Ok(RunSpec {
            scene: self.scene.clone(),
            instructions,
            backend: self.physics,
            seed: self.seed,
            // Absolute, so component processes started elsewhere find the same files.
            params: ParamFiles {
                gait: self
                    .gait_params
                    .as_deref()
                    .map(std::path::absolute)
                    .transpose()?,
                crawl: self
                    .crawl_params
                    .as_deref()
                    .map(std::path::absolute)
                    .transpose()?,
                planner: self
                    .planner_params
                    .as_deref()
                    .map(std::path::absolute)
                    .transpose()?,
                physics: self
                    .physics_params
                    .as_deref()
                    .map(std::path::absolute)
                    .transpose()?,
            },
        })
    }
}

/// Arguments of `plamo run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    #[command(flatten)]
    spec: SpecArgs,
    /// Run planner, controller and physics as separate processes over iceoryx2.
    #[arg(long)]
    processes: bool,
    /// With --processes: do not spawn the components; print the `plamo component`
    /// commands and wait for them to be started by hand.
    #[arg(long, requires = "processes")]
    attach: bool,
    /// With --attach: how long to wait for the components to come up [s].
    #[arg(long, default_value_t = 300.0, requires = "attach")]
    attach_timeout: f64,
    /// Pace the simulation to the wall clock (only sleeps; results are unchanged).
    #[arg(long)]
    realtime: bool,
    /// Simulated-time limit [s] (default: 2 x the planned route time + 15 s, as in the
    /// evals).
    #[arg(long)]
    max_seconds: Option<f64>,
    /// Run id (isolates the run's shared memory); default: generated from pid and time.
    #[arg(long)]
    run: Option<String>,
    /// Record plans, trajectory, obstacles, metrics and a map into this directory.
    #[arg(long)]
    out: Option<PathBuf>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Fault for the physics process (reliability tests): crash@TICK, wrong-tick@TICK.
    #[arg(long, hide = true, requires = "processes")]
    inject_fault: Option<String>,
}

#[derive(Serialize)]
struct AgentPlanJson<'a> {
    agent: usize,
    instructions: &'a [plamo_planner::Instruction],
    route: &'a [plamo_planner::Trajectory],
}

#[derive(Serialize)]
struct MetricsJson<'a> {
    scene: &'a str,
    physics: &'a str,
    seed: u64,
    status: &'a str,
    ticks: u64,
    simulated_s: f64,
    digest: String,
    agents: Vec<AgentJson<'a>>,
}

#[derive(Serialize)]
struct AgentJson<'a> {
    agent: usize,
    instructions: Vec<String>,
    results: &'a [InstructionReport],
}

/// A command line a POSIX shell reads back as `program` and `args`.
fn shell_words(program: &str, args: &[String]) -> String {
    let quote = |w: &str| {
        if !w.is_empty()
            && w.bytes()
                .all(|b| b.is_ascii_alphanumeric() || b"-_./=@:,".contains(&b))
        {
            w.to_string()
        } else {
            format!("'{}'", w.replace('\'', r"'\''"))
        }
    };
    std::iter::once(program)
        .chain(args.iter().map(String::as_str))
        .map(quote)
        .collect::<Vec<_>>()
        .join(" ")
}

fn generated_run_id() -> String {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    format!("r{}-{:x}", std::process::id(), (nanos as u64) & 0xffff_ffff)
}

/// Run `plamo run`.
pub fn run(args: RunArgs) -> anyhow::Result<ExitCode> {
    let spec = args.spec.to_spec()?;
    if !spec.backend.is_available() {
        anyhow::bail!(
            "`--physics {}` needs plamo built with the `mujoco` feature \
             (scripts/install-mujoco.sh, then `cargo run --release --features mujoco -- run ...`)",
            spec.backend
        );
    }
    let scene = spec.load_scene()?;
    // The routes as planned from the start (also what each planner computes first).
    let planners = (0..spec.agents())
        .map(|k| spec.planner(&scene, k))
        .collect::<Result<Vec<_>, _>>()?;
    let route_time = planners
        .iter()
        .filter_map(|p| p.planner().route().last().map(|t| t.end_time()))
        .fold(0.0, f64::max);
    let max_seconds = args
        .max_seconds
        .unwrap_or_else(|| plamo::spec::default_time_limit(route_time));
    let counts: Vec<usize> = planners
        .iter()
        .map(|p| p.planner().instructions().len())
        .collect();
    let texts: Vec<Vec<String>> = planners
        .iter()
        .map(|p| {
            p.planner()
                .instructions()
                .iter()
                .map(|i| i.text.clone())
                .collect()
        })
        .collect();

    let run_id = RunId::new(&args.run.clone().unwrap_or_else(generated_run_id))
        .map_err(anyhow::Error::msg)?;
    let wall = Instant::now();
    let (links, procs) = if args.processes {
        let exe = std::env::current_exe().context("locating the plamo executable")?;
        let launch = if args.attach {
            eprintln!("run `{run_id}`: start each component, e.g. in its own terminal:");
            for (_, _, a) in component_args(&spec, &run_id) {
                eprintln!("  {}", shell_words(&exe.display().to_string(), &a));
            }
            Launch::Attach
        } else {
            Launch::Spawn {
                exe: &exe,
                physics_fault: args.inject_fault.as_deref(),
            }
        };
        let mut settings = IpcSettings::default();
        if args.attach {
            if !(args.attach_timeout.is_finite() && args.attach_timeout > 0.0) {
                anyhow::bail!(
                    "--attach-timeout {}: must be a positive number of seconds",
                    args.attach_timeout
                );
            }
            settings.ready_timeout = std::time::Duration::from_secs_f64(args.attach_timeout);
        }
        let (procs, links) = ProcessRun::launch(&spec, &run_id, launch, settings)?;
        for stale in &procs.cleaned {
            eprintln!(
                "removed {} stale shared-memory file(s) of crashed run `{}`",
                stale.files, stale.run
            );
        }
        (links, Some(procs))
    } else {
        (spec.in_process(&scene)?, None)
    };
    let setup_s = wall.elapsed().as_secs_f64();
    let mut recorder = match &args.out {
        Some(dir) => Some(
            Recorder::create(dir, spec.agents())
                .with_context(|| format!("creating {}", dir.display()))?,
        ),
        None => None,
    };
    let outcome = drive(
        links,
        &scene,
        &counts,
        max_seconds,
        &args,
        recorder.as_mut(),
        &texts,
    );
    let (lockstep, status, loop_s, late) = match outcome {
        Ok(v) => v,
        Err(failed) => {
            let (e, links) = *failed;
            let killed = procs.map(|p| p.finish(links)).unwrap_or_default();
            if !killed.is_empty() {
                eprintln!("stopped by force: {}", killed.join(", "));
            }
            return Err(anyhow::Error::new(e).context(format!("run `{run_id}` failed")));
        }
    };
    let times = lockstep.times().clone();
    let sim_s = lockstep.tick().seconds();
    let report = lockstep.report();
    let digest = lockstep.digest().value();
    let world = *lockstep.world();
    if let Some(p) = procs {
        p.finish(Some(lockstep.into_links()));
    }
    let wall_s = wall.elapsed().as_secs_f64();

    // Summary.
    let status_text = match status {
        StepStatus::Finished => "finished",
        _ => "timed out",
    };
    say!(
        "{} on `{}` ({}, {} agent(s), {}): {status_text} after {sim_s:.2} s simulated",
        if args.processes {
            "multi-process"
        } else {
            "in-process"
        },
        scene.name,
        spec.backend,
        spec.agents(),
        if args.realtime {
            "real time"
        } else {
            "as fast as possible"
        },
    );
    let mut all_ok = status == StepStatus::Finished;
    for (k, (results, names)) in report.iter().zip(&texts).enumerate() {
        for (r, text) in results.iter().zip(names) {
            all_ok &= r.success;
            let m = &r.metrics;
            say!(
                "  agent {k} [{}] {text:<40} {:>6.1} s  xy {:.2} m (lag {:.2}, off route {:.2})  z {:.2} m  falls {}  residual {:.1}% / {:.1}% m g, {:.0} / {:.0} N m",
                if r.success {
                    "ok"
                } else if r.reached {
                    "FELL"
                } else {
                    "FAIL"
                },
                r.time_s,
                m.xy_err_mean,
                m.lag_mean,
                m.cross_track_mean,
                m.z_err_mean,
                m.falls,
                100.0 * m.residual_force_mean,
                100.0 * m.residual_force_peak,
                m.residual_torque_mean,
                m.residual_torque_peak,
            );
        }
    }
    let (step_med, step_p99) = median_p99(&times.steps);
    let (phys_med, phys_p99) = median_p99(&times.physics);
    let (plan_med, plan_p99) = median_p99(&times.planners);
    let (ctl_med, ctl_p99) = median_p99(&times.controllers);
    say!(
        "wall {wall_s:.2} s (setup {setup_s:.2} s, loop {loop_s:.2} s), real-time factor {:.1}x{}",
        sim_s / loop_s.max(1e-9),
        if args.realtime {
            format!(", {late} late tick(s)")
        } else {
            String::new()
        }
    );
    say!(
        "per control step [us] median/p99: step {:.0}/{:.0}, physics {:.0}/{:.0}, planners {:.0}/{:.0}, controllers {:.0}/{:.0}",
        step_med * 1e6,
        step_p99 * 1e6,
        phys_med * 1e6,
        phys_p99 * 1e6,
        plan_med * 1e6,
        plan_p99 * 1e6,
        ctl_med * 1e6,
        ctl_p99 * 1e6
    );
    say!("trajectory digest {digest:016x}");

    if let (Some(dir), Some(rec)) = (&args.out, recorder.as_mut()) {
        rec.finish()?;
        write_outputs(
            dir,
            &scene,
            &spec,
            &planners,
            rec,
            &report,
            &texts,
            status_text,
            &world,
            digest,
        )?;
        plamo::record::write_scene(dir, &scene)?;
        plamo::export::export_dir(dir)?;
        say!(
            "wrote {} (replay.glb, motion.bvh, replay.mcap; watch it: plamo view {0})",
            dir.display()
        );
    }
    Ok(if all_ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

type Driven = (Lockstep, StepStatus, f64, u64);
/// A run error and the links to shut down (boxed: the links are large).
type Failed = Box<(plamo::lockstep::RunError, Option<plamo::lockstep::Links>)>;

fn drive(
    links: plamo::lockstep::Links,
    scene: &plamo_scenes::Scene,
    counts: &[usize],
    max_seconds: f64,
    args: &RunArgs,
    mut recorder: Option<&mut Recorder>,
    texts: &[Vec<String>],
) -> Result<Driven, Failed> {
    let controller = plamo_controller::ControllerSettings::default();
    let mut ls = Lockstep::start(links, scene.clone(), counts, &controller, max_seconds)
        .map_err(|e| Box::new((e, None)))?;
    let io = |e: std::io::Error| plamo::lockstep::RunError::Setup(format!("recording: {e}"));
    let bar = Progress::new(
        (max_seconds * 30.0).ceil() as u64,
        "control steps",
        "{bar:30} {msg}",
        args.quiet,
    )
    .map_err(|e| Box::new((plamo::lockstep::RunError::Setup(e.to_string()), None)))?;
    let start = Instant::now();
    let mut late = 0u64;
    macro_rules! bail {
        ($e:expr) => {{
            bar.abandon();
            return Err(Box::new(($e, Some(ls.into_links()))));
        }};
    }
    // A world is written once the next control step has judged it by the fall rule,
    // so the trajectory's `fallen` column is the one the fall counts use.
    let mut unwritten = *ls.world();
    let status = loop {
        let step = ls.step();
        if let Some(r) = recorder.as_deref_mut() {
            let done = !matches!(step, Ok(StepStatus::Running));
            if let Err(e) = r.world(&unwritten, ls.fall_verdicts()) {
                bail!(io(e));
            }
            if !done {
                r.plans(ls.plans());
                unwritten = *ls.world();
            }
        }
        match step {
            Ok(StepStatus::Running) => {}
            Ok(s) => break s,
            Err(e) => bail!(e),
        }
        if args.realtime && pace(start, ls.tick(), 1.0) {
            late += 1;
        }
        let c = ls.tick().0 / 4;
        if c % 15 == 0 {
            let t = ls.tick().seconds();
            let k = ls.instruction(0);
            let n = texts[0].len();
            bar.set_position(c);
            bar.set_message(format!(
                "instruction {}/{n} `{}`  t {t:.1} s  {:.1}x real time",
                (k + 1).min(n),
                texts[0].get(k).map_or("done", String::as_str),
                t / start.elapsed().as_secs_f64().max(1e-9)
            ));
        }
    };
    bar.finish_and_clear();
    Ok((ls, status, start.elapsed().as_secs_f64(), late))
}

/// Speed colour scale of the executed path: blue at rest, red at 3 m/s.
fn speed_bar() -> ColorBar {
    ColorBar {
        label: "executed head speed [m/s]".into(),
        min: 0.0,
        max: 3.0,
        colors: vec![
            [30, 60, 220],
            [20, 170, 200],
            [40, 170, 60],
            [240, 180, 20],
            [215, 30, 30],
        ],
    }
}

#[allow(clippy::too_many_arguments)]
fn write_outputs(
    dir: &Path,
    scene: &plamo_scenes::Scene,
    spec: &RunSpec,
    planners: &[plamo_planner::PlannerComponent],
    rec: &Recorder,
    report: &[Vec<InstructionReport>],
    texts: &[Vec<String>],
    status: &str,
    world: &plamo_interfaces::PhysicsOutput,
    digest: u64,
) -> anyhow::Result<()> {
    let plans: Vec<AgentPlanJson> = planners
        .iter()
        .enumerate()
        .map(|(agent, p)| AgentPlanJson {
            agent,
            instructions: p.planner().instructions(),
            route: p.planner().route(),
        })
        .collect();
    let replans: Vec<serde_json::Value> = rec
        .replans
        .iter()
        .map(|p| {
            serde_json::json!({
                "tick": p.tick,
                "agent": p.agent,
                "instruction": p.instruction,
                "waypoints": p.waypoints.iter().map(|w| [w.position[0], w.position[1], w.position[2], w.speed]).collect::<Vec<_>>(),
            })
        })
        .collect();
    std::fs::write(
        dir.join("plans.json"),
        serde_json::to_string_pretty(&serde_json::json!({ "initial": plans, "replans": replans }))?,
    )?;
    let metrics = MetricsJson {
        scene: &scene.name,
        physics: spec.backend.as_str(),
        seed: spec.seed,
        status,
        ticks: world.tick,
        simulated_s: plamo_interfaces::Tick(world.tick).seconds(),
        digest: format!("{digest:016x}"),
        agents: report
            .iter()
            .zip(texts)
            .enumerate()
            .map(|(agent, (results, names))| AgentJson {
                agent,
                instructions: names.clone(),
                results,
            })
            .collect(),
    };
    std::fs::write(
        dir.join("metrics.json"),
        serde_json::to_string_pretty(&metrics)?,
    )?;

    let bar = speed_bar();
    let mut overlay = MapOverlay {
        title: format!("{}: planned (grey) vs executed head path", scene.name),
        colorbar: Some(bar.clone()),
        ..Default::default()
    };
    for (k, p) in planners.iter().enumerate() {
        for tr in p.planner().route() {
            overlay.paths.push(OverlayPath {
                points: tr.points.iter().map(|q| [q.x, q.y]).collect(),
                colors: vec![[90, 90, 90]],
                width: 2,
                dashed: true,
                label: (k == 0).then(|| "planned".to_string()),
            });
        }
    }
    for (k, heads) in rec.heads.iter().enumerate() {
        if heads.len() < 2 {
            continue;
        }
        overlay.paths.push(OverlayPath {
            points: heads.iter().map(|h| h.xy).collect(),
            colors: heads[..heads.len() - 1]
                .iter()
                .map(|h| bar.color_for(h.speed))
                .collect(),
            width: 3,
            dashed: false,
            label: Some(format!("agent {k} executed (colour: speed)")),
        });
        if let Some(h) = heads.last() {
            overlay.markers.push(OverlayMarker {
                at: h.xy,
                color: [0, 0, 0],
                label: Some(format!("agent {k} end")),
            });
        }
    }
    render_map(scene, &overlay, &dir.join("run.png"))?;
    Ok(())
}
