//! Triangle meshes of the physics shapes (capsules, spheres, boxes), the terrain
//! height map and the scene's boxes, in f32 as glTF stores them.

use std::f64::consts::PI;

use plamo_physics::humanoid::Shape;
use plamo_scenes::{Footprint, HeightGrid};

/// An indexed triangle mesh with per-vertex normals and optional colours.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals.
    pub normals: Vec<[f32; 3]>,
    /// Linear RGB vertex colours (empty: none).
    pub colors: Vec<[f32; 3]>,
    /// Counter-clockwise triangles (outward normals).
    pub indices: Vec<u32>,
}

fn f32x3(v: [f64; 3]) -> [f32; 3] {
    v.map(|c| c as f32)
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    a.map(|c| c * s)
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalize(a: [f64; 3]) -> [f64; 3] {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    if n > 0.0 { scale(a, 1.0 / n) } else { a }
}

impl Mesh {
    /// Append another mesh.
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.colors.extend_from_slice(&other.colors);
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }

    /// A capsule around the segment `from`-`to` (a sphere when they coincide).
    pub fn capsule(from: [f64; 3], to: [f64; 3], radius: f64) -> Mesh {
        const SEG: usize = 16;
        const RINGS: usize = 6;
        let d = [to[0] - from[0], to[1] - from[1], to[2] - from[2]];
        let axis = if d.iter().map(|c| c * c).sum::<f64>() > 1e-18 {
            normalize(d)
        } else {
            [0.0, 0.0, 1.0]
        };
        let helper = if axis[2].abs() < 0.9 {
            [0.0, 0.0, 1.0]
        } else {
            [1.0, 0.0, 0.0]
        };
        let u = normalize(cross(axis, helper));
        let v = cross(axis, u);
        // Profile from the `from` pole to the `to` pole: (centre, elevation angle).
        let mut profile: Vec<([f64; 3], f64)> = Vec::new();
        for i in 0..=RINGS {
            profile.push((from, -PI / 2.0 + PI / 2.0 * i as f64 / RINGS as f64));
        }
        // A sphere (from == to) has no cylinder band: its equator ring is shared.
        let first = usize::from(from == to);
        for i in first..=RINGS {
            profile.push((to, PI / 2.0 * i as f64 / RINGS as f64));
        }
        let mut m = Mesh::default();
        for (r, &(c, phi)) in profile.iter().enumerate() {
            let pole = r == 0 || r == profile.len() - 1;
            let n_here = if pole { 1 } else { SEG + 1 };
            for k in 0..n_here {
                let th = 2.0 * PI * k as f64 / SEG as f64;
                let radial = add(scale(u, th.cos()), scale(v, th.sin()));
                let n = if pole {
                    scale(axis, phi.sin().signum())
                } else {
                    add(scale(radial, phi.cos()), scale(axis, phi.sin()))
                };
                m.positions.push(f32x3(add(c, scale(n, radius))));
                m.normals.push(f32x3(n));
            }
        }
        // Ring r starts at: pole 0 has 1 vertex, then rings of SEG + 1.
        let start = |r: usize| if r == 0 { 0 } else { 1 + (r - 1) * (SEG + 1) };
        let last = profile.len() - 1;
        for r in 0..last {
            for k in 0..SEG {
                let (a0, a1) = (start(r) + k, start(r) + k + 1);
                let (b0, b1) = (start(r + 1) + k, start(r + 1) + k + 1);
                if r == 0 {
                    m.indices.extend([0, b1 as u32, b0 as u32]);
                } else if r + 1 == last {
                    m.indices.extend([a0 as u32, a1 as u32, start(last) as u32]);
                } else {
                    m.indices.extend([
                        a0 as u32, a1 as u32, b1 as u32, a0 as u32, b1 as u32, b0 as u32,
                    ]);
                }
            }
        }
        m
    }

    /// A box given its centre, half extents and yaw about +Z.
    pub fn cuboid(center: [f64; 3], half: [f64; 3], yaw: f64) -> Mesh {
        let (s, c) = yaw.sin_cos();
        let rot = |p: [f64; 3]| [c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]];
        let mut m = Mesh::default();
        for axis in 0..3 {
            for sign in [-1.0, 1.0] {
                let mut n = [0.0; 3];
                n[axis] = sign;
                let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
                let base = m.positions.len() as u32;
                for (da, db) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                    let mut p = [0.0; 3];
                    p[axis] = sign * half[axis];
                    p[a] = da * half[a];
                    p[b] = db * half[b];
                    m.positions.push(f32x3(add(center, rot(p))));
                    m.normals.push(f32x3(rot(n)));
                }
                // (a, b, n) is right-handed, so (0, 1, 2) faces +n; flip for -n.
                if sign > 0.0 {
                    m.indices
                        .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
                } else {
                    m.indices
                        .extend([base, base + 2, base + 1, base, base + 3, base + 2]);
                }
            }
        }
        m
    }

    /// A vertical box over a footprint from `z0` to `z1`.
    pub fn prism(fp: &Footprint, z0: f64, z1: f64) -> Mesh {
        Mesh::cuboid(
            [fp.center[0], fp.center[1], 0.5 * (z0 + z1)],
            [fp.half_extents[0], fp.half_extents[1], 0.5 * (z1 - z0)],
            fp.yaw,
        )
    }

    /// A physics shape in its body frame.
    pub fn shape(shape: &Shape) -> Mesh {
        match *shape {
            Shape::Capsule { from, to, radius } => Mesh::capsule(from, to, radius),
            Shape::Sphere { center, radius } => Mesh::capsule(center, center, radius),
            Shape::Box {
                center,
                half_extents,
            } => Mesh::cuboid(center, half_extents, 0.0),
        }
    }

    /// The terrain as a height-field mesh, every `stride`-th sample, coloured by
    /// height (low: grass green, high: earth brown) so steps and slopes read.
    pub fn terrain(h: &HeightGrid, stride: usize) -> Mesh {
        let stride = stride.max(1);
        let idx = |n: usize| -> Vec<usize> {
            let mut v: Vec<usize> = (0..n).step_by(stride).collect();
            if v.last() != Some(&(n - 1)) {
                v.push(n - 1);
            }
            v
        };
        let (is, js) = (idx(h.nx), idx(h.ny));
        let (lo, hi) = h.height_range();
        let span = (hi - lo).max(1e-6);
        let mut m = Mesh::default();
        for &j in &js {
            for &i in &is {
                let [x, y] = h.position(i, j);
                let z = h.sample(i as isize, j as isize);
                // Central differences on the full grid for smooth shading.
                let r = h.resolution;
                let dzdx = (h.sample(i as isize + 1, j as isize)
                    - h.sample(i as isize - 1, j as isize))
                    / (2.0 * r);
                let dzdy = (h.sample(i as isize, j as isize + 1)
                    - h.sample(i as isize, j as isize - 1))
                    / (2.0 * r);
                m.positions.push(f32x3([x, y, z]));
                m.normals.push(f32x3(normalize([-dzdx, -dzdy, 1.0])));
                let f = ((z - lo) / span) as f32;
                let grass = [0.20, 0.42, 0.14];
                let earth = [0.45, 0.33, 0.20];
                let mut c = [0.0f32; 3];
                for k in 0..3 {
                    c[k] = grass[k] + (earth[k] - grass[k]) * f;
                }
                // A faint checker every metre gives scale and shows motion.
                let (ci, cj) = ((x.floor() as i64), (y.floor() as i64));
                let k = if (ci + cj).rem_euclid(2) == 0 {
                    1.0
                } else {
                    0.9
                };
                m.colors.push(c.map(|v| v * k));
            }
        }
        let w = is.len() as u32;
        for j in 0..js.len() as u32 - 1 {
            for i in 0..w - 1 {
                let a = j * w + i;
                let b = a + 1;
                let c = a + w;
                let d = c + 1;
                m.indices.extend([a, b, d, a, d, c]);
            }
        }
        m
    }

    /// Minimum and maximum of the positions.
    #[cfg(test)]
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for p in &self.positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every triangle's geometric normal agrees with its vertex normals (outward
    /// winding) and none has zero area.
    fn check_winding(m: &Mesh) {
        for t in m.indices.chunks(3) {
            let p: Vec<[f64; 3]> = t
                .iter()
                .map(|&i| m.positions[i as usize].map(f64::from))
                .collect();
            let e1 = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
            let e2 = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
            let g = cross(e1, e2);
            let area = g.iter().map(|c| c * c).sum::<f64>().sqrt();
            assert!(area > 1e-9, "degenerate triangle {t:?}");
            let n: [f64; 3] = (0..3)
                .map(|k| t.iter().map(|&i| f64::from(m.normals[i as usize][k])).sum())
                .collect::<Vec<f64>>()
                .try_into()
                .unwrap();
            assert!(
                g[0] * n[0] + g[1] * n[1] + g[2] * n[2] > 0.0,
                "inward {t:?}"
            );
        }
    }

    #[test]
    fn shapes_are_closed_outward_and_sized() {
        let c = Mesh::capsule([0.0, 0.0, -0.03], [0.0, 0.0, -0.24], 0.05);
        check_winding(&c);
        let (lo, hi) = c.bounds();
        assert!((lo[2] + 0.29).abs() < 1e-6 && (hi[2] - 0.02).abs() < 1e-6);
        check_winding(&Mesh::capsule([0.0, -0.07, 0.0], [0.0, 0.07, 0.0], 0.1));
        check_winding(&Mesh::capsule([0.1; 3], [0.1; 3], 0.1));
        let b = Mesh::cuboid([0.0; 3], [1.0, 2.0, 3.0], 0.3);
        check_winding(&b);
        let (lo, hi) = Mesh::cuboid([0.0; 3], [1.0, 2.0, 3.0], 0.0).bounds();
        assert_eq!((lo, hi), ([-1.0, -2.0, -3.0], [1.0, 2.0, 3.0]));
    }

    #[test]
    fn terrain_follows_the_height_map() {
        let mut h = HeightGrid::flat([0.0, 0.0], [2.0, 1.0], 0.1, 0.0);
        h.heights[5] = 0.3;
        let m = Mesh::terrain(&h, 1);
        assert_eq!(m.positions.len(), h.nx * h.ny);
        assert_eq!(m.positions[5], [0.5, 0.0, 0.3]);
        check_winding(&m);
        let coarse = Mesh::terrain(&h, 3);
        // Edges are kept: the last sample of each row is always included.
        assert!(coarse.positions.iter().any(|p| p[0] == 2.0 && p[1] == 1.0));
    }
}
