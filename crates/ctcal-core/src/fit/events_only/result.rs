//! The result of a fit without frames: the model's parameters (null where the events do
//! not identify them, with why), the noise measured, the loop's steps, the test-block
//! errors and every assumption.

use super::blocks::Blocks;
use super::candidates::{on_excess, symmetric_rate};
use super::measure::Measuring;
use super::measure::{
    BlockMeasure, CONFIRMING_QUIET_SHARE, Isolation, QUIET_SHARE, SUPPORT_RADII_PX,
    SUPPORT_WINDOWS_US, UpperBound,
};
use super::model::{ERROR_METRIC, NoiseModel, compare, distance};
use super::simulate_back::{Replaying, simulated};
use super::steps::Judging;
use super::{EventsOnly, FitRun, IntervalEdge};
use crate::estimate::CtEstimate;
use crate::fit::effects::Effect;
use crate::fit::metric::Components;
use crate::fit::observe::Role;
use crate::fit::selection::finish::{HOT_FRACTION, HOT_RATE, hot_rate_unmeasured};
use crate::fit::selection::keep::PARSIMONY;
use crate::fit::wording::significant;
use crate::fit::{
    AddedEffect, FitInput, FitOptions, FitResult, FittedParams, Holdout, Step, Uncertain,
};
use crate::sim::PixelParams;
use std::collections::BTreeMap;

/// Why mismatch, bandwidth and jitter are not identified without frames.
const NEEDS_BRIGHTNESS: [(&str, &str); 3] = [
    (
        "ct_sigma",
        "per-pixel threshold mismatch shows in how many events each pixel gives for the brightness change it saw: that needs grey frames or a known stimulus (estimate screen)",
    ),
    (
        "cutoff_hz",
        "the photoreceptor bandwidth shows in how events lag brightness changes of known speed and intensity: that needs grey frames or a known stimulus",
    ),
    (
        "timestamp_jitter_s",
        "timestamp jitter shows against a stimulus of known timing: that needs a screen recording or frames",
    ),
];

/// Everything the result is made from.
pub(super) struct Parts<'a> {
    pub input: &'a FitInput<'a>,
    pub options: &'a FitOptions,
    pub blocks: &'a Blocks,
    pub judging: &'a Judging<'a>,
    pub run: FitRun,
    pub thresholds: Result<CtEstimate, String>,
    pub steps: Vec<Step>,
    pub model: NoiseModel,
    /// Why the recording's frames were not used, where it has frames.
    pub frames_unused: Option<String>,
}

/// Where the absolute thresholds come from. eppps runs on the fit run only (the blocks
/// before the first held-out one), so it is said which part of the recording that is: the
/// same method on the whole recording measures other events and may differ.
fn thresholds_source(thresholds: &Result<CtEstimate, String>, blocks: &Blocks) -> String {
    match thresholds {
        Ok(e) if e.method == "eppps" => {
            let start = blocks.spans[0].0;
            let end = blocks.spans[blocks.count() - 1].1;
            let fit_end = blocks.fit_end().min(end);
            format!(
                "estimate eppps on the fit run only, the events' first {:.3} s of {:.3} s ({:.0} %; the selection and test blocks are left out, so it can differ from eppps on the whole recording): events per pixel of travel against calibration scenes drawn from its natural-image prior (the prior's spread is in the interval); not a measurement of this sensor's thresholds",
                crate::events::us_to_s(fit_end - start),
                crate::events::us_to_s(end - start),
                100.0 * (fit_end - start) as f64 / (end - start).max(1) as f64
            )
        }
        Ok(e) => format!("estimate {} (given)", e.method),
        Err(reason) => format!("none: {reason}"),
    }
}

/// The result in stages: the parameters, the test errors, the details, then the
/// assumptions (the test errors' and the hot pixels' last).
pub(super) fn result(parts: Parts) -> FitResult {
    let kept = |name: &str| parts.steps.iter().any(|s| s.effect == name && s.kept);
    let parameters = parameters(
        &parts.run,
        &parts.thresholds,
        &kept,
        parts.frames_unused.as_deref(),
    );
    let test = test_blocks(
        parts.input,
        parts.blocks,
        parts.judging,
        &parts.run,
        parts.options,
    );
    let errors = test_errors(&test, &parts.model);
    let events_only = details(
        &parts.run,
        (&parts.thresholds, parts.blocks),
        parts.judging,
        kept("thresholds"),
    );
    let mut assumptions = assumptions(
        &parts.run,
        &parts.thresholds,
        parts.blocks,
        parts.judging,
        parts.options,
        parts.frames_unused.as_deref(),
    );
    assumptions.push(test_errors_note(&errors));
    if !parameters.hot.is_empty() {
        assumptions.push(hot_pixels_note(parameters.hot.len()));
    }
    assembled(parts, parameters, errors, events_only, assumptions)
}

/// How the test errors were measured: simulated back, or (`why` not) from the parameters.
fn test_errors_note(errors: &TestErrors) -> String {
    let (predicted_before, predicted_after) = (errors.predicted_before, errors.predicted_after);
    match &errors.why {
        None => format!(
            "error_before and error_after: the ideal pixel and the final model simulated back onto the test blocks' supported events (the scene as recorded) and measured like the recording (isolated rates, hot pixels); intervals and balance from the model's parameters. Read from the parameters alone they are {predicted_before:.4} and {predicted_after:.4}"
        ),
        Some(why) => format!(
            "error_before and error_after from the model's parameters, not simulated back: {why}"
        ),
    }
}

/// How the `named` hot pixels were found and measured.
fn hot_pixels_note(named: usize) -> String {
    format!(
        "hot pixels: {} named on the fit blocks (robust z against the busiest neighbour, their excess showing also where no neighbour fires within 30 ms); hot_pixel_fraction counts each 1 / the search's detection probability at its rate (Horvitz-Thompson, at least 1/2; Garwood's exact Poisson interval of the count); hot_pixel_rate_hz is the median of their rates beyond their 8 neighbours' median, its interval the median's order-statistic one (the pixels' Poisson errors where too few are named), reaching down to the rate the search names at 10 % of the pixels where it names that median at under 90 %; without frames no model of the scene at each pixel is simulated, so no count outliers of the model's own (a low threshold under mismatch) are subtracted",
        named
    )
}

/// The result from its stages: the parameters, the test errors (the parameters' reading
/// of them joins the details) and the assumptions.
fn assembled(
    parts: Parts,
    parameters: Parameters,
    errors: TestErrors,
    mut events_only: EventsOnly,
    assumptions: Vec<String>,
) -> FitResult {
    let Parameters {
        params,
        why,
        uncertainties,
        hot,
    } = parameters;
    events_only.predicted_error_before = errors.predicted_before;
    events_only.predicted_error_after = errors.predicted_after;
    events_only.simulated_back_why = errors.why;
    FitResult {
        biases: None,
        identified: crate::fit::identified(&params, &why),
        params: FittedParams {
            model: params,
            not_identified: why.clone(),
        },
        why,
        not_detected: BTreeMap::new(),
        uncertainties,
        effects_added: added(&parts.steps),
        error_metric: ERROR_METRIC,
        error_before: errors.before.total,
        error_after: errors.after.total,
        components_before: errors.before,
        components_after: errors.after,
        steps: parts.steps,
        ambiguities: Vec::new(),
        hot_pixels_masked: hot,
        // which hot pixels the search sees, whether or not it named some
        hot_pixel_detection: parts.run.hot_found.detection.clone(),
        noise_detection: None,
        bandwidth_detection: None,
        mismatch_detection: None,
        residuals_before: None,
        residuals_after: None,
        assumptions,
        holdout: holdout(parts.blocks, parts.options),
        simulations: 0,
        frame_exposure_us: None,
        events_only: Some(events_only),
    }
}

/// The model's parameters with their intervals, what is not identified and why, and the
/// hot pixels named (where the loop kept them).
struct Parameters {
    params: PixelParams,
    why: BTreeMap<String, String>,
    uncertainties: BTreeMap<String, Uncertain>,
    hot: Vec<crate::stats::hot_pixels::HotPixel>,
}

/// The stages of [`Parameters`]: absolute thresholds, what needs brightness, noise,
/// refractory period and hot pixels.
fn parameters(
    run: &FitRun,
    thresholds: &Result<CtEstimate, String>,
    kept: &dyn Fn(&str) -> bool,
    frames_unused: Option<&str>,
) -> Parameters {
    let mut why = BTreeMap::new();
    let mut uncertainties = BTreeMap::new();
    let (on, off) = absolute(thresholds, &mut why, &mut uncertainties);
    for (key, reason) in NEEDS_BRIGHTNESS {
        let reason = match frames_unused {
            None => reason.to_string(),
            Some(_) => format!("{reason}; the recording's frames are not used (see assumptions)"),
        };
        why.insert(key.to_string(), reason);
    }
    let mut out = Parameters {
        params: PixelParams::ideal(on, off),
        why,
        uncertainties,
        hot: Vec::new(),
    };
    noise_params(run, kept, &mut out);
    refractory_param(
        run,
        kept("refractory"),
        &mut out.params,
        &mut out.why,
        &mut out.uncertainties,
    );
    if kept("hot_pixels") && !run.hot.is_empty() {
        out.hot = run.hot.clone();
        hot_params(run, &mut out);
    }
    out
}

/// The named hot pixels' fraction and rate, with their intervals.
fn hot_params(run: &FitRun, out: &mut Parameters) {
    let found = &run.hot_found;
    out.params.hot_pixel_fraction = Some(found.fraction.value);
    out.uncertainties
        .insert(HOT_FRACTION.into(), found.fraction.clone());
    // the train a simulator adds on top of the pixel's own events
    if let Some(rate) = &found.rate {
        out.params.hot_pixel_rate_hz = Some(rate.value);
        out.uncertainties.insert(HOT_RATE.into(), rate.clone());
    }
    if let Some(reason) = hot_rate_unmeasured(&out.why, &out.uncertainties) {
        out.why.insert(HOT_RATE.into(), reason);
    }
}

/// The test blocks' errors of the ideal pixel and the final model.
struct TestErrors {
    before: Components,
    after: Components,
    predicted_before: f64,
    predicted_after: f64,
    /// Why the models were not simulated back.
    why: Option<String>,
}

/// What the test errors are measured on.
struct TestBlocks<'a> {
    measuring: Measuring<'a>,
    spans: Vec<(crate::events::TimeUs, crate::events::TimeUs)>,
    judging: &'a Judging<'a>,
    run: &'a FitRun,
    seed: u64,
}

fn test_blocks<'a>(
    input: &'a FitInput,
    blocks: &Blocks,
    judging: &'a Judging<'a>,
    run: &'a FitRun,
    options: &FitOptions,
) -> TestBlocks<'a> {
    TestBlocks {
        measuring: Measuring {
            events: input.events,
            sensor: input.sensor,
            excluded: input.excluded,
            hot: &run.hot_positions,
        },
        spans: blocks
            .of(Role::Test)
            .iter()
            .map(|&b| blocks.spans[b])
            .collect(),
        judging,
        run,
        seed: options.seed,
    }
}

/// Both models simulated back onto the test blocks ([`simulated`]); read from their
/// parameters where that cannot be done.
fn test_errors(t: &TestBlocks, model: &NoiseModel) -> TestErrors {
    let test = t.judging.of(Role::Test);
    let reference = t.judging.reference;
    let ideal = NoiseModel::ideal();
    let predicted_before = distance(&ideal, &test, reference);
    let predicted_after = distance(model, &test, reference);
    let replaying = Replaying {
        measuring: &t.measuring,
        spans: &t.spans,
        isolation: t.run.isolation,
        trains: &t.run.trains,
        edge_us: reference.edge_us,
        seed: t.seed,
    };
    let back = |m: &NoiseModel| simulated(&replaying, m).map(|p| compare(&p, &test, reference));
    let (predicted_before_total, predicted_after_total) =
        (predicted_before.total, predicted_after.total);
    match (back(&ideal), back(model)) {
        (Ok(before), Ok(after)) => TestErrors {
            before,
            after,
            predicted_before: predicted_before_total,
            predicted_after: predicted_after_total,
            why: None,
        },
        (Err(why), _) | (_, Err(why)) => TestErrors {
            before: predicted_before,
            after: predicted_after,
            predicted_before: predicted_before_total,
            predicted_after: predicted_after_total,
            why: Some(why),
        },
    }
}

/// The absolute thresholds and their standard errors (from the 95 % interval), or not
/// identified with the reason (the model then holds NaN, `null` in JSON).
fn absolute(
    thresholds: &Result<CtEstimate, String>,
    why: &mut BTreeMap<String, String>,
    uncertainties: &mut BTreeMap<String, Uncertain>,
) -> (f64, f64) {
    let mut value =
        |key: &str, v: Option<f64>, ci: Option<crate::estimate::Interval>| match (thresholds, v) {
            (Ok(_), Some(v)) => {
                let se = match ci {
                    Some([Some(lo), Some(hi)]) => Some((hi - lo) / (2.0 * 1.96)),
                    _ => None,
                };
                let uncertain = match ci {
                    Some(ci) => Uncertain::with_interval(v, se, ci),
                    None => Uncertain::positive(v, se),
                };
                uncertainties.insert(key.to_string(), uncertain);
                v
            }
            (Ok(e), None) => {
                why.insert(
                    key.to_string(),
                    e.why
                        .get(key)
                        .cloned()
                        .unwrap_or_else(|| format!("{} determined no value", e.method)),
                );
                f64::NAN
            }
            (Err(reason), _) => {
                why.insert(key.to_string(), reason.clone());
                f64::NAN
            }
        };
    let (on, off, on_ci, off_ci) = match thresholds {
        Ok(e) => (e.ct_on, e.ct_off, e.ct_on_ci95, e.ct_off_ci95),
        Err(_) => (None, None, None, None),
    };
    (value("ct_on", on, on_ci), value("ct_off", off, off_ci))
}

/// Shot noise and leak: their values where kept, else not identified with an upper
/// bound (absent when even the bound is below the floor at which rates are told apart).
fn noise_params(run: &FitRun, kept: &dyn Fn(&str) -> bool, out: &mut Parameters) {
    let scene = super::candidates::scene_like_isolated(run);
    shot_noise_param(run, kept("shot_noise"), scene.as_ref(), out);
    leak_param(run, kept("leak"), scene.as_ref(), out);
}

/// Shot noise: the isolated events' symmetric rate where kept, else bounded.
fn shot_noise_param(
    run: &FitRun,
    kept: bool,
    scene: Option<&super::candidates::SceneLike>,
    out: &mut Parameters,
) {
    let Parameters {
        params,
        why,
        uncertainties,
        ..
    } = out;
    if let Some((rate, se)) = symmetric_rate(run) {
        if let (Some(scene), false) = (scene, kept) {
            // the lower end, from the OFF excess over the scene's balance, may pass the
            // upper (draw 8002: 3 OFF and 1 ON isolated events read 0.0004 to 0.0003 Hz)
            let upper = 2.0 * (rate + 2.0 * se);
            let lower = 2.0 * scene.noise_at_least_hz;
            let range = if lower < upper {
                format!(
                    "lies between {} and {} Hz",
                    significant(lower),
                    significant(upper)
                )
            } else {
                format!("is at most {} Hz", significant(upper))
            };
            why.insert(
                "shot_noise_rate_hz".into(),
                format!(
                    "{}: the shot noise {range} (2 standard errors); a static stretch of the recording, or grey frames, would tell them apart",
                    scene.evidence(),
                ),
            );
        } else if kept {
            params.shot_noise_rate_hz = Some(2.0 * rate);
            let dark = dark_rate(2.0 * rate, 2.0 * se);
            uncertainties.insert("shot_noise_rate_hz".into(), down_to_none(dark, run));
            why.insert(
                "shot_noise_bright_factor".into(),
                "how the noise rate depends on brightness needs each pixel's intensity (grey frames); the rate given is the one at the recording's brightness".into(),
            );
        } else {
            why.insert(
                "shot_noise_rate_hz".into(),
                format!(
                    "not told apart from none: at most {} Hz (2 standard errors)",
                    significant(2.0 * (rate + 2.0 * se))
                ),
            );
        }
    }
}

/// Leak: the isolated events' ON excess where kept (a lower bound after an onset, reaching
/// down to the scene's share where it may hold the excess), else bounded.
fn leak_param(
    run: &FitRun,
    kept: bool,
    scene: Option<&super::candidates::SceneLike>,
    out: &mut Parameters,
) {
    let Some((excess, se)) = on_excess(run) else {
        return;
    };
    // an onset only where the isolated events are not the scene's own: a scene whose
    // unsupported events turn ON-heavy later would rise the same way
    if let (Some(onset), None) = (&run.leak_onset, scene) {
        leak_after_onset(onset, (excess, se), kept, out);
    } else if let (Some(scene), false) = (scene, kept) {
        out.why.insert(
            "leak_rate_hz".into(),
            format!(
                "{}: the leak lies between 0 and {} Hz (the ON excess of isolated events, {} +- {} Hz, with 2 standard errors)",
                scene.evidence(),
                significant(excess.max(0.0) + 2.0 * se),
                significant(excess),
                significant(se)
            ),
        );
    } else if kept {
        leak_measured(run, (excess, se), out);
    } else {
        out.why.insert(
            "leak_rate_hz".into(),
            leak_bounded((excess, se), run.noise[1]),
        );
    }
}

/// Why a leak the loop did not keep is bounded, and by how much: by the ON excess of the
/// isolated events over the OFF ones, which shot noise firing both polarities alike leaves
/// to a leak; or, where the OFF events exceed the ON ones beyond 2 standard errors (noise
/// that is not symmetric, which no simulator models: the EVK4 sample's isolated events are
/// OFF-heavy by 66 standard errors), by the isolated ON rate `on` itself, every event of
/// which could be a leak's.
fn leak_bounded((excess, se): (f64, f64), on: Option<(f64, f64)>) -> String {
    const CAVEAT: &str = "shot-noise events reset the pixel, so a leak much slower than the shot noise is hidden; and where the recording starts at a reset, a simulator's first frame or a camera's start, a leak whose period is longer than the time since fires no event yet: the bound holds for leak phases spread at random, as in a camera that has been running";
    if let (true, Some((on, on_se))) = (excess < -2.0 * se, on) {
        return format!(
            "the isolated events are OFF-heavy (ON - OFF = {} +- {} Hz), which noise firing both polarities alike does not make, so their balance does not bound a leak; the isolated ON rate, {} +- {} Hz, does: at most {} Hz ({CAVEAT})",
            significant(excess),
            significant(se),
            significant(on),
            significant(on_se),
            significant(on + 2.0 * on_se)
        );
    }
    format!(
        "the ON excess of isolated events, {} +- {} Hz, is not told apart from none: at most {} Hz ({CAVEAT})",
        significant(excess),
        significant(se),
        significant(excess.max(0.0) + 2.0 * se)
    )
}

/// Leak after an `onset`: the ON `(excess, se)` a lower bound, whether or not the loop
/// `kept` leak (the model simulates the measured excess, the JSON says it is at least
/// that).
fn leak_after_onset(
    onset: &super::leak_onset::Onset,
    (excess, se): (f64, f64),
    kept: bool,
    out: &mut Parameters,
) {
    if kept {
        out.params.leak_rate_hz = Some(excess);
    }
    let lo = (excess - 2.0 * se).max(0.0);
    out.why.insert(
        "leak_rate_hz".into(),
        format!(
            "{}: at least {lo:.4} Hz (2 standard errors), upper end not determined",
            onset.evidence()
        ),
    );
    out.uncertainties.insert(
        "leak_rate_hz".into(),
        Uncertain::with_interval(excess.max(0.0), Some(se), [Some(lo), None]),
    );
}

/// Leak kept: the ON `(excess, se)`, its interval reaching down to none under a noise
/// bound and to the scene's share where the scene may hold the excess.
fn leak_measured(run: &FitRun, (excess, se): (f64, f64), out: &mut Parameters) {
    out.params.leak_rate_hz = Some(excess);
    let leak = down_to_none(Uncertain::positive(excess, Some(se)), run);
    let leak = match super::candidates::scene_share(run) {
        Some(share) => reach_down_to_scene_share(leak, share, se, excess, &mut out.why),
        None => leak,
    };
    out.uncertainties.insert("leak_rate_hz".into(), leak);
}

/// `leak`'s interval reaching down to the least leak the isolated events hold where the
/// scene's own may be among them ([`super::candidates::SceneShare`]), with 2 standard
/// errors of the ON excess, and the reason in `why`; as it is where that is no lower.
fn reach_down_to_scene_share(
    leak: Uncertain,
    share: super::candidates::SceneShare,
    se: f64,
    excess: f64,
    why: &mut BTreeMap<String, String>,
) -> Uncertain {
    let least = (share.leak_at_least_hz - 2.0 * se).max(0.0);
    match leak.ci95 {
        Some([Some(lo), hi]) if least < lo => {
            why.insert("leak_rate_hz".into(), share.text(excess));
            Uncertain::with_interval(leak.value, leak.standard_error, [Some(least), hi])
        }
        _ => leak,
    }
}

/// A noise rate whose isolated events were still falling as the support grew
/// or unconfirmed ([`FitRun::noise_bound`]) is an upper bound: its interval reaches down to none.
fn down_to_none(rate: Uncertain, run: &FitRun) -> Uncertain {
    match rate.ci95 {
        Some([_, hi]) if run.noise_bound.is_some() => {
            Uncertain::with_interval(rate.value, rate.standard_error, [Some(0.0), hi])
        }
        _ => rate,
    }
}

/// The dark shot-noise rate (what `shot_noise_rate_hz` means to v2e and ctcal) from the rate
/// measured at the recording's brightness, `measured` +- `se`: the rate falls towards white
/// to [`PixelParams::shot_noise_bright_factor`] of the dark rate (0.25, v2e's), and without
/// frames the brightness is not known, so the interval runs from the measured rate's lower
/// end (a dark scene) to its upper end over that factor (a white one); the value is the
/// measured rate. Without the factor the interval held only the measured rate (coverage
/// draw 4077, fitted from its events: 1.44 [1.38, 1.50] Hz for a dark rate of 1.79).
fn dark_rate(measured: f64, se: f64) -> Uncertain {
    let at_brightness = Uncertain::positive(measured, Some(se));
    let [lo, hi] = at_brightness
        .ci95
        .unwrap_or([Some(measured), Some(measured)]);
    let white = PixelParams::ideal(1.0, 1.0).shot_noise_bright_factor();
    Uncertain::with_interval(measured, Some(se), [lo, hi.map(|h| h / white)])
}

/// When the shortest same-pixel interval bounds a refractory period.
const ONLY_IF_RESPECTED: &str = " where every event respects it (a camera's pixel resets at each; v2e and ctcal's simulator let shot-noise events through it)";

fn refractory_param(
    run: &FitRun,
    kept: bool,
    params: &mut PixelParams,
    why: &mut BTreeMap<String, String>,
    uncertainties: &mut BTreeMap<String, Uncertain>,
) {
    match &run.edge {
        Some(edge) if kept => {
            params.refractory_s = Some(edge.edge_us * 1e-6);
            uncertainties.insert(
                "refractory_s".into(),
                Uncertain::with_interval(
                    edge.edge_us * 1e-6,
                    Some((edge.range_us[1] - edge.range_us[0]) * 1e-6 / 4.0),
                    [Some(edge.range_us[0] * 1e-6), Some(edge.range_us[1] * 1e-6)],
                ),
            );
        }
        Some(edge) => {
            let reason = match &edge.not_refractory {
                Some(why) => format!(
                    "{why}; a refractory period, if any, is at most {:.0} us{ONLY_IF_RESPECTED}",
                    edge.edge_us
                ),
                None if edge.found => format!(
                    "an edge at {:.0} us that the selection blocks did not confirm",
                    edge.edge_us
                ),
                None => format!(
                    "no gap at the short end of the same-pixel intervals: a refractory period, if any, is at most {:.0} us{ONLY_IF_RESPECTED}",
                    edge.edge_us
                ),
            };
            why.insert("refractory_s".into(), reason);
        }
        None => {
            why.insert(
                "refractory_s".into(),
                "too few same-pixel intervals on the fit blocks to see their short end".into(),
            );
        }
    }
}

fn added(steps: &[Step]) -> Vec<AddedEffect> {
    steps
        .iter()
        .filter(|s| s.kept)
        .filter_map(|s| {
            Some(AddedEffect {
                effect: Effect::parse(&s.effect)?,
                evidence: s.evidence.clone(),
                error_after: s.error_after?,
            })
        })
        .collect()
}

fn details(
    run: &FitRun,
    (thresholds, blocks): (&Result<CtEstimate, String>, &Blocks),
    judging: &Judging,
    ratio_confirmed: bool,
) -> EventsOnly {
    let test = judging.of(Role::Test);
    let rate = |r: Option<(f64, f64)>| r.map(|(value, se)| Uncertain::positive(value, Some(se)));
    let (ct_ratio, ct_ratio_why) = match run.balance {
        Some((b, se)) if se.is_finite() && ratio_confirmed => (Some(Uncertain::positive(b, Some(se))), None),
        Some((b, se)) if se.is_finite() => (None, Some(format!("the fit blocks' balance OFF/ON = {b:.3} +- {se:.3} did not hold on the selection blocks: the scene's brightness does not return over the recording, so the balance is not the threshold ratio"))),
        Some(_) => (None, Some("under three fit blocks with events of both polarities: the balance's spread cannot be measured".to_string())),
        None => (None, Some("too few supported events of one polarity on the fit blocks".to_string())),
    };
    EventsOnly {
        thresholds_source: thresholds_source(thresholds, blocks),
        ct_on_ci95: thresholds.as_ref().ok().and_then(|e| e.ct_on_ci95),
        ct_off_ci95: thresholds.as_ref().ok().and_then(|e| e.ct_off_ci95),
        ct_ratio,
        ct_ratio_why,
        noise_on_hz: rate(run.noise[1]),
        noise_off_hz: rate(run.noise[0]),
        noise_on_test_hz: BlockMeasure::isolated_rate(&test, run.isolation, true).map(|r| r.0),
        noise_upper_bound: run.noise_bound.is_some(),
        noise_off_test_hz: BlockMeasure::isolated_rate(&test, run.isolation, false).map(|r| r.0),
        predicted_error_before: f64::NAN,
        predicted_error_after: f64::NAN,
        simulated_back_why: None,
        quiet_pixel_seconds: run.quiet_pixel_seconds,
        quiet_share: run.quiet_share,
        support_window_ms: run.isolation.window_us() as f64 / 1e3,
        support_radius_px: run.isolation.radius_px(),
        timestamp_step_us: run.timestamp_step_us,
        interval_edge: run.edge.as_ref().map(|e| IntervalEdge {
            edge_us: e.edge_us,
            range_us: e.range_us,
            found: e.found,
            not_refractory: e.not_refractory.clone(),
            below: e.below,
            above: e.above,
            intervals: e.intervals,
        }),
    }
}

/// Every assumption but the test errors' and the hot pixels': the thresholds' source
/// and its own, the method's, the noise bound's, a distance without intervals.
fn assumptions(
    run: &FitRun,
    thresholds: &Result<CtEstimate, String>,
    blocks: &Blocks,
    judging: &Judging,
    options: &FitOptions,
    frames_unused: Option<&str>,
) -> Vec<String> {
    let mut out = Vec::new();
    if let Ok(e) = thresholds {
        out.push(format!(
            "absolute thresholds from estimate {}, marked as such; its assumptions:",
            e.method
        ));
        out.extend(
            e.assumptions
                .iter()
                .map(|a| format!("  {} : {a}", e.method)),
        );
    }
    out.extend(method_assumptions(run, blocks, options, frames_unused));
    out.extend(noise_bound_note(run));
    if judging.reference.edge_us.is_none() {
        out.push("too few same-pixel intervals for the interval component of the distance".into());
    }
    out
}

/// What a fit without frames assumes whatever it finds: the scene not simulated, the
/// isolated events' support, the noise's polarities and brightness, the balance, the
/// blocks and the keep rule.
fn method_assumptions(
    run: &FitRun,
    blocks: &Blocks,
    options: &FitOptions,
    frames_unused: Option<&str>,
) -> [String; 7] {
    let seconds = |r| blocks.seconds(&blocks.of(r));
    [
        format!(
            "{}: the scene is not simulated; the pixel's own effects are measured from the events and checked as a noise model on held-out blocks",
            frames_unused.map_or("no grey frames".to_string(), |why| format!("grey frames not used ({why})"))
        ),
        format!(
            "isolated events: no event within +-{} ms at the {} pixels within {} px (the shortest of {:?} ms after which a longer window no longer lowers the rate: the scene's slow events are supported by then; then the narrowest of radii {:?} px after which a wider one no longer lowers it: the scene's events that fire without their 8 neighbours, an edge crossing one pixel's threshold and not theirs, are supported by then, while noise, independent of its surroundings, keeps its rate); their rate counts only the time no neighbour event covered, at pixels left uncovered at least {:.0} % of a block",
            run.isolation.window_us() / 1000,
            (2 * run.isolation.radius_px() + 1).pow(2) - 1,
            run.isolation.radius_px(),
            SUPPORT_WINDOWS_US.map(|w| w / 1000),
            SUPPORT_RADII_PX,
            100.0 * super::measure::QUIET_SHARE
        ),
        "shot noise fires ON and OFF equally and leak ON only (v2e, Hu et al. 2021): the OFF rate gives the shot noise (ON + OFF = twice it), the ON excess the leak".to_string(),
        "noise rates are those at the recording's brightness: v2e and ctcal give shot_noise_rate_hz as the dark rate, falling to 0.25 of it at full white; without frames the brightness is unknown, so the dark rate lies between 1 and 4 times the value given, and its interval reaches 4 times the measured rate's upper end".to_string(),
        "Cp/Cn from the ON/OFF balance of supported events assumes brightness at each pixel returns over the fit blocks (net log change zero); the jackknife over fit blocks carries how far it does not".to_string(),
        format!(
            "time in {} blocks over the events' span: fit {:.2} s (the first {:.0} %), selection {:.2} s (judges each effect), test {:.2} s (error_before and error_after only)",
            blocks.count(),
            seconds(Role::Fit),
            100.0 * (1.0 - options.holdout),
            seconds(Role::Selection),
            seconds(Role::Test)
        ),
        format!(
            "an effect is kept when its error on the selection blocks falls by more than twice the chance spread of the per-block relative fall (fit blocks, over sqrt of the selection blocks), and by at least {:.0} %",
            100.0 * PARSIMONY
        ),
    ]
}

/// Why the noise rates are upper bounds ([`UpperBound`]), where they are.
fn noise_bound_note(run: &FitRun) -> Option<String> {
    match run.noise_bound? {
        UpperBound::StillFalling => Some(format!(
            "the isolated-event rate was still falling as the support grew ({} ms, {} px) when the scene's events left too little quiet time or the widest neighbourhood was reached: part of the isolated events are the scene's own, so the shot-noise (and leak) rates are upper bounds, their intervals reaching down to none",
            run.isolation.window_us() / 1000,
            run.isolation.radius_px()
        )),
        UpperBound::Unconfirmed { quiet_share } => Some(format!(
            "the scene left {:.2} % of the pixel time quiet (below {:.0} %; noise alone keeps quiet pixels, uncovered half the time, on most of the sensor under this support up to {:.2} Hz a pixel, ON + OFF, and leaves under a tenth of the time quiet at 1.2-1.6 times that) and no wider support kept enough of it to check the isolated-event rate ({} ms, {} px): the quiet pixels are where the scene's activity thins out and their isolated events may be its own, so the shot-noise (and leak) rates are upper bounds, their intervals reaching down to none",
            100.0 * quiet_share,
            100.0 * CONFIRMING_QUIET_SHARE,
            noise_leaving_share(QUIET_SHARE, run.isolation),
            run.isolation.window_us() / 1000,
            run.isolation.radius_px()
        )),
    }
}

fn holdout(blocks: &Blocks, options: &FitOptions) -> Holdout {
    let selection = blocks.of(Role::Selection);
    let test = blocks.of(Role::Test);
    let mut held: Vec<usize> = selection.iter().chain(&test).copied().collect();
    held.sort_unstable();
    Holdout {
        fraction: options.holdout,
        blocks: blocks.count(),
        fit_seconds: blocks.seconds(&blocks.of(Role::Fit)),
        held_out_seconds: blocks.seconds(&held),
        selection_seconds: blocks.seconds(&selection),
        test_seconds: blocks.seconds(&test),
        guard_seconds: 0.0,
        held_out_blocks: held,
        selection_blocks: selection,
        test_blocks: test,
    }
}

/// The noise rate (Hz a pixel, ON + OFF) at which noise alone leaves a pixel uncovered
/// `share` of the time under `support`: `exp(-2 N r W) = share` with `N` the neighbours
/// within its radius and `±W` its window (the pixel's own events do not cover it).
fn noise_leaving_share(share: f64, support: Isolation) -> f64 {
    let side = 2 * support.radius_px() + 1;
    let neighbours = (side * side - 1) as f64;
    let window_s = support.window_us() as f64 * 1e-6;
    -share.ln() / (2.0 * neighbours * window_s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Isolated events balanced within chance bound a leak by their ON excess; OFF-heavy
    /// ones (the EVK4 sample: ON - OFF = -0.00189 +- 0.0000287 Hz) by the ON rate itself,
    /// as the asymmetry is noise no simulator models.
    #[test]
    fn an_off_heavy_balance_bounds_a_leak_by_the_on_rate_alone() {
        let balanced = leak_bounded((0.0023, 0.0013), Some((0.01, 0.001)));
        assert!(balanced.contains("at most 0.00490 Hz"), "{balanced}");
        let off_heavy = leak_bounded((-0.00189, 0.0000287), Some((0.0011, 0.00002)));
        assert!(
            off_heavy.contains("OFF-heavy") && off_heavy.contains("at most 0.00114 Hz"),
            "{off_heavy}"
        );
    }

    #[test]
    fn noise_alone_leaves_a_pixel_uncovered_at_a_rate_set_by_the_support() {
        // 8 neighbours within ±10 ms: exp(-16 r 0.01) = 0.1 at r = ln 10 / 0.16 = 14.39 Hz,
        // a half at 4.33 Hz; 48 neighbours (7 x 7) within ±300 ms: ln 10 / 28.8 = 0.080 Hz
        let narrow = Isolation::default();
        assert!((noise_leaving_share(0.1, narrow) - 14.391).abs() < 1e-3);
        assert!((noise_leaving_share(0.5, narrow) - 4.332).abs() < 1e-3);
        let wide = Isolation {
            window: 3,
            radius: 2,
        };
        assert!((noise_leaving_share(0.1, wide) - 0.0799).abs() < 1e-4);
    }

    /// Coverage draw 4077 read from its events: 1.44 +- 0.03 Hz of shot noise measured at
    /// its brightness for a dark rate of 1.79 Hz. The interval reaches the rate over v2e's
    /// factor at white (0.25), and starts where the measured rate's does.
    #[test]
    fn the_dark_shot_noise_rate_spans_the_unknown_brightness() {
        let u = dark_rate(1.44, 0.03);
        let [Some(lo), Some(hi)] = u.ci95.unwrap() else {
            panic!("a closed interval")
        };
        let spread = (crate::estimate::interval::z95() * 0.03 / 1.44f64).exp();
        assert_eq!(u.value, 1.44);
        assert!((lo - 1.44 / spread).abs() < 1e-9, "{lo}");
        assert!((hi - 4.0 * 1.44 * spread).abs() < 1e-9, "{hi}");
        assert!(lo < 1.79 && 1.79 < hi);
    }
}
