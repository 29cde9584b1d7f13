//! The model-based tracking controller, the default policy (no network needed).
//!
//! One gait per family of forms, chosen by the requested head height and speed:
//! [`biped`] walks, runs and crouch-walks (its parameters blended continuously).

mod biped;
mod ik;
mod params;

pub use ik::{LegGeometry, leg_fk, leg_ik};
pub use params::{DEFAULT_GAIT_PARAMS, FormParams, GAIT_PARAMS_VERSION, GaitParams, ResidualGains};

use plamo_physics::{NUM_BODIES, NUM_JOINTS};

use crate::error::{ControllerError, Result};
use crate::observation::{Observation, ObservationLayout};
use crate::policy::{Action, Policy, RootWrench};
use crate::settings::ControllerSettings;
use biped::BipedGait;

/// The model-based controller (see the module docs).
#[derive(Debug, Clone)]
pub struct ModelBasedController {
    biped: BipedGait,
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
        params.validate()?;
        settings.validate()?;
        Ok(Self {
            biped: BipedGait::new(params, settings),
        })
    }

    /// The parameters in use.
    pub fn params(&self) -> &GaitParams {
        self.biped.params()
    }

    /// The residual wrench of the last action (world frame).
    pub fn last_wrench(&self) -> RootWrench {
        self.biped.last_wrench()
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
        self.biped.act(obs, out);
        Ok(())
    }

    fn reset(&mut self) {
        self.biped.reset();
    }

    fn name(&self) -> &str {
        "model-based"
    }
}
