//! `plamo eval pyramid` (paper 5.2, "Terrain preference", Fig. 7): the built-in
//! `pyramid` scene, "walk from the west to the east", with the terrain preference c
//! (edge length + length * (e^(c * slope) - 1)) at 0 and larger values. Planner-only
//! measures (path length, planned time, highest point) next to the executed ones
//! (success, completion time, falls); the map shows every c's planned path and the
//! head tracks.

use std::path::Path;

use anyhow::bail;
use plamo_planner::PlannerSettings;
use serde::{Deserialize, Serialize};

use super::episode::{EpisodeSpec, parse_track, plan, run_episode};
use super::table::field;
use super::{Experiment, Meta, RunOptions, Table, command_line, mean};
use crate::viz::{MapOverlay, OverlayPath, render_map};

/// The instruction of every run.
pub const INSTRUCTION: &str = "Walk from the west to the east";

/// Terrain preferences compared by default (0: the shortest way, straight over).
pub const DEFAULT_C: [f64; 4] = [0.0, 0.5, 1.0, 4.0];

/// The pyramid sweep's parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pyramid {
    /// Runs per c.
    pub runs: usize,
    /// Seed of run 0 (run r uses seed + r).
    pub seed: u64,
    /// Terrain preferences c \[1\].
    pub c: Vec<f64>,
}

impl Pyramid {
    /// Check the parameters.
    pub fn new(runs: usize, seed: u64, c: Vec<f64>) -> anyhow::Result<Self> {
        if runs == 0 {
            bail!("--runs 0: need at least one run per c");
        }
        if c.is_empty() {
            bail!("--c: give at least one terrain preference");
        }
        if let Some(v) = c.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            bail!("--c: {v} is not a terrain preference (finite, >= 0)");
        }
        Ok(Self { runs, seed, c })
    }

    fn settings(base: PlannerSettings, c: f64) -> PlannerSettings {
        PlannerSettings {
            slope_preference_c: c,
            ..base
        }
    }
}

const COLUMNS: [&str; 16] = [
    "job",
    "c_index",
    "c",
    "seed",
    "success",
    "reached",
    "falls",
    "time_s",
    "xy_err",
    "z_err",
    "planned_length",
    "planned_time",
    "planned_top",
    "timed_out",
    "planning_error",
    "track",
];

const PALETTE: [[u8; 3]; 6] = [
    [220, 30, 30],
    [30, 90, 220],
    [20, 160, 60],
    [200, 120, 0],
    [150, 40, 170],
    [0, 150, 160],
];

impl Experiment for Pyramid {
    const NAME: &'static str = "pyramid";
    type Job = (usize, f64, u64);

    fn columns(&self) -> Vec<&'static str> {
        COLUMNS.to_vec()
    }

    fn jobs(&self) -> anyhow::Result<Vec<Self::Job>> {
        Ok(super::point_runs(&self.c, self.runs, self.seed))
    }

    fn run_job(
        &self,
        _j: usize,
        job: &Self::Job,
        opts: &RunOptions,
    ) -> anyhow::Result<Vec<String>> {
        let (i, c, seed) = *job;
        let scene = plamo_scenes::builtin("pyramid")?;
        let spec = EpisodeSpec {
            scene: &scene,
            instructions: INSTRUCTION.into(),
            backend: opts.physics,
            seed,
            planner: Self::settings(opts.planner(), c),
            controller: opts.controller,
            physics_settings: opts.physics_settings(),
            max_seconds: opts.max_seconds,
        };
        let top = plan(&spec).map_or(f64::NAN, |(_, p)| {
            p.route()
                .iter()
                .flat_map(|t| t.points.iter())
                .map(|p| p.ground)
                .fold(f64::NEG_INFINITY, f64::max)
        });
        let ep = run_episode(&spec)?;
        let b = |x: bool| u8::from(x).to_string();
        Ok(vec![
            i.to_string(),
            c.to_string(),
            seed.to_string(),
            b(ep.success()),
            b(ep.reached == ep.instructions),
            ep.falls.to_string(),
            ep.time_s.to_string(),
            ep.xy_err.to_string(),
            ep.z_err.to_string(),
            ep.planned_length.to_string(),
            ep.planned_time.to_string(),
            top.to_string(),
            b(ep.timed_out),
            field(ep.planning_error.as_deref().unwrap_or("")),
            ep.track_field(),
        ])
    }

    fn params(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or_default()
    }

    fn summarize(&self, runs: &Table, meta: &Meta, out: &Path) -> anyhow::Result<String> {
        let scene = plamo_scenes::builtin("pyramid")?;
        let args = format!(
            " --runs {} --seed {} --c {}",
            self.runs,
            self.seed,
            self.c
                .iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(",")
        );
        let mut md = format!(
            "Command: `{}`\n\n\
             Scene `pyramid` (2.5 m high, about 23 degrees), \"{INSTRUCTION}\", {} runs per c. \
             Planned: the planner's route from the start (planner only). Executed: success = \
             the east reached without a fall; time = mean over runs that reached it.\n\n\
             | c | planned length [m] | planned time [s] | planned top [m] | success | reached | time [s] | falls/run | XY / Z err [m] |\n\
             |---|---|---|---|---|---|---|---|---|\n",
            command_line(meta, &args),
            self.runs
        );
        let mut csv = Table {
            header: [
                "c",
                "runs",
                "planned_length_m",
                "planned_time_s",
                "planned_top_m",
                "success_rate",
                "reached_rate",
                "time_mean_reached_s",
                "falls_per_run",
                "xy_err_mean",
                "z_err_mean",
            ]
            .map(String::from)
            .to_vec(),
            rows: vec![],
        };
        let mut overlay = MapOverlay {
            title: format!(
                "pyramid ({}): planned paths (solid) and head tracks (thin) per terrain preference c",
                meta.physics
            ),
            ..Default::default()
        };
        for (i, &c) in self.c.iter().enumerate() {
            let rows: Vec<usize> = (0..runs.rows.len())
                .filter(|&r| runs.usize(r, "c_index").ok() == Some(i))
                .collect();
            let n = rows.len().max(1) as f64;
            let get = |name: &str| -> anyhow::Result<Vec<f64>> {
                rows.iter().map(|&r| runs.f64(r, name)).collect()
            };
            let mut succ = 0;
            let mut times = Vec::new();
            for &r in &rows {
                succ += usize::from(runs.flag(r, "success")?);
                if runs.flag(r, "reached")? {
                    times.push(runs.f64(r, "time_s")?);
                }
            }
            let (len, pt, top) = (
                mean(&get("planned_length")?),
                mean(&get("planned_time")?),
                mean(&get("planned_top")?),
            );
            let falls = get("falls")?.iter().sum::<f64>() / n;
            let (xy, z) = (mean(&get("xy_err")?), mean(&get("z_err")?));
            let t = mean(&times);
            md.push_str(&format!(
                "| {c} | {len:.1} | {pt:.1} | {top:.2} | {:.0}% | {:.0}% | {} | {falls:.1} | {xy:.2} / {z:.2} |\n",
                100.0 * succ as f64 / n,
                100.0 * times.len() as f64 / n,
                if t.is_finite() {
                    format!("{t:.1}")
                } else {
                    "-".into()
                },
            ));
            csv.rows.push(vec![
                c.to_string(),
                rows.len().to_string(),
                format!("{len:.3}"),
                format!("{pt:.3}"),
                format!("{top:.3}"),
                format!("{:.4}", succ as f64 / n),
                format!("{:.4}", times.len() as f64 / n),
                format!("{t:.3}"),
                format!("{falls:.3}"),
                format!("{xy:.4}"),
                format!("{z:.4}"),
            ]);
            let color = PALETTE[i % PALETTE.len()];
            // The plan does not depend on the seed (only the start heading does).
            let spec = EpisodeSpec {
                scene: &scene,
                instructions: INSTRUCTION.into(),
                backend: plamo_physics::BackendKind::Rapier,
                seed: self.seed,
                planner: Self::settings(meta.planner(), c),
                controller: meta.controller(),
                physics_settings: meta.physics_settings(),
                max_seconds: None,
            };
            if let Ok((_, p)) = plan(&spec) {
                overlay.paths.push(OverlayPath {
                    points: p
                        .route()
                        .iter()
                        .flat_map(|t| t.points.iter().map(|q| [q.x, q.y]))
                        .collect(),
                    colors: vec![color],
                    width: 4,
                    dashed: false,
                    label: Some(format!("c = {c}: {len:.1} m, {pt:.1} s planned")),
                });
            }
            for &r in &rows {
                overlay.paths.push(OverlayPath {
                    points: parse_track(runs.str(r, "track")?),
                    colors: vec![color],
                    width: 1,
                    dashed: true,
                    label: None,
                });
            }
        }
        std::fs::write(out.join("summary.csv"), csv.to_csv())?;
        render_map(&scene, &overlay, &out.join("pyramid.png"))?;
        md.push_str("\n![pyramid detour](pyramid.png)\n");
        Ok(md)
    }
}
