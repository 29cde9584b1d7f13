//! The paper's experiments as reproducible sweeps (`plamo eval slalom | pyramid |
//! random | dynamic`, issue #8).
//!
//! Every experiment is a list of independent jobs (one closed-loop run each) that
//! depends only on the experiment's parameters, never on the thread count or on the
//! machine: jobs run in parallel with rayon, each writes one row of `runs.csv`, and
//! every summary (markdown, `summary.csv`, PNG plots) is computed from those rows
//! alone. A sweep can run as `n` shards (`--shard i/n`, job `j` belongs to shard
//! `j % n + 1`); [`merge`] puts the shards' rows back in job order and writes the
//! same files, byte for byte, as the unsharded run.

pub mod body_state;
pub mod compare;
pub mod dynamic;
pub mod episode;
pub mod fall_posture;
pub mod ground;
pub mod plot;
pub mod pyramid;
pub mod random;
pub mod slalom;
pub mod table;

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use plamo_controller::{CrawlParams, GaitParams};
use plamo_physics::{BackendKind, PhysicsSettings};
use plamo_planner::PlannerSettings;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

pub use crate::spec::ControllerParams;
pub use table::Table;

use crate::progress::Progress;

/// One part of a sweep split across machines: jobs `j` with `j % count == index - 1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// 1-based shard number.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl Shard {
    /// The whole sweep.
    pub const ALL: Shard = Shard { index: 1, count: 1 };

    /// Whether job `j` belongs to this shard.
    pub fn owns(&self, j: usize) -> bool {
        j % self.count == self.index - 1
    }
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("`{s}`: expected i/n with 1 <= i <= n (e.g. 2/4)");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// How a sweep runs; none of it changes a result except `physics` and `max_seconds`.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Physics engine.
    pub physics: BackendKind,
    /// Output folder (created).
    pub out: PathBuf,
    /// Which part of the sweep to run.
    pub shard: Shard,
    /// Worker threads; 0: one per core.
    pub threads: usize,
    /// Cap on every run's simulated time \[s\] (small test sweeps); `None`: each
    /// experiment's own limit.
    pub max_seconds: Option<f64>,
    /// No progress bar.
    pub quiet: bool,
    /// Planner settings every run starts from (each experiment sets its swept fields
    /// on top); `None`: the defaults.
    pub planner: Option<PlannerSettings>,
    /// Controller parameters of every run (`--gait-params`, `--crawl-params`).
    pub controller: ControllerParams,
    /// Physics settings of every run (`--physics-params`); `None`: the defaults.
    pub physics_settings: Option<PhysicsSettings>,
}

impl RunOptions {
    /// The planner settings every run starts from.
    pub fn planner(&self) -> PlannerSettings {
        self.planner.clone().unwrap_or_default()
    }

    /// The physics settings of every run.
    pub fn physics_settings(&self) -> PhysicsSettings {
        self.physics_settings.clone().unwrap_or_default()
    }
}

/// The planner settings of a sweep run with `--planner-params`, written next to
/// `eval.json` (every field, defaults included).
pub const PLANNER_FILE: &str = "planner.toml";
/// The gait parameters of a sweep run with `--gait-params`, written next to `eval.json`.
pub const GAIT_FILE: &str = "gait.toml";
/// The crawl parameters of a sweep run with `--crawl-params`, written next to
/// `eval.json`.
pub const CRAWL_FILE: &str = "crawl.toml";
/// The physics settings of a sweep run with `--physics-params`, written next to
/// `eval.json` (every field, defaults included).
pub const PHYSICS_FILE: &str = "physics.toml";

/// What every output folder says about the sweep that wrote it (`eval.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Meta {
    /// Experiment name (`slalom`, `pyramid`, `random`, `dynamic`).
    pub experiment: String,
    /// Physics engine.
    pub physics: String,
    /// Cap on simulated time per run \[s\], if one was given.
    pub max_seconds: Option<f64>,
    /// Number of jobs of the whole sweep.
    pub jobs: usize,
    /// The shard this folder holds; absent for a whole (or merged) sweep.
    pub shard: Option<Shard>,
    /// The experiment's own parameters.
    pub params: serde_json::Value,
    /// Planner settings from `--planner-params`, when given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub planner: Option<PlannerSettings>,
    /// Gait parameters from `--gait-params`, when given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gait: Option<GaitParams>,
    /// Crawl parameters from `--crawl-params`, when given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crawl: Option<CrawlParams>,
    /// Physics settings from `--physics-params`, when given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub physics_settings: Option<PhysicsSettings>,
}

impl Meta {
    /// The planner settings every run of the sweep started from.
    pub fn planner(&self) -> PlannerSettings {
        self.planner.clone().unwrap_or_default()
    }

    /// The controller parameters every run of the sweep used.
    pub fn controller(&self) -> ControllerParams {
        ControllerParams {
            gait: self.gait,
            crawl: self.crawl,
        }
    }

    /// The physics settings every run of the sweep used.
    pub fn physics_settings(&self) -> PhysicsSettings {
        self.physics_settings.clone().unwrap_or_default()
    }

    /// The parameter files this sweep wrote next to `eval.json`, as command-line
    /// flags, each path `dir` joined with the file's name (`dir` empty: the bare
    /// names, for a command run in the folder).
    pub fn param_flags(&self, dir: &Path) -> String {
        [
            ("--planner-params", PLANNER_FILE, self.planner.is_some()),
            ("--gait-params", GAIT_FILE, self.gait.is_some()),
            ("--crawl-params", CRAWL_FILE, self.crawl.is_some()),
            (
                "--physics-params",
                PHYSICS_FILE,
                self.physics_settings.is_some(),
            ),
        ]
        .into_iter()
        .filter(|f| f.2)
        .map(|(flag, file, _)| format!(" {flag} {}", dir.join(file).display()))
        .collect()
    }
}

/// One experiment: its jobs, how one job runs, and how rows become a summary.
pub trait Experiment: Sync {
    /// Experiment name, also the subcommand.
    const NAME: &'static str;
    /// One job's description.
    type Job: Sync;
    /// Column names of `runs.csv` (the first must be `job`).
    fn columns(&self) -> Vec<&'static str>;
    /// Every job of the sweep, in order.
    fn jobs(&self) -> anyhow::Result<Vec<Self::Job>>;
    /// Run job `j`; the fields of its row after the `job` column.
    fn run_job(&self, j: usize, job: &Self::Job, opts: &RunOptions) -> anyhow::Result<Vec<String>>;
    /// Write the summary files into `out` from every row; returns the markdown.
    fn summarize(&self, runs: &Table, meta: &Meta, out: &Path) -> anyhow::Result<String>;
    /// Parameters as JSON for `eval.json`.
    fn params(&self) -> serde_json::Value;
}

/// Run experiment `e` (the shard of it `opts` asks for) and write its folder.
/// Returns the markdown summary, or a note when only a shard was run.
pub fn run<E: Experiment>(e: &E, opts: &RunOptions) -> anyhow::Result<String> {
    if !opts.physics.is_available() {
        bail!(
            "`--physics {}` needs plamo built with the `mujoco` feature \
             (scripts/install-mujoco.sh, then `cargo run --release --features mujoco -- eval ...`)",
            opts.physics
        );
    }
    if let Some(m) = opts.max_seconds
        && !(m.is_finite() && m > 0.0)
    {
        bail!("--max-seconds {m}: must be finite and > 0");
    }
    let jobs = e.jobs()?;
    let mine: Vec<usize> = (0..jobs.len()).filter(|&j| opts.shard.owns(j)).collect();
    let bar = Progress::new(
        mine.len() as u64,
        E::NAME,
        &format!(
            "{} {{bar:30}} {{pos}}/{{len}} runs [{{elapsed}} < {{eta}}]",
            E::NAME
        ),
        opts.quiet,
    )?;
    let work = || -> Vec<anyhow::Result<Vec<String>>> {
        mine.par_iter()
            .map(|&j| {
                let r = e
                    .run_job(j, &jobs[j], opts)
                    .with_context(|| format!("{} job {j}", E::NAME));
                bar.inc(1);
                r.map(|mut fields| {
                    fields.insert(0, j.to_string());
                    fields
                })
            })
            .collect()
    };
    let rows = if opts.threads == 0 {
        work()
    } else {
        rayon::ThreadPoolBuilder::new()
            .num_threads(opts.threads)
            .build()
            .context("starting the worker threads")?
            .install(work)
    };
    bar.finish_and_clear();
    let table = Table {
        header: e.columns().iter().map(|s| s.to_string()).collect(),
        rows: rows.into_iter().collect::<anyhow::Result<_>>()?,
    };
    let meta = Meta {
        experiment: E::NAME.into(),
        physics: opts.physics.to_string(),
        max_seconds: opts.max_seconds,
        jobs: jobs.len(),
        shard: (opts.shard != Shard::ALL).then_some(opts.shard),
        params: e.params(),
        planner: opts.planner.clone(),
        gait: opts.controller.gait,
        crawl: opts.controller.crawl,
        physics_settings: opts.physics_settings.clone(),
    };
    write_folder(e, &meta, table, &opts.out)
}

/// Write `eval.json` and `runs.csv`, and the summary when the folder holds every job.
fn write_folder<E: Experiment>(
    e: &E,
    meta: &Meta,
    table: Table,
    out: &Path,
) -> anyhow::Result<String> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    std::fs::write(
        out.join("eval.json"),
        serde_json::to_string_pretty(meta)? + "\n",
    )?;
    // The summaries' commands pass these files, so they rerun the sweep as it was.
    if let Some(p) = &meta.planner {
        std::fs::write(out.join(PLANNER_FILE), toml::to_string(p)?)?;
    }
    if let Some(p) = &meta.gait {
        std::fs::write(out.join(GAIT_FILE), toml::to_string(p)?)?;
    }
    if let Some(p) = &meta.crawl {
        std::fs::write(out.join(CRAWL_FILE), toml::to_string(p)?)?;
    }
    if let Some(p) = &meta.physics_settings {
        std::fs::write(out.join(PHYSICS_FILE), toml::to_string(p)?)?;
    }
    // The summary reads the rows back from their text, so a merged sweep (which only
    // has the text) summarizes exactly the same numbers.
    let text = table.to_csv();
    std::fs::write(out.join("runs.csv"), &text)?;
    if let Some(s) = meta.shard {
        return Ok(format!(
            "shard {s} of `{}`: {} runs written to {}; combine all {} shards with `plamo eval merge`",
            meta.experiment,
            table.rows.len(),
            out.display(),
            s.count
        ));
    }
    let table = Table::parse(&text, "runs.csv")?;
    let md = e.summarize(&table, meta, out)?;
    std::fs::write(out.join(format!("{}.md", meta.experiment)), &md)?;
    Ok(md)
}

fn read_meta(dir: &Path) -> anyhow::Result<Meta> {
    let p = dir.join("eval.json");
    let text = std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
    serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))
}

/// `plamo eval merge`: combine the shard folders `dirs` of one sweep into `out` (or
/// summarize one whole-sweep folder again).
pub fn merge(dirs: &[PathBuf], out: &Path) -> anyhow::Result<String> {
    if dirs.is_empty() {
        bail!("no shard folders given: plamo eval merge DIR... --out DIR");
    }
    let metas = dirs
        .iter()
        .map(|d| read_meta(d))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let first = &metas[0];
    // One whole-sweep folder: summarize its rows again (after a summary change).
    let whole = Shard::ALL;
    let shard = match first.shard {
        Some(s) => s,
        None if dirs.len() == 1 => whole,
        None => bail!(
            "{} holds a whole sweep, not a shard (run with --shard i/n)",
            dirs[0].display()
        ),
    };
    let mut seen = vec![false; shard.count];
    for (d, m) in dirs.iter().zip(&metas) {
        let same = Meta {
            shard: m.shard,
            ..first.clone()
        };
        if *m != same {
            bail!(
                "{} is from a different sweep than {} (experiment, physics, parameters and \
                 --max-seconds must match)",
                d.display(),
                dirs[0].display()
            );
        }
        let s = m.shard.unwrap_or(whole);
        if s.count != shard.count {
            bail!(
                "{} is shard {s}, {} is shard {shard}: shard counts differ",
                d.display(),
                dirs[0].display()
            );
        }
        if std::mem::replace(&mut seen[s.index - 1], true) {
            bail!("shard {s} given twice ({})", d.display());
        }
    }
    if let Some(i) = seen.iter().position(|s| !s) {
        bail!("shard {}/{} is missing", i + 1, shard.count);
    }
    let mut rows = Vec::new();
    let mut header = None;
    for d in dirs {
        let p = d.join("runs.csv");
        let text =
            std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
        let t = Table::parse(&text, &p.display().to_string())?;
        if header.as_ref().is_some_and(|h| *h != t.header) {
            bail!("{}: columns differ from the other shards", p.display());
        }
        header = Some(t.header.clone());
        rows.extend(t.rows);
    }
    let header = header.unwrap_or_default();
    let mut keyed = rows
        .into_iter()
        .map(|r| {
            let j: usize = r
                .first()
                .and_then(|v| v.parse().ok())
                .ok_or_else(|| anyhow::anyhow!("a row without a job number"))?;
            Ok((j, r))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    keyed.sort_by_key(|(j, _)| *j);
    let ok = keyed.len() == first.jobs && keyed.iter().enumerate().all(|(i, (j, _))| i == *j);
    if !ok {
        bail!(
            "the shards hold {} rows, the sweep has {} jobs (0..{}): a shard is incomplete",
            keyed.len(),
            first.jobs,
            first.jobs
        );
    }
    let table = Table {
        header,
        rows: keyed.into_iter().map(|(_, r)| r).collect(),
    };
    let meta = Meta {
        shard: None,
        ..first.clone()
    };
    let params = meta.params.clone();
    let bad = |e: serde_json::Error| anyhow::anyhow!("eval.json parameters: {e}");
    match meta.experiment.as_str() {
        slalom::Slalom::NAME => write_folder(
            &serde_json::from_value::<slalom::Slalom>(params).map_err(bad)?,
            &meta,
            table,
            out,
        ),
        pyramid::Pyramid::NAME => write_folder(
            &serde_json::from_value::<pyramid::Pyramid>(params).map_err(bad)?,
            &meta,
            table,
            out,
        ),
        random::RandomScenes::NAME => write_folder(
            &serde_json::from_value::<random::RandomScenes>(params).map_err(bad)?,
            &meta,
            table,
            out,
        ),
        dynamic::Dynamic::NAME => write_folder(
            &serde_json::from_value::<dynamic::Dynamic>(params).map_err(bad)?,
            &meta,
            table,
            out,
        ),
        other => bail!("eval.json: unknown experiment `{other}`"),
    }
}

/// Wilson score interval of a proportion `k / n` at z (1.96: 95%); (0, 1) for n = 0.
pub fn wilson(k: usize, n: usize, z: f64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let n = n as f64;
    let p = k as f64 / n;
    let z2 = z * z;
    let centre = p + z2 / (2.0 * n);
    let half = z * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
    let d = 1.0 + z2 / n;
    (
        ((centre - half) / d).max(0.0),
        ((centre + half) / d).min(1.0),
    )
}

/// The command line that reproduces a sweep, for the markdown.
pub fn command_line(meta: &Meta, args: &str) -> String {
    let cap = meta
        .max_seconds
        .map_or(String::new(), |m| format!(" --max-seconds {m}"));
    format!(
        "plamo eval {} --physics {}{args}{cap}{}",
        meta.experiment,
        meta.physics,
        meta.param_flags(Path::new(""))
    )
}

/// Mean of `v`; NaN when empty.
pub fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// The jobs of a sweep over `points`: each point `runs` times, run r seeded
/// `seed + r`, as (point index, point, seed).
pub fn point_runs<P: Copy>(points: &[P], runs: usize, seed: u64) -> Vec<(usize, P, u64)> {
    points
        .iter()
        .enumerate()
        .flat_map(|(i, &p)| (0..runs as u64).map(move |r| (i, p, seed.wrapping_add(r))))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_parses_and_partitions() {
        let s: Shard = "2/3".parse().unwrap();
        assert_eq!(s, Shard { index: 2, count: 3 });
        assert!(s.owns(1) && s.owns(4) && !s.owns(0));
        for bad in ["0/2", "3/2", "1/0", "x", "1-2"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }

    #[test]
    fn wilson_matches_a_known_interval() {
        // 8 of 10 at 95%: (0.490, 0.943).
        let (lo, hi) = wilson(8, 10, 1.96);
        assert!(
            (lo - 0.4902).abs() < 1e-3 && (hi - 0.9433).abs() < 1e-3,
            "{lo} {hi}"
        );
        assert_eq!(wilson(0, 0, 1.96), (0.0, 1.0));
    }
}
