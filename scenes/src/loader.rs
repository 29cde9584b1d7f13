//! Entry points that turn text, files and names into validated scenes.

use std::path::{Path, PathBuf};

use crate::file_format::SceneFile;
use crate::{Scene, SceneError};

/// Parse a TOML scene file's text; `origin` names it in errors (a path or a name).
/// Relative paths inside it (height-map PNGs) are looked up in the current directory.
pub fn from_toml_str(text: &str, origin: &str) -> Result<Scene, SceneError> {
    from_toml_in(text, origin, Path::new("."))
}

/// Parse TOML text into the file format, without building the scene.
pub fn parse_toml(text: &str, origin: &str) -> Result<SceneFile, SceneError> {
    let de = toml::Deserializer::parse(text).map_err(|e| SceneError::Parse {
        origin: origin.to_string(),
        field: ".".to_string(),
        message: one_line(&e.to_string()),
    })?;
    serde_path_to_error::deserialize(de).map_err(|e| {
        let field = e.path().to_string();
        SceneError::Parse {
            origin: origin.to_string(),
            field,
            message: one_line(&e.into_inner().to_string()),
        }
    })
}

fn from_toml_in(text: &str, origin: &str, base_dir: &Path) -> Result<Scene, SceneError> {
    let file = parse_toml(text, origin)?;
    crate::compile::build(&file, origin, base_dir)
}

/// The toml crate's messages span several lines with a source excerpt; keep the
/// excerpt but on one line so every error is one line.
fn one_line(s: &str) -> String {
    s.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

/// Load a scene file: `.toml` (PlaMo format) or `.json` (ProtoMotions path-follower).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let io = |source| SceneError::Io {
        file: path.to_path_buf(),
        source,
    };
    let origin = path.display().to_string();
    match path.extension().and_then(|e| e.to_str()) {
        Some("toml") => {
            let text = std::fs::read_to_string(path).map_err(io)?;
            let base = path
                .parent()
                .map_or_else(|| PathBuf::from("."), Path::to_path_buf);
            from_toml_in(&text, &origin, &base)
        }
        Some("json") => {
            let text = std::fs::read_to_string(path).map_err(io)?;
            crate::protomotions::from_json_str(&text, &origin)
        }
        _ => Err(SceneError::UnknownFileType {
            file: path.to_path_buf(),
        }),
    }
}

/// A built-in scene by name, a random scene by its name `random-<seed>` (the scene
/// `plamo scenes random --seed <seed>` writes, and `plamo eval random` runs), else a
/// scene file by path.
pub fn resolve(name_or_path: &str) -> Result<Scene, SceneError> {
    if crate::builtin_names().contains(&name_or_path) {
        return crate::builtin(name_or_path);
    }
    let path = Path::new(name_or_path);
    if let Some(seed) = name_or_path
        .strip_prefix("random-")
        .and_then(|s| s.parse::<u64>().ok())
        && !path.exists()
    {
        return Ok(crate::random_scene(seed));
    }
    if path.extension().is_none() && !path.exists() {
        // Looks like a name, not a file: say which names exist.
        return crate::builtin(name_or_path);
    }
    load(path)
}
