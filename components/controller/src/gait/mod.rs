//! The model-based tracking controller, the default policy (no network needed).
//!
//! One gait per family of forms, chosen by the requested head height and speed:
//! [`biped`] walks, runs and crouch-walks (its parameters blended continuously);
//! [`crawl`] goes down on hands and knees when the plan's head height drops below
//! [`CrawlParams::crawl_below`] and stands up again above
//! [`CrawlParams::stand_above`] (hysteresis), or for a crouch-walk above
//! [`CrawlParams::crouch_stand_above`] that the plan keeps for 5 s, handing the biped
//! a reset state.

mod biped;
mod crawl;
mod ik;
mod map_plane;
mod params;
mod plan_ground;
mod plan_trace;

pub use crawl::{CRAWL_PARAMS_VERSION, CrawlParams, DEFAULT_CRAWL_PARAMS, HAND_CRAWL_PARAMS};
pub use ik::{LegGeometry, leg_fk, leg_ik};
pub use params::{DEFAULT_GAIT_PARAMS, FormParams, GAIT_PARAMS_VERSION, GaitParams, ResidualGains};

use plamo_physics::{FEET, NUM_BODIES, NUM_JOINTS};

use crate::error::{ControllerError, Result};
use crate::math::{clamp_norm, from_heading_frame};
use crate::observation::{NUM_WAYPOINTS, Observation, ObservationLayout, WAYPOINT_SPACING};
use crate::policy::{Action, Policy, RootWrench};
use crate::settings::{ControllerSettings, GRAVITY};
use biped::BipedGait;
use crawl::CrawlGait;

/// How far a crawler may lag behind its plan and still stand up when the plan rises
/// \[m\], unless the way up is clear ([`STAND_HEADROOM`]): a plan that ran ahead of a
/// slow crawl may rise past a low ceiling the body is still under.
const MAX_STAND_LAG: f64 = 0.6;

/// Free height above the plan's requested head height (the planner's `head_margin`)
/// that lets a crawler stand up however far its plan has run ahead \[m\]. The lag guard
/// ([`MAX_STAND_LAG`]) is for a body still under a low top; with no top within
/// [`crate::observation::HEADROOM_REACH`] of the root, a crawler that lagged kept
/// crawling on the open ground of a walk leg until a replan brought the plan back, and
/// fell there (MuJoCo random tours, seeds 0-999: 7 of the 71 tours lost to a fall).
const STAND_HEADROOM: f64 = 0.1;

/// Distance from the head to the plan's first waypoint beyond what the plan's own
/// speed puts there \[m\].
fn plan_lead(obs: &Observation) -> f64 {
    let w = obs.waypoints[0];
    w[0].hypot(w[1]) - WAYPOINT_SPACING * obs.waypoint_speeds[0].max(0.0)
}

/// Each body's mass over the humanoid's total \[-\], physics body order.
fn mass_fractions() -> [f64; NUM_BODIES] {
    let masses = plamo_physics::humanoid::BODIES.map(|b| {
        b.shapes
            .iter()
            .map(plamo_physics::humanoid::shape_mass)
            .sum::<f64>()
    });
    let total: f64 = masses.iter().sum();
    masses.map(|m| m / total)
}

/// Offset of the centre of mass from the root, heading frame (forward, left) \[m\]:
/// body origins weighted by `fractions` (see [`mass_fractions`]).
fn com_offset(fractions: &[f64; NUM_BODIES], obs: &Observation) -> [f64; 2] {
    fractions
        .iter()
        .zip(&obs.body_pos)
        .fold([0.0; 2], |[x, y], (m, p)| [x + m * p[0], y + m * p[1]])
}

/// The centre of mass's offset from the midpoint of the ankles, heading frame
/// (forward, left) \[m\], and the ankles' lateral positions (lower, upper) \[m\].
fn com_over_feet(fractions: &[f64; NUM_BODIES], obs: &Observation) -> ([f64; 2], [f64; 2]) {
    let com = com_offset(fractions, obs);
    let (a, b) = (obs.body_pos[FEET[0]], obs.body_pos[FEET[1]]);
    let mid = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
    (
        [com[0] - mid[0], com[1] - mid[1]],
        [a[1].min(b[1]) - mid[1], a[1].max(b[1]) - mid[1]],
    )
}

/// The residual force a gait asks for, heading frame \[N\]: the horizontal velocity
/// error times `vel_gain` \[1/s\], and a height PD (`height_gain` \[1/s^2\] on the
/// root height error, `height_damping` \[1/s\] on the vertical velocity) that only
/// pushes up, both times the body mass `m` \[kg\].
fn residual_force(
    m: f64,
    vel_gain: f64,
    v_err: [f64; 2],
    height_gain: f64,
    height_err: f64,
    height_damping: f64,
    vz: f64,
) -> [f64; 3] {
    [
        m * vel_gain * v_err[0],
        m * vel_gain * v_err[1],
        (m * (height_gain * height_err - height_damping * vz)).max(0.0),
    ]
}

/// The bounded residual root wrench of a gait's step: `force` \[N\] and `torque`
/// \[N m\] in the heading frame, the force clamped to its cap in `settings` and the
/// torque to `torque_cap` \[N m\], turned into the world frame. It goes into the
/// action only when a cap in `settings` is non-zero.
fn residual_wrench(
    settings: &ControllerSettings,
    torque_cap: f64,
    heading: f64,
    force: [f64; 3],
    torque: [f64; 3],
    out: &mut Action,
) -> RootWrench {
    let m = settings.body_mass;
    let force = clamp_norm(force, settings.residual_force_cap * m * GRAVITY);
    let torque = clamp_norm(torque, torque_cap);
    let wrench = RootWrench {
        force: from_heading_frame(heading, force),
        torque: from_heading_frame(heading, torque),
    };
    out.root_wrench =
        (settings.residual_force_cap > 0.0 || settings.residual_torque_cap > 0.0).then_some(wrench);
    wrench
}

/// The model-based controller (see the module docs).
#[derive(Debug, Clone)]
pub struct ModelBasedController {
    biped: BipedGait,
    crawl: CrawlGait,
    /// Whether the crawl gait (including its get-down and get-up) is in charge.
    crawling: bool,
    /// How long the biped has been braking for a get-down \[s\].
    braking: f64,
    /// The observation the biped brakes on (the plan held at the head).
    brake_obs: Observation,
    /// Whether no step has been taken since the start or a reset.
    fresh: bool,
}

impl ModelBasedController {
    /// The layout this controller expects (the plamo-physics humanoid).
    pub const LAYOUT: ObservationLayout = ObservationLayout {
        num_joints: NUM_JOINTS,
        num_bodies: NUM_BODIES,
    };

    /// A controller with the built-in parameters.
    pub fn new(settings: ControllerSettings) -> Result<Self> {
        Self::with_params(GaitParams::default(), settings)
    }

    /// A controller with explicit parameters.
    pub fn with_params(params: GaitParams, settings: ControllerSettings) -> Result<Self> {
        Self::with_all_params(params, CrawlParams::default(), settings)
    }

    /// A controller with explicit biped and crawl parameters.
    pub fn with_all_params(
        params: GaitParams,
        crawl: CrawlParams,
        settings: ControllerSettings,
    ) -> Result<Self> {
        params.validate()?;
        crawl.validate()?;
        settings.validate()?;
        Ok(Self {
            crawl: CrawlGait::new(crawl, settings.clone()),
            biped: BipedGait::new(params, settings),
            crawling: false,
            braking: 0.0,
            brake_obs: Observation::new(Self::LAYOUT),
            fresh: true,
        })
    }

    /// The crawl parameters in use.
    pub fn crawl_params(&self) -> &CrawlParams {
        self.crawl.params()
    }

    /// Whether the crawl gait is in charge (getting down, crawling or getting up).
    pub fn is_crawling(&self) -> bool {
        self.crawling
    }

    /// The parameters in use.
    pub fn params(&self) -> &GaitParams {
        self.biped.params()
    }

    /// Whether a crawler may stand up into a crouch-walk: the plan asks for at least
    /// `crouch_stand_above` at every waypoint (5 s ahead: no crawl coming, under a
    /// ceiling or otherwise; the planner puts the head below `crawl_below` wherever a
    /// top is too low for a crouch). A crawl on a crouch-walk leg kept its head at
    /// ~0.35 m against the fall rule's bar of 0.8 - 0.5 m, so a dip on stairs counted
    /// as a fall, and the user had asked for a crouch-walk.
    fn crouch_ahead(&self, obs: &Observation) -> bool {
        let p = self.crawl.params();
        let head = obs.root_height + obs.head_pos[2];
        obs.waypoints
            .iter()
            .zip(&obs.waypoint_ground)
            .all(|(w, g)| head + w[2] - g >= p.crouch_stand_above)
    }

    /// The residual wrench of the last action (world frame).
    pub fn last_wrench(&self) -> RootWrench {
        if self.crawling {
            self.crawl.last_wrench()
        } else {
            self.biped.last_wrench()
        }
    }
}

impl Policy for ModelBasedController {
    fn act(&mut self, obs: &Observation, out: &mut Action) -> Result<()> {
        if obs.layout() != Self::LAYOUT {
            return Err(ControllerError::WrongLength {
                what: "observation (the model-based controller needs the plamo-physics humanoid)",
                expected: Self::LAYOUT.len(),
                got: obs.layout().len(),
            });
        }
        // The plan's head height above the ground under its own point, 0.5 s ahead:
        // measured from the ground under the root, a crouch-walk down a slope or stairs
        // asked for 0.8 m minus the descent ahead and went down on hands and knees.
        let requested =
            obs.root_height + obs.head_pos[2] + obs.waypoints[0][2] - obs.waypoint_ground[0];
        let p = self.crawl.params();
        let (below, above) = (p.crawl_below, p.stand_above);
        let (down_speed, brake_time) = (p.down_speed, p.brake_time);
        let kneeling_crawls = p.reset_kneeling_crawls;
        if requested >= below {
            self.braking = 0.0;
        }
        if std::mem::take(&mut self.fresh)
            && kneeling_crawls
            && !self.crawling
            && requested >= below
            && obs.root_height + obs.head_pos[2] < below
        {
            self.crawling = true;
            self.crawl.reset();
        }
        if !self.crawling && requested < below {
            // Getting down at a walk pitches the body onto its head before the hands
            // are down: the biped first brakes (the plan held at the head) to
            // `down_speed`, for at most `brake_time`.
            let speed = obs.root_lin_vel[0].hypot(obs.root_lin_vel[1]);
            if speed > down_speed && self.braking < brake_time {
                self.braking += plamo_interfaces::CONTROL_DT;
                self.brake_obs.clone_from(obs);
                self.brake_obs.waypoints = [[0.0; 3]; NUM_WAYPOINTS];
                self.brake_obs.waypoint_speeds = [0.0; NUM_WAYPOINTS];
                self.biped.act(&self.brake_obs, out);
                return Ok(());
            }
            self.braking = 0.0;
            self.crawling = true;
            self.crawl.begin_down(obs);
        } else if self.crawling {
            if self.crawl.stood_up() {
                self.crawling = false;
                self.biped.reset();
            } else if self.crawl.standing_up() {
                if requested < below {
                    self.crawl.begin_down(obs);
                }
            } else if self.crawl.settled()
                && (plan_lead(obs) < MAX_STAND_LAG || obs.headroom > requested + STAND_HEADROOM)
                && (requested > above || self.crouch_ahead(obs))
            {
                self.crawl.begin_up(obs);
            }
        }
        if self.crawling {
            self.crawl.act(obs, out);
        } else {
            self.biped.act(obs, out);
        }
        Ok(())
    }

    fn reset(&mut self) {
        self.biped.reset();
        self.crawl.reset();
        self.crawling = false;
        self.braking = 0.0;
        self.fresh = true;
    }

    fn name(&self) -> &str {
        "model-based"
    }
}
