//! One closed-loop run for the experiments: planner (with the experiment's
//! [`PlannerSettings`]), controller and physics in lockstep in this process, exactly
//! as `plamo run` builds them from a [`RunSpec`] except for the planner settings,
//! plus what the experiments measure beyond the lockstep's per-instruction report:
//! collisions with walls, ceilings and moving obstacles, and the head's track.
//! A wall or ceiling is touched when physics reports a body in contact close to one
//! ([`STATIC_ATTRIBUTION`]); a moving obstacle when a body comes within
//! [`BODY_RADIUS`] of its surface (obstacles are kinematic: they push, never stop).

use plamo_controller::ControllerSettings;
use plamo_physics::{BackendKind, PhysicsSettings};
use plamo_planner::{
    FLAG_INFEASIBLE, FLAG_REPLANNED, Locomotion, Planner, PlannerComponent, PlannerSettings,
};
use plamo_scenes::{ObstacleShape, Scene};

use super::body_state::{BodyState, HeadTrack};
use super::fall_posture::{FallPose, FallPosture};
use super::ground::{GroundKind, ground_kind};
use crate::lockstep::{InProcess, Links, Lockstep, RunError, StepStatus};
use crate::spec::{ControllerParams, RunSpec, controller_with, default_time_limit};

/// Radius around a body's origin taken as its surface when checking contact with
/// moving obstacles \[m\] (the humanoid's limb capsules are
/// 0.04-0.1 m thick; body positions are their origins).
pub const BODY_RADIUS: f64 = 0.1;

/// Head track sampling period \[s\].
const TRACK_DT: f64 = 0.5;

pub use crate::spec::{TIME_LIMIT_EXTRA, TIME_LIMIT_FACTOR};

/// What a run is.
#[derive(Debug, Clone)]
pub struct EpisodeSpec<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Instruction text; the first must say where it starts ("from the <landmark>").
    pub instructions: String,
    /// Physics engine.
    pub backend: BackendKind,
    /// Seed of the start-heading perturbation ([`RunSpec::seed`]).
    pub seed: u64,
    /// Planner parameters.
    pub planner: PlannerSettings,
    /// Controller parameters.
    pub controller: ControllerParams,
    /// Physics settings.
    pub physics_settings: PhysicsSettings,
    /// Simulated-time limit \[s\]; `None`: [`TIME_LIMIT_FACTOR`] x planned time +
    /// [`TIME_LIMIT_EXTRA`].
    pub max_seconds: Option<f64>,
}

/// What a run did.
#[derive(Debug, Clone, Default)]
pub struct Episode {
    /// The planner could not plan the route at the start (the message).
    pub planning_error: Option<String>,
    /// A component failed during the run (the message).
    pub run_error: Option<String>,
    /// Instructions in the text.
    pub instructions: usize,
    /// Instructions whose target was reached.
    pub reached: usize,
    /// Fall events over the run.
    pub falls: u32,
    /// The planner flagged the remaining route infeasible at some step.
    pub infeasible: bool,
    /// The time limit ended the run.
    pub timed_out: bool,
    /// Simulated time until the last instruction was done, or the run ended \[s\].
    pub time_s: f64,
    /// Mean head XY error against the plan, over every recorded step \[m\].
    pub xy_err: f64,
    /// Mean absolute head Z error \[m\].
    pub z_err: f64,
    /// Mean residual root force over every recorded step, fraction of m*g \[-\].
    pub residual_force: f64,
    /// Control steps with some body touching a wall or ceiling.
    pub static_contact_steps: u32,
    /// Times some body started touching a moving obstacle.
    pub dynamic_collisions: u32,
    /// Control steps on which the plan was re-planned.
    pub replans: u32,
    /// Planned route length at the start \[m\] (planner only).
    pub planned_length: f64,
    /// Planned route time at the start \[s\] (planner only).
    pub planned_time: f64,
    /// Head XY every [`TRACK_DT`] seconds.
    pub track: Vec<[f64; 2]>,
    /// Where each fall happened, in order (as many as [`Episode::falls`]).
    pub fall_sites: Vec<FallSite>,
    /// Fingerprint of every world state of the run (as `plamo run` prints it): a
    /// replay with the same scene, instructions, seed and time limit matches it.
    pub digest: u64,
}

/// Where a fall happened: the form the instruction asked for, the ground under
/// the root, the body's posture when the fall rule first judged the humanoid
/// fallen, what the body was doing in the seconds before, and when in its
/// instruction that was.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FallSite {
    /// The instruction's locomotion.
    pub locomotion: Locomotion,
    /// The ground there.
    pub ground: GroundKind,
    /// How the body lay.
    pub posture: FallPosture,
    /// What the body was doing before (the plan's form may be another).
    pub body: BodyState,
    /// The instruction it fell in (0 = the first).
    pub leg: usize,
    /// How long that instruction had been running \[s\]: a fall in a leg's first
    /// seconds is one of the change of form or of heading at its landmark.
    pub into_leg: f64,
}

/// A locomotion's instruction verb ("crouch-walk"), as the experiments write it.
pub fn verb(l: Locomotion) -> &'static str {
    match l {
        Locomotion::Crawl => "crawl",
        Locomotion::CrouchWalk => "crouch-walk",
        Locomotion::Walk => "walk",
        Locomotion::Run => "run",
        Locomotion::Sprint => "sprint",
    }
}

impl FallSite {
    /// `verb@ground` ("crawl@rough").
    pub fn field(&self) -> String {
        format!("{}@{}", verb(self.locomotion), self.ground.name())
    }
}

impl Episode {
    /// Every target reached without a fall.
    pub fn success(&self) -> bool {
        self.planning_error.is_none()
            && self.run_error.is_none()
            && self.reached == self.instructions
            && self.falls == 0
    }

    /// Mean 3D head displacement: hypot of the mean XY and mean Z errors \[m\].
    pub fn displacement(&self) -> f64 {
        self.xy_err.hypot(self.z_err)
    }

    /// The track as `x:y;x:y;...` (centimetres), a CSV-safe field.
    pub fn track_field(&self) -> String {
        self.track
            .iter()
            .map(|p| format!("{:.2}:{:.2}", p[0], p[1]))
            .collect::<Vec<_>>()
            .join(";")
    }

    /// The fall sites as `verb@ground;...`, a CSV-safe field.
    pub fn fall_sites_field(&self) -> String {
        self.join_falls(FallSite::field)
    }

    /// The fall postures as `posture;...` (in the order of
    /// [`Episode::fall_sites_field`]), a CSV-safe field.
    pub fn fall_postures_field(&self) -> String {
        self.join_falls(|s| s.posture.name().to_string())
    }

    /// What the bodies were doing before the falls, as `state;...` (in the order of
    /// [`Episode::fall_sites_field`]), a CSV-safe field.
    pub fn fall_bodies_field(&self) -> String {
        self.join_falls(|s| s.body.name().to_string())
    }

    /// When in their instructions the falls came, as `n:seconds;...` (n from 1, as
    /// `plamo run` numbers instructions; in the order of
    /// [`Episode::fall_sites_field`]), a CSV-safe field.
    pub fn fall_legs_field(&self) -> String {
        self.join_falls(|s| format!("{}:{:.2}", s.leg + 1, s.into_leg))
    }

    fn join_falls(&self, each: impl Fn(&FallSite) -> String) -> String {
        self.fall_sites
            .iter()
            .map(each)
            .collect::<Vec<_>>()
            .join(";")
    }
}

/// Parse [`Episode::track_field`] back.
pub fn parse_track(s: &str) -> Vec<[f64; 2]> {
    s.split(';')
        .filter_map(|p| {
            let (x, y) = p.split_once(':')?;
            Some([x.parse().ok()?, y.parse().ok()?])
        })
        .collect()
}

/// The planner for `spec` at its start, or the planning error.
pub fn plan(spec: &EpisodeSpec) -> Result<(RunSpec, Planner), String> {
    let run = RunSpec {
        scene: spec.scene.name.clone(),
        instructions: vec![spec.instructions.clone()],
        backend: spec.backend,
        seed: spec.seed,
        params: Default::default(),
    };
    let p = run.placement(spec.scene, 0).map_err(|e| e.to_string())?;
    let planner = Planner::new(
        spec.scene.clone(),
        &spec.instructions,
        [p.x, p.y],
        spec.planner.clone(),
    )
    .map_err(|e| e.to_string())?;
    Ok((run, planner))
}

/// How far from a wall or ceiling a body in contact may be and still have its
/// contact put down to it \[m\] (body positions are origins, not surfaces).
pub const STATIC_ATTRIBUTION: f64 = 0.2;

/// Whether body `b`, which physics reports in contact with something, touches a wall
/// or a ceiling: near one and not a foot on the ground.
fn touches_static(scene: &Scene, b: [f64; 3]) -> bool {
    let r = STATIC_ATTRIBUTION;
    if b[2] - scene.height_at(b[0], b[1]) < r {
        return false;
    }
    scene
        .walls
        .iter()
        .any(|w| w.footprint.signed_distance(b[0], b[1]) < r && b[2] < w.z_max + r)
        || scene.tops.iter().any(|t| {
            t.footprint.signed_distance(b[0], b[1]) < r && b[2] > t.z_bottom - r && b[2] < t.z_top
        })
}

/// Whether a body at `b` touches moving obstacle `k` at time `t`.
fn touches_dynamic(scene: &Scene, k: usize, t: f64, b: [f64; 3]) -> bool {
    let o = &scene.dynamic[k];
    let st = o.motion.state_at(t);
    let d = [
        b[0] - st.position[0],
        b[1] - st.position[1],
        b[2] - st.position[2],
    ];
    match o.shape {
        ObstacleShape::Sphere { radius } => {
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() < radius + BODY_RADIUS
        }
        ObstacleShape::Box { half_extents: h } => {
            // Boxes yaw with their velocity (as in physics and the planner).
            let v = st.velocity;
            let yaw = if v[0].abs() + v[1].abs() > 1e-9 {
                v[1].atan2(v[0])
            } else {
                0.0
            };
            let (s, c) = yaw.sin_cos();
            let lx = c * d[0] + s * d[1];
            let ly = -s * d[0] + c * d[1];
            lx.abs() < h[0] + BODY_RADIUS
                && ly.abs() < h[1] + BODY_RADIUS
                && d[2].abs() < h[2] + BODY_RADIUS
        }
    }
}

/// Run `spec` to the end.
pub fn run_episode(spec: &EpisodeSpec) -> anyhow::Result<Episode> {
    let mut ep = Episode::default();
    let (run, planner) = match plan(spec) {
        Ok(v) => v,
        Err(e) => {
            ep.planning_error = Some(e);
            ep.instructions = plamo_planner::parse_instructions(&spec.instructions, spec.scene)
                .map_or(1, |v| v.len());
            return Ok(ep);
        }
    };
    ep.instructions = planner.instructions().len();
    let forms: Vec<Locomotion> = planner
        .instructions()
        .iter()
        .map(|i| i.locomotion)
        .collect();
    ep.planned_length = planner.route().iter().map(|t| t.length()).sum();
    ep.planned_time = planner.route().last().map_or(0.0, |t| t.end_time());
    let max_seconds = spec
        .max_seconds
        .unwrap_or_else(|| default_time_limit(ep.planned_time));
    let scene = spec.scene;
    let links = Links {
        physics: Box::new(InProcess::new(
            "physics",
            run.physics_facing(scene, &spec.physics_settings, &[planner.start_heading()])?,
        )),
        planners: vec![Box::new(InProcess::new(
            "planner-0",
            PlannerComponent::new(planner, 0),
        ))],
        controllers: vec![Box::new(InProcess::new(
            "controller-0",
            controller_with(scene, 0, spec.controller, run.backend)?,
        ))],
    };
    let mut ls = Lockstep::start(
        links,
        scene.clone(),
        &[ep.instructions],
        &ControllerSettings::default(),
        max_seconds,
    )?;
    let mut touching = vec![false; scene.dynamic.len()];
    let mut next_track = 0.0;
    let mut falls_so_far = 0;
    // The instruction under way and when it began \[s\].
    let mut leg = (0, 0.0);
    let mut head_track = HeadTrack::default();
    let status = loop {
        // The pose the fall rule judges in this step (the body may be put back in it).
        let a = &ls.world().agents[0];
        let judged = FallPose {
            root: a.root_position,
            orientation: a.root_orientation,
            head: a.head_position,
        };
        head_track.record(scene, judged.root, judged.head);
        let stepped = ls.step();
        // A site for each fall the run's own count gained (the count is kept per
        // instruction: a fall across an instruction's end counts in both).
        let falls = ls.falls(0);
        let i = (ls.plans()[0].instruction as usize).min(forms.len().saturating_sub(1));
        if i != leg.0 {
            leg = (i, ls.tick().seconds());
        }
        for _ in falls_so_far..falls {
            ep.fall_sites.push(FallSite {
                locomotion: forms.get(i).copied().unwrap_or(Locomotion::Walk),
                ground: ground_kind(&scene.terrain, judged.root[0], judged.root[1]),
                posture: FallPosture::of(scene, &judged),
                // The step just recorded: never empty.
                body: head_track.state().unwrap_or(BodyState::Upright),
                leg: i,
                into_leg: ls.tick().seconds() - leg.1,
            });
        }
        if falls > falls_so_far {
            head_track.clear();
        }
        falls_so_far = falls;
        let status = match stepped {
            Ok(s) => s,
            Err(e @ RunError::Component { .. }) => {
                ep.run_error = Some(e.to_string());
                break StepStatus::TimedOut;
            }
            Err(e) => return Err(e.into()),
        };
        if status != StepStatus::Running {
            break status;
        }
        let t = ls.tick().seconds();
        let plan = &ls.plans()[0];
        ep.infeasible |= plan.flags & FLAG_INFEASIBLE != 0;
        ep.replans += u32::from(plan.flags & FLAG_REPLANNED != 0);
        let a = &ls.world().agents[0];
        let bodies = a.bodies();
        if t >= next_track {
            ep.track.push([a.head_position[0], a.head_position[1]]);
            next_track += TRACK_DT;
        }
        let contact = |i: usize| i < 32 && a.body_contacts & (1 << i) != 0;
        if bodies
            .iter()
            .enumerate()
            .any(|(i, &b)| contact(i) && touches_static(scene, b))
        {
            ep.static_contact_steps += 1;
        }
        for (k, was) in touching.iter_mut().enumerate() {
            let now = bodies.iter().any(|&b| touches_dynamic(scene, k, t, b));
            ep.dynamic_collisions += u32::from(now && !*was);
            *was = now;
        }
    };
    ep.timed_out = status == StepStatus::TimedOut && ep.run_error.is_none();
    ep.digest = ls.digest().value();
    let report = ls.report().swap_remove(0);
    let mut steps = 0u64;
    for r in &report {
        ep.reached += usize::from(r.reached);
        ep.falls += r.metrics.falls;
        ep.time_s += r.time_s;
        ep.xy_err += r.metrics.xy_err_mean * r.metrics.steps as f64;
        ep.z_err += r.metrics.z_err_mean * r.metrics.steps as f64;
        ep.residual_force += r.metrics.residual_force_mean * r.metrics.steps as f64;
        steps += r.metrics.steps;
    }
    if steps > 0 {
        ep.xy_err /= steps as f64;
        ep.z_err /= steps as f64;
        ep.residual_force /= steps as f64;
    }
    Ok(ep)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every fall the run counts gets a site, in the form the instruction asked for,
    /// on the ground it happened on: rapier's run over a flight of stairs at 5 m/s
    /// falls there (the default `stand_step_speed` slows it to 1 m/s, and then it
    /// does not fall; since the swing foot lands by arrival, at 4 m/s its only fall
    /// is on a landing).
    #[test]
    fn falls_get_their_sites() {
        let scene = plamo_scenes::builtin("terrain-stairs").expect("built-in scene");
        let ep = run_episode(&EpisodeSpec {
            scene: &scene,
            instructions: "Run from the start to the goal".into(),
            backend: BackendKind::Rapier,
            seed: 0,
            planner: PlannerSettings {
                stand_step_speed: 0.0,
                run_speed: 5.0,
                ..Default::default()
            },
            controller: Default::default(),
            physics_settings: Default::default(),
            // Long enough for the run to go over the flight and back onto it: 8 s
            // stopped falling there once rapier took 4 solver iterations.
            max_seconds: Some(16.0),
        })
        .expect("episode");
        assert!(ep.falls > 0, "no fall to attribute: pick a harder ground");
        assert_eq!(
            ep.fall_sites.len(),
            ep.falls as usize,
            "{:?}",
            ep.fall_sites
        );
        // A run from standing that never got down: upright before its first fall.
        assert_eq!(
            ep.fall_sites[0].body,
            BodyState::Upright,
            "{:?}",
            ep.fall_sites
        );
        for s in &ep.fall_sites {
            assert_eq!(s.locomotion, Locomotion::Run);
            // One instruction: every fall is in it, timed from the start.
            assert_eq!(s.leg, 0);
            assert!(s.into_leg > 0.0 && s.into_leg <= 16.0, "{s:?}");
        }
        // One entry per fall in every per-fall field.
        for field in [
            ep.fall_postures_field(),
            ep.fall_bodies_field(),
            ep.fall_legs_field(),
        ] {
            assert_eq!(field.split(';').count(), ep.falls as usize, "{field}");
        }
        assert!(
            ep.fall_legs_field().starts_with("1:"),
            "{}",
            ep.fall_legs_field()
        );
        assert!(
            ep.fall_sites.iter().any(|s| s.ground == GroundKind::Stairs),
            "{}",
            ep.fall_sites_field()
        );
    }
}
