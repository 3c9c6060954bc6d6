//! The effect library: each effect a real sensor shows and the ideal pixel model lacks,
//! with its residual signature (how a model without it is wrong), the evidence read from
//! the residuals, and the parameter it adds to the simulator with a starting value and a
//! search range. One module per effect:
//!
//! | effect | signature | parameter |
//! |---|---|---|
//! | [`bandwidth`] | a count deficit that grows as intensity falls (and change gets faster) | `cutoff_hz` |
//! | [`leak`] | ON excess among unsupported events | `leak_rate_hz` |
//! | [`shot_noise`] | excess of both polarities among unsupported events, stronger in the dark | `shot_noise_rate_hz` |
//! | [`hot_pixels`] | a few pixels far above their neighbours | masked; `hot_pixel_fraction`, `hot_pixel_rate_hz` |
//! | [`refractory`] | a gap in the shortest same-pixel intervals | `refractory_s` |
//! | [`mismatch`] | per-pixel thresholds that differ (event timing), counts more dispersed | `ct_sigma` |
//! | [`display`] | a spectral line at the refresh rate | `[display]` (through `estimate screen`) |
//! | [`jitter`] | same-pixel intervals shorter than the timestamps allow | `timestamp_jitter_s` |

pub mod bandwidth;
pub mod display;
#[cfg(test)]
pub(crate) mod fixture;
pub mod hot_pixels;
pub mod jitter;
pub mod leak;
pub mod mismatch;
pub(crate) mod quiet_noise;
pub mod refractory;
pub mod shot_noise;

use super::observe::{Geometry, Observed, Subset};
use crate::sim::PixelParams;
use serde::{Deserialize, Serialize};

/// An effect of the sensor model (the CLI's effect names).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    Mismatch,
    Refractory,
    Bandwidth,
    Leak,
    ShotNoise,
    HotPixels,
    TimestampJitter,
    Display,
}

impl Effect {
    pub const ALL: [Effect; 8] = [
        Effect::HotPixels,
        Effect::Bandwidth,
        Effect::Leak,
        Effect::ShotNoise,
        Effect::Refractory,
        Effect::Mismatch,
        Effect::TimestampJitter,
        Effect::Display,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Effect::Mismatch => "mismatch",
            Effect::Refractory => "refractory",
            Effect::Bandwidth => "bandwidth",
            Effect::Leak => "leak",
            Effect::ShotNoise => "shot_noise",
            Effect::HotPixels => "hot_pixels",
            Effect::TimestampJitter => "timestamp_jitter",
            Effect::Display => "display",
        }
    }

    /// Whether a candidate of this effect is also judged on its own signature
    /// ([`crate::fit::selection`]'s keep rule, [`signature`]): a refractory period, whose
    /// gap in the shortest intervals the distance barely sees, and shot noise, whose
    /// isolated events are one component of the distance's seven and in a busy scene move
    /// it less than its block-to-block chance (coverage draws 7033, 8014, 9030).
    pub fn judged_by_signature(self) -> bool {
        matches!(self, Effect::Refractory | Effect::ShotNoise)
    }

    /// Whether the search of this effect's parameter profiles the threshold mismatch with
    /// the thresholds ([`crate::fit::search::search_profiled`]): a refractory period,
    /// which caps the busiest pixels and so narrows the spread of counts that mismatch
    /// widens.
    pub fn searched_with_mismatch(self) -> bool {
        self == Effect::Refractory
    }

    pub fn parse(name: &str) -> Option<Effect> {
        Effect::ALL.into_iter().find(|e| e.name() == name)
    }

    /// The PARAMS.toml key the effect's searched parameter sets (`None`: set in closed
    /// form, or not by a search).
    pub fn parameter(self) -> Option<&'static str> {
        match self {
            Effect::Mismatch => Some("ct_sigma"),
            Effect::Refractory => Some("refractory_s"),
            Effect::Bandwidth => Some("cutoff_hz"),
            Effect::Leak => Some("leak_rate_hz"),
            Effect::ShotNoise => Some("shot_noise_rate_hz"),
            Effect::TimestampJitter => Some("timestamp_jitter_s"),
            Effect::HotPixels | Effect::Display => None,
        }
    }

    /// Sets the searched parameter.
    pub fn set(self, params: &mut PixelParams, value: f64) {
        let slot = match self {
            Effect::Mismatch => &mut params.ct_sigma,
            Effect::Refractory => &mut params.refractory_s,
            Effect::Bandwidth => &mut params.cutoff_hz,
            Effect::Leak => {
                // a leak that grows with the light keeps its growth's ratio to the dark part
                if let (Some(dark), Some(per_dn)) =
                    (params.leak_rate_hz, params.leak_rate_hz_per_dn)
                    && dark > 0.0
                {
                    params.leak_rate_hz_per_dn = Some(per_dn * value / dark);
                }
                &mut params.leak_rate_hz
            }
            Effect::ShotNoise => &mut params.shot_noise_rate_hz,
            Effect::TimestampJitter => &mut params.timestamp_jitter_s,
            Effect::HotPixels | Effect::Display => return,
        };
        *slot = Some(value);
    }

    /// Removes the effect's parameter from `params` (the effect switched off).
    pub fn clear(self, params: &mut PixelParams) {
        match self {
            Effect::Mismatch => params.ct_sigma = None,
            Effect::Refractory => params.refractory_s = None,
            Effect::Bandwidth => params.cutoff_hz = None,
            Effect::Leak => {
                params.leak_rate_hz = None;
                params.leak_rate_hz_per_dn = None;
            }
            Effect::ShotNoise => params.shot_noise_rate_hz = None,
            Effect::TimestampJitter => params.timestamp_jitter_s = None,
            Effect::HotPixels | Effect::Display => {}
        }
    }

    /// The searched parameter's value in `params` (`None`: not set, or no parameter).
    pub fn value(self, params: &PixelParams) -> Option<f64> {
        match self {
            Effect::Mismatch => params.ct_sigma,
            Effect::Refractory => params.refractory_s,
            Effect::Bandwidth => params.cutoff_hz,
            Effect::Leak => params.leak_rate_hz,
            Effect::ShotNoise => params.shot_noise_rate_hz,
            Effect::TimestampJitter => params.timestamp_jitter_s,
            Effect::HotPixels | Effect::Display => None,
        }
    }

    /// The range searched around a starting value (a factor either side, or the
    /// effect's own plausible range).
    pub fn range(self, start: f64) -> (f64, f64) {
        match self {
            Effect::Bandwidth => (2.0, 5000.0),
            Effect::Mismatch => (
                (start / 3.0).max(mismatch::RANGE.0),
                (start * 3.0).min(mismatch::RANGE.1),
            ),
            Effect::TimestampJitter => (5e-6, 5e-3),
            // started at the recording's shortest intervals, which a period bounds from
            // below and jitter moves below it
            Effect::Refractory => (start / 2.0, start * 2.0),
            _ => (start / 5.0, start * 5.0),
        }
    }
}

impl std::fmt::Display for Effect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// What the evidence of every effect reads: the recording's and the current model's
/// statistics on the fit blocks, and what is known besides.
pub struct Context<'a> {
    pub real: &'a Observed,
    pub sim: &'a Observed,
    pub geometry: &'a Geometry,
    /// Pixels compared (not left out, not masked).
    pub kept: &'a [bool],
    pub model: &'a PixelParams,
    /// The estimators' frozen mismatch with its 95 % interval, when measured.
    pub mismatch_estimate: Option<(f64, [f64; 2])>,
    /// The recording's timestamp grid period, when its stamps are quantised.
    pub timestamp_grid_us: Option<i64>,
    /// The recording's shortest same-pixel intervals on the fit blocks, seconds
    /// ([`refractory::shortest_interval_s`]), when there are enough.
    pub shortest_interval_s: Option<f64>,
    /// The recording's OFF isolated-event rate at quiet pixels on the fit run
    /// ([`crate::fit::events_only::QuietOff`]), where measured.
    pub quiet_off: Option<crate::fit::events_only::QuietOff>,
    /// The leak drift the event timing of the starting estimate measured
    /// ([`leak::TimingDrift`]), where it ran.
    pub leak_drift: Option<leak::TimingDrift>,
    pub subset: Subset,
}

/// How strongly the residuals call for an effect.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Evidence {
    pub effect: Effect,
    /// Strength in standard errors (z); an effect is tried when it reaches
    /// [`EVIDENCE_THRESHOLD`] and its size is large enough to matter (`relevant`).
    pub score: f64,
    pub relevant: bool,
    /// What was seen, in words and numbers.
    pub text: String,
    /// Where the parameter search starts.
    #[serde(skip)]
    pub start: Option<f64>,
    /// A second reading of the start that disagrees with `start` (leak's still pixels,
    /// [`leak::evidence`]): the effect's own step searches from both and keeps the value
    /// with the lower error on the fit blocks (the comparisons of look-alikes,
    /// `selection::alternatives`, search from `start` alone).
    #[serde(skip)]
    pub other_start: Option<f64>,
}

/// The evidence (in standard errors) an effect needs to be tried.
pub const EVIDENCE_THRESHOLD: f64 = 5.0;

impl Evidence {
    pub fn none(effect: Effect, text: impl Into<String>) -> Self {
        Self {
            effect,
            score: 0.0,
            relevant: false,
            text: text.into(),
            start: None,
            other_start: None,
        }
    }

    /// Whether the effect should be tried.
    pub fn calls_for(&self) -> bool {
        self.relevant && self.score >= EVIDENCE_THRESHOLD
    }
}

/// The evidence for `effect` in `context`.
pub fn evidence(effect: Effect, context: &Context) -> Evidence {
    match effect {
        Effect::Bandwidth => bandwidth::evidence(context),
        Effect::Leak => leak::evidence(context),
        Effect::ShotNoise => shot_noise::evidence(context),
        Effect::HotPixels => hot_pixels::evidence(context),
        Effect::Refractory => refractory::evidence(context),
        Effect::Mismatch => mismatch::evidence(context),
        Effect::Display => display::evidence(context),
        Effect::TimestampJitter => jitter::evidence(context),
    }
}

/// The signature `effect` is judged by ([`Effect::judged_by_signature`]): shot noise's is
/// the quiet pixels' count alone ([`quiet_noise::signature`]); every other effect's is its
/// evidence.
pub fn signature(effect: Effect, context: &Context) -> Evidence {
    match effect {
        Effect::ShotNoise => quiet_noise::signature(context, shot_noise::RELEVANT_HZ),
        _ => evidence(effect, context),
    }
}

/// Why `effect` is measured absent, where a direct measure says so (shot noise: the quiet
/// pixels' isolated OFF events, [`quiet_noise::rules_out`]); such an effect is not tried
/// and takes no other's place. Not leak: its quiet pixels' ON events bound only a leak
/// faster than one event in the recording's length, since the simulator's leak (as v2e's)
/// fires its first event one period after the first frame, while a slower one still
/// quickens the ON events of every pixel the scene resets (coverage draw 8027: 0.54 Hz over
/// 1.5 s, no quiet ON excess, lost to such a rule).
pub fn ruled_out(effect: Effect, context: &Context) -> Option<String> {
    match effect {
        Effect::ShotNoise => quiet_noise::rules_out(context, shot_noise::RELEVANT_HZ),
        _ => None,
    }
}

/// Unsupported events of the fit blocks, summed over intensity: (real OFF, real ON,
/// simulated OFF, simulated ON), and the pixel-seconds they came from.
pub(crate) fn background_totals(c: &Context) -> ([f64; 4], f64) {
    isolated_totals(c.real, c.sim, c.geometry, c.subset)
}

/// [`background_totals`] of a recording `real` and a model `sim` over `subset`.
pub(crate) fn isolated_totals(
    real: &Observed,
    sim: &Observed,
    geometry: &Geometry,
    subset: Subset,
) -> ([f64; 4], f64) {
    let (r, s) = (
        real.background_of(geometry, subset),
        sim.background_of(geometry, subset),
    );
    let mut totals = [0.0; 4];
    for i in 0..r.len() {
        totals[i % 2] += r[i] as f64;
        totals[2 + i % 2] += s[i] as f64;
    }
    let exposure = (0..super::observe::INTENSITY_BINS)
        .map(|b| geometry.exposure_of(b, subset))
        .sum();
    (totals, exposure)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_set_their_key() {
        for e in Effect::ALL {
            assert_eq!(Effect::parse(e.name()), Some(e));
        }
        let mut p = PixelParams::ideal(0.3, 0.3);
        Effect::Bandwidth.set(&mut p, 40.0);
        Effect::ShotNoise.set(&mut p, 0.7);
        assert_eq!((p.cutoff_hz, p.shot_noise_rate_hz), (Some(40.0), Some(0.7)));
        assert_eq!(Effect::Leak.parameter(), Some("leak_rate_hz"));
    }
}
