//! What kind of ground a spot of a scene is, read from the height map alone (random
//! scenes and user scenes keep no record of the generators that made their terrain):
//! the experiments say where humanoids fall in these words.
//!
//! A square window around the spot is sampled on the height map's own grid and a
//! smooth surface (a quadric) is fitted by least squares. A step is a jump between neighbouring samples
//! with level treads around it; rough ground leaves scattered residuals; a slope
//! is tilted (a ramp, a hill's flank); anything else is flat.

use plamo_scenes::HeightGrid;
use serde::{Deserialize, Serialize};

/// Half the side of the window judged around a spot \[m\]: about a stride, and small
/// enough that a 3 m hill's curvature stays below the roughness threshold.
pub const WINDOW_HALF: f64 = 0.3;
/// Smallest jump between neighbouring samples taken as a step edge \[m\] (stairs
/// here have 0.1-0.15 m risers).
pub const STEP_JUMP: f64 = 0.07;
/// Height difference between neighbouring samples still taken as level \[m\].
pub const LEVEL: f64 = 0.005;
/// Share of level neighbour pairs that makes a window with a step edge stairs rather
/// than rough ground (a 0.6 m window over 0.4 m treads has one or two risers).
pub const LEVEL_SHARE: f64 = 0.6;
/// Smallest RMS residual from the fitted surface taken as rough ground \[m\]: the
/// random scenes' gentlest gravel (+-2 cm) leaves 3 mm and more, a hill's flank
/// 2 mm at most.
pub const ROUGH_RMS: f64 = 0.0027;
/// Smallest gradient of the fitted surface at the spot taken as a slope (rise over run; 0.07 is
/// 4 degrees).
pub const SLOPE_GRADIENT: f64 = 0.07;

/// Kinds of ground, in the order they are tested.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GroundKind {
    /// Level and even.
    Flat,
    /// A tilted plane (ramps, ridges, hills).
    Slope,
    /// Uneven (gravel, bumps).
    Rough,
    /// A step edge (stairs, ledges).
    Stairs,
}

impl GroundKind {
    /// Every kind, in table order.
    pub const ALL: [GroundKind; 4] = [Self::Flat, Self::Slope, Self::Rough, Self::Stairs];

    /// The kind's name as written in CSV files and tables.
    pub fn name(self) -> &'static str {
        match self {
            Self::Flat => "flat",
            Self::Slope => "slope",
            Self::Rough => "rough",
            Self::Stairs => "stairs",
        }
    }
}

/// The coefficients of `basis` that fit `h` best (the normal equations; 6 unknowns).
fn least_squares(h: &[f64], basis: impl Fn(usize) -> [f64; 6]) -> [f64; 6] {
    let mut ata = nalgebra::SMatrix::<f64, 6, 6>::zeros();
    let mut atb = nalgebra::SVector::<f64, 6>::zeros();
    for (k, &z) in h.iter().enumerate() {
        let b = nalgebra::SVector::<f64, 6>::from(basis(k));
        ata += b * b.transpose();
        atb += b * z;
    }
    // A window of at least 3 x 3 samples determines a quadric; a degenerate one
    // (zero resolution) reads as flat.
    ata.cholesky().map_or([0.0; 6], |c| c.solve(&atb).into())
}

/// The kind of ground around (x, y).
pub fn ground_kind(terrain: &HeightGrid, x: f64, y: f64) -> GroundKind {
    let r = terrain.resolution.max(1e-3);
    let n = (WINDOW_HALF / r).round().max(1.0) as i32;
    let side = (2 * n + 1) as usize;
    // On the grid's own samples: between them a riser is interpolated into a ramp
    // whose jump is shared by two sample pairs.
    let snap = |v: f64, o: f64| o + ((v - o) / r).round() * r;
    let (x0, y0) = (snap(x, terrain.origin[0]), snap(y, terrain.origin[1]));
    let mut h = Vec::with_capacity(side * side);
    for j in -n..=n {
        for i in -n..=n {
            h.push(terrain.height_at(x0 + f64::from(i) * r, y0 + f64::from(j) * r));
        }
    }
    // Least-squares quadric (a hill's flank is smooth, not rough): the basis
    // 1, x, y, x^2, xy, y^2 over the window's offsets.
    let offsets: Vec<f64> = (-n..=n).map(|i| f64::from(i) * r).collect();
    let basis = |k: usize| {
        let (u, v) = (offsets[k % side], offsets[k / side]);
        [1.0, u, v, u * u, u * v, v * v]
    };
    let c = least_squares(&h, basis);
    let fit = |k: usize| basis(k).iter().zip(&c).map(|(b, c)| b * c).sum::<f64>();
    let residual = |k: usize| h[k] - fit(k);
    let (gx, gy) = (c[1], c[2]);
    // Treads are level: stairs are a few big jumps between samples at equal height.
    let (mut jump, mut level, mut pairs) = (0.0f64, 0usize, 0usize);
    let mut rss = 0.0;
    for k in 0..h.len() {
        let e = residual(k);
        rss += e * e;
        let right = (k % side + 1 < side).then(|| k + 1);
        let up = (k + side < h.len()).then(|| k + side);
        for m in [right, up].into_iter().flatten() {
            let d = (h[m] - h[k]).abs();
            jump = jump.max(d);
            level += usize::from(d < LEVEL);
            pairs += 1;
        }
    }
    let rms = (rss / h.len() as f64).sqrt();
    if jump >= STEP_JUMP && level as f64 >= LEVEL_SHARE * pairs as f64 {
        GroundKind::Stairs
    } else if rms >= ROUGH_RMS {
        GroundKind::Rough
    } else if gx.hypot(gy) >= SLOPE_GRADIENT {
        GroundKind::Slope
    } else {
        GroundKind::Flat
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The locomotion strips' generated terrains read as what they were made as, at
    /// every 0.5 m along their middle (their landings between flights are left out).
    #[test]
    fn strips_read_as_their_kind() {
        let kind_at = |scene: &str, x: f64| {
            let s = plamo_scenes::builtin(scene).expect("built-in scene");
            ground_kind(&s.terrain, x, 3.0)
        };
        for k in 0..20 {
            let x = 10.0 + 0.5 * f64::from(k);
            assert_eq!(
                kind_at("terrain-slope", x),
                GroundKind::Slope,
                "slope at x {x}"
            );
            assert_eq!(
                kind_at("terrain-rough", x),
                GroundKind::Rough,
                "rough at x {x}"
            );
        }
        assert_eq!(kind_at("terrain-slope", 2.0), GroundKind::Flat);
        // A flight of 0.4 m treads: every window of 0.6 m holds a riser.
        for k in 0..8 {
            let x = 7.5 + 0.4 * f64::from(k);
            let got = kind_at("terrain-stairs", x);
            assert_eq!(got, GroundKind::Stairs, "stairs at x {x}");
        }
    }

    /// Random scenes' gentle gravel (+-2 cm and more), hills, ramps and stairs read as
    /// the generator that made them, away from the tiles' edges; hills' flanks are
    /// smooth, not rough.
    #[test]
    fn random_scenes_read_as_their_generators() {
        use plamo_scenes::generators::Generator;
        let mut checked = std::collections::BTreeMap::new();
        for seed in 0..8 {
            let (file, scene) = plamo_scenes::random_scene_with_file(seed);
            for tile in &file.terrain.tiles {
                let Some(area) = &tile.area else { continue };
                for j in 0..8 {
                    for i in 0..8 {
                        let at = |k: u32, lo: f64, hi: f64| {
                            lo + 0.5 + (hi - lo - 1.0) * (f64::from(k) + 0.5) / 8.0
                        };
                        let x = at(i, area.min[0], area.max[0]);
                        let y = at(j, area.min[1], area.max[1]);
                        let got = ground_kind(&scene.terrain, x, y);
                        let allowed: &[GroundKind] = match tile.generator {
                            Generator::Rough { .. } => &[GroundKind::Rough],
                            Generator::Slope { .. } | Generator::Hill { .. } => {
                                &[GroundKind::Slope, GroundKind::Flat]
                            }
                            Generator::Stairs { .. } => &[GroundKind::Stairs, GroundKind::Flat],
                            _ => continue,
                        };
                        assert!(
                            allowed.contains(&got),
                            "scene {seed} at ({x:.2}, {y:.2}): {got:?}, made by {:?}",
                            tile.generator
                        );
                        *checked.entry(got).or_insert(0) += 1;
                    }
                }
            }
        }
        for kind in GroundKind::ALL {
            assert!(
                checked.get(&kind).copied().unwrap_or(0) > 0,
                "{kind:?} never seen: {checked:?}"
            );
        }
    }
}
