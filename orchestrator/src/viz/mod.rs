//! Pictures: top-down scene maps with overlays (planned paths, markers, colour bars).
//!
//! [`render_map`] draws a [`Scene`](plamo_scenes::Scene) from above: terrain height
//! shading with a colour bar, walls, hatched low ceilings labelled with their
//! clearance, dashed paths of moving obstacles, labelled landmark regions, a scale
//! bar and axes in metres; a [`MapOverlay`] adds paths and markers on top.

mod colors;
mod fonts;
mod map;
mod overlay;
pub mod profile;

pub use colors::{TERRAIN_COLORS, color_at};
pub use fonts::{FAMILY, ensure_registered};
pub use map::render_map;
pub use overlay::{ColorBar, MapOverlay, OverlayMarker, OverlayPath};
