//! `plamo eval locomotion`: paper Table 2's protocol for the controller. For each
//! terrain (flat, slope, rough, stairs) x form (crawl 0.4 m @ 1 m/s, crouch-walk 0.8 m
//! @ 2 m/s, walk 1.47 m @ 2 m/s, run 1.47 m @ 4 m/s), straight paths with constant speed
//! and head height along the terrain strip; prints mean XY/Z errors next to the
//! paper's, fall rate and residual; writes markdown and a bar plot.
//!
//! The paper's other experiments (`slalom`, `pyramid`, `random`, `dynamic`) and
//! `merge` and `compare` live in [`plamo::eval`]; here are only their arguments.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::{Args, Subcommand};
use plamo::eval::dynamic::Dynamic;
use plamo::eval::pyramid::{self, Pyramid};
use plamo::eval::random::RandomScenes;
use plamo::eval::slalom::{self, QpConfig, Slalom};
use plamo::eval::{self, Experiment, RunOptions, Shard};
use plamo::progress::Progress;
use plamo::spec::ControllerParams;
use plamo::viz::{FAMILY, ensure_registered};
use plamo_controller::{
    ControllerSettings, MetricsSummary, RUN_STAGGER, RampedPath, START_ACCEL, STRIP_LENGTH,
    StraightPath, run_path_with, staggered_start, terrain_scene,
};
use plamo_physics::BackendKind;
use plamo_scenes::Scene;
use plotters::prelude::*;
use rayon::prelude::*;

/// `plamo eval ...` subcommands.
#[derive(Debug, Subcommand)]
pub enum EvalCommand {
    /// Table 2: terrain x locomotion form tracking errors.
    Locomotion(LocomotionArgs),
    /// Slalom: constant speeds vs the speed QP; Pareto plots (failure, error vs time).
    Slalom(SlalomArgs),
    /// Pyramid: path length and time with terrain preference c = 0 vs larger c.
    Pyramid(PyramidArgs),
    /// Random 4-landmark scenes: success rate (Wilson interval), failure causes.
    Random(RandomArgs),
    /// Moving obstacles crossing the way: collision rate, re-planning on vs off.
    Dynamic(DynamicArgs),
    /// Combine the shard folders of one sweep (`--shard i/n`) into one result, or
    /// summarize one whole-sweep folder again.
    Merge(MergeArgs),
    /// Pair two random-scene sweeps tour by tour (same seeds): gained and lost tours,
    /// exact McNemar test, identical trajectories, outcomes and first falls.
    Compare(CompareArgs),
}

/// Arguments every experiment sweep takes.
#[derive(Debug, Args)]
pub struct SweepArgs {
    /// Physics engine: rapier, or mujoco (build with `--features mujoco`).
    #[arg(long, default_value = "rapier")]
    physics: BackendKind,
    /// Output folder (created); default: eval-<experiment>.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Run only part i of n of the sweep (e.g. 2/4); combine with `plamo eval merge`.
    #[arg(long)]
    shard: Option<Shard>,
    /// Worker threads (0: one per core). Results do not depend on it.
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Cap every run's simulated time [s] (quick looks and tests).
    #[arg(long)]
    max_seconds: Option<f64>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Planner parameter file: a TOML table of planner settings (see
    /// `PlannerSettings`; fields left out keep their defaults). Each experiment sets
    /// its own swept fields on top of it.
    #[arg(long)]
    planner_params: Option<PathBuf>,
    /// Biped gait parameter file, e.g. from `plamo tune` (default: the built-in one).
    #[arg(long)]
    gait_params: Option<PathBuf>,
    /// Crawl parameter file, e.g. from `plamo tune --form crawl` (default: the
    /// built-in one).
    #[arg(long)]
    crawl_params: Option<PathBuf>,
    /// Physics parameter file: a TOML table of physics settings (see
    /// `PhysicsSettings`; fields left out keep their defaults).
    #[arg(long)]
    physics_params: Option<PathBuf>,
}

impl SweepArgs {
    fn options(&self, name: &str) -> anyhow::Result<RunOptions> {
        let planner = self
            .planner_params
            .as_deref()
            .map(plamo::spec::load_planner_settings)
            .transpose()
            .map_err(anyhow::Error::msg)?;
        let controller =
            ControllerParams::load(self.gait_params.as_deref(), self.crawl_params.as_deref())
                .map_err(anyhow::Error::msg)?;
        let physics_settings = self
            .physics_params
            .as_deref()
            .map(plamo::spec::load_physics_settings)
            .transpose()
            .map_err(anyhow::Error::msg)?;
        Ok(RunOptions {
            physics: self.physics,
            out: self
                .out
                .clone()
                .unwrap_or_else(|| PathBuf::from(format!("eval-{name}"))),
            shard: self.shard.unwrap_or(Shard::ALL),
            threads: self.threads,
            max_seconds: self.max_seconds,
            quiet: self.quiet,
            planner,
            controller,
            physics_settings,
        })
    }
}

/// Arguments of `plamo eval slalom`.
#[derive(Debug, Args)]
pub struct SlalomArgs {
    #[command(flatten)]
    sweep: SweepArgs,
    /// Runs per point (paper: 100).
    #[arg(long, default_value_t = 10)]
    runs: usize,
    /// Seed of the first run (run r: seed + r).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Constant speeds [m/s], comma-separated (default 1,1.5,2,2.5,3,3.5).
    #[arg(long, value_delimiter = ',')]
    speeds: Option<Vec<f64>>,
    /// Speed-QP configurations V_MAX:A_LAT:A_MAX[:A_MIN], comma-separated
    /// (default: see `plamo::eval::slalom::DEFAULT_QP`).
    #[arg(long, value_delimiter = ',')]
    qp: Option<Vec<QpConfig>>,
}

/// Arguments of `plamo eval pyramid`.
#[derive(Debug, Args)]
pub struct PyramidArgs {
    #[command(flatten)]
    sweep: SweepArgs,
    /// Runs per terrain preference.
    #[arg(long, default_value_t = 4)]
    runs: usize,
    /// Seed of the first run (run r: seed + r).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Terrain preferences c, comma-separated (default 0,0.5,1,4).
    #[arg(long, value_delimiter = ',')]
    c: Option<Vec<f64>>,
}

/// Arguments of `plamo eval random`.
#[derive(Debug, Args)]
pub struct RandomArgs {
    #[command(flatten)]
    sweep: SweepArgs,
    /// Number of random scenes.
    #[arg(long, default_value_t = 50)]
    scenes: usize,
    /// Seed of the first scene (scene k: `plamo scenes random --seed S+k`).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Forms the legs are drawn from, comma-separated (crawl, crouch-walk, walk, run;
    /// default all four, the paper's tours). `--forms crawl`: every leg crawls.
    #[arg(long, value_delimiter = ',')]
    forms: Vec<String>,
    /// Scene seeds to run, comma-separated, instead of `--scenes` from `--seed`
    /// (e.g. the tours a sweep lost, as a bench; `plamo eval compare` pairs them with
    /// the full sweep's).
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["scenes", "seed"])]
    seeds: Vec<u64>,
}

/// Arguments of `plamo eval dynamic`.
#[derive(Debug, Args)]
pub struct DynamicArgs {
    #[command(flatten)]
    sweep: SweepArgs,
    /// Number of corridor scenes (each run with re-planning on and off).
    #[arg(long, default_value_t = 20)]
    scenes: usize,
    /// Seed of the first scene.
    #[arg(long, default_value_t = 0)]
    seed: u64,
}

/// Arguments of `plamo eval merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// The shard folders, one per shard of the sweep.
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Output folder of the combined result (created).
    #[arg(long)]
    out: PathBuf,
}

/// Arguments of `plamo eval compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// Folder of the base sweep (`plamo eval random --out`).
    base: PathBuf,
    /// Folder of the sweep compared against it.
    new: PathBuf,
    /// Folder to write `compare.md` into (created); default: print only.
    #[arg(long)]
    out: Option<PathBuf>,
}

fn report(md: anyhow::Result<String>, out: &std::path::Path) -> anyhow::Result<ExitCode> {
    say!("{}", md?);
    say!("wrote {}", out.display());
    Ok(ExitCode::SUCCESS)
}

fn sweep<E: Experiment>(e: &E, a: &SweepArgs) -> anyhow::Result<ExitCode> {
    let opts = a.options(E::NAME)?;
    report(eval::run(e, &opts), &opts.out)
}

/// Arguments of `plamo eval locomotion`.
#[derive(Debug, Args)]
pub struct LocomotionArgs {
    /// Physics engine: rapier or mujoco.
    #[arg(long, default_value = "rapier")]
    physics: String,
    /// Runs per cell (start offsets differ).
    #[arg(long, default_value_t = 4)]
    runs: usize,
    /// Longest simulated time per run [s].
    #[arg(long, default_value_t = 10.0)]
    duration: f64,
    /// Biped gait parameter file, e.g. from `plamo tune` (default: the built-in one).
    #[arg(long, visible_alias = "params")]
    gait_params: Option<PathBuf>,
    /// Crawl parameter file, e.g. from `plamo tune --form crawl` (default: the built-in
    /// one).
    #[arg(long)]
    crawl_params: Option<PathBuf>,
    /// Physics parameter file: a TOML table of physics settings (see
    /// `PhysicsSettings`; fields left out keep their defaults).
    #[arg(long)]
    physics_params: Option<PathBuf>,
    /// Output directory (created).
    #[arg(long, default_value = "eval-locomotion")]
    out: PathBuf,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

const TERRAINS: [&str; 4] = ["flat", "slope", "rough", "stairs"];
/// (name, head height m, speed m/s).
const FORMS: [(&str, f64, f64); 4] = [
    ("crawl", 0.4, 1.0),
    ("crouch-walk", 0.8, 2.0),
    ("walk", 1.47, 2.0),
    ("run", 1.47, 4.0),
];
/// Paper Table 2, (XY, Z) per terrain row and form column [m].
const PAPER: [[(f64, f64); 4]; 4] = [
    [(0.20, 0.07), (0.20, 0.03), (0.24, 0.21), (0.52, 0.26)],
    [(0.21, 0.09), (0.22, 0.03), (0.25, 0.21), (0.60, 0.27)],
    [(0.25, 0.10), (0.25, 0.04), (0.29, 0.24), (0.79, 0.31)],
    [(0.45, 0.13), (0.41, 0.07), (0.39, 0.27), (1.01, 0.35)],
];

/// Mean results of one cell.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
struct Cell {
    xy: f64,
    /// The XY error's along-track part (+ behind the plan) and its cross-track part,
    /// means over the runs \[m\] (see `plamo_controller::metrics`).
    lag: f64,
    cross_track: f64,
    z: f64,
    falls_per_min: f64,
    fallen_fraction: f64,
    residual_mean: f64,
    residual_peak: f64,
    /// Residual torque mean over the runs, peak over them \[N m\].
    torque_mean: f64,
    torque_peak: f64,
}

/// Runs `plamo eval`.
pub fn run(cmd: EvalCommand) -> anyhow::Result<ExitCode> {
    match cmd {
        EvalCommand::Locomotion(a) => locomotion(a),
        EvalCommand::Slalom(a) => sweep(
            &Slalom::new(
                a.runs,
                a.seed,
                a.speeds.unwrap_or_else(|| slalom::DEFAULT_SPEEDS.to_vec()),
                a.qp.unwrap_or_else(|| slalom::DEFAULT_QP.to_vec()),
            )?,
            &a.sweep,
        ),
        EvalCommand::Pyramid(a) => sweep(
            &Pyramid::new(
                a.runs,
                a.seed,
                a.c.unwrap_or_else(|| pyramid::DEFAULT_C.to_vec()),
            )?,
            &a.sweep,
        ),
        EvalCommand::Random(a) => {
            let mut e = RandomScenes::new(a.scenes, a.seed, &a.forms)?;
            if !a.seeds.is_empty() {
                e = e.with_seeds(&a.seeds)?;
            }
            sweep(&e, &a.sweep)
        }
        EvalCommand::Dynamic(a) => sweep(&Dynamic::new(a.scenes, a.seed)?, &a.sweep),
        EvalCommand::Merge(a) => report(eval::merge(&a.dirs, &a.out), &a.out),
        EvalCommand::Compare(a) => {
            let md = eval::compare::compare(&a.base, &a.new, a.out.as_deref())?;
            say!("{md}");
            if let Some(out) = &a.out {
                say!("wrote {}", out.join("compare.md").display());
            }
            Ok(ExitCode::SUCCESS)
        }
    }
}

fn locomotion(a: LocomotionArgs) -> anyhow::Result<ExitCode> {
    let backend: BackendKind = a
        .physics
        .parse()
        .map_err(|e| anyhow::anyhow!("--physics: {e}"))?;
    let params = ControllerParams::load(a.gait_params.as_deref(), a.crawl_params.as_deref())
        .map_err(anyhow::Error::msg)?;
    let physics_settings = plamo::spec::physics_settings_or_default(a.physics_params.as_deref())
        .map_err(anyhow::Error::msg)?;
    let settings = ControllerSettings {
        body_mass: plamo_physics::humanoid::total_mass(),
        ..Default::default()
    };
    let scenes: Vec<(Scene, [f64; 2])> = TERRAINS
        .iter()
        .map(|t| Ok(terrain_scene(t)?))
        .collect::<anyhow::Result<_>>()?;
    let jobs: Vec<(usize, usize, usize)> = (0..TERRAINS.len())
        .flat_map(|t| (0..FORMS.len()).flat_map(move |f| (0..a.runs).map(move |r| (t, f, r))))
        .collect();
    let bar = Progress::new(
        jobs.len() as u64,
        "locomotion",
        "{bar:30} {pos}/{len} runs [{elapsed} < {eta}]",
        a.quiet,
    )?;
    let results: Vec<anyhow::Result<MetricsSummary>> = jobs
        .par_iter()
        .map(|&(t, f, r)| {
            let (scene, start) = &scenes[t];
            let (_, head, speed) = FORMS[f];
            // Runs differ by where they start along the strip and sideways [m].
            let path = RampedPath {
                line: StraightPath {
                    start: staggered_start(*start, r),
                    speed,
                    head_height: head,
                },
                accel: START_ACCEL,
            };
            let duration = a
                .duration
                .min((STRIP_LENGTH - RUN_STAGGER * r as f64) / speed);
            let mut policy = params.policy(backend, settings.clone())?;
            let m = run_path_with(
                backend,
                &physics_settings,
                scene,
                &path,
                duration,
                &mut policy,
                &settings,
            )?;
            bar.inc(1);
            Ok(m)
        })
        .collect();
    bar.finish();
    let mut cells = [[Cell::default(); 4]; 4];
    for (&(t, f, _), m) in jobs.iter().zip(results) {
        let m = m?;
        let c = &mut cells[t][f];
        let k = a.runs as f64;
        c.xy += m.xy_err_mean / k;
        c.lag += m.lag_mean / k;
        c.cross_track += m.cross_track_mean / k;
        c.z += m.z_err_mean / k;
        c.falls_per_min += f64::from(m.falls) / m.duration_s.max(1e-9) * 60.0 / k;
        c.fallen_fraction += m.fallen_fraction / k;
        c.residual_mean += m.residual_force_mean / k;
        c.residual_peak = c.residual_peak.max(m.residual_force_peak);
        c.torque_mean += m.residual_torque_mean / k;
        c.torque_peak = c.torque_peak.max(m.residual_torque_peak);
    }
    let md = markdown(&cells, &a);
    say!("{md}");
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    std::fs::write(a.out.join("locomotion.md"), &md)?;
    std::fs::write(
        a.out.join("locomotion.json"),
        serde_json::to_string_pretty(&cells)?,
    )?;
    plot(&cells, &a.out.join("locomotion.png"))?;
    say!("wrote {}", a.out.display());
    Ok(ExitCode::SUCCESS)
}

fn markdown(cells: &[[Cell; 4]; 4], a: &LocomotionArgs) -> String {
    let mut s = format!(
        "Command: `plamo eval locomotion --physics {} --runs {} --duration {}{}`\n\n\
         Paths start from rest at {START_ACCEL} m/s^2, then keep the form's speed.\n\n\
         Mean head XY-err / Z-err [m], ours (paper Table 2 in brackets).\n\n\
         | terrain | crawl 0.4 m @ 1 | crouch-walk 0.8 m @ 2 | walk 1.47 m @ 2 | run 1.47 m @ 4 |\n|---|---|---|---|---|\n",
        a.physics,
        a.runs,
        a.duration,
        [
            ("--gait-params", &a.gait_params),
            ("--crawl-params", &a.crawl_params),
            ("--physics-params", &a.physics_params)
        ]
        .iter()
        .filter_map(|(flag, p)| p.as_ref().map(|p| format!(" {flag} {}", p.display())))
        .collect::<String>()
    );
    push_rows(&mut s, cells, |t, f, c| {
        let (px, pz) = PAPER[t][f];
        format!("{:.2} / {:.2} ({px:.2} / {pz:.2})", c.xy, c.z)
    });
    s.push_str(
        "\nThe XY-err split along the plan's direction of travel: lag (along the path, + \
         behind the plan's point) / off the route (cross-track) [m]; a humanoid on the \
         route but slower than its plan has all of its XY-err as lag:\n\n\
         | terrain | crawl | crouch-walk | walk | run |\n|---|---|---|---|---|\n",
    );
    push_rows(&mut s, cells, |_, _, c| {
        format!("{:.2} / {:.2}", c.lag, c.cross_track)
    });
    s.push_str(
        "\nFalls per minute / fraction of steps fallen / residual force mean, peak [m*g] / \
         residual torque mean, peak [N m]:\n\n\
         | terrain | crawl | crouch-walk | walk | run |\n|---|---|---|---|---|\n",
    );
    push_rows(&mut s, cells, |_, _, c| {
        format!(
            "{:.1} / {:.2} / {:.2}, {:.2} / {:.0}, {:.0}",
            c.falls_per_min,
            c.fallen_fraction,
            c.residual_mean,
            c.residual_peak,
            c.torque_mean,
            c.torque_peak
        )
    });
    s
}

/// One markdown row per terrain, `cell(terrain, form, cell)` in each form's column.
fn push_rows(s: &mut String, cells: &[[Cell; 4]; 4], cell: impl Fn(usize, usize, &Cell) -> String) {
    for (t, row) in cells.iter().enumerate() {
        s.push_str(&format!("| {} |", TERRAINS[t]));
        for (f, c) in row.iter().enumerate() {
            s.push_str(&format!(" {} |", cell(t, f, c)));
        }
        s.push('\n');
    }
}

fn plot(cells: &[[Cell; 4]; 4], path: &std::path::Path) -> anyhow::Result<()> {
    ensure_registered()?;
    let root = BitMapBackend::new(path, (1000, 500)).into_drawing_area();
    root.fill(&WHITE)?;
    let max = cells
        .iter()
        .flatten()
        .map(|c| c.xy)
        .chain(PAPER.iter().flatten().map(|p| p.0))
        .fold(0.5_f64, f64::max)
        * 1.1;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Head XY error: ours (filled) vs paper (outline)",
            (FAMILY, 20),
        )
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0.0..16.0, 0.0..max)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_desc("XY-err [m]")
        .label_style((FAMILY, 14))
        .draw()?;
    let colors = [RED, BLUE, GREEN, MAGENTA];
    for t in 0..4 {
        for f in 0..4 {
            let x0 = (t * 4 + f) as f64 + 0.1;
            let c = colors[f];
            chart.draw_series(std::iter::once(Rectangle::new(
                [(x0, 0.0), (x0 + 0.4, cells[t][f].xy)],
                c.filled(),
            )))?;
            chart.draw_series(std::iter::once(Rectangle::new(
                [(x0 + 0.4, 0.0), (x0 + 0.8, PAPER[t][f].0)],
                c.stroke_width(2),
            )))?;
        }
        chart.draw_series(std::iter::once(Text::new(
            TERRAINS[t].to_string(),
            (t as f64 * 4.0 + 1.5, -max * 0.04),
            (FAMILY, 15).into_font(),
        )))?;
    }
    for (f, (name, _, _)) in FORMS.iter().enumerate() {
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(0.0, 0.0), (0.0, 0.0)],
                colors[f].filled(),
            )))?
            .label(*name)
            .legend(move |(x, y)| {
                Rectangle::new([(x, y - 5), (x + 10, y + 5)], colors[f].filled())
            });
    }
    chart
        .configure_series_labels()
        .label_font((FAMILY, 14))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}
