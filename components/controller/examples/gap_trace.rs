//! Diagnosis: follow one leg of a `plamo plan --out DIR` plan (DIR/plan.json) on a
//! built-in scene and print, every 0.25 s, the controller's form, the head, the
//! heading against the plan's direction and which bodies touch something other than
//! the terrain (walls, ceilings).
//!
//! `cargo run --release -p plamo-controller --features mujoco --example gap_trace --
//! PLAN.json [rapier|mujoco] [leg] [t0] [duration] [scene]`

use std::error::Error;

use plamo_controller::{
    ControllerSettings, HeadPath, ModelBasedController, Observation, Policy, Waypoint, control_step,
};
use plamo_physics::{BODY_NAMES, BackendKind, HumanoidPose, PhysicsSettings, create_backend};
use plamo_scenes::Scene;

struct Timed {
    /// (t, x, y, head z absolute, v)
    pts: Vec<[f64; 5]>,
    t0: f64,
}

impl Timed {
    fn at(&self, t: f64) -> ([f64; 5], [f64; 2]) {
        let t = t + self.t0;
        let k = self
            .pts
            .partition_point(|p| p[0] <= t)
            .clamp(1, self.pts.len() - 1);
        let (a, b) = (self.pts[k - 1], self.pts[k]);
        let f = ((t - a[0]) / (b[0] - a[0]).max(1e-9)).clamp(0.0, 1.0);
        let p: [f64; 5] = std::array::from_fn(|i| a[i] + f * (b[i] - a[i]));
        let d = [b[1] - a[1], b[2] - a[2]];
        let n = d[0].hypot(d[1]).max(1e-9);
        (p, [d[0] / n, d[1] / n])
    }
}

impl HeadPath for Timed {
    fn point(&self, _scene: &Scene, t: f64) -> Waypoint {
        let (p, _) = self.at(t);
        Waypoint {
            x: p[1],
            y: p[2],
            z: p[3],
            v: p[4],
        }
    }
    fn direction(&self, t: f64) -> [f64; 2] {
        self.at(t).1
    }
    fn head_height(&self) -> f64 {
        0.5
    }
}

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let plan: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&args[0])?)?;
    let kind = match args.get(1).map(String::as_str) {
        Some("mujoco") => BackendKind::Mujoco,
        _ => BackendKind::Rapier,
    };
    let leg: usize = args.get(2).map_or(Ok(0), |s| s.parse())?;
    let t0: f64 = args.get(3).map_or(Ok(0.0), |s| s.parse())?;
    let duration: f64 = args.get(4).map_or(Ok(30.0), |s| s.parse())?;
    let scene = plamo_scenes::builtin(args.get(5).map_or("playground", String::as_str))?;
    let tr = &plan["route"][leg];
    let start_t = tr["t0"].as_f64().unwrap_or(0.0);
    let pts: Vec<[f64; 5]> = tr["points"]
        .as_array()
        .ok_or("no points")?
        .iter()
        .map(|p| {
            let g = |k: &str| p[k].as_f64().unwrap_or(0.0);
            [
                g("t"),
                g("x"),
                g("y"),
                g("ground") + g("head_height"),
                g("v"),
            ]
        })
        .collect();
    let path = Timed {
        pts,
        t0: t0 - start_t.min(0.0),
    };
    let settings = ControllerSettings::default();
    let crawl = match std::env::var_os("PLAMO_CRAWL_PARAMS") {
        Some(p) => plamo_controller::CrawlParams::load(std::path::Path::new(&p))?,
        None => plamo_controller::CrawlParams::default(),
    };
    let mut policy = ModelBasedController::with_all_params(
        plamo_controller::GaitParams::default(),
        crawl,
        settings.clone(),
    )?;
    let mut physics = create_backend(kind, &scene, &PhysicsSettings::default())?;
    let (p, d) = path.at(0.0);
    physics.reset(&HumanoidPose::standing_on(
        &scene.terrain,
        p[1],
        p[2],
        d[1].atan2(d[0]),
    ))?;
    policy.reset();
    let mut obs = Observation::new(ModelBasedController::LAYOUT);
    let mut action = plamo_controller::Action::zeros(ModelBasedController::LAYOUT.num_joints);
    let steps = (duration * 30.0) as usize;
    for c in 0..steps {
        let t = c as f64 / 30.0;
        let s = physics.state().clone();
        let ground = scene.height_at(s.head[0], s.head[1]);
        let touching: Vec<&str> = (0..BODY_NAMES.len())
            .filter(|&b| s.contact[b] && !s.terrain_contact[b])
            .map(|b| BODY_NAMES[b])
            .collect();
        let (p, d) = path.at(t);
        let herr = (d[1].atan2(d[0]) - s.heading() + std::f64::consts::PI)
            .rem_euclid(2.0 * std::f64::consts::PI)
            - std::f64::consts::PI;
        let fallen = s.head[2] - ground < settings.fall_min_head_height;
        if c % 8 == 0 || (fallen && c % 2 == 0) || (!touching.is_empty() && c % 2 == 0) {
            println!(
                "t {:6.2} {} torso {:4.2} sh {:4.2} head ({:5.2},{:5.2},{:4.2}) plan ({:5.2},{:5.2},{:4.2}) v {:4.2} lag {:4.2} heading_err {:6.1} deg{}{}",
                t + t0,
                if policy.is_crawling() {
                    "crawl"
                } else {
                    "biped"
                },
                s.body_pos[1][2] - ground,
                s.body_pos[3][2] - ground,
                s.head[0],
                s.head[1],
                s.head[2] - ground,
                p[1],
                p[2],
                p[3] - scene.height_at(p[1], p[2]),
                p[4],
                (p[1] - s.head[0]).hypot(p[2] - s.head[1]),
                herr.to_degrees(),
                if touching.is_empty() {
                    String::new()
                } else {
                    format!(" TOUCH {touching:?}")
                },
                if fallen { " FALLEN" } else { "" }
            );
        }
        if fallen {
            println!("fall at t {:.2}", t + t0);
            break;
        }
        control_step(
            physics.as_mut(),
            &s,
            &path,
            &scene,
            t,
            &mut policy,
            &mut obs,
            &mut action,
        )?;
    }
    Ok(())
}
