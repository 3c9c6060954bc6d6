//! Contrast-threshold estimators (Stoffregen et al., "Reducing the Sim-to-Real Gap for
//! Event Cameras", ECCV 2020, Sec. 3.1 and supplement): from a recording's grey frames
//! ([`aps`]: re-simulation and event timing, with per-pixel maps), from its event rate
//! against simulated scenes of matching dynamics (`eppps`), and from a recording of an
//! on-screen stimulus (`screen`). Every method returns one [`CtEstimate`] whose intervals
//! include the method's systematic error ([`interval`]).
//!
//! The estimators read events and frames already in memory and simulate with [`crate::sim`];
//! they never read files (the binary does).

pub mod align;
pub mod aps;
pub mod dynamics;
pub mod eppps;
pub mod flow;
pub mod frames;
pub mod image;
pub mod interval;
pub mod lsq;
pub mod offset;
pub mod resim;
pub mod screen;
pub mod timing;

use crate::events::{EventChunk, Sensor, TimeUs};
use interval::{FrameRatePoint, Measured};
use serde::Serialize;

/// An estimate cannot be made from this input: what is missing and what to do.
#[derive(Debug, Clone, thiserror::Error)]
#[error("{problem}\n  fix: {fix}")]
pub struct EstimateError {
    pub problem: String,
    pub fix: String,
}

impl EstimateError {
    pub fn new(problem: impl Into<String>, fix: impl Into<String>) -> Self {
        Self {
            problem: problem.into(),
            fix: fix.into(),
        }
    }
}

/// One estimator's result inside a [`CtEstimate`].
#[derive(Clone, Debug, Serialize)]
pub struct EstimatorReport {
    pub name: &'static str,
    pub description: &'static str,
    pub ct_on: Measured,
    pub ct_off: Measured,
    /// The estimate with every frame, every 2nd and every 3rd (ON, OFF).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub frame_rate_series_on: Vec<FrameRatePoint>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub frame_rate_series_off: Vec<FrameRatePoint>,
    /// Method-specific numbers (samples, cells, corrections).
    pub details: serde_json::Value,
}

/// The result of `ctcal estimate` (the JSON keys of `../shared/CLI.md`).
#[derive(Clone, Debug, Serialize)]
pub struct CtEstimate {
    pub method: &'static str,
    pub ct_on: f64,
    pub ct_off: f64,
    /// Mean of the two.
    pub ct: f64,
    pub ct_on_ci95: [f64; 2],
    pub ct_off_ci95: [f64; 2],
    pub ct_ci95: [f64; 2],
    /// Frame intervals used, `[t_start_s, t_end_s]` in the recording's clock (aps).
    pub intervals_used: Vec<[f64; 2]>,
    pub assumptions: Vec<String>,
    /// Frozen per-pixel mismatch (both polarities), estimation noise removed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ct_sigma: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ct_sigma_ci95: Option<[f64; 2]>,
    pub estimators: Vec<EstimatorReport>,
    /// Frame intervals not used, with the reason.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub intervals_dropped: Vec<frames::IntervalInfo>,
    /// Method-specific results (calibration curve, display fit, maps), flattened.
    #[serde(flatten)]
    pub extra: serde_json::Map<String, serde_json::Value>,
}

impl CtEstimate {
    /// An estimate from combined ON and OFF values.
    pub fn from_parts(method: &'static str, on: &Measured, off: &Measured) -> Self {
        Self {
            method,
            ct_on: on.value,
            ct_off: off.value,
            ct: 0.5 * (on.value + off.value),
            ct_on_ci95: on.ci95,
            ct_off_ci95: off.ci95,
            // the mean of two correlated estimates: the mean of their bounds
            ct_ci95: [
                0.5 * (on.ci95[0] + off.ci95[0]),
                0.5 * (on.ci95[1] + off.ci95[1]),
            ],
            intervals_used: Vec::new(),
            assumptions: Vec::new(),
            ct_sigma: None,
            ct_sigma_ci95: None,
            estimators: Vec::new(),
            intervals_dropped: Vec::new(),
            extra: serde_json::Map::new(),
        }
    }
}

/// A progress callback: the stage being worked on and how far it is (0..=1).
pub type Progress<'a> = &'a (dyn Fn(&str, f64) + Sync);

/// The grid a recording's timestamps are quantised to, if they are: `(period, phase)`.
/// Simulator-made recordings stamp events at the end of each simulation frame (v2e:
/// hundreds of events per distinct timestamp); real cameras stamp to the microsecond.
pub fn timestamp_grid(events: &EventChunk) -> Option<(TimeUs, TimeUs)> {
    let mut distinct: Vec<TimeUs> = events.t.clone();
    distinct.dedup();
    if distinct.len() < 10 || (events.len() as f64) < 4.0 * distinct.len() as f64 {
        return None;
    }
    let mut gaps: Vec<TimeUs> = distinct.windows(2).map(|w| w[1] - w[0]).collect();
    gaps.sort_unstable();
    let period = gaps[gaps.len() / 2];
    (period >= 10).then(|| (period, distinct[0].rem_euclid(period)))
}

/// Moves every event to the end of its cell of `grid` (as the recording's own stamps
/// are), keeping time order.
pub fn quantise(events: &mut EventChunk, (period, phase): (TimeUs, TimeUs)) {
    for t in &mut events.t {
        let k = (*t - phase + period - 1).div_euclid(period);
        *t = k * period + phase;
    }
}

/// Pixels to leave out: `excluded` plus hot pixels found in the events' counts.
pub fn exclude_hot_pixels(
    events: &EventChunk,
    sensor: Sensor,
    excluded: &[bool],
) -> (Vec<bool>, usize) {
    let (w, h) = (sensor.width as usize, sensor.height as usize);
    let mut counts = vec![0u32; w * h];
    for i in 0..events.len() {
        counts[events.y[i] as usize * w + events.x[i] as usize] += 1;
    }
    let duration = crate::events::us_to_s(
        events.t.last().copied().unwrap_or(0) - events.t.first().copied().unwrap_or(0),
    );
    let hot = crate::stats::hot_pixels::find_hot_pixels(&counts, w, h, duration);
    let mut out = excluded.to_vec();
    for p in &hot {
        out[p.y as usize * w + p.x as usize] = true;
    }
    (out, hot.len())
}
