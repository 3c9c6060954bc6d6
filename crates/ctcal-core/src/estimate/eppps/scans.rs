//! Line scans: what one ideal pixel sees while a scene moves past it. For a scene that moves
//! at `v`, a pixel's log intensity over time is the scene's log intensity along a line in
//! the direction of `-v`, read at `|v|` pixels per second; an ideal pixel (Lichtsteiner et
//! al., JSSC 2008) fires an event each time that profile moves one threshold from the level
//! of its last event. Counting events along many such lines through an image, at a grid of
//! thresholds, gives the calibration curve of `estimate eppps`: events per pixel of travel,
//! over pixels that fired, against the threshold.
//!
//! Each scan begins with a burn-in stretch before its counted part, so that the pixel's
//! memorised level at the start is what the scene before it left there (a pixel of a running
//! camera is somewhere between two events, not freshly reset).

use rayon::prelude::*;

/// Distance between samples along a scan, pixels.
pub const STEP_PX: f64 = 0.25;
/// Stretch scanned before counting starts, pixels.
pub const BURN_IN_PX: f64 = 16.0;
/// Side of the tiles a recording without frames is counted in, and of the blocks of
/// parallel scans that stand for them: a tile counts when any of its pixels has signal, so
/// that blank parts of the view do not, while a tile's pixels that stay silent still do
/// (they carry the threshold: the higher it is, the fewer of them fire).
pub const TILE_PX: usize = 8;

/// Thresholds of the calibration curve: 25 log-spaced values from 0.03 to 3.
pub fn threshold_grid() -> Vec<f64> {
    (0..25)
        .map(|k| (0.03f64.ln() + k as f64 * (100f64.ln() / 24.0)).exp())
        .collect()
}

/// A log-intensity image, row-major.
#[derive(Clone, Debug)]
pub struct LogImage {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl LogImage {
    /// Bilinear sample at (x, y), clamped to the image.
    pub fn sample(&self, x: f64, y: f64) -> f32 {
        let x = x.clamp(0.0, (self.width - 1) as f64);
        let y = y.clamp(0.0, (self.height - 1) as f64);
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
        let (fx, fy) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
        let at = |x: usize, y: usize| self.data[y * self.width + x];
        (1.0 - fy) * ((1.0 - fx) * at(x0, y0) + fx * at(x1, y0))
            + fy * ((1.0 - fx) * at(x0, y1) + fx * at(x1, y1))
    }
}

/// One scan: a start point, a unit direction and the counted length, pixels.
#[derive(Clone, Copy, Debug)]
pub struct Scan {
    pub x: f64,
    pub y: f64,
    pub dx: f64,
    pub dy: f64,
    pub length: f64,
}

/// A scan's log-intensity profile: `burn` samples of burn-in, then the counted part.
pub struct Profile {
    pub values: Vec<f32>,
    pub burn: usize,
    /// Counted length, pixels.
    pub length: f64,
}

/// The profile of `scan` through `image`.
pub fn profile(image: &LogImage, scan: &Scan) -> Profile {
    let burn = (BURN_IN_PX / STEP_PX).round() as usize;
    let counted = (scan.length / STEP_PX).ceil().max(1.0) as usize;
    let values = (0..=burn + counted)
        .map(|i| {
            let s = (i as f64 - burn as f64) * STEP_PX;
            image.sample(scan.x + s * scan.dx, scan.y + s * scan.dy)
        })
        .collect();
    Profile {
        values,
        burn,
        length: scan.length,
    }
}

/// ON and OFF events of an ideal pixel of threshold `c` along `profile`, counted after its
/// burn-in; the memorised level starts at the first sample and moves by one threshold per
/// event.
pub fn count(profile: &Profile, c: f32) -> (u32, u32) {
    let mut reference = profile.values[0];
    let (mut on, mut off) = (0u32, 0u32);
    for (i, &level) in profile.values.iter().enumerate() {
        let counted = i > profile.burn;
        while level - reference >= c {
            reference += c;
            on += counted as u32;
        }
        while reference - level >= c {
            reference -= c;
            off += counted as u32;
        }
    }
    (on, off)
}

/// One point of a calibration curve: at threshold `ct`, ON and OFF events per pixel of
/// travel over the scans that fired, and the share of scans that fired.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct CurvePoint {
    pub ct: f64,
    pub on_per_px: f64,
    pub off_per_px: f64,
    pub active_fraction: f64,
    /// Events per scan (ON + OFF), over all scans.
    pub events_per_scan: f64,
}

/// The calibration curve of `profiles` at every threshold of `grid`: per pixel of the
/// travel of the scans that fired (`fired_only`, as the recording's pixels are counted
/// without frames) or of all scans.
pub fn curve(profiles: &[Profile], grid: &[f64], fired_only: bool) -> Vec<CurvePoint> {
    grid.par_iter()
        .map(|&ct| {
            let (mut on, mut off, mut travel, mut active) = (0u64, 0u64, 0.0f64, 0usize);
            for p in profiles {
                let (a, b) = count(p, ct as f32);
                active += (a + b > 0) as usize;
                if a + b > 0 || !fired_only {
                    on += a as u64;
                    off += b as u64;
                    travel += p.length;
                }
            }
            let travel = travel.max(1e-9);
            CurvePoint {
                ct,
                on_per_px: on as f64 / travel,
                off_per_px: off as f64 / travel,
                active_fraction: active as f64 / profiles.len().max(1) as f64,
                events_per_scan: (on + off) as f64 / profiles.len().max(1) as f64,
            }
        })
        .collect()
}

/// A block of `TILE_PX` x `TILE_PX` parallel scans one pixel apart, moving together: what
/// one tile of the sensor sees.
#[derive(Clone, Copy, Debug)]
pub struct Block {
    /// The corner scan.
    pub corner: Scan,
}

/// ON and OFF events of a block's pixels at each threshold of `grid`.
fn block_counts(image: &LogImage, block: &Block, grid: &[f64]) -> Vec<[u32; 2]> {
    let mut out = vec![[0u32; 2]; grid.len()];
    for j in 0..TILE_PX {
        for i in 0..TILE_PX {
            let scan = Scan {
                x: block.corner.x + i as f64,
                y: block.corner.y + j as f64,
                ..block.corner
            };
            let p = profile(image, &scan);
            for (slot, &c) in out.iter_mut().zip(grid) {
                let (on, off) = count(&p, c as f32);
                slot[0] += on;
                slot[1] += off;
            }
        }
    }
    out
}

/// The calibration curve of `blocks` through `image`: per threshold, events per pixel of
/// travel over the blocks where any pixel fired (as the recording's tiles are counted).
pub fn block_curve(image: &LogImage, blocks: &[Block], grid: &[f64]) -> Vec<CurvePoint> {
    let counts: Vec<Vec<[u32; 2]>> = blocks
        .par_iter()
        .map(|b| block_counts(image, b, grid))
        .collect();
    let pixels = (TILE_PX * TILE_PX) as f64;
    (0..grid.len())
        .map(|k| {
            let (mut on, mut off, mut travel, mut active) = (0u64, 0u64, 0.0f64, 0usize);
            for (b, c) in blocks.iter().zip(&counts) {
                if c[k][0] + c[k][1] > 0 {
                    on += c[k][0] as u64;
                    off += c[k][1] as u64;
                    travel += pixels * b.corner.length;
                    active += 1;
                }
            }
            let travel = travel.max(1e-9);
            CurvePoint {
                ct: grid[k],
                on_per_px: on as f64 / travel,
                off_per_px: off as f64 / travel,
                active_fraction: active as f64 / blocks.len().max(1) as f64,
                events_per_scan: (on + off) as f64 / (pixels * blocks.len().max(1) as f64),
            }
        })
        .collect()
}

/// The threshold at which a curve's `rate` (falling with the threshold) reaches `target`,
/// interpolated in log-log between grid points; `None` outside the curve.
pub fn invert(curve: &[CurvePoint], rate: impl Fn(&CurvePoint) -> f64, target: f64) -> Option<f64> {
    curve.windows(2).find_map(|w| {
        let (r0, r1) = (rate(&w[0]), rate(&w[1]));
        (r0 >= target && target >= r1 && r1 > 0.0 && r0 > r1).then(|| {
            let f = (target.ln() - r0.ln()) / (r1.ln() - r0.ln());
            (w[0].ct.ln() + f * (w[1].ct.ln() - w[0].ct.ln())).exp()
        })
    })
}

/// The local slope `d ln rate / d ln ct` of a curve at `ct` (for turning an error of the
/// rate into an error of the threshold); -1 where it cannot be measured.
pub fn log_slope(curve: &[CurvePoint], rate: impl Fn(&CurvePoint) -> f64, ct: f64) -> f64 {
    curve
        .windows(2)
        .find(|w| w[0].ct <= ct && ct <= w[1].ct)
        .and_then(|w| {
            let (r0, r1) = (rate(&w[0]), rate(&w[1]));
            (r0 > 0.0 && r1 > 0.0).then(|| (r1.ln() - r0.ln()) / (w[1].ct.ln() - w[0].ct.ln()))
        })
        .filter(|s| s.is_finite() && *s < 0.0)
        .unwrap_or(-1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp_image(slope: f32) -> LogImage {
        LogImage {
            width: 200,
            height: 4,
            data: (0..800).map(|i| slope * (i % 200) as f32).collect(),
        }
    }

    #[test]
    fn a_ramp_fires_one_event_per_threshold_of_change() {
        // log intensity rising 0.05 per pixel, 40 px counted: a change of 2.0 is 6 events of
        // 0.3 (1.8) or 7, depending on where the burn-in left the memorised level
        let image = ramp_image(0.05);
        let scan = Scan {
            x: 20.0,
            y: 1.0,
            dx: 1.0,
            dy: 0.0,
            length: 40.0,
        };
        let p = profile(&image, &scan);
        let (on, off) = count(&p, 0.3);
        assert_eq!(off, 0);
        assert!(on == 6 || on == 7, "{on}");
        // against the ramp: OFF
        let back = Scan {
            dx: -1.0,
            x: 120.0,
            ..scan
        };
        assert_eq!(count(&profile(&image, &back), 0.3).0, 0);
    }

    #[test]
    fn the_curve_of_a_ramp_inverts_to_its_threshold() {
        let image = ramp_image(0.05);
        let profiles: Vec<Profile> = (0..50)
            .map(|k| {
                profile(
                    &image,
                    &Scan {
                        x: 20.0 + k as f64 * 0.37,
                        y: 1.0,
                        dx: 1.0,
                        dy: 0.0,
                        length: 100.0,
                    },
                )
            })
            .collect();
        let grid = threshold_grid();
        let c = curve(&profiles, &grid, true);
        // 0.05 per pixel: 0.05 / C events per pixel of travel
        let ct = invert(&c, |p| p.on_per_px, 0.05 / 0.25).unwrap();
        assert!((ct - 0.25).abs() < 0.01, "{ct}");
        let slope = log_slope(&c, |p| p.on_per_px, 0.25);
        // counts are whole events (17 at 0.3 for 16.7), so the slope between grid points is
        // about -1 within that rounding
        assert!((slope + 1.0).abs() < 0.2, "{slope}");
        assert!((grid[0] - 0.03).abs() < 1e-12 && (grid[24] - 3.0).abs() < 1e-9);
    }
}
