//! The events-only noise model and its distance to a recording's blocks.
//!
//! Without frames the scene cannot be simulated, but what the pixel adds to it can be
//! predicted block by block: the rate of isolated events per polarity (shot noise, leak),
//! the named hot pixels' rates, the share of short same-pixel intervals (refractory period)
//! and the ON/OFF balance of the scene's events (the threshold ratio). The ideal pixel
//! predicts no isolated events, no hot pixels, a smooth interval density down to zero and
//! balanced polarities.

use super::measure::{BlockMeasure, Isolation};
use crate::fit::metric::{BACKGROUND_FLOOR_HZ, Components};

/// The distance's name, as reported.
pub const ERROR_METRIC: &str = "root sum of squares of: RMS over ON and OFF of |ln| ratio of isolated-event rates at quiet pixels (floor: twice the rate's standard error, within 0.0001-0.01 Hz/pixel); RMS |ln| ratio of the named hot pixels' rates (floor: the mean pixel rate); |share predicted - share measured| of same-pixel intervals under the fit run's edge, relative to those in [edge, 2 edge); |ln(OFF/ON) difference| of supported events";

/// The lowest rate floor of the isolated-event component, Hz per pixel (the frame-based
/// fit's [`BACKGROUND_FLOOR_HZ`] is the highest: rates measured on more quiet pixel-time
/// are told apart further down, to twice their standard error).
pub const RATE_FLOOR_HZ: f64 = 1e-4;

/// What the model predicts.
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseModel {
    /// Isolated events per pixel per second, ON and OFF.
    pub noise_on_hz: f64,
    pub noise_off_hz: f64,
    /// Rates of the named hot pixels (the fit run's list), `None` for a model without them.
    pub hot_rates_hz: Option<Vec<f64>>,
    /// Whether the model has a refractory period at the fit run's edge.
    pub refractory: bool,
    /// Expected OFF/ON count ratio of the scene's events (Cp / Cn).
    pub balance: f64,
}

impl NoiseModel {
    pub fn ideal() -> Self {
        Self {
            noise_on_hz: 0.0,
            noise_off_hz: 0.0,
            hot_rates_hz: None,
            refractory: false,
            balance: 1.0,
        }
    }
}

/// What the distance compares against beyond the blocks: the fit run's interval edge.
#[derive(Clone, Copy, Debug)]
pub struct Reference {
    pub edge_us: Option<f64>,
    /// The support the noise is measured under ([`super::measure::choose_isolation`]).
    pub isolation: Isolation,
}

/// What a model says the blocks measure: the isolated-event rates, the named hot pixels'
/// rates, the share of short same-pixel intervals and the scene's OFF/ON balance. From
/// the model's parameters ([`Prediction::of`]) or from the model simulated onto the
/// blocks and measured ([`super::simulate_back`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Prediction {
    pub on_hz: f64,
    pub off_hz: f64,
    /// `None`: the hot pixels fire like any pixel (the blocks' mean pixel rate).
    pub hot_rates_hz: Option<Vec<f64>>,
    /// Same-pixel intervals under the edge, relative to those in [edge, 2 edge).
    pub short_share: f64,
    pub balance: f64,
}

impl Prediction {
    /// The model's parameters read as measurements: the rates as given, no short
    /// intervals under a refractory period and a smooth density (share 1) without.
    pub fn of(model: &NoiseModel) -> Self {
        Self {
            on_hz: model.noise_on_hz,
            off_hz: model.noise_off_hz,
            hot_rates_hz: model.hot_rates_hz.clone(),
            short_share: if model.refractory { 0.0 } else { 1.0 },
            balance: model.balance,
        }
    }
}

/// The distance of `model` to the recording's `blocks`.
pub fn distance(model: &NoiseModel, blocks: &[&BlockMeasure], reference: Reference) -> Components {
    compare(&Prediction::of(model), blocks, reference)
}

/// The distance of a prediction to the recording's `blocks`.
pub fn compare(
    predicted: &Prediction,
    blocks: &[&BlockMeasure],
    reference: Reference,
) -> Components {
    let background = isolated_component(predicted, blocks, reference.isolation);
    let hot_pixels = hot_pixel_component(predicted, blocks);
    let intervals = reference.edge_us.map_or(0.0, |e| {
        (predicted.short_share - short_share(blocks, e))
            .abs()
            .min(2.0)
    });
    let polarity = balance_component(predicted, blocks);
    let hot_value = hot_pixels.unwrap_or(0.0);
    let total = [background, hot_value, intervals, polarity]
        .iter()
        .map(|v| v * v)
        .sum::<f64>()
        .sqrt();
    Components {
        background,
        intervals,
        polarity,
        hot_pixels,
        total,
        ..Components::default()
    }
}

/// The log ratio of a predicted rate to a measured one, each with `floor` added.
fn floored_log_ratio(predicted: f64, measured: f64, floor: f64) -> f64 {
    ((predicted + floor) / (measured + floor)).ln()
}

/// The isolated-event component: RMS over ON and OFF of the log ratio of the predicted
/// rates to those measured under `isolation` (0 where either is not measured).
fn isolated_component(
    predicted: &Prediction,
    blocks: &[&BlockMeasure],
    isolation: Isolation,
) -> f64 {
    match (
        BlockMeasure::isolated_rate(blocks, isolation, true),
        BlockMeasure::isolated_rate(blocks, isolation, false),
    ) {
        (Some((on, on_se)), Some((off, off_se))) => {
            // rates are told apart down to twice their standard error on these blocks
            let floor = |se: f64| (2.0 * se).clamp(RATE_FLOOR_HZ, BACKGROUND_FLOOR_HZ);
            let a = floored_log_ratio(predicted.on_hz, on, floor(on_se));
            let b = floored_log_ratio(predicted.off_hz, off, floor(off_se));
            ((a * a + b * b) / 2.0).sqrt()
        }
        _ => 0.0,
    }
}

/// The hot-pixel component: RMS over the named hot pixels of the log ratio of the
/// predicted rates (the blocks' mean pixel rate where the model has none) to those
/// measured, floored at that mean; `None` without named pixels or time.
fn hot_pixel_component(predicted: &Prediction, blocks: &[&BlockMeasure]) -> Option<f64> {
    let seconds: f64 = blocks.iter().map(|b| b.seconds).sum();
    let hot = blocks.first().map_or(0, |b| b.hot_events.len());
    (hot > 0 && seconds > 0.0).then(|| {
        let base = blocks
            .iter()
            .map(|b| b.pixel_rate_hz * b.seconds)
            .sum::<f64>()
            / seconds;
        let squares: f64 = (0..hot)
            .map(|k| {
                let measured = blocks.iter().map(|b| b.hot_events[k]).sum::<u64>() as f64 / seconds;
                let predicted = predicted.hot_rates_hz.as_ref().map_or(base, |r| r[k]);
                floored_log_ratio(predicted, measured, base.max(BACKGROUND_FLOOR_HZ)).powi(2)
            })
            .sum();
        (squares / hot as f64).sqrt()
    })
}

/// The balance component: the `|ln|` difference of the scene's OFF/ON ratio from the
/// predicted one (0 without events of both polarities).
fn balance_component(predicted: &Prediction, blocks: &[&BlockMeasure]) -> f64 {
    let (on, off): (u64, u64) = blocks
        .iter()
        .fold((0, 0), |(a, b), m| (a + m.signal_on, b + m.signal_off));
    if on > 0 && off > 0 {
        ((off as f64 / on as f64).ln() - predicted.balance.ln()).abs()
    } else {
        0.0
    }
}

/// Same-pixel intervals of `blocks` under `edge_us`, relative to those in [edge, 2 edge).
pub fn short_share(blocks: &[&BlockMeasure], edge_us: f64) -> f64 {
    let (mut under, mut above) = (0usize, 0usize);
    for b in blocks {
        for &v in &b.intervals {
            let v = v as f64;
            if v < edge_us {
                under += 1;
            } else if v < 2.0 * edge_us {
                above += 1;
            }
        }
    }
    under as f64 / above.max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block() -> BlockMeasure {
        BlockMeasure {
            seconds: 2.0,
            pixel_seconds: 200.0,
            isolated: vec![super::super::measure::Isolated {
                on: 300,
                off: 100,
                pixel_seconds: 100.0,
            }],
            signal_on: 1000,
            signal_off: 1500,
            intervals: vec![500, 1200, 1500, 1900],
            hot_events: vec![200],
            pixel_rate_hz: 1.0,
            signal_rate_hz: 0.8,
        }
    }

    #[test]
    fn the_distance_of_a_model_that_predicts_every_measurement_is_zero() {
        let b = block();
        let reference = Reference {
            edge_us: Some(1000.0),
            isolation: Isolation::default(),
        };
        let exact = NoiseModel {
            noise_on_hz: 3.0,
            noise_off_hz: 1.0,
            hot_rates_hz: Some(vec![100.0]),
            refractory: false,
            balance: 1.5,
        };
        let d = distance(&exact, &[&b], reference);
        // one interval of 500 us under the edge, three in [1000, 2000): share 1/3
        assert!((d.intervals - 2.0 / 3.0).abs() < 1e-12, "{d:?}");
        assert!(d.background < 1e-12 && d.polarity < 1e-12);
        assert!(d.hot_pixels.unwrap() < 1e-12);
        let ideal = distance(&NoiseModel::ideal(), &[&b], reference);
        // background: floors 0.01 (2 SE = 2 sqrt(300) / 100 = 0.35 is above the ceiling)
        let expected =
            ((0.01f64 / 3.01).ln().powi(2) / 2.0 + (0.01f64 / 1.01).ln().powi(2) / 2.0).sqrt();
        assert!((ideal.background - expected).abs() < 1e-9, "{ideal:?}");
        assert!((ideal.polarity - 1.5f64.ln()).abs() < 1e-12);
        // hot: ln((1 + 1) / (100 + 1))
        assert!((ideal.hot_pixels.unwrap() - (2.0f64 / 101.0).ln().abs()).abs() < 1e-9);
        assert!(ideal.total > d.total);
    }
}
