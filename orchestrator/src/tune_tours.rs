//! The random tours of `plamo eval random` as `plamo tune`'s objective (`--tours N`):
//! a candidate's cost is what its whole tours do, through the planner and the
//! orchestrator, instead of what short rollouts on one ground do. Searches on
//! rollouts lowered their cost while the tours lost: a crawl rollout of 8-12 s almost
//! never falls where a tour's crawl leg, after a get-down, around a corner, along a
//! stair's side, falls in one tour of five (RESULTS.md, "Crawl").

use plamo_controller::{ControllerError, Cost, Form, RESIDUAL_COST, TrackingGuard, TunedParams};
use plamo_physics::{BackendKind, PhysicsSettings};
use plamo_planner::{Locomotion, PlannerSettings};
use plamo_scenes::Scene;
use rayon::prelude::*;

use crate::eval::episode::{EpisodeSpec, plan, run_episode, verb};
use crate::eval::random::{FORMS, tour};
use crate::spec::ControllerParams;

/// Where `--tour-seed` starts by default: far past the seeds `plamo eval random`
/// reports (0-3199 in RESULTS.md), so a search does not tune on its own test set.
pub const DEFAULT_TOUR_SEED: u64 = 100_000;

/// How many scene seeds past the first a tour set may look through for tours with the
/// form in them, per tour asked for: with all four forms drawn for three legs, 58% of
/// tours have a crawl leg.
const SEEDS_PER_TOUR: u64 = 20;

/// A fixed set of random tours, each with a leg in the tuned form.
pub struct TourObjective {
    form: Form,
    backends: Vec<BackendKind>,
    physics: PhysicsSettings,
    fall_cost: f64,
    tours: Vec<(Scene, u64, String)>,
    guard: Option<TrackingGuard>,
}

impl TourObjective {
    /// The first `n` random tours from scene seed `seed` on that have a leg in `form`
    /// and a plan at their start, run in every engine of `backends` under `physics`; a
    /// failed tour costs `fall_cost` (`None`: the form's own).
    pub fn new(
        form: Form,
        n: usize,
        seed: u64,
        backends: Vec<BackendKind>,
        physics: PhysicsSettings,
        fall_cost: Option<f64>,
    ) -> anyhow::Result<Self> {
        anyhow::ensure!(n > 0, "--tours must be at least 1");
        anyhow::ensure!(
            !backends.is_empty(),
            "no physics engine to run the tours in"
        );
        let mut tours = Vec::with_capacity(n);
        let last = seed.saturating_add(SEEDS_PER_TOUR.saturating_mul(n as u64));
        let mut s = seed;
        while tours.len() < n && s < last {
            let scene = plamo_scenes::random_scene(s);
            let text = tour(&scene, s, &FORMS[..])?;
            if has_leg(&text, form)
                && plan(&tour_spec(&scene, s, &text, backends[0], &physics, None)).is_ok()
            {
                tours.push((scene, s, text));
            }
            s += 1;
        }
        anyhow::ensure!(
            tours.len() == n,
            "only {} of {n} tours from scene seed {seed} have a `{}` leg and a plan",
            tours.len(),
            form_verb(form)
        );
        Ok(Self {
            form,
            backends,
            physics,
            fall_cost: fall_cost.unwrap_or(form.fall_cost()),
            tours,
            guard: None,
        })
    }

    /// The same tours, with `guard`'s price for lost tracking added to every cost.
    pub fn with_guard(mut self, guard: TrackingGuard) -> Self {
        self.guard = Some(guard);
        self
    }

    /// The guard added by [`Self::with_guard`], if any.
    pub fn guard(&self) -> Option<&TrackingGuard> {
        self.guard.as_ref()
    }

    /// The scene seed after the last tour's: where a held-out set of tours starts.
    pub fn next_seed(&self) -> u64 {
        self.tours.last().map_or(0, |(_, s, _)| s + 1)
    }

    /// The tours' instructions, in order, with their scene seeds.
    pub fn tours(&self) -> impl Iterator<Item = (u64, &str)> {
        self.tours.iter().map(|(_, s, t)| (*s, t.as_str()))
    }

    /// The cost of `params` over every tour in every engine: `fall_cost` times the
    /// share of tours not finished (a fall, a collision, a timeout) + the head's mean
    /// XY error + the form's weight times its mean Z error + [`RESIDUAL_COST`] times
    /// the mean residual force (fraction of m*g), as a rollout's cost has it: a first
    /// search without it bought its crawl's fewer falls with 0.17 m*g of residual
    /// force instead of 0.12. `falls` is the share of tours with a fall. With a
    /// [`TrackingGuard`] its price is added and `tracking` is its XY error.
    pub fn cost(&self, params: &TunedParams) -> plamo_controller::Result<Cost> {
        // Only the searched file moves; the other stays each engine's built-in one (a
        // crawl search in rapier keeps `gait-rapier.toml` under its tours).
        let controller = if self.form == Form::Crawl {
            ControllerParams {
                gait: None,
                crawl: Some(params.crawl),
            }
        } else {
            ControllerParams {
                gait: Some(params.gait),
                crawl: None,
            }
        };
        let jobs: Vec<(BackendKind, usize)> = self
            .backends
            .iter()
            .flat_map(|&b| (0..self.tours.len()).map(move |i| (b, i)))
            .collect();
        let episodes: Vec<_> = jobs
            .par_iter()
            .map(|&(b, i)| {
                let (scene, seed, text) = &self.tours[i];
                run_episode(&tour_spec(
                    scene,
                    *seed,
                    text,
                    b,
                    &self.physics,
                    Some(controller),
                ))
            })
            .collect();
        let mut c = Cost::default();
        for ep in episodes {
            let ep = ep.map_err(|e| ControllerError::InvalidSettings {
                field: "tour",
                reason: e.to_string(),
            })?;
            c.total += self.fall_cost * f64::from(u8::from(!ep.success()))
                + ep.xy_err
                + self.form.z_weight() * ep.z_err
                + RESIDUAL_COST * ep.residual_force;
            c.falls += f64::from(u8::from(ep.falls > 0));
            c.xy += ep.xy_err;
            c.z += ep.z_err;
            c.residual += ep.residual_force;
        }
        let k = jobs.len().max(1) as f64;
        c.total /= k;
        c.falls /= k;
        c.xy /= k;
        c.z /= k;
        c.residual /= k;
        if let Some(g) = &self.guard {
            let (xy, price) = g.price(params)?;
            c.total += price;
            c.tracking = xy;
        }
        Ok(c)
    }
}

/// The instruction verb of `form` (as the experiments write it: "crouch-walk").
fn form_verb(form: Form) -> &'static str {
    verb(match form {
        Form::Crawl => Locomotion::Crawl,
        Form::Crouch => Locomotion::CrouchWalk,
        Form::Walk => Locomotion::Walk,
        Form::Run => Locomotion::Run,
    })
}

/// Whether tour `text` has a leg in `form`: its verb as a word, so a crouch-walk is
/// not a walk.
fn has_leg(text: &str, form: Form) -> bool {
    text.split(|c: char| !(c.is_alphanumeric() || c == '-'))
        .any(|w| w.eq_ignore_ascii_case(form_verb(form)))
}

/// A tour as `plamo eval random` runs it (its seeds, default planner and physics).
fn tour_spec<'a>(
    scene: &'a Scene,
    seed: u64,
    text: &str,
    backend: BackendKind,
    physics: &PhysicsSettings,
    controller: Option<ControllerParams>,
) -> EpisodeSpec<'a> {
    EpisodeSpec {
        scene,
        instructions: text.to_string(),
        backend,
        seed,
        planner: PlannerSettings::default(),
        controller: controller.unwrap_or_default(),
        physics_settings: physics.clone(),
        max_seconds: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(text: &str) -> Vec<String> {
        text.split(|c: char| !(c.is_alphanumeric() || c == '-'))
            .map(str::to_lowercase)
            .collect()
    }

    /// Every tour has a leg in the form, by its verb: a crouch-walk is not a walk.
    #[test]
    fn every_tour_has_a_leg_in_the_form() {
        for form in [Form::Crawl, Form::Walk, Form::Crouch, Form::Run] {
            let t = TourObjective::new(
                form,
                6,
                DEFAULT_TOUR_SEED,
                vec![BackendKind::Rapier],
                PhysicsSettings::default(),
                None,
            )
            .unwrap();
            let tours: Vec<_> = t.tours().collect();
            assert_eq!(tours.len(), 6);
            for (seed, text) in &tours {
                assert!(*seed >= DEFAULT_TOUR_SEED);
                assert!(
                    words(text).contains(&form_verb(form).to_string()),
                    "{form:?}: {text}"
                );
                // Drawn as `plamo eval random` draws it.
                let scene = plamo_scenes::random_scene(*seed);
                assert_eq!(*text, tour(&scene, *seed, &FORMS[..]).unwrap());
            }
            // Seeds increase: the first tours with the form, in order.
            assert!(tours.windows(2).all(|w| w[0].0 < w[1].0));
        }
        // Some walk-free tours have a crouch-walk: the verb is a word, not a substring.
        let walk: Vec<u64> = TourObjective::new(
            Form::Walk,
            20,
            DEFAULT_TOUR_SEED,
            vec![BackendKind::Rapier],
            PhysicsSettings::default(),
            None,
        )
        .unwrap()
        .tours()
        .map(|(s, _)| s)
        .collect();
        let skipped_crouch = (DEFAULT_TOUR_SEED..*walk.last().unwrap())
            .filter(|s| !walk.contains(s))
            .any(|s| {
                let text = tour(&plamo_scenes::random_scene(s), s, &FORMS[..]).unwrap();
                words(&text).contains(&"crouch-walk".to_string())
            });
        assert!(
            skipped_crouch,
            "no walk-free tour with a crouch-walk was skipped"
        );
    }

    #[test]
    fn no_tours_or_no_engine_is_an_error() {
        let e = |n, b: Vec<BackendKind>| {
            TourObjective::new(Form::Crawl, n, 0, b, PhysicsSettings::default(), None)
                .err()
                .unwrap()
                .to_string()
        };
        assert!(e(0, vec![BackendKind::Rapier]).contains("--tours"));
        assert!(e(1, vec![]).contains("engine"));
    }

    /// The cost is deterministic and moves with the searched file.
    #[cfg(feature = "mujoco")]
    #[test]
    fn the_cost_is_the_tours_and_moves_with_the_crawl() {
        let t = TourObjective::new(
            Form::Crawl,
            2,
            DEFAULT_TOUR_SEED,
            vec![BackendKind::Mujoco],
            PhysicsSettings::default(),
            Some(5.0),
        )
        .unwrap();
        let base = TunedParams::default();
        let a = t.cost(&base).unwrap();
        let b = t.cost(&base).unwrap();
        assert_eq!(a.total.to_bits(), b.total.to_bits());
        assert!(a.xy > 0.0 && a.z > 0.0 && a.residual > 0.0);
        // The share of failed tours times the fall cost is in the total.
        assert!(a.total >= a.xy + a.z + RESIDUAL_COST * a.residual - 1e-12);
        let mut slow = base;
        slow.crawl.max_speed *= 0.5;
        let c = t.cost(&slow).unwrap();
        assert!(c.total != a.total, "a crawl at half speed priced the same");
    }
}
