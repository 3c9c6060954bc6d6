//! The report model read back from its JSON (`results.json`, or one sequence's entry in
//! it), so that sequences computed on other machines, or in other runs, are merged into one
//! report by the same code as sequences computed here.
//!
//! The model's types serialise only (their `&'static str` names, NaN written as `null`,
//! the fitted model with `null` for unidentified parameters); [`Decode`] reads each back
//! from a [`Value`]: a JSON `null` is NaN where a number is required, an absent list or map
//! is empty, and a name is interned. The JSON writes a fitted parameter the data do not
//! identify as `null`; the value the fit simulated it with is in the sequence's ctcal
//! configuration (`configs/NAME/params.toml`), which [`restore_fit_model`] reads back.

use crate::estimate::frames::IntervalInfo;
use crate::estimate::interval::{FrameRatePoint, Measured};
use crate::estimate::{CtEstimate, EstimatorReport};
use crate::fit::events_only::{EventsOnly, IntervalEdge};
use crate::fit::metric::Components;
use crate::fit::residuals::{BackgroundBin, Bin, IntervalDistributions, Residuals, Spectrum};
use crate::fit::{
    AddedEffect, Ambiguity, BandwidthDetection, FitResult, FittedParams, Holdout,
    HotPixelDetection, MismatchDetection, NoiseDetection, NoiseLimit, Step, StepResiduals,
    Uncertain,
};
use crate::model::{
    InputFile, MethodResult, PlotEntry, PresetLevel, SequenceOutputs, SequenceReport, Truth,
};
use crate::sim::PixelParams;
use crate::stats::hot_pixels::HotPixel;
use crate::stats::timeline::{FrameSummary, RateWindow};
use crate::stats::{IntervalSummary, SequenceStats};
use serde_json::{Map, Value};
use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;
use std::sync::Mutex;

/// Why a value could not be read back.
#[derive(Debug, thiserror::Error)]
#[error("`{place}`: {problem}")]
pub struct DecodeError {
    /// The JSON path of the value (e.g. `sequences[0].stats.width`).
    pub place: String,
    pub problem: String,
}

impl DecodeError {
    fn new(problem: impl Into<String>) -> Self {
        Self {
            place: String::new(),
            problem: problem.into(),
        }
    }

    /// The error with `key` in front of its place.
    fn at(mut self, key: &str) -> Self {
        self.place = if self.place.is_empty() {
            key.to_string()
        } else if self.place.starts_with('[') {
            format!("{key}{}", self.place)
        } else {
            format!("{key}.{}", self.place)
        };
        self
    }
}

/// A model type read back from its JSON.
pub trait Decode: Sized {
    fn decode(v: &Value) -> Result<Self, DecodeError>;
}

/// The value under `key` of an object (absent reads as `null`).
fn field<T: Decode>(v: &Value, key: &str) -> Result<T, DecodeError> {
    T::decode(v.get(key).unwrap_or(&Value::Null)).map_err(|e| e.at(key))
}

fn describe(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "an object",
    }
}

fn expected(what: &str, v: &Value) -> DecodeError {
    DecodeError::new(format!("is {}, not {what}", describe(v)))
}

impl Decode for f64 {
    fn decode(v: &Value) -> Result<Self, DecodeError> {
        match v {
            // serde_json writes NaN and the infinities as null
            Value::Null => Ok(f64::NAN),
            _ => v.as_f64().ok_or_else(|| expected("a number", v)),
        }
    }
}

impl Decode for f32 {
    fn decode(v: &Value) -> Result<Self, DecodeError> {
        f64::decode(v).map(|x| x as f32)
    }
}

macro_rules! integers {
    ($($t:ty),*) => {$(
        impl Decode for $t {
            fn decode(v: &Value) -> Result<Self, DecodeError> {
                let n = v
                    .as_i64()
                    .map(i128::from)
                    .or_else(|| v.as_u64().map(i128::from))
                    .ok_or_else(|| expected("a whole number", v))?;
                <$t>::try_from(n).map_err(|_| DecodeError::new(format!("{n} is out of range")))
            }
        }
    )*};
}
integers!(u16, u32, u64, usize, i64);

impl Decode for bool {
    fn decode(v: &Value) -> Result<Self, DecodeError> {
        v.as_bool().ok_or_else(|| expected("a boolean", v))
    }
}

impl Decode for String {
    fn decode(v: &Value) -> Result<Self, DecodeError> {
        v.as_str()
            .map(str::to_string)
            .ok_or_else(|| expected("a string", v))
    }
}

impl Decode for PathBuf {
    fn decode(v: &Value) -> Result<Self, DecodeError> {
        String::decode(v).map(PathBuf::from)
    }
}

/// Names read back, each kept once for the life of the process.
static NAMES: Mutex<BTreeSet<&'static str>> = Mutex::new(BTreeSet::new());

impl Decode for &'static str {
    fn decode(v: &Value) -> Result<Self, DecodeError> {
        let text = v.as_str().ok_or_else(|| expected("a string", v))?;
        let mut names = NAMES.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(&name) = names.get(text) {
            return Ok(name);
        }
        let name: &'static str = Box::leak(text.to_string().into_boxed_str());
        names.insert(name);
        Ok(name)
    }
}

impl Decode for Value {
    fn decode(v: &Value) -> Result<Self, DecodeError> {
        Ok(v.clone())
    }
}

impl Decode for Map<String, Value> {
    fn decode(v: &Value) -> Result<Self, DecodeError> {
        match v {
            Value::Null => Ok(Map::new()),
            Value::Object(m) => Ok(m.clone()),
            _ => Err(expected("an object", v)),
        }
    }
}

impl<T: Decode> Decode for Option<T> {
    fn decode(v: &Value) -> Result<Self, DecodeError> {
        match v {
            Value::Null => Ok(None),
            _ => T::decode(v).map(Some),
        }
    }
}

impl<T: Decode> Decode for Vec<T> {
    fn decode(v: &Value) -> Result<Self, DecodeError> {
        match v {
            Value::Null => Ok(Vec::new()),
            Value::Array(items) => items
                .iter()
                .enumerate()
                .map(|(i, item)| T::decode(item).map_err(|e| e.at(&format!("[{i}]"))))
                .collect(),
            _ => Err(expected("a list", v)),
        }
    }
}

impl<T: Decode, const N: usize> Decode for [T; N] {
    fn decode(v: &Value) -> Result<Self, DecodeError> {
        let items = Vec::<T>::decode(v)?;
        let n = items.len();
        items
            .try_into()
            .map_err(|_| DecodeError::new(format!("has {n} items, not {N}")))
    }
}

impl<A: Decode, B: Decode> Decode for (A, B) {
    fn decode(v: &Value) -> Result<Self, DecodeError> {
        let [a, b] = <[Value; 2]>::decode(v)?;
        Ok((A::decode(&a)?, B::decode(&b)?))
    }
}

impl<T: Decode> Decode for BTreeMap<String, T> {
    fn decode(v: &Value) -> Result<Self, DecodeError> {
        match v {
            Value::Null => Ok(BTreeMap::new()),
            Value::Object(m) => m
                .iter()
                .map(|(k, item)| Ok((k.clone(), T::decode(item).map_err(|e| e.at(k))?)))
                .collect(),
            _ => Err(expected("an object", v)),
        }
    }
}

/// Types that deserialise with serde as they are.
macro_rules! with_serde {
    ($($t:ty),*) => {$(
        impl Decode for $t {
            fn decode(v: &Value) -> Result<Self, DecodeError> {
                serde_json::from_value(v.clone()).map_err(|e| DecodeError::new(e.to_string()))
            }
        }
    )*};
}
with_serde!(crate::fit::effects::Effect);

/// Structs read field by field, each under its own name.
macro_rules! structs {
    ($($t:ident { $($f:ident),* $(,)? })*) => {$(
        impl Decode for $t {
            fn decode(v: &Value) -> Result<Self, DecodeError> {
                if !v.is_object() {
                    return Err(expected("an object", v));
                }
                Ok($t { $($f: field(v, stringify!($f))?),* })
            }
        }
    )*};
}

structs! {
    SequenceReport { name, dataset, format, inputs, stats, methods, fit, fit_not_applied,
        truth, warnings, outputs, seconds }
    InputFile { path, bytes, sha256 }
    MethodResult { method, estimate, not_applied }
    Truth { source, params }
    SequenceOutputs { plots, configs, masks, plots_not_drawn }
    PlotEntry { name, title }
    PresetLevel { ct, events_per_pixel_per_second }
    SequenceStats { biases, width, height, sensor_source, events, on_events, off_events,
        on_fraction, t_first_us, t_last_us, duration_s, events_per_pixel_per_second,
        on_per_pixel_per_second, off_per_pixel_per_second, active_pixel_fraction,
        rate_timeline, rate_window_s, rate_window_note, hot_pixels, hot_pixel_method,
        background_rate_hz, background_rate_method, support_window_s, median_pixel_rate_hz,
        inter_event_interval_s, frames, pixels_kept, selection, excluded_hot_pixels, why }
    RateWindow { t_s, window_s, events, events_per_pixel_per_second }
    HotPixel { x, y, events, rate_hz, z }
    IntervalSummary { p5, median, count, zero, resolution }
    FrameSummary { count, median_interval_s }
    EstimatorReport { name, description, ct_on, ct_off, frame_rate_series_on,
        frame_rate_series_off, details }
    Measured { value, standard_error, systematic, ci95 }
    FrameRatePoint { frame_step, frame_interval_s, value }
    IntervalInfo { t_start_s, t_end_s, used, reason, motion_px }
    FitResult { biases, params, identified, why, not_detected, uncertainties, effects_added, error_metric,
        error_before, error_after, components_before, components_after, steps, ambiguities,
        hot_pixels_masked, hot_pixel_detection, noise_detection, bandwidth_detection, mismatch_detection, residuals_before,
        residuals_after, assumptions,
        holdout, simulations, frame_exposure_us, events_only }
    HotPixelDetection { detectable_above_hz, probability, meaning }
    NoiseDetection { limits, probe_hz, meaning }
    BandwidthDetection { called_for_below_hz, evidence, recording_evidence, simulations, tried,
        why, meaning }
    MismatchDetection { at_most, timing_ci95, recording_evidence, counts_call_for_it, evidence,
        tried_spread, why, meaning }
    NoiseLimit { called_for_above_hz, isolated_hz_per_hz, tried, why, at_most_hz }
    EventsOnly { thresholds_source, ct_on_ci95, ct_off_ci95, ct_ratio, ct_ratio_why,
        noise_on_hz, noise_off_hz, noise_on_test_hz, noise_upper_bound, noise_off_test_hz,
        predicted_error_before, predicted_error_after, simulated_back_why, quiet_pixel_seconds,
        quiet_share, support_window_ms, support_radius_px, timestamp_step_us, interval_edge }
    IntervalEdge { edge_us, range_us, found, not_refractory, below, above, intervals }
    Uncertain { value, standard_error, ci95 }
    AddedEffect { effect, evidence, error_after }
    Ambiguity { kept, alternative, parameter, value, error_kept, error_alternative, chance,
        separated_by, kept_ci95_if_present, kept_thresholds, alternative_thresholds }
    StepResiduals { by_intensity, by_rate_of_change }
    Step { effect, evidence, score, parameters, error_before, error_after, components_after,
        chance, kept, reason, simulations, residuals_before, residuals_after }
    Components { counts, background, intervals, polarity, active, dispersion, lag, hot_pixels,
        total }
    Bin { label, x, real, simulated, log_ratio }
    BackgroundBin { intensity_dn, real_on_hz, simulated_on_hz, real_off_hz, simulated_off_hz }
    IntervalDistributions { bin_start_s, real, simulated }
    Spectrum { frequency_hz, real, simulated }
    Residuals { by_intensity, by_intensity_on, by_intensity_off, by_rate_of_change,
        by_polarity, by_region, over_time, background, intervals, spectrum }
    Holdout { fraction, blocks, held_out_blocks, selection_blocks, test_blocks, fit_seconds,
        held_out_seconds, selection_seconds, test_seconds, guard_seconds }
}

impl Decode for crate::biases::Biases {
    fn decode(v: &Value) -> Result<Self, DecodeError> {
        Ok(Self {
            source: field(v, "source")?,
            values: field(v, "values")?,
        })
    }
}

/// The keys of [`CtEstimate`] itself; the others are its method's `extra`.
const ESTIMATE_KEYS: [&str; 13] = [
    "method",
    "ct_on",
    "ct_off",
    "ct",
    "ct_on_ci95",
    "ct_off_ci95",
    "ct_ci95",
    "why",
    "intervals_used",
    "assumptions",
    "ct_sigma",
    "ct_sigma_ci95",
    "estimators",
];

impl Decode for CtEstimate {
    fn decode(v: &Value) -> Result<Self, DecodeError> {
        let Value::Object(all) = v else {
            return Err(expected("an object", v));
        };
        let mut extra: serde_json::Map<String, Value> = all
            .iter()
            .filter(|(k, _)| !ESTIMATE_KEYS.contains(&k.as_str()) && *k != "intervals_dropped")
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        // a spread written as `null` beside its reason rides in `extra` (the field is left
        // out where a method does not measure it): read back the same way
        if all.get("ct_sigma") == Some(&Value::Null) {
            extra.insert("ct_sigma".into(), Value::Null);
        }
        Ok(CtEstimate {
            method: field(v, "method")?,
            ct_on: field(v, "ct_on")?,
            ct_off: field(v, "ct_off")?,
            ct: field(v, "ct")?,
            ct_on_ci95: field(v, "ct_on_ci95")?,
            ct_off_ci95: field(v, "ct_off_ci95")?,
            ct_ci95: field(v, "ct_ci95")?,
            why: field(v, "why")?,
            intervals_used: field(v, "intervals_used")?,
            assumptions: field(v, "assumptions")?,
            ct_sigma: field(v, "ct_sigma")?,
            ct_sigma_ci95: field(v, "ct_sigma_ci95")?,
            estimators: field(v, "estimators")?,
            intervals_dropped: field(v, "intervals_dropped")?,
            extra,
        })
    }
}

impl Decode for FittedParams {
    /// The model with `null` (an unidentified parameter) at 0 until [`restore_fit_model`]
    /// reads its value; which parameters are unidentified is read from the fit's `why`.
    fn decode(v: &Value) -> Result<Self, DecodeError> {
        let Value::Object(given) = v else {
            return Err(expected("an object", v));
        };
        let mut model = serde_json::to_value(PixelParams::ideal(0.0, 0.0))
            .map_err(|e| DecodeError::new(e.to_string()))?;
        let mut not_identified = BTreeMap::new();
        if let Value::Object(m) = &mut model {
            for (k, value) in given {
                if value.is_null() {
                    not_identified.insert(k.clone(), String::new());
                } else {
                    m.insert(k.clone(), value.clone());
                }
            }
        }
        Ok(FittedParams {
            model: serde_json::from_value(model).map_err(|e| DecodeError::new(e.to_string()))?,
            not_identified,
        })
    }
}

/// A fit's `not_identified` reasons are its `why` (the JSON keeps them there).
fn with_reasons(mut fit: FitResult) -> FitResult {
    for (key, why) in fit.params.not_identified.iter_mut() {
        if let Some(reason) = fit.why.get(key) {
            why.clone_from(reason);
        }
    }
    fit
}

/// The path of a fitted sequence's ctcal configuration inside the report folder.
pub fn params_toml_path(s: &SequenceReport) -> Option<&str> {
    s.fit.as_ref()?;
    s.outputs
        .configs
        .iter()
        .map(String::as_str)
        .find(|p| p.ends_with("/params.toml"))
}

/// The fitted model of `s` as it was simulated, from the text of its ctcal configuration
/// (the JSON leaves out the values of unidentified parameters).
pub fn restore_fit_model(s: &mut SequenceReport, params_toml: &str) -> Result<(), DecodeError> {
    let Some(fit) = s.fit.as_mut() else {
        return Ok(());
    };
    let mut model = PixelParams::from_toml(params_toml, "params.toml")
        .map_err(|e| DecodeError::new(e.to_string()).at("fit.params"))?;
    // the configuration carries the report's seed; the fit's model has none
    model.seed = None;
    fit.params.model = model;
    Ok(())
}

/// One sequence from its entry in `results.json`.
pub fn sequence(v: &Value) -> Result<SequenceReport, DecodeError> {
    let mut s = SequenceReport::decode(v)?;
    s.fit = s.fit.map(with_reasons);
    Ok(s)
}

/// The parts of a whole `results.json` a merge takes again.
pub struct Results {
    pub seed: u64,
    pub sequences: Vec<SequenceReport>,
    pub presets: Vec<PresetLevel>,
    /// Name, path and error of the recordings that failed.
    pub failed: Vec<(String, String, String)>,
}

/// A whole `results.json`.
pub fn results(v: &Value) -> Result<Results, DecodeError> {
    let sequences = match v.get("sequences") {
        Some(Value::Array(items)) => items
            .iter()
            .enumerate()
            .map(|(i, s)| sequence(s).map_err(|e| e.at(&format!("sequences[{i}]"))))
            .collect::<Result<_, _>>()?,
        other => {
            return Err(expected("a list", other.unwrap_or(&Value::Null)).at("sequences"));
        }
    };
    let failed = match v.get("failed") {
        Some(Value::Array(items)) => items
            .iter()
            .enumerate()
            .map(|(i, f)| {
                Ok((field(f, "name")?, field(f, "path")?, field(f, "error")?))
                    .map_err(|e: DecodeError| e.at(&format!("failed[{i}]")))
            })
            .collect::<Result<_, _>>()?,
        _ => Vec::new(),
    };
    Ok(Results {
        seed: field(v, "seed")?,
        sequences,
        presets: field(v, "presets")?,
        failed,
    })
}
