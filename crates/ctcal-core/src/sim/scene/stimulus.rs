//! The on-screen calibration stimulus (Stoffregen et al. 2020, method 3): a checkerboard
//! moving on a grey background, to be played full-screen on a monitor and recorded by the
//! camera. The board's top-left corner follows triangle waves, `bx(t) = x0 + Ax tri(t/Px)`,
//! `by(t) = y0 + Ay tri(t/Py)` (`tri(0) = 0` rising, peaks +-1), with the speed split between
//! the axes; every frame is the exact pixel-area average of the ideal pattern (white squares
//! 255, black 0, background 128), rounded to 8 bits. Frame `k` is shown at `k / refresh_hz`.

use crate::events::Frame;
use serde::{Deserialize, Serialize};

/// Parameters of the calibration checkerboard.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StimulusSpec {
    pub width: usize,
    pub height: usize,
    pub refresh_hz: f64,
    pub duration_s: f64,
    pub square_px: f64,
    pub squares: [usize; 2],
    pub speed_px_s: f64,
}

impl Default for StimulusSpec {
    fn default() -> Self {
        Self {
            width: 240,
            height: 180,
            refresh_hz: 75.0,
            duration_s: 1.0,
            square_px: 15.0,
            squares: [8, 6],
            speed_px_s: 40.0,
        }
    }
}

/// Triangle wave of period 1: 0 at 0, +1 at 1/4, -1 at 3/4.
fn triangle(phase: f64) -> f64 {
    let p = phase.rem_euclid(1.0);
    if p < 0.25 {
        4.0 * p
    } else if p < 0.75 {
        2.0 - 4.0 * p
    } else {
        4.0 * p - 4.0
    }
}

/// Length of `[a, b)` inside `[lo, hi)`.
fn overlap(a: f64, b: f64, lo: f64, hi: f64) -> f64 {
    (b.min(hi) - a.max(lo)).max(0.0)
}

impl StimulusSpec {
    /// Board top-left corner at time t: amplitudes fill a quarter of the free space on each
    /// axis; the x axis sweeps 4x slower than y, the speed split equally between the axes.
    pub fn board_corner(&self, t: f64) -> (f64, f64) {
        let (bw, bh) = (
            self.squares[0] as f64 * self.square_px,
            self.squares[1] as f64 * self.square_px,
        );
        let (x0, y0) = (
            (self.width as f64 - bw) / 2.0,
            (self.height as f64 - bh) / 2.0,
        );
        let axis_speed = self.speed_px_s / 2f64.sqrt();
        let (ax, ay) = (x0 * 0.95, y0 * 0.95);
        // triangle slope is 4 amplitudes per period: period = 4 A / speed
        let (px, py) = (4.0 * ax / axis_speed, 4.0 * ay / axis_speed);
        let tri = |t: f64, period: f64, amplitude: f64| {
            if period > 0.0 {
                amplitude * triangle(t / period)
            } else {
                0.0
            }
        };
        (x0 + tri(t, px, ax), y0 + tri(t, py, ay))
    }

    /// Screen DN of frame `k`.
    pub fn render(&self, k: usize) -> Frame {
        let t = k as f64 / self.refresh_hz;
        let (bx, by) = self.board_corner(t);
        let sq = self.square_px;
        let (nx, ny) = (self.squares[0], self.squares[1]);
        let mut pixels = vec![0u8; self.width * self.height];
        for y in 0..self.height {
            for x in 0..self.width {
                let (px, py) = (x as f64, y as f64);
                let mut white = 0.0;
                let mut board = 0.0;
                for j in 0..ny {
                    let oy = overlap(py, py + 1.0, by + j as f64 * sq, by + (j + 1) as f64 * sq);
                    if oy == 0.0 {
                        continue;
                    }
                    for i in 0..nx {
                        let ox =
                            overlap(px, px + 1.0, bx + i as f64 * sq, bx + (i + 1) as f64 * sq);
                        let area = ox * oy;
                        board += area;
                        if (i + j) % 2 == 0 {
                            white += area;
                        }
                    }
                }
                let value = 255.0 * white + 128.0 * (1.0 - board);
                pixels[y * self.width + x] = value.round().clamp(0.0, 255.0) as u8;
            }
        }
        Frame {
            t: (t * 1e6).round() as i64,
            width: self.width as u32,
            height: self.height as u32,
            pixels,
            exposure_us: None,
        }
    }

    pub fn frame_count(&self) -> usize {
        (self.duration_s * self.refresh_hz).round() as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_wave_shape() {
        assert_eq!(triangle(0.0), 0.0);
        assert_eq!(triangle(0.25), 1.0);
        assert_eq!(triangle(0.5), 0.0);
        assert_eq!(triangle(0.75), -1.0);
        assert!((triangle(0.125) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn first_frame_is_a_centred_board_on_grey() {
        let spec = StimulusSpec::default();
        let f = spec.render(0);
        // board 120x90 centred: corner at (60, 45); top-left square white
        assert_eq!(f.pixels[0], 128);
        assert_eq!(f.pixels[50 * 240 + 65], 255);
        assert_eq!(f.pixels[50 * 240 + 80], 0);
        assert_eq!(spec.frame_count(), 75);
    }

    #[test]
    fn board_moves_at_the_requested_speed() {
        let spec = StimulusSpec::default();
        let (a, b) = (spec.board_corner(0.0), spec.board_corner(0.01));
        let speed = ((b.0 - a.0).hypot(b.1 - a.1)) / 0.01;
        assert!((speed - 40.0).abs() < 1e-6, "{speed}");
    }
}
