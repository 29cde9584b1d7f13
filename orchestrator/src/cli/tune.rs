//! `plamo tune`: offline "training" of the model-based gait. Separable CMA-ES over one
//! form's parameters (plamo-controller `tune`), rollouts in parallel with rayon,
//! deterministic per seed; writes the whole parameter file of the form: the biped's
//! `gait.toml` for walk, run and crouch, `crawl.toml` for the crawl.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use plamo::tune_tours::TourObjective;
use plamo_controller::{
    ControllerSettings, CrawlParams, Form, GaitParams, SearchField, TrackingGuard, TuneSettings,
    TunedParams, search_box, start_like, tune, tune_with,
};
use plamo_physics::BackendKind;

/// Arguments of `plamo tune`.
#[derive(Debug, Args)]
pub struct TuneArgs {
    /// Form to tune: walk, run, crouch (`gait.toml`) or crawl (`crawl.toml`).
    #[arg(long, default_value = "walk")]
    form: String,
    /// CMA-ES generations.
    #[arg(long, default_value_t = 30)]
    budget: u32,
    /// Seed of candidate and scenario draws.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Physics engines, comma-separated (rapier, mujoco).
    #[arg(long, default_value = "mujoco")]
    physics: String,
    /// Rollouts per candidate and engine.
    #[arg(long, default_value_t = 4)]
    rollouts: usize,
    /// Simulated seconds per rollout.
    #[arg(long, default_value_t = 8.0)]
    duration: f64,
    /// Starting parameter file of the form (a gait file, or a crawl file with
    /// `--form crawl`; default: the built-in one, for a gait search in rapier alone
    /// rapier's `gait-rapier.toml`, else `gait.toml`).
    #[arg(long)]
    from: Option<PathBuf>,
    /// Start the search from another form's tuned parameters (e.g. `--start-like walk`
    /// for the run).
    #[arg(long)]
    start_like: Option<String>,
    /// Ground of the rollouts, comma-separated, assigned round-robin: flat, slope,
    /// rough, stairs (the strips of `plamo eval locomotion`), ceiling (flat under a
    /// 0.6 m ceiling, for the crawl), hill (a straight path across two hills' flanks),
    /// arc (4 m turns on flat ground), drop (a walk that
    /// drops to the form at 3 s, on flat ground), rise (the form, standing up at half
    /// the rollout, on flat ground), turnback (a stop after 3 m and back at 2.6 rad, on
    /// flat ground).
    #[arg(long, default_value = "flat")]
    terrains: String,
    /// Price candidates by whole random tours instead of rollouts: the first N tours
    /// of `plamo eval random` from `--tour-seed` with a leg in the form, each through
    /// planner and orchestrator in every `--physics` engine; the cost is the fall cost
    /// per tour not finished + head XY error + Z error + residual force; the start and the result are
    /// then priced on the next N tours too, which the search never saw. 0: rollouts.
    #[arg(long, default_value_t = 0, conflicts_with_all = ["rollouts", "duration", "terrains"])]
    tours: usize,
    /// First scene seed of the `--tours` (default far past the seeds RESULTS.md
    /// reports, so a search does not tune on its test set).
    #[arg(long, default_value_t = plamo::tune_tours::DEFAULT_TOUR_SEED)]
    tour_seed: u64,
    /// With `--tours`: a candidate whose mean head XY error on flat rollouts (straight
    /// and 4 m turns, from standing, at the form's speeds) is more than this many
    /// metres above the start's pays 10 per metre beyond, so the search cannot buy
    /// fewer failed tours with a form that lags its plan.
    #[arg(long, value_name = "METRES", allow_negative_numbers = true)]
    keep_tracking: Option<f64>,
    /// Physics parameter file: a TOML table of physics settings for every rollout
    /// (see `PhysicsSettings`; fields left out keep their defaults).
    #[arg(long)]
    physics_params: Option<PathBuf>,
    /// Cost of a fall per rollout, in metres of XY error (default: the form's own, 3 for
    /// the run and the crawl, 1 for the walk and the crouch).
    #[arg(long, allow_negative_numbers = true)]
    fall_cost: Option<f64>,
    /// A field to search beyond the form's built-in box, or a new range for one of its
    /// fields, in the field's unit: NAME=LO..HI, e.g. `--search max_speed=0.7..1.4` for
    /// the crawl, `--search residual.rot_gain=100..300` for the walk. Repeatable; any
    /// number field of the form's section of the file (`[walk]`, `[run]`, `[crouch]`
    /// and `residual.*` for the biped, the whole crawl file for the crawl).
    #[arg(long, value_name = "NAME=LO..HI")]
    search: Vec<String>,
    /// Output parameter file (default: gait.toml, or crawl.toml with `--form crawl`).
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Runs `plamo tune`.
pub fn run(args: TuneArgs) -> anyhow::Result<ExitCode> {
    let form: Form = args.form.parse()?;
    if let Some(c) = args.fall_cost
        && !(c.is_finite() && c >= 0.0)
    {
        anyhow::bail!("--fall-cost must be a finite number >= 0 (m-equivalent per fall), got {c}");
    }
    anyhow::ensure!(
        args.keep_tracking.is_none() || args.tours > 0,
        "--keep-tracking guards a search on tours: give --tours N too"
    );
    let backends = args
        .physics
        .split(',')
        .map(|b| b.trim().parse::<BackendKind>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| anyhow::anyhow!("--physics: {e}"))?;
    let mut base = TunedParams::default();
    // A search in one engine starts from that engine's built-in gait.
    if let [only] = backends[..] {
        base.gait = GaitParams::built_in(only);
    }
    match (&args.from, form) {
        (Some(p), Form::Crawl) => base.crawl = CrawlParams::load(p)?,
        (Some(p), _) => base.gait = GaitParams::load(p)?,
        (None, _) => {}
    }
    let base = match &args.start_like {
        Some(like) => start_like(&base, form, like.parse()?)?,
        None => base,
    };
    let out = args.out.clone().unwrap_or_else(|| {
        PathBuf::from(if form == Form::Crawl {
            "crawl.toml"
        } else {
            "gait.toml"
        })
    });
    let search = args
        .search
        .iter()
        .map(|f| f.parse::<SearchField>())
        .collect::<Result<Vec<_>, _>>()?;
    // Checked before the first rollout: a typo in a field name fails at once.
    search_box(form, &search)?;
    let physics = plamo::spec::physics_settings_or_default(args.physics_params.as_deref())
        .map_err(anyhow::Error::msg)?;
    let settings = TuneSettings {
        form,
        generations: args.budget,
        seed: args.seed,
        backends,
        rollouts: args.rollouts,
        duration: args.duration,
        sigma0: 0.15,
        controller: ControllerSettings {
            body_mass: plamo_physics::humanoid::total_mass(),
            ..Default::default()
        },
        terrains: args.terrains.split(',').map(|t| t.trim().into()).collect(),
        physics,
        fall_cost: args.fall_cost,
        search: search.clone(),
    };
    let bar = ProgressBar::new(u64::from(args.budget));
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} gen  {msg}  [{elapsed} < {eta}]")
            .context("progress template")?,
    );
    // A bar is drawn only on a terminal; a tune run from a script or a cluster job (15
    // minutes and more) logs one line per generation instead (every generation, not
    // every tenth as `plamo::progress` does: each is minutes of work).
    let log_lines = !std::io::stderr().is_terminal();
    let (what, version) = match form {
        Form::Crawl => ("Crawl", plamo_controller::CRAWL_PARAMS_VERSION),
        _ => ("Model-based gait", plamo_controller::GAIT_PARAMS_VERSION),
    };
    let objective = if args.tours > 0 {
        format!(
            "--tours {} --tour-seed {}{}",
            args.tours,
            args.tour_seed,
            args.keep_tracking
                .map(|m| format!(" --keep-tracking {m}"))
                .unwrap_or_default()
        )
    } else {
        format!(
            "--rollouts {} --duration {} --terrains {}",
            args.rollouts, args.duration, args.terrains
        )
    };
    let command = format!(
        "plamo tune --form {} --budget {} --seed {} --physics {} {objective}{}{}{}{}{} --out {}",
        args.form,
        args.budget,
        args.seed,
        args.physics,
        args.from
            .as_ref()
            .map(|p| format!(" --from {}", p.display()))
            .unwrap_or_default(),
        args.start_like
            .as_ref()
            .map(|f| format!(" --start-like {f}"))
            .unwrap_or_default(),
        args.physics_params
            .as_ref()
            .map(|p| format!(" --physics-params {}", p.display()))
            .unwrap_or_default(),
        args.fall_cost
            .map(|c| format!(" --fall-cost {c}"))
            .unwrap_or_default(),
        search
            .iter()
            .map(|f| format!(" --search {f}"))
            .collect::<String>(),
        out.display(),
    );
    // The guard checks its margin and prices the start before the tours are drawn,
    // so a bad `--keep-tracking` is refused at once.
    let guard = args
        .keep_tracking
        .map(|margin| {
            TrackingGuard::new(&base, &settings, margin)
                .map_err(|e| anyhow::anyhow!("--keep-tracking: {e}"))
        })
        .transpose()?;
    let tours = if args.tours > 0 {
        let t = TourObjective::new(
            form,
            args.tours,
            args.tour_seed,
            settings.backends.clone(),
            settings.physics.clone(),
            args.fall_cost,
        )?;
        say!(
            "pricing candidates by {} tours (scene seeds {}..={})",
            args.tours,
            args.tour_seed,
            t.tours().last().map_or(args.tour_seed, |(s, _)| s)
        );
        Some(match guard {
            Some(g) => {
                say!(
                    "keeping the start's tracking: flat rollouts' XY {:.3} m, {} m allowed",
                    g.start_xy(),
                    args.keep_tracking.unwrap_or_default()
                );
                t.with_guard(g)
            }
            None => t,
        })
    } else {
        None
    };
    let write = |params: &TunedParams, cost: &plamo_controller::Cost, when: &str| {
        let falls = if args.tours > 0 {
            format!("tours with a fall {:.3}", cost.falls)
        } else {
            format!("falls/rollout {:.2}", cost.falls)
        };
        let tracking = match tours.as_ref().and_then(TourObjective::guard) {
            Some(g) => format!(
                " Flat rollouts' XY {:.3} m (start {:.3} m).",
                cost.tracking,
                g.start_xy()
            ),
            _ => String::new(),
        };
        let header = format!(
            "{what} parameters (version {version}). Generated by:\n  {command}\n{when} cost {:.4}: {falls}, XY {:.3} m, Z {:.3} m, residual {:.3} m*g.{tracking}",
            cost.total, cost.xy, cost.z, cost.residual,
        );
        let text = params.to_toml(form, &header)?;
        // Written aside and renamed, so a run killed mid-write leaves the last whole file.
        let part = out.with_extension("part");
        std::fs::write(&part, text).with_context(|| format!("writing {}", part.display()))?;
        std::fs::rename(&part, &out).with_context(|| format!("writing {}", out.display()))
    };
    // A search is minutes to hours: the best so far is on disk after every generation
    // that improves it, so a run stopped by a job's time limit keeps what it found.
    let mut checkpoint = Ok(());
    let on_generation = |g: &plamo_controller::Generation| {
        let line = format!(
            "cost {:.3} (falls {:.2}, xy {:.3} m, z {:.3} m, residual {:.3} mg) sigma {:.3}",
            g.best.total, g.best.falls, g.best.xy, g.best.z, g.best.residual, g.sigma
        );
        if log_lines {
            eprintln!("generation {}/{}: best {line}", g.index, args.budget);
        }
        if g.improved && checkpoint.is_ok() {
            let when = format!(
                "Checkpoint after generation {} of {}:",
                g.index, args.budget
            );
            checkpoint = write(&g.best_params, &g.best, &when);
        }
        bar.set_position(u64::from(g.index));
        bar.set_message(line);
    };
    let (best, cost) = match &tours {
        Some(t) => tune_with(&base, &settings, |p| t.cost(p), on_generation)?,
        None => tune(&base, &settings, on_generation)?,
    };
    bar.finish();
    checkpoint?;
    // The search's tours are few and its objective chaotic in the parameters, so its
    // best is partly the luckiest on those tours: the next as many tours, which it
    // never saw, say how much of the gain holds.
    let held_out = match &tours {
        Some(t) if best != base => {
            let h = TourObjective::new(
                form,
                args.tours,
                t.next_seed(),
                settings.backends.clone(),
                settings.physics.clone(),
                args.fall_cost,
            )?;
            let (a, b) = (h.cost(&base)?, h.cost(&best)?);
            let line = format!(
                "Held out, the next {} tours (scene seeds {}..={}): start cost {:.4} (tours with a fall {:.3}), this file {:.4} ({:.3}).",
                args.tours,
                t.next_seed(),
                h.next_seed() - 1,
                a.total,
                a.falls,
                b.total,
                b.falls
            );
            say!("{line}");
            format!("\n{line}")
        }
        _ => String::new(),
    };
    write(&best, &cost, format!("{held_out}\nFinal").trim_start())?;
    say!("{}", serde_json::to_string_pretty(&cost)?);
    say!("wrote {}", out.display());
    Ok(ExitCode::SUCCESS)
}
