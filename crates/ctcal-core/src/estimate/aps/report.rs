//! The report of `estimate aps`: each estimator's thresholds with the systematic errors
//! measured for them (the frame-rate series, the self-calibration's bias, the frame-time
//! alignment, the log offset, the interpolation's missing share), their combination, the
//! mismatch `ct_sigma`, and the photoreceptor lag and leak drift the event timing found.

use super::Pass;
use crate::estimate::frames::PreparedFrames;
use crate::estimate::interval::{FrameRatePoint, Measured, combine, frame_rate_systematic};
use crate::estimate::timing::TimingEstimate;
use crate::estimate::timing::spread::Spread;
use crate::estimate::{CtEstimate, Determinable, EstimatorReport};
use crate::events::us_to_s;
use serde_json::json;

/// A re-simulated threshold with the share of the change the frames' interpolation misses
/// (the event timing's, [`crate::estimate::timing::PolarityEstimate::interpolation_share`]) put back:
/// the value, and the size of the correction. Shares beyond +-50 % are not trusted to be
/// the interpolation's and are not applied.
fn interpolation_corrected(value: f64, share: f64) -> (f64, f64) {
    if !share.is_finite() || share.abs() >= 0.5 {
        return (value, 0.0);
    }
    let corrected = value / (1.0 - share);
    (corrected, (corrected - value).abs())
}

/// One value of each pass, against the pass's frame interval (passes without it left out).
pub(super) fn series(
    passes: &[(usize, &Pass)],
    value: impl Fn(&Pass) -> Option<f64>,
) -> Vec<FrameRatePoint> {
    passes
        .iter()
        .filter_map(|(step, p)| {
            Some(FrameRatePoint {
                frame_step: *step,
                frame_interval_s: p.interval_s,
                value: value(p)?,
            })
        })
        .collect()
}

/// What the event timing's error is made of where the frames were read in blocks.
pub(super) fn blocks_assumption(timing: &TimingEstimate) -> Option<String> {
    let (on, off) = (
        timing.on.between_blocks_standard_error?,
        timing.off.between_blocks_standard_error?,
    );
    Some(format!(
        "read in blocks of frames: the event timing's statistical error adds to the bootstrap over pixels the spread between the blocks in quadrature (weighted delete-one-block jackknife, scaled by t(0.975, blocks - 1) / 1.96: ON {on:.4}, OFF {off:.4}; together: ON {:.4}, OFF {:.4}), so that thresholds that change over the recording widen the interval; the parts not read are not measured",
        timing.on.standard_error, timing.off.standard_error
    ))
}

/// The event timing's thresholds: the full pass's, less the self-calibration's `bias` (ON,
/// OFF, spread), with the frame-rate, half-the-correction, alignment and offset
/// systematics in their intervals.
pub(super) fn timing_report(
    passes: &[(usize, &Pass)],
    (bias_on, bias_off, sigma_bias): (f64, f64, f64),
    alignment: (f64, f64),
) -> EstimatorReport {
    let full = passes[0].1;
    let series_on = series(passes, |p| Some(p.timing.on.ct));
    let series_off = series(passes, |p| Some(p.timing.off.ct));
    let measure = |t: &crate::estimate::timing::PolarityEstimate,
                   bias: f64,
                   series: &[FrameRatePoint],
                   alignment: f64| {
        let (_, frame_rate) = frame_rate_systematic(series);
        // half the applied correction stays in the interval
        Measured::new(
            t.ct - bias,
            t.standard_error,
            frame_rate
                .hypot(0.5 * bias)
                .hypot(alignment)
                .hypot(t.offset_systematic),
        )
    };
    EstimatorReport {
        name: "event_timing",
        description: "per-pixel log change between consecutive events, from frames interpolated along the optical flow; mean over pixels",
        ct_on: measure(&full.timing.on, bias_on, &series_on, alignment.0),
        ct_off: measure(&full.timing.off, bias_off, &series_off, alignment.1),
        frame_rate_series_on: series_on,
        frame_rate_series_off: series_off,
        details: json!({
            "on": full.timing.on,
            "off": full.timing.off,
            "self_calibration_bias_on": bias_on,
            "self_calibration_bias_off": bias_off,
            "self_calibration_bias_sigma": sigma_bias,
            "alignment_systematic_on": alignment.0,
            "alignment_systematic_off": alignment.1,
        }),
    }
}

/// The share of the change the frames' interpolation misses, as pass `p`'s event timing
/// found it for polarity `on`.
fn missed_share(p: &Pass, on: bool) -> f64 {
    let t = if on { &p.timing.on } else { &p.timing.off };
    t.interpolation_share
}

/// The re-simulation's threshold of polarity `on` over the passes, each with its pass's
/// missed share put back ([`interpolation_corrected`]).
fn corrected_series(passes: &[(usize, &Pass)], on: bool) -> Vec<FrameRatePoint> {
    series(passes, |p| {
        p.resim.as_ref().map(|r| {
            let ct = if on { r.ct_on } else { r.ct_off };
            interpolation_corrected(ct, missed_share(p, on)).0
        })
    })
}

/// The assumption naming the interpolation's correction of the re-simulation `r`: the
/// shares of the full pass, and the thresholds before and after (`corrected`, ON and OFF).
fn interpolation_note(
    r: &crate::estimate::resim::ResimEstimate,
    full: &Pass,
    [on_value, off_value]: [f64; 2],
) -> String {
    format!(
        "the re-simulation's counts come from the same frames interpolated along the flow as the event timing's samples, so they miss the share of the change the timing found the interpolation to miss (ON {:.1} %, OFF {:.1} %): its thresholds are divided by one less that share (ON {:.4} -> {on_value:.4}, OFF {:.4} -> {off_value:.4}), and half the correction stays in their intervals",
        100.0 * missed_share(full, true),
        100.0 * missed_share(full, false),
        r.ct_on,
        r.ct_off,
    )
}

/// A re-simulated threshold `value` with its standard error, and the frame-rate series',
/// the `offset`'s and half the `applied` correction's systematics. The offset moves the
/// re-simulation as it moves the timing (the same frames through the same log).
fn resimulation_measured(
    value: f64,
    se: f64,
    series: &[FrameRatePoint],
    offset: f64,
    applied: f64,
) -> Measured {
    let systematic = frame_rate_systematic(series)
        .1
        .hypot(offset)
        .hypot(0.5 * applied);
    Measured::new(value, se, systematic)
}

/// The re-simulation's thresholds `r` (of the full pass), with the share of the change the
/// interpolation misses put back, and the frame-rate, offset and half-the-correction
/// systematics in their intervals; and the assumption naming the correction where one was
/// applied.
pub(super) fn resimulation_report(
    passes: &[(usize, &Pass)],
    r: &crate::estimate::resim::ResimEstimate,
) -> (EstimatorReport, Option<String>) {
    let full = passes[0].1;
    let series_on = corrected_series(passes, true);
    let series_off = corrected_series(passes, false);
    let (on_value, on_applied) = interpolation_corrected(r.ct_on, missed_share(full, true));
    let (off_value, off_applied) = interpolation_corrected(r.ct_off, missed_share(full, false));
    let note = (on_applied > 0.0 || off_applied > 0.0)
        .then(|| interpolation_note(r, full, [on_value, off_value]));
    let on = resimulation_measured(
        on_value,
        r.standard_error_on,
        &series_on,
        full.timing.on.offset_systematic,
        on_applied,
    );
    let off = resimulation_measured(
        off_value,
        r.standard_error_off,
        &series_off,
        full.timing.off.offset_systematic,
        off_applied,
    );
    let report = EstimatorReport {
        name: "resimulation",
        description: "the frames upsampled along the optical flow and simulated; thresholds whose counts match the real ones in every region and interval (median log ratio)",
        ct_on: on,
        ct_off: off,
        frame_rate_series_on: series_on,
        frame_rate_series_off: series_off,
        details: serde_json::to_value(r).unwrap_or_default(),
    };
    (report, note)
}

/// The method's own systematic error of the combined thresholds, relative to the value:
/// what event timing and re-simulation, combined, miss beyond every term they measure
/// (frame rate, self-calibration, alignment, log offset, the estimators' disagreement).
/// Measured on the coverage study's draws with frames
/// (`benches/coverage/aps-systematic-2026-11-29`, its `systematic.py`: seeds 1-100 and
/// 1001-1080, 194 polarity-cases of random scenes, brightness, speed, frame rate and
/// effects): the smallest term at which 95 % of them are covered (0: 82.5 %, 0.05: 88.1 %,
/// 0.10: 91.8 %, 0.13: 95.4 %). The misses are draws with several moving objects, noise in
/// a dim scene and photoreceptor bandwidth: effects the frames do not show, which move the
/// events by more than the measured terms allow. Median relative half-width 31 % -> 40 %.
pub const METHOD_SYSTEMATIC: f64 = 0.13;

fn method_systematic_assumption() -> String {
    format!(
        "method systematic: {:.0} % of each threshold in its interval, what event timing and re-simulation miss beyond their measured terms on simulated recordings with known thresholds, random scenes and random sensor effects (coverage study, 194 polarity-cases: the smallest term that covers 95 % of them)",
        100.0 * METHOD_SYSTEMATIC
    )
}

/// How many times each threshold (ON, OFF) a log response the events cannot tell from the
/// chosen one gives (each at its own offset): the intervals reach it, on its side only
/// ([`Measured::reaching`]); 1 without one.
fn response_ratios(other: Option<&crate::estimate::timing::OtherResponse>) -> [f64; 2] {
    other.map_or([1.0; 2], |o| o.threshold_ratios())
}

fn slow_assumption(slow: &super::Slow) -> String {
    let f = &slow.found;
    let what = match slow.thresholds {
        Some([on, off]) => format!(
            "the re-simulation with that cutoff (started from the estimators' thresholds times those ratios, else from the quantiser's own) finds ON {on:.4} and OFF {off:.4}, and the intervals reach down to them where they are lower"
        ),
        None => "the re-simulation with that cutoff finds no thresholds, so the intervals do not carry them (the fit, which models bandwidth, can)".to_string(),
    };
    format!(
        "the photoreceptor may be slower than the scene: the events follow the frames low-passed at a cutoff of {} Hz at white ({:.2} Hz at the middle frame's median DN; {} .. {} Hz within 2 standard errors) better than the frames themselves, by {:.1} standard errors of the tile-by-tile count distance of an ideal quantiser on the frames' samples ({:.3} -> {:.3} per 16 x 16 px tile{}), and asks for thresholds {:.2} (ON) and {:.2} (OFF) times as high; the check also fires on simulated recordings without a cutoff (refractory periods, leak and noise spread counts over frames too), where the reach is small (`benches/coverage/aps-slow-photoreceptor-2026-12-05`); such a pixel averages the scene and fires less than the frames' change, so the event timing and the ideal re-simulation read its thresholds high (a refractory period, which also thins the events of fast changes, can look alike: `fit` tells them apart); {what}",
        f.cutoff_hz,
        f.cutoff_at_median_dn_hz,
        f.cutoff_range_hz[0],
        f.cutoff_range_hz[1],
        f.significance,
        f.distance_without,
        f.distance_at_cutoff,
        if f.block_row_step > 1 {
            format!(
                "; every {}th row of 4 x 4 px blocks compared",
                f.block_row_step
            )
        } else {
            String::new()
        },
        f.threshold_ratios[0],
        f.threshold_ratios[1],
    )
}

fn response_assumption(other: &crate::estimate::timing::OtherResponse) -> String {
    let [on, off] = other.threshold_ratios();
    let name = match other.response {
        "eps" => format!("a pure ln(DN + b), b = {:.1} DN", other.offset_dn),
        _ => format!("v2e's lin-log (b = {:.1} DN)", other.offset_dn),
    };
    format!(
        "log response not determined: {name} explains the events' timing within the pixels' noise of the response used (its scatter {:.2} times, 95 % {:.2} .. {:.2}, across the margin {REPLACE:.2} a response must beat); its thresholds, ON {on:.2} and OFF {off:.2} times the ones used, are in the intervals (more events, or frames of brighter scenes, tell the two apart)",
        other.score_ratio,
        other.score_ratio_ci95[0],
        other.score_ratio_ci95[1],
        REPLACE = crate::estimate::timing::response::REPLACE_MARGIN,
    )
}

/// What the estimate reports beside its thresholds.
pub(super) struct Findings {
    /// The log response not chosen where the events cannot rule it out: its thresholds
    /// are carried into the intervals ([`response_systematic`]).
    pub(super) other_response: Option<crate::estimate::timing::OtherResponse>,
    /// The event timing's per-pixel spread, both polarities combined.
    pub(super) spread: Spread,
    /// The self-calibration's bias of that spread.
    pub(super) sigma_bias: f64,
    /// That spread over the passes (every frame, every 2nd and 3rd frame).
    pub(super) sigma_series: Vec<FrameRatePoint>,
    /// How far the spread moves across the frames' offset range
    /// ([`crate::estimate::timing::TimingEstimate::sigma_offset_systematic`]).
    pub(super) sigma_offset_systematic: f64,
    /// The least-squares cross-check ([`crate::estimate::lsq`]).
    pub(super) lsq: Option<crate::estimate::lsq::LeastSquares>,
    pub(super) alignment: serde_json::Value,
    pub(super) offset: Option<crate::estimate::timing::Offset>,
    /// The offset the counts give, where it was searched ([`super::count_offset`]).
    pub(super) offset_from_counts: Option<super::count_offset::CountOffset>,
    /// A photoreceptor much slower than the scene, where the events show one: the
    /// thresholds it asks for are carried into the intervals.
    pub(super) slow: Option<super::Slow>,
}

/// The estimate: the estimators' thresholds combined, the mismatch, the assumptions (the
/// method's, then the range checks'), a withheld value where the re-simulation found no
/// threshold, and the maps, alignment, offset, lag, drift and span found.
pub(super) fn assemble(
    estimators: Vec<EstimatorReport>,
    mut assumptions: Vec<String>,
    frames: &PreparedFrames,
    full: &Pass,
    findings: Findings,
) -> CtEstimate {
    let [on, off] = combined_thresholds(
        &estimators,
        &findings,
        full.timing.offset_reach(),
        &mut assumptions,
    );
    let mut estimate = CtEstimate::from_parts("aps", &on, &off, Determinable::POSITIVE);
    estimate.intervals_used = frames.used_intervals();
    estimate.intervals_dropped = frames
        .intervals
        .iter()
        .filter(|i| !i.used)
        .cloned()
        .collect();
    sigma_result(
        &mut estimate,
        &mut assumptions,
        (
            &findings.spread,
            findings.sigma_bias,
            &findings.sigma_series,
            findings.sigma_offset_systematic,
        ),
    );
    let range_notes = std::mem::replace(&mut estimate.assumptions, assumptions);
    estimate.assumptions.extend(range_notes);
    if full.resim.is_none() {
        estimate.withhold(&format!(
            "the re-simulation of these frames reproduces the recording's event counts at no threshold: its events are not what ideal pixels make from these frames (noise, or effects the frames do not show), so the event timing's value (ON {:.4}, OFF {:.4}, under `estimators`) has no independent check (in the coverage study's test subset both such values missed the truth, one by a factor of 6.5)",
            estimators[0].ct_on.value, estimators[0].ct_off.value
        ));
    }
    withhold_noise_polarities(&mut estimate, &full.timing);
    estimate.estimators = estimators;
    for (key, value) in extra_reports(frames, full, findings) {
        estimate.extra.insert(key.into(), value);
    }
    estimate
}

/// Withholds each threshold whose samples show no peak above the noise beneath them
/// ([`crate::estimate::timing::peak::Peak`]): its events are mostly noise, which both the
/// event timing and the re-simulation's counts read as crossings. The spread goes with it,
/// as it rests on both polarities' maps.
fn withhold_noise_polarities(estimate: &mut CtEstimate, timing: &TimingEstimate) {
    for (on, polarity) in [(true, &timing.on), (false, &timing.off)] {
        let Some(peak) = polarity.peak.filter(|p| !p.stands_out()) else {
            continue;
        };
        let name = if on { "ON" } else { "OFF" };
        estimate.withhold_polarity(
            on,
            &format!(
                "{}, and the re-simulation counts them alike. A method that models the noise (the fit) or a stretch with more motion or contrast can measure it",
                peak.describe(name)
            ),
        );
        estimate.spread_not_determined(
            None,
            format!(
                "the per-pixel spread rests on both polarities' maps, and the {name} samples show no threshold peak above the noise (see ct_{})",
                name.to_lowercase()
            ),
        );
    }
}

/// ON and OFF thresholds combined over the `estimators`, each with the method's systematic
/// error and reaching to what the other log response, a slow photoreceptor and, where a
/// polarity gave no offset, event timing at the ends of the offset's range, down to no
/// offset (`offset_reach`, ratios to the value, ON then OFF) ask for; their assumptions
/// added.
fn combined_thresholds(
    estimators: &[EstimatorReport],
    findings: &Findings,
    offset_reach: [[f64; 2]; 2],
    assumptions: &mut Vec<String>,
) -> [Measured; 2] {
    let response = response_ratios(findings.other_response.as_ref());
    // the thresholds a photoreceptor much slower than the scene asks for, where the
    // re-simulation with its cutoff found them
    let slow = findings.slow.as_ref().and_then(|s| s.thresholds);
    let combined = |pick: fn(&EstimatorReport) -> &Measured,
                    response: f64,
                    slow: Option<f64>,
                    [offset_lo, offset_hi]: [f64; 2]| {
        let refs: Vec<&Measured> = estimators.iter().map(pick).collect();
        match combine(&refs) {
            Some((value, error)) => Measured::new(value, error, METHOD_SYSTEMATIC * value)
                .reaching(response)
                // a slow photoreceptor reads thresholds high only: the reach goes down
                .reaching(slow.map_or(1.0, |c| (c / value).min(1.0)))
                .reaching(offset_lo)
                .reaching(offset_hi),
            None => Measured::new(f64::NAN, f64::NAN, 0.0),
        }
    };
    assumptions.push(method_systematic_assumption());
    assumptions.extend(findings.other_response.as_ref().map(response_assumption));
    assumptions.extend(findings.slow.as_ref().map(slow_assumption));
    [
        combined(
            |e| &e.ct_on,
            response[0],
            slow.map(|s| s[0]),
            offset_reach[0],
        ),
        combined(
            |e| &e.ct_off,
            response[1],
            slow.map(|s| s[1]),
            offset_reach[1],
        ),
    ]
}

/// The estimate's `extra` beside the thresholds: the per-pixel maps' reach, the frame
/// alignment, the log response and offset, the spread's frame-rate series, the
/// photoreceptor's lag and slowness, leak drift and the time span.
fn extra_reports(
    frames: &PreparedFrames,
    full: &Pass,
    findings: Findings,
) -> [(&'static str, serde_json::Value); 9] {
    let maps = &full.timing.maps;
    [
        (
            "maps",
            json!({
                "pixels_on": maps.ct_on.iter().filter(|v| v.is_finite()).count(),
                "pixels_off": maps.ct_off.iter().filter(|v| v.is_finite()).count(),
                "least_squares_cross_check": findings.lsq,
            }),
        ),
        ("frame_time_alignment", findings.alignment),
        ("log_response_other", json!(findings.other_response)),
        (
            "frame_offset_dn",
            json!({"value": frames.offset, "estimate": findings.offset, "from_counts": findings.offset_from_counts}),
        ),
        ("ct_sigma_frame_rate_series", json!(findings.sigma_series)),
        ("photoreceptor_lag", lag_report(&full.timing.lag)),
        (
            "photoreceptor_slow",
            json!(findings.slow.as_ref().map(|s| json!({
                "check": s.found,
                "resimulated_thresholds": s.thresholds,
            }))),
        ),
        ("leak_drift", drift_report(&full.timing.drift)),
        (
            "time_span_s",
            json!([
                us_to_s(frames.times[0]),
                us_to_s(*frames.times.last().expect("two frames"))
            ]),
        ),
    ]
}

/// The method's own systematic error of the spread `ct_sigma`, absolute (ln units): what
/// the per-pixel thresholds' spread misses beyond its measured terms (the self-calibration's
/// bias, the 10 % floor, the frame-rate series, the offset range) where effects the frames
/// do not show vary from pixel to pixel (bandwidth in dim pixels, several moving objects,
/// refractory periods), adding apparent spread or hiding real spread. Measured on the
/// coverage study's draws with frames (`benches/coverage/aps-sigma-systematic-2026-11-29`,
/// its `sigma_systematic.py`: 53 draws of seeds 1-100 and 1001-1080 with a resolved
/// spread): the smallest term, added in quadrature, at which 95 % of them are covered (0:
/// 75.5 %, 0.010: 90.6 %, 0.012: 96.2 %). An absolute term because the misses are as large
/// for spreads of 0.04 as of 0.08 (the largest: 0.022 for a true 0.076 in a multi-object
/// scene); one relative to the thresholds covers as many draws only by leaving more spreads
/// unresolved (25 against 19 at 95 %).
pub const SIGMA_METHOD_SYSTEMATIC: f64 = 0.012;

/// The frozen threshold spread: the timing's per-pixel spread (estimation noise removed,
/// both polarities combined: [`crate::estimate::timing::spread`]) less the
/// self-calibration's bias. Its interval carries the whole bias and at least 10 % of the
/// value as systematic (the spread a mismatch-free simulation of the same frames shows
/// varies by about that between seeds), and, in quadrature, the frame-rate systematic of
/// the spread over the passes (`series`): how far the spread moves when every 2nd and 3rd
/// frame is used, as for the thresholds, and its change across the frames' offset range
/// (`offset`), as for the thresholds, and the method's own systematic
/// ([`SIGMA_METHOD_SYSTEMATIC`]). Where a polarity showed that the noise
/// subtraction overshoots, the upper side is raised by what it overshot. Where the bias
/// eats the measured spread, the spread is not resolved: `null` with an upper bound; where
/// both polarities overshoot, `null` with the spread the larger overshoot can hide as bound.
fn sigma_result(
    estimate: &mut CtEstimate,
    assumptions: &mut Vec<String>,
    (spread, sigma_bias, series, offset): (&Spread, f64, &[FrameRatePoint], f64),
) {
    if spread.has_overshoot() {
        assumptions.push(overshoot_note(spread));
    }
    if !spread.sigma.is_finite() {
        // as for one polarity: no more spread than the larger overshoot can hide
        let upper = spread.raised(0.0);
        not_resolved(
            estimate,
            upper,
            format!(
                "not resolved: in both polarities the per-pixel thresholds spread less than their estimation noise by more than chance allows (the noise subtraction overshoots), so no spread is measured; 95 % upper bound {upper:.4}, the spread the larger overshoot can hide"
            ),
        );
        return;
    }
    let sigma = spread.sigma;
    // no spread from the self-calibration's simulation: no correction, and none known
    let sigma_bias = if sigma_bias.is_finite() {
        sigma_bias
    } else {
        assumptions.push("ct_sigma: the self-calibration's simulation gave no spread (both its polarities overshoot), so the method's own bias of the spread is not known and 0 is used: only the 10 % floor and the method systematic stand for it".into());
        0.0
    };
    let value = sigma - sigma_bias;
    let (_, frame_rate) = frame_rate_systematic(series);
    let floor = sigma_bias.abs().max(0.1 * value.abs());
    let systematic = floor
        .hypot(frame_rate)
        .hypot(offset)
        .hypot(SIGMA_METHOD_SYSTEMATIC);
    let measure = Measured::new(value, spread.sigma_standard_error, systematic);
    let said = spread_said(spread);
    assumptions.push(format!(
        "ct_sigma: the per-pixel spread {said} less the self-calibration's bias {sigma_bias:+.4}; its interval holds that whole bias and at least 10 % of the value ({floor:.4}) and, in quadrature, how far the spread moves when every 2nd and 3rd frame is used ({frame_rate:.4}), across the frames' offset range ({offset:.4}) and the method systematic {SIGMA_METHOD_SYSTEMATIC} (what the spread misses on simulated recordings with known mismatch and random sensor effects, coverage study, 53 draws: the smallest term that covers 95 % of them) as systematic ({systematic:.4})"
    ));
    let hi = spread.raised(measure.ci95[1]);
    if measure.ci95[0] > 0.0 {
        estimate.ct_sigma = Some(value);
        estimate.ct_sigma_ci95 = Some([measure.ci95[0], hi]);
    } else {
        let upper = hi.max(unresolved_upper_bound(spread));
        not_resolved(
            estimate,
            upper,
            format!(
                "not resolved: the per-pixel spread {said} is within the method's own spread on a mismatch-free simulation ({sigma_bias:.4}) and its errors, the method systematic included; 95 % upper bound {upper:.4} (the excess variance of the per-pixel thresholds over their estimation noise, plus 1.96 of its standard errors)"
            ),
        );
    }
}

/// The per-pixel spread as the notes give it: its value, or, where the thresholds spread
/// no more than their estimation noise (the spread is then 0, `sqrt(max(v, 0))`), that
/// excess variance, which 0.0000 alone would not tell.
fn spread_said(spread: &Spread) -> String {
    if spread.sigma > 0.0 {
        format!("{:.4}", spread.sigma)
    } else {
        format!(
            "0 (the per-pixel thresholds' variance less their estimation noise's is {:.2e} +- {:.2e}, not above 0)",
            spread.excess_variance, spread.excess_variance_standard_error
        )
    }
}

/// `ct_sigma` not resolved: `null`, `[0, upper]` and the reason.
fn not_resolved(estimate: &mut CtEstimate, upper: f64, why: String) {
    estimate.spread_not_determined(Some([0.0, upper]), why);
}

/// What a polarity whose noise subtraction overshoots does to `ct_sigma`, in words.
fn overshoot_note(spread: &Spread) -> String {
    let left_out = match spread.used {
        [true, false] => "OFF",
        [false, true] => "ON",
        _ => "both polarities'",
    };
    format!(
        "ct_sigma: the {left_out} per-pixel thresholds spread less than their estimation noise by more than {} standard errors (the pooled within-pixel variance of busy pixels overstates the noise of pixels with one or two samples), so that polarity is left out; the same subtraction may lower the other polarity's spread by as much, so the interval's upper side is raised by it in variance ({:.2e} log^2: sqrt(hi^2 + that))",
        crate::estimate::timing::spread::OVERSHOOT_Z,
        spread.overshoot
    )
}

/// The 95 % upper bound of a spread the data do not resolve, found where it is bounded: in
/// the combined excess variance (between-pixel variance less estimation noise, which the
/// bootstrap follows through zero), `sqrt(max(v, 0) + 1.96 se(v))`, raised by an
/// overshoot. With few samples per pixel the estimation noise is large and so is the
/// bound; the spread of `sigma` itself (zero in most draws there) would give a bound near
/// zero that the data do not support.
fn unresolved_upper_bound(spread: &Spread) -> f64 {
    let (v, se) = (
        spread.excess_variance,
        spread.excess_variance_standard_error,
    );
    spread.raised((v.max(0.0) + crate::estimate::interval::z95() * se).sqrt())
}

/// Whether a nuisance coefficient of the event timing differs from zero at 95 %, in words.
fn resolved(value: f64, standard_error: f64) -> &'static str {
    if value.abs() > crate::estimate::interval::z95() * standard_error {
        "resolved: differs from zero at 95 %"
    } else {
        "not resolved: within 1.96 standard errors of zero"
    }
}

/// The photoreceptor lag the timing took out of the thresholds, for the JSON: a coefficient
/// of its regression, so noise can make it negative (no lag to speak of); the cutoff it
/// stands for exists only for a positive lag, and where there is none the reason says so.
fn lag_report(lag: &crate::estimate::timing::Lag) -> serde_json::Value {
    let mut report = json!({
        "tau_times_dn_s": lag.tau_times_dn,
        "standard_error": lag.standard_error,
        "resolved": resolved(lag.tau_times_dn, lag.standard_error),
        "cutoff_hz_at_median_dn": lag.cutoff_hz_at_median_dn,
        "median_dn": lag.median_dn,
        "meaning": "the photoreceptor's lag behind the light, tau = tau_times_dn / (DN + b), measured from how pairs of events straddling a change of speed deviate; taken out of the thresholds (a regression coefficient: noise makes it negative where there is no lag)",
    });
    if lag.cutoff_hz_at_median_dn.is_none() {
        report["why"] = json!(format!(
            "no cutoff: the lag measured is not positive ({:.2e} s DN, standard error {:.1e}), so it stands for no photoreceptor bandwidth limit (a negative value beyond its noise is an effect the timing model lacks, such as refractory delays, not a lag)",
            lag.tau_times_dn, lag.standard_error
        ));
    }
    report
}

/// The drift of the memorised level the timing took out of the thresholds, for the JSON.
fn drift_report(drift: &crate::estimate::timing::Drift) -> serde_json::Value {
    json!({
        "log_units_per_second_at_median_dn": drift.at_median_dn,
        "median_dn": drift.median_dn,
        "standard_error": drift.standard_error,
        "resolved": resolved(drift.at_median_dn, drift.standard_error),
        "per_dn": drift.per_dn,
        "per_dn_standard_error": drift.per_dn_standard_error,
        "meaning": "the memorised level's drift the event timing measured, positive downward (leak: ON events come early, OFF late); a negative value is an upward drift, which leak does not make: noise, or an effect the timing lacks; taken out of the thresholds either way",
    })
}

#[cfg(test)]
mod tests {
    use super::{
        SIGMA_METHOD_SYSTEMATIC, drift_report, interpolation_corrected, lag_report, sigma_result,
    };
    use crate::estimate::interval::{Measured, z95};
    use crate::estimate::timing::spread::Spread;
    use crate::estimate::{CtEstimate, Determinable};

    /// `ct_sigma` from a spread of `sigma` +- `standard_error` with no bias, frame-rate
    /// series or offset term: the value, its interval and the `why` of a null.
    fn spread_reported(sigma: f64, standard_error: f64) -> CtEstimate {
        let threshold = Measured::new(0.3, 0.01, 0.0);
        let mut estimate =
            CtEstimate::from_parts("aps", &threshold, &threshold, Determinable::POSITIVE);
        let spread = Spread {
            excess_variance: sigma * sigma,
            excess_variance_standard_error: 2.0 * sigma * standard_error,
            sigma,
            sigma_standard_error: standard_error,
            used: [true, true],
            overshoot: 0.0,
        };
        let mut assumptions = Vec::new();
        sigma_result(&mut estimate, &mut assumptions, (&spread, 0.0, &[], 0.0));
        assert!(
            assumptions
                .iter()
                .any(|a| a.contains("method systematic 0.012")),
            "{assumptions:?}"
        );
        estimate
    }

    #[test]
    fn the_spreads_interval_carries_the_method_systematic_and_a_small_spread_is_not_resolved() {
        // 0.05 +- 0.004: half-width 1.96 sqrt(0.004^2 + 0.005^2 (the 10 % floor) + 0.012^2)
        let estimate = spread_reported(0.05, 0.004);
        let half = z95() * (0.004f64.powi(2) + 0.005f64.powi(2) + 0.012f64.powi(2)).sqrt();
        assert!((half - 0.02662).abs() < 1e-4, "{half}");
        assert_eq!(estimate.ct_sigma, Some(0.05));
        let [lo, hi] = estimate.ct_sigma_ci95.unwrap();
        assert!((lo - (0.05 - half)).abs() < 1e-12 && (hi - (0.05 + half)).abs() < 1e-12);
        // 0.02 +- 0.003, which the old terms resolved ([0.013, 0.027]): the method's own
        // error reaches 0, so the spread is `null` with its upper bound
        let estimate = spread_reported(0.02, 0.003);
        assert_eq!(estimate.ct_sigma, None);
        let upper = estimate.ct_sigma_ci95.unwrap()[1];
        let half =
            z95() * (0.003f64.powi(2) + 0.002f64.powi(2) + SIGMA_METHOD_SYSTEMATIC.powi(2)).sqrt();
        assert!(upper >= 0.02 + half - 1e-12, "{upper}");
        assert!(estimate.why["ct_sigma"].contains("method systematic included"));
    }

    #[test]
    fn a_negative_lag_has_no_cutoff_and_says_why_and_an_upward_drift_says_what_it_is() {
        // slider_depth's event timing: tau (DN + b) -0.0071 s DN, a drift of -0.29 log/s
        let lag = crate::estimate::timing::Lag {
            tau_times_dn: -0.0071,
            standard_error: 0.002,
            cutoff_hz_at_median_dn: None,
            median_dn: 80.0,
        };
        let report = lag_report(&lag);
        assert_eq!(report["resolved"], "resolved: differs from zero at 95 %");
        assert!(report["cutoff_hz_at_median_dn"].is_null());
        assert!(report["why"].as_str().unwrap().contains("not positive"));
        let lag = crate::estimate::timing::Lag {
            standard_error: 0.004,
            cutoff_hz_at_median_dn: Some(120.0),
            ..lag
        };
        let report = lag_report(&lag);
        assert_eq!(
            report["resolved"],
            "not resolved: within 1.96 standard errors of zero"
        );
        assert!(report.get("why").is_none());
        let drift = crate::estimate::timing::Drift {
            at_zero_dn: -0.3,
            per_dn: 0.0001,
            median_dn: 100.0,
            at_median_dn: -0.29,
            standard_error: 0.1,
            per_dn_standard_error: 0.001,
        };
        let report = drift_report(&drift);
        assert_eq!(report["resolved"], "resolved: differs from zero at 95 %");
        assert!(report["meaning"].as_str().unwrap().contains("upward drift"));
    }

    #[test]
    fn the_interpolations_share_is_put_back_into_a_resimulated_threshold() {
        // counts from frames that show 90 % of the change give 90 % of the threshold
        let (value, applied) = interpolation_corrected(0.27, 0.1);
        assert!((value - 0.3).abs() < 1e-12 && (applied - 0.03).abs() < 1e-12);
        // a share that large is not the interpolation's: left alone
        assert_eq!(interpolation_corrected(0.27, 0.6), (0.27, 0.0));
        assert_eq!(interpolation_corrected(0.27, f64::NAN), (0.27, 0.0));
    }
}
