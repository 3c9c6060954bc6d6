//! Fitting the simulator to a recording, and closing the loop: start from the ideal pixel
//! with the estimated thresholds, look at where the model is still wrong, trace that
//! residual to the effect whose signature it carries ([`effects`]), add the effect, fit its
//! parameter with the thresholds, and keep it only if the error on held-out data falls;
//! repeat until nothing helps.
//!
//! - The recording's grey frames, upsampled along the optical flow, are simulated with the
//!   candidate model ([`search`]), and the simulation is compared with the recording
//!   statistic by statistic ([`observe`]) under one sim-to-real distance ([`metric`]).
//! - Time is cut into blocks: the first ones fit, the rest is held out as a selection run
//!   (an effect is kept only if its error there falls by more than measured chance) and a
//!   test run (the final error, touched once) ([`selection`]).
//! - Thresholds start from `estimate aps` on the fit run (event timing and re-simulation);
//!   in a static scene (no change in the frames) they cannot be measured: a start value,
//!   reported as not identified.
//!
//! The approach is that of Stoffregen et al. (ECCV 2020), who matched simulator settings
//! to datasets by hand through events per pixel per second, made automatic and extended to
//! every effect of the pixel model (Lichtsteiner et al. 2008; v2e, Hu et al. 2021).

pub mod effects;
pub mod events_only;
pub mod metric;
pub mod not_detected;
pub mod observe;
pub mod residuals;
pub mod search;
pub mod selection;
mod wording;

use crate::estimate::EstimateError;
use crate::events::{EventChunk, Frame, Sensor, TimeUs};
use crate::sim::PixelParams;
use crate::stats::hot_pixels::HotPixel;
use effects::Effect;
use metric::Components;
use residuals::{Bin, Residuals};
use serde::Serialize;
use std::collections::BTreeMap;

/// A fit cannot be made from this input: what is missing and what to do.
pub type FitError = EstimateError;

/// Which effects the fit considers.
#[derive(Clone, Debug, PartialEq)]
pub enum EffectChoice {
    /// Every effect, each tried when its residual signature calls for it.
    Auto,
    /// None: the ideal pixel with fitted thresholds.
    None,
    /// These, in this order, each tried whatever the evidence (and kept only if the
    /// held-out error falls).
    List(Vec<Effect>),
}

/// Settings of a fit.
#[derive(Clone, Debug)]
pub struct FitOptions {
    pub effects: EffectChoice,
    /// Fraction of the frames' span held out of the fit (the later part: selection, then
    /// test).
    pub holdout: f64,
    /// Number of time blocks.
    pub blocks: usize,
    /// The estimator's settings (log response, frame options) for the starting thresholds.
    pub aps: crate::estimate::aps::ApsOptions,
    /// Thresholds used where a static scene cannot measure them.
    pub default_threshold: f64,
    /// Absolute thresholds measured elsewhere (e.g. `estimate screen` on this recording)
    /// for a fit without frames; without them it runs `estimate eppps` on its fit run.
    pub thresholds: Option<crate::estimate::CtEstimate>,
    pub seed: u64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            effects: EffectChoice::Auto,
            holdout: 0.4,
            blocks: 10,
            aps: crate::estimate::aps::ApsOptions::default(),
            default_threshold: 0.3,
            thresholds: None,
            seed: crate::DEFAULT_SEED,
        }
    }
}

impl FitOptions {
    /// The blocks a held-out fraction `holdout` leaves to fit, select and test (the split
    /// the fit makes of its time blocks, [`observe::roles`]).
    fn split_of(&self, holdout: f64) -> [usize; 3] {
        let fitting = ((1.0 - holdout.clamp(0.0, 1.0)) * self.blocks as f64).round();
        let role = observe::roles(fitting as usize, self.blocks);
        let count = |r| role.iter().filter(|&&x| x == r).count();
        [
            count(observe::Role::Fit),
            count(observe::Role::Selection),
            count(observe::Role::Test),
        ]
    }

    /// Whether `holdout` keeps at least 3 fit blocks (the starting thresholds and their
    /// spread over blocks) and leaves at least one selection block (to judge the effects)
    /// and one test block (`error_before`/`error_after`, which no decision has seen).
    fn splits(&self, holdout: f64) -> bool {
        let [fit, selection, test] = self.split_of(holdout);
        (0.0..1.0).contains(&holdout) && fit >= 3 && selection >= 1 && test >= 1
    }

    /// The held-out fractions, in hundredths, that [`Self::check`] accepts for these
    /// blocks (0.16 to 0.75 of 10); `None` where no fraction splits them (under 5 blocks).
    pub fn holdout_range(&self) -> Option<(f64, f64)> {
        let accepted: Vec<f64> = (0..100)
            .map(|h| h as f64 / 100.0)
            .filter(|&h| self.splits(h))
            .collect();
        Some((*accepted.first()?, *accepted.last()?))
    }

    /// Refuses a held-out fraction that does not split the blocks into at least 3 fit, one
    /// selection and one test block.
    pub fn check(&self) -> Result<(), FitError> {
        if self.holdout.is_finite() && self.splits(self.holdout) {
            return Ok(());
        }
        let held = if self.holdout.is_finite() {
            let [fit, selection, test] = self.split_of(self.holdout);
            format!(
                "leaves {fit} fit, {selection} selection and {test} test blocks of {}",
                self.blocks
            )
        } else {
            "is not a number".to_string()
        };
        Err(FitError::new(
            format!(
                "a held-out fraction of {} {held}: the fit needs at least 3 blocks to fit (its starting thresholds and their spread over blocks), one selection block (to judge the effects) and one test block (for the errors no decision has seen)",
                self.holdout
            ),
            match self.holdout_range() {
                Some((lo, hi)) => format!("hold out a fraction between {lo} and {hi}"),
                None => format!("cut the time into 5 blocks or more ({} now)", self.blocks),
            },
        ))
    }
}

/// What a fit reads.
pub struct FitInput<'a> {
    pub sensor: Sensor,
    /// Time-sorted events.
    pub events: &'a EventChunk,
    /// Grey frames (time-sorted, the sensor's size).
    pub frames: &'a [Frame],
    /// Pixels left out (region of interest, mask).
    pub excluded: &'a [bool],
    /// Spans between blocks of frames read from a longer recording whose events were not
    /// read (empty: read whole).
    pub unread: &'a [(TimeUs, TimeUs)],
}

/// A parameter with its standard error and 95 % interval.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Uncertain {
    pub value: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub standard_error: Option<f64>,
    /// 95 % interval `[lo, hi]`; an open side (`null`) is one the data do not bound (the
    /// fit error stays within chance out to the end of the searched range).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ci95: Option<crate::estimate::Interval>,
}

impl Uncertain {
    /// A parameter that cannot be negative (a threshold, a rate, a time): its interval is
    /// log-normal, `value * exp(+-1.96 se / value)`, as the searches work in the
    /// logarithm of the parameter (and a symmetric interval would cross zero when the
    /// standard error is large).
    pub fn positive(value: f64, standard_error: Option<f64>) -> Self {
        let ci95 = standard_error
            .filter(|se| se.is_finite() && *se >= 0.0 && value > 0.0)
            .map(|se| {
                let spread = (crate::estimate::interval::z95() * se / value).exp();
                [Some(value / spread), Some(value * spread)]
            });
        Self {
            value,
            standard_error,
            ci95,
        }
    }

    /// The 95 % interval: `ci95`, else `value +- 1.96 standard_error`, else none.
    pub fn interval(&self) -> Option<crate::estimate::Interval> {
        self.ci95.or_else(|| {
            let half = crate::estimate::interval::z95() * self.standard_error?;
            Some([Some(self.value - half), Some(self.value + half)])
        })
    }

    /// A value with an interval measured otherwise (a profile, a count).
    pub fn with_interval(
        value: f64,
        standard_error: Option<f64>,
        ci95: crate::estimate::Interval,
    ) -> Self {
        Self {
            value,
            standard_error,
            ci95: Some(ci95),
        }
    }
}

/// An effect the loop added.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AddedEffect {
    pub effect: Effect,
    pub evidence: String,
    /// Held-out error after adding it.
    pub error_after: f64,
}

/// The residuals a step changed, before and after (for the report's plots).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StepResiduals {
    pub by_intensity: Vec<Bin>,
    pub by_rate_of_change: Vec<Bin>,
}

impl From<&Residuals> for StepResiduals {
    fn from(r: &Residuals) -> Self {
        Self {
            by_intensity: r.by_intensity.clone(),
            by_rate_of_change: r.by_rate_of_change.clone(),
        }
    }
}

/// One step of the loop: an effect tried (or a parameter left out), and why it was kept
/// or not.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Step {
    /// The effect's name (or `thresholds`).
    pub effect: String,
    pub evidence: String,
    /// The evidence in standard errors.
    pub score: f64,
    /// The parameters fitted in this step.
    pub parameters: BTreeMap<String, f64>,
    /// Error of the model before and with the effect on the selection blocks.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_before: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_after: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub components_after: Option<Components>,
    /// The fall of the selection error chance alone would give (twice its measured
    /// standard error), where measurable.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub chance: Option<f64>,
    pub kept: bool,
    pub reason: String,
    pub simulations: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residuals_before: Option<StepResiduals>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residuals_after: Option<StepResiduals>,
}

impl Step {
    /// A step with its evidence, not yet judged (nothing fitted, not kept).
    pub fn untried(effect: String, evidence: String, score: f64) -> Self {
        Self {
            effect,
            evidence,
            score,
            parameters: BTreeMap::new(),
            error_before: None,
            error_after: None,
            components_after: None,
            chance: None,
            kept: false,
            reason: String::new(),
            simulations: 0,
            residuals_before: None,
            residuals_after: None,
        }
    }
}

/// Per parameter the model sets (log response aside): whether the data identify it (not in
/// `not_identified`); the not-identified ones are listed too, as `false`.
pub fn identified(
    params: &PixelParams,
    not_identified: &BTreeMap<String, String>,
) -> BTreeMap<String, bool> {
    let mut out: BTreeMap<String, bool> = serde_json::to_value(params)
        .ok()
        .and_then(|v| v.as_object().cloned())
        .unwrap_or_default()
        .into_iter()
        .filter(|(k, v)| !v.is_null() && k != "log_response" && k != "log_eps")
        .map(|(k, _)| {
            let known = !not_identified.contains_key(&k);
            (k, known)
        })
        .collect();
    for key in not_identified.keys() {
        out.insert(key.clone(), false);
    }
    out
}

/// The fitted model, and which of its parameters the data do not identify: in JSON those
/// are `null` (the model simulated needs a value; a reader must not take it for a result).
#[derive(Clone, Debug, PartialEq)]
pub struct FittedParams {
    pub model: PixelParams,
    /// Parameter (PARAMS.toml key) -> why the data do not identify it.
    pub not_identified: BTreeMap<String, String>,
}

impl std::ops::Deref for FittedParams {
    type Target = PixelParams;
    fn deref(&self) -> &PixelParams {
        &self.model
    }
}

impl std::ops::DerefMut for FittedParams {
    fn deref_mut(&mut self) -> &mut PixelParams {
        &mut self.model
    }
}

impl Serialize for FittedParams {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut value = serde_json::to_value(&self.model).map_err(serde::ser::Error::custom)?;
        if let Some(map) = value.as_object_mut() {
            for key in self.not_identified.keys() {
                map.insert(key.clone(), serde_json::Value::Null);
            }
        }
        value.serialize(serializer)
    }
}

/// The result of `ctcal fit` (the JSON keys of `../shared/CLI.md`, and more).
#[derive(Clone, Debug, Serialize)]
pub struct FitResult {
    /// Sensor biases saved in or beside the recording (filled by the caller that knows the
    /// files; absent when none are found). No model ties them to the parameters.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub biases: Option<crate::biases::Biases>,
    /// The fitted model (PARAMS.toml keys; `null` where not identified).
    pub params: FittedParams,
    /// Per parameter of the model: whether the data identify it.
    pub identified: BTreeMap<String, bool>,
    /// Why a parameter is not identified (`null` in `params`).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub why: BTreeMap<String, String>,
    /// Per parameter of an effect the final model lacks (absent from `params`, so off in a
    /// configuration): why it is off, and the strength at which this recording would have
    /// shown it where that was measured ([`not_detected`]). Off is not a measurement of
    /// zero.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub not_detected: BTreeMap<String, String>,
    pub uncertainties: BTreeMap<String, Uncertain>,
    pub effects_added: Vec<AddedEffect>,
    pub error_metric: &'static str,
    /// Error of the ideal model (fitted thresholds) and of the final model on the test
    /// blocks (which neither fitted nor chose anything).
    pub error_before: f64,
    pub error_after: f64,
    pub components_before: Components,
    pub components_after: Components,
    pub steps: Vec<Step>,
    /// Pairs of effects the recording does not separate: the kept one and a look-alike
    /// that explains it as well within chance, with what data would separate them.
    pub ambiguities: Vec<Ambiguity>,
    /// Hot pixels named (simulated where they are as their own event trains).
    pub hot_pixels_masked: Vec<HotPixel>,
    /// Which hot pixels `hot_pixel_fraction` counts: those fast enough to be found.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hot_pixel_detection: Option<HotPixelDetection>,
    /// Which noise rates the recording would show, for the noise effects the final model
    /// lacks (a fit with frames).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise_detection: Option<NoiseDetection>,
    /// Which photoreceptor cutoff the recording would show, where the final model has none
    /// (a fit with frames).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bandwidth_detection: Option<BandwidthDetection>,
    /// What bounds or questions a threshold mismatch the final model lacks, where event
    /// timing resolved no spread (a fit with frames).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mismatch_detection: Option<MismatchDetection>,
    /// Residuals of the ideal model and of the final one (fit blocks; a fit without
    /// frames simulates no scene and has none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residuals_before: Option<Residuals>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residuals_after: Option<Residuals>,
    pub assumptions: Vec<String>,
    pub holdout: Holdout,
    pub simulations: usize,
    /// Exposure of the grey frames (the file's, else `--exposure-s`), for the simulator
    /// configurations.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frame_exposure_us: Option<crate::TimeUs>,
    /// What a fit without frames measured beyond the parameters (where the thresholds
    /// come from, the noise rates, the interval edge, the threshold ratio).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub events_only: Option<events_only::EventsOnly>,
}

/// Which noise rates a fit with frames would have seen
/// (`fit::selection::noise_detection`): per noise effect the final model lacks, the rate at
/// which the recording's isolated events would have called for it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NoiseDetection {
    /// By parameter (`shot_noise_rate_hz`, `leak_rate_hz`).
    pub limits: BTreeMap<String, NoiseLimit>,
    /// The rate the effect was simulated at to measure its isolated events, Hz.
    pub probe_hz: f64,
    pub meaning: &'static str,
}

/// Which photoreceptor cutoff a fit with frames would have seen
/// (`fit::selection::bandwidth_detection`), where the final model has none.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BandwidthDetection {
    /// The highest cutoff at white at which a recording of this scene would have called
    /// for the effect in about 95 % of such recordings; `null` with `why` where none
    /// would, or the recording already calls for it.
    pub called_for_below_hz: Option<f64>,
    /// `[cutoff_hz, standard errors]`: the evidence of every cutoff simulated.
    pub evidence: Vec<[f64; 2]>,
    /// The recording's own bandwidth evidence beside the final model, standard errors;
    /// `null` where the recording has nothing the evidence reads.
    pub recording_evidence: Option<f64>,
    /// The simulations the detection ran (the final model once, then one per cutoff).
    pub simulations: usize,
    /// The effect was called for and tried, and not kept.
    pub tried: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub why: Option<String>,
    pub meaning: &'static str,
}

/// What bounds or questions a threshold mismatch the final model of a fit with frames
/// lacks, where event timing resolved no spread (`fit::selection::mismatch_detection`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MismatchDetection {
    /// The most event timing on the fit run allows: the upper end of its 95 % interval of
    /// the frozen per-pixel threshold spread (log units); `null` with `why` where it gave
    /// no interval.
    pub at_most: Option<f64>,
    /// That interval.
    pub timing_ci95: Option<[f64; 2]>,
    /// The per-pixel counts' dispersion within tiles against the final model's, standard
    /// errors; `null` where too few events per pixel to compare.
    pub recording_evidence: Option<f64>,
    /// That evidence calls for mismatch: a spread may be present that the selection did not
    /// keep.
    pub counts_call_for_it: bool,
    /// The evidence in words.
    pub evidence: String,
    /// The spread the fit blocks chose where the loop tried mismatch and did not keep it.
    pub tried_spread: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub why: Option<String>,
    pub meaning: &'static str,
}

/// One noise effect's detection limit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NoiseLimit {
    /// The rate at which the evidence would call for the effect; `null` with `why` where
    /// no rate would, or the recording already calls for it.
    pub called_for_above_hz: Option<f64>,
    /// Isolated OFF and ON events the effect adds per pixel-second of the fit blocks, per
    /// Hz of its rate, at the last rate simulated (how much of it stays isolated in this
    /// scene).
    pub isolated_hz_per_hz: Option<[f64; 2]>,
    /// The effect was called for and tried, and not kept.
    pub tried: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub why: Option<String>,
    /// The most the recording allows whatever the scene hides: shot noise's dark rate its
    /// isolated OFF events at quiet pixels allow (95 %,
    /// [`effects::quiet_noise::at_most_dark_hz`]), a leak's rate at the frames' median DN
    /// the event timing's drift allows ([`effects::leak::TimingDrift::at_most_hz`], with
    /// its record on the coverage draws, [`effects::leak::DRIFT_LIMIT_HELD`]); absent where
    /// not measured.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub at_most_hz: Option<f64>,
}

/// Which hot pixels the hot-pixel search sees ([`crate::stats::hot_pixels::Detectability`])
/// and so which `hot_pixel_fraction` counts.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HotPixelDetection {
    /// The rate at which a hot pixel placed at a random kept pixel is named at half of
    /// them: hot pixels this fast or faster are counted in full.
    pub detectable_above_hz: f64,
    /// `[rate_hz, probability]`: the share of kept pixels at which a hot pixel of that rate
    /// is named ([`HotPixelDetection::rates_hz`] and `detectable_above_hz`).
    pub probability: Vec<[f64; 2]>,
    pub meaning: &'static str,
}

impl HotPixelDetection {
    /// The rates [`HotPixelDetection::probability`] is given at: eight a decade from 1 Hz
    /// to 5.6 kHz.
    pub fn rates_hz() -> Vec<f64> {
        (0..30).map(|k| 10f64.powf(k as f64 / 8.0)).collect()
    }

    /// The detection with its half-detection rate and its `[rate_hz, probability]` curve.
    pub fn new(detectable_above_hz: f64, probability: Vec<[f64; 2]>) -> Self {
        Self {
            detectable_above_hz,
            probability,
            meaning: "the hot-pixel search names a hot pixel of rate r at a share probability(r) of the kept pixels; each named pixel weighs 1 / max(probability, 1/2) in hot_pixel_fraction, so hot pixels at detectable_above_hz or faster are counted in full and a slower one as 2 probability(r) of one: the fraction does not determine slower hot pixels",
        }
    }
}

/// How the data were split.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Holdout {
    pub fraction: f64,
    pub blocks: usize,
    /// Selection and test blocks together.
    pub held_out_blocks: Vec<usize>,
    pub selection_blocks: Vec<usize>,
    pub test_blocks: Vec<usize>,
    pub fit_seconds: f64,
    pub held_out_seconds: f64,
    pub selection_seconds: f64,
    pub test_seconds: f64,
    /// Frame intervals left out between runs of different roles.
    pub guard_seconds: f64,
}

pub use selection::{Ambiguity, fit};

#[cfg(test)]
mod tests {
    use super::*;

    /// Ten blocks: 0.16 (0.15 leaves 8.5, rounded to 9 fit blocks and one held out) to 0.75
    /// (2.5 rounds to 3); eight: 0.19 to 0.68 (at least 3 of 8 fit, 2 held out); four cannot split.
    #[test]
    fn a_holdout_must_leave_fit_selection_and_test_blocks() {
        let with = |blocks, holdout| FitOptions {
            blocks,
            holdout,
            ..FitOptions::default()
        };
        assert_eq!(with(10, 0.4).holdout_range(), Some((0.16, 0.75)));
        assert_eq!(with(8, 0.4).holdout_range(), Some((0.19, 0.68)));
        assert_eq!(with(4, 0.4).holdout_range(), None);
        assert!(with(10, 0.4).check().is_ok());
        let e = with(10, 0.1).check().unwrap_err();
        assert!(
            e.problem
                .contains("leaves 9 fit, 0 selection and 1 test blocks of 10"),
            "{e}"
        );
        assert!(with(8, 0.7).check().is_err());
        assert!(with(10, f64::NAN).check().is_err());
        assert!(with(1, 2.0).check().is_err());
        assert!(
            with(4, 0.5)
                .check()
                .unwrap_err()
                .to_string()
                .contains("5 blocks or more")
        );
    }
}
