//! The one error type of the crate: every variant names where the problem is (the
//! file or scene), the field path inside it, the bad value and what is allowed.

use std::path::PathBuf;

/// Why a scene could not be loaded, built or accepted.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{}: cannot read: {source}", file.display())]
    Io {
        /// The file.
        file: PathBuf,
        /// The operating-system error.
        #[source]
        source: std::io::Error,
    },
    /// The text is not a well-formed scene file: bad syntax, a wrong type, a missing
    /// or an unknown key.
    #[error("{origin}: {field}: {message}")]
    Parse {
        /// The file or the name the text came from.
        origin: String,
        /// Field path inside the file (`landmarks[2].region.radius`), `.` for the root.
        field: String,
        /// The parser's message (what it found and what it expected).
        message: String,
    },
    /// A field has a value outside what is allowed.
    #[error("{origin}: {field} = {value}: {allowed}")]
    Invalid {
        /// The file or scene name.
        origin: String,
        /// Field path (`walls[0].size`).
        field: String,
        /// The offending value, as written.
        value: String,
        /// What would be allowed.
        allowed: String,
    },
    /// A height-map PNG could not be decoded or has the wrong pixel format.
    #[error("{origin}: {field} = {file:?}: {reason}")]
    HeightImage {
        /// The scene file that names the image.
        origin: String,
        /// Field path of the image's name.
        field: String,
        /// The image file.
        file: PathBuf,
        /// What is wrong and what is allowed.
        reason: String,
    },
    /// Two landmarks cannot reach each other under the reachability rules
    /// ([`crate::ReachRules`]).
    #[error(
        "{origin}: landmarks[{to}] ({to_name:?}) cannot be reached from landmarks[{from}] \
         ({from_name:?}): every landmark must be reachable at least by crawling \
         (outside walls, headroom >= {min_headroom} m, steps <= {max_step} m)"
    )]
    Unreachable {
        /// The file or scene name.
        origin: String,
        /// Index of the start landmark.
        from: usize,
        /// Its name.
        from_name: String,
        /// Index of the landmark that cannot be reached.
        to: usize,
        /// Its name.
        to_name: String,
        /// Headroom rule used \[m\].
        min_headroom: f64,
        /// Step rule used \[m\].
        max_step: f64,
    },
    /// No built-in scene has this name.
    #[error(
        "no built-in scene {name:?}; the built-in scenes are: {}, and random-<seed> for a \
         random scene",
        valid.join(", ")
    )]
    UnknownBuiltin {
        /// The name asked for.
        name: String,
        /// The valid names.
        valid: Vec<String>,
    },
    /// The file's extension says neither TOML nor ProtoMotions JSON.
    #[error(
        "{}: unknown scene file type; allowed: .toml (PlaMo scene) or .json (ProtoMotions)",
        file.display()
    )]
    UnknownFileType {
        /// The file.
        file: PathBuf,
    },
}

impl SceneError {
    /// Shorthand for [`SceneError::Invalid`].
    pub(crate) fn invalid(
        origin: &str,
        field: impl Into<String>,
        value: impl std::fmt::Debug,
        allowed: impl Into<String>,
    ) -> Self {
        SceneError::Invalid {
            origin: origin.to_string(),
            field: field.into(),
            value: format!("{value:?}"),
            allowed: allowed.into(),
        }
    }
}
