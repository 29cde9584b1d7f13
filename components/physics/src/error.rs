//! Typed errors of the physics component.

use plamo_interfaces::Tick;

use crate::BackendKind;

/// Everything that can go wrong building or stepping a physics backend.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PhysicsError {
    /// A [`crate::PhysicsSettings`] field is out of its documented range.
    #[error("invalid physics setting `{field}`: {reason}")]
    InvalidSettings {
        /// Field name.
        field: &'static str,
        /// What is allowed.
        reason: String,
    },
    /// The scene cannot be turned into a physics world.
    #[error("invalid scene for physics: {reason}")]
    InvalidScene {
        /// What is wrong.
        reason: String,
    },
    /// An action had the wrong number of joint targets.
    #[error("action has {got} joint targets, expected {expected} (see JOINT_NAMES)")]
    WrongActionLength {
        /// [`crate::NUM_JOINTS`].
        expected: usize,
        /// Length received.
        got: usize,
    },
    /// An input value is NaN or infinite.
    #[error("non-finite value in `{field}` at index {index}: {value}")]
    NonFinite {
        /// Which input ("targets", "root_wrench", "pose.joints", ...).
        field: &'static str,
        /// Index inside that input.
        index: usize,
        /// The value.
        value: f64,
    },
    /// An initial pose is unusable (e.g. a zero quaternion).
    #[error("invalid pose: {reason}")]
    InvalidPose {
        /// What is wrong.
        reason: String,
    },
    /// A humanoid index beyond the number of humanoids in the world.
    #[error("no humanoid {index}: the world has {count}")]
    NoSuchHumanoid {
        /// Index asked for.
        index: usize,
        /// Humanoids in the world.
        count: usize,
    },
    /// The simulation produced a state no humanoid can have (non-finite, or moving
    /// impossibly fast: [`crate::HumanoidState::unphysical`]), or the engine failed
    /// inside a step. The backend refuses to step until `reset`.
    #[error("{backend} simulation diverged at tick {tick}: {reason}")]
    Diverged {
        /// Backend.
        backend: BackendKind,
        /// Tick at which the divergence was detected.
        tick: u64,
        /// What was found.
        reason: String,
    },
    /// The backend is not compiled in (e.g. MuJoCo without the `mujoco` feature).
    #[error("physics backend `{kind}` is not available: {reason}")]
    Unavailable {
        /// The backend asked for.
        kind: BackendKind,
        /// Why, and how to enable it.
        reason: &'static str,
    },
    /// The engine rejected the generated model.
    #[error("{backend} rejected the model: {reason}")]
    Model {
        /// Backend.
        backend: BackendKind,
        /// Engine message.
        reason: String,
    },
}

impl PhysicsError {
    /// `Ok` when `index` names one of the `count` humanoids of a world, else
    /// [`PhysicsError::NoSuchHumanoid`] (shared by every backend).
    pub(crate) fn check_index(index: usize, count: usize) -> Result<(), Self> {
        if index < count {
            Ok(())
        } else {
            Err(Self::NoSuchHumanoid { index, count })
        }
    }

    /// [`PhysicsError::Diverged`] for `backend` at `tick`.
    pub(crate) fn diverged(backend: BackendKind, tick: Tick, reason: impl Into<String>) -> Self {
        Self::Diverged {
            backend,
            tick: tick.0,
            reason: reason.into(),
        }
    }

    /// The error a backend returns while a humanoid is still marked diverged.
    pub(crate) fn still_diverged(backend: BackendKind, tick: Tick) -> Self {
        Self::diverged(
            backend,
            tick,
            "a previous step diverged; reset every diverged humanoid",
        )
    }
}

/// `"xyz".parse::<BackendKind>()` failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown physics backend `{given}`; valid values: rapier, mujoco")]
pub struct ParseBackendKindError {
    /// The string that was given.
    pub given: String,
}
