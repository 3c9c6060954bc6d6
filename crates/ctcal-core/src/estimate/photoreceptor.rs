//! A photoreceptor much slower than the scene: whether the events follow the frames or a
//! low-passed copy of them.
//!
//! The photoreceptor is a first-order low-pass filter in log intensity whose cutoff rises
//! with photocurrent (Delbruck & Mead 1994; Lichtsteiner et al. 2008; v2e's
//! `f(DN) = f_white (DN + 20) / 275`, as the simulator takes it,
//! [`crate::sim::effects::bandwidth`]). The event timing's lag term, `tau r`, holds while
//! `tau` is short against the time a pixel's brightness takes to turn. Where the cutoff is
//! far below that, the pixel never follows the scene: its log signal is a running average,
//! so it crosses far fewer thresholds than the frames' change, and its events come frames
//! late. Both aps estimators then read the thresholds several times too high (coverage
//! draw 11005: a 6.8 Hz cutoff at white, 1.2 Hz at its 31 DN, read 1.95 for 0.315; draws
//! 10012, 2004 and 4076 alike).
//!
//! The check: each pixel's frame samples, linear in time between frames, pass through the
//! low-pass at each cutoff of [`CUTOFFS_HZ`] and through none; an ideal quantiser fires on
//! the result, its thresholds set so that the ON and the OFF totals match the recording's
//! (one threshold per polarity: the count falls about as its inverse); its ON and OFF
//! counts per block of 4 x 4 pixels and frame interval are compared with the real ones by
//! the chi-square distance `(r - s)^2 / (r + s + 1)`. The quantiser carries the memory of a
//! high threshold (several intervals' change to fire once), which alone would look like a
//! lag, and frame noise hits both sides alike. A cutoff is resolved where it lowers the
//! distance, tile by tile (16 x 16 pixels: neighbouring blocks share edges) against no
//! low-pass, by more than [`RESOLVED_SE`] standard errors of that paired difference, asks
//! for lower thresholds on both polarities, and is not the grid's fastest (a pixel that
//! fast follows the frames within an interval). Pixels near black or clipped are not
//! compared in an interval (as the rest of aps leaves them out), the filter starts settled
//! at the first frame and after a span not read. No flow and no simulator: the frames' samples only,
//! which is enough to tell a pixel that averages over several frames from one that follows
//! them, not to measure a threshold: aps re-simulates the frames with the cutoff found,
//! and eppps scans them through it ([`super::eppps::calibration::low_pass`]).

use super::frames::{PreparedFrames, reliable_pair};
use crate::events::{EventChunk, TimeUs};
use crate::sim::effects::bandwidth;
use rayon::prelude::*;
use serde::Serialize;

/// The cutoffs at white (255 DN) tried, Hz. At the top of the grid a pixel follows frames
/// at the rates APS frames come (at most a few hundred per second) within an interval, and
/// the event timing's lag term covers it: a best cutoff there is not resolved.
pub const CUTOFFS_HZ: [f64; 10] = [1.0, 2.0, 3.0, 5.0, 7.0, 10.0, 20.0, 50.0, 100.0, 200.0];

/// The cutoffs tried first (every other one, with both ends' neighbours), and the gain
/// one of them must show for the rest to be tried: the distance changes smoothly with the
/// cutoff, so where none lowers it by one standard error no cutoff between them lowers it
/// by [`RESOLVED_SE`], and the check stops at half its cost.
const COARSE_CUTOFFS_HZ: [f64; 5] = [1.0, 3.0, 7.0, 20.0, 100.0];
const SCREEN_SE: f64 = 1.0;

/// Standard errors of the paired tile-by-tile difference a cutoff must lower the
/// distance by to be resolved.
pub const RESOLVED_SE: f64 = 3.0;

/// Side of the blocks whose counts are compared, pixels.
const BLOCK_PX: usize = 4;

/// Side of the tiles whose gains are taken as independent, blocks (16 x 16 pixels, the
/// re-simulation's tiles: an edge crosses neighbouring blocks together).
const TILE_BLOCKS: usize = 4;

/// The thresholds the quantiser's are matched within (log units), and how close a count
/// must come to the real total: within [`MATCH_TOLERANCE`] the search stops. A coarse
/// staircase of counts (a checkerboard's pixels all cross the same contrast) can leave no
/// threshold that matches: the nearest count's cells are then scaled to the real total,
/// so that both sides of a comparison hold the recording's events; beyond [`MATCH_MISS`]
/// the cutoff is not compared.
const MATCH_RANGE: [f64; 2] = [1e-3, 10.0];
const MATCH_TOLERANCE: f64 = 0.005;
const MATCH_MISS: f64 = 0.5;

/// At most this many counts to match a threshold.
const MATCH_COUNTS: usize = 40;

/// The first threshold tried (log units: a DAVIS's typical 0.2-0.5, Stoffregen et al.
/// 2020); the steps from it are what matter.
const MATCH_START: f64 = 0.3;

/// At most this many pixel samples (pixels x frames) are held (two f32 copies, 128 MB);
/// beyond, every n-th row of blocks is compared.
const MAX_SAMPLES: usize = 16_000_000;

/// Fewest real events of each polarity, and kept pixels, for a comparison.
const MIN_EVENTS: u64 = 50;
const MIN_PIXELS: usize = 16;

/// What the check found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SlowPhotoreceptor {
    /// The cutoff at white whose low-pass explains the events best (Hz, the simulator's
    /// terms: [`bandwidth::cutoff_at_dn`]).
    pub cutoff_hz: f64,
    /// The grid's cutoffs whose distance lies within two standard errors of the best's
    /// (Hz at white).
    pub cutoff_range_hz: [f64; 2],
    /// The cutoff at the middle frame's median DN, Hz.
    pub cutoff_at_median_dn_hz: f64,
    /// Mean distance per tile without a low-pass and at the cutoff.
    pub distance_without: f64,
    pub distance_at_cutoff: f64,
    /// How many standard errors of the paired difference the cutoff lowers the distance.
    pub significance: f64,
    /// The quantiser's thresholds (ON, OFF) with the cutoff over those without: how much
    /// lower thresholds the low-pass asks for on the same counts.
    pub threshold_ratios: [f64; 2],
    /// The quantiser's thresholds with the cutoff (frame samples only: a start for the
    /// re-simulation, not a measurement).
    pub quantiser_thresholds: [f64; 2],
    /// Every how many rows of blocks were compared (1: all; more where the recording holds
    /// more than [`MAX_SAMPLES`] pixel samples).
    pub block_row_step: usize,
}

/// The quantiser at one cutoff: per-tile distances and its matched thresholds.
struct Tried {
    cutoff_hz: f64,
    distances: Vec<f64>,
    thresholds: [f64; 2],
}

/// The check on `events` and `frames`; `None` where there are too few frames, events or
/// pixels to compare, or no cutoff is resolved.
pub fn check(
    events: &EventChunk,
    frames: &PreparedFrames,
    excluded: &[bool],
) -> Option<SlowPhotoreceptor> {
    resolve(&Samples::new(events, frames, excluded)?)
}

/// The cutoff of [`CUTOFFS_HZ`] that explains `samples`' real counts best, where it is
/// resolved against no low-pass and consistent with a slow photoreceptor.
fn resolve(samples: &Samples) -> Option<SlowPhotoreceptor> {
    let without = samples.tried(None)?;
    let tried = screened_grid(samples, &without)?;
    let best = tried.iter().max_by(|a, b| {
        let gain = |t: &Tried| paired_gain(&without.distances, &t.distances).0;
        gain(a).total_cmp(&gain(b))
    })?;
    let (gain, se) = paired_gain(&without.distances, &best.distances);
    let significance = if se > 0.0 { gain / se } else { 0.0 };
    let ratios = [0, 1].map(|i| best.thresholds[i] / without.thresholds[i]);
    let slower = ratios.iter().all(|&r| r < 1.0);
    let fastest = CUTOFFS_HZ[CUTOFFS_HZ.len() - 1];
    if !(significance > RESOLVED_SE && slower && best.cutoff_hz < fastest) {
        return None;
    }
    let tiles = without.distances.len().max(1) as f64;
    Some(SlowPhotoreceptor {
        cutoff_hz: best.cutoff_hz,
        cutoff_range_hz: cutoff_range(&tried, best),
        cutoff_at_median_dn_hz: bandwidth::cutoff_at_dn(samples.median_dn, best.cutoff_hz),
        distance_without: without.distances.iter().sum::<f64>() / tiles,
        distance_at_cutoff: best.distances.iter().sum::<f64>() / tiles,
        significance,
        threshold_ratios: ratios,
        quantiser_thresholds: best.thresholds,
        block_row_step: samples.block_row_step,
    })
}

/// The quantiser at the coarse cutoffs, and at the rest where one of those gains at
/// least [`SCREEN_SE`] standard errors; `None` where none does.
fn screened_grid(samples: &Samples, without: &Tried) -> Option<Vec<Tried>> {
    let tried_at = |cutoffs: &[f64]| -> Vec<Tried> {
        cutoffs
            .par_iter()
            .filter_map(|&f| samples.tried(Some(f)))
            .collect()
    };
    let mut tried = tried_at(&COARSE_CUTOFFS_HZ);
    let screened = tried.iter().any(|t| {
        let (gain, se) = paired_gain(&without.distances, &t.distances);
        gain > SCREEN_SE * se
    });
    if !screened {
        return None;
    }
    let rest: Vec<f64> = CUTOFFS_HZ
        .iter()
        .copied()
        .filter(|f| !COARSE_CUTOFFS_HZ.contains(f))
        .collect();
    tried.extend(tried_at(&rest));
    Some(tried)
}

/// The lowest and highest cutoffs whose distance rises over the best's by no more than
/// two standard errors of the paired difference.
fn cutoff_range(tried: &[Tried], best: &Tried) -> [f64; 2] {
    let within = tried.iter().filter(|t| {
        let (gain, se) = paired_gain(&best.distances, &t.distances);
        -gain <= 2.0 * se
    });
    within.fold([f64::INFINITY, 0.0], |[lo, hi], t| {
        [lo.min(t.cutoff_hz), hi.max(t.cutoff_hz)]
    })
}

/// How much `other` lowers the per-tile distances `base`: the sum of the differences and
/// its standard error (the differences' spread times the square root of their number; 0
/// for a single tile, which then resolves nothing).
fn paired_gain(base: &[f64], other: &[f64]) -> (f64, f64) {
    let n = base.len() as f64;
    let d: Vec<f64> = base.iter().zip(other).map(|(a, b)| a - b).collect();
    let sum: f64 = d.iter().sum();
    let mean = sum / n;
    let var = d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (sum, (var * n).sqrt())
}

/// The pixels' frame samples, the real counts and the blocks they are compared in.
struct Samples {
    /// Log intensity per frame, pixel-major (`pixel * frames + k`), kept pixels only.
    log: Vec<f32>,
    /// Frame DN per frame, same layout (the cutoff's intensity, and which intervals are
    /// reliable).
    dn: Vec<f32>,
    /// Frame times, microseconds.
    times: Vec<TimeUs>,
    /// Intervals whose counts are compared (used by aps).
    compared: Vec<bool>,
    /// Intervals after which the filter and quantiser restart (a span whose events were
    /// not read).
    restart: Vec<bool>,
    /// Block of each kept pixel, and tile of each block.
    block_of: Vec<usize>,
    tile_of: Vec<usize>,
    tiles: usize,
    /// Real ON and OFF counts per (block, interval): `block * intervals + k`.
    real_on: Vec<u32>,
    real_off: Vec<u32>,
    /// Real totals over the compared intervals.
    total_on: u64,
    total_off: u64,
    median_dn: f64,
    block_row_step: usize,
}

/// Kept pixels: their index into the samples by sensor index (`usize::MAX`: not kept),
/// block, log and DN samples.
struct Kept {
    slot: Vec<usize>,
    block_of: Vec<usize>,
    log: Vec<f32>,
    dn: Vec<f32>,
}

/// The recording's ON and OFF counts per (block, interval), and their totals.
struct RealCounts {
    on: Vec<u32>,
    off: Vec<u32>,
    total_on: u64,
    total_off: u64,
}

impl Kept {
    /// The real counts of the `compared` intervals in `cells` (block x interval) cells,
    /// where the pixel is kept and reliable in both frames.
    fn count_real(
        &self,
        events: &EventChunk,
        frames: &PreparedFrames,
        compared: &[bool],
        cells: usize,
    ) -> RealCounts {
        let intervals = compared.len();
        let (width, height) = (frames.width, frames.height);
        let mut real = RealCounts {
            on: vec![0; cells],
            off: vec![0; cells],
            total_on: 0,
            total_off: 0,
        };
        for i in 0..events.len() {
            let (x, y) = (events.x[i] as usize, events.y[i] as usize);
            let k = frames.times.partition_point(|&ft| ft <= events.t[i]);
            if x >= width || y >= height || k == 0 || k > intervals || !compared[k - 1] {
                continue;
            }
            let index = y * width + x;
            let p = self.slot[index];
            if p == usize::MAX || !frames.reliable(k - 1, index) {
                continue;
            }
            let cell = self.block_of[p] * intervals + (k - 1);
            if events.on[i] {
                real.on[cell] += 1;
                real.total_on += 1;
            } else {
                real.off[cell] += 1;
                real.total_off += 1;
            }
        }
        real
    }
}

impl Samples {
    fn new(events: &EventChunk, frames: &PreparedFrames, excluded: &[bool]) -> Option<Self> {
        let n_frames = frames.times.len();
        if n_frames < 4 || frames.width == 0 || frames.height == 0 {
            return None;
        }
        let intervals = n_frames - 1;
        let (blocks_x, blocks_y) = (
            frames.width.div_ceil(BLOCK_PX),
            frames.height.div_ceil(BLOCK_PX),
        );
        let block_row_step = (frames.width * frames.height * n_frames).div_ceil(MAX_SAMPLES);
        let kept = Self::kept(frames, excluded, block_row_step.max(1));
        let tiles_x = blocks_x.div_ceil(TILE_BLOCKS);
        let tile_of: Vec<usize> = (0..blocks_x * blocks_y)
            .map(|b| (b / blocks_x / TILE_BLOCKS) * tiles_x + (b % blocks_x) / TILE_BLOCKS)
            .collect();
        let tiles = tiles_x * blocks_y.div_ceil(TILE_BLOCKS);
        let compared: Vec<bool> = frames.intervals.iter().map(|i| i.used).collect();
        let restart: Vec<bool> = (0..intervals)
            .map(|k| {
                let (a, b) = (frames.times[k], frames.times[k + 1]);
                frames.unread.iter().any(|&(s, e)| s < b && e > a)
            })
            .collect();
        let cells = blocks_x * blocks_y * intervals;
        let real = kept.count_real(events, frames, &compared, cells);
        let enough = real.total_on >= MIN_EVENTS
            && real.total_off >= MIN_EVENTS
            && kept.block_of.len() >= MIN_PIXELS;
        enough.then(|| Self {
            times: frames.times.clone(),
            compared,
            restart,
            tile_of,
            tiles,
            real_on: real.on,
            real_off: real.off,
            total_on: real.total_on,
            total_off: real.total_off,
            median_dn: median_dn(frames),
            block_row_step: block_row_step.max(1),
            log: kept.log,
            dn: kept.dn,
            block_of: kept.block_of,
        })
    }

    /// The pixels compared: not `excluded`, in every `step`-th row of blocks, with finite
    /// log values in every frame.
    fn kept(frames: &PreparedFrames, excluded: &[bool], step: usize) -> Kept {
        let (width, height) = (frames.width, frames.height);
        let blocks_x = width.div_ceil(BLOCK_PX);
        let mut kept = Kept {
            slot: vec![usize::MAX; width * height],
            block_of: Vec::new(),
            log: Vec::new(),
            dn: Vec::new(),
        };
        for (index, slot) in kept.slot.iter_mut().enumerate() {
            let (x, y) = (index % width, index / width);
            let out = excluded.get(index).copied().unwrap_or(false)
                || !(y / BLOCK_PX).is_multiple_of(step)
                || frames
                    .dn
                    .iter()
                    .any(|f| !frames.log(f.data[index]).is_finite());
            if out {
                continue;
            }
            *slot = kept.block_of.len();
            kept.block_of.push((y / BLOCK_PX) * blocks_x + x / BLOCK_PX);
            for frame in &frames.dn {
                let v = frame.data[index];
                kept.dn.push(v);
                kept.log.push(frames.log(v));
            }
        }
        kept
    }

    fn frames(&self) -> usize {
        self.times.len()
    }

    /// Every kept pixel's log signal at the frame times through the low-pass at `cutoff`
    /// (at white; `None`: no filter), pixel-major as `log`.
    fn filtered(&self, cutoff: Option<f64>) -> std::borrow::Cow<'_, [f32]> {
        let n = self.frames();
        let Some(cutoff) = cutoff else {
            return std::borrow::Cow::Borrowed(&self.log);
        };
        let mut out = vec![0f32; self.log.len()];
        out.par_chunks_mut(n)
            .zip(self.log.par_chunks(n).zip(self.dn.par_chunks(n)))
            .for_each(|(y, (u, dn))| {
                y[0] = u[0];
                for k in 0..n - 1 {
                    if self.restart[k] {
                        y[k + 1] = u[k + 1];
                        continue;
                    }
                    let h = (self.times[k + 1] - self.times[k]) as f32;
                    let tau = bandwidth::tau_us(0.5 * (dn[k] + dn[k + 1]), cutoff as f32);
                    y[k + 1] = bandwidth::advance(y[k], u[k], u[k + 1], h, tau);
                }
            });
        std::borrow::Cow::Owned(out)
    }

    /// The ideal quantiser's ON (`on`) or OFF events on pixel signal `y` (its frame
    /// samples, `dn` its frame values) with one threshold `c` for both polarities:
    /// `fire(k, count)` for each compared interval `k` in which it fires where the pixel is
    /// reliable.
    #[inline]
    fn quantise(
        &self,
        (y, dn): (&[f32], &[f32]),
        c: f32,
        on: bool,
        mut fire: impl FnMut(usize, u32),
    ) {
        let mut memory = y[0];
        let inverse = 1.0 / c;
        for k in 0..y.len() - 1 {
            if self.restart[k] {
                memory = y[k + 1];
                continue;
            }
            let change = y[k + 1] - memory;
            // whole thresholds crossed: the truncation of a non-negative ratio is its floor
            // (without libm's `floorf` call)
            let steps = (change.abs() * inverse) as u32;
            if steps >= 1 {
                memory += steps as f32 * c * change.signum();
                if (change > 0.0) == on && self.compared[k] && reliable_pair(dn[k], dn[k + 1]) {
                    fire(k, steps);
                }
            }
        }
    }

    fn pixels<'a>(&'a self, signal: &'a [f32]) -> impl Iterator<Item = (&'a [f32], &'a [f32])> {
        signal
            .chunks(self.frames())
            .zip(self.dn.chunks(self.frames()))
    }

    /// The quantiser's total of one polarity over the compared intervals.
    fn quantised_total(&self, signal: &[f32], c: f32, on: bool) -> u64 {
        let n = self.frames();
        signal
            .par_chunks(n)
            .zip(self.dn.par_chunks(n))
            .map(|pixel| {
                let mut total = 0u64;
                self.quantise(pixel, c, on, |_, fired| total += fired as u64);
                total
            })
            .sum()
    }

    /// The quantiser's counts of one polarity per (block, interval).
    fn quantised_cells(&self, signal: &[f32], c: f32, on: bool) -> Vec<u32> {
        let intervals = self.frames() - 1;
        let mut cells = vec![0u32; self.real_on.len()];
        for (p, pixel) in self.pixels(signal).enumerate() {
            let base = self.block_of[p] * intervals;
            self.quantise(pixel, c, on, |k, fired| {
                cells[base + k] = cells[base + k].saturating_add(fired)
            });
        }
        cells
    }

    /// The threshold at which the quantiser's total of one polarity on `signal` matches
    /// the real one. The count falls about as `1 / c`, so `c n(c) / target` is nearly the
    /// root, and a step to it usually lands within [`MATCH_TOLERANCE`] in a few counts; the
    /// count is a step function, so each step is kept inside the bracket the counts so
    /// far allow and falls back to bisecting it (in the logarithm) where it would leave it.
    /// The threshold whose count came nearest, with the real total over that count;
    /// `None` where it misses by more than [`MATCH_MISS`].
    fn matched_threshold(&self, signal: &[f32], on: bool) -> Option<(f32, f64)> {
        let target = (if on { self.total_on } else { self.total_off }) as f64;
        let (mut lo, mut hi) = (MATCH_RANGE[0], MATCH_RANGE[1]);
        let (mut c, mut nearest) = (MATCH_START, (f64::INFINITY, MATCH_START, 0.0));
        for _ in 0..MATCH_COUNTS {
            let n = self.quantised_total(signal, c as f32, on) as f64;
            let miss = (n - target).abs() / target;
            if miss < nearest.0 {
                nearest = (miss, c, n);
            }
            if miss <= MATCH_TOLERANCE || hi / lo < 1.0 + 1e-4 {
                break;
            }
            if n > target {
                lo = c;
            } else {
                hi = c;
            }
            let step = c * n / target;
            c = if n > 0.0 && step > lo && step < hi {
                step
            } else {
                (lo * hi).sqrt()
            };
        }
        (nearest.0 <= MATCH_MISS && nearest.2 > 0.0).then(|| (nearest.1 as f32, target / nearest.2))
    }

    /// The quantiser on the signal low-passed at `cutoff` with the matched thresholds: its
    /// per-tile distance (summed over compared intervals, ON and OFF); `None` where a
    /// threshold does not match.
    fn tried(&self, cutoff: Option<f64>) -> Option<Tried> {
        let signal = self.filtered(cutoff);
        let intervals = self.frames() - 1;
        let mut distances = vec![0f64; self.tiles];
        let mut thresholds = [0f64; 2];
        for (slot, on) in [(0, true), (1, false)] {
            let (c, scale) = self.matched_threshold(&signal, on)?;
            thresholds[slot] = c as f64;
            let simulated = self.quantised_cells(&signal, c, on);
            let real = if on { &self.real_on } else { &self.real_off };
            for (cell, (&r, &s)) in real.iter().zip(&simulated).enumerate() {
                let (r, s) = (r as f64, s as f64 * scale);
                distances[self.tile_of[cell / intervals]] += (r - s).powi(2) / (r + s + 1.0);
            }
        }
        Some(Tried {
            cutoff_hz: cutoff.unwrap_or(f64::INFINITY),
            distances,
            thresholds,
        })
    }
}

/// The median DN of the middle frame (where the cutoff at white is read as a cutoff).
fn median_dn(frames: &PreparedFrames) -> f64 {
    let mut v: Vec<f32> = frames.dn[frames.dn.len() / 2].data.clone();
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f32::total_cmp).1 as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `pixels` pixels, one per block, whose log intensity is a square wave of amplitude
    /// 1 (period `period` frames, phase by pixel) at 100 frames per second, 200 DN.
    fn square_waves(pixels: usize, frames: usize, period: usize) -> Samples {
        let mut log = Vec::new();
        for p in 0..pixels {
            for k in 0..frames {
                log.push(if ((k + p) / (period / 2)).is_multiple_of(2) {
                    0.0
                } else {
                    1.0
                });
            }
        }
        let intervals = frames - 1;
        Samples {
            dn: vec![200.0; log.len()],
            log,
            times: (0..frames as TimeUs).map(|k| k * 10_000).collect(),
            compared: vec![true; intervals],
            restart: vec![false; intervals],
            block_of: (0..pixels).collect(),
            tile_of: (0..pixels).collect(),
            tiles: pixels,
            real_on: vec![0; pixels * intervals],
            real_off: vec![0; pixels * intervals],
            total_on: 0,
            total_off: 0,
            median_dn: 200.0,
            block_row_step: 1,
        }
    }

    /// `samples` with the real counts an ideal quantiser with threshold `c` makes from its
    /// signal low-passed at `cutoff`.
    fn with_counts(mut samples: Samples, cutoff: Option<f64>, c: f32) -> Samples {
        let signal = samples.filtered(cutoff).into_owned();
        samples.real_on = samples.quantised_cells(&signal, c, true);
        samples.real_off = samples.quantised_cells(&signal, c, false);
        samples.total_on = samples.real_on.iter().map(|&n| n as u64).sum();
        samples.total_off = samples.real_off.iter().map(|&n| n as u64).sum();
        samples
    }

    #[test]
    fn the_quantiser_fires_each_whole_threshold_since_its_memory() {
        let mut samples = square_waves(1, 5, 2);
        samples.log = vec![0.0, 0.25, 0.5, 0.1, -0.3];
        let (mut on, mut off) = (vec![0; 4], vec![0; 4]);
        samples.dn = vec![200.0; 5];
        let pixel = (&samples.log[..], &samples.dn[..]);
        samples.quantise(pixel, 0.2, true, |k, n| on[k] += n);
        samples.quantise(pixel, 0.2, false, |k, n| off[k] += n);
        // a clipped frame leaves its intervals uncompared, the memory still moves
        let mut clipped = samples.dn.clone();
        clipped[2] = 255.0;
        let mut on_clipped = vec![0; 4];
        samples.quantise((&samples.log, &clipped), 0.2, true, |k, n| {
            on_clipped[k] += n
        });
        assert_eq!(on_clipped, [1, 0, 0, 0]);
        // memory 0 -> 0.2 -> 0.4 -> 0.2 -> -0.2
        assert_eq!(on, [1, 1, 0, 0]);
        assert_eq!(off, [0, 0, 1, 2]);
    }

    #[test]
    fn the_paired_gain_is_the_sum_of_differences_with_their_standard_error() {
        // differences 2, 3, 2: sum 7, variance 1/3, standard error sqrt(3 / 3) = 1
        let (sum, se) = paired_gain(&[3.0, 5.0, 4.0], &[1.0, 2.0, 2.0]);
        assert!((sum - 7.0).abs() < 1e-12 && (se - 1.0).abs() < 1e-12);
    }

    #[test]
    fn events_of_a_slow_photoreceptor_resolve_its_cutoff() {
        // 5 Hz at white, 3.8 Hz at 200 DN (tau 42 ms), against a wave turning every 80 ms
        let samples = with_counts(square_waves(64, 60, 16), Some(5.0), 0.1);
        let found = resolve(&samples).expect("resolved");
        assert_eq!(found.cutoff_hz, 5.0, "{found:?}");
        assert!(found.cutoff_range_hz[0] <= 5.0 && found.cutoff_range_hz[1] >= 5.0);
        assert!((found.cutoff_at_median_dn_hz - 5.0 * 220.0 / 275.0).abs() < 1e-9);
        // the unfiltered wave asks for thresholds several times higher on these counts
        assert!(found.threshold_ratios.iter().all(|&r| r < 0.7), "{found:?}");
    }

    #[test]
    fn a_count_between_the_steps_is_matched_by_the_nearest_scaled() {
        // a wave of amplitude 1: each rise fires 1 ON for c in (0.5, 1], 2 in (1/3, 0.5]
        let mut samples = square_waves(8, 40, 8);
        let rises = samples.quantised_total(&samples.log, 0.9, true);
        // more events than the lowest threshold tried (1e-3: 1000 a rise) makes
        samples.total_on = rises * 5000;
        assert_eq!(samples.matched_threshold(&samples.log, true), None);
        // between the steps: the nearest count, scaled to the total
        samples.total_on = rises + rises * 3 / 10;
        let (c, scale) = samples.matched_threshold(&samples.log, true).expect("near");
        let n = samples.quantised_total(&samples.log, c, true) as f64;
        assert!(c > 1.0 / 3.0 && c <= 1.0, "{c}");
        assert!(
            (n * scale - samples.total_on as f64).abs() < 1e-6,
            "{n} {scale}"
        );
        samples.total_on = rises;
        let (c, scale) = samples
            .matched_threshold(&samples.log, true)
            .expect("matched");
        assert!(c > 0.5 && c <= 1.0 && scale == 1.0, "{c} {scale}");
    }

    #[test]
    fn events_of_a_fast_photoreceptor_resolve_none() {
        let samples = with_counts(square_waves(64, 60, 16), None, 0.1);
        assert_eq!(resolve(&samples), None);
        // 1 kHz at white follows 100 Hz frames within an interval
        let samples = with_counts(square_waves(64, 60, 16), Some(1000.0), 0.1);
        assert_eq!(resolve(&samples), None);
    }
}
