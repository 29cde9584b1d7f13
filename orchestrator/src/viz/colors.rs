//! Colour scales.

/// Terrain heights, low to high: meadow green, dry grass, sand, earth, rock.
pub const TERRAIN_COLORS: [[u8; 3]; 5] = [
    [88, 150, 96],
    [164, 190, 110],
    [226, 206, 146],
    [176, 128, 86],
    [150, 146, 140],
];

/// The colour at `t` in \[0, 1\] along evenly spaced `stops` (clamped).
pub fn color_at(stops: &[[u8; 3]], t: f64) -> [u8; 3] {
    match stops.len() {
        0 => [0, 0, 0],
        1 => stops[0],
        n => {
            let t = if t.is_finite() {
                t.clamp(0.0, 1.0)
            } else {
                0.0
            };
            let f = t * (n - 1) as f64;
            let k = (f.floor() as usize).min(n - 2);
            let u = f - k as f64;
            let (a, b) = (stops[k], stops[k + 1]);
            [0, 1, 2].map(|c| (a[c] as f64 + (b[c] as f64 - a[c] as f64) * u).round() as u8)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_between_stops_and_clamps() {
        let s = [[0, 0, 0], [100, 200, 50], [200, 200, 250]];
        assert_eq!(color_at(&s, 0.0), [0, 0, 0]);
        assert_eq!(color_at(&s, 0.25), [50, 100, 25]);
        assert_eq!(color_at(&s, 0.75), [150, 200, 150]);
        assert_eq!(color_at(&s, 1.0), [200, 200, 250]);
        assert_eq!(color_at(&s, 7.0), [200, 200, 250]);
        assert_eq!(color_at(&s, f64::NAN), [0, 0, 0]);
    }
}
