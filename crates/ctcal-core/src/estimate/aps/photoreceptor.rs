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
//! distance, block by block against no low-pass, by more than [`RESOLVED_SE`] standard
//! errors of that paired difference. No flow and no simulator: the frames' samples only,
//! which is enough to tell a pixel that averages over several frames from one that follows
//! them, not to measure a threshold (aps re-simulates with the cutoff found for that).

use super::super::frames::PreparedFrames;
use crate::events::{EventChunk, TimeUs};
use crate::sim::effects::bandwidth;
use rayon::prelude::*;
use serde::Serialize;

/// The cutoffs at white (255 DN) tried, Hz. Above 200 Hz a pixel follows frames at the
/// rates APS frames come (at most a few hundred per second) within an interval; the event
/// timing's lag term covers the rest.
pub const CUTOFFS_HZ: [f64; 10] = [1.0, 2.0, 3.0, 5.0, 7.0, 10.0, 20.0, 50.0, 100.0, 200.0];

/// Standard errors of the paired block-by-block difference a cutoff must lower the
/// distance by to be resolved.
pub const RESOLVED_SE: f64 = 3.0;

/// The cutoffs tried first (one in three of [`CUTOFFS_HZ`], spanning it), and the gain one
/// of them must show for the others to be tried: where none lowers the distance by even
/// one standard error, no neighbour between them lowers it by three (the distance changes
/// smoothly with the cutoff), and the check stops at a third of its cost.
const COARSE_CUTOFFS_HZ: [f64; 4] = [2.0, 5.0, 20.0, 100.0];
const SCREEN_SE: f64 = 1.0;

/// Side of the blocks whose counts are compared, pixels.
const BLOCK_PX: usize = 4;

/// The thresholds the quantiser's are matched within (log units).
const MATCH_RANGE: [f64; 2] = [1e-3, 10.0];

/// How close a matched threshold's count comes to the real one (relative).
const MATCH_TOLERANCE: f64 = 0.005;

/// At most this many counts to match a threshold.
const MATCH_COUNTS: usize = 40;

/// What the check found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SlowPhotoreceptor {
    /// The cutoff at white whose low-pass explains the events best (Hz, simulator terms).
    pub cutoff_hz: f64,
    /// The cutoffs of the grid whose distance lies within two standard errors of the
    /// best's (Hz at white).
    pub cutoff_range_hz: [f64; 2],
    /// The cutoff at the frames' median DN, Hz.
    pub cutoff_at_median_dn_hz: f64,
    /// Mean distance per block without a low-pass and at the cutoff.
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
}

/// The pixels' frame samples, the real counts and the blocks they are compared in.
struct Samples {
    /// Log intensity per frame, pixel-major (`pixel * frames + k`), kept pixels only.
    log: Vec<f32>,
    /// Frame DN per frame, same layout (the cutoff's intensity).
    dn: Vec<f32>,
    /// Frame times, microseconds.
    times: Vec<TimeUs>,
    /// Intervals whose counts are compared (used by aps).
    compared: Vec<bool>,
    /// Intervals after which the filter and quantiser restart (a span whose events were
    /// not read).
    restart: Vec<bool>,
    /// Block of each kept pixel.
    block_of: Vec<usize>,
    blocks: usize,
    /// Real ON and OFF counts per (block, interval): `block * intervals + k`.
    real_on: Vec<u32>,
    real_off: Vec<u32>,
    /// Real totals over the compared intervals.
    total_on: u64,
    total_off: u64,
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
/// resolved against no low-pass.
fn resolve(samples: &Samples) -> Option<SlowPhotoreceptor> {
    let without = samples.distances(None)?;
    let gain = |d: &[f64]| paired_gain(&without.0, d);
    let tried_at = |cutoffs: &[f64]| -> Vec<(f64, Vec<f64>, [f64; 2])> {
        cutoffs
            .par_iter()
            .filter_map(|&f| {
                let (d, c) = samples.distances(Some(f))?;
                Some((f, d, c))
            })
            .collect()
    };
    // every third cutoff first; the rest only where one of those gains at all
    let mut tried = tried_at(&COARSE_CUTOFFS_HZ);
    let screened = tried.iter().any(|t| {
        let (g, se) = gain(&t.1);
        g > SCREEN_SE * se
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
    let (best, best_gain) = tried
        .iter()
        .map(|t| (t, gain(&t.1)))
        .max_by(|a, b| a.1.0.total_cmp(&b.1.0))?;
    let (gain_sum, se) = best_gain;
    let significance = if se > 0.0 { gain_sum / se } else { 0.0 };
    if significance.is_nan() || significance <= RESOLVED_SE {
        return None;
    }
    let best_total: f64 = best.1.iter().sum();
    // a worse cutoff raises the distance against the best's: within 2 standard errors
    let within: Vec<f64> = tried
        .iter()
        .filter(|t| {
            let (g, se) = paired_gain(&best.1, &t.1);
            -g <= 2.0 * se
        })
        .map(|t| t.0)
        .collect();
    let blocks = without.0.len().max(1) as f64;
    let median_dn = samples.median_dn();
    Some(SlowPhotoreceptor {
        cutoff_hz: best.0,
        cutoff_range_hz: [
            within.iter().copied().fold(f64::INFINITY, f64::min),
            within.iter().copied().fold(0.0, f64::max),
        ],
        cutoff_at_median_dn_hz: best.0 * (median_dn + 20.0) / 275.0,
        distance_without: without.0.iter().sum::<f64>() / blocks,
        distance_at_cutoff: best_total / blocks,
        significance,
        threshold_ratios: [best.2[0] / without.1[0], best.2[1] / without.1[1]],
        quantiser_thresholds: best.2,
    })
}

/// How much `other` lowers the per-block distances `base`: the sum of the differences and
/// its standard error (the differences' spread times the square root of their number).
fn paired_gain(base: &[f64], other: &[f64]) -> (f64, f64) {
    let n = base.len() as f64;
    let d: Vec<f64> = base.iter().zip(other).map(|(a, b)| a - b).collect();
    let sum: f64 = d.iter().sum();
    let mean = sum / n;
    let var = d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (sum, (var * n).sqrt())
}

impl Samples {
    fn new(events: &EventChunk, frames: &PreparedFrames, excluded: &[bool]) -> Option<Self> {
        let (width, height) = (frames.width, frames.height);
        let k_frames = frames.times.len();
        if k_frames < 4 {
            return None;
        }
        let intervals = k_frames - 1;
        let blocks_x = width.div_ceil(BLOCK_PX);
        let blocks = blocks_x * height.div_ceil(BLOCK_PX);
        let mut kept = vec![usize::MAX; width * height];
        let mut block_of = Vec::new();
        let mut log = Vec::new();
        let mut dn = Vec::new();
        for (index, slot) in kept.iter_mut().enumerate() {
            if excluded.get(index).copied().unwrap_or(false) {
                continue;
            }
            *slot = block_of.len();
            block_of.push((index / width / BLOCK_PX) * blocks_x + (index % width) / BLOCK_PX);
            for frame in &frames.dn {
                let v = frame.data[index];
                dn.push(v);
                log.push(frames.log(v));
            }
        }
        let compared: Vec<bool> = frames.intervals.iter().map(|i| i.used).collect();
        let restart: Vec<bool> = (0..intervals)
            .map(|k| {
                let (a, b) = (frames.times[k], frames.times[k + 1]);
                frames.unread.iter().any(|&(s, e)| s < b && e > a)
            })
            .collect();
        let mut real_on = vec![0u32; blocks * intervals];
        let mut real_off = vec![0u32; blocks * intervals];
        let (mut total_on, mut total_off) = (0u64, 0u64);
        for i in 0..events.len() {
            let t = events.t[i];
            let k = frames.times.partition_point(|&ft| ft <= t);
            if k == 0 || k > intervals || !compared[k - 1] {
                continue;
            }
            let index = events.y[i] as usize * width + events.x[i] as usize;
            let Some(&p) = kept.get(index).filter(|&&p| p != usize::MAX) else {
                continue;
            };
            let cell = block_of[p] * intervals + (k - 1);
            if events.on[i] {
                real_on[cell] += 1;
                total_on += 1;
            } else {
                real_off[cell] += 1;
                total_off += 1;
            }
        }
        (total_on >= 50 && total_off >= 50 && block_of.len() >= 16).then_some(Self {
            log,
            dn,
            times: frames.times.clone(),
            compared,
            restart,
            block_of,
            blocks,
            real_on,
            real_off,
            total_on,
            total_off,
        })
    }

    fn frames(&self) -> usize {
        self.times.len()
    }

    fn median_dn(&self) -> f64 {
        let mut v: Vec<f32> = self.dn.iter().copied().step_by(7).collect();
        if v.is_empty() {
            return 128.0;
        }
        let mid = v.len() / 2;
        *v.select_nth_unstable_by(mid, f32::total_cmp).1 as f64
    }

    /// Every kept pixel's log signal at the frame times through the low-pass at `cutoff`
    /// (at white; `None`: no filter), pixel-major as `log`.
    fn filtered(&self, cutoff: Option<f64>) -> Vec<f32> {
        let n = self.frames();
        let Some(cutoff) = cutoff else {
            return self.log.clone();
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
        out
    }

    /// The ideal quantiser's ON (`on`) or OFF events on pixel signal `y` (its frame
    /// samples) with one threshold `c` for both polarities: `fire(k, count)` for each
    /// interval `k` in which it fires.
    #[inline]
    fn quantise(&self, y: &[f32], c: f32, on: bool, mut fire: impl FnMut(usize, u32)) {
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
                if (change > 0.0) == on && self.compared[k] {
                    fire(k, steps);
                }
            }
        }
    }

    /// The quantiser's total of one polarity over the compared intervals.
    fn quantised_total(&self, signal: &[f32], c: f32, on: bool) -> u64 {
        signal
            .par_chunks(self.frames())
            .map(|y| {
                let mut total = 0u64;
                self.quantise(y, c, on, |_, n| total += n as u64);
                total
            })
            .sum()
    }

    /// The quantiser's counts of one polarity per (block, interval).
    fn quantised_cells(&self, signal: &[f32], c: f32, on: bool) -> Vec<u32> {
        let intervals = self.frames() - 1;
        let mut cells = vec![0u32; self.blocks * intervals];
        for (p, y) in signal.chunks(self.frames()).enumerate() {
            let base = self.block_of[p] * intervals;
            self.quantise(y, c, on, |k, n| cells[base + k] += n);
        }
        cells
    }

    /// The threshold at which the quantiser's total of one polarity on `signal` matches
    /// the real one. The count falls about as `1 / c`, so `c n(c) / target` is nearly the
    /// root, and a step to it usually lands within [`MATCH_TOLERANCE`] in a few counts; the
    /// count is a step function, so each step is kept inside the bracket the counts so
    /// far allow and falls back to bisecting it (in the logarithm) where it would leave it.
    fn matched_threshold(&self, signal: &[f32], on: bool) -> f32 {
        let target = (if on { self.total_on } else { self.total_off }) as f64;
        let (mut lo, mut hi) = (MATCH_RANGE[0], MATCH_RANGE[1]);
        let mut c = 0.3f64;
        for _ in 0..MATCH_COUNTS {
            let n = self.quantised_total(signal, c as f32, on) as f64;
            if (n - target).abs() <= MATCH_TOLERANCE * target {
                return c as f32;
            }
            if n > target {
                lo = c;
            } else {
                hi = c;
            }
            if hi / lo < 1.0 + 1e-4 {
                break;
            }
            let step = c * n / target;
            c = if n > 0.0 && step > lo && step < hi {
                step
            } else {
                (lo * hi).sqrt()
            };
        }
        c as f32
    }

    /// Per-block distance (summed over compared intervals, ON and OFF) of the quantiser on
    /// the signal low-passed at `cutoff`, with the matched thresholds.
    fn distances(&self, cutoff: Option<f64>) -> Option<(Vec<f64>, [f64; 2])> {
        let signal = self.filtered(cutoff);
        let intervals = self.frames() - 1;
        let mut distance = vec![0f64; self.blocks];
        let mut thresholds = [0f64; 2];
        for (slot, on) in [(0, true), (1, false)] {
            let c = self.matched_threshold(&signal, on);
            thresholds[slot] = c as f64;
            let simulated = self.quantised_cells(&signal, c, on);
            let real = if on { &self.real_on } else { &self.real_off };
            for (cell, (&r, &s)) in real.iter().zip(&simulated).enumerate() {
                let (r, s) = (r as f64, s as f64);
                distance[cell / intervals] += (r - s).powi(2) / (r + s + 1.0);
            }
        }
        thresholds
            .iter()
            .all(|c| c.is_finite())
            .then_some((distance, thresholds))
    }
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
        Samples {
            dn: vec![200.0; log.len()],
            log,
            times: (0..frames as TimeUs).map(|k| k * 10_000).collect(),
            compared: vec![true; frames - 1],
            restart: vec![false; frames - 1],
            block_of: (0..pixels).collect(),
            blocks: pixels,
            real_on: Vec::new(),
            real_off: Vec::new(),
            total_on: 0,
            total_off: 0,
        }
    }

    /// `samples` with the real counts an ideal quantiser with threshold `c` makes from its
    /// signal low-passed at `cutoff`.
    fn with_counts(mut samples: Samples, cutoff: Option<f64>, c: f32) -> Samples {
        let signal = samples.filtered(cutoff);
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
        samples.quantise(&samples.log, 0.2, true, |k, n| on[k] += n);
        samples.quantise(&samples.log, 0.2, false, |k, n| off[k] += n);
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
    fn events_of_a_fast_photoreceptor_resolve_none() {
        let samples = with_counts(square_waves(64, 60, 16), None, 0.1);
        assert_eq!(resolve(&samples), None);
        // 1 kHz at white follows 100 Hz frames within an interval
        let samples = with_counts(square_waves(64, 60, 16), Some(1000.0), 0.1);
        assert_eq!(resolve(&samples), None);
    }
}
