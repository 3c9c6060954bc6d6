//! What a case really is (`truth.json` beside its events): the true value of every scored
//! parameter, which effects are present, and what the recording turned out like (events,
//! brightness), for tracing a miss to its cause.

use super::case::{CaseSpec, Generator, SceneFamily};
use crate::sim::peers::Peer;
use crate::sim::{LogResponse, PixelParams};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The truth of one written case.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    pub case_id: String,
    pub generator: Generator,
    pub family: SceneFamily,
    /// Effects present, by the fit's names (`bandwidth`, `leak`, ...), plus
    /// `log_response_eps` when the pixel's log response is not the estimators' default.
    pub effects: Vec<String>,
    /// True value of every scored parameter (absent: not defined, e.g. `cutoff_hz` of a
    /// pixel without a bandwidth limit).
    pub values: BTreeMap<String, f64>,
    pub params: PixelParams,
    pub width: usize,
    pub height: usize,
    pub duration_s: f64,
    pub speed_px_s: f64,
    /// Mean camera DN of the scene halfway through the recording (through the display for
    /// an on-screen case).
    pub mean_dn: f64,
    pub events: u64,
    pub on_events: u64,
    pub events_per_pixel_per_second: f64,
    pub aps_frames: usize,
    /// The scene's render rate, or the display's refresh rate.
    pub sample_hz: f64,
}

/// The effects present in `params` (the fit's effect names).
pub fn effects_present(params: &PixelParams) -> Vec<String> {
    let on = |v: Option<f64>| v.is_some_and(|v| v > 0.0);
    [
        ("mismatch", on(params.ct_sigma)),
        ("refractory", on(params.refractory_s)),
        ("bandwidth", params.cutoff_hz().is_some()),
        ("leak", params.has_leak()),
        ("shot_noise", on(params.shot_noise_rate_hz)),
        ("hot_pixels", params.hot_pixels().is_some()),
        ("timestamp_jitter", on(params.timestamp_jitter_s)),
        ("display", params.display.is_some()),
        (
            "log_response_eps",
            params.log_response() == LogResponse::Eps,
        ),
    ]
    .into_iter()
    .filter(|(_, present)| *present)
    .map(|(name, _)| name.to_string())
    .collect()
}

/// The true value of every parameter the study scores: an absent effect is 0 (no leak, no
/// noise, no refractory period), except the bandwidth, which is then not defined.
pub fn true_values(params: &PixelParams) -> BTreeMap<String, f64> {
    let mut values = BTreeMap::new();
    let mut put = |key: &str, value: f64| {
        values.insert(key.to_string(), value);
    };
    put("ct_on", params.ct_on);
    put("ct_off", params.ct_off);
    put("ct_sigma", params.ct_sigma.unwrap_or(0.0));
    put("refractory_s", params.refractory_s());
    put("leak_rate_hz", params.leak_rate_hz());
    put("leak_rate_hz_per_dn", params.leak_rate_hz_per_dn());
    put("shot_noise_rate_hz", params.shot_noise_rate_hz());
    put(
        "timestamp_jitter_s",
        params.timestamp_jitter_s.unwrap_or(0.0),
    );
    let (fraction, rate) = params.hot_pixels().unwrap_or((0.0, 0.0));
    put("hot_pixel_fraction", fraction);
    if rate > 0.0 {
        put("hot_pixel_rate_hz", rate);
    }
    if let Some(cutoff) = params.cutoff_hz() {
        put("cutoff_hz", cutoff);
    }
    values
}

/// The effects and scored values of a peer's case: the thresholds, and a leak's two parts
/// (DVS-Voltmeter's drift `k4 + k5 L` is ctcal's `leak_rate_hz` and `leak_rate_hz_per_dn`
/// in ON events a second, its thresholds being 1 V; 0 for the peers without a leak). The
/// peers' threshold noise (redrawn per interval or per event), refractory period (changes
/// dropped, not delayed) and noise (diffusion, measured distributions) are not the
/// parameters ctcal's fit reports, so they are listed as effects for the breakdown, not
/// scored.
fn peer_truth(peer: &Peer) -> (Vec<String>, BTreeMap<String, f64>) {
    let truth = peer.truth().expect("a case's peer reads no noise files");
    let effects = [
        (
            "threshold_noise",
            truth.ct_sigma > 0.0 || truth.ct_sigma_off > 0.0,
        ),
        ("refractory", truth.refractory.period_s > 0.0),
        (
            "leak",
            truth.leak.on_rate_hz > 0.0 || truth.leak.on_rate_hz_per_dn > 0.0,
        ),
        (
            "noise",
            truth.noise.on_rate_hz > 0.0 || truth.noise.model != "none",
        ),
        ("bandwidth", truth.cutoff.is_some()),
        ("latency", truth.latency.mean_s > 0.0),
    ]
    .into_iter()
    .filter(|(_, present)| *present)
    .map(|(name, _)| name.to_string())
    .collect();
    let values = [
        ("ct_on", truth.ct_on),
        ("ct_off", truth.ct_off),
        ("leak_rate_hz", truth.leak.on_rate_hz),
        ("leak_rate_hz_per_dn", truth.leak.on_rate_hz_per_dn),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect();
    (effects, values)
}

impl Truth {
    /// The truth of `case` before simulation (the recording's measurements at zero).
    pub fn of(case: &CaseSpec) -> Truth {
        let (width, height) = case.size();
        let (effects, values) = match &case.peer {
            Some(peer) => peer_truth(peer),
            None => (effects_present(&case.params), true_values(&case.params)),
        };
        Truth {
            case_id: case.id.clone(),
            generator: case.generator,
            family: case.family,
            effects,
            values,
            params: case.params.clone(),
            width,
            height,
            duration_s: case.duration_s(),
            speed_px_s: case.speed_px_s,
            mean_dn: 0.0,
            events: 0,
            on_events: 0,
            events_per_pixel_per_second: 0.0,
            aps_frames: 0,
            sample_hz: 0.0,
        }
    }

    pub fn value(&self, parameter: &str) -> Option<f64> {
        self.values.get(parameter).copied()
    }

    pub fn has_effect(&self, effect: &str) -> bool {
        self.effects.iter().any(|e| e == effect)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coverage::Generator;
    use crate::coverage::method::Method;
    use crate::coverage::record::{Outcome, RunRecord};
    use crate::coverage::summary::score::in_population;

    /// A DVS-Voltmeter draw's leak is scored in ctcal's units: its drift `k4 + k5 L` in
    /// volts per microsecond against thresholds of 1 V is `k4 * 1e6` ON events a second in
    /// the dark and `k5 * 1e6` more per DN; a ctcal draw without a growing leak has 0.
    #[test]
    fn a_voltmeter_leak_is_scored_as_its_two_parts() {
        let case = CaseSpec::draw_from(13014, &[Generator::Voltmeter]);
        let Some(Peer::Voltmeter(peer)) = &case.peer else {
            panic!("a DVS-Voltmeter draw: {:?}", case.peer);
        };
        let truth = Truth::of(&case);
        assert_eq!(truth.value("leak_rate_hz"), Some(peer.k[3] * 1e6));
        assert_eq!(truth.value("leak_rate_hz_per_dn"), Some(peer.k[4] * 1e6));
        assert!(truth.value("leak_rate_hz_per_dn").unwrap() > 0.0);
        let outcome = Outcome::Ok {
            output: Some(serde_json::json!({"params": {}})),
        };
        let record = RunRecord::new(case, Some(truth), Method::Fit, 1.0, outcome);
        assert!(in_population(&record, "leak_rate_hz_per_dn"));
        let ctcal = Truth::of(&CaseSpec::draw(13014));
        assert_eq!(ctcal.value("leak_rate_hz_per_dn"), Some(0.0));
    }
}
