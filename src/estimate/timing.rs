//! Contrast thresholds from event timing, per pixel.
//!
//! At each event the pixel's memorised level moves by exactly one threshold to the level the
//! photoreceptor has at that moment (the remainder is kept), so between two consecutive
//! events of one pixel, at `t_i` and `t_j`, its log intensity changed by exactly
//! `L(t_j) - L(t_i) = +Cp` if the second event is ON and `-Cn` if it is OFF, whatever the
//! first one was (Lichtsteiner et al., JSSC 2008; the "event generation model" of Gallego et
//! al., TPAMI 2022). Measuring `L` at the event times from the frames, interpolated along the
//! optical flow ([`super::frames`]), gives one sample of the pixel's threshold per event.
//!
//! Noise events (shot noise, leak, hot pixels) break this chain: a sample is kept only when
//! both its events have spatio-temporal support ([`crate::stats::support`]) and its value
//! lies in the window around the mode of all samples of its polarity. Per pixel the kept
//! samples are averaged into a threshold map; the sensor's thresholds are the mean over
//! pixels (not over events: a low-threshold pixel fires more, and an event-weighted mean
//! would be biased low by the mismatch). The frozen mismatch `ct_sigma` is the spread of
//! the map with each pixel's estimation noise removed: `sigma^2 = Var_p(C_p) - mean_p(s^2 /
//! n_p)`, `s^2` the pooled within-pixel variance of the samples.

use super::frames::PreparedFrames;
use crate::events::{EventChunk, Sensor, TimeUs};
use crate::stats::support::supported;
use rand::{RngExt, SeedableRng};
use serde::Serialize;

/// Settings of the timing estimator.
#[derive(Clone, Debug)]
pub struct TimingOptions {
    /// Spatio-temporal support window for noise rejection (`None`: keep every event).
    pub support_window_us: Option<TimeUs>,
    /// Kept samples lie within this fraction of the mode on either side... below: mode *
    /// (1 - window), above: mode * (1 + 2 window).
    pub mode_window: f64,
    /// Bootstrap resamples for the statistical interval.
    pub bootstrap: usize,
}

impl Default for TimingOptions {
    fn default() -> Self {
        Self {
            support_window_us: None,
            mode_window: 0.5,
            bootstrap: 200,
        }
    }
}

/// The threshold estimate of one polarity.
#[derive(Clone, Debug, Serialize)]
pub struct PolarityEstimate {
    /// Mean over pixels of each pixel's threshold.
    pub ct: f64,
    /// Standard error of `ct` (bootstrap over pixels).
    pub standard_error: f64,
    /// Frozen mismatch, estimation noise removed.
    pub sigma: f64,
    pub sigma_standard_error: f64,
    /// Samples kept, and pixels with at least one.
    pub samples: usize,
    pub pixels: usize,
    /// Samples rejected as noise (outside the mode window).
    pub rejected: usize,
    /// Robust relative spread of the kept samples (1.4826 MAD / mode): how consistently the
    /// frames explain the events.
    pub sample_spread: f64,
}

/// Per-pixel thresholds (NaN without a sample) and sample counts, row-major.
#[derive(Clone, Debug)]
pub struct ThresholdMaps {
    pub width: usize,
    pub height: usize,
    pub ct_on: Vec<f32>,
    pub ct_off: Vec<f32>,
    pub count: Vec<u32>,
}

/// Result of the timing estimator.
#[derive(Clone, Debug)]
pub struct TimingEstimate {
    pub on: PolarityEstimate,
    pub off: PolarityEstimate,
    pub maps: ThresholdMaps,
}

/// One sample: a pixel, the polarity of the second event and the log change.
#[derive(Clone, Copy)]
struct Sample {
    pixel: u32,
    on: bool,
    change: f32,
}

/// Estimates per-pixel thresholds from the timing of `events` (time-sorted) against
/// `frames`. Pixels where `excluded` is set (hot pixels, outside a region) are left out.
/// `None` when there are too few samples.
pub fn estimate(
    events: &EventChunk,
    frames: &PreparedFrames,
    sensor: Sensor,
    excluded: &[bool],
    options: &TimingOptions,
) -> Option<TimingEstimate> {
    let samples = collect_samples(events, frames, sensor, excluded, options);
    let on = polarity(&samples, true, sensor, options)?;
    let off = polarity(&samples, false, sensor, options)?;
    let pixels = sensor.pixels();
    let mut count = vec![0u32; pixels];
    for (values, _) in [&on.1, &off.1] {
        for (p, v) in values.iter().enumerate() {
            count[p] += v.1;
        }
    }
    let map = |values: &Vec<(f64, u32)>| {
        values
            .iter()
            .map(|&(sum, n)| {
                if n > 0 {
                    (sum / n as f64) as f32
                } else {
                    f32::NAN
                }
            })
            .collect()
    };
    Some(TimingEstimate {
        maps: ThresholdMaps {
            width: sensor.width as usize,
            height: sensor.height as usize,
            ct_on: map(&on.1.0),
            ct_off: map(&off.1.0),
            count,
        },
        on: on.0,
        off: off.0,
    })
}

/// How consistently the frames explain the events: the mean over polarities of the robust
/// relative spread of the samples around their mode (smallest when the frames' times are
/// aligned with the events'). `None` with too few samples.
pub fn spread(
    events: &EventChunk,
    frames: &PreparedFrames,
    sensor: Sensor,
    excluded: &[bool],
    options: &TimingOptions,
) -> Option<f64> {
    let samples = collect_samples(events, frames, sensor, excluded, options);
    let mut total = 0.0;
    for on in [true, false] {
        let sign = if on { 1.0 } else { -1.0 };
        let values: Vec<f64> = samples
            .iter()
            .filter(|s| s.on == on)
            .map(|s| sign * s.change as f64)
            .collect();
        let m = mode(&values, options.mode_window / 2.0)?;
        let (lo, hi) = (
            m * (1.0 - options.mode_window),
            m * (1.0 + 2.0 * options.mode_window),
        );
        let mut deviations: Vec<f64> = values
            .iter()
            .filter(|&&v| v >= lo && v <= hi)
            .map(|v| (v - m).abs())
            .collect();
        if deviations.len() < 10 {
            return None;
        }
        let mid = deviations.len() / 2;
        total += 0.5 * 1.4826 * *deviations.select_nth_unstable_by(mid, f64::total_cmp).1 / m;
    }
    Some(total)
}

/// Every usable sample of the recording.
fn collect_samples(
    events: &EventChunk,
    frames: &PreparedFrames,
    sensor: Sensor,
    excluded: &[bool],
    options: &TimingOptions,
) -> Vec<Sample> {
    let support = options
        .support_window_us
        .map(|w| supported(events, sensor, w));
    let width = sensor.width as usize;
    // the previous event of each pixel: its log intensity (NaN when unknown or noise)
    let mut previous = vec![f32::NAN; sensor.pixels()];
    let mut samples = Vec::new();
    for i in 0..events.len() {
        let (x, y) = (events.x[i], events.y[i]);
        let pixel = y as usize * width + x as usize;
        if excluded[pixel] {
            continue;
        }
        let level = match frames.log_at(x, y, events.t[i]) {
            Some(level) if support.as_ref().is_none_or(|s| s[i]) => level,
            _ => f32::NAN,
        };
        let before = previous[pixel];
        if before.is_finite() && level.is_finite() {
            samples.push(Sample {
                pixel: pixel as u32,
                on: events.on[i],
                change: level - before,
            });
        }
        previous[pixel] = level;
    }
    samples
}

/// The mode of `values` (positive thresholds): start at the median, then repeatedly the
/// mean of the values within the window around the estimate.
fn mode(values: &[f64], window: f64) -> Option<f64> {
    let mut sorted: Vec<f64> = values.iter().copied().filter(|v| *v > 0.0).collect();
    if sorted.len() < 10 {
        return None;
    }
    sorted.sort_by(f64::total_cmp);
    let mut m = sorted[sorted.len() / 2];
    for _ in 0..50 {
        let (lo, hi) = (m * (1.0 - window), m * (1.0 + window));
        let a = sorted.partition_point(|&v| v < lo);
        let b = sorted.partition_point(|&v| v <= hi);
        if b <= a {
            break;
        }
        let next = sorted[a..b].iter().sum::<f64>() / (b - a) as f64;
        if (next - m).abs() < 1e-7 * m {
            m = next;
            break;
        }
        m = next;
    }
    Some(m)
}

/// Per-pixel sums and counts of kept samples of one polarity.
type PixelSums = (Vec<(f64, u32)>, Vec<f64>);

fn polarity(
    samples: &[Sample],
    on: bool,
    sensor: Sensor,
    options: &TimingOptions,
) -> Option<(PolarityEstimate, PixelSums)> {
    let sign = if on { 1.0 } else { -1.0 };
    let values: Vec<f64> = samples
        .iter()
        .filter(|s| s.on == on)
        .map(|s| sign * s.change as f64)
        .collect();
    let m = mode(&values, options.mode_window / 2.0)?;
    let (lo, hi) = (
        m * (1.0 - options.mode_window),
        m * (1.0 + 2.0 * options.mode_window),
    );
    let mut sums = vec![(0.0f64, 0u32); sensor.pixels()];
    let mut squares = vec![0.0f64; sensor.pixels()];
    let mut kept = 0;
    for s in samples.iter().filter(|s| s.on == on) {
        let v = sign * s.change as f64;
        if v >= lo && v <= hi {
            let cell = &mut sums[s.pixel as usize];
            cell.0 += v;
            cell.1 += 1;
            squares[s.pixel as usize] += v * v;
            kept += 1;
        }
    }
    let rejected = values.len() - kept;
    let mut deviations: Vec<f64> = values
        .iter()
        .filter(|&&v| v >= lo && v <= hi)
        .map(|v| (v - m).abs())
        .collect();
    let sample_spread = if deviations.is_empty() {
        f64::NAN
    } else {
        let mid = deviations.len() / 2;
        1.4826 * *deviations.select_nth_unstable_by(mid, f64::total_cmp).1 / m
    };
    let pixels: Vec<(f64, u32, f64)> = sums
        .iter()
        .zip(&squares)
        .filter(|((_, n), _)| *n > 0)
        .map(|(&(sum, n), &sq)| (sum, n, sq))
        .collect();
    if pixels.len() < 10 {
        return None;
    }
    let (ct, sigma) = mean_and_sigma(&pixels);
    // bootstrap over pixels
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(if on { 11 } else { 12 });
    let mut cts = Vec::with_capacity(options.bootstrap);
    let mut sigmas = Vec::with_capacity(options.bootstrap);
    let mut resample = Vec::with_capacity(pixels.len());
    for _ in 0..options.bootstrap {
        resample.clear();
        for _ in 0..pixels.len() {
            resample.push(pixels[rng.random_range(0..pixels.len())]);
        }
        let (c, s) = mean_and_sigma(&resample);
        cts.push(c);
        sigmas.push(s);
    }
    Some((
        PolarityEstimate {
            ct,
            standard_error: std_dev(&cts),
            sigma,
            sigma_standard_error: std_dev(&sigmas),
            samples: kept,
            pixels: pixels.len(),
            rejected,
            sample_spread,
        },
        (sums, squares),
    ))
}

/// The mean of per-pixel thresholds and the frozen spread with estimation noise removed,
/// from per-pixel (sum, count, sum of squares).
fn mean_and_sigma(pixels: &[(f64, u32, f64)]) -> (f64, f64) {
    let n = pixels.len() as f64;
    let means: Vec<f64> = pixels.iter().map(|&(s, c, _)| s / c as f64).collect();
    let mean = means.iter().sum::<f64>() / n;
    let between = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    // pooled within-pixel variance over pixels with two samples or more
    let (mut within, mut dof) = (0.0, 0.0);
    for &(s, c, sq) in pixels {
        if c >= 2 {
            within += sq - s * s / c as f64;
            dof += (c - 1) as f64;
        }
    }
    let pooled = if dof > 0.0 { within / dof } else { 0.0 };
    let noise = pixels
        .iter()
        .map(|&(_, c, _)| pooled / c as f64)
        .sum::<f64>()
        / n;
    (mean, (between - noise).max(0.0).sqrt())
}

fn std_dev(values: &[f64]) -> f64 {
    if values.len() < 2 {
        return 0.0;
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mode_ignores_a_broad_noise_floor() {
        // 600 samples at 0.30 +- 0.01 and 400 spread evenly over 0..1
        let mut values: Vec<f64> = (0..600).map(|i| 0.29 + 0.02 * (i as f64 / 600.0)).collect();
        values.extend((0..400).map(|i| i as f64 / 400.0));
        let m = mode(&values, 0.25).unwrap();
        assert!((m - 0.30).abs() < 0.01, "{m}");
    }

    #[test]
    fn sigma_removes_the_estimation_noise_of_each_pixel() {
        // every pixel has the same threshold 0.3 and two samples, each off by +-0.05 (all
        // four combinations equally often): the pixel means spread by 0.035, all of it noise
        let sample = |i: usize, bit: usize| if (i >> bit) & 1 == 0 { 0.35 } else { 0.25 };
        let pixels: Vec<(f64, u32, f64)> = (0..1000)
            .map(|i| {
                let (a, b) = (sample(i, 0), sample(i, 1));
                (a + b, 2, a * a + b * b)
            })
            .collect();
        let (mean, sigma) = mean_and_sigma(&pixels);
        assert!((mean - 0.3).abs() < 1e-3, "{mean}");
        assert!(sigma < 0.005, "{sigma}");
        // a real spread of 0.03 on top is recovered: shift half the pixels by +-0.03
        let shifted: Vec<(f64, u32, f64)> = pixels
            .iter()
            .enumerate()
            .map(|(i, &(s, c, _))| {
                let d = if (i >> 2) & 1 == 0 { 0.03 } else { -0.03 };
                let (a, b) = (sample(i, 0) + d, sample(i, 1) + d);
                (s + 2.0 * d, c, a * a + b * b)
            })
            .collect();
        let (_, sigma) = mean_and_sigma(&shifted);
        assert!((sigma - 0.03).abs() < 0.004, "{sigma}");
    }
}
