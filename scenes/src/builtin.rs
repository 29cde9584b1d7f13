//! The built-in scenes: TOML files in the crate's directory, embedded in the binary
//! so `plamo` works from anywhere.

use crate::{Scene, SceneError};

const FILES: [(&str, &str); 7] = [
    ("playground", include_str!("../playground.toml")),
    ("slalom", include_str!("../slalom.toml")),
    ("pyramid", include_str!("../pyramid.toml")),
    ("terrain-flat", include_str!("../terrain-flat.toml")),
    ("terrain-slope", include_str!("../terrain-slope.toml")),
    ("terrain-rough", include_str!("../terrain-rough.toml")),
    ("terrain-stairs", include_str!("../terrain-stairs.toml")),
];

const NAMES: [&str; 7] = [
    FILES[0].0, FILES[1].0, FILES[2].0, FILES[3].0, FILES[4].0, FILES[5].0, FILES[6].0,
];

/// Names of the built-in scenes.
pub fn builtin_names() -> &'static [&'static str] {
    &NAMES
}

/// The TOML text of a built-in scene.
pub fn builtin_source(name: &str) -> Option<&'static str> {
    FILES.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
}

/// A built-in scene by name; an unknown name is an error listing the valid ones.
pub fn builtin(name: &str) -> Result<Scene, SceneError> {
    let text = builtin_source(name).ok_or_else(|| SceneError::UnknownBuiltin {
        name: name.to_string(),
        valid: NAMES.iter().map(|s| s.to_string()).collect(),
    })?;
    crate::from_toml_str(text, &format!("{name}.toml (built-in)"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_loads_and_validates() {
        for name in builtin_names() {
            let s = builtin(name).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(&s.name, name);
            crate::validate(&s).unwrap();
            assert!(s.landmarks.len() >= 2, "{name}");
        }
    }

    #[test]
    fn unknown_name_lists_the_valid_ones() {
        let e = builtin("playgroud").unwrap_err().to_string();
        assert!(
            e.contains("playgroud") && e.contains("playground") && e.contains("terrain-stairs")
        );
    }
}
