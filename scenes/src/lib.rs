//! The PlaMo scene (paper eq. 1): Scene = { h, O_static, O_dynamic, O_top, L }.
//!
//! A [`Scene`] is the resolved, validated model every component reads: a terrain
//! height grid, static walls, low ceilings ("top obstacles"), dynamic obstacles with
//! deterministic motion rules, and named landmarks. All coordinates are world frame,
//! Z up, metres; angles in radians.
#![warn(missing_docs)]

mod geometry;
mod model;
mod motion;
mod queries;
mod terrain;

pub use geometry::Footprint;
pub use model::{DynamicObstacle, Landmark, ObstacleShape, Region, Scene, TopObstacle, Wall};
pub use motion::{Motion, ObstacleState};
pub use queries::{LOCAL_MAP_SAMPLES, LOCAL_MAP_SIDE, LOCAL_MAP_SPACING, LocalHeightMap};
pub use terrain::HeightGrid;
