//! Oriented rectangles in the XY plane: the footprint of walls, ceilings and regions.

use serde::{Deserialize, Serialize};

/// An oriented rectangle in the XY plane.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Footprint {
    /// Centre \[m\].
    pub center: [f64; 2],
    /// Half extents along the rectangle's own x and y axes \[m\], both > 0.
    pub half_extents: [f64; 2],
    /// Rotation about +Z \[rad\], counter-clockwise from world +X.
    pub yaw: f64,
}

impl Footprint {
    /// Axis-aligned rectangle.
    pub fn axis_aligned(center: [f64; 2], half_extents: [f64; 2]) -> Self {
        Self {
            center,
            half_extents,
            yaw: 0.0,
        }
    }

    /// The rectangle with its rotation's sine and cosine worked out once, for
    /// callers that ask for many distances to it.
    pub fn frame(&self) -> FootprintFrame {
        let (sin, cos) = self.yaw.sin_cos();
        FootprintFrame {
            footprint: *self,
            sin,
            cos,
        }
    }

    /// The point expressed in the rectangle's frame.
    pub fn to_local(&self, x: f64, y: f64) -> [f64; 2] {
        self.frame().to_local(x, y)
    }

    /// Signed distance from (x, y) to the rectangle: negative inside \[m\].
    pub fn signed_distance(&self, x: f64, y: f64) -> f64 {
        self.frame().signed_distance(x, y)
    }

    /// Whether (x, y) lies inside or on the boundary.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        self.signed_distance(x, y) <= 0.0
    }

    /// The four corners, counter-clockwise.
    pub fn corners(&self) -> [[f64; 2]; 4] {
        let (s, c) = self.yaw.sin_cos();
        let [hx, hy] = self.half_extents;
        [[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]].map(|[lx, ly]| {
            [
                self.center[0] + c * lx - s * ly,
                self.center[1] + s * lx + c * ly,
            ]
        })
    }

    /// Axis-aligned bounding box as (min, max).
    pub fn aabb(&self) -> ([f64; 2], [f64; 2]) {
        let cs = self.corners();
        let mut lo = cs[0];
        let mut hi = cs[0];
        for p in &cs[1..] {
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
        (lo, hi)
    }
}

/// A [`Footprint`] with the sine and cosine of its yaw (from [`Footprint::frame`]):
/// the same distances without a `sin_cos` per query, which was 44% of the planner's
/// grid build on the playground (its footprint checks ask ~10^6 distances to walls).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FootprintFrame {
    footprint: Footprint,
    sin: f64,
    cos: f64,
}

impl FootprintFrame {
    /// The point expressed in the rectangle's frame.
    pub fn to_local(&self, x: f64, y: f64) -> [f64; 2] {
        let (s, c) = (self.sin, self.cos);
        let dx = x - self.footprint.center[0];
        let dy = y - self.footprint.center[1];
        [c * dx + s * dy, -s * dx + c * dy]
    }

    /// Whether every point within `reach` of (x, y) lies further than `clear` from
    /// the rectangle \[m\]: a sure answer from its bounding circle, without a
    /// distance per point (false may still be clear).
    pub fn clear_of_disc(&self, x: f64, y: f64, reach: f64, clear: f64) -> bool {
        let [cx, cy] = self.footprint.center;
        let [hx, hy] = self.footprint.half_extents;
        // The rectangle lies within hypot(hx, hy) of its centre; the margin keeps
        // rounding from ever skipping a distance the exact test would need.
        (x - cx).hypot(y - cy) - hx.hypot(hy) - reach > clear + 1e-6
    }

    /// Signed distance from (x, y) to the rectangle: negative inside \[m\].
    pub fn signed_distance(&self, x: f64, y: f64) -> f64 {
        let [lx, ly] = self.to_local(x, y);
        let qx = lx.abs() - self.footprint.half_extents[0];
        let qy = ly.abs() - self.footprint.half_extents[1];
        let outside = (qx.max(0.0).powi(2) + qy.max(0.0).powi(2)).sqrt();
        let inside = qx.max(qy).min(0.0);
        outside + inside
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_disc_clear_of_the_bounding_circle_is_clear_of_the_box() {
        let f = Footprint {
            center: [1.0, 1.0],
            half_extents: [2.0, 0.5],
            yaw: 0.3,
        }
        .frame();
        let (reach, clear) = (1.3, 0.25);
        let mut skipped = 0;
        for i in -40..=40 {
            for j in -40..=40 {
                let (x, y) = (1.0 + 0.15 * i as f64, 1.0 + 0.15 * j as f64);
                if !f.clear_of_disc(x, y, reach, clear) {
                    continue;
                }
                skipped += 1;
                // Every point of the disc's rim and centre is clear.
                for k in 0..32 {
                    let a = k as f64 * std::f64::consts::TAU / 32.0;
                    let (px, py) = (x + reach * a.cos(), y + reach * a.sin());
                    assert!(f.signed_distance(px, py) > clear, "({x}, {y}) at {a}");
                }
            }
        }
        // Far enough out, most centres are skipped; near the box none is.
        assert!(skipped > 3000, "{skipped}");
        assert!(!f.clear_of_disc(1.0, 1.0, reach, clear));
        assert!(!f.clear_of_disc(1.0, 2.9, reach, clear));
    }

    #[test]
    fn signed_distance_of_rotated_box() {
        let f = Footprint {
            center: [1.0, 1.0],
            half_extents: [2.0, 0.5],
            yaw: std::f64::consts::FRAC_PI_2,
        };
        // Rotated 90 degrees: long axis along world Y.
        assert!((f.signed_distance(1.0, 1.0) + 0.5).abs() < 1e-12);
        assert!((f.signed_distance(1.0, 4.0) - 1.0).abs() < 1e-12);
        assert!((f.signed_distance(2.5, 1.0) - 1.0).abs() < 1e-12);
        assert!(f.contains(1.2, 2.9));
        assert!(!f.contains(1.6, 1.0));
        let (lo, hi) = f.aabb();
        assert!((lo[0] - 0.5).abs() < 1e-12 && (hi[1] - 3.0).abs() < 1e-12);
    }
}
