//! What a run is (scene, per-agent instructions, backend, seed) and how its
//! components are built from it. The orchestrator and every component process build
//! from the same [`RunSpec`], so they agree on the scene, the agents and their start.

use std::path::{Path, PathBuf};

use plamo_controller::{
    ControllerComponent, ControllerSettings, CrawlParams, GaitParams, ModelBasedController,
};
use plamo_physics::{BackendKind, PhysicsComponent, PhysicsSettings, Placement};
use plamo_planner::{Planner, PlannerComponent, PlannerSettings, Source, parse_instructions};
use plamo_scenes::{Region, Scene};

use crate::lockstep::{InProcess, Links, RunError, stands_clear};
use crate::seeds::splitmix;

/// Largest start-heading perturbation drawn from the seed \[rad\].
pub const SEED_YAW_JITTER: f64 = 0.05;
/// Spacing of the rings searched for a start where a standing body fits \[m\].
const START_SEARCH_STEP: f64 = 0.1;
/// Radius of ground a standing start needs level \[m\]: the feet and their first step.
const START_FOOTPRINT: f64 = 0.3;
/// Largest height change between ground points a terrain cell apart within
/// [`START_FOOTPRINT`] of a start \[m\]: a slope of 0.7 rad (the planner's steepest)
/// changes 0.084 m per 0.1 m cell; a tile's edge changes more at once.
const START_MAX_STEP: f64 = 0.1;

/// Default simulated-time limit of a run (`plamo run` and every eval): this many
/// times the planned route time...
pub const TIME_LIMIT_FACTOR: f64 = 2.0;
/// ... plus this much \[s\].
pub const TIME_LIMIT_EXTRA: f64 = 15.0;

/// The default simulated-time limit for routes planned to take `route_time` \[s\].
pub fn default_time_limit(route_time: f64) -> f64 {
    TIME_LIMIT_FACTOR * route_time + TIME_LIMIT_EXTRA
}

/// Everything that decides a run's result.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSpec {
    /// Built-in scene name or scene file path.
    pub scene: String,
    /// One instruction text per agent (the agent count is its length).
    pub instructions: Vec<String>,
    /// Physics engine.
    pub backend: BackendKind,
    /// Seed of the start-heading perturbation.
    pub seed: u64,
    /// The controller's parameter files (default: the built-in ones).
    pub params: ParamFiles,
}

/// Parameter files for the planner and the model-based controller (e.g. from `plamo
/// tune`); `None` keeps the built-in parameters.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParamFiles {
    /// Biped gait parameters (`gait.toml` layout).
    pub gait: Option<PathBuf>,
    /// Crawl parameters (`crawl.toml` layout).
    pub crawl: Option<PathBuf>,
    /// Planner parameters: a TOML table of [`PlannerSettings`] fields; fields it
    /// leaves out keep their defaults.
    pub planner: Option<PathBuf>,
    /// Physics settings: a TOML table of [`PhysicsSettings`] fields; fields it leaves
    /// out keep their defaults.
    pub physics: Option<PathBuf>,
}

/// Controller parameters already read (a sweep reads its files once, then runs every
/// job from them); `None` keeps the built-in parameters.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ControllerParams {
    /// Biped gait parameters.
    pub gait: Option<GaitParams>,
    /// Crawl parameters.
    pub crawl: Option<CrawlParams>,
}

impl ControllerParams {
    /// Read a gait and a crawl parameter file (`None`: built in); an error names the
    /// file.
    pub fn load(gait: Option<&Path>, crawl: Option<&Path>) -> Result<Self, String> {
        fn named<T, E: std::fmt::Display>(
            what: &str,
            path: &Path,
            r: Result<T, E>,
        ) -> Result<T, String> {
            r.map_err(|e| {
                let (e, p) = (e.to_string(), path.display().to_string());
                // Parse errors already start with the path.
                if e.contains(&p) {
                    format!("{what} parameter file {e}")
                } else {
                    format!("{what} parameter file {p}: {e}")
                }
            })
        }
        Ok(Self {
            gait: gait
                .map(|p| named("gait", p, GaitParams::load(p)))
                .transpose()?,
            crawl: crawl
                .map(|p| named("crawl", p, CrawlParams::load(p)))
                .transpose()?,
        })
    }

    /// The gait parameters under `backend`: the file's, or the engine's built-in ones
    /// ([`GaitParams::built_in`]).
    pub fn gait_for(&self, backend: BackendKind) -> GaitParams {
        self.gait.unwrap_or_else(|| GaitParams::built_in(backend))
    }

    /// The model-based policy with these files under `backend` (built-in where `None`).
    pub fn policy(
        &self,
        backend: BackendKind,
        settings: ControllerSettings,
    ) -> plamo_controller::Result<ModelBasedController> {
        ModelBasedController::with_all_params(
            self.gait_for(backend),
            self.crawl.unwrap_or_default(),
            settings,
        )
    }

    /// Whether both are the built-in parameters.
    pub fn is_built_in(&self) -> bool {
        self.gait.is_none() && self.crawl.is_none()
    }
}

/// Planner settings from a TOML file of [`PlannerSettings`] fields (the rest keep
/// their defaults), validated; the error names the file and the field.
pub fn load_planner_settings(path: &Path) -> Result<PlannerSettings, String> {
    let named =
        |e: &dyn std::fmt::Display| format!("planner parameter file {}: {e}", path.display());
    let text = std::fs::read_to_string(path).map_err(|e| named(&e))?;
    let settings: PlannerSettings = toml::from_str(&text).map_err(|e| named(&e))?;
    settings.validate().map_err(|e| named(&e))?;
    Ok(settings)
}

/// The physics settings of a `--physics-params` file, checked against their ranges.
pub fn load_physics_settings(path: &Path) -> Result<PhysicsSettings, String> {
    let named =
        |e: &dyn std::fmt::Display| format!("physics parameter file {}: {e}", path.display());
    let text = std::fs::read_to_string(path).map_err(|e| named(&e))?;
    let settings: PhysicsSettings = toml::from_str(&text).map_err(|e| named(&e))?;
    PhysicsSettings {
        humanoids: 1,
        ..settings.clone()
    }
    .validate()
    .map_err(|e| named(&e))?;
    Ok(settings)
}

/// The physics settings of an optional `--physics-params` file: the file's, or the
/// defaults without one.
pub fn physics_settings_or_default(path: Option<&Path>) -> Result<PhysicsSettings, String> {
    path.map_or_else(|| Ok(PhysicsSettings::default()), load_physics_settings)
}

/// Where a humanoid starts in `region`: its centre, or where the centre has no room
/// to stand (a low top over it, a wall beside it) or no level ground
/// ([`level_start`]) the nearest spot of the region that has both, searched on rings
/// [`START_SEARCH_STEP`] apart (without a level one, the centre or the nearest with
/// room). A body spawned standing
/// into a ceiling is thrown out of it by the physics at several m/s. The centre if
/// no spot of the region fits: the lockstep's first control step then puts the body
/// in the plan's form there (on hands and knees under a low top).
fn start_spot(scene: &Scene, region: &Region) -> [f64; 2] {
    let c = region.center();
    let room = |p: [f64; 2]| stands_clear(scene, p[0], p[1]);
    let fits = |p: [f64; 2]| room(p) && level_start(scene, p[0], p[1]);
    if fits(c) {
        return c;
    }
    // Level ground first; where the landmark has none, room to stand as before.
    search_start(region, fits)
        .or_else(|| {
            if room(c) {
                Some(c)
            } else {
                search_start(region, room)
            }
        })
        .unwrap_or(c)
}

/// Whether the ground within [`START_FOOTPRINT`] of (x, y) is free of steps: no two
/// points a terrain cell apart differ by more than [`START_MAX_STEP`]. A body spawned
/// with its feet across a tile's 0.35-0.45 m edge fell in its first second (random-294,
/// random-521; RESULTS.md "Random 4-landmark scenes", session 24).
fn level_start(scene: &Scene, x: f64, y: f64) -> bool {
    let r = scene.terrain.resolution;
    let n = (START_FOOTPRINT / r).ceil() as i32;
    let h = |i: i32, j: i32| scene.height_at(x + f64::from(i) * r, y + f64::from(j) * r);
    (-n..=n).all(|i| {
        (-n..=n).all(|j| {
            let c = h(i, j);
            (c - h(i + 1, j)).abs() <= START_MAX_STEP && (c - h(i, j + 1)).abs() <= START_MAX_STEP
        })
    })
}

/// The first spot of `region` on rings [`START_SEARCH_STEP`] apart around its centre,
/// nearest first, where `fits`.
fn search_start(region: &Region, fits: impl Fn([f64; 2]) -> bool) -> Option<[f64; 2]> {
    let c = region.center();
    let (lo, hi) = region.aabb();
    let reach = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
    let rings = (reach / START_SEARCH_STEP).ceil() as usize;
    (1..=rings)
        .flat_map(|r| {
            let d = r as f64 * START_SEARCH_STEP;
            let n = 8 * r;
            (0..n).map(move |k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                [c[0] + d * a.cos(), c[1] + d * a.sin()]
            })
        })
        .find(|p| region.contains(p[0], p[1]) && fits(*p))
}

/// Agent `k`'s model-based controller with `params` (built-in where `None`).
pub fn controller_with(
    scene: &Scene,
    k: usize,
    params: ControllerParams,
    backend: BackendKind,
) -> Result<ControllerComponent, RunError> {
    let policy = params
        .policy(backend, ControllerSettings::default())
        .map_err(setup)?;
    Ok(ControllerComponent::with_policy(
        k as u32,
        scene.clone(),
        Box::new(policy),
    ))
}

fn setup(e: impl std::fmt::Display) -> RunError {
    RunError::Setup(e.to_string())
}

impl RunSpec {
    /// Number of agents.
    pub fn agents(&self) -> usize {
        self.instructions.len()
    }

    /// Load the scene.
    pub fn load_scene(&self) -> Result<Scene, RunError> {
        plamo_scenes::resolve(&self.scene).map_err(setup)
    }

    /// Where agent `k` starts: the centre of its first instruction's source landmark
    /// (or the spot of it nearest the centre with room to stand, see [`start_spot`]),
    /// facing its first target, heading perturbed by the seed. The physics world puts
    /// it there facing along its plan instead ([`RunSpec::placement_facing`]).
    pub fn placement(&self, scene: &Scene, k: usize) -> Result<Placement, RunError> {
        self.placement_facing(scene, k, None)
    }

    /// Where agent `k` starts ([`RunSpec::placement`]), facing `heading` \[rad\] (its
    /// plan's [`Planner::start_heading`]) where given, else its first target; either
    /// perturbed by the seed. A route that leaves round a wall or a hill sets off
    /// another way than the target lies: a body facing the target turned on the spot
    /// first, and a crawl did so while getting down.
    pub fn placement_facing(
        &self,
        scene: &Scene,
        k: usize,
        heading: Option<f64>,
    ) -> Result<Placement, RunError> {
        let parsed = parse_instructions(&self.instructions[k], scene).map_err(setup)?;
        let first = parsed
            .first()
            .ok_or_else(|| RunError::Setup(format!("agent {k}: no instructions")))?;
        let Source::Landmark(name) = &first.source else {
            return Err(RunError::Setup(format!(
                "agent {k}: the first instruction `{}` must say where it starts (\"from the <landmark>\")",
                first.text
            )));
        };
        let region = |n: &str| {
            scene
                .landmark(n)
                .map(|l| &l.region)
                .ok_or_else(|| RunError::Setup(format!("no landmark `{n}`")))
        };
        let [x, y] = start_spot(scene, region(name)?);
        let [tx, ty] = region(&first.target)?.center();
        let r = splitmix(&mut (self.seed ^ splitmix(&mut (k as u64))));
        let unit = (r >> 11) as f64 / (1u64 << 53) as f64;
        let yaw = heading.unwrap_or_else(|| (ty - y).atan2(tx - x))
            + (2.0 * unit - 1.0) * SEED_YAW_JITTER;
        Ok(Placement { x, y, yaw })
    }

    /// The planner settings: the spec's planner file, or the defaults.
    pub fn planner_settings(&self) -> Result<PlannerSettings, RunError> {
        match &self.params.planner {
            Some(f) => load_planner_settings(f).map_err(RunError::Setup),
            None => Ok(PlannerSettings::default()),
        }
    }

    /// Agent `k`'s planner.
    pub fn planner(&self, scene: &Scene, k: usize) -> Result<PlannerComponent, RunError> {
        self.planner_in(scene, scene, k)
    }

    /// Agent `k`'s planner, placed in `scene` and planning in `plan_scene` (the scene
    /// with more obstacles, e.g. a host's).
    pub fn planner_in(
        &self,
        scene: &Scene,
        plan_scene: &Scene,
        k: usize,
    ) -> Result<PlannerComponent, RunError> {
        let p = self.placement(scene, k)?;
        let planner = Planner::new(
            plan_scene.clone(),
            &self.instructions[k],
            [p.x, p.y],
            self.planner_settings()?,
        )
        .map_err(|e| RunError::Setup(format!("agent {k}: {e}")))?;
        Ok(PlannerComponent::new(planner, k as u32))
    }

    /// Agent `k`'s controller: the model-based policy with the spec's parameter files.
    pub fn controller(&self, scene: &Scene, k: usize) -> Result<ControllerComponent, RunError> {
        let params =
            ControllerParams::load(self.params.gait.as_deref(), self.params.crawl.as_deref())
                .map_err(setup)?;
        controller_with(scene, k, params, self.backend)
    }

    /// The physics settings: the spec's file, or the defaults.
    pub fn physics_settings(&self) -> Result<PhysicsSettings, RunError> {
        physics_settings_or_default(self.params.physics.as_deref()).map_err(RunError::Setup)
    }

    /// The physics world with every agent at its start, with the spec's settings.
    pub fn physics(&self, scene: &Scene) -> Result<PhysicsComponent, RunError> {
        self.physics_with(scene, &self.physics_settings()?)
    }

    /// The physics world with every agent at its start, with `settings` (a sweep
    /// reads its file once); each agent's plan is made here for the way it faces.
    pub fn physics_with(
        &self,
        scene: &Scene,
        settings: &PhysicsSettings,
    ) -> Result<PhysicsComponent, RunError> {
        let headings = (0..self.agents())
            .map(|k| Ok(self.planner(scene, k)?.planner().start_heading()))
            .collect::<Result<Vec<_>, RunError>>()?;
        self.physics_facing(scene, settings, &headings)
    }

    /// The physics world with every agent at its start facing `headings[k]`
    /// ([`RunSpec::placement_facing`]; from planners already made).
    pub fn physics_facing(
        &self,
        scene: &Scene,
        settings: &PhysicsSettings,
        headings: &[Option<f64>],
    ) -> Result<PhysicsComponent, RunError> {
        let placements = (0..self.agents())
            .map(|k| self.placement_facing(scene, k, headings.get(k).copied().flatten()))
            .collect::<Result<Vec<_>, _>>()?;
        if !self.backend.is_available() {
            return Err(RunError::Setup(format!(
                "physics backend `{}` is not in this build: rebuild plamo with `--features mujoco` \
                 (after scripts/install-mujoco.sh)",
                self.backend
            )));
        }
        PhysicsComponent::new(self.backend, scene, settings, &placements).map_err(setup)
    }

    /// Every component in this process.
    pub fn in_process(&self, scene: &Scene) -> Result<Links, RunError> {
        let mut planners: Vec<Box<dyn crate::lockstep::Link<_, _>>> = Vec::new();
        let mut controllers: Vec<Box<dyn crate::lockstep::Link<_, _>>> = Vec::new();
        let mut headings = Vec::new();
        for k in 0..self.agents() {
            let planner = self.planner(scene, k)?;
            headings.push(planner.planner().start_heading());
            planners.push(Box::new(InProcess::new(format!("planner-{k}"), planner)));
            controllers.push(Box::new(InProcess::new(
                format!("controller-{k}"),
                self.controller(scene, k)?,
            )));
        }
        let physics = self.physics_facing(scene, &self.physics_settings()?, &headings)?;
        Ok(Links {
            physics: Box::new(InProcess::new("physics", physics)),
            planners,
            controllers,
        })
    }

    /// What a component process was built for, as it announces itself to the
    /// orchestrator (which refuses a component started for another run): scene,
    /// backend, seed, agent count and an FNV-1a fingerprint of the instructions.
    pub fn identity(&self) -> String {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in self.instructions.join("\n").bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
        }
        let mut scene = self.scene.clone();
        if scene.len() > 300 {
            let mut cut = scene.len() - 300;
            while !scene.is_char_boundary(cut) {
                cut += 1;
            }
            scene = format!("...{}", &scene[cut..]);
        }
        let file = |f: &Option<PathBuf>| {
            f.as_ref()
                .map_or("built-in".to_string(), |p| p.display().to_string())
        };
        format!(
            "scene {scene}, physics {}, seed {}, {} agent(s), instructions #{h:016x}, gait {}, crawl {}, planner {}, physics settings {}",
            self.backend,
            self.seed,
            self.agents(),
            file(&self.params.gait),
            file(&self.params.crawl),
            file(&self.params.planner),
            file(&self.params.physics)
        )
    }

    /// The command-line arguments that give a component process this spec.
    pub fn to_args(&self) -> Vec<String> {
        let mut a = vec![
            "--scene".to_string(),
            self.scene.clone(),
            "--physics".into(),
            self.backend.to_string(),
            "--seed".into(),
            self.seed.to_string(),
        ];
        for i in &self.instructions {
            a.push("--instructions".into());
            a.push(i.clone());
        }
        for (flag, file) in [
            ("--gait-params", &self.params.gait),
            ("--crawl-params", &self.params.crawl),
            ("--planner-params", &self.params.planner),
            ("--physics-params", &self.params.physics),
        ] {
            if let Some(f) = file {
                a.push(flag.into());
                a.push(f.display().to_string());
            }
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Start landmark `a` (x 2.8..5.2) and target `b`.
    const OPEN: &str = r#"
name = "low-start"
[terrain]
size = [12.0, 8.0]
[[landmarks]]
name = "a"
region = { kind = "circle", center = [4.0, 4.0], radius = 1.2 }
[[landmarks]]
name = "b"
region = { kind = "circle", center = [10.0, 4.0], radius = 1.0 }
"#;
    /// A 1.2 m ceiling over the east half of `a` (x >= 4).
    const ROOF: &str = r#"
[[tops]]
name = "roof"
center = [5.5, 4.0]
size = [3.0, 4.0]
clearance = 1.2
thickness = 0.2
"#;

    /// The scene of `toml` and a walk from `a` to `b` in it.
    fn walk_a_to_b(toml: &str) -> (Scene, RunSpec) {
        let scene = plamo_scenes::from_toml_str(toml, "low-start").unwrap();
        let spec = RunSpec {
            scene: "low-start".into(),
            instructions: vec!["Walk from the a to the b".into()],
            backend: BackendKind::Rapier,
            seed: 0,
            params: ParamFiles::default(),
        };
        (scene, spec)
    }

    fn start(toml: &str) -> (Scene, Placement) {
        let (scene, spec) = walk_a_to_b(toml);
        let p = spec.placement(&scene, 0).unwrap();
        (scene, p)
    }

    /// A wall east of `a` from the south edge to y 6.5: the route to `b` leaves `a`
    /// northwards, and the body is put there facing that way, not towards `b`.
    #[test]
    fn a_start_faces_along_its_plan_not_at_its_target() {
        let wall = r#"
[[walls]]
name = "screen"
center = [5.6, 3.25]
size = [0.3, 6.5]
height = 1.8
"#;
        let toml = OPEN.replacen("[[landmarks]]", &format!("{wall}\n[[landmarks]]"), 1);
        let (scene, spec) = walk_a_to_b(&toml);
        let towards_b = spec.placement(&scene, 0).unwrap().yaw;
        assert!(towards_b.abs() <= SEED_YAW_JITTER, "{towards_b}");
        let heading = spec
            .planner(&scene, 0)
            .unwrap()
            .planner()
            .start_heading()
            .expect("a route with length");
        assert!(heading > 0.5, "the route sets off north-east: {heading}");
        let p = spec.placement_facing(&scene, 0, Some(heading)).unwrap();
        assert!(
            (p.yaw - heading).abs() <= SEED_YAW_JITTER,
            "{} vs {heading}",
            p.yaw
        );
        // The same jitter either way: only the direction it is added to differs.
        assert!(((p.yaw - heading) - towards_b).abs() < 1e-12);
    }

    #[test]
    fn a_start_under_a_low_top_moves_to_where_the_body_can_stand() {
        let (_, p) = start(OPEN);
        assert_eq!([p.x, p.y], [4.0, 4.0]);
        let (scene, p) = start(&format!("{OPEN}{ROOF}"));
        let region = &scene.landmark("a").unwrap().region;
        assert!(
            region.contains(p.x, p.y),
            "({}, {}) left the landmark",
            p.x,
            p.y
        );
        assert!(stands_clear(&scene, p.x, p.y), "({}, {})", p.x, p.y);
        // Near the centre: the body's 0.3 m radius west of the roof's edge at x 4,
        // within a search step.
        let d = (p.x - 4.0).hypot(p.y - 4.0);
        assert!(p.x <= 3.7 + 1e-9 && d <= 0.4 + 1e-9, "({}, {})", p.x, p.y);
    }

    #[test]
    fn a_start_on_a_tiles_edge_moves_onto_level_ground() {
        // A 0.4 m high tile whose west edge (x 4.05) runs through the landmark's
        // centre: the feet would straddle it.
        let ledge = r#"
[[terrain.tiles]]
area = { min = [4.05, 0.0], max = [12.0, 8.0] }
generator = { kind = "flat", height = 0.4 }
"#;
        let toml = OPEN.replacen("[[landmarks]]", &format!("{ledge}\n[[landmarks]]"), 1);
        let (scene, p) = start(&toml);
        assert!(
            !level_start(&scene, 4.0, 4.0),
            "the centre straddles the edge"
        );
        assert!(level_start(&scene, p.x, p.y), "({}, {})", p.x, p.y);
        assert!(scene.landmark("a").unwrap().region.contains(p.x, p.y));
        // Off the edge by the footprint and at most a search step more.
        let off = (p.x - 4.05).abs();
        assert!((0.3..=0.5).contains(&off), "({}, {})", p.x, p.y);
        // Flat ground: the centre, as before.
        let (flat, q) = start(OPEN);
        assert!(level_start(&flat, 4.0, 4.0));
        assert_eq!([q.x, q.y], [4.0, 4.0]);
    }
}
