//! Where the fit starts: the time split (the fit run first, the held-out runs after it) and
//! the starting thresholds, measured by `estimate aps` on the fit run alone so that nothing
//! the loop is judged on has shaped its start.

use super::super::{FitInput, FitOptions, Step};
use crate::estimate::aps::{self, ApsInput};
use crate::estimate::{CtEstimate, Interval};
use crate::events::{EventChunk, Frame, TimeUs};
use crate::sim::PixelParams;
use std::collections::BTreeMap;

/// The end of the fit run: the first `1 - holdout` of the frames' span (everything when
/// nothing is held out).
pub fn fit_end(frames: &[Frame], holdout: f64) -> TimeUs {
    match (frames.first(), frames.last()) {
        (Some(a), Some(b)) if holdout > 0.0 => {
            a.t + ((b.t - a.t) as f64 * (1.0 - holdout)) as TimeUs
        }
        _ => TimeUs::MAX,
    }
}

/// The fit run's events and frames (those up to `end`).
pub struct FitRun {
    pub events: EventChunk,
    pub frames: Vec<Frame>,
}

impl FitRun {
    pub fn new(input: &FitInput, end: TimeUs) -> Self {
        Self {
            events: input.events.between(TimeUs::MIN, end),
            frames: input
                .frames
                .iter()
                .filter(|f| f.t <= end)
                .cloned()
                .collect(),
        }
    }

    pub fn aps_input<'a>(&'a self, input: &'a FitInput) -> ApsInput<'a> {
        ApsInput {
            sensor: input.sensor,
            events: &self.events,
            frames: &self.frames,
            excluded: input.excluded,
            unread: input.unread,
        }
    }
}

/// The starting point: thresholds, whether they stay fixed, the mismatch the estimator
/// measured (value, 95 % interval), the step that records it, and what it assumed.
pub struct Start {
    pub params: PixelParams,
    pub fixed: bool,
    pub mismatch: Option<(f64, [f64; 2])>,
    /// The 95 % interval of the spread where the estimator's event timing resolved none
    /// (its value `null`, the interval reaching 0): the most it allows.
    pub spread_unresolved: Option<[f64; 2]>,
    /// The thresholds as `estimate aps` measured them, with their intervals (none for a
    /// start value).
    pub measured: Option<super::agreement::Measured>,
    /// The thresholds as the start's event timing measured them, where `estimate aps`
    /// computed it, whether or not aps reported a value ([`event_timing`]).
    pub timing: Option<super::agreement::Measured>,
    /// The share of each threshold (ON, OFF) the start found the frames' interpolation to
    /// miss ([`aps::ApsResult::interpolation_share`]; none for a start value).
    pub interpolation_share: Option<[f64; 2]>,
    /// The frames' log offset the start's thresholds were read at, and the range their
    /// systematic spans ([`aps::ApsResult::frame_offset_dn`]; none for a start value).
    pub frame_offset_dn: Option<(f32, (f32, f32))>,
    /// Where the start's offset was not confirmed by both polarities, each threshold at the
    /// ends of the offset's range (down to no offset) over the value ([`aps::ApsResult::offset_reach`]).
    pub offset_reach: Option<[[f64; 2]; 2]>,
    /// The leak drift the estimate's event timing measured (none for a start value).
    pub leak_drift: Option<crate::fit::effects::leak::TimingDrift>,
    pub step: Step,
    pub assumptions: Vec<String>,
}

fn step(evidence: String, parameters: BTreeMap<String, f64>, kept: bool, reason: String) -> Step {
    Step {
        effect: "thresholds".into(),
        evidence,
        score: 0.0,
        parameters,
        error_before: None,
        error_after: None,
        components_after: None,
        chance: None,
        kept,
        reason,
        simulations: 0,
        residuals_before: None,
        residuals_after: None,
    }
}

/// The starting thresholds: `estimate aps` on the fit run, or (a static scene, or aps
/// finding none) `options.default_threshold` as a start value, said so in `assumptions`.
pub fn thresholds(
    input: &FitInput,
    run: &FitRun,
    options: &FitOptions,
    change_rate: f64,
    static_scene: bool,
) -> Start {
    let default = options.default_threshold;
    let fallback = |evidence: String, reason: String, fixed: bool| Start {
        params: PixelParams::ideal(default, default),
        fixed,
        mismatch: None,
        spread_unresolved: None,
        measured: None,
        timing: None,
        interpolation_share: None,
        frame_offset_dn: None,
        offset_reach: None,
        leak_drift: None,
        assumptions: vec![format!(
            "thresholds start at {default} (a start value, not a measurement): {reason}"
        )],
        step: step(evidence, BTreeMap::new(), false, reason),
    };
    if static_scene {
        return fallback(
            format!("the frames change by {change_rate:.4} log units per pixel per second"),
            "a static scene does not show the thresholds; they stay there (leak and shot-noise rates do not depend on them)".into(),
            true,
        );
    }
    let found = aps::estimate(&run.aps_input(input), &options.aps, &|_, _| {});
    let found = found.map(|f| {
        (
            f.estimate,
            f.interpolation_share,
            (f.frame_offset_dn, f.offset_reach),
            f.leak_drift,
            f.noise_polarities,
        )
    });
    match found {
        Ok((e, share, (offset, reach), drift, noise)) => match e.thresholds() {
            Some((on, off)) => Start {
                interpolation_share: Some(share),
                frame_offset_dn: Some(offset),
                offset_reach: (reach != [[1.0; 2]; 2]).then_some(reach),
                leak_drift: Some(crate::fit::effects::leak::TimingDrift::of(&drift, on)),
                timing: event_timing(&e, noise),
                ..measured(&e, on, off)
            },
            None => Start {
                timing: event_timing(&e, noise),
                ..fallback(
                    format!(
                        "estimate aps on the fit run determined no thresholds: {}",
                        reasons_once(&e.why)
                    ),
                    "fitted to the counts from there".into(),
                    false,
                )
            },
        },
        Err(error) => fallback(
            format!("estimate aps on the fit run: {}", error.problem),
            "fitted to the counts from there".into(),
            false,
        ),
    }
}

/// Each distinct reason once, after the quantities it is given for (`ct_on, ct_off: why`):
/// aps usually gives one reason for every quantity.
fn reasons_once(why: &BTreeMap<String, String>) -> String {
    let mut grouped: Vec<(Vec<&str>, &str)> = Vec::new();
    for (key, reason) in why {
        match grouped.iter_mut().find(|(_, r)| *r == reason.as_str()) {
            Some((keys, _)) => keys.push(key),
            None => grouped.push((vec![key], reason)),
        }
    }
    grouped
        .iter()
        .map(|(keys, reason)| format!("{}: {reason}", keys.join(", ")))
        .collect::<Vec<_>>()
        .join("; ")
}

/// The thresholds (value, 95 % interval) of the event timing among `e`'s estimators: the
/// log change between a pixel's consecutive events read from the frames, which counts no
/// events, so that an effect that loses or adds events (ESIM's threshold redrawn per
/// sample interval strands pixels on a ramp; a random walk of the reference) leaves it
/// where the count-matched thresholds move. aps may report no value of its own (its
/// re-simulation check failing) and still have this one. A polarity whose samples are
/// mostly noise (`noise`, ON and OFF: aps withheld it for that) is left out, as a value
/// that is not a number, and so is one whose interval reaches 0 or is not finite: it
/// bounds nothing below, so the fit has nothing to disagree with or to span.
fn event_timing(e: &CtEstimate, noise: [bool; 2]) -> Option<super::agreement::Measured> {
    let timing = e.estimators.iter().find(|r| r.name == "event_timing")?;
    let side = |m: &crate::estimate::interval::Measured, noise: bool| {
        let [lo, hi] = m.ci95;
        if !noise && m.value.is_finite() && lo > 0.0 && hi.is_finite() {
            (m.value, [Some(lo), Some(hi)])
        } else {
            (f64::NAN, [None, None])
        }
    };
    Some([
        side(&timing.ct_on, noise[0]),
        side(&timing.ct_off, noise[1]),
    ])
}

fn measured(e: &CtEstimate, on: f64, off: f64) -> Start {
    let ci = |c: Option<Interval>| {
        let [lo, hi] = c.unwrap_or([None, None]);
        let side = |v: Option<f64>| v.map_or("open".to_string(), |v| format!("{v:.4}"));
        format!("[{}, {}]", side(lo), side(hi))
    };
    Start {
        params: PixelParams::ideal(on, off),
        fixed: false,
        mismatch: e.ct_sigma.zip(e.ct_sigma_ci95),
        spread_unresolved: e
            .ct_sigma_ci95
            .filter(|[lo, hi]| e.ct_sigma.is_none() && *lo >= 0.0 && hi.is_finite() && hi > lo),
        measured: Some([
            (on, e.ct_on_ci95.unwrap_or([None, None])),
            (off, e.ct_off_ci95.unwrap_or([None, None])),
        ]),
        timing: None,
        interpolation_share: None,
        frame_offset_dn: None,
        offset_reach: None,
        leak_drift: None,
        assumptions: Vec::new(),
        step: step(
            format!(
                "estimate aps on the fit run: ON {on:.4} {}, OFF {off:.4} {}",
                ci(e.ct_on_ci95),
                ci(e.ct_off_ci95)
            ),
            BTreeMap::from([("ct_on".to_string(), on), ("ct_off".to_string(), off)]),
            true,
            "the starting point; refitted with every effect".into(),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(t: TimeUs) -> Frame {
        Frame {
            t,
            width: 1,
            height: 1,
            pixels: vec![0],
            exposure_us: None,
        }
    }

    #[test]
    fn the_fit_run_is_the_first_share_of_the_frames_span() {
        let frames: Vec<Frame> = (0..11).map(|k| frame(1000 + 100 * k)).collect();
        assert_eq!(fit_end(&frames, 0.4), 1000 + 600);
        assert_eq!(fit_end(&frames, 0.0), TimeUs::MAX);
        assert_eq!(fit_end(&[], 0.3), TimeUs::MAX);
    }

    #[test]
    fn a_reason_given_for_several_quantities_is_written_once_after_their_names() {
        let why: BTreeMap<String, String> = [
            ("ct_off", "no threshold reproduces the counts"),
            ("ct_on", "no threshold reproduces the counts"),
            ("ct_sigma", "no thresholds"),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
        assert_eq!(
            reasons_once(&why),
            "ct_off, ct_on: no threshold reproduces the counts; ct_sigma: no thresholds"
        );
    }
}
