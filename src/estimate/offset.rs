//! The black offset of grey frames. APS frames are often written with a black level
//! subtracted (`DN = g (I - b)`, dark pixels clipped at 0), so `ln(DN)` exaggerates log
//! changes, most in the dark, and every threshold measured from such frames comes out too
//! high. The offset is identifiable from the events: a pixel's threshold does not depend on
//! how bright it is, so with the right offset `o` the event-timing samples
//! `ln(DN_j + o) - ln(DN_i + o)` ([`super::timing`]) do not depend on the intensity level.
//! The offset is the root of the regression slope of the (polarity-normalised) samples on
//! `ln(DN + o)`, found by bisection.
//!
//! Only looked for when the frames show the signature of a subtracted black level (pixels
//! clipped at exactly 0 DN): simulator frames and frames of a sensor without one have none,
//! and a slope there can come from real physics (the photoreceptor's bandwidth falls in the
//! dark), which the offset must not absorb.

use super::frames::PreparedFrames;
use crate::events::{EventChunk, Sensor};
use serde::Serialize;

/// Share of frame pixels at exactly 0 DN from which a subtracted black level is assumed.
pub const CLIPPED_BLACK_SHARE: f64 = 0.002;

/// Samples needed per polarity to estimate the offset.
const MIN_PAIRS: usize = 2000;

/// The estimated offset.
#[derive(Clone, Debug, Serialize)]
pub struct BlackOffset {
    /// DN added to the frames before the log.
    pub offset_dn: f64,
    /// Sample pairs used.
    pub pairs: usize,
    /// The slope of the samples on log intensity without the offset (the evidence).
    pub slope_without_offset: f64,
}

/// Share of the frames' pixels at exactly 0 DN.
pub fn clipped_black_share(frames: &PreparedFrames) -> f64 {
    let (zero, all) = frames.dn.iter().fold((0usize, 0usize), |(z, a), d| {
        (
            z + d.data.iter().filter(|&&v| v == 0.0).count(),
            a + d.data.len(),
        )
    });
    zero as f64 / all.max(1) as f64
}

/// (DN at the first event, DN at the second, second event ON) for consecutive events of a
/// pixel in used intervals, DN interpolated along the flow without any offset.
fn pairs(
    events: &EventChunk,
    frames: &PreparedFrames,
    sensor: Sensor,
    excluded: &[bool],
) -> Vec<(f32, f32, bool)> {
    let width = sensor.width as usize;
    let mut previous = vec![f32::NAN; sensor.pixels()];
    let mut out = Vec::new();
    for i in 0..events.len() {
        let (x, y) = (events.x[i], events.y[i]);
        let pixel = y as usize * width + x as usize;
        if excluded[pixel] {
            continue;
        }
        let dn = frames.dn_at(x, y, events.t[i]).unwrap_or(f32::NAN);
        let before = previous[pixel];
        if before.is_finite() && dn.is_finite() {
            out.push((before, dn, events.on[i]));
        }
        previous[pixel] = dn;
    }
    out
}

/// The regression slope of the polarity-normalised samples on the log level, with offset
/// `o` (`None` with too few inliers).
fn slope(pairs: &[(f32, f32, bool)], o: f64) -> Option<f64> {
    let mut normalised = Vec::with_capacity(pairs.len());
    for on in [true, false] {
        let sign = if on { 1.0 } else { -1.0 };
        let samples: Vec<(f64, f64)> = pairs
            .iter()
            .filter(|p| p.2 == on)
            .map(|&(a, b, _)| {
                let (a, b) = (a as f64 + o, b as f64 + o);
                (sign * (b.ln() - a.ln()), (0.5 * (a + b)).ln())
            })
            .filter(|(d, level)| d.is_finite() && level.is_finite())
            .collect();
        let mut values: Vec<f64> = samples.iter().map(|s| s.0).filter(|&d| d > 0.0).collect();
        if values.len() < MIN_PAIRS {
            return None;
        }
        let mid = values.len() / 2;
        let median = *values.select_nth_unstable_by(mid, f64::total_cmp).1;
        normalised.extend(
            samples
                .iter()
                .filter(|(d, _)| *d > 0.3 * median && *d < 2.5 * median)
                .map(|&(d, level)| (d / median, level)),
        );
    }
    let n = normalised.len() as f64;
    let (md, ml) = normalised
        .iter()
        .fold((0.0, 0.0), |(a, b), (d, l)| (a + d / n, b + l / n));
    let sll: f64 = normalised.iter().map(|(_, l)| (l - ml).powi(2)).sum();
    let sdl: f64 = normalised.iter().map(|(d, l)| (d - md) * (l - ml)).sum();
    (sll > 0.0).then(|| sdl / sll)
}

/// Estimates the black offset of `frames` (whose own offset must be 0).
pub fn estimate(
    events: &EventChunk,
    frames: &PreparedFrames,
    sensor: Sensor,
    excluded: &[bool],
) -> Option<BlackOffset> {
    let pairs = pairs(events, frames, sensor, excluded);
    let floor = pairs
        .iter()
        .map(|p| p.0.min(p.1) as f64)
        .fold(f64::INFINITY, f64::min);
    let (mut lo, mut hi) = (1.0 - floor.max(0.0) * 0.9, 255.0);
    let (slope_lo, slope_hi) = (slope(&pairs, lo)?, slope(&pairs, hi)?);
    let without = slope(&pairs, 0.0)?;
    // too small an offset leaves dark changes too large: the slope is negative there
    if !(slope_lo < 0.0 && slope_hi > 0.0) {
        return None;
    }
    for _ in 0..30 {
        let mid = 0.5 * (lo + hi);
        if slope(&pairs, mid)? < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(BlackOffset {
        offset_dn: 0.5 * (lo + hi),
        pairs: pairs.len(),
        slope_without_offset: without,
    })
}
