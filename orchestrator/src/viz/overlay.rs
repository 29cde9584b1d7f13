//! What callers draw on top of a scene map.

/// Things to draw over a scene map, and its title.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MapOverlay {
    /// Polylines (planned paths, executed trajectories), drawn in order.
    pub paths: Vec<OverlayPath>,
    /// Points of interest (start, goal, failure), drawn after the paths.
    pub markers: Vec<OverlayMarker>,
    /// Title above the map; empty: the scene's name and description.
    pub title: String,
    /// A colour bar explaining `OverlayPath::colors` (e.g. speed), drawn beside the
    /// terrain's.
    pub colorbar: Option<ColorBar>,
}

/// A polyline in world XY \[m\].
#[derive(Debug, Clone, PartialEq)]
pub struct OverlayPath {
    /// Vertices \[m\].
    pub points: Vec<[f64; 2]>,
    /// One colour for the whole path, or one per point (segment k takes colour k).
    pub colors: Vec<[u8; 3]>,
    /// Line width \[px\].
    pub width: u32,
    /// Draw dashed.
    pub dashed: bool,
    /// Legend entry, if any.
    pub label: Option<String>,
}

/// A labelled dot in world XY \[m\].
#[derive(Debug, Clone, PartialEq)]
pub struct OverlayMarker {
    /// Position \[m\].
    pub at: [f64; 2],
    /// Fill colour.
    pub color: [u8; 3],
    /// Text beside it, if any.
    pub label: Option<String>,
}

/// A colour scale: `colors` evenly spread from `min` (first) to `max` (last).
#[derive(Debug, Clone, PartialEq)]
pub struct ColorBar {
    /// What the colours mean, with unit ("speed [m/s]").
    pub label: String,
    /// Value of the first colour.
    pub min: f64,
    /// Value of the last colour.
    pub max: f64,
    /// At least one colour.
    pub colors: Vec<[u8; 3]>,
}

impl OverlayPath {
    /// Colour of segment `k` (from point k to k + 1).
    pub fn color_of_segment(&self, k: usize) -> [u8; 3] {
        match self.colors.len() {
            0 => [0, 0, 0],
            1 => self.colors[0],
            n => self.colors[k.min(n - 1)],
        }
    }
}

impl ColorBar {
    /// The colour for `value`, linearly interpolated and clamped to the ends.
    pub fn color_for(&self, value: f64) -> [u8; 3] {
        let t = if self.max > self.min {
            (value - self.min) / (self.max - self.min)
        } else {
            0.5
        };
        super::colors::color_at(&self.colors, t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_colours_and_colour_bar_lookup() {
        let p = OverlayPath {
            points: vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]],
            colors: vec![[1, 1, 1], [2, 2, 2]],
            width: 2,
            dashed: false,
            label: None,
        };
        assert_eq!(p.color_of_segment(0), [1, 1, 1]);
        assert_eq!(p.color_of_segment(5), [2, 2, 2]);
        let bar = ColorBar {
            label: "speed [m/s]".into(),
            min: 0.0,
            max: 2.0,
            colors: vec![[0, 0, 0], [200, 100, 0]],
        };
        assert_eq!(bar.color_for(1.0), [100, 50, 0]);
        assert_eq!(bar.color_for(-5.0), [0, 0, 0]);
        assert_eq!(bar.color_for(9.0), [200, 100, 0]);
    }
}
