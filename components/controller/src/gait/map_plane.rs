//! The least-squares plane through the local height map: the ground's level and slope
//! under the body, with treads and gravel averaged out (the biped's ramp under its
//! feet, the crawl's measure of stepped ground).

use crate::math::ramp_past;
use plamo_scenes::{LOCAL_MAP_SIDE, LOCAL_MAP_SPACING};

/// Distance of the map's first and last rows (and columns) from its centre \[m\].
pub(crate) const MAP_HALF: f64 = (LOCAL_MAP_SIDE as f64 - 1.0) / 2.0 * LOCAL_MAP_SPACING;

/// Distance of map row (or column) `i`'s samples from the map's centre \[m\].
pub(crate) fn map_coord(i: usize) -> f64 {
    (i as f64 - (LOCAL_MAP_SIDE as f64 - 1.0) / 2.0) * LOCAL_MAP_SPACING
}

/// `mean + forward * x + lateral * y`, x along the map's rows (forward), y along its
/// columns (left), both from its centre \[m\].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MapPlane {
    /// Mean height \[m\].
    pub mean: f64,
    /// Rise over run forward \[1\].
    pub forward: f64,
    /// Rise over run to the left \[1\].
    pub lateral: f64,
}

impl MapPlane {
    /// The plane fitted to a local height map (`LOCAL_MAP_SIDE`^2 samples, row-major).
    pub(crate) fn fit(map: &[f64]) -> Self {
        // The grid is symmetric about its centre, so the mean and the two slopes
        // separate: each slope is the line through the row (column) means.
        let n = LOCAL_MAP_SIDE as f64;
        let (mut sum, mut sx, mut sy, mut ss) = (0.0, 0.0, 0.0, 0.0);
        for k in 0..LOCAL_MAP_SIDE {
            let x = map_coord(k);
            let row: f64 = map[k * LOCAL_MAP_SIDE..(k + 1) * LOCAL_MAP_SIDE]
                .iter()
                .sum();
            let column: f64 = (0..LOCAL_MAP_SIDE)
                .map(|r| map[r * LOCAL_MAP_SIDE + k])
                .sum();
            sum += row;
            sx += x * row / n;
            sy += x * column / n;
            ss += x * x;
        }
        Self {
            mean: sum / (n * n),
            forward: sx / ss,
            lateral: sy / ss,
        }
    }

    /// Height of the plane at (x, y) \[m\].
    pub(crate) fn at(&self, x: f64, y: f64) -> f64 {
        self.mean + self.forward * x + self.lateral * y
    }

    /// Largest distance of a sample of `map` from its least-squares plane \[m\]: a
    /// step or a bump, not a slope (stepped ground and gravel for the crawl's
    /// slowdown and the biped's longer steps).
    pub(crate) fn roughness(map: &[f64]) -> f64 {
        let plane = Self::fit(map);
        let mut worst: f64 = 0.0;
        for r in 0..LOCAL_MAP_SIDE {
            for c in 0..LOCAL_MAP_SIDE {
                let h = map[r * LOCAL_MAP_SIDE + c];
                worst = worst.max((h - plane.at(map_coord(r), map_coord(c))).abs());
            }
        }
        worst
    }

    /// Share of rough ground under `map`, 0-1: its [`roughness`](Self::roughness)
    /// from `step` \[m\] (0) to twice it (1).
    pub(crate) fn rough_share(map: &[f64], step: f64) -> f64 {
        ramp_past(Self::roughness(map), step)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plane_is_fitted_exactly() {
        let mut map = [0.0; LOCAL_MAP_SIDE * LOCAL_MAP_SIDE];
        for r in 0..LOCAL_MAP_SIDE {
            for c in 0..LOCAL_MAP_SIDE {
                map[r * LOCAL_MAP_SIDE + c] = 0.3 + 0.2 * map_coord(r) - 0.1 * map_coord(c);
            }
        }
        let p = MapPlane::fit(&map);
        assert!((p.mean - 0.3).abs() < 1e-12);
        assert!((p.forward - 0.2).abs() < 1e-12);
        assert!((p.lateral + 0.1).abs() < 1e-12);
        assert!((p.at(map_coord(7), map_coord(0)) - map[7 * LOCAL_MAP_SIDE]).abs() < 1e-12);
    }
}
