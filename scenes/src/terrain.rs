//! The terrain height map h(x, y) on a regular grid.

use serde::{Deserialize, Serialize};

/// Terrain heights on a regular grid. Sample (i, j) sits at
/// `(origin[0] + i * resolution, origin[1] + j * resolution)`; heights are stored
/// row-major with `i` fastest: `heights[j * nx + i]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeightGrid {
    /// World XY of sample (0, 0) \[m\].
    pub origin: [f64; 2],
    /// Spacing between samples \[m\] (default 0.1).
    pub resolution: f64,
    /// Samples along X.
    pub nx: usize,
    /// Samples along Y.
    pub ny: usize,
    /// Heights \[m\], `nx * ny` values, `heights[j * nx + i]`.
    pub heights: Vec<f64>,
}

impl HeightGrid {
    /// A flat grid covering `[origin, origin + size]` at height `z`.
    pub fn flat(origin: [f64; 2], size: [f64; 2], resolution: f64, z: f64) -> Self {
        let nx = (size[0] / resolution).round() as usize + 1;
        let ny = (size[1] / resolution).round() as usize + 1;
        Self {
            origin,
            resolution,
            nx,
            ny,
            heights: vec![z; nx * ny],
        }
    }

    /// Height of sample (i, j) \[m\]; indices are clamped to the grid.
    pub fn sample(&self, i: isize, j: isize) -> f64 {
        let i = i.clamp(0, self.nx as isize - 1) as usize;
        let j = j.clamp(0, self.ny as isize - 1) as usize;
        self.heights[j * self.nx + i]
    }

    /// World XY of sample (i, j).
    pub fn position(&self, i: usize, j: usize) -> [f64; 2] {
        [
            self.origin[0] + i as f64 * self.resolution,
            self.origin[1] + j as f64 * self.resolution,
        ]
    }

    /// The sample nearest to (x, y), if it is on the grid.
    pub fn cell_of(&self, x: f64, y: f64) -> Option<(usize, usize)> {
        let fi = ((x - self.origin[0]) / self.resolution).round();
        let fj = ((y - self.origin[1]) / self.resolution).round();
        (fi >= 0.0 && fj >= 0.0 && (fi as usize) < self.nx && (fj as usize) < self.ny)
            .then_some((fi as usize, fj as usize))
    }

    /// Minimum and maximum world XY covered by the grid.
    pub fn bounds(&self) -> ([f64; 2], [f64; 2]) {
        (
            self.origin,
            [
                self.origin[0] + (self.nx - 1) as f64 * self.resolution,
                self.origin[1] + (self.ny - 1) as f64 * self.resolution,
            ],
        )
    }

    /// Whether (x, y) is inside the grid's bounds.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        let (lo, hi) = self.bounds();
        x >= lo[0] && y >= lo[1] && x <= hi[0] && y <= hi[1]
    }

    /// Bilinear height at (x, y) \[m\]; outside the grid the edge value is extended.
    pub fn height_at(&self, x: f64, y: f64) -> f64 {
        let fx = ((x - self.origin[0]) / self.resolution).clamp(0.0, (self.nx - 1) as f64);
        let fy = ((y - self.origin[1]) / self.resolution).clamp(0.0, (self.ny - 1) as f64);
        let i0 = (fx.floor() as isize).min(self.nx as isize - 2).max(0);
        let j0 = (fy.floor() as isize).min(self.ny as isize - 2).max(0);
        let tx = fx - i0 as f64;
        let ty = fy - j0 as f64;
        let h00 = self.sample(i0, j0);
        let h10 = self.sample(i0 + 1, j0);
        let h01 = self.sample(i0, j0 + 1);
        let h11 = self.sample(i0 + 1, j0 + 1);
        (h00 * (1.0 - tx) + h10 * tx) * (1.0 - ty) + (h01 * (1.0 - tx) + h11 * tx) * ty
    }

    /// Gradient (dh/dx, dh/dy) at (x, y) by central differences over one cell.
    pub fn gradient_at(&self, x: f64, y: f64) -> [f64; 2] {
        let r = self.resolution;
        [
            (self.height_at(x + 0.5 * r, y) - self.height_at(x - 0.5 * r, y)) / r,
            (self.height_at(x, y + 0.5 * r) - self.height_at(x, y - 0.5 * r)) / r,
        ]
    }

    /// Unit surface normal at (x, y).
    pub fn normal_at(&self, x: f64, y: f64) -> [f64; 3] {
        let [gx, gy] = self.gradient_at(x, y);
        let n = (gx * gx + gy * gy + 1.0).sqrt();
        [-gx / n, -gy / n, 1.0 / n]
    }

    /// Slope angle at (x, y) \[rad\], 0 on flat ground.
    pub fn slope_at(&self, x: f64, y: f64) -> f64 {
        let [gx, gy] = self.gradient_at(x, y);
        (gx * gx + gy * gy).sqrt().atan()
    }

    /// Lowest and highest sample.
    pub fn height_range(&self) -> (f64, f64) {
        self.heights
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &h| {
                (lo.min(h), hi.max(h))
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> HeightGrid {
        // h = 0.5 x + 0.25 y on a 11 x 11 grid with 0.1 m spacing.
        let mut g = HeightGrid::flat([0.0, 0.0], [1.0, 1.0], 0.1, 0.0);
        for j in 0..g.ny {
            for i in 0..g.nx {
                let [x, y] = g.position(i, j);
                g.heights[j * g.nx + i] = 0.5 * x + 0.25 * y;
            }
        }
        g
    }

    #[test]
    fn bilinear_is_exact_on_a_plane() {
        let g = ramp();
        for &(x, y) in &[(0.0, 0.0), (0.33, 0.71), (0.99, 0.05), (0.5, 0.5)] {
            assert!((g.height_at(x, y) - (0.5 * x + 0.25 * y)).abs() < 1e-12);
        }
        // Outside: edge value extended.
        assert!((g.height_at(2.0, 0.0) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn bilinear_between_four_samples() {
        let mut g = HeightGrid::flat([0.0, 0.0], [0.1, 0.1], 0.1, 0.0);
        g.heights = vec![0.0, 1.0, 2.0, 4.0]; // (0,0) (1,0) (0,1) (1,1)
        // At (0.05, 0.05): mean of the four = 1.75.
        assert!((g.height_at(0.05, 0.05) - 1.75).abs() < 1e-12);
        assert!((g.height_at(0.1, 0.05) - 2.5).abs() < 1e-12);
    }

    #[test]
    fn gradient_normal_and_slope_of_a_plane() {
        let g = ramp();
        let [gx, gy] = g.gradient_at(0.5, 0.5);
        assert!((gx - 0.5).abs() < 1e-9 && (gy - 0.25).abs() < 1e-9);
        let n = g.normal_at(0.5, 0.5);
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        assert!((len - 1.0).abs() < 1e-12 && n[0] < 0.0 && n[2] > 0.0);
        let expected = (0.5f64.powi(2) + 0.25f64.powi(2)).sqrt().atan();
        assert!((g.slope_at(0.5, 0.5) - expected).abs() < 1e-9);
    }

    #[test]
    fn cells_and_bounds() {
        let g = ramp();
        assert_eq!(g.cell_of(0.52, 0.49), Some((5, 5)));
        assert_eq!(g.cell_of(-0.2, 0.0), None);
        assert_eq!(g.bounds(), ([0.0, 0.0], [1.0, 1.0]));
    }
}
