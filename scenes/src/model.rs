//! The resolved scene model (paper eq. 1). Built by the scene-file loader, the
//! generators or the importers, and validated before anyone reads it.

use serde::{Deserialize, Serialize};

use crate::{Footprint, HeightGrid, Motion};

/// A static, non-passable obstacle: a box from `z_min` to `z_max` over `footprint`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Wall {
    /// Optional name for messages.
    pub name: String,
    /// XY footprint.
    pub footprint: Footprint,
    /// Bottom of the box \[m\] (at or below the terrain under it).
    pub z_min: f64,
    /// Top of the box \[m\].
    pub z_max: f64,
}

/// A height-limiting ("top") obstacle: a box whose bottom at `z_bottom` is the
/// ceiling the character must fit under.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TopObstacle {
    /// Optional name for messages.
    pub name: String,
    /// XY footprint.
    pub footprint: Footprint,
    /// Ceiling height, the box's underside \[m\].
    pub z_bottom: f64,
    /// Top of the box \[m\].
    pub z_top: f64,
}

/// Shape of a dynamic obstacle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ObstacleShape {
    /// A sphere (a ball).
    Sphere {
        /// Radius \[m\].
        radius: f64,
    },
    /// An axis-aligned box (a cart, a car), yaw follows the velocity direction.
    Box {
        /// Half extents \[m\].
        half_extents: [f64; 3],
    },
}

impl ObstacleShape {
    /// Radius of the horizontal circle that bounds the shape \[m\].
    pub fn bounding_radius_xy(&self) -> f64 {
        match *self {
            ObstacleShape::Sphere { radius } => radius,
            ObstacleShape::Box { half_extents: h } => (h[0] * h[0] + h[1] * h[1]).sqrt(),
        }
    }
}

/// A moving obstacle with a deterministic motion rule.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DynamicObstacle {
    /// Name for messages and outputs ("ball").
    pub name: String,
    /// Shape.
    pub shape: ObstacleShape,
    /// Motion rule; the state at time t is `motion.state_at(t)`.
    pub motion: Motion,
}

/// The set of (x, y) positions a landmark covers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Region {
    /// A disc.
    Circle {
        /// Centre \[m\].
        center: [f64; 2],
        /// Radius \[m\], > 0.
        radius: f64,
    },
    /// An oriented rectangle.
    Rect {
        /// Footprint.
        #[serde(flatten)]
        footprint: Footprint,
    },
}

impl Region {
    /// Whether (x, y) lies in the region.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        match self {
            Region::Circle { center, radius } => {
                (x - center[0]).powi(2) + (y - center[1]).powi(2) <= radius * radius
            }
            Region::Rect { footprint } => footprint.contains(x, y),
        }
    }

    /// Centre of the region.
    pub fn center(&self) -> [f64; 2] {
        match self {
            Region::Circle { center, .. } => *center,
            Region::Rect { footprint } => footprint.center,
        }
    }

    /// Axis-aligned bounding box as (min, max).
    pub fn aabb(&self) -> ([f64; 2], [f64; 2]) {
        match self {
            Region::Circle { center, radius } => (
                [center[0] - radius, center[1] - radius],
                [center[0] + radius, center[1] + radius],
            ),
            Region::Rect { footprint } => footprint.aabb(),
        }
    }
}

/// A named goal region ("tree", "car").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Landmark {
    /// Name used in instructions, lower case.
    pub name: String,
    /// The cells that count as reaching it.
    pub region: Region,
}

/// A scene: Scene = { h, O_static, O_dynamic, O_top, L } (paper eq. 1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scene {
    /// Scene name ("playground").
    pub name: String,
    /// One-line description.
    pub description: String,
    /// Terrain height map h(x, y).
    pub terrain: HeightGrid,
    /// Static obstacles O_static.
    pub walls: Vec<Wall>,
    /// Dynamic obstacles O_dynamic.
    pub dynamic: Vec<DynamicObstacle>,
    /// Top obstacles O_top (low ceilings).
    pub tops: Vec<TopObstacle>,
    /// Landmarks L.
    pub landmarks: Vec<Landmark>,
}
