//! `plamo eval slalom` (paper 5.3, "Speed control", Figs. 8-9): the built-in
//! `slalom` scene, "run from the start to the finish", with constant speeds against
//! the planner's minimum-time speed profile (QP) under several acceleration limits.
//! Every point is the mean of `runs` runs (start heading perturbed by the seed).
//! Success: the finish reached without a fall. Outputs the two Pareto plots: failure
//! rate vs mean completion time, 3D displacement error vs mean completion time.

use std::path::Path;

use anyhow::bail;
use plamo_interfaces::CONTROL_DT;
use plamo_planner::PlannerSettings;
use plotters::style::RGBColor;
use serde::{Deserialize, Serialize};

use super::episode::{EpisodeSpec, parse_track, plan, run_episode};
use super::plot::{Series, scatter};
use super::table::field;
use super::{Experiment, Meta, RunOptions, Table, command_line, mean};
use crate::viz::{ColorBar, MapOverlay, OverlayPath, color_at, render_map};

/// Acceleration limit that never binds \[m/s^2\]: a "constant speed" plan keeps its
/// speed through every turn and starts at full speed.
pub const UNLIMITED_ACCELERATION: f64 = 1.0e3;

/// One configuration of the speed QP.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QpConfig {
    /// Top speed (the run form's) \[m/s\].
    pub v_max: f64,
    /// Lateral acceleration limit a_lat \[m/s^2\].
    pub a_lat: f64,
    /// Longitudinal acceleration limit a_max \[m/s^2\].
    pub a_max: f64,
    /// Deceleration limit a_min \[m/s^2\], < 0 (paper: -0.1).
    pub a_min: f64,
}

impl std::str::FromStr for QpConfig {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let form = "V_MAX:A_LAT:A_MAX[:A_MIN], e.g. 3.5:1:0.5:-0.1 (A_MIN defaults to -0.1)";
        let v: Vec<f64> = s
            .split(':')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("`{s}`: expected {form}"))?;
        let (v_max, a_lat, a_max, a_min) = match v[..] {
            [a, b, c] => (a, b, c, PlannerSettings::default().a_min),
            [a, b, c, d] => (a, b, c, d),
            _ => return Err(format!("`{s}`: expected {form}")),
        };
        if ![v_max, a_lat, a_max]
            .iter()
            .all(|x| x.is_finite() && *x > 0.0)
        {
            return Err(format!(
                "`{s}`: V_MAX, A_LAT and A_MAX must be finite and > 0"
            ));
        }
        if !(a_min.is_finite() && a_min < 0.0) {
            return Err(format!(
                "`{s}`: A_MIN is a deceleration limit, finite and < 0"
            ));
        }
        Ok(QpConfig {
            v_max,
            a_lat,
            a_max,
            a_min,
        })
    }
}

/// The slalom sweep's parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Slalom {
    /// Runs per point.
    pub runs: usize,
    /// Seed of run 0 (run r uses seed + r).
    pub seed: u64,
    /// Constant speeds \[m/s\].
    pub speeds: Vec<f64>,
    /// Speed-QP configurations.
    pub qp: Vec<QpConfig>,
}

/// The paper's constant speeds span 1-3.5 m/s.
pub const DEFAULT_SPEEDS: [f64; 6] = [1.0, 1.5, 2.0, 2.5, 3.0, 3.5];

/// QP configurations (v_max:a_lat:a_max:a_min): the paper's a_max 0.5 / a_min -0.1
/// with the default a_lat 1, then looser limits (planned slalom times 46, 25, 22,
/// 15 s), and slower tops the controller follows today.
pub const DEFAULT_QP: [QpConfig; 6] = [
    QpConfig {
        v_max: 3.5,
        a_lat: 1.0,
        a_max: 0.5,
        a_min: -0.1,
    },
    QpConfig {
        v_max: 3.5,
        a_lat: 2.0,
        a_max: 1.0,
        a_min: -1.0,
    },
    QpConfig {
        v_max: 3.5,
        a_lat: 4.0,
        a_max: 1.0,
        a_min: -1.0,
    },
    QpConfig {
        v_max: 3.5,
        a_lat: 8.0,
        a_max: 2.0,
        a_min: -2.0,
    },
    QpConfig {
        v_max: 2.0,
        a_lat: 2.0,
        a_max: 1.0,
        a_min: -1.0,
    },
    QpConfig {
        v_max: 1.5,
        a_lat: 4.0,
        a_max: 1.0,
        a_min: -1.0,
    },
];

/// The instruction of every run.
pub const INSTRUCTION: &str = "Run from the start to the finish";

/// One point of the sweep.
#[derive(Debug, Clone, Copy)]
pub enum Point {
    /// Constant speed \[m/s\].
    Constant(f64),
    /// Speed QP.
    Qp(QpConfig),
}

impl Point {
    fn label(&self) -> String {
        match self {
            Point::Constant(v) => format!("const {v} m/s"),
            Point::Qp(q) => format!("QP {}:{}:{}:{}", q.v_max, q.a_lat, q.a_max, q.a_min),
        }
    }

    /// The planner settings of this point, on top of `base`.
    pub fn settings(&self, base: PlannerSettings) -> PlannerSettings {
        match *self {
            Point::Constant(v) => PlannerSettings {
                run_speed: v,
                a_lat: UNLIMITED_ACCELERATION,
                a_max: UNLIMITED_ACCELERATION,
                a_min: -UNLIMITED_ACCELERATION,
                ..base
            },
            Point::Qp(q) => PlannerSettings {
                run_speed: q.v_max,
                a_lat: q.a_lat,
                a_max: q.a_max,
                a_min: q.a_min,
                ..base
            },
        }
    }
}

impl Slalom {
    /// Check the parameters.
    pub fn new(
        runs: usize,
        seed: u64,
        speeds: Vec<f64>,
        qp: Vec<QpConfig>,
    ) -> anyhow::Result<Self> {
        if runs == 0 {
            bail!("--runs 0: need at least one run per point");
        }
        if let Some(v) = speeds.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
            bail!("--speeds: {v} is not a speed (finite, > 0 m/s)");
        }
        if speeds.is_empty() && qp.is_empty() {
            bail!("--speeds and --qp are both empty: nothing to compare");
        }
        Ok(Self {
            runs,
            seed,
            speeds,
            qp,
        })
    }

    /// The map: the first QP point's plan coloured by planned speed, and the head
    /// track of the first run of the slowest and fastest constant speeds and of the
    /// first QP point.
    fn paths_map(
        &self,
        runs: &Table,
        meta: &Meta,
        points: &[Point],
        out: &Path,
    ) -> anyhow::Result<()> {
        const STOPS: [[u8; 3]; 3] = [[40, 60, 220], [240, 200, 40], [220, 30, 30]];
        const PALETTE: [[u8; 3]; 7] = [
            [200, 30, 30],
            [30, 60, 200],
            [20, 150, 60],
            [150, 40, 170],
            [0, 150, 160],
            [200, 120, 0],
            [90, 90, 90],
        ];
        let scene = plamo_scenes::builtin("slalom")?;
        let mut overlay = MapOverlay {
            title: format!(
                "slalom ({}): planned speed and head tracks (first run of each)",
                meta.physics
            ),
            ..Default::default()
        };
        if let Some(q) = points.iter().find(|p| matches!(p, Point::Qp(_))) {
            let spec = EpisodeSpec {
                scene: &scene,
                instructions: INSTRUCTION.into(),
                backend: plamo_physics::BackendKind::Rapier,
                seed: self.seed,
                planner: q.settings(meta.planner()),
                controller: meta.controller(),
                physics_settings: meta.physics_settings(),
                max_seconds: None,
            };
            if let Ok((_, p)) = plan(&spec) {
                let pts: Vec<_> = p.route().iter().flat_map(|t| t.points.iter()).collect();
                let vmax = pts.iter().map(|p| p.v).fold(0.1, f64::max);
                overlay.paths.push(OverlayPath {
                    points: pts.iter().map(|p| [p.x, p.y]).collect(),
                    colors: pts.iter().map(|p| color_at(&STOPS, p.v / vmax)).collect(),
                    width: 6,
                    dashed: false,
                    label: Some(format!("plan, {}", q.label())),
                });
                overlay.colorbar = Some(ColorBar {
                    label: "planned speed [m/s]".into(),
                    min: 0.0,
                    max: vmax,
                    colors: STOPS.to_vec(),
                });
            }
        }
        // Few enough for the map's legend: the slowest and fastest constant speeds and
        // the first QP point.
        let constants = || {
            points.iter().enumerate().filter_map(|(i, p)| match p {
                Point::Constant(v) => Some((i, *v)),
                Point::Qp(_) => None,
            })
        };
        let slowest = constants().min_by(|a, b| a.1.total_cmp(&b.1)).map(|c| c.0);
        let fastest = constants().max_by(|a, b| a.1.total_cmp(&b.1)).map(|c| c.0);
        let first_qp = (0..points.len()).find(|&i| matches!(points[i], Point::Qp(_)));
        let mut shown: Vec<usize> = [slowest, fastest, first_qp].into_iter().flatten().collect();
        shown.dedup();
        for (k, &i) in shown.iter().enumerate() {
            let Some(r) = (0..runs.rows.len()).find(|&r| runs.usize(r, "point").ok() == Some(i))
            else {
                continue;
            };
            overlay.paths.push(OverlayPath {
                points: parse_track(runs.str(r, "track")?),
                colors: vec![PALETTE[k % PALETTE.len()]],
                width: 2,
                dashed: matches!(points[i], Point::Constant(_)),
                label: Some(points[i].label()),
            });
        }
        render_map(&scene, &overlay, &out.join("slalom_paths.png"))
    }

    fn points(&self) -> Vec<Point> {
        self.speeds
            .iter()
            .map(|&v| Point::Constant(v))
            .chain(self.qp.iter().map(|&q| Point::Qp(q)))
            .collect()
    }
}

const COLUMNS: [&str; 21] = [
    "job",
    "point",
    "label",
    "kind",
    "v",
    "a_lat",
    "a_max",
    "seed",
    "success",
    "reached",
    "falls",
    "time_s",
    "xy_err",
    "z_err",
    "disp_err",
    "wall_contact_steps",
    "timed_out",
    "planned_time",
    "planned_length",
    "planning_error",
    "track",
];

impl Experiment for Slalom {
    const NAME: &'static str = "slalom";
    type Job = (usize, Point, u64);

    fn columns(&self) -> Vec<&'static str> {
        COLUMNS.to_vec()
    }

    fn jobs(&self) -> anyhow::Result<Vec<Self::Job>> {
        Ok(super::point_runs(&self.points(), self.runs, self.seed))
    }

    fn run_job(
        &self,
        _j: usize,
        job: &Self::Job,
        opts: &RunOptions,
    ) -> anyhow::Result<Vec<String>> {
        let (i, point, seed) = *job;
        let scene = plamo_scenes::builtin("slalom")?;
        let ep = run_episode(&EpisodeSpec {
            scene: &scene,
            instructions: INSTRUCTION.into(),
            backend: opts.physics,
            seed,
            planner: point.settings(opts.planner()),
            controller: opts.controller,
            physics_settings: opts.physics_settings(),
            max_seconds: opts.max_seconds,
        })?;
        let (kind, v, a_lat, a_max) = match point {
            Point::Constant(v) => ("constant", v, f64::INFINITY, f64::INFINITY),
            Point::Qp(q) => ("qp", q.v_max, q.a_lat, q.a_max),
        };
        let b = |x: bool| u8::from(x).to_string();
        Ok(vec![
            i.to_string(),
            point.label(),
            kind.into(),
            v.to_string(),
            a_lat.to_string(),
            a_max.to_string(),
            seed.to_string(),
            b(ep.success()),
            b(ep.reached == ep.instructions),
            ep.falls.to_string(),
            ep.time_s.to_string(),
            ep.xy_err.to_string(),
            ep.z_err.to_string(),
            ep.displacement().to_string(),
            ep.static_contact_steps.to_string(),
            b(ep.timed_out),
            ep.planned_time.to_string(),
            ep.planned_length.to_string(),
            field(ep.planning_error.as_deref().unwrap_or("")),
            ep.track_field(),
        ])
    }

    fn params(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or_default()
    }

    fn summarize(&self, runs: &Table, meta: &Meta, out: &Path) -> anyhow::Result<String> {
        let points = self.points();
        let mut stats = Vec::new();
        for (i, p) in points.iter().enumerate() {
            let rows: Vec<usize> = (0..runs.rows.len())
                .filter(|&r| runs.usize(r, "point").ok() == Some(i))
                .collect();
            let n = rows.len();
            let mut s = PointStats {
                label: p.label(),
                constant: matches!(p, Point::Constant(_)),
                runs: n,
                ..Default::default()
            };
            let mut times = Vec::new();
            let (mut disp, mut xy, mut z, mut pt, mut pl) =
                (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for &r in &rows {
                s.successes += usize::from(runs.flag(r, "success")?);
                if runs.flag(r, "reached")? {
                    s.reached += 1;
                    times.push(runs.f64(r, "time_s")?);
                }
                s.falls += runs.usize(r, "falls")?;
                let contact = runs.usize(r, "wall_contact_steps")?;
                s.wall_runs += usize::from(contact > 0);
                s.wall_steps += contact;
                disp.push(runs.f64(r, "disp_err")?);
                xy.push(runs.f64(r, "xy_err")?);
                z.push(runs.f64(r, "z_err")?);
                pt.push(runs.f64(r, "planned_time")?);
                pl.push(runs.f64(r, "planned_length")?);
            }
            s.time = mean(&times);
            s.disp = mean(&disp);
            s.xy = mean(&xy);
            s.z = mean(&z);
            s.planned_time = mean(&pt);
            s.planned_length = mean(&pl);
            stats.push(s);
        }
        let fail = |s: &PointStats| 1.0 - s.successes as f64 / s.runs.max(1) as f64;
        let pareto_fail = pareto(&stats, |s| fail(s));
        let pareto_disp = pareto(&stats, |s| s.disp);

        let mut csv = Table {
            header: [
                "label",
                "kind",
                "runs",
                "success_rate",
                "failure_rate",
                "reached_rate",
                "time_mean_reached_s",
                "disp_err_mean",
                "xy_err_mean",
                "z_err_mean",
                "falls_per_run",
                "wall_contact_run_rate",
                "wall_contact_s_per_run",
                "planned_time_s",
                "planned_length_m",
                "pareto_failure_time",
                "pareto_error_time",
            ]
            .map(String::from)
            .to_vec(),
            rows: vec![],
        };
        let args = format!(
            " --runs {} --seed {} --speeds {} --qp {}",
            self.runs,
            self.seed,
            self.speeds
                .iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(","),
            self.qp
                .iter()
                .map(|q| format!("{}:{}:{}:{}", q.v_max, q.a_lat, q.a_max, q.a_min))
                .collect::<Vec<_>>()
                .join(",")
        );
        let mut md = format!(
            "Command: `{}`\n\n\
             Scene `slalom`, \"{INSTRUCTION}\", {} runs per point. Success: the finish reached \
             without a fall. Time: mean over runs that reached the finish. 3D error: hypot of \
             the mean head XY and Z errors against the plan. Wall contact: the share of runs \
             in which some body touched a wall, and the mean time of contact per run (a hand \
             brushing a wall's end in a turn counts). Planned: the planner's own route \
             (planner only).\n\n\
             | point | success | reached | time [s] | 3D err [m] | XY / Z err [m] | falls/run | wall contact: runs, s/run | planned time [s] | planned length [m] | Pareto (fail, err) |\n\
             |---|---|---|---|---|---|---|---|---|---|---|\n",
            command_line(meta, &args),
            self.runs
        );
        for (k, s) in stats.iter().enumerate() {
            let n = s.runs.max(1) as f64;
            let yn = |b: bool| if b { "yes" } else { "no" };
            md.push_str(&format!(
                "| {} | {:.0}% | {:.0}% | {} | {:.2} | {:.2} / {:.2} | {:.1} | {:.0}%, {:.1} | {:.1} | {:.1} | {}, {} |\n",
                s.label,
                100.0 * s.successes as f64 / n,
                100.0 * s.reached as f64 / n,
                if s.time.is_finite() {
                    format!("{:.1}", s.time)
                } else {
                    "-".into()
                },
                s.disp,
                s.xy,
                s.z,
                s.falls as f64 / n,
                100.0 * s.wall_runs as f64 / n,
                s.wall_steps as f64 * CONTROL_DT / n,
                s.planned_time,
                s.planned_length,
                yn(pareto_fail[k]),
                yn(pareto_disp[k]),
            ));
            csv.rows.push(vec![
                field(&s.label),
                if s.constant { "constant" } else { "qp" }.into(),
                s.runs.to_string(),
                format!("{:.4}", s.successes as f64 / n),
                format!("{:.4}", fail(s)),
                format!("{:.4}", s.reached as f64 / n),
                format!("{:.3}", s.time),
                format!("{:.4}", s.disp),
                format!("{:.4}", s.xy),
                format!("{:.4}", s.z),
                format!("{:.3}", s.falls as f64 / n),
                format!("{:.4}", s.wall_runs as f64 / n),
                format!("{:.3}", s.wall_steps as f64 * CONTROL_DT / n),
                format!("{:.3}", s.planned_time),
                format!("{:.3}", s.planned_length),
                u8::from(pareto_fail[k]).to_string(),
                u8::from(pareto_disp[k]).to_string(),
            ]);
        }
        std::fs::write(out.join("summary.csv"), csv.to_csv())?;
        self.paths_map(runs, meta, &points, out)?;
        let short = |s: &PointStats| {
            s.label
                .replace("const ", "")
                .replace(" m/s", "")
                .replace("QP ", "")
        };
        let series = |y: &dyn Fn(&PointStats) -> f64| {
            let pick = |constant: bool| {
                stats
                    .iter()
                    .filter(|s| s.constant == constant)
                    .map(|s| (s.time, y(s), short(s)))
                    .collect::<Vec<_>>()
            };
            vec![
                Series {
                    name: "constant speed [m/s]".into(),
                    color: RGBColor(200, 40, 40),
                    triangles: false,
                    line: true,
                    points: pick(true),
                },
                Series {
                    name: "speed QP (v_max:a_lat:a_max:a_min)".into(),
                    color: RGBColor(30, 80, 200),
                    triangles: true,
                    line: false,
                    points: pick(false),
                },
            ]
        };
        scatter(
            &out.join("slalom_failure.png"),
            &format!("Slalom ({}): failure rate vs completion time", meta.physics),
            "mean completion time of runs that reached the finish [s]",
            "failure rate",
            &series(&fail),
        )?;
        scatter(
            &out.join("slalom_error.png"),
            &format!(
                "Slalom ({}): 3D displacement error vs completion time",
                meta.physics
            ),
            "mean completion time of runs that reached the finish [s]",
            "mean 3D displacement error [m]",
            &series(&|s: &PointStats| s.disp),
        )?;
        let missing: Vec<&str> = stats
            .iter()
            .filter(|s| !s.time.is_finite())
            .map(|s| s.label.as_str())
            .collect();
        if !missing.is_empty() {
            md.push_str(&format!(
                "\nNot in the plots (no run reached the finish, so no completion time): {}.\n",
                missing.join(", ")
            ));
        }
        md.push_str("\n![failure vs time](slalom_failure.png)\n![error vs time](slalom_error.png)\n![paths](slalom_paths.png)\n");
        Ok(md)
    }
}

#[derive(Debug, Default)]
struct PointStats {
    label: String,
    constant: bool,
    runs: usize,
    successes: usize,
    reached: usize,
    falls: usize,
    wall_runs: usize,
    /// Control steps with a wall touched, over all runs.
    wall_steps: usize,
    time: f64,
    disp: f64,
    xy: f64,
    z: f64,
    planned_time: f64,
    planned_length: f64,
}

/// Which points no other point beats in both completion time and `y` (points without
/// a completion time are never on the front).
fn pareto(stats: &[PointStats], y: impl Fn(&PointStats) -> f64) -> Vec<bool> {
    stats
        .iter()
        .map(|p| {
            p.time.is_finite()
                && !stats.iter().any(|q| {
                    q.time.is_finite()
                        && q.time <= p.time
                        && y(q) <= y(p)
                        && (q.time < p.time || y(q) < y(p))
                })
        })
        .collect()
}
