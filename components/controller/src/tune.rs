//! Offline "training" of the model-based gait: separable CMA-ES over one form's
//! parameters (the biped's walk, run or crouch-walk section of `gait.toml`, or the
//! crawl's `crawl.toml`), minimising tracking error + residual + falls over randomised
//! constant-speed straight paths. Deterministic per seed (rollouts are deterministic,
//! candidates are drawn from a seeded generator, rayon results are collected in order).

mod cmaes;
mod search_box;

use rayon::prelude::*;

use plamo_physics::{BackendKind, PhysicsError, PhysicsSettings};

pub use cmaes::{Rng, Sample, SepCmaEs};
pub use search_box::{SearchField, search_box, start_like};
use search_box::{decode, encode};

use crate::error::{ControllerError, Result};
use crate::gait::{CrawlParams, GaitParams, ModelBasedController};
use crate::rollout::{
    ArcPath, DropPath, HeadPath, RampedPath, RisingPath, START_ACCEL, StraightPath, TurnPath,
    ceiling_scene, flat_scene, run_path_with,
};
use crate::settings::ControllerSettings;

/// The locomotion form whose parameters are tuned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Form {
    /// Walk (head 1.47 m).
    Walk,
    /// Run (head 1.47 m).
    Run,
    /// Crouch-walk (head 0.8 m).
    Crouch,
    /// Crawl on forearms and knees (head ~0.4 m; `crawl.toml`). Its rollouts start
    /// standing, so the get-down is part of every one.
    Crawl,
}

impl std::str::FromStr for Form {
    type Err = ControllerError;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "walk" => Ok(Form::Walk),
            "run" => Ok(Form::Run),
            "crouch" => Ok(Form::Crouch),
            "crawl" => Ok(Form::Crawl),
            _ => Err(ControllerError::InvalidSettings {
                field: "form",
                reason: format!("unknown form `{s}` (walk, run, crouch, crawl)"),
            }),
        }
    }
}

impl Form {
    /// Requested head height \[m\] and speed range \[m/s\] the form is tuned over.
    pub fn task(self) -> (f64, [f64; 2]) {
        match self {
            Form::Walk => (1.47, [1.0, 2.0]),
            Form::Run => (1.47, [2.5, 4.0]),
            Form::Crouch => (0.8, [0.6, 2.0]),
            // The paper's crawl is 1 m/s; slower crawls are what a plan asks for in
            // tight spots.
            Form::Crawl => (0.4, [0.4, 1.0]),
        }
    }

    /// Weight of the head Z error in the cost \[-\]: the crouch's point is its low
    /// head (an earlier search kept the head 0.25 m high to avoid falls).
    pub fn z_weight(self) -> f64 {
        match self {
            Form::Crouch => 3.0,
            Form::Walk | Form::Run | Form::Crawl => 1.0,
        }
    }

    /// Cost of a fall \[m-equivalent\]: more than the XY error a reset onto the plan
    /// saves. The run's XY error is metres (the start from rest leaves it behind), so
    /// at 1 m a search trades falls for lag; a fall ends a run in a route.
    /// The crawl's too: a crawler that falls must get up and down again, which costs
    /// seconds.
    pub fn fall_cost(self) -> f64 {
        match self {
            Form::Run | Form::Crawl => 3.0,
            Form::Walk | Form::Crouch => 1.0,
        }
    }
}

/// What a tuning run starts from and returns: the controller's two parameter files,
/// the biped's and the crawl's (a form's search moves only its own fields).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TunedParams {
    /// Walk, run and crouch-walk (`gait.toml`).
    pub gait: GaitParams,
    /// The crawl (`crawl.toml`).
    pub crawl: CrawlParams,
}

impl Default for TunedParams {
    /// The built-in files.
    fn default() -> Self {
        Self {
            gait: GaitParams::default(),
            crawl: CrawlParams::default(),
        }
    }
}

impl TunedParams {
    fn validate(&self) -> Result<()> {
        self.gait.validate()?;
        self.crawl.validate()
    }

    /// The file `form`'s search changed, as TOML with a header naming the command
    /// that made it: `crawl.toml` for the crawl, `gait.toml` otherwise.
    pub fn to_toml(&self, form: Form, header: &str) -> Result<String> {
        match form {
            Form::Crawl => with_header(
                &self.crawl,
                header,
                "Units: see the `CrawlParams` docs (m, s, rad, N m/rad).",
            ),
            _ => to_toml(&self.gait, header),
        }
    }
}

/// Tuning settings.
#[derive(Debug, Clone)]
pub struct TuneSettings {
    /// Form to tune.
    pub form: Form,
    /// Generations of CMA-ES.
    pub generations: u32,
    /// Seed of the candidate and scenario draws.
    pub seed: u64,
    /// Physics engines every candidate is rolled out in.
    pub backends: Vec<BackendKind>,
    /// Rollouts per candidate and backend (speeds stratified over the form's range).
    pub rollouts: usize,
    /// Simulated seconds per rollout \[s\].
    pub duration: f64,
    /// Initial step size in the normalised \[0, 1\] box \[-\].
    pub sigma0: f64,
    /// Controller settings (residual caps) used in the rollouts.
    pub controller: ControllerSettings,
    /// Physics settings of every rollout (friction, solver, contacts; the defaults
    /// unless a study tunes under others).
    pub physics: PhysicsSettings,
    /// Ground of the rollouts, assigned round-robin: `flat`, `ceiling` (flat under a
    /// 0.6 m ceiling, for the crawl), `arc` (a turn on flat ground, left and right
    /// alternately; its cost counts the heading too), `drop` (flat: a walk at the
    /// rollout's speed that drops to the form's head height at [`DROP_AT`]), `rise`
    /// (flat: the form from the start, standing up at half the rollout), `turnback`
    /// (flat: a stop after 3 m and back at [`TURN_BACK`], left and right alternately),
    /// `hill` (a straight path across two hills' flanks) or a built-in terrain strip
    /// without its `terrain-` prefix (`slope`, `rough`, `stairs`; the strips of `plamo
    /// eval locomotion`).
    pub terrains: Vec<String>,
    /// Cost of a fall per rollout \[m-equivalent\]; `None` takes the form's own
    /// (3 for the run and the crawl, 1 for the walk and the crouch). The Table 2
    /// strips ask for no falls at all: a search there may weigh them up.
    pub fall_cost: Option<f64>,
    /// Fields added to the form's built-in search box, or re-bounding one of its
    /// fields ([`search_box()`]); empty: the box the built-in files were made with.
    pub search: Vec<SearchField>,
}

/// Cost of a rollout whose simulation diverged \[m-equivalent\]: ten of the costliest
/// falls.
const DIVERGED_COST: f64 = 30.0;

/// Turn radius of the `arc` rollouts, left and right alternately \[m\].
const ARC_RADIUS: f64 = 4.0;

/// Cost per unit of the paper's direction reward missed on an `arc` rollout
/// \[m-equivalent\]: a body can follow a turning path sideways, so its XY error alone
/// does not see a lost heading.
const ARC_HEADING_COST: f64 = 2.0;

/// Cost per unit of mean residual force (fraction of m*g) \[m-equivalent\]: 0.1 m*g
/// weighs as 0.2 m of XY error, so the search prefers a gait that propels itself.
pub const RESIDUAL_COST: f64 = 2.0;

/// Cost of one parameter set: mean over rollouts of
/// `xy_err + w_z * z_err + RESIDUAL_COST * residual_force_mean + w_fall * falls`
/// (metres, fraction of m*g, count; `w_z` 3 for the crouch, else 1; `w_fall` 3 for the
/// run, else 1).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Cost {
    /// Total cost \[-\].
    pub total: f64,
    /// Mean falls per rollout.
    pub falls: f64,
    /// Mean head XY error \[m\].
    pub xy: f64,
    /// Mean head Z error \[m\].
    pub z: f64,
    /// Mean residual force, fraction of m*g.
    pub residual: f64,
    /// Mean head XY error of a [`TrackingGuard`]'s flat rollouts \[m\]; 0 without one.
    pub tracking: f64,
}

/// Progress after one generation.
#[derive(Debug, Clone)]
pub struct Generation {
    /// Generation number, from 1.
    pub index: u32,
    /// Best cost so far.
    pub best: Cost,
    /// The parameters of `best`.
    pub best_params: TunedParams,
    /// Whether this generation found `best` (a caller that checkpoints writes then).
    pub improved: bool,
    /// Step size now.
    pub sigma: f64,
}

/// The ground named `name` and where a rollout starts on it: a flat plane, the flat
/// plane with the crawl bench's 0.6 m ceiling (`ceiling`, [`ceiling_scene`]), or a
/// built-in terrain strip (x 5 -> 35 m), started where `plamo eval locomotion` starts.
pub fn terrain_scene(name: &str) -> Result<(plamo_scenes::Scene, [f64; 2])> {
    match name {
        "flat" => return Ok((flat_scene(60.0), [0.0, 0.0])),
        "ceiling" => return Ok((ceiling_scene(60.0), [0.0, 0.0])),
        "hill" => {
            let scene = plamo_scenes::from_toml_str(HILL_SCENE, "tune-hill (built-in)")
                .expect("the built-in hill ground is valid");
            return Ok((scene, [2.0, 5.0]));
        }
        _ => {}
    }
    let scene = plamo_scenes::builtin(&format!("terrain-{name}")).map_err(|e| {
        ControllerError::InvalidSettings {
            field: "terrains",
            reason: format!("unknown terrain `{name}` ({GROUNDS}): {e}"),
        }
    })?;
    Ok((scene, [5.0, 3.0]))
}

/// The `hill` ground: two cosine hills 0.8 m high and 3.5 m in radius (a random
/// tour's hill tiles are 0.2-1 m by 2.5-4.5 m), 1.5 m left then 1.5 m right of a
/// straight path along y = 5 m from x = 2 m, so the path crosses their flanks at up
/// to ~19 degrees, mostly across it: the slope a tour's crawl meets side-on, which
/// the strips (up and down an 8 degree ridge) do not have.
const HILL_SCENE: &str = r#"
name = "tune-hill"
description = "tuning ground: a straight path across the flanks of two cosine hills"

[terrain]
size = [40.0, 10.0]

[[terrain.tiles]]
generator = { kind = "hill", center = [6.0, 6.5], radius = 3.5, height = 0.8, profile = "cosine" }

[[terrain.tiles]]
generator = { kind = "hill", center = [13.0, 3.5], radius = 3.5, height = 0.8, profile = "cosine" }

[[landmarks]]
name = "start"
region = { kind = "circle", center = [2.0, 5.0], radius = 0.75 }

[[landmarks]]
name = "goal"
region = { kind = "circle", center = [30.0, 5.0], radius = 0.75 }
"#;

/// Every ground name [`TuneSettings::terrains`] takes, for error messages.
const GROUNDS: &str = "flat, slope, rough, stairs, ceiling, hill, arc, drop, rise, turnback";

/// Evaluates `params` on the scenarios drawn for `seed` (same seed, same scenarios).
pub fn evaluate(params: &TunedParams, s: &TuneSettings, seed: u64) -> Result<Cost> {
    evaluate_on(&grounds(s)?, params, s, seed)
}

/// When a `drop` rollout's plan leaves the walk for the form's head height \[s\]:
/// the walk from rest has reached its speed (1 m/s^2 up to at most 2 m/s).
pub const DROP_AT: f64 = 3.0;

/// The shape of a rollout's plan on its ground.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Course {
    /// Straight from rest at the form's head height ([`RampedPath`]).
    Straight,
    /// A 4 m turn, left and right alternately ([`ArcPath`]).
    Arc,
    /// A walk that drops to the form ([`DropPath`]): a tour's form change.
    Drop,
    /// The form, then standing up at half the rollout ([`RisingPath`]).
    Rise,
    /// A stop at a corner and back the other way ([`TurnPath`], [`TURN_BACK`]): a
    /// tour's landmark.
    TurnBack,
}

/// Turn at a `turnback` rollout's corner, left and right alternately \[rad\]: most
/// legs of the random tours turn back at their landmark by 2-3 rad.
pub const TURN_BACK: f64 = 2.6;

/// Length of a `turnback` rollout's first leg \[m\].
const TURN_BACK_FIRST: f64 = 3.0;

/// One rollout ground: the scene, where the plan starts, and the plan's shape.
type Ground = (plamo_scenes::Scene, [f64; 2], Course);

/// The rollouts' grounds for `s.terrains`: built once per search, not per candidate
/// (a terrain strip is generated from its scene file).
fn grounds(s: &TuneSettings) -> Result<Vec<Ground>> {
    // `arc` turns on flat ground (a crawl tuned on straight paths alone lost its
    // heading control); `drop` and `rise` change form and `turnback` stops and turns
    // back on flat ground, as a tour's legs do; every other name is a ground for a
    // straight path.
    let flat = |course| Ok((flat_scene(60.0), [0.0, 0.0], course));
    let grounds = s
        .terrains
        .iter()
        .map(|t| match t.as_str() {
            "arc" => flat(Course::Arc),
            "drop" => flat(Course::Drop),
            "rise" => flat(Course::Rise),
            "turnback" => flat(Course::TurnBack),
            _ => terrain_scene(t).map(|(scene, start)| (scene, start, Course::Straight)),
        })
        .collect::<Result<Vec<_>>>()?;
    if grounds.is_empty() {
        return Err(ControllerError::InvalidSettings {
            field: "terrains",
            reason: format!("no terrain to tune on ({GROUNDS})"),
        });
    }
    Ok(grounds)
}

/// [`evaluate`] on grounds already built by [`grounds`].
fn evaluate_on(
    grounds: &[Ground],
    params: &TunedParams,
    s: &TuneSettings,
    seed: u64,
) -> Result<Cost> {
    let (head, [lo, hi]) = s.form.task();
    let mut rng = Rng::new(seed);
    let jobs: Vec<(BackendKind, f64)> = s
        .backends
        .iter()
        .flat_map(|&b| (0..s.rollouts).map(move |i| (b, i)))
        .map(|(b, i)| {
            // Stratified speeds over the range, each jittered within its stratum.
            let k = s.rollouts.max(1) as f64;
            (b, lo + (hi - lo) * (i as f64 + rng.uniform()) / k)
        })
        .collect();
    let results: Vec<Result<Cost>> = jobs
        .par_iter()
        .enumerate()
        .map(|(k, &(backend, speed))| {
            let mut policy = ModelBasedController::with_all_params(
                params.gait,
                params.crawl,
                s.controller.clone(),
            )?;
            let (scene, start, course) = &grounds[(k % s.rollouts.max(1)) % grounds.len()];
            let (start, arc) = (*start, *course == Course::Arc);
            let line = StraightPath {
                start,
                speed,
                head_height: head,
            };
            let path: Box<dyn HeadPath> = match course {
                Course::Arc => Box::new(ArcPath {
                    start,
                    speed,
                    head_height: head,
                    straight: 2.0,
                    radius: if k % 2 == 0 { ARC_RADIUS } else { -ARC_RADIUS },
                }),
                Course::Straight => Box::new(RampedPath {
                    line,
                    accel: START_ACCEL,
                }),
                Course::Drop => Box::new(DropPath {
                    start,
                    walk_speed: speed.min(2.0),
                    crawl_speed: speed,
                    head_height: head,
                    drop_at: DROP_AT,
                }),
                Course::Rise => Box::new(RisingPath {
                    line,
                    up_at: 0.5 * s.duration,
                }),
                Course::TurnBack => Box::new(TurnPath {
                    start,
                    speed,
                    corner_speed: 0.0,
                    head_height: head,
                    first: TURN_BACK_FIRST,
                    turn: if k % 2 == 0 { TURN_BACK } else { -TURN_BACK },
                    accel: 1.0,
                }),
            };
            let m = match run_path_with(
                backend,
                &s.physics,
                scene,
                path.as_ref(),
                s.duration,
                &mut policy,
                &s.controller,
            ) {
                Ok(m) => m,
                // Gains that blow the simulation up make a bad candidate, not a failed
                // search (a crawl tuned in MuJoCo alone spun rapier's body past 100 rad/s).
                Err(ControllerError::Physics(PhysicsError::Diverged { .. })) => {
                    return Ok(Cost {
                        total: DIVERGED_COST,
                        falls: 1.0,
                        ..Default::default()
                    });
                }
                Err(e) => return Err(e),
            };
            let falls = f64::from(m.falls);
            let heading = if arc {
                ARC_HEADING_COST * (1.0 - m.mean_reward.dir)
            } else {
                0.0
            };
            Ok(Cost {
                total: m.xy_err_mean
                    + s.form.z_weight() * m.z_err_mean
                    + RESIDUAL_COST * m.residual_force_mean
                    + s.fall_cost.unwrap_or(s.form.fall_cost()) * falls
                    + heading,
                falls,
                xy: m.xy_err_mean,
                z: m.z_err_mean,
                residual: m.residual_force_mean,
                tracking: 0.0,
            })
        })
        .collect();
    let mut sum = Cost::default();
    for r in &results {
        let c = r.as_ref().map_err(|e| ControllerError::InvalidSettings {
            field: "rollout",
            reason: e.to_string(),
        })?;
        sum.total += c.total;
        sum.falls += c.falls;
        sum.xy += c.xy;
        sum.z += c.z;
        sum.residual += c.residual;
    }
    let k = results.len().max(1) as f64;
    Ok(Cost {
        total: sum.total / k,
        falls: sum.falls / k,
        xy: sum.xy / k,
        z: sum.z / k,
        residual: sum.residual / k,
        tracking: 0.0,
    })
}

/// Cost per metre of flat-ground XY error a candidate loses against the search's start
/// beyond a [`TrackingGuard`]'s margin \[m-equivalent per m\]: 0.1 m more lag costs
/// as much as one tour in ten failing at a fall cost of 10.
pub const TRACKING_COST: f64 = 10.0;

/// Rollouts per engine of a [`TrackingGuard`]: a straight path and a 4 m turn at two
/// speeds each, stratified over the form's range.
const TRACKING_ROLLOUTS: usize = 4;

/// Simulated seconds of a [`TrackingGuard`]'s rollouts \[s\].
const TRACKING_DURATION: f64 = 12.0;

/// Keeps a search priced on something else (whole tours) from buying it with how
/// closely the form follows its plan: a crawl tuned on the tours alone fell half as
/// often and lagged 0.3 m behind a 0.5 m/s plan on flat ground instead of 0.17-0.2 m
/// (RESULTS.md, "Crawl", session 28). A candidate pays [`TRACKING_COST`] per metre its
/// mean XY error on flat rollouts (straight and `arc`, from standing, the form's
/// speeds) exceeds the start's by more than `margin`.
pub struct TrackingGuard {
    settings: TuneSettings,
    grounds: Vec<Ground>,
    start_xy: f64,
    margin: f64,
}

impl TrackingGuard {
    /// The guard for a search from `base` in the engines, physics and controller
    /// settings of `s`; the rollouts' speeds are drawn once from `s.seed`.
    pub fn new(base: &TunedParams, s: &TuneSettings, margin: f64) -> Result<Self> {
        if !(margin.is_finite() && margin >= 0.0) {
            return Err(ControllerError::InvalidSettings {
                field: "keep_tracking",
                reason: format!("the margin must be a finite number >= 0 m, got {margin}"),
            });
        }
        let settings = TuneSettings {
            rollouts: TRACKING_ROLLOUTS,
            duration: TRACKING_DURATION,
            terrains: vec!["flat".into(), "arc".into()],
            fall_cost: None,
            ..s.clone()
        };
        let grounds = grounds(&settings)?;
        let start_xy = evaluate_on(&grounds, base, &settings, settings.seed)?.xy;
        Ok(Self {
            settings,
            grounds,
            start_xy,
            margin,
        })
    }

    /// The start's mean XY error on the guard's rollouts \[m\].
    pub fn start_xy(&self) -> f64 {
        self.start_xy
    }

    /// `params`' mean XY error on the guard's rollouts \[m\] and what it pays for it
    /// \[m-equivalent\].
    pub fn price(&self, params: &TunedParams) -> Result<(f64, f64)> {
        let xy = evaluate_on(&self.grounds, params, &self.settings, self.settings.seed)?.xy;
        let over = (xy - self.start_xy - self.margin).max(0.0);
        Ok((xy, TRACKING_COST * over))
    }
}

/// Runs CMA-ES from `base`; returns the best parameters found and their cost. The
/// scenarios (stratified, jittered speeds over the form's range) are drawn once from
/// the seed, so the objective is deterministic and the best is monotone.
pub fn tune(
    base: &TunedParams,
    s: &TuneSettings,
    on_generation: impl FnMut(&Generation),
) -> Result<(TunedParams, Cost)> {
    let grounds = grounds(s)?;
    tune_with(
        base,
        s,
        |p| evaluate_on(&grounds, p, s, s.seed),
        on_generation,
    )
}

/// [`tune`] on another objective: `cost` prices a candidate (e.g. by whole tours
/// through the planner and orchestrator, which this crate does not know). The search
/// (form, generations, seed, step size) is `s`'s; its rollout fields are `cost`'s
/// business. `cost` must be deterministic for the search to be.
pub fn tune_with(
    base: &TunedParams,
    s: &TuneSettings,
    cost: impl Fn(&TunedParams) -> Result<Cost> + Sync,
    mut on_generation: impl FnMut(&Generation),
) -> Result<(TunedParams, Cost)> {
    let fields = search_box(s.form, &s.search)?;
    let mut rng = Rng::new(s.seed);
    let mut es = SepCmaEs::new(encode(base, s.form, &fields)?, s.sigma0, 0);
    let mut best = (*base, cost(base)?);
    for g in 1..=s.generations {
        let samples = es.ask(&mut rng);
        // The whole generation at once: a candidate's rollouts alone leave most cores
        // idle behind its slowest one (a rapier rollout). Collected in order, so the
        // search is the same on any number of cores.
        let evaluated: Vec<Result<(TunedParams, Cost)>> = samples
            .par_iter()
            .map(|smp| {
                let p = decode(base, s.form, &fields, &smp.x)?;
                let c = match p.validate() {
                    Ok(()) => cost(&p)?,
                    Err(_) => Cost {
                        total: 1e3,
                        ..Default::default()
                    },
                };
                Ok((p, c))
            })
            .collect();
        let mut costs = Vec::with_capacity(samples.len());
        let mut gen_best: Option<(TunedParams, Cost)> = None;
        for (smp, evaluated) in samples.iter().zip(evaluated) {
            let (p, c) = evaluated?;
            // Out-of-box candidates are clamped and pay for the distance.
            let outside: f64 = smp.x.iter().map(|v| (v - v.clamp(0.0, 1.0)).powi(2)).sum();
            costs.push(c.total + outside);
            if gen_best.as_ref().is_none_or(|(_, b)| c.total < b.total) {
                gen_best = Some((p, c));
            }
        }
        es.tell(&samples, &costs);
        let improved = gen_best.is_some_and(|(_, c)| c.total < best.1.total);
        if let (true, Some(b)) = (improved, gen_best) {
            best = b;
        }
        on_generation(&Generation {
            index: g,
            best: best.1,
            best_params: best.0,
            improved,
            sigma: es.sigma,
        });
    }
    // The objective is deterministic: the best's cost is its final score (pricing it
    // again, a whole generation's work with tours, would give the same number).
    Ok(best)
}

/// The parameters as a TOML file with a header naming the command that made them.
pub fn to_toml(params: &GaitParams, header: &str) -> Result<String> {
    with_header(
        params,
        header,
        "Units: see `FormParams`/`ResidualGains` docs (m, s, rad, N m/rad).",
    )
}

/// `params` as TOML after `header` and `units` as comment lines.
fn with_header<T: serde::Serialize>(params: &T, header: &str, units: &str) -> Result<String> {
    let body = toml::to_string(params).map_err(|e| ControllerError::InvalidSettings {
        field: "params",
        reason: e.to_string(),
    })?;
    let mut out = String::new();
    for line in header.lines() {
        out.push_str("# ");
        out.push_str(line);
        out.push('\n');
    }
    out.push_str("# ");
    out.push_str(units);
    out.push('\n');
    out.push_str(&body);
    Ok(out)
}
