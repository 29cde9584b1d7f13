//! The human-written TOML scene file: what a person types, in the units a person
//! thinks in (sizes, heights above the ground, angles in degrees). [`crate::build`]
//! turns it into the resolved [`crate::Scene`].
//!
//! ```toml
//! name = "demo"
//! description = "a slope and a wall"
//!
//! [terrain]
//! size = [20.0, 20.0]        # metres along X and Y
//! resolution = 0.1           # grid spacing, default 0.1 m
//!
//! [[terrain.tiles]]          # generators, applied in order
//! area = { min = [5.0, 0.0], max = [15.0, 20.0] }
//! generator = { kind = "slope", angle_deg = 8.0, direction_deg = 0.0, symmetric = true }
//!
//! [[walls]]
//! center = [10.0, 5.0]
//! size = [0.4, 6.0]
//! height = 2.0
//!
//! [[tops]]                   # low ceilings
//! center = [4.0, 15.0]
//! size = [3.0, 4.0]
//! clearance = 0.6            # above the highest ground under it
//! thickness = 0.2
//!
//! [[dynamic]]
//! name = "ball"
//! shape = { kind = "sphere", radius = 0.25 }
//! motion = { kind = "linear", from = [2.0, 2.0, 0.25], to = [8.0, 2.0, 0.25], speed = 1.5 }
//!
//! [[landmarks]]
//! name = "tree"
//! region = { kind = "circle", center = [2.0, 18.0], radius = 1.0 }
//! ```

use serde::{Deserialize, Serialize};

use crate::generators::Generator;
use crate::{Motion, ObstacleShape};

/// Default grid spacing \[m\].
pub const DEFAULT_RESOLUTION: f64 = 0.1;

fn default_resolution() -> f64 {
    DEFAULT_RESOLUTION
}
fn default_wall_height() -> f64 {
    2.0
}
fn default_thickness() -> f64 {
    0.2
}
fn is_zero(v: &f64) -> bool {
    *v == 0.0
}
fn is_default_resolution(v: &f64) -> bool {
    *v == DEFAULT_RESOLUTION
}
fn is_zero2(v: &[f64; 2]) -> bool {
    *v == [0.0, 0.0]
}

/// A scene file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Scene name.
    pub name: String,
    /// One-line description.
    #[serde(default)]
    pub description: String,
    /// The terrain.
    pub terrain: TerrainSpec,
    /// Static walls.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub walls: Vec<WallSpec>,
    /// Low ceilings.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tops: Vec<TopSpec>,
    /// Moving obstacles.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub dynamic: Vec<DynamicSpec>,
    /// Named goal regions.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub landmarks: Vec<LandmarkSpec>,
}

/// The terrain: an extent, an optional height grid, and generator tiles applied on
/// top of it in order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TerrainSpec {
    /// Extent along X and Y \[m\]; required unless `grid` gives it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<[f64; 2]>,
    /// World XY of the grid's first sample \[m\], default (0, 0).
    #[serde(default, skip_serializing_if = "is_zero2")]
    pub origin: [f64; 2],
    /// Grid spacing \[m\], default 0.1, allowed 0.02 ..= 1.
    #[serde(
        default = "default_resolution",
        skip_serializing_if = "is_default_resolution"
    )]
    pub resolution: f64,
    /// Heights given directly (inline rows or a PNG); tiles are added on top.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grid: Option<GridSpec>,
    /// Generator tiles, applied in order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tiles: Vec<Tile>,
}

/// Heights given as data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum GridSpec {
    /// Inline rows: `heights[j][i]` is the height \[m\] at (origin + (i, j) * resolution).
    Inline {
        /// Rows along Y, each the same length (samples along X).
        heights: Vec<Vec<f64>>,
    },
    /// A 16-bit (or 8-bit) grayscale PNG; the image's top row is the largest Y.
    /// Height = `offset + scale * value`.
    Png {
        /// Path, relative to the scene file.
        path: String,
        /// Metres per grey level.
        scale: f64,
        /// Height of grey level 0 \[m\].
        #[serde(default, skip_serializing_if = "is_zero")]
        offset: f64,
    },
}

/// How a tile combines with the heights below it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BlendMode {
    /// Add the generator's height (the default).
    #[default]
    Add,
    /// Replace the heights in the area.
    Set,
    /// Keep the larger of the two.
    Max,
}

fn is_add(m: &BlendMode) -> bool {
    *m == BlendMode::Add
}

/// An axis-aligned rectangle \[m\].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Area {
    /// Lower-left corner.
    pub min: [f64; 2],
    /// Upper-right corner.
    pub max: [f64; 2],
}

/// One generator applied over an area.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tile {
    /// Where it applies; default the whole terrain.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub area: Option<Area>,
    /// How it combines with what is below.
    #[serde(default, skip_serializing_if = "is_add")]
    pub blend: BlendMode,
    /// The generator.
    pub generator: Generator,
}

/// A static wall: a box standing on the ground.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallSpec {
    /// Optional name.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub name: String,
    /// Centre \[m\].
    pub center: [f64; 2],
    /// Full size along the wall's own X and Y \[m\], both > 0.
    pub size: [f64; 2],
    /// Rotation \[deg\], counter-clockwise.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub yaw_deg: f64,
    /// Height above the highest ground under it \[m\], default 2.
    #[serde(default = "default_wall_height")]
    pub height: f64,
}

/// A low ceiling: a slab whose underside is `clearance` above the highest ground
/// under it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TopSpec {
    /// Optional name.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub name: String,
    /// Centre \[m\].
    pub center: [f64; 2],
    /// Full size \[m\], both > 0.
    pub size: [f64; 2],
    /// Rotation \[deg\], counter-clockwise.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub yaw_deg: f64,
    /// Free height under it \[m\], > 0.
    pub clearance: f64,
    /// Slab thickness \[m\], default 0.2.
    #[serde(default = "default_thickness")]
    pub thickness: f64,
}

/// A moving obstacle (shape and motion use the model's own types; heights absolute).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicSpec {
    /// Name.
    pub name: String,
    /// Shape.
    pub shape: ObstacleShape,
    /// Motion rule.
    pub motion: Motion,
}

/// A landmark region as written in a file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum RegionSpec {
    /// A disc.
    Circle {
        /// Centre \[m\].
        center: [f64; 2],
        /// Radius \[m\], > 0.
        radius: f64,
    },
    /// A rectangle.
    Rect {
        /// Centre \[m\].
        center: [f64; 2],
        /// Full size \[m\].
        size: [f64; 2],
        /// Rotation \[deg\].
        #[serde(default, skip_serializing_if = "is_zero")]
        yaw_deg: f64,
    },
}

/// A named goal region.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LandmarkSpec {
    /// Name used in instructions (lower case, no spaces).
    pub name: String,
    /// Region.
    pub region: RegionSpec,
}

impl SceneFile {
    /// The file as TOML text that [`crate::from_toml_str`] reads back to the same
    /// scene.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("scene files always serialise: no maps with non-string keys")
    }
}
