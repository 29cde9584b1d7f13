//! Terrain generators: each writes heights into a [`HeightGrid`] over an area.
//! Tiles of different generators compose a terrain (see [`crate::file_format::Tile`]).
//!
//! All generators are pure functions of their parameters and the sample position, so
//! the same file always gives the same heights (the rough generator hashes its seed
//! with the lattice index instead of drawing from a stream).

use serde::{Deserialize, Serialize};

use crate::HeightGrid;
use crate::SceneError;
use crate::file_format::{Area, BlendMode};

fn default_feature() -> f64 {
    0.1
}

/// Shape of a hill's profile.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HillProfile {
    /// Smooth: `height * (1 + cos(pi * r / radius)) / 2`.
    #[default]
    Cosine,
    /// A cone: linear in the distance from the centre.
    Cone,
    /// A square pyramid: linear in the larger of |dx| and |dy|.
    Pyramid,
}

/// A terrain generator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Generator {
    /// Constant height.
    Flat {
        /// Height \[m\].
        height: f64,
    },
    /// A ramp rising at `angle_deg` towards `direction_deg`, starting at the area's
    /// edge; `symmetric` makes it a ridge that comes back down at the far edge.
    Slope {
        /// Inclination \[deg\], 0 ..= 45.
        angle_deg: f64,
        /// Uphill direction \[deg\] counter-clockwise from +X.
        #[serde(default)]
        direction_deg: f64,
        /// Rise to the middle, then fall.
        #[serde(default)]
        symmetric: bool,
    },
    /// Gravel: value noise in \[-amplitude, amplitude\] on a lattice of
    /// `feature_size`, interpolated bilinearly.
    Rough {
        /// Half the peak-to-peak height \[m\], 0 ..= 0.2.
        amplitude: f64,
        /// Noise seed.
        #[serde(default)]
        seed: u64,
        /// Lattice spacing \[m\], default 0.1.
        #[serde(default = "default_feature")]
        feature_size: f64,
    },
    /// Steps of `step_height` every `step_depth` towards `direction_deg`;
    /// `steps` caps the count (a landing after), `symmetric` goes back down.
    Stairs {
        /// Riser \[m\], 0 < h <= 0.5.
        step_height: f64,
        /// Tread \[m\], >= 0.1.
        step_depth: f64,
        /// Uphill direction \[deg\].
        #[serde(default)]
        direction_deg: f64,
        /// At most this many steps.
        #[serde(default)]
        steps: Option<u32>,
        /// Rise to the middle, then fall.
        #[serde(default)]
        symmetric: bool,
    },
    /// A hill (or pyramid) around `center`.
    Hill {
        /// Top \[m\].
        center: [f64; 2],
        /// Radius of the base (half side for a pyramid) \[m\], > 0.
        radius: f64,
        /// Height of the top above the base \[m\].
        height: f64,
        /// Profile.
        #[serde(default)]
        profile: HillProfile,
    },
}

/// A 64-bit mix (splitmix64 finaliser): a deterministic hash of lattice indices.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Uniform value in \[-1, 1\] for lattice point (i, j).
fn lattice(seed: u64, i: i64, j: i64) -> f64 {
    let h = mix(seed ^ mix(i as u64 ^ mix(j as u64)));
    (h >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}

/// Projection extent of an area along a unit direction: (min, max).
fn extent(area: &Area, d: [f64; 2]) -> (f64, f64) {
    let cs = [
        area.min,
        [area.max[0], area.min[1]],
        area.max,
        [area.min[0], area.max[1]],
    ];
    cs.iter()
        .map(|c| c[0] * d[0] + c[1] * d[1])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| {
            (lo.min(s), hi.max(s))
        })
}

fn positive(origin: &str, field: &str, v: f64, max: f64) -> Result<(), SceneError> {
    if v.is_finite() && v > 0.0 && v <= max {
        Ok(())
    } else {
        Err(SceneError::invalid(
            origin,
            field,
            v,
            format!("a number > 0 and <= {max}"),
        ))
    }
}

fn finite(origin: &str, field: &str, v: f64) -> Result<(), SceneError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(SceneError::invalid(origin, field, v, "a finite number"))
    }
}

impl Generator {
    /// Check the parameters; `field` is the generator's path for messages.
    pub fn check(&self, origin: &str, field: &str) -> Result<(), SceneError> {
        let f = |name: &str| format!("{field}.{name}");
        match *self {
            Generator::Flat { height } => finite(origin, &f("height"), height),
            Generator::Slope {
                angle_deg,
                direction_deg,
                ..
            } => {
                if !(angle_deg.is_finite() && (0.0..=45.0).contains(&angle_deg)) {
                    return Err(SceneError::invalid(
                        origin,
                        f("angle_deg"),
                        angle_deg,
                        "an angle in degrees, 0 ..= 45",
                    ));
                }
                finite(origin, &f("direction_deg"), direction_deg)
            }
            Generator::Rough {
                amplitude,
                feature_size,
                ..
            } => {
                if !(amplitude.is_finite() && (0.0..=0.2).contains(&amplitude)) {
                    return Err(SceneError::invalid(
                        origin,
                        f("amplitude"),
                        amplitude,
                        "metres, 0 ..= 0.2",
                    ));
                }
                positive(origin, &f("feature_size"), feature_size, 10.0)
            }
            Generator::Stairs {
                step_height,
                step_depth,
                direction_deg,
                ..
            } => {
                positive(origin, &f("step_height"), step_height, 0.5)?;
                if !(step_depth.is_finite() && (0.1..=10.0).contains(&step_depth)) {
                    return Err(SceneError::invalid(
                        origin,
                        f("step_depth"),
                        step_depth,
                        "metres, 0.1 ..= 10",
                    ));
                }
                finite(origin, &f("direction_deg"), direction_deg)
            }
            Generator::Hill {
                center,
                radius,
                height,
                ..
            } => {
                finite(origin, &f("center[0]"), center[0])?;
                finite(origin, &f("center[1]"), center[1])?;
                positive(origin, &f("radius"), radius, 1e4)?;
                finite(origin, &f("height"), height)
            }
        }
    }

    /// The generator's height at (x, y) for a tile covering `area`.
    pub fn height(&self, area: &Area, x: f64, y: f64) -> f64 {
        match *self {
            Generator::Flat { height } => height,
            Generator::Slope {
                angle_deg,
                direction_deg,
                symmetric,
            } => {
                let d = unit(direction_deg);
                let (lo, hi) = extent(area, d);
                let s = along(x, y, d, lo, hi, symmetric);
                angle_deg.to_radians().tan() * s
            }
            Generator::Rough {
                amplitude,
                seed,
                feature_size,
            } => {
                let fx = x / feature_size;
                let fy = y / feature_size;
                let (i, j) = (fx.floor(), fy.floor());
                let (tx, ty) = (fx - i, fy - j);
                let (i, j) = (i as i64, j as i64);
                let v00 = lattice(seed, i, j);
                let v10 = lattice(seed, i + 1, j);
                let v01 = lattice(seed, i, j + 1);
                let v11 = lattice(seed, i + 1, j + 1);
                amplitude
                    * ((v00 * (1.0 - tx) + v10 * tx) * (1.0 - ty)
                        + (v01 * (1.0 - tx) + v11 * tx) * ty)
            }
            Generator::Stairs {
                step_height,
                step_depth,
                direction_deg,
                steps,
                symmetric,
            } => {
                let d = unit(direction_deg);
                let (lo, hi) = extent(area, d);
                let s = along(x, y, d, lo, hi, symmetric);
                let mut n = (s / step_depth + 1e-9).floor();
                if let Some(max) = steps {
                    n = n.min(max as f64);
                }
                step_height * n
            }
            Generator::Hill {
                center,
                radius,
                height,
                profile,
            } => {
                let dx = x - center[0];
                let dy = y - center[1];
                let r = match profile {
                    HillProfile::Pyramid => dx.abs().max(dy.abs()),
                    _ => (dx * dx + dy * dy).sqrt(),
                } / radius;
                if r >= 1.0 {
                    0.0
                } else if profile == HillProfile::Cosine {
                    height * 0.5 * (1.0 + (std::f64::consts::PI * r).cos())
                } else {
                    height * (1.0 - r)
                }
            }
        }
    }

    /// Write this generator into `grid` over `area` (the whole grid when `None`).
    ///
    /// An area is half-open, `min <= x < max`, but for an edge on the terrain's own far
    /// edge: a sample on the edge two tiles share belongs to the one that starts there.
    /// Closed areas gave it both, and with [`BlendMode::Add`] the shared edge of two
    /// raised tiles became a ridge one sample wide and up to their summed height (in
    /// random scenes, where four tiles meet on two lines, 0.2 m ridges that the
    /// planner's step rule let paths cross; 58% of first falls in 200 MuJoCo tours
    /// came within 0.4 m of those lines, which are near 25% of the way).
    pub fn apply(&self, grid: &mut HeightGrid, area: Option<&Area>, blend: BlendMode) {
        let (lo, hi) = grid.bounds();
        let whole = Area { min: lo, max: hi };
        let area = area.unwrap_or(&whole);
        let eps = 1e-9;
        let inside = |v: f64, k: usize| {
            v >= area.min[k] - eps
                && if area.max[k] >= hi[k] - eps {
                    v <= area.max[k] + eps
                } else {
                    v < area.max[k] - eps
                }
        };
        for j in 0..grid.ny {
            for i in 0..grid.nx {
                let [x, y] = grid.position(i, j);
                if !inside(x, 0) || !inside(y, 1) {
                    continue;
                }
                let h = self.height(area, x, y);
                let cell = &mut grid.heights[j * grid.nx + i];
                *cell = match blend {
                    BlendMode::Add => *cell + h,
                    BlendMode::Set => h,
                    BlendMode::Max => cell.max(h),
                };
            }
        }
    }
}

fn unit(direction_deg: f64) -> [f64; 2] {
    let (s, c) = direction_deg.to_radians().sin_cos();
    [c, s]
}

/// Distance travelled uphill into the tile; with `symmetric`, the distance to the
/// nearer of the two ends.
fn along(x: f64, y: f64, d: [f64; 2], lo: f64, hi: f64, symmetric: bool) -> f64 {
    let s = (x * d[0] + y * d[1] - lo).clamp(0.0, hi - lo);
    if symmetric { s.min(hi - lo - s) } else { s }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> HeightGrid {
        HeightGrid::flat([0.0, 0.0], [10.0, 4.0], 0.1, 0.0)
    }

    fn at(g: &HeightGrid, x: f64, y: f64) -> f64 {
        let (i, j) = g.cell_of(x, y).unwrap();
        g.heights[j * g.nx + i]
    }

    #[test]
    fn tiles_that_share_an_edge_do_not_both_add_to_it() {
        let mut g = grid();
        let tile = |x0: f64, x1: f64| Area {
            min: [x0, 0.0],
            max: [x1, 4.0],
        };
        let raised = Generator::Flat { height: 0.2 };
        raised.apply(&mut g, Some(&tile(0.0, 5.0)), BlendMode::Add);
        raised.apply(&mut g, Some(&tile(5.0, 10.0)), BlendMode::Add);
        // Every sample once, the shared edge x = 5 and the terrain's far edges
        // included: level ground, no ridge along the edge.
        assert!(
            g.heights.iter().all(|&h| h == 0.2),
            "{:?}",
            g.height_range()
        );
        // An area short of the far edge leaves its own far edge out.
        Generator::Flat { height: 0.1 }.apply(&mut g, Some(&tile(2.0, 4.0)), BlendMode::Add);
        let near = |x: f64, h: f64| (at(&g, x, 1.0) - h).abs() < 1e-12;
        assert!(near(2.0, 0.3) && near(3.9, 0.3) && near(4.0, 0.2));
    }

    #[test]
    fn flat_sets_and_adds_only_inside_its_area() {
        let mut g = grid();
        let area = Area {
            min: [2.0, 0.0],
            max: [4.0, 4.0],
        };
        Generator::Flat { height: 0.5 }.apply(&mut g, Some(&area), BlendMode::Add);
        Generator::Flat { height: 0.25 }.apply(&mut g, None, BlendMode::Add);
        assert_eq!(at(&g, 3.0, 1.0), 0.75);
        assert_eq!(at(&g, 5.0, 1.0), 0.25);
        Generator::Flat { height: 0.1 }.apply(&mut g, Some(&area), BlendMode::Set);
        assert_eq!(at(&g, 3.0, 1.0), 0.1);
        Generator::Flat { height: 0.2 }.apply(&mut g, None, BlendMode::Max);
        assert_eq!(at(&g, 3.0, 1.0), 0.2);
        assert_eq!(at(&g, 5.0, 1.0), 0.25);
    }

    #[test]
    fn slope_rises_at_its_angle_in_its_direction() {
        let mut g = grid();
        let slope = Generator::Slope {
            angle_deg: 10.0,
            direction_deg: 0.0,
            symmetric: false,
        };
        slope.apply(&mut g, None, BlendMode::Add);
        let expected = 10f64.to_radians().tan();
        assert!((at(&g, 5.0, 2.0) - 5.0 * expected).abs() < 1e-9);
        assert!((g.slope_at(5.0, 2.0) - 10f64.to_radians()).abs() < 1e-6);
        // Towards +Y instead: no change along X.
        let mut g = grid();
        Generator::Slope {
            angle_deg: 10.0,
            direction_deg: 90.0,
            symmetric: false,
        }
        .apply(&mut g, None, BlendMode::Add);
        assert!((at(&g, 1.0, 3.0) - at(&g, 9.0, 3.0)).abs() < 1e-9);
        assert!((at(&g, 1.0, 3.0) - 3.0 * expected).abs() < 1e-9);
    }

    #[test]
    fn symmetric_slope_is_a_ridge_back_to_zero() {
        let mut g = grid();
        Generator::Slope {
            angle_deg: 5.0,
            direction_deg: 0.0,
            symmetric: true,
        }
        .apply(&mut g, None, BlendMode::Add);
        assert!(at(&g, 0.0, 1.0).abs() < 1e-9 && at(&g, 10.0, 1.0).abs() < 1e-9);
        let top = 5.0 * 5f64.to_radians().tan();
        assert!((at(&g, 5.0, 1.0) - top).abs() < 1e-9);
    }

    #[test]
    fn rough_is_bounded_deterministic_and_seed_dependent() {
        let r = |seed| Generator::Rough {
            amplitude: 0.05,
            seed,
            feature_size: 0.1,
        };
        let mut a = grid();
        let mut b = grid();
        let mut c = grid();
        r(1).apply(&mut a, None, BlendMode::Add);
        r(1).apply(&mut b, None, BlendMode::Add);
        r(2).apply(&mut c, None, BlendMode::Add);
        assert_eq!(a, b);
        assert_ne!(a, c);
        let (lo, hi) = a.height_range();
        assert!(lo >= -0.05 && hi <= 0.05 && hi - lo > 0.05, "{lo} {hi}");
    }

    #[test]
    fn stairs_step_by_step_height_with_landing_and_descent() {
        let mut g = grid();
        Generator::Stairs {
            step_height: 0.15,
            step_depth: 0.5,
            direction_deg: 0.0,
            steps: Some(4),
            symmetric: false,
        }
        .apply(&mut g, None, BlendMode::Add);
        assert_eq!(at(&g, 0.2, 1.0), 0.0);
        assert!((at(&g, 0.7, 1.0) - 0.15).abs() < 1e-12);
        assert!((at(&g, 1.2, 1.0) - 0.30).abs() < 1e-12);
        assert!((at(&g, 9.0, 1.0) - 0.60).abs() < 1e-12, "capped at 4 steps");
        let mut g = grid();
        Generator::Stairs {
            step_height: 0.1,
            step_depth: 1.0,
            direction_deg: 0.0,
            steps: None,
            symmetric: true,
        }
        .apply(&mut g, None, BlendMode::Add);
        assert!((at(&g, 5.0, 1.0) - 0.5).abs() < 1e-12);
        assert!((at(&g, 9.5, 1.0)).abs() < 1e-12);
        assert!((at(&g, 8.5, 1.0) - 0.1).abs() < 1e-12);
    }

    #[test]
    fn hill_profiles_peak_at_the_centre_and_vanish_at_the_radius() {
        for profile in [HillProfile::Cosine, HillProfile::Cone, HillProfile::Pyramid] {
            let mut g = grid();
            Generator::Hill {
                center: [5.0, 2.0],
                radius: 2.0,
                height: 1.0,
                profile,
            }
            .apply(&mut g, None, BlendMode::Add);
            assert!((at(&g, 5.0, 2.0) - 1.0).abs() < 1e-12, "{profile:?}");
            assert!(at(&g, 7.5, 2.0).abs() < 1e-12, "{profile:?}");
            assert!(at(&g, 6.0, 2.0) > 0.0 && at(&g, 6.0, 2.0) < 1.0);
        }
        // Pyramid: same height along a square ring, cone: not.
        let mut g = grid();
        Generator::Hill {
            center: [5.0, 2.0],
            radius: 2.0,
            height: 1.0,
            profile: HillProfile::Pyramid,
        }
        .apply(&mut g, None, BlendMode::Add);
        assert!((at(&g, 6.0, 3.0) - at(&g, 6.0, 2.0)).abs() < 1e-12);
    }

    #[test]
    fn check_rejects_bad_parameters_with_their_field() {
        let bad = Generator::Stairs {
            step_height: f64::NAN,
            step_depth: 0.5,
            direction_deg: 0.0,
            steps: None,
            symmetric: false,
        };
        let e = bad
            .check("f.toml", "terrain.tiles[1].generator")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("terrain.tiles[1].generator.step_height") && e.contains("NaN"),
            "{e}"
        );
        let bad = Generator::Slope {
            angle_deg: 60.0,
            direction_deg: 0.0,
            symmetric: false,
        };
        assert!(
            bad.check("f", "g")
                .unwrap_err()
                .to_string()
                .contains("0 ..= 45")
        );
        let bad = Generator::Hill {
            center: [0.0, 0.0],
            radius: -1.0,
            height: 1.0,
            profile: HillProfile::Cone,
        };
        assert!(
            bad.check("f", "g")
                .unwrap_err()
                .to_string()
                .contains("g.radius")
        );
    }
}
