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

/// Thresholds of the calibration curve: 31 log-spaced values from 0.03 to 9.5 (24 steps a
/// factor 100). Real sensors' thresholds lie well inside; the top reaches past the log
/// range of every prior image under every floor (1.7-5.8), so that each curve falls to no
/// events inside the grid and a sparse recording's threshold is bracketed, not cut off at
/// the grid's end. Thresholds above a scan's own range cost nothing ([`Profile::range`]).
pub fn threshold_grid() -> Vec<f64> {
    (0..31)
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
    /// Time the scene takes to move one pixel past the scan, seconds.
    pub seconds_per_px: f64,
}

/// A scan's log-intensity profile: `burn` samples of burn-in, then the counted part.
pub struct Profile {
    pub values: Vec<f32>,
    /// The time of each sample, seconds (any origin).
    pub times_s: Vec<f64>,
    pub burn: usize,
    /// Counted length, pixels.
    pub length: f64,
}

impl Profile {
    /// The largest change from the first sample: no threshold above it fires (the
    /// memorised level starts at the first sample and moves only with an event).
    pub fn range(&self) -> f32 {
        let first = self.values.first().copied().unwrap_or(0.0);
        self.values
            .iter()
            .fold(0f32, |r, &v| r.max((v - first).abs()))
    }
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
    let times_s = (0..=burn + counted)
        .map(|i| i as f64 * STEP_PX * scan.seconds_per_px)
        .collect();
    Profile {
        values,
        times_s,
        burn,
        length: scan.length,
    }
}

/// ON and OFF events of an ideal pixel of thresholds `c_on`, `c_off` along `profile`,
/// counted after its burn-in; the memorised level starts at the first sample and moves by
/// one threshold per event. The two thresholds interact: the memorised level is a play
/// operator of width `c_on + c_off` on the profile, so a pixel's ON count depends on its OFF
/// threshold wherever the profile turns.
pub fn count(profile: &Profile, c_on: f32, c_off: f32) -> (u32, u32) {
    let mut reference = profile.values[0];
    let (mut on, mut off) = (0u32, 0u32);
    for (i, &level) in profile.values.iter().enumerate() {
        let counted = i > profile.burn;
        while level - reference >= c_on {
            reference += c_on;
            on += counted as u32;
        }
        while reference - level >= c_off {
            reference -= c_off;
            off += counted as u32;
        }
    }
    (on, off)
}

/// The pixel the scans simulate besides its ON threshold: its OFF threshold as a multiple
/// of the ON one, and its refractory period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanPixel {
    /// OFF threshold / ON threshold.
    pub ratio: f64,
    /// Refractory period, seconds (0: none).
    pub refractory_s: f64,
}

impl ScanPixel {
    pub const SYMMETRIC: ScanPixel = ScanPixel {
        ratio: 1.0,
        refractory_s: 0.0,
    };

    /// ON and OFF events along `profile`, whose [`Profile::range`] is `range`, at ON
    /// threshold `c`.
    fn count(&self, profile: &Profile, range: f32, c: f64) -> (u32, u32) {
        let (c_on, c_off) = (c as f32, (c * self.ratio) as f32);
        if c_on > range && c_off > range {
            (0, 0)
        } else if self.refractory_s > 0.0 {
            count_refractory(profile, c_on, c_off, self.refractory_s)
        } else {
            count(profile, c_on, c_off)
        }
    }
}

/// [`count`] for a pixel with a refractory period (the simulator's and v2e's semantics,
/// [`crate::sim::effects::refractory`]): after an event the pixel cannot fire for
/// `refractory_s`; a crossing inside the period stays pending and fires when it ends if the
/// level is then still a threshold away, one event per period. Between samples the level
/// is interpolated linearly in time, so crossings are timed within a sample.
pub fn count_refractory(profile: &Profile, c_on: f32, c_off: f32, refractory_s: f64) -> (u32, u32) {
    let (v, t) = (&profile.values, &profile.times_s);
    let mut reference = v[0];
    let mut ready = f64::NEG_INFINITY;
    let (mut on, mut off) = (0u32, 0u32);
    for i in 1..v.len().min(t.len()) {
        let (t0, t1, v0, v1) = (t[i - 1], t[i], v[i - 1], v[i]);
        let counted = (i > profile.burn) as u32;
        let level_at = |s: f64| {
            if t1 > t0 {
                v0 + (v1 - v0) * ((s - t0) / (t1 - t0)) as f32
            } else {
                v1
            }
        };
        let mut from = t0;
        loop {
            let start = from.max(ready);
            if start > t1 {
                break;
            }
            let level = level_at(start);
            let fired = if level - reference >= c_on {
                Some((start, true))
            } else if reference - level >= c_off {
                Some((start, false))
            } else {
                // the next crossing later in this stretch, if the level gets there
                let up = v1 > level;
                let target = if up {
                    reference + c_on
                } else {
                    reference - c_off
                };
                let reached = if up { v1 >= target } else { v1 <= target };
                (reached && v1 != level && t1 > start).then(|| {
                    let f = f64::from((target - level) / (v1 - level));
                    (start + f * (t1 - start), up)
                })
            };
            let Some((at, up)) = fired else { break };
            if up {
                reference += c_on;
                on += counted;
            } else {
                reference -= c_off;
                off += counted;
            }
            ready = at + refractory_s;
            from = at;
        }
    }
    (on, off)
}

/// Which polarity a calibration curve is read for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    On,
    Off,
}

impl Side {
    /// Events of this polarity per pixel of travel at a curve point.
    pub fn rate(self, p: &CurvePoint) -> f64 {
        match self {
            Side::On => p.on_per_px,
            Side::Off => p.off_per_px,
        }
    }

    /// This polarity's threshold at a curve point.
    pub fn threshold(self, p: &CurvePoint) -> f64 {
        match self {
            Side::On => p.ct,
            Side::Off => p.ct_off,
        }
    }
}

/// One point of a calibration curve: at ON threshold `ct` and OFF threshold `ct_off`, ON and
/// OFF events per pixel of travel over the scans that fired, and the share of scans that
/// fired.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct CurvePoint {
    pub ct: f64,
    pub ct_off: f64,
    pub on_per_px: f64,
    pub off_per_px: f64,
    pub active_fraction: f64,
    /// Events per scan (ON + OFF), over all scans.
    pub events_per_scan: f64,
}

/// The calibration curve of `profiles` at every ON threshold of `grid` for `pixel`: per
/// pixel of the travel of the scans that fired (`fired_only`, as the recording's pixels are
/// counted without frames) or of all scans.
pub fn curve(
    profiles: &[Profile],
    grid: &[f64],
    fired_only: bool,
    pixel: ScanPixel,
) -> Vec<CurvePoint> {
    let ranges: Vec<f32> = profiles.par_iter().map(Profile::range).collect();
    grid.par_iter()
        .map(|&ct| {
            let (mut on, mut off, mut travel, mut active) = (0u64, 0u64, 0.0f64, 0usize);
            for (p, &range) in profiles.iter().zip(&ranges) {
                let (a, b) = pixel.count(p, range, ct);
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
                ct_off: ct * pixel.ratio,
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

/// ON and OFF events of a block's pixels at each ON threshold of `grid`.
fn block_counts(image: &LogImage, block: &Block, grid: &[f64], pixel: ScanPixel) -> Vec<[u32; 2]> {
    let mut out = vec![[0u32; 2]; grid.len()];
    for j in 0..TILE_PX {
        for i in 0..TILE_PX {
            let scan = Scan {
                x: block.corner.x + i as f64,
                y: block.corner.y + j as f64,
                ..block.corner
            };
            let p = profile(image, &scan);
            let range = p.range();
            for (slot, &c) in out.iter_mut().zip(grid) {
                let (on, off) = pixel.count(&p, range, c);
                slot[0] += on;
                slot[1] += off;
            }
        }
    }
    out
}

/// The calibration curve of `blocks` through `image` for `pixel`: per ON threshold, events
/// per pixel of travel over the blocks where any pixel fired (as the recording's tiles are
/// counted).
pub fn block_curve(
    image: &LogImage,
    blocks: &[Block],
    grid: &[f64],
    pixel: ScanPixel,
) -> Vec<CurvePoint> {
    let counts: Vec<Vec<[u32; 2]>> = blocks
        .par_iter()
        .map(|b| block_counts(image, b, grid, pixel))
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
                ct_off: grid[k] * pixel.ratio,
                on_per_px: on as f64 / travel,
                off_per_px: off as f64 / travel,
                active_fraction: active as f64 / blocks.len().max(1) as f64,
                events_per_scan: (on + off) as f64 / (pixels * blocks.len().max(1) as f64),
            }
        })
        .collect()
}

/// Where a target rate falls against a calibration curve (its rate falls with the
/// threshold, though not always strictly: a noisy tail of few firing blocks can rise again).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Inverted {
    /// At this threshold, interpolated in log-log between the two grid points around it.
    At(f64),
    /// Between two grid points: the curve makes more events than the target at the first
    /// and none at the second (the scene's whole log range is crossed by one threshold
    /// there), so the threshold lies in `(lo, hi]`.
    Between(f64, f64),
    /// Fewer events than the curve makes even at its highest threshold: above it.
    Above(f64),
    /// More events than the curve makes even at its lowest threshold: below it.
    Below(f64),
    /// A target that is not a positive rate, or a curve without events.
    Outside,
}

impl Inverted {
    /// The threshold this calibration gives, or the grid bound that stands in for it
    /// (`Between`: the geometric middle of its two points).
    pub fn value(self) -> Option<f64> {
        match self {
            Inverted::At(v) | Inverted::Above(v) | Inverted::Below(v) => Some(v),
            Inverted::Between(lo, hi) => Some((lo * hi).sqrt()),
            Inverted::Outside => None,
        }
    }
}

/// The threshold of `side` at which its rate reaches `target`: the first pair of grid
/// points whose rates bracket it, interpolated in log-log (or bounded, where the second
/// makes no events); else which end of the curve the target lies beyond.
pub fn invert(curve: &[CurvePoint], side: Side, target: f64) -> Inverted {
    if target.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Inverted::Outside;
    }
    for w in curve.windows(2) {
        let (r0, r1) = (side.rate(&w[0]), side.rate(&w[1]));
        let (c0, c1) = (side.threshold(&w[0]), side.threshold(&w[1]));
        if !(r0 >= target && target >= r1) {
            continue;
        }
        if r1 == 0.0 {
            return Inverted::Between(c0, c1);
        }
        if r0 == r1 {
            // a plateau at the target
            return Inverted::At((c0 * c1).sqrt());
        }
        let f = (target.ln() - r0.ln()) / (r1.ln() - r0.ln());
        return Inverted::At((c0.ln() + f * (c1.ln() - c0.ln())).exp());
    }
    match (curve.first(), curve.last()) {
        (Some(first), _) if target > side.rate(first) => Inverted::Below(side.threshold(first)),
        (_, Some(last)) if target < side.rate(last) => Inverted::Above(side.threshold(last)),
        _ => Inverted::Outside,
    }
}

/// The local slope `d ln rate / d ln threshold` of `side` at threshold `ct` (for turning an
/// error of the rate into an error of the threshold); -1 where it cannot be measured.
pub fn log_slope(curve: &[CurvePoint], side: Side, ct: f64) -> f64 {
    curve
        .windows(2)
        .find(|w| side.threshold(&w[0]) <= ct && ct <= side.threshold(&w[1]))
        .and_then(|w| {
            let (r0, r1) = (side.rate(&w[0]), side.rate(&w[1]));
            let (c0, c1) = (side.threshold(&w[0]), side.threshold(&w[1]));
            (r0 > 0.0 && r1 > 0.0).then(|| (r1.ln() - r0.ln()) / (c1.ln() - c0.ln()))
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
            seconds_per_px: 0.01,
        };
        let p = profile(&image, &scan);
        let (on, off) = count(&p, 0.3, 0.3);
        assert_eq!(off, 0);
        assert!(on == 6 || on == 7, "{on}");
        // against the ramp: OFF
        let back = Scan {
            dx: -1.0,
            x: 120.0,
            ..scan
        };
        assert_eq!(count(&profile(&image, &back), 0.3, 0.3).0, 0);
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
                        seconds_per_px: 0.01,
                    },
                )
            })
            .collect();
        let grid = threshold_grid();
        let c = curve(&profiles, &grid, true, ScanPixel::SYMMETRIC);
        // 0.05 per pixel: 0.05 / C events per pixel of travel
        let Inverted::At(ct) = invert(&c, Side::On, 0.05 / 0.25) else {
            panic!("the ramp's rate is on its curve");
        };
        assert!((ct - 0.25).abs() < 0.01, "{ct}");
        let slope = log_slope(&c, Side::On, 0.25);
        // counts are whole events (17 at 0.3 for 16.7), so the slope between grid points is
        // about -1 within that rounding
        assert!((slope + 1.0).abs() < 0.2, "{slope}");
        assert!((grid[0] - 0.03).abs() < 1e-12 && (grid[24] - 3.0).abs() < 1e-9);
    }

    /// A curve with the given ON rates at thresholds 0.1, 0.2, 0.4, ...
    fn rates_curve(rates: &[f64]) -> Vec<CurvePoint> {
        rates
            .iter()
            .enumerate()
            .map(|(k, &r)| CurvePoint {
                ct: 0.1 * 2f64.powi(k as i32),
                ct_off: 0.3 * 2f64.powi(k as i32),
                on_per_px: r,
                off_per_px: r,
                active_fraction: 1.0,
                events_per_scan: r,
            })
            .collect()
    }

    #[test]
    fn a_target_is_read_off_its_curve_or_bounded_where_the_curve_ends() {
        let curve = rates_curve(&[0.8, 0.4, 0.1, 0.0, 0.0]);
        // on the curve: log-log between 0.2 (0.4) and 0.4 (0.1)
        match invert(&curve, Side::On, 0.2) {
            Inverted::At(v) => assert!((v - 0.2 * 2f64.powf(0.5)).abs() < 1e-12, "{v}"),
            other => panic!("{other:?}"),
        }
        // the OFF side reads its own thresholds
        match invert(&curve, Side::Off, 0.4) {
            Inverted::At(v) => assert!((v - 0.6).abs() < 1e-12, "{v}"),
            other => panic!("{other:?}"),
        }
        // fewer events than at 0.4, none at 0.8: between them
        assert_eq!(invert(&curve, Side::On, 0.05), Inverted::Between(0.4, 0.8));
        assert!((Inverted::Between(0.4, 0.8).value().unwrap() - 0.32f64.sqrt()).abs() < 1e-12);
        // beyond either end
        assert_eq!(invert(&curve, Side::On, 1.0), Inverted::Below(0.1));
        assert_eq!(
            invert(&rates_curve(&[0.8, 0.4, 0.2]), Side::On, 0.1),
            Inverted::Above(0.4)
        );
        // no rate, no curve
        assert_eq!(invert(&curve, Side::On, 0.0), Inverted::Outside);
        assert_eq!(invert(&curve, Side::On, f64::NAN), Inverted::Outside);
        assert_eq!(invert(&[], Side::On, 0.1), Inverted::Outside);
        // a tail that rises again after a zero: the first bracket counts
        assert_eq!(
            invert(&rates_curve(&[0.5, 0.2, 0.0, 0.001, 0.0]), Side::On, 0.1),
            Inverted::Between(0.2, 0.4)
        );
        // a plateau at the target
        assert_eq!(
            invert(&rates_curve(&[0.5, 0.2, 0.2, 0.1]), Side::On, 0.2),
            Inverted::At(0.2)
        );
    }

    #[test]
    fn a_pixel_s_on_count_depends_on_its_off_threshold_where_the_profile_turns() {
        // a triangle wave between 0.05 and 1.1: with thresholds 0.2 / 0.2 the memorised level
        // swings 0.2 <-> 1.0, 4 ON events per rise; with an OFF threshold of 0.6 it falls
        // only to 0.4 (one OFF event of 0.6), so each rise makes 3 ON events (0.6, 0.8, 1.0)
        let values: Vec<f32> = (0..4000)
            .map(|i| {
                let phase = (i % 200) as f32 / 100.0;
                0.05 + 1.05 * if phase < 1.0 { phase } else { 2.0 - phase }
            })
            .collect();
        let p = Profile {
            times_s: (0..values.len()).map(|i| i as f64 * 1e-3).collect(),
            values,
            burn: 400,
            length: 900.0,
        };
        let (on_sym, off_sym) = count(&p, 0.2, 0.2);
        let (on_wide, off_wide) = count(&p, 0.2, 0.6);
        // 18 rises and falls after the burn-in
        assert_eq!((on_sym, off_sym), (72, 72));
        assert_eq!((on_wide, off_wide), (54, 18));
    }

    #[test]
    fn a_refractory_pixel_fires_at_most_once_per_period_and_keeps_the_change_pending() {
        // a ramp of 0.05 per ms: a 0.1 threshold is crossed every 2 ms
        let values: Vec<f32> = (0..=100).map(|i| 0.05 * i as f32).collect();
        let p = Profile {
            times_s: (0..=100).map(|i| i as f64 * 1e-3).collect(),
            values,
            burn: 0,
            length: 25.0,
        };
        let ideal = count(&p, 0.1, 0.1);
        assert_eq!(count_refractory(&p, 0.1, 0.1, 0.0), ideal);
        // 1 ms < 2 ms between crossings: nothing lost, nothing delayed past the end
        assert_eq!(count_refractory(&p, 0.1, 0.1, 1e-3), ideal);
        // 5 ms: one event per 5 ms over the 100 ms ramp (the first at 2 ms)
        let (on, off) = count_refractory(&p, 0.1, 0.1, 5e-3);
        assert_eq!((on, off), (20, 0));
        assert!(ideal.0 >= 49, "{ideal:?}");
    }
}
