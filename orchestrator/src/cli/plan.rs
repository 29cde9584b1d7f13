//! `plamo plan`: run the planner alone on a scene and write the plan as JSON, a
//! top-down map (path coloured by speed, line width by head height) and a
//! speed / head-height profile over distance.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use plamo_planner::{Planner, PlannerSettings, Source, Trajectory, parse_instructions};
use serde::Serialize;

use plamo::viz::profile::{ProfileSegment, render_profile};
use plamo::viz::{ColorBar, MapOverlay, OverlayMarker, OverlayPath, render_map};

/// Arguments of `plamo plan`.
#[derive(Debug, Args)]
pub struct PlanArgs {
    /// Built-in scene name or path to a scene file.
    #[arg(long)]
    scene: String,
    /// Instructions, e.g. "run from the tree to the car, then crawl to the bench".
    #[arg(long)]
    instructions: String,
    /// Terrain preference c (edge length grows by e^(c * slope) - 1).
    #[arg(long)]
    c: Option<f64>,
    /// Planner parameter file: a TOML table of planner settings (see
    /// `PlannerSettings`; fields left out keep their defaults), as for `plamo run`;
    /// `--c` goes on top of it.
    #[arg(long)]
    planner_params: Option<PathBuf>,
    /// Start position "X,Y" in metres; default: the first instruction's source.
    #[arg(long, value_parser = parse_xy, allow_hyphen_values = true)]
    start: Option<[f64; 2]>,
    /// Output directory (created).
    #[arg(long)]
    out: PathBuf,
}

fn parse_xy(s: &str) -> Result<[f64; 2], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("expected X,Y in metres: {e}"))?;
    match v.as_slice() {
        [x, y] if x.is_finite() && y.is_finite() => Ok([*x, *y]),
        _ => Err(format!("expected X,Y in metres, got `{s}`")),
    }
}

#[derive(Serialize)]
struct PlanJson<'a> {
    scene: &'a str,
    instructions: &'a [plamo_planner::Instruction],
    settings: &'a PlannerSettings,
    start: [f64; 2],
    total_length_m: f64,
    total_time_s: f64,
    plan_ms: f64,
    route: &'a [Trajectory],
}

/// Speed colour scale: blue at or below 1 m/s, red at or above 3.5 m/s.
fn speed_bar() -> ColorBar {
    ColorBar {
        label: "speed [m/s]".into(),
        min: 1.0,
        max: 3.5,
        colors: vec![
            [30, 60, 220],
            [20, 170, 200],
            [40, 170, 60],
            [240, 180, 20],
            [215, 30, 30],
        ],
    }
}

/// Line width for a head height: standing 6 px, crouched 4 px, crawling 2 px.
fn width_for(head: f64) -> u32 {
    if head >= 1.2 {
        6
    } else if head >= 0.6 {
        4
    } else {
        2
    }
}

/// Run `plamo plan`.
pub fn run(args: PlanArgs) -> anyhow::Result<ExitCode> {
    let scene = plamo_scenes::resolve(&args.scene)
        .with_context(|| format!("loading scene `{}`", args.scene))?;
    let mut settings = match &args.planner_params {
        Some(f) => plamo::spec::load_planner_settings(f).map_err(anyhow::Error::msg)?,
        None => PlannerSettings::default(),
    };
    if let Some(c) = args.c {
        settings.slope_preference_c = c;
    }
    let parsed = parse_instructions(&args.instructions, &scene)?;
    let start = match (args.start, &parsed[0].source) {
        (Some(p), _) => p,
        (None, Source::Landmark(name)) => scene
            .landmark(name)
            .map(|l| l.region.center())
            .context("source landmark")?,
        (None, _) => {
            anyhow::bail!("the first instruction has no \"from the <landmark>\"; pass --start X,Y")
        }
    };
    let t0 = Instant::now();
    let planner = Planner::new(scene.clone(), &args.instructions, start, settings.clone())?;
    let plan_ms = t0.elapsed().as_secs_f64() * 1e3;
    let route = planner.route();
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;

    let total_length: f64 = route.iter().map(|t| t.length()).sum();
    let total_time = route.last().map_or(0.0, |t| t.end_time());
    let json = PlanJson {
        scene: &scene.name,
        instructions: planner.instructions(),
        settings: &settings,
        start,
        total_length_m: total_length,
        total_time_s: total_time,
        plan_ms,
        route,
    };
    let json_path = args.out.join("plan.json");
    std::fs::write(&json_path, serde_json::to_string_pretty(&json)?)
        .with_context(|| format!("writing {}", json_path.display()))?;

    // Map: one overlay path per run of equal line width, coloured per segment.
    let bar = speed_bar();
    let mut overlay = MapOverlay {
        title: format!(
            "{}: {} instruction(s), c = {}, {:.1} m in {:.1} s",
            scene.name,
            route.len(),
            settings.slope_preference_c,
            total_length,
            total_time
        ),
        colorbar: Some(bar.clone()),
        ..Default::default()
    };
    let mut labelled = false;
    for (k, (tr, ins)) in route.iter().zip(planner.instructions()).enumerate() {
        let pts = &tr.points;
        let mut i = 0;
        while i + 1 < pts.len() {
            let w = width_for(pts[i].head_height);
            let mut j = i + 1;
            while j + 1 < pts.len() && width_for(pts[j].head_height) == w {
                j += 1;
            }
            overlay.paths.push(OverlayPath {
                points: pts[i..=j].iter().map(|p| [p.x, p.y]).collect(),
                colors: pts[i..j].iter().map(|p| bar.color_for(p.v)).collect(),
                width: w,
                dashed: false,
                label: (!labelled).then(|| "plan (colour: speed; width: head height)".to_string()),
            });
            labelled = true;
            i = j;
        }
        if let Some(p) = pts.first() {
            overlay.markers.push(OverlayMarker {
                at: [p.x, p.y],
                color: [0, 0, 0],
                label: Some(format!("{}: {:?}", k + 1, ins.locomotion).to_lowercase()),
            });
        }
        // The lowest head point of each ceiling passage.
        let want = settings.head_height(ins.locomotion);
        if let Some(low) = pts
            .iter()
            .filter(|p| p.head_height < want - 0.05)
            .min_by(|a, b| a.head_height.total_cmp(&b.head_height))
        {
            overlay.markers.push(OverlayMarker {
                at: [low.x, low.y],
                color: [120, 60, 0],
                label: Some(format!("head {:.2} m", low.head_height)),
            });
        }
    }
    if let Some(p) = route.last().and_then(|t| t.points.last()) {
        overlay.markers.push(OverlayMarker {
            at: [p.x, p.y],
            color: [0, 0, 0],
            label: Some("end".into()),
        });
    }
    let map_path = args.out.join("plan.png");
    render_map(&scene, &overlay, &map_path)?;

    // Profiles over the route's distance.
    let mut offset = 0.0;
    let mut segments = Vec::new();
    for (tr, ins) in route.iter().zip(planner.instructions()) {
        let cap_of = |p: &plamo_planner::PathPoint| {
            let lat = if p.curvature > 1e-9 {
                (settings.a_lat / p.curvature).sqrt()
            } else {
                f64::INFINITY
            };
            p.v_cap.min(lat)
        };
        segments.push(ProfileSegment {
            label: ins.text.clone(),
            distance: tr.points.iter().map(|p| offset + p.s).collect(),
            speed: tr.points.iter().map(|p| p.v).collect(),
            speed_cap: tr.points.iter().map(cap_of).collect(),
            head_height: tr.points.iter().map(|p| p.head_height).collect(),
            headroom: tr
                .points
                .iter()
                .map(|p| scene.headroom_at(p.x, p.y))
                .collect(),
        });
        offset += tr.length();
    }
    let profile_path = args.out.join("profile.png");
    render_profile(
        &format!("{}: speed and head height along the plan", scene.name),
        &segments,
        &profile_path,
    )?;

    say!(
        "planned {} instruction(s) on `{}` in {:.1} ms: {:.1} m, {:.1} s",
        route.len(),
        scene.name,
        plan_ms,
        total_length,
        total_time
    );
    for (tr, ins) in route.iter().zip(planner.instructions()) {
        let v_top = tr.points.iter().map(|p| p.v).fold(0.0, f64::max);
        say!(
            "  {:<45} {:>6.1} m {:>6.1} s  top {:.2} m/s",
            ins.text,
            tr.length(),
            tr.duration(),
            v_top
        );
    }
    say!(
        "wrote {}, {}, {}",
        json_path.display(),
        map_path.display(),
        profile_path.display()
    );
    Ok(ExitCode::SUCCESS)
}
