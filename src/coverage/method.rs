//! The methods whose intervals the study scores, how each is called, which cases it
//! applies to, and which parameters it reports.

use super::case::CaseSpec;
use serde::{Deserialize, Serialize};

/// A ctcal command that reports values with 95 % intervals.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// `ctcal estimate aps`: thresholds from APS frames.
    Aps,
    /// `ctcal estimate eppps`: thresholds from the event rate (through the frames'
    /// contrast where the case has frames).
    Eppps,
    /// `ctcal estimate eppps` told to leave the frames aside: the same from the events
    /// alone, through the natural-image prior (what a sensor without frames gets).
    EpppsEvents,
    /// `ctcal estimate screen`: thresholds from an on-screen stimulus.
    Screen,
    /// `ctcal fit`: every simulator parameter.
    Fit,
    /// `ctcal fit --no-frames`: the same from the events alone (what a sensor without
    /// frames gets: thresholds through eppps' natural-image prior, no scene simulated).
    FitEvents,
}

/// The parameters an estimator reports.
const THRESHOLDS: [&str; 3] = ["ct_on", "ct_off", "ct_sigma"];

/// The parameters the fit reports (the PARAMS.toml keys the study has truth for), and
/// [`CUTOFF_LIMIT`] and [`MISMATCH_LIMIT`].
const FITTED: [&str; 13] = [
    "ct_on",
    "ct_off",
    "ct_sigma",
    MISMATCH_LIMIT,
    "cutoff_hz",
    CUTOFF_LIMIT,
    "leak_rate_hz",
    "leak_rate_hz_per_dn",
    "shot_noise_rate_hz",
    "refractory_s",
    "timestamp_jitter_s",
    "hot_pixel_fraction",
    "hot_pixel_rate_hz",
];

impl Method {
    pub const ALL: [Method; 6] = [
        Method::Aps,
        Method::Eppps,
        Method::EpppsEvents,
        Method::Screen,
        Method::Fit,
        Method::FitEvents,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Method::Aps => "aps",
            Method::Eppps => "eppps",
            Method::EpppsEvents => "eppps_events",
            Method::Screen => "screen",
            Method::Fit => "fit",
            Method::FitEvents => "fit_events",
        }
    }

    pub fn parse(name: &str) -> Option<Method> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    /// On-screen cases go to `screen` only; every other case to the rest.
    pub fn applies_to(self, case: &CaseSpec) -> bool {
        (self == Method::Screen) == case.is_screen()
    }

    pub fn parameters(self) -> &'static [&'static str] {
        if self.is_fit() { &FITTED } else { &THRESHOLDS }
    }

    /// `fit`, with or without the frames: reports every simulator parameter and the
    /// effects it added.
    pub fn is_fit(self) -> bool {
        matches!(self, Method::Fit | Method::FitEvents)
    }
}

/// The short name of a parameter in the tables (`Cp`, `Cn`, else the key).
pub fn label(parameter: &str) -> &str {
    match parameter {
        "ct_on" => "Cp",
        "ct_off" => "Cn",
        other => other,
    }
}

/// A fit's `bandwidth_detection.called_for_below_hz` where it kept no cutoff, scored as the
/// interval `[limit, open)` against the true cutoff: the fit says a cutoff at or below the
/// limit would have been called for, so a silent fit's true cutoff lies above it.
pub const CUTOFF_LIMIT: &str = "cutoff_hz_limit";

/// A fit's `mismatch_detection.at_most` where its model has no spread and event timing
/// resolved none, scored as the interval `[0, at_most]` against the true spread.
pub const MISMATCH_LIMIT: &str = "ct_sigma_limit";

/// The truth a parameter is scored against: its own, but [`CUTOFF_LIMIT`]'s is the cutoff
/// and [`MISMATCH_LIMIT`]'s the spread.
pub fn truth_key(parameter: &str) -> &str {
    match parameter {
        CUTOFF_LIMIT => "cutoff_hz",
        MISMATCH_LIMIT => "ct_sigma",
        other => other,
    }
}

/// The effect a parameter belongs to (the fit's effect names); thresholds have none.
pub fn effect_of(parameter: &str) -> Option<&'static str> {
    Some(match parameter {
        "ct_sigma" | MISMATCH_LIMIT => "mismatch",
        "cutoff_hz" | CUTOFF_LIMIT => "bandwidth",
        "leak_rate_hz" | "leak_rate_hz_per_dn" => "leak",
        "shot_noise_rate_hz" => "shot_noise",
        "refractory_s" => "refractory",
        "timestamp_jitter_s" => "timestamp_jitter",
        "hot_pixel_fraction" | "hot_pixel_rate_hz" => "hot_pixels",
        _ => return None,
    })
}
