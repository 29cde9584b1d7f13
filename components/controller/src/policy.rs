//! The policy contract: observation in, action out.

use crate::error::Result;
use crate::observation::Observation;

/// A bounded wrench applied at the root (pelvis), world frame: the model-based
/// controller's residual help. Its size is always reported by the metrics.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct RootWrench {
    /// Force \[N\].
    pub force: [f64; 3],
    /// Torque \[N m\].
    pub torque: [f64; 3],
}

/// What a policy commands for one control step (held for 4 physics steps).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Action {
    /// PD position targets \[rad\], one per actuated joint, physics joint order.
    pub pd_targets: Vec<f64>,
    /// Residual root wrench, `None` when the policy uses none.
    pub root_wrench: Option<RootWrench>,
}

impl Action {
    /// An action holding every joint at zero with no wrench.
    pub fn zeros(num_joints: usize) -> Self {
        Self {
            pd_targets: vec![0.0; num_joints],
            root_wrench: None,
        }
    }
}

/// A locomotion policy: maps an [`Observation`] to an [`Action`].
///
/// Implementations: [`crate::OnnxPolicy`] (learned) and the model-based tracking
/// controller. `act` overwrites `out` completely and must not allocate in steady state.
pub trait Policy {
    /// Computes the action for `obs` into `out` (`out.pd_targets` has one entry per
    /// joint of the observation's layout).
    fn act(&mut self, obs: &Observation, out: &mut Action) -> Result<()>;

    /// Forgets internal state (gait phase, filters) before a new episode.
    fn reset(&mut self) {}

    /// Short name for logs and reports.
    fn name(&self) -> &str;
}
