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
pub mod event_flow;
pub mod flow;
pub mod frames;
pub mod image;
pub mod interval;
pub mod lsq;
pub mod photoreceptor;
pub mod resim;
pub mod root;
pub mod screen;
pub mod timing;

use crate::events::{EventChunk, Sensor, TimeUs};
use crate::hint::Text;
use interval::{FrameRatePoint, Measured};
use serde::Serialize;
use std::collections::BTreeMap;

/// An estimate cannot be made from this input: what is missing and what to do.
#[derive(Debug, Clone)]
pub struct EstimateError {
    pub problem: String,
    pub fix: Text,
}

impl EstimateError {
    pub fn new(problem: impl Into<String>, fix: impl Into<Text>) -> Self {
        Self {
            problem: problem.into(),
            fix: fix.into(),
        }
    }

    /// The problem and its fix.
    pub fn message(&self) -> Text {
        Text::from(self.problem.as_str()).fixed_by(&self.fix)
    }
}

impl std::fmt::Display for EstimateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.message().fmt(f)
    }
}

impl std::error::Error for EstimateError {}

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

/// A 95 % interval; a side is `None` (JSON `null`) where it is open: the value was
/// extrapolated beyond what the method simulated, so nothing bounds it on that side.
pub type Interval = [Option<f64>; 2];

/// The result of `ctcal estimate` (the JSON keys of `../shared/CLI.md`). A threshold the
/// data do not determine is `None` (JSON `null`), with the reason under `why`.
#[derive(Clone, Debug, Serialize)]
pub struct CtEstimate {
    pub method: &'static str,
    pub ct_on: Option<f64>,
    pub ct_off: Option<f64>,
    /// Mean of the two.
    pub ct: Option<f64>,
    pub ct_on_ci95: Option<Interval>,
    pub ct_off_ci95: Option<Interval>,
    pub ct_ci95: Option<Interval>,
    /// Why a value is `None`, by its key.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub why: BTreeMap<String, String>,
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

/// The range of thresholds a method's result can be trusted in: inside it a value is a
/// result; outside it (but positive) it is an extrapolation, kept with its interval open on
/// the far side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Determinable {
    pub lo: f64,
    pub hi: f64,
    /// What the range is, for the assumption that names an extrapolation.
    pub what: &'static str,
}

impl Determinable {
    /// Any positive threshold.
    pub const POSITIVE: Determinable = Determinable {
        lo: 0.0,
        hi: f64::INFINITY,
        what: "positive thresholds",
    };
}

/// One polarity's value as reported: a result, an extrapolation (one side of its interval
/// open) or not determinable (with the reason).
fn checked(
    name: &str,
    m: &Measured,
    range: Determinable,
) -> Result<(f64, Interval, Option<String>), String> {
    if let Some(why) = why_not_determinable(name, m) {
        return Err(why);
    }
    let lo = (m.ci95[0] > 0.0).then_some(m.ci95[0]);
    if let Some((ci, note)) = range.extrapolation(name, m, lo) {
        return Ok((m.value, ci, Some(note)));
    }
    let (ci, note) = range.clipped(name, m, lo);
    Ok((m.value, ci, note))
}

/// Why the data do not determine `m` (named `name`): a value that is not finite or not
/// positive, or an uncertainty that is not finite; `None` where they do.
fn why_not_determinable(name: &str, m: &Measured) -> Option<String> {
    if !m.value.is_finite() {
        return Some(format!(
            "the method gave no finite {name} ({}): the data do not determine it",
            m.value
        ));
    }
    if m.value <= 0.0 {
        return Some(format!(
            "the method gave {name} = {:.4}, not a threshold (<= 0): the data do not determine it (too few or inconsistent events for this method)",
            m.value
        ));
    }
    let total = m.total_error();
    if !total.is_finite() {
        return Some(format!(
            "{name} = {:.4} has no finite uncertainty: not determinable",
            m.value
        ));
    }
    None
}

impl Determinable {
    /// The interval and note of a value `m` outside the range: an extrapolation, its
    /// interval open on the far side (`lo`: its lower end where positive); `None` inside.
    fn extrapolation(
        &self,
        name: &str,
        m: &Measured,
        lo: Option<f64>,
    ) -> Option<(Interval, String)> {
        if m.value < self.lo {
            return Some((
                [None, Some(m.ci95[1])],
                format!(
                    "{name} = {:.4} is an extrapolation below {} (down to {:.4}): its interval is open below",
                    m.value, self.what, self.lo
                ),
            ));
        }
        if m.value > self.hi {
            return Some((
                [lo, None],
                format!(
                    "{name} = {:.4} is an extrapolation above {} (up to {:.4}): its interval is open above",
                    m.value, self.what, self.hi
                ),
            ));
        }
        None
    }

    /// The interval of a value `m` inside the range (`lo`: its lower end where positive,
    /// else 0): open on a side where it runs past the range, with the notes saying so.
    fn clipped(&self, name: &str, m: &Measured, lo: Option<f64>) -> (Interval, Option<String>) {
        let (mut ci, mut notes) = ([lo.or(Some(0.0)), Some(m.ci95[1])], Vec::new());
        if m.ci95[1] > self.hi {
            ci[1] = None;
            notes.push(format!(
                "the 95 % interval of {name} runs past {} (up to {:.4}): open above",
                self.what, self.hi
            ));
        }
        if self.lo > 0.0 && m.ci95[0] < self.lo {
            ci[0] = None;
            notes.push(format!(
                "the 95 % interval of {name} runs below {} (down to {:.4}): open below",
                self.what, self.lo
            ));
        }
        (ci, (!notes.is_empty()).then(|| notes.join("; ")))
    }
}

impl CtEstimate {
    /// Adds `time_span_s`, the first and the last event's times in seconds, where the
    /// method has not given its own (`aps` gives its frames' span); none without events.
    pub fn span_events(&mut self, events: &crate::events::EventChunk) {
        if let (Some(&first), Some(&last)) = (events.t.first(), events.t.last()) {
            self.extra.entry("time_span_s").or_insert_with(|| {
                serde_json::json!([crate::events::us_to_s(first), crate::events::us_to_s(last)])
            });
        }
    }

    /// An estimate from ON and OFF values, each checked: a value that is not finite or not
    /// positive is not determinable (`None`, with the reason under `why`); one outside
    /// `range` is an extrapolation (kept, its interval open on that side, and said in the
    /// assumptions). A lower interval bound at or below zero is reported as 0.
    pub fn from_parts(
        method: &'static str,
        on: &Measured,
        off: &Measured,
        range: Determinable,
    ) -> Self {
        let mut estimate = Self::empty(method);
        let mut parts = [None, None];
        for (slot, (key, m)) in [("ct_on", on), ("ct_off", off)].into_iter().enumerate() {
            match checked(key, m, range) {
                Ok((value, ci, note)) => {
                    parts[slot] = Some((value, ci));
                    estimate.assumptions.extend(note);
                }
                Err(why) => {
                    estimate.why.insert(key.into(), why);
                }
            }
        }
        estimate.set_parts(parts[0], parts[1]);
        estimate
    }

    /// Withdraws the thresholds (and the spread) a method measured but cannot stand by, for
    /// `reason`: each becomes not determinable; the estimators' own values stay under
    /// `estimators` for inspection.
    pub fn withhold(&mut self, reason: &str) {
        for key in ["ct_on", "ct_off", "ct"] {
            self.why.insert(key.into(), reason.to_string());
        }
        self.ct_on = None;
        self.ct_on_ci95 = None;
        self.ct_off = None;
        self.ct_off_ci95 = None;
        self.ct = None;
        self.ct_ci95 = None;
        self.spread_not_determined(None, reason.to_string());
    }

    /// `ct_sigma` not determined: written as `null` (not left out, as it is where a method
    /// does not measure the spread; it rides in `extra`, and the decoder reads it back so),
    /// with `interval` (an upper bound, or none) and `why`.
    pub fn spread_not_determined(&mut self, interval: Option<[f64; 2]>, why: String) {
        self.ct_sigma = None;
        self.ct_sigma_ci95 = interval;
        self.extra
            .insert("ct_sigma".into(), serde_json::Value::Null);
        self.why.insert("ct_sigma".into(), why);
    }

    /// Withdraws one threshold (ON when `on`, else OFF) for `reason`; the mean goes with it.
    pub fn withhold_polarity(&mut self, on: bool, reason: &str) {
        let part = |value: Option<f64>, ci: Option<Interval>| Some((value?, ci?));
        let mut parts = [
            part(self.ct_on, self.ct_on_ci95),
            part(self.ct_off, self.ct_off_ci95),
        ];
        parts[usize::from(!on)] = None;
        let key = if on { "ct_on" } else { "ct_off" };
        self.why.insert(key.into(), reason.to_string());
        self.set_parts(parts[0], parts[1]);
    }

    /// An estimate that determined nothing, for `reason`.
    pub fn not_determinable(method: &'static str, reason: &str) -> Self {
        let mut estimate = Self::empty(method);
        for key in ["ct_on", "ct_off", "ct"] {
            estimate.why.insert(key.into(), reason.to_string());
        }
        estimate
    }

    fn empty(method: &'static str) -> Self {
        Self {
            method,
            ct_on: None,
            ct_off: None,
            ct: None,
            ct_on_ci95: None,
            ct_off_ci95: None,
            ct_ci95: None,
            why: BTreeMap::new(),
            intervals_used: Vec::new(),
            assumptions: Vec::new(),
            ct_sigma: None,
            ct_sigma_ci95: None,
            estimators: Vec::new(),
            intervals_dropped: Vec::new(),
            extra: serde_json::Map::new(),
        }
    }

    fn set_parts(&mut self, on: Option<(f64, Interval)>, off: Option<(f64, Interval)>) {
        self.ct_on = on.map(|p| p.0);
        self.ct_on_ci95 = on.map(|p| p.1);
        self.ct_off = off.map(|p| p.0);
        self.ct_off_ci95 = off.map(|p| p.1);
        match (on, off) {
            (Some((a, ca)), Some((b, cb))) => {
                self.ct = Some(0.5 * (a + b));
                // the mean of two correlated estimates: the mean of their bounds (open if
                // either is)
                let side = |x: Option<f64>, y: Option<f64>| Some(0.5 * (x? + y?));
                self.ct_ci95 = Some([side(ca[0], cb[0]), side(ca[1], cb[1])]);
            }
            _ => {
                self.ct = None;
                self.ct_ci95 = None;
                self.why.insert(
                    "ct".into(),
                    "the mean needs both the ON and the OFF threshold".into(),
                );
            }
        }
    }

    /// Both thresholds, when both were determined.
    pub fn thresholds(&self) -> Option<(f64, f64)> {
        Some((self.ct_on?, self.ct_off?))
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
