//! Typed errors of the controller. Outcomes (fell, reached) are data in
//! [`crate::MetricsSummary`], never errors.

use std::path::PathBuf;

/// Everything that can go wrong building observations, loading or running a policy.
#[derive(Debug, thiserror::Error)]
pub enum ControllerError {
    /// A settings or parameter field is outside its documented range.
    #[error("invalid setting `{field}`: {reason}")]
    InvalidSettings {
        /// Field name.
        field: &'static str,
        /// What was wrong and what is allowed.
        reason: String,
    },
    /// An input vector had the wrong length for the configured layout.
    #[error("`{what}` has length {got}, expected {expected}")]
    WrongLength {
        /// Which input (e.g. `joint_pos`, `flattened observation`).
        what: &'static str,
        /// Length required by the layout.
        expected: usize,
        /// Length received.
        got: usize,
    },
    /// An input or output value was NaN or infinite.
    #[error("`{what}` contains a non-finite value at index {index}")]
    NonFinite {
        /// Which vector.
        what: &'static str,
        /// First offending index.
        index: usize,
    },
    /// A policy was built for another observation version.
    #[error(
        "observation version mismatch: policy expects version {found}, this controller produces version {expected}"
    )]
    VersionMismatch {
        /// [`crate::OBSERVATION_VERSION`].
        expected: u32,
        /// Version recorded in the policy's sidecar.
        found: u32,
    },
    /// The sidecar file next to an ONNX model is absent.
    #[error("no sidecar for model {model}: looked for {tried:?}")]
    SidecarMissing {
        /// The model path.
        model: PathBuf,
        /// Sidecar paths that were tried.
        tried: Vec<PathBuf>,
    },
    /// Reading a file failed.
    #[error("cannot read {path}: {source}")]
    Io {
        /// File path.
        path: PathBuf,
        /// Underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A TOML file (sidecar or gait parameters) did not parse.
    #[error("{path}: {source}")]
    Toml {
        /// File path (or `<built-in>`).
        path: PathBuf,
        /// Underlying error with line/column.
        #[source]
        source: toml::de::Error,
    },
    /// A JSON sidecar did not parse.
    #[error("{path}: {source}")]
    Json {
        /// File path.
        path: PathBuf,
        /// Underlying error with line/column.
        #[source]
        source: serde_json::Error,
    },
    /// The sidecar's joint list does not match the humanoid's joints.
    #[error("joint order mismatch: {reason}")]
    JointMismatch {
        /// Which joint is missing or extra.
        reason: String,
    },
    /// The physics backend failed during a rollout.
    #[error("physics: {0}")]
    Physics(#[from] plamo_physics::PhysicsError),
    /// The ONNX runtime (tract) failed to load, optimise or run the network.
    #[error("ONNX model {path}: {stage} failed: {source}")]
    Onnx {
        /// Model path.
        path: PathBuf,
        /// `load`, `optimise` or `run`.
        stage: &'static str,
        /// Underlying tract error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync + 'static>,
    },
}

/// Result alias for the controller.
pub type Result<T, E = ControllerError> = std::result::Result<T, E>;

/// Returns an error naming the first non-finite entry of `values`.
pub(crate) fn check_finite<T: Copy + Into<f64>>(what: &'static str, values: &[T]) -> Result<()> {
    match values.iter().position(|v| !(*v).into().is_finite()) {
        Some(index) => Err(ControllerError::NonFinite { what, index }),
        None => Ok(()),
    }
}
