//! The sim-to-real distance: one number for how unlike a recording a simulation of it is,
//! made of components that each look at one statistic ([`super::observe`]), so that a user
//! sees which statistic the model still misses:
//!
//! - `counts`: root mean square over count cells (intensity x rate of change x polarity,
//!   supported events) of `ln((s + 1/2) / (r + 1/2))`, each cell weighted by its events,
//!   over cells with at least 40 events in the two together;
//! - `background`: the same over intensity bins and polarities for the rates of unsupported
//!   events, with a floor of 0.01 Hz per pixel (below which noise is not told apart);
//! - `intervals`: total-variation distance between the normalised same-pixel interval
//!   histograms (0: the same shape, 1: disjoint);
//! - `polarity`: `|ln(ON/OFF)|` difference;
//! - `active`: log ratio of the numbers of pixels that fired;
//! - `dispersion`: log ratio of the pooled within-tile index of dispersion of per-pixel
//!   counts (variance over mean), which threshold mismatch raises;
//! - `lag`: root mean square over intensity bins of the recording's median lag behind the
//!   simulation ([`super::observe::lag`]: each supported recorded event's signed offset from
//!   the nearest simulated event of its pixel and polarity) about its mean over the bins, in
//!   median frame intervals (the time the frames resolve a change to), over bins with at
//!   least 50 paired events. A photoreceptor bandwidth the model lacks makes the recording
//!   lag more in the dark; a lag alike at every intensity (frame timestamps at another point
//!   of the exposure than the events assume) is not a pixel's and is left out.
//!
//! The total is the root sum of squares. Every component is dimensionless and about as
//! large as the relative error it measures, so none needs a weight.

use super::observe::{Geometry, INTENSITY_BINS, Observed, Subset, TILE_PX};
use serde::Serialize;

/// The name of the distance, as reported.
pub const ERROR_METRIC: &str = "root sum of squares of: event-weighted RMS log count ratio over intensity x rate-of-change x polarity cells (supported events; a pixel's rate over as many frame intervals, up to 8 a side, as 2 grey levels of change need); event-weighted RMS log ratio of unsupported-event rates per intensity and polarity (floor 0.01 Hz/pixel); total-variation distance of same-pixel interval histograms; |ln(ON/OFF)| difference; |log ratio| of active pixels; |log ratio| of the within-tile index of dispersion of per-pixel counts; RMS over intensity bins of the recording's median signed offset from the nearest simulated event of the same pixel and polarity (supported events, within 100 ms), about its mean over the bins, in median frame intervals";

/// The components of the distance and their total.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Components {
    pub counts: f64,
    pub background: f64,
    pub intervals: f64,
    pub polarity: f64,
    pub active: f64,
    pub dispersion: f64,
    /// The recording's lag behind the simulation (fit with frames only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lag: Option<f64>,
    /// The named hot pixels' rates (fit without frames only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hot_pixels: Option<f64>,
    pub total: f64,
}

/// Events a count cell needs (real and simulated together) to be compared.
const MIN_CELL_EVENTS: u32 = 40;
/// The rate below which unsupported events are not told apart, events per pixel-second.
pub const BACKGROUND_FLOOR_HZ: f64 = 0.01;

fn log_ratio(s: f64, r: f64) -> f64 {
    ((s + 0.5) / (r + 0.5)).ln()
}

/// Root mean square of `(value, weight)` pairs.
fn weighted_rms(values: &[(f64, f64)]) -> f64 {
    let w: f64 = values.iter().map(|v| v.1).sum();
    if w <= 0.0 {
        0.0
    } else {
        (values.iter().map(|(v, w)| w * v * v).sum::<f64>() / w).sqrt()
    }
}

/// The count-cell log ratios (simulated over real) of `subset`, with the real count of each.
pub fn cell_ratios(
    real: &Observed,
    sim: &Observed,
    g: &Geometry,
    subset: Subset,
) -> Vec<(f64, u32, usize)> {
    ratios_of_cells(&real.cells_of(g, subset), &sim.cells_of(g, subset))
}

/// The log ratios (simulated over real) of count cells `r` (real) and `s` (simulated),
/// with the real count and the index of each, over cells with enough events to compare.
pub fn ratios_of_cells(r: &[u32], s: &[u32]) -> Vec<(f64, u32, usize)> {
    r.iter()
        .zip(s)
        .enumerate()
        .filter(|(_, (r, s))| **r + **s >= MIN_CELL_EVENTS)
        .map(|(i, (&r, &s))| (log_ratio(s as f64, r as f64), r, i))
        .collect()
}

/// The simulated events of each cell of [`cell_ratios`] (for weights).
fn cell_weights(
    sim: &Observed,
    g: &Geometry,
    subset: Subset,
    ratios: &[(f64, u32, usize)],
) -> Vec<(f64, f64)> {
    let s = sim.cells_of(g, subset);
    ratios
        .iter()
        .map(|&(ratio, r, i)| (ratio, 0.5 * (r as f64 + s[i] as f64)))
        .collect()
}

/// Unsupported-event rates per `[intensity][polarity]` of `subset` (events per
/// pixel-second), `None` where the bin has no exposure.
pub fn background_rates(o: &Observed, g: &Geometry, subset: Subset) -> Vec<Option<f64>> {
    let counts = o.background_of(g, subset);
    (0..INTENSITY_BINS * 2)
        .map(|i| {
            let exposure = g.exposure_of(i / 2, subset);
            (exposure > 1.0).then(|| counts[i] as f64 / exposure)
        })
        .collect()
}

/// Pooled within-tile index of dispersion of per-pixel counts (tiles with at least 2
/// events per pixel on average), or `None` without such tiles.
pub fn dispersion(counts: &[u32], g: &Geometry, kept: &[bool]) -> Option<f64> {
    let (w, h) = (g.sensor.width as usize, g.sensor.height as usize);
    dispersion_in_tiles(counts, w, h, kept)
}

/// [`dispersion`] of a `w` x `h` sensor's per-pixel `counts`.
fn dispersion_in_tiles(counts: &[u32], w: usize, h: usize, kept: &[bool]) -> Option<f64> {
    let (mut deviation, mut mean_total) = (0.0, 0.0);
    for ty in (0..h).step_by(TILE_PX) {
        for tx in (0..w).step_by(TILE_PX) {
            let values: Vec<f64> = (ty..(ty + TILE_PX).min(h))
                .flat_map(|y| (tx..(tx + TILE_PX).min(w)).map(move |x| y * w + x))
                .filter(|&p| kept[p])
                .map(|p| counts[p] as f64)
                .collect();
            if values.len() < 16 {
                continue;
            }
            let mean = values.iter().sum::<f64>() / values.len() as f64;
            if mean < 2.0 {
                continue;
            }
            deviation += values.iter().map(|v| (v - mean).powi(2)).sum::<f64>();
            mean_total += mean * values.len() as f64;
        }
    }
    (mean_total > 0.0).then(|| deviation / mean_total)
}

/// Indices of dispersion this far apart near zero are not told apart: a tenth of a Poisson
/// process's (1). A tile whose pixels all fired equally often (a regular scene crossed
/// without mismatch: every pixel of a tile meets the same edges) has an index of 0, and the
/// ratio of two indices would be infinite (coverage draw 3016: the fit's mismatch search
/// handed the infinite distance to Brent's line search, which stepped to NaN).
pub const DISPERSION_FLOOR: f64 = 0.1;

/// `ln(simulated / real)` of two [`dispersion`] indices, each with [`DISPERSION_FLOOR`]
/// added: finite for any indices, and less than 0.02 from the plain log ratio where both
/// are at least 5 (counts spread by mismatch, as on real sensors).
pub fn dispersion_log_ratio(real: f64, simulated: f64) -> f64 {
    ((simulated + DISPERSION_FLOOR) / (real + DISPERSION_FLOOR)).ln()
}

/// Normalised histogram.
pub fn normalised(h: &[u32]) -> Vec<f64> {
    let total: f64 = h.iter().map(|&v| v as f64).sum();
    h.iter()
        .map(|&v| if total > 0.0 { v as f64 / total } else { 0.0 })
        .collect()
}

/// The distance of `sim` from `real` over `subset`; `kept` flags the pixels compared
/// (neither left out by the user nor masked as hot).
pub fn distance(
    real: &Observed,
    sim: &Observed,
    g: &Geometry,
    subset: Subset,
    kept: &[bool],
) -> Components {
    let ratios = cell_ratios(real, sim, g, subset);
    let counts = weighted_rms(&cell_weights(sim, g, subset, &ratios));
    let background = background_component(real, sim, g, subset);
    let intervals = interval_component(real, sim, g, subset);
    let polarity = polarity_component(real, sim, g, subset);
    let (active, dispersion) = pixel_components(real, sim, g, subset, kept);
    let lag = lag_component(sim, g, subset);
    let total = [
        counts,
        background,
        intervals,
        polarity,
        active,
        dispersion,
        lag.unwrap_or(0.0),
    ]
    .iter()
    .map(|v| v * v)
    .sum::<f64>()
    .sqrt();
    Components {
        counts,
        background,
        intervals,
        polarity,
        active,
        dispersion,
        lag,
        hot_pixels: None,
        total,
    }
}

/// The `background` component over `subset`: the unsupported events' rate ratio with the
/// floor, weighted by events (a bin needs 20 events in the two, or exposure enough for the
/// floor to make 20).
fn background_component(real: &Observed, sim: &Observed, g: &Geometry, subset: Subset) -> f64 {
    let (rb, sb) = (real.background_of(g, subset), sim.background_of(g, subset));
    weighted_rms(
        &(0..rb.len())
            .filter_map(|i| {
                let exposure = g.exposure_of(i / 2, subset);
                let floor = BACKGROUND_FLOOR_HZ * exposure;
                let (r, s) = (rb[i] as f64, sb[i] as f64);
                (r + s >= 20.0 || floor >= 20.0)
                    .then(|| (((s + floor) / (r + floor)).ln(), 0.5 * (r + s) + floor))
            })
            .collect::<Vec<_>>(),
    )
}

/// The `intervals` component over `subset`: the total-variation distance of the normalised
/// same-pixel interval histograms.
fn interval_component(real: &Observed, sim: &Observed, g: &Geometry, subset: Subset) -> f64 {
    let (ri, si) = (
        normalised(&real.intervals_of(g, subset)),
        normalised(&sim.intervals_of(g, subset)),
    );
    0.5 * ri.iter().zip(&si).map(|(a, b)| (a - b).abs()).sum::<f64>()
}

/// The `polarity` component over `subset`: the `|ln(ON/OFF)|` difference.
fn polarity_component(real: &Observed, sim: &Observed, g: &Geometry, subset: Subset) -> f64 {
    let ([r_off, r_on], [s_off, s_on]) = (real.polarity_of(g, subset), sim.polarity_of(g, subset));
    (log_ratio(s_on as f64, s_off as f64) - log_ratio(r_on as f64, r_off as f64)).abs()
}

/// The `active` and `dispersion` components over `subset`, from the per-pixel counts of
/// the `kept` pixels: the log ratio of the pixels that fired, and of their counts'
/// within-tile dispersion (0 where either has none).
fn pixel_components(
    real: &Observed,
    sim: &Observed,
    g: &Geometry,
    subset: Subset,
    kept: &[bool],
) -> (f64, f64) {
    let (rp, sp) = (real.pixels_of(g, subset), sim.pixels_of(g, subset));
    let active_of = |c: &[u32]| c.iter().zip(kept).filter(|&(&n, &k)| k && n > 0).count() as f64;
    let active = log_ratio(active_of(&sp), active_of(&rp)).abs();
    let dispersion = match (dispersion(&rp, g, kept), dispersion(&sp, g, kept)) {
        (Some(r), Some(s)) => dispersion_log_ratio(r, s).abs(),
        _ => 0.0,
    };
    (active, dispersion)
}

/// The `lag` component of `sim` (paired with the recording) over `subset`: `None` when it
/// was not paired, 0 when fewer than two intensity bins have enough paired events.
fn lag_component(sim: &Observed, g: &Geometry, subset: Subset) -> Option<f64> {
    if sim.lag.every_event.is_empty() || g.frame_interval_s <= 0.0 {
        return None;
    }
    let lags: Vec<f64> = sim
        .lag_of(g, subset)
        .iter()
        .flatten()
        .map(|l| l.median_s / g.frame_interval_s)
        .collect();
    if lags.len() < 2 {
        return Some(0.0);
    }
    let n = lags.len() as f64;
    let mean = lags.iter().sum::<f64>() / n;
    Some((lags.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / n).sqrt())
}

/// The median count-cell log ratio of each polarity over `subset` (OFF, ON): where the
/// thresholds are right, as many cells have too many simulated events as too few.
pub fn median_ratios(
    real: &Observed,
    sim: &Observed,
    g: &Geometry,
    subset: Subset,
) -> [Option<f64>; 2] {
    median_ratios_of(&cell_ratios(real, sim, g, subset))
}

/// The median of the [`ratios_of_cells`] of each polarity (OFF, ON), over cells with at
/// least 5 real events.
pub fn median_ratios_of(ratios: &[(f64, u32, usize)]) -> [Option<f64>; 2] {
    [0, 1].map(|pol| {
        let v: Vec<f64> = ratios
            .iter()
            .filter(|(_, r, i)| i % 2 == pol && *r >= 5)
            .map(|c| c.0)
            .collect();
        crate::stats::robust::median(&v)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rms_and_log_ratio() {
        assert_eq!(weighted_rms(&[]), 0.0);
        assert!((weighted_rms(&[(3.0, 1.0), (4.0, 1.0)]) - (12.5f64).sqrt()).abs() < 1e-12);
        assert!((weighted_rms(&[(3.0, 3.0), (1.0, 1.0)]) - 7f64.sqrt()).abs() < 1e-12);
        assert_eq!(log_ratio(9.5, 9.5), 0.0);
        assert!((log_ratio(19.5, 9.5) - 2f64.ln()).abs() < 1e-12);
    }

    #[test]
    fn normalised_histograms_sum_to_one() {
        let n = normalised(&[1, 3, 0]);
        assert_eq!(n, vec![0.25, 0.75, 0.0]);
        assert_eq!(normalised(&[0, 0]), vec![0.0, 0.0]);
    }

    #[test]
    fn a_tile_without_spread_gives_a_finite_dispersion_ratio() {
        // one 16 x 16 tile (TILE_PX) whose pixels fired 3 times each: the index is 0
        let kept = vec![true; 256];
        let regular = vec![3u32; 256];
        assert_eq!(dispersion_in_tiles(&regular, 16, 16, &kept), Some(0.0));
        // a spread of 2 events in every other pixel: variance 1, mean 3 -> index 1/3
        let spread: Vec<u32> = (0..256).map(|i| if i % 2 == 0 { 2 } else { 4 }).collect();
        let d = dispersion_in_tiles(&spread, 16, 16, &kept).unwrap();
        assert!((d - 1.0 / 3.0).abs() < 1e-12, "{d}");
        // hand computed: ln((0 + 0.1) / (1/3 + 0.1)) = ln(0.3 / 1.3)
        let ratio = dispersion_log_ratio(d, 0.0);
        assert!((ratio - (0.3f64 / 1.3).ln()).abs() < 1e-12, "{ratio}");
        assert_eq!(dispersion_log_ratio(0.0, 0.0), 0.0);
        // indices of 5 and 10: less than 0.02 from ln 2
        assert!((dispersion_log_ratio(5.0, 10.0) - 2f64.ln()).abs() < 0.02);
    }
}
