//! A moving checkerboard rendered with an exact box filter (each pixel the area average of
//! the ideal pattern over its footprint), as in the `dev_refractory` oracle:
//! `I(x, y, t) = a + b Gx(x, t) Gy(y, t)`, `a = (hi + lo)/2`, `b = (hi - lo)/2`, where
//! `Gx(x, t)` is the mean over `[x - 1/2, x + 1/2]` of the square wave `S(z - x0 - vx t)`
//! (+1 on even squares, -1 on odd ones); likewise `Gy`. The square whose corner is at
//! `(x0 + vx t, y0 + vy t)` is bright.

use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CheckerboardScene {
    pub square_px: f64,
    pub lo_dn: f64,
    pub hi_dn: f64,
    #[serde(default)]
    pub vx_px_s: f64,
    #[serde(default)]
    pub vy_px_s: f64,
    #[serde(default)]
    pub origin_px: [f64; 2],
}

/// Integral of the unit square wave of half-period `square` from 0 to `z` (a triangle wave).
fn square_wave_integral(z: f64, square: f64) -> f64 {
    let phase = z.rem_euclid(2.0 * square);
    if phase < square {
        phase
    } else {
        2.0 * square - phase
    }
}

/// Mean of the square wave over `[z - 1/2, z + 1/2]`.
pub fn box_filtered_square_wave(z: f64, square: f64) -> f64 {
    square_wave_integral(z + 0.5, square) - square_wave_integral(z - 0.5, square)
}

impl CheckerboardScene {
    pub fn max_speed_px_s(&self) -> f64 {
        self.vx_px_s.hypot(self.vy_px_s)
    }

    /// Renders rows `rows` into `out` (those rows only).
    pub fn render(&self, width: usize, rows: std::ops::Range<usize>, t: f64, out: &mut [f32]) {
        let (a, b) = (
            (self.hi_dn + self.lo_dn) / 2.0,
            (self.hi_dn - self.lo_dn) / 2.0,
        );
        let (x0, y0) = (
            self.origin_px[0] + self.vx_px_s * t,
            self.origin_px[1] + self.vy_px_s * t,
        );
        let gx: Vec<f64> = (0..width)
            .map(|x| box_filtered_square_wave(x as f64 - x0, self.square_px))
            .collect();
        let first = rows.start;
        for y in rows {
            let gy = box_filtered_square_wave(y as f64 - y0, self.square_px);
            for (x, g) in gx.iter().enumerate() {
                out[(y - first) * width + x] = (a + b * g * gy) as f32;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_filter_of_the_square_wave() {
        // deep inside the first (bright) square
        assert_eq!(box_filtered_square_wave(5.0, 48.0), 1.0);
        // inside the second (dark) square
        assert_eq!(box_filtered_square_wave(60.0, 48.0), -1.0);
        // a pixel centred on the edge at 48 is half bright, half dark
        assert!(box_filtered_square_wave(48.0, 48.0).abs() < 1e-12);
        // a quarter of the way across the edge
        assert!((box_filtered_square_wave(47.75, 48.0) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn renders_within_the_two_levels() {
        let scene = CheckerboardScene {
            square_px: 48.0,
            lo_dn: 60.0,
            hi_dn: 160.0,
            vx_px_s: -66.0,
            vy_px_s: 15.0,
            origin_px: [17.3, -29.6],
        };
        let mut frame = vec![0f32; 240 * 180];
        scene.render(240, 0..180, 0.37, &mut frame);
        assert!(frame.iter().all(|&v| (59.999..=160.001).contains(&v)));
        assert!(frame.contains(&160.0) && frame.contains(&60.0));
    }
}
