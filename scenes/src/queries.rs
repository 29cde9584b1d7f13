//! Queries the planner, controller and physics read from a scene.

use crate::{Landmark, ObstacleState, Scene};

/// Samples per side of the controller's local height map (paper 4.2: 8 x 8).
pub const LOCAL_MAP_SIDE: usize = 8;
/// Samples in the local height map.
pub const LOCAL_MAP_SAMPLES: usize = LOCAL_MAP_SIDE * LOCAL_MAP_SIDE;
/// Spacing of the local height map \[m\]: 8 samples span 0.8 m.
pub const LOCAL_MAP_SPACING: f64 = 0.1;

/// The controller's local height map: `values[r * 8 + c]` is the terrain height
/// minus the reference height at forward offset `(r - 3.5) * 0.1` m and left offset
/// `(c - 3.5) * 0.1` m in the heading frame.
pub type LocalHeightMap = [f64; LOCAL_MAP_SAMPLES];

impl Scene {
    /// Terrain height at (x, y), bilinear \[m\].
    pub fn height_at(&self, x: f64, y: f64) -> f64 {
        self.terrain.height_at(x, y)
    }

    /// Terrain slope angle at (x, y) \[rad\].
    pub fn slope_at(&self, x: f64, y: f64) -> f64 {
        self.terrain.slope_at(x, y)
    }

    /// Terrain unit normal at (x, y).
    pub fn normal_at(&self, x: f64, y: f64) -> [f64; 3] {
        self.terrain.normal_at(x, y)
    }

    /// The lowest ceiling (top-obstacle underside) above (x, y), if any \[m\].
    pub fn ceiling_at(&self, x: f64, y: f64) -> Option<f64> {
        self.tops
            .iter()
            .filter(|t| t.footprint.contains(x, y))
            .map(|t| t.z_bottom)
            .fold(None, |acc: Option<f64>, z| {
                Some(acc.map_or(z, |a| a.min(z)))
            })
    }

    /// Free height under the ceiling at (x, y): ceiling minus terrain \[m\], or
    /// `None` under open sky.
    pub fn headroom_at(&self, x: f64, y: f64) -> Option<f64> {
        self.ceiling_at(x, y).map(|c| c - self.height_at(x, y))
    }

    /// Lowest free height under the tops whose footprint comes within `distance` of
    /// (x, y), over the terrain at (x, y) \[m\], or `None` with no top that near: the
    /// room a body reaching `distance` from (x, y) has.
    pub fn headroom_near(&self, x: f64, y: f64, distance: f64) -> Option<f64> {
        let ground = self.height_at(x, y);
        self.tops
            .iter()
            .filter(|t| t.footprint.signed_distance(x, y) < distance)
            .map(|t| t.z_bottom - ground)
            .reduce(f64::min)
    }

    /// Signed distance from (x, y) to the nearest wall, negative inside one \[m\];
    /// `f64::INFINITY` when there are no walls.
    pub fn wall_clearance(&self, x: f64, y: f64) -> f64 {
        self.walls
            .iter()
            .map(|w| w.footprint.signed_distance(x, y))
            .fold(f64::INFINITY, f64::min)
    }

    /// Whether (x, y) is inside a wall.
    pub fn in_wall(&self, x: f64, y: f64) -> bool {
        self.wall_clearance(x, y) <= 0.0
    }

    /// The landmark with this name (case-insensitive).
    pub fn landmark(&self, name: &str) -> Option<&Landmark> {
        self.landmarks
            .iter()
            .find(|l| l.name.eq_ignore_ascii_case(name))
    }

    /// Names of all landmarks, in file order.
    pub fn landmark_names(&self) -> Vec<&str> {
        self.landmarks.iter().map(|l| l.name.as_str()).collect()
    }

    /// Grid cells (i, j) of the terrain that lie in the landmark's region.
    pub fn landmark_cells(&self, landmark: &Landmark) -> Vec<(usize, usize)> {
        let g = &self.terrain;
        let (lo, hi) = landmark.region.aabb();
        let i0 = (((lo[0] - g.origin[0]) / g.resolution).floor().max(0.0)) as usize;
        let j0 = (((lo[1] - g.origin[1]) / g.resolution).floor().max(0.0)) as usize;
        let i1 = (((hi[0] - g.origin[0]) / g.resolution).ceil().max(0.0) as usize).min(g.nx - 1);
        let j1 = (((hi[1] - g.origin[1]) / g.resolution).ceil().max(0.0) as usize).min(g.ny - 1);
        let mut cells = Vec::new();
        for j in j0..=j1 {
            for i in i0..=i1 {
                let [x, y] = g.position(i, j);
                if landmark.region.contains(x, y) {
                    cells.push((i, j));
                }
            }
        }
        cells
    }

    /// State of every dynamic obstacle at time `t` \[s\], in scene order.
    pub fn obstacle_states_at(&self, t: f64) -> Vec<ObstacleState> {
        self.dynamic.iter().map(|d| d.motion.state_at(t)).collect()
    }

    /// The controller's local height map around (x, y), rotated to `heading` \[rad\]
    /// (from +X, counter-clockwise) and relative to `reference_z` \[m\].
    pub fn local_height_map(
        &self,
        x: f64,
        y: f64,
        heading: f64,
        reference_z: f64,
    ) -> LocalHeightMap {
        let mut out = [0.0; LOCAL_MAP_SAMPLES];
        let first = -(LOCAL_MAP_SIDE as f64 - 1.0) / 2.0;
        self.local_heights_into(x, y, heading, reference_z, first, &mut out);
        out
    }

    /// Rows of [`LOCAL_MAP_SIDE`] terrain samples laid out as the local height map's
    /// (same columns and spacing, rotated to `heading`, relative to `reference_z`),
    /// the first row `first_row` spacings ahead of (x, y): `out[r * 8 + c]` lies
    /// `(first_row + r) * 0.1` m forward. As many rows as `out` holds (whole rows);
    /// the controller's map is the 8 rows from -3.5 (-0.35 m).
    pub fn local_heights_into(
        &self,
        x: f64,
        y: f64,
        heading: f64,
        reference_z: f64,
        first_row: f64,
        out: &mut [f64],
    ) {
        let (s, c) = heading.sin_cos();
        let half = (LOCAL_MAP_SIDE as f64 - 1.0) / 2.0;
        for (r, row) in out.chunks_exact_mut(LOCAL_MAP_SIDE).enumerate() {
            let fwd = (first_row + r as f64) * LOCAL_MAP_SPACING;
            for (col, v) in row.iter_mut().enumerate() {
                let left = (col as f64 - half) * LOCAL_MAP_SPACING;
                let wx = x + c * fwd - s * left;
                let wy = y + s * fwd + c * left;
                *v = self.height_at(wx, wy) - reference_z;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Footprint, HeightGrid, Landmark, Region, TopObstacle, Wall};

    fn scene_with(grid: HeightGrid) -> Scene {
        Scene {
            name: "t".into(),
            description: String::new(),
            terrain: grid,
            walls: vec![Wall {
                name: "w".into(),
                footprint: Footprint::axis_aligned([5.0, 5.0], [1.0, 0.5]),
                z_min: -1.0,
                z_max: 2.0,
            }],
            dynamic: vec![],
            tops: vec![
                TopObstacle {
                    name: "a".into(),
                    footprint: Footprint::axis_aligned([2.0, 2.0], [1.0, 1.0]),
                    z_bottom: 1.0,
                    z_top: 1.2,
                },
                TopObstacle {
                    name: "b".into(),
                    footprint: Footprint::axis_aligned([2.5, 2.0], [1.0, 1.0]),
                    z_bottom: 0.7,
                    z_top: 0.9,
                },
            ],
            landmarks: vec![Landmark {
                name: "Tree".into(),
                region: Region::Circle {
                    center: [8.0, 8.0],
                    radius: 0.25,
                },
            }],
        }
    }

    /// h = 0.2 x - 0.1 y on a 10 m x 10 m grid.
    fn plane() -> HeightGrid {
        let mut g = HeightGrid::flat([0.0, 0.0], [10.0, 10.0], 0.1, 0.0);
        for j in 0..g.ny {
            for i in 0..g.nx {
                let [x, y] = g.position(i, j);
                g.heights[j * g.nx + i] = 0.2 * x - 0.1 * y;
            }
        }
        g
    }

    #[test]
    fn ceiling_is_the_lowest_top_and_headroom_subtracts_terrain() {
        let s = scene_with(HeightGrid::flat([0.0, 0.0], [10.0, 10.0], 0.1, 0.25));
        assert_eq!(s.ceiling_at(1.2, 2.0), Some(1.0));
        assert_eq!(s.ceiling_at(2.2, 2.0), Some(0.7));
        assert_eq!(s.ceiling_at(9.0, 9.0), None);
        assert!((s.headroom_at(2.2, 2.0).unwrap() - 0.45).abs() < 1e-12);
        // 0.2 m west of top a, 0.7 m west of the lower top b.
        assert!((s.headroom_near(0.8, 2.0, 0.3).unwrap() - 0.75).abs() < 1e-12);
        assert!((s.headroom_near(0.8, 2.0, 1.0).unwrap() - 0.45).abs() < 1e-12);
        assert_eq!(s.headroom_near(0.8, 2.0, 0.1), None);
    }

    #[test]
    fn wall_clearance_is_signed() {
        let s = scene_with(HeightGrid::flat([0.0, 0.0], [10.0, 10.0], 0.1, 0.0));
        assert!((s.wall_clearance(5.0, 7.0) - 1.5).abs() < 1e-12);
        assert!((s.wall_clearance(5.0, 5.0) + 0.5).abs() < 1e-12);
        assert!(s.in_wall(5.9, 5.4));
        assert!(!s.in_wall(6.1, 5.0));
    }

    #[test]
    fn landmark_lookup_and_cells() {
        let s = scene_with(HeightGrid::flat([0.0, 0.0], [10.0, 10.0], 0.1, 0.0));
        let l = s.landmark("tree").expect("case-insensitive");
        let cells = s.landmark_cells(l);
        // Grid points within 0.25 m of (8, 8) at 0.1 m spacing: 21 points
        // (offsets with dx^2 + dy^2 <= 6.25 cells^2).
        assert_eq!(cells.len(), 21);
        assert!(cells.contains(&(80, 80)));
        assert!(cells.iter().all(|&(i, j)| {
            let [x, y] = s.terrain.position(i, j);
            (x - 8.0).powi(2) + (y - 8.0).powi(2) <= 0.0625 + 1e-12
        }));
    }

    #[test]
    fn local_height_map_rotates_with_heading() {
        let s = scene_with(plane());
        let (x, y, z0) = (5.0, 5.0, 0.3);
        // Heading +X: row r is forward along +X, column c is left along +Y.
        let m = s.local_height_map(x, y, 0.0, z0);
        for r in 0..8 {
            for c in 0..8 {
                let fwd = (r as f64 - 3.5) * 0.1;
                let left = (c as f64 - 3.5) * 0.1;
                let h = 0.2 * (x + fwd) - 0.1 * (y + left) - z0;
                assert!((m[r * 8 + c] - h).abs() < 1e-9, "r{r} c{c}");
            }
        }
        // Hand-computed corner values at heading +Y (90 deg): forward is +Y, left is -X.
        let m = s.local_height_map(x, y, std::f64::consts::FRAC_PI_2, z0);
        // r = 7, c = 0: fwd = +0.35 (y + 0.35), left = -0.35 -> x + 0.35.
        let expect = 0.2 * 5.35 - 0.1 * 5.35 - 0.3;
        assert!((m[7 * 8] - expect).abs() < 1e-9);
        // r = 0, c = 7: fwd = -0.35 (y - 0.35), left = +0.35 -> x - 0.35.
        let expect = 0.2 * 4.65 - 0.1 * 4.65 - 0.3;
        assert!((m[7] - expect).abs() < 1e-9);
    }

    #[test]
    fn rows_ahead_continue_the_map_on_the_same_columns() {
        let s = scene_with(plane());
        let (x, y, z0, heading) = (5.0, 5.0, 0.3, 0.7);
        let map = s.local_height_map(x, y, heading, z0);
        // Rows 4.5 .. 8.5 spacings ahead: the first overlaps nothing, and 8 rows from
        // -3.5 are the map itself, value for value.
        let mut same = [0.0; LOCAL_MAP_SAMPLES];
        s.local_heights_into(x, y, heading, z0, -3.5, &mut same);
        assert_eq!(same, map);
        let mut ahead = [0.0; 5 * LOCAL_MAP_SIDE];
        s.local_heights_into(x, y, heading, z0, 4.5, &mut ahead);
        let (sn, cs) = heading.sin_cos();
        for r in 0..5 {
            for c in 0..8 {
                let fwd = (4.5 + r as f64) * 0.1;
                let left = (c as f64 - 3.5) * 0.1;
                let (wx, wy) = (x + cs * fwd - sn * left, y + sn * fwd + cs * left);
                let h = 0.2 * wx - 0.1 * wy - z0;
                assert!((ahead[r * 8 + c] - h).abs() < 1e-9, "r{r} c{c}");
            }
        }
        // The first row ahead is one spacing beyond the map's front row.
        let step = ahead[3] - map[7 * 8 + 3];
        assert!((step - 0.1 * (0.2 * cs - 0.1 * sn)).abs() < 1e-9, "{step}");
    }
}
