//! `plamo eval dynamic` (paper 4.1, re-planning around dynamic obstacles with a 1.5 s
//! look-ahead): seeded corridor scenes, 24 x 12 m and flat, where three balls or
//! boxes cross the straight way from `start` to `goal`, each timed to reach the
//! middle when the planned walk does. Every scene runs twice, with the planner's
//! re-planning on and off ([`PlannerSettings::dynamic_replanning`]); the collision
//! rate (runs in which some body touched a moving obstacle) is compared with 95%
//! Wilson intervals. Planner only: whether the start plan, tracked perfectly, would
//! meet an obstacle.

use std::path::Path;

use anyhow::bail;
use plamo_planner::{PlannerSettings, Prediction, predict_conflict};
use plamo_scenes::file_format::{DynamicSpec, LandmarkSpec, RegionSpec, SceneFile, TerrainSpec};
use plamo_scenes::{Motion, ObstacleShape, Scene};
use plotters::style::RGBColor;
use serde::{Deserialize, Serialize};

use super::episode::{
    EpisodeSpec, TIME_LIMIT_EXTRA, TIME_LIMIT_FACTOR, parse_track, plan, run_episode,
};
use super::plot::{Bar, bars};
use super::random::Z95;
use super::table::field;
use super::{Experiment, Meta, RunOptions, Table, command_line, mean, wilson};
use crate::seeds::unit;
use crate::spec::default_time_limit;
use crate::viz::{MapOverlay, OverlayPath, render_map};

/// The instruction of every run.
pub const INSTRUCTION: &str = "Walk from the start to the goal";

/// Corridor size \[m\].
pub const SIZE: [f64; 2] = [24.0, 12.0];

/// Walking top speed in these scenes \[m/s\]: within what the controller walks today
/// (1.0-1.5 m/s), so the comparison is about obstacles rather than falls.
pub const WALK_SPEED: f64 = 1.5;

/// The dynamic-obstacle sweep's parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Dynamic {
    /// Number of scenes (each runs with re-planning on and off).
    pub scenes: usize,
    /// Seed of the first scene (scene k uses seed + k).
    pub seed: u64,
}

impl Dynamic {
    /// Check the parameters.
    pub fn new(scenes: usize, seed: u64) -> anyhow::Result<Self> {
        if scenes == 0 {
            bail!("--scenes 0: need at least one scene");
        }
        Ok(Self { scenes, seed })
    }
}

fn settings(base: PlannerSettings, replan: bool) -> PlannerSettings {
    PlannerSettings {
        walk_speed: WALK_SPEED,
        dynamic_replanning: replan,
        ..base
    }
}

fn r2(v: f64) -> f64 {
    (v * 100.0).round() / 100.0
}

/// Corridor scene `seed`: three obstacles crossing the way, timed against the plan.
pub fn scene(seed: u64) -> anyhow::Result<Scene> {
    Ok(plamo_scenes::from_toml_str(
        &scene_file(seed)?.to_toml(),
        "crossing",
    )?)
}

/// [`scene`] as a scene file (what `plamo run --scene FILE` loads).
pub fn scene_file(seed: u64) -> anyhow::Result<SceneFile> {
    let mid = SIZE[1] / 2.0;
    let mut file = SceneFile {
        name: format!("crossing-{seed}"),
        description: format!("three obstacles cross the corridor, seed {seed}"),
        terrain: TerrainSpec {
            size: Some(SIZE),
            origin: [0.0, 0.0],
            resolution: 0.1,
            grid: None,
            tiles: vec![],
        },
        walls: vec![],
        tops: vec![],
        dynamic: vec![],
        landmarks: vec![
            LandmarkSpec {
                name: "start".into(),
                region: RegionSpec::Circle {
                    center: [2.5, mid],
                    radius: 1.0,
                },
            },
            LandmarkSpec {
                name: "goal".into(),
                region: RegionSpec::Circle {
                    center: [SIZE[0] - 2.5, mid],
                    radius: 1.0,
                },
            },
        ],
    };
    // When the obstacle-free plan passes each x.
    let empty = plamo_scenes::from_toml_str(&file.to_toml(), "crossing")?;
    let spec = EpisodeSpec {
        scene: &empty,
        instructions: INSTRUCTION.into(),
        backend: plamo_physics::BackendKind::Rapier,
        seed,
        // The scene is the seed's alone: timed against the default plan.
        planner: settings(PlannerSettings::default(), true),
        controller: Default::default(),
        physics_settings: Default::default(),
        max_seconds: None,
    };
    let (_, planner) = plan(&spec).map_err(anyhow::Error::msg)?;
    let pts: Vec<(f64, f64)> = planner
        .route()
        .iter()
        .flat_map(|t| t.points.iter().map(move |p| (p.x, t.start_time + p.t)))
        .collect();
    let pass_time = |x: f64| {
        pts.iter()
            .find(|p| p.0 >= x)
            .or(pts.last())
            .map_or(1.0, |p| p.1)
    };
    let mut st = seed ^ 0x6479_6e61; // "dyna"
    let half_run = mid - 1.0; // from y = 1 to the middle
    for (k, x0) in [7.0, 12.0, 17.0].into_iter().enumerate() {
        let x = r2(x0 + 2.0 * unit(&mut st) - 1.0);
        let (shape, z) = if unit(&mut st) < 0.5 {
            let r = r2(0.3 + 0.2 * unit(&mut st));
            (ObstacleShape::Sphere { radius: r }, r)
        } else {
            (
                ObstacleShape::Box {
                    half_extents: [0.4, 0.3, 0.5],
                },
                0.5,
            )
        };
        // Reach the middle when the plan passes x, give or take 25%.
        let t = pass_time(x).max(1.0);
        let speed = r2((half_run / t * (0.75 + 0.5 * unit(&mut st))).max(0.2));
        let (a, b) = if unit(&mut st) < 0.5 {
            (1.0, SIZE[1] - 1.0)
        } else {
            (SIZE[1] - 1.0, 1.0)
        };
        file.dynamic.push(DynamicSpec {
            name: format!("crosser{k}"),
            shape,
            motion: Motion::Linear {
                from: [x, a, z],
                to: [x, b, z],
                speed,
            },
        });
    }
    Ok(file)
}

/// The planner settings of the re-planning runs, written next to `eval.json` for the
/// replay command (every field: the sweep's walking speed included).
pub const REPLAY_PLANNER_FILE: &str = "planner-replanning.toml";

/// How to watch a run with re-planning again: the scene of each re-planned run that
/// collided and of the first scene as files (`crossing-<seed>.toml`), the re-planning
/// runs' planner settings in `out`, and the `plamo run` command that replays the first
/// re-planned run that collided (else the first scene's) bit for bit.
fn replay_note(runs: &Table, meta: &Meta, out: &Path) -> anyhow::Result<String> {
    let replanned: Vec<usize> = (0..runs.rows.len())
        .filter(|&r| runs.flag(r, "replanning").ok() == Some(true))
        .collect();
    let collided: Vec<usize> = replanned
        .iter()
        .copied()
        .filter(|&r| runs.flag(r, "collided").ok() == Some(true))
        .collect();
    let Some(&first) = collided.first().or(replanned.first()) else {
        return Ok(String::new());
    };
    let scenes = if collided.is_empty() {
        &replanned[..1]
    } else {
        &collided[..]
    };
    for &r in scenes {
        let seed: u64 = runs.str(r, "scene_seed")?.parse()?;
        std::fs::write(
            out.join(format!("crossing-{seed}.toml")),
            scene_file(seed)?.to_toml(),
        )?;
    }
    let planner = settings(meta.planner(), true);
    std::fs::write(out.join(REPLAY_PLANNER_FILE), toml::to_string(&planner)?)?;
    let seed = runs.str(first, "scene_seed")?;
    let limit = match meta.max_seconds {
        Some(m) => m,
        None => default_time_limit(runs.f64(first, "planned_time")?),
    };
    // The gait and crawl files as the sweep wrote them; the planner's is the one above.
    let others = Meta {
        planner: None,
        ..meta.clone()
    }
    .param_flags(Path::new(""));
    let which = if collided.is_empty() {
        "No re-planned run collided. The first scene's".to_string()
    } else {
        format!(
            "{} re-planned run(s) collided; their scenes are `crossing-<seed>.toml` in this \
             folder. The first one's",
            collided.len()
        )
    };
    Ok(format!(
        "\n{which} run replays exactly, run in this folder (its trajectory digest is \
         runs.csv's `digest`; time limit {TIME_LIMIT_FACTOR} x the planned time + \
         {TIME_LIMIT_EXTRA} s unless `--max-seconds` was given):\n\n\
         ```\nplamo run --scene crossing-{seed}.toml --instructions \"{INSTRUCTION}\" --physics \
         {physics} --seed {seed} --max-seconds {limit} --planner-params {REPLAY_PLANNER_FILE}{others} \
         --out crossing-{seed}\n```\n",
        physics = meta.physics,
    ))
}

const COLUMNS: [&str; 18] = [
    "job",
    "scene_seed",
    "replanning",
    "collided",
    "dynamic_collisions",
    "success",
    "reached",
    "falls",
    "replans",
    "time_s",
    "xy_err",
    "planned_conflict",
    "planned_length",
    "planned_time",
    "timed_out",
    "error",
    "digest",
    "track",
];

impl Experiment for Dynamic {
    const NAME: &'static str = "dynamic";
    type Job = (u64, bool);

    fn columns(&self) -> Vec<&'static str> {
        COLUMNS.to_vec()
    }

    fn jobs(&self) -> anyhow::Result<Vec<Self::Job>> {
        Ok((0..self.scenes as u64)
            .flat_map(|k| {
                let s = self.seed.wrapping_add(k);
                [(s, true), (s, false)]
            })
            .collect())
    }

    fn run_job(
        &self,
        _j: usize,
        job: &Self::Job,
        opts: &RunOptions,
    ) -> anyhow::Result<Vec<String>> {
        let (seed, replan) = *job;
        let scene = scene(seed)?;
        let spec = EpisodeSpec {
            scene: &scene,
            instructions: INSTRUCTION.into(),
            backend: opts.physics,
            seed,
            planner: settings(opts.planner(), replan),
            controller: opts.controller,
            physics_settings: opts.physics_settings(),
            max_seconds: opts.max_seconds,
        };
        // Planner only: would the start plan meet an obstacle anywhere along it?
        let conflict = plan(&spec).ok().is_some_and(|(_, p)| {
            let whole = PlannerSettings {
                collision_horizon: p.route().last().map_or(1.0, |t| t.end_time() + 1.0),
                ..spec.planner.clone()
            };
            p.route()
                .iter()
                .any(|t| predict_conflict(t, &scene, &whole, 0.0, Prediction::Rules).is_some())
        });
        let ep = run_episode(&spec)?;
        let b = |x: bool| u8::from(x).to_string();
        Ok(vec![
            seed.to_string(),
            b(replan),
            b(ep.dynamic_collisions > 0),
            ep.dynamic_collisions.to_string(),
            b(ep.success()),
            b(ep.reached == ep.instructions),
            ep.falls.to_string(),
            ep.replans.to_string(),
            ep.time_s.to_string(),
            ep.xy_err.to_string(),
            b(conflict),
            ep.planned_length.to_string(),
            ep.planned_time.to_string(),
            b(ep.timed_out),
            field(
                ep.planning_error
                    .as_deref()
                    .or(ep.run_error.as_deref())
                    .unwrap_or(""),
            ),
            format!("{:016x}", ep.digest),
            ep.track_field(),
        ])
    }

    fn params(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or_default()
    }

    fn summarize(&self, runs: &Table, meta: &Meta, out: &Path) -> anyhow::Result<String> {
        let args = format!(" --scenes {} --seed {}", self.scenes, self.seed);
        let mut md = format!(
            "Command: `{}`\n\n\
             {} corridor scenes (seeds {}..{}), \"{INSTRUCTION}\" at up to {WALK_SPEED} m/s, three \
             balls or boxes crossing the way, each run with the planner's re-planning on and \
             off. Collision: some body came within {} m of a moving obstacle's surface. \
             Planner only: the start plan, tracked perfectly, would meet an obstacle.\n\n\
             | re-planning | collision rate (95% Wilson) | collisions/run | success | reached | falls/run | re-plans/run | time [s] | start plan meets an obstacle |\n\
             |---|---|---|---|---|---|---|---|---|\n",
            command_line(meta, &args),
            self.scenes,
            self.seed,
            self.seed + self.scenes as u64 - 1,
            super::episode::BODY_RADIUS,
        );
        let mut csv = Table {
            header: [
                "replanning",
                "runs",
                "collision_rate",
                "wilson95_low",
                "wilson95_high",
                "collisions_per_run",
                "success_rate",
                "reached_rate",
                "falls_per_run",
                "replans_per_run",
                "time_mean_reached_s",
                "planned_conflict_rate",
            ]
            .map(String::from)
            .to_vec(),
            rows: vec![],
        };
        let mut chart = Vec::new();
        for on in [true, false] {
            let rows: Vec<usize> = (0..runs.rows.len())
                .filter(|&r| runs.flag(r, "replanning").ok() == Some(on))
                .collect();
            let n = rows.len();
            let nf = n.max(1) as f64;
            let count = |name: &str| -> anyhow::Result<usize> {
                rows.iter()
                    .map(|&r| runs.flag(r, name).map(usize::from))
                    .sum()
            };
            let total = |name: &str| -> anyhow::Result<f64> {
                rows.iter().map(|&r| runs.f64(r, name)).sum()
            };
            let collided = count("collided")?;
            let (lo, hi) = wilson(collided, n, Z95);
            let mut times = Vec::new();
            for &r in &rows {
                if runs.flag(r, "reached")? {
                    times.push(runs.f64(r, "time_s")?);
                }
            }
            let t = mean(&times);
            let name = if on { "on" } else { "off" };
            let rate = collided as f64 / nf;
            md.push_str(&format!(
                "| {name} | {:.0}% ({:.0}-{:.0}%) | {:.2} | {:.0}% | {:.0}% | {:.2} | {:.1} | {} | {:.0}% |\n",
                100.0 * rate,
                100.0 * lo,
                100.0 * hi,
                total("dynamic_collisions")? / nf,
                100.0 * count("success")? as f64 / nf,
                100.0 * count("reached")? as f64 / nf,
                total("falls")? / nf,
                total("replans")? / nf,
                if t.is_finite() {
                    format!("{t:.1}")
                } else {
                    "-".into()
                },
                100.0 * count("planned_conflict")? as f64 / nf,
            ));
            csv.rows.push(vec![
                name.into(),
                n.to_string(),
                format!("{rate:.4}"),
                format!("{lo:.4}"),
                format!("{hi:.4}"),
                format!("{:.4}", total("dynamic_collisions")? / nf),
                format!("{:.4}", count("success")? as f64 / nf),
                format!("{:.4}", count("reached")? as f64 / nf),
                format!("{:.4}", total("falls")? / nf),
                format!("{:.4}", total("replans")? / nf),
                format!("{t:.3}"),
                format!("{:.4}", count("planned_conflict")? as f64 / nf),
            ]);
            chart.push(Bar {
                label: format!("re-planning {name}"),
                value: rate,
                interval: Some((lo, hi)),
                color: if on {
                    RGBColor(30, 90, 220)
                } else {
                    RGBColor(210, 50, 40)
                },
            });
        }
        std::fs::write(out.join("summary.csv"), csv.to_csv())?;
        bars(
            &out.join("dynamic.png"),
            &format!(
                "Moving obstacles ({}, {} scenes): collision rate, 95% Wilson intervals",
                meta.physics, self.scenes
            ),
            "share of runs with a collision",
            &chart,
            1.0,
        )?;
        // The first scene's two runs on its map.
        let first = scene(self.seed)?;
        let mut overlay = MapOverlay {
            title: format!(
                "{} ({}): head tracks with re-planning on (blue) and off (red)",
                first.name, meta.physics
            ),
            ..Default::default()
        };
        for r in 0..runs.rows.len() {
            if runs.str(r, "scene_seed")? != self.seed.to_string() {
                continue;
            }
            let on = runs.flag(r, "replanning")?;
            overlay.paths.push(OverlayPath {
                points: parse_track(runs.str(r, "track")?),
                colors: vec![if on { [30, 90, 220] } else { [210, 50, 40] }],
                width: 3,
                dashed: !on,
                label: Some(format!("re-planning {}", if on { "on" } else { "off" })),
            });
        }
        render_map(&first, &overlay, &out.join("dynamic_map.png"))?;
        md.push_str("\n![collision rate](dynamic.png)\n![first scene](dynamic_map.png)\n");
        md.push_str(&replay_note(runs, meta, out)?);
        Ok(md)
    }
}
