//! The PlaMo scene (paper eq. 1): Scene = { h, O_static, O_dynamic, O_top, L }.
//!
//! A [`Scene`] is the resolved, validated model every component reads: a terrain
//! height grid, static walls, low ceilings ("top obstacles"), dynamic obstacles with
//! deterministic motion rules, and named landmarks. All coordinates are world frame,
//! Z up, metres; angles in radians.
//!
//! Scenes come from human-written TOML files ([`file_format`], [`from_toml_str`],
//! [`load`]), from the built-in library ([`builtin`]), from ProtoMotions JSON
//! ([`load`] on a `.json` file) or from the seeded generator ([`random_scene`]).
//! Every scene is checked by [`validate`]; errors are [`SceneError`]s that name the
//! file, the field, the bad value and what is allowed.
#![warn(missing_docs)]

mod builtin;
mod compile;
mod errors;
pub mod file_format;
pub mod generators;
mod geometry;
mod height_png;
mod loader;
mod model;
mod motion;
mod protomotions;
mod queries;
mod random;
mod reach;
mod terrain;
mod validate;

pub use builtin::{builtin, builtin_names, builtin_source};
pub use errors::SceneError;
pub use file_format::SceneFile;
pub use geometry::{Footprint, FootprintFrame};
pub use height_png::{read as read_height_png, write as write_height_png};
pub use loader::{from_toml_str, load, parse_toml, resolve};
pub use model::{DynamicObstacle, Landmark, ObstacleShape, Region, Scene, TopObstacle, Wall};
pub use motion::{Motion, ObstacleState};
pub use protomotions::{TILE_RESOLUTION, TILE_SIZE, from_json_str as from_protomotions_json};
pub use queries::{LOCAL_MAP_SAMPLES, LOCAL_MAP_SIDE, LOCAL_MAP_SPACING, LocalHeightMap};
pub use random::{RANDOM_SIZE, random_scene, random_scene_file, random_scene_with_file};
pub use reach::{ReachRules, flood_fill, landmarks_connected, passable_cells, reachable};
pub use terrain::HeightGrid;
pub use validate::validate;
