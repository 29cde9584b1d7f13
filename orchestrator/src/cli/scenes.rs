//! `plamo scenes ...`: list, show, validate, render and generate scenes.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::Subcommand;
use plamo::viz::{MapOverlay, render_map};
use plamo_scenes::{Motion, Region, Scene};

/// Scene subcommands.
#[derive(Debug, Subcommand)]
pub enum ScenesCommand {
    /// List the built-in scenes.
    List,
    /// Print a summary of a scene (built-in name or file).
    Show {
        /// Built-in scene name or a .toml / .json file.
        scene: String,
    },
    /// Check scene files; exits non-zero if any is invalid.
    Validate {
        /// Scene files (.toml, or ProtoMotions .json) or built-in names.
        #[arg(required = true)]
        files: Vec<String>,
    },
    /// Draw a scene from above into a PNG.
    Render {
        /// Built-in scene name or a file.
        scene: String,
        /// The picture to write.
        #[arg(long)]
        out: PathBuf,
    },
    /// Write a random (always valid) scene file.
    Random {
        /// Seed: the same seed gives the same scene.
        #[arg(long)]
        seed: u64,
        /// The .toml file to write.
        #[arg(long)]
        out: PathBuf,
    },
}

/// Run a scene subcommand.
pub fn run(cmd: ScenesCommand) -> anyhow::Result<ExitCode> {
    match cmd {
        ScenesCommand::List => {
            for name in plamo_scenes::builtin_names() {
                let s = plamo_scenes::builtin(name)?;
                say!("{name:<16} {}", s.description);
            }
            Ok(ExitCode::SUCCESS)
        }
        ScenesCommand::Show { scene } => {
            let s = plamo_scenes::resolve(&scene)?;
            print!("{}", summary(&s));
            Ok(ExitCode::SUCCESS)
        }
        ScenesCommand::Validate { files } => {
            let mut failed = 0;
            for f in &files {
                // `plamo scenes validate scenes/*.toml` also matches the crate's
                // manifest, which lives beside the built-in scene files.
                if std::path::Path::new(f).file_name() == Some("Cargo.toml".as_ref()) {
                    say!("skip   {f}: a Cargo manifest, not a scene");
                    continue;
                }
                match plamo_scenes::resolve(f).and_then(|s| plamo_scenes::validate(&s).map(|()| s))
                {
                    Ok(s) => say!("ok     {f}: {}", one_line(&s)),
                    Err(e) => {
                        failed += 1;
                        say!("error  {e}");
                    }
                }
            }
            if failed > 0 {
                eprintln!("{failed} of {} scene(s) invalid", files.len());
                Ok(ExitCode::FAILURE)
            } else {
                Ok(ExitCode::SUCCESS)
            }
        }
        ScenesCommand::Render { scene, out } => {
            let s = plamo_scenes::resolve(&scene)?;
            render_map(&s, &MapOverlay::default(), &out)?;
            say!("wrote {}", out.display());
            Ok(ExitCode::SUCCESS)
        }
        ScenesCommand::Random { seed, out } => {
            let (file, scene) = plamo_scenes::random_scene_with_file(seed);
            std::fs::write(&out, file.to_toml())
                .with_context(|| format!("cannot write {}", out.display()))?;
            say!("wrote {}: {}", out.display(), one_line(&scene));
            Ok(ExitCode::SUCCESS)
        }
    }
}

fn one_line(s: &Scene) -> String {
    let (lo, hi) = s.terrain.bounds();
    format!(
        "{} ({:.0} x {:.0} m, {} walls, {} ceilings, {} moving, landmarks: {})",
        s.name,
        hi[0] - lo[0],
        hi[1] - lo[1],
        s.walls.len(),
        s.tops.len(),
        s.dynamic.len(),
        s.landmark_names().join(", ")
    )
}

fn summary(s: &Scene) -> String {
    use std::fmt::Write;
    let g = &s.terrain;
    let (lo, hi) = g.bounds();
    let (zmin, zmax) = g.height_range();
    let mut o = String::new();
    let _ = writeln!(o, "{}: {}", s.name, s.description);
    let _ = writeln!(
        o,
        "terrain   x {:.1} ..= {:.1} m, y {:.1} ..= {:.1} m, {} x {} samples at {} m, height {zmin:.2} ..= {zmax:.2} m",
        lo[0], hi[0], lo[1], hi[1], g.nx, g.ny, g.resolution
    );
    for w in &s.walls {
        let f = &w.footprint;
        let _ = writeln!(
            o,
            "wall      {:<14} centre ({:.1}, {:.1}), {:.1} x {:.1} m, yaw {:.0} deg, top {:.2} m",
            w.name,
            f.center[0],
            f.center[1],
            2.0 * f.half_extents[0],
            2.0 * f.half_extents[1],
            f.yaw.to_degrees(),
            w.z_max
        );
    }
    for t in &s.tops {
        let f = &t.footprint;
        let _ = writeln!(
            o,
            "ceiling   {:<14} centre ({:.1}, {:.1}), {:.1} x {:.1} m, underside at {:.2} m",
            t.name,
            f.center[0],
            f.center[1],
            2.0 * f.half_extents[0],
            2.0 * f.half_extents[1],
            t.z_bottom
        );
    }
    for d in &s.dynamic {
        let rule = match d.motion {
            Motion::Linear { speed, .. } => format!("back and forth at {speed} m/s"),
            Motion::Circle { period, .. } => format!("circle, period {period} s"),
            Motion::Waypoints { ref points, speed } => {
                format!("loop through {} points at {speed} m/s", points.len())
            }
            Motion::Ball { .. } => "thrown ball".to_string(),
        };
        let _ = writeln!(o, "moving    {:<14} {rule}", d.name);
    }
    for l in &s.landmarks {
        let region = match l.region {
            Region::Circle { center, radius } => {
                format!("circle ({:.1}, {:.1}) r {radius} m", center[0], center[1])
            }
            Region::Rect { footprint: f } => format!(
                "rect ({:.1}, {:.1}) {:.1} x {:.1} m",
                f.center[0],
                f.center[1],
                2.0 * f.half_extents[0],
                2.0 * f.half_extents[1]
            ),
        };
        let _ = writeln!(o, "landmark  {:<14} {region}", l.name);
    }
    o
}
