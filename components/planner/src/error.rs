//! Typed errors (bad input, broken invariants). Outcomes such as "reached" or
//! "infeasible at run time" are in [`crate::PlanStatus`], not here.

/// Why a target cannot be reached.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum UnreachableReason {
    /// The start position is off the terrain grid.
    StartOffGrid,
    /// No traversable cell near the start (inside a wall, under a top too low even for
    /// crawling, or walled in).
    StartBlocked,
    /// No traversable cell in (or next to) the target landmark's region.
    TargetBlocked,
    /// Start and target lie in different connected components of the traversable grid
    /// (walls, low tops or infeasible slopes separate them).
    Disconnected,
    /// A dynamic obstacle, at its predicted position, covers every cell of the target
    /// region: the target is occupied (for now; a later step plans again).
    TargetOccupied {
        /// The obstacle, numbered as in [`crate::Conflict::obstacle`].
        obstacle: usize,
    },
    /// A dynamic obstacle, at its predicted position, covers the character and every
    /// free cell near it.
    StartOccupied {
        /// The obstacle, numbered as in [`crate::Conflict::obstacle`].
        obstacle: usize,
    },
}

impl std::fmt::Display for UnreachableReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::StartOffGrid => "the start is off the terrain grid",
            Self::StartBlocked => "no traversable cell near the start",
            Self::TargetBlocked => "the target region has no traversable cell",
            Self::Disconnected => {
                "start and target are separated by walls, low tops or infeasible slopes"
            }
            Self::TargetOccupied { obstacle } => {
                return write!(
                    f,
                    "dynamic obstacle {obstacle} covers the whole target region at its predicted position"
                );
            }
            Self::StartOccupied { obstacle } => {
                return write!(
                    f,
                    "dynamic obstacle {obstacle} covers the character and every free cell near it"
                );
            }
        })
    }
}

/// Why the speed optimisation failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpeedFailure {
    /// The constraints admit no speed profile (e.g. a fixed end speed out of reach).
    Infeasible,
    /// The solver stopped early (iterations, time, numerical trouble).
    NotConverged,
    /// The problem was malformed (lengths differ, NaN).
    BadProblem,
}

/// Planner errors.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanError {
    /// A settings field is out of range.
    #[error("planner settings: `{field}` {reason}")]
    InvalidSettings {
        /// Field name.
        field: &'static str,
        /// What is allowed.
        reason: String,
    },
    /// No instruction in the text.
    #[error("no instruction given; expected e.g. \"run from the tree to the car\"")]
    NoInstructions,
    /// The instruction does not start with a known locomotion verb.
    #[error("instruction {index} (\"{text}\"): unknown verb `{verb}`; valid verbs: {}", valid.join(", "))]
    UnknownVerb {
        /// 0-based instruction index.
        index: usize,
        /// The instruction text.
        text: String,
        /// The word that was read as the verb.
        verb: String,
        /// Accepted verbs.
        valid: Vec<String>,
    },
    /// A landmark name is not in the scene.
    #[error("instruction {index} (\"{text}\"): unknown landmark `{name}`; landmarks in this scene: {}", valid.join(", "))]
    UnknownLandmark {
        /// 0-based instruction index.
        index: usize,
        /// The instruction text.
        text: String,
        /// The name that was not found.
        name: String,
        /// Landmarks of the scene.
        valid: Vec<String>,
    },
    /// The instruction does not follow the template.
    #[error(
        "instruction {index} (\"{text}\"): {reason}; expected \"<verb> [from the <landmark>] to the <landmark>\""
    )]
    Malformed {
        /// 0-based instruction index.
        index: usize,
        /// The instruction text.
        text: String,
        /// What is missing.
        reason: &'static str,
    },
    /// The target cannot be reached.
    #[error("instruction {index} (\"{text}\"): cannot reach `{target}`: {reason}")]
    Unreachable {
        /// 0-based instruction index.
        index: usize,
        /// The instruction text.
        text: String,
        /// Target landmark.
        target: String,
        /// Why.
        reason: UnreachableReason,
    },
    /// The speed optimisation failed.
    #[error("speed optimisation failed: {0:?}")]
    Speed(SpeedFailure),
    /// A step input is out of range.
    #[error("planner input `{field}`: {reason}")]
    InvalidInput {
        /// Field name.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
}
