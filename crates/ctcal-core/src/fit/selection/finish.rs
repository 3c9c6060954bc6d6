//! The fit's result: the final model's error on the test blocks, the thresholds' standard
//! errors, what the data identify and what they do not, and every assumption with its size.

use super::super::effects::Effect;
use super::super::metric::{ERROR_METRIC, cell_ratios, median_ratios_of, ratios_of_cells};
use super::super::observe::{Observed, Role, Subset};
use super::super::residuals::{Residuals, residuals};
use super::super::search::{Simulated, Simulation, THRESHOLD_RANGE};
use super::super::{
    AddedEffect, FitInput, FitOptions, FitResult, FittedParams, Holdout, Step, Uncertain,
};
use super::State;
use super::keep::{PARSIMONY, UNMEASURED_CHANCE};
use crate::estimate::frames::exposure_of;
use crate::stats::jackknife::{t95_scale, weighted_jackknife_se};
use crate::stats::robust::mad_sigma;
use std::collections::BTreeMap;

/// Standard errors of the thresholds: the larger of two measures of how well the fit
/// blocks fix them (thresholds are profiled to a zero median count-cell log ratio, and
/// counts scale about as `1 / C`, so a median log ratio `m` is a threshold off by `e^m`):
///
/// - within the cells: the spread of the count-cell log ratios on the fit blocks (MAD
///   sigma, times 1.2533 for the median's efficiency, over sqrt(cells)), which takes the
///   cells as independent;
/// - between the fit blocks: the delete-one-block jackknife of the median log ratio
///   ([`crate::stats::jackknife`], scaled by `t(0.975, blocks - 1) / 1.96`), which sees
///   what the first cannot: a model that matches some stretches of the recording and not
///   others (an effect it lacks acting unevenly, the scene each block shows).
pub fn threshold_uncertainty(
    simulation: &Simulation,
    model: &Simulated,
) -> BTreeMap<String, Uncertain> {
    let ratios = cell_ratios(
        &simulation.real,
        &model.observed,
        simulation.geometry,
        Subset::Fit,
    );
    let between = between_blocks(simulation, model);
    let se = |pol: usize, c: f64| {
        let v: Vec<f64> = ratios
            .iter()
            .filter(|(_, r, i)| i % 2 == pol && *r >= 5)
            .map(|c| c.0)
            .collect();
        let within = (v.len() >= 3)
            .then(|| mad_sigma(&v))
            .flatten()
            .map(|s| 1.2533 * s / (v.len() as f64).sqrt());
        // the cells decide whether a threshold is measured at all (three at least); the
        // jackknife only widens
        within.map(|w| c * between[pol].map_or(w, |b| w.max(b)))
    };
    let p = &model.params;
    BTreeMap::from([
        (
            "ct_on".to_string(),
            Uncertain::positive(p.ct_on, se(1, p.ct_on)),
        ),
        (
            "ct_off".to_string(),
            Uncertain::positive(p.ct_off, se(0, p.ct_off)),
        ),
    ])
}

/// The delete-one-fit-block jackknife standard error of each polarity's median count-cell
/// log ratio (OFF, ON), each block sized by its real events; `None` under three fit blocks
/// or where a polarity has no median without some block.
fn between_blocks(simulation: &Simulation, model: &Simulated) -> [Option<f64>; 2] {
    let g = simulation.geometry;
    let blocks = g.blocks_of(Role::Fit);
    if blocks.len() < 3 {
        return [None, None];
    }
    let cells = |o: &Observed| -> Vec<Vec<u32>> {
        blocks
            .iter()
            .map(|&b| o.cells_of(g, Subset::Block(b)))
            .collect()
    };
    let (real, sim) = (cells(&simulation.real), cells(&model.observed));
    let without = |per_block: &[Vec<u32>], left_out: Option<usize>| -> Vec<u32> {
        let mut sum = vec![0u32; per_block[0].len()];
        for (k, block) in per_block.iter().enumerate() {
            if Some(k) != left_out {
                sum.iter_mut().zip(block).for_each(|(s, &c)| *s += c);
            }
        }
        sum
    };
    let medians = |left_out: Option<usize>| {
        median_ratios_of(&ratios_of_cells(
            &without(&real, left_out),
            &without(&sim, left_out),
        ))
    };
    let whole = medians(None);
    let left_out: Vec<[Option<f64>; 2]> = (0..blocks.len()).map(|k| medians(Some(k))).collect();
    let sizes: Vec<f64> = real
        .iter()
        .map(|b| b.iter().map(|&c| c as f64).sum::<f64>().max(1.0))
        .collect();
    let scale = t95_scale(blocks.len());
    [0, 1].map(|pol| {
        let whole = whole[pol]?;
        let values: Option<Vec<f64>> = left_out.iter().map(|m| m[pol]).collect();
        Some(weighted_jackknife_se(whole, &values?, &sizes) * scale)
    })
}

/// Says so when the ideal model already makes more isolated events than the recording: the
/// frames' own noise becomes events when they are simulated (read noise, and the 8-bit
/// quantisation, one DN being a large log step in the dark). Only the polarities whose
/// threshold the counts fix (`measured`: OFF, ON) are compared: a threshold left at its
/// search's start makes as many events as that value does, which says nothing about the
/// frames (coverage draw 13008: ON only measured, its OFF threshold left at 0.3 for a true
/// 0.6 made 11,060 OFF events where the recording has 2, which the note had blamed on the
/// frames' noise).
pub fn read_noise_note(
    simulation: &Simulation,
    ideal: &Simulated,
    measured: [bool; 2],
    assumptions: &mut Vec<String>,
) {
    if measured == [false, false] {
        return;
    }
    let g = simulation.geometry;
    // background counts alternate OFF, ON per intensity bin
    let sum = |v: Vec<u32>| {
        v.iter()
            .enumerate()
            .filter(|(i, _)| measured[i % 2])
            .map(|(_, &x)| x as f64)
            .sum::<f64>()
    };
    let r = sum(simulation.real.background_of(g, Subset::All));
    let s = sum(ideal.observed.background_of(g, Subset::All));
    if s > 1.2 * r && s - r > 5.0 * (r + s + 1.0).sqrt() {
        let which = match measured {
            [true, true] => "",
            [false, _] => " (ON events: the OFF threshold is not measured)",
            [true, false] => " (OFF events: the ON threshold is not measured)",
        };
        assumptions.push(format!(
            "the ideal model already makes {:.0} % more isolated events than the recording{which}: the frames' own noise (read noise, and quantisation in the dark) becomes events when they are simulated, so sensor noise below that level cannot be measured",
            100.0 * (s / r.max(1.0) - 1.0)
        ));
    }
}

/// What the loop produced, for the result.
pub struct Parts<'a> {
    pub before: super::super::metric::Components,
    pub residuals_before: Residuals,
    pub added: Vec<AddedEffect>,
    pub steps: Vec<Step>,
    pub ambiguities: Vec<super::Ambiguity>,
    pub assumptions: Vec<String>,
    pub fixed: bool,
    /// The starting thresholds as measured (the intervals widen where the fit disagrees).
    pub start: Option<super::agreement::Measured>,
    /// The start's event timing's thresholds, whether or not the start reported a value
    /// (the intervals widen where the fit disagrees with them too).
    pub timing: Option<super::agreement::Measured>,
    /// What the fit run told before any effect was tried (the threshold spread event
    /// timing measures, the timestamp grid, the shortest same-pixel interval).
    pub known: super::Known,
    /// The share of each threshold (ON, OFF) the start found the frames' interpolation to
    /// miss (the intervals reach up by it).
    pub interpolation_share: Option<[f64; 2]>,
    /// Where the start's frames' offset was not confirmed by both polarities, each
    /// threshold at the ends of the offset's range (down to no offset) over the value (the
    /// intervals reach them).
    pub offset_reach: Option<[[f64; 2]; 2]>,
    /// The log response not chosen, where the events cannot rule it out (the intervals
    /// reach the thresholds it gives).
    pub other_response: Option<crate::estimate::timing::OtherResponse>,
    /// The thresholds at coarser frame rates and a doubled exposure (their systematics
    /// join the intervals).
    pub frame_quality: super::frame_quality::FrameQuality,
    /// Whether the frames' times were aligned to the fit run's events (a lag common to
    /// every pixel is then taken up by the alignment).
    pub frames_aligned: bool,
    pub options: &'a FitOptions,
    pub input: &'a FitInput<'a>,
}

/// The result of the fit, in stages: the final model's error on the test blocks, the
/// thresholds' intervals, the noise intervals, hot pixels and the detections, then what the
/// data leave undetermined. Each stage appends its assumptions in this order.
pub fn result(simulation: &Simulation, mut state: State, mut parts: Parts) -> FitResult {
    let tested = Tested::of(simulation, &state);
    let written = intervals(simulation, &mut state, &mut parts);
    let judged = judged(simulation, &mut state, &mut parts, written.noise);
    let params = written.params;
    let identified = super::super::identified(&params, &judged.not_identified);
    FitResult {
        biases: None,
        why: judged.not_identified.clone(),
        not_detected: std::collections::BTreeMap::new(),
        identified,
        params: FittedParams {
            model: params,
            not_identified: judged.not_identified,
        },
        uncertainties: state.uncertainty,
        effects_added: parts.added,
        error_metric: ERROR_METRIC,
        error_before: parts.before.total,
        error_after: tested.after.total,
        components_before: parts.before,
        components_after: tested.after,
        steps: parts.steps,
        ambiguities: parts.ambiguities,
        hot_pixels_masked: state.hot,
        hot_pixel_detection: state.hot_detection,
        noise_detection: judged.noise_detection,
        bandwidth_detection: judged.bandwidth_detection,
        mismatch_detection: judged.mismatch_detection,
        residuals_before: Some(parts.residuals_before),
        residuals_after: Some(tested.residuals_after),
        events_only: None,
        assumptions: parts.assumptions,
        holdout: holdout(simulation, parts.options),
        simulations: simulation.count.get(),
        frame_exposure_us: exposure_of(parts.input.frames, parts.options.aps.exposure_us),
    }
}

/// The final model as the loop left it, measured before any interval is taken: its error
/// on the test blocks and its residuals on the fit blocks.
struct Tested {
    after: super::super::metric::Components,
    residuals_after: Residuals,
}

impl Tested {
    fn of(simulation: &Simulation, state: &State) -> Self {
        let g = simulation.geometry;
        Tested {
            after: simulation.distance(&state.model.observed, g.testing(), &state.kept),
            residuals_after: residuals(&simulation.real, &state.model.observed, g, Subset::Fit),
        }
    }
}

/// The parameters as written and the noise intervals, from [`intervals`].
struct Written {
    params: crate::sim::params::PixelParams,
    noise: NoiseIntervals,
}

/// The intervals, in order: the thresholds' (widened), the noise parameters', the hot
/// pixels' (which may change the parameters as written), then the method's spread
/// systematic; each appends its assumptions to the parts'.
fn intervals(simulation: &Simulation, state: &mut State, parts: &mut Parts) -> Written {
    let widening = Widening {
        fixed: parts.fixed,
        frame_quality: &parts.frame_quality,
        interpolation_share: parts.interpolation_share,
        offset_reach: parts.offset_reach,
        other_response: parts.other_response.as_ref(),
        start: parts.start.as_ref(),
        timing: parts.timing.as_ref(),
        ambiguities: &parts.ambiguities,
    };
    let assumptions = &mut parts.assumptions;
    assumptions.extend(threshold_intervals(simulation, state, widening));
    let noise = noise_intervals(simulation, state, parts.fixed, parts.known, assumptions);
    let mut params = params_to_write(state);
    if !state.hot.is_empty() {
        assumptions.push(super::hot_report::hot_pixels(
            simulation,
            state,
            parts.input,
            parts.known.mismatch,
            &mut params,
        ));
    } else {
        state.hot_detection = super::hot_report::search_reach(simulation, state);
    }
    // after the hot pixels, whose excess is counted across the profile's own interval
    assumptions.extend(super::method_systematic::widen_spread(
        &mut state.uncertainty,
    ));
    Written { params, noise }
}

/// What the final model is checked for and what the data leave undetermined, from
/// [`judged`].
struct Judged {
    noise_detection: Option<crate::fit::NoiseDetection>,
    bandwidth_detection: Option<crate::fit::BandwidthDetection>,
    mismatch_detection: Option<crate::fit::MismatchDetection>,
    not_identified: BTreeMap<String, String>,
}

/// The detections, the parameters the data do not identify, then the assumptions of the
/// blocks' split; each appends its assumptions to the parts'.
fn judged(
    simulation: &Simulation,
    state: &mut State,
    parts: &mut Parts,
    noise: NoiseIntervals,
) -> Judged {
    let Detections {
        noise: noise_detection,
        bandwidth: bandwidth_detection,
        mismatch: mismatch_detection,
    } = detections(
        simulation,
        state,
        &parts.steps,
        parts.known,
        parts.frames_aligned,
        &mut parts.assumptions,
    );
    let not_identified = undetermined(
        simulation,
        state,
        Undetermined {
            fixed: parts.fixed,
            steps: &parts.steps,
            measured_spread: parts.known.mismatch,
            spread_unresolved: parts.known.spread_unresolved,
            noise,
            leak_growth: parts.known.leak_drift.and_then(|d| d.growth),
        },
        &mut parts.ambiguities,
        &mut parts.assumptions,
    );
    parts
        .assumptions
        .extend(split_assumptions(simulation, parts.options));
    Judged {
        noise_detection,
        bandwidth_detection,
        mismatch_detection,
        not_identified,
    }
}

/// What widens the thresholds' intervals beyond their standard errors.
struct Widening<'a> {
    /// Thresholds held at given values (no standard errors, no method systematic).
    fixed: bool,
    frame_quality: &'a super::frame_quality::FrameQuality,
    interpolation_share: Option<[f64; 2]>,
    offset_reach: Option<[[f64; 2]; 2]>,
    other_response: Option<&'a crate::estimate::timing::OtherResponse>,
    start: Option<&'a super::agreement::Measured>,
    timing: Option<&'a super::agreement::Measured>,
    /// The look-alikes the data do not separate from a kept effect, with their thresholds.
    ambiguities: &'a [super::Ambiguity],
}

/// The thresholds' intervals: their standard errors on the fit blocks, widened by the
/// frames' quality checks, the interpolation the frames miss, the start's disagreement,
/// the look-alike models' thresholds and the method systematics (thresholds and cutoff);
/// returns the assumptions each adds.
fn threshold_intervals(
    simulation: &Simulation,
    state: &mut State,
    widening: Widening,
) -> Vec<String> {
    let mut assumptions = Vec::new();
    state
        .uncertainty
        .extend(threshold_uncertainty(simulation, &state.model));
    if !widening.fixed && simulation.geometry.blocks_of(Role::Fit).len() >= 3 {
        assumptions.push("the thresholds' standard errors are the larger of the count cells' spread on the fit blocks (cells taken as independent) and the delete-one-block jackknife of the median cell log ratio over the fit blocks (scaled by t(0.975, blocks - 1) / 1.96): a model that matches some stretches of the recording and not others widens them".into());
    }
    assumptions.extend(super::frame_quality::widen(
        &mut state.uncertainty,
        widening.frame_quality,
    ));
    if let Some(share) = widening.interpolation_share
        && let Some(note) = super::agreement::reach_for_interpolation(&mut state.uncertainty, share)
    {
        assumptions.push(note);
    }
    // (thresholds held at a start value are not fitted: nothing to reconcile)
    if let Some(start) = widening.start.filter(|_| !widening.fixed)
        && let Some(note) = super::agreement::reconcile(
            &mut state.uncertainty,
            start,
            ("start", "the start's thresholds"),
        )
    {
        assumptions.push(note);
    }
    if let Some(timing) = widening.timing.filter(|_| !widening.fixed)
        && let Some(note) = super::agreement::reconcile(
            &mut state.uncertainty,
            timing,
            (
                "event timing",
                if widening.start.is_some() {
                    "the start's event timing on its own (the log change between a pixel's consecutive events, read from the frames; the start's thresholds, with their interval, are not it alone)"
                } else {
                    "the start's event timing (the log change between a pixel's consecutive events, read from the frames; `estimate aps` on the fit run computed it but reported no thresholds)"
                },
            ),
        )
    {
        assumptions.push(note);
    }
    if !widening.fixed {
        assumptions.extend(reach_what_the_data_leave_open(state, &widening));
    }
    assumptions.extend(super::method_systematic::widen_cutoff(
        &mut state.uncertainty,
    ));
    assumptions
}

/// The fitted thresholds' intervals reaching what the data leave open: the look-alike
/// models' thresholds, the other log response's, an unconfirmed offset's ends, then the
/// method systematic; the assumptions each adds.
fn reach_what_the_data_leave_open(state: &mut State, widening: &Widening) -> Vec<String> {
    let uncertainty = &mut state.uncertainty;
    let mut assumptions: Vec<String> =
        super::look_alikes::widen(uncertainty, widening.ambiguities, &state.model.params)
            .into_iter()
            .collect();
    assumptions.extend(
        widening
            .other_response
            .and_then(|other| reach_for_other_response(uncertainty, other)),
    );
    assumptions.extend(
        widening
            .offset_reach
            .and_then(|reach| reach_for_unconfirmed_offset(uncertainty, reach)),
    );
    assumptions.extend(super::method_systematic::widen(uncertainty));
    assumptions
}

/// Each threshold's interval (ON, OFF) reaching every one of its ratios to the value that
/// is not 1, each on its own side; the intervals that changed, in words.
fn reach_thresholds(
    uncertainty: &mut BTreeMap<String, crate::fit::Uncertain>,
    ratios: [&[f64]; 2],
) -> Vec<String> {
    ["ct_on", "ct_off"]
        .into_iter()
        .zip(ratios)
        .filter_map(|(key, ratios)| {
            let ratios: Vec<f64> = ratios
                .iter()
                .copied()
                .filter(|r| r.is_finite() && *r > 0.0 && *r != 1.0)
                .collect();
            if ratios.is_empty() {
                return None;
            }
            super::method_systematic::reach_ln_each(uncertainty, key, &ratios)
        })
        .collect()
}

/// Widens each threshold's interval on the other log response's side, in ln C in
/// quadrature, so that it reaches the threshold that response gives
/// ([`crate::estimate::timing::response`]); returns the assumption that says so.
fn reach_for_other_response(
    uncertainty: &mut BTreeMap<String, crate::fit::Uncertain>,
    other: &crate::estimate::timing::OtherResponse,
) -> Option<String> {
    let [on, off] = other.threshold_ratios();
    let widened = reach_thresholds(uncertainty, [&[on], &[off]]);
    (!widened.is_empty()).then(|| {
        format!(
            "log response not determined: {} (b = {:.1} DN) explains the fit run's event timing within the pixels' noise of the response used (its scatter {:.2} times, 95 % {:.2} .. {:.2}); its thresholds, ON {on:.2} and OFF {off:.2} times the ones used, are in the intervals: {}",
            if other.response == "eps" { "a pure ln(DN + b)" } else { "v2e's lin-log" },
            other.offset_dn,
            other.score_ratio,
            other.score_ratio_ci95[0],
            other.score_ratio_ci95[1],
            widened.join("; ")
        )
    })
}

/// Widens each threshold's interval, in ln C in quadrature on each side, to reach the
/// thresholds the start's event timing read at the ends of the offset's range (down to no
/// offset, the frames as written), where one polarity gave no offset (`reach`: ON, OFF,
/// each the lower and the higher ratio to the value;
/// [`crate::estimate::aps::ApsResult::offset_reach`]): the fit simulates the frames at the
/// start's offset, which is then a compromise, not a measurement; returns the assumption
/// that says so.
fn reach_for_unconfirmed_offset(
    uncertainty: &mut BTreeMap<String, crate::fit::Uncertain>,
    reach: [[f64; 2]; 2],
) -> Option<String> {
    let widened = reach_thresholds(uncertainty, [&reach[0], &reach[1]]);
    (!widened.is_empty()).then(|| {
        let [[on_lo, on_hi], [off_lo, off_hi]] = reach;
        format!(
            "frames' log offset not confirmed: one polarity of the start's event timing gives no offset anywhere in its search (something else that depends on brightness moves its samples), so the offset the frames are simulated at is a compromise; the thresholds event timing reads at the ends of the offset's range, down to no offset (the frames as written), ON {on_lo:.2} .. {on_hi:.2} and OFF {off_lo:.2} .. {off_hi:.2} times the start's, are in the intervals: {}",
            widened.join("; ")
        )
    })
}

/// The noise parameters' intervals and what they leave undetermined.
struct NoiseIntervals {
    /// Parameters measured directly (by counting), kept out of the look-alikes' reach to 0.
    measured: &'static [&'static str],
    /// Thresholds the count effects' checks leave undetermined, with why.
    undetermined: Vec<(String, String)>,
}

/// Shot noise's interval from the quiet pixels' count, then the check that no count effect
/// (shot noise, leak, a slow photoreceptor, a refractory period) takes up the thresholds'
/// share of the events within its own interval ([`super::count_effects`]).
fn noise_intervals(
    simulation: &Simulation,
    state: &mut State,
    fixed: bool,
    known: super::Known,
    assumptions: &mut Vec<String>,
) -> NoiseIntervals {
    let counted = crate::fit::effects::quiet_noise::take_count_interval(
        &mut state.uncertainty,
        known.quiet_off,
        simulation.geometry,
        &state.model.params,
    );
    let measured: &'static [&'static str] = if counted.is_some() {
        &["shot_noise_rate_hz"]
    } else {
        &[]
    };
    assumptions.extend(counted);
    let mut undetermined = Vec::new();
    if !fixed {
        for check in super::count_effects::check(simulation, state) {
            assumptions.push(check.note);
            undetermined.extend(check.undetermined);
        }
    }
    NoiseIntervals {
        measured,
        undetermined,
    }
}

/// The final model's parameters as written (no seed; a pure ln(DN) response, offset 0, as
/// the smallest offset a PARAMS.toml takes: 1e-6 of white, < 3e-4 log units at DN 1; only
/// pixels at DN 0 differ).
fn params_to_write(state: &State) -> crate::sim::params::PixelParams {
    let mut params = state.model.params.clone();
    params.seed = None;
    if params.log_eps == Some(0.0) {
        params.log_eps = Some(1e-6);
    }
    params
}

/// What the final model is checked with for the effects it lacks.
struct Detections {
    noise: Option<crate::fit::NoiseDetection>,
    bandwidth: Option<crate::fit::BandwidthDetection>,
    mismatch: Option<crate::fit::MismatchDetection>,
}

/// The detections the final model is checked with: sensor noise below what the loop could
/// add, a photoreceptor cutoff the loop did not add (with its limit), and a threshold
/// spread it left out (what event timing allows, what the counts still call for).
fn detections(
    simulation: &Simulation,
    state: &State,
    steps: &[Step],
    known: super::Known,
    frames_aligned: bool,
    assumptions: &mut Vec<String>,
) -> Detections {
    let context = super::context_of(state, simulation, known);
    let noise = super::noise_detection::detect(simulation, state, steps, known);
    let bandwidth = super::bandwidth_detection::detect(
        simulation,
        &context,
        &state.masked,
        steps,
        frames_aligned,
    );
    let mismatch = super::mismatch_detection::detect(&context, steps, known.spread_unresolved);
    Detections {
        noise: noted(noise, assumptions),
        bandwidth: noted(bandwidth, assumptions),
        mismatch: noted(mismatch, assumptions),
    }
}

/// A detection, its assumption appended to `assumptions`.
fn noted<D>(found: Option<(D, String)>, assumptions: &mut Vec<String>) -> Option<D> {
    found.map(|(detection, note)| {
        assumptions.push(note);
        detection
    })
}

/// What decides which parameters are undetermined.
struct Undetermined<'a> {
    fixed: bool,
    steps: &'a [Step],
    /// The threshold spread event timing measured (value, interval), if it did.
    measured_spread: Option<(f64, [f64; 2])>,
    /// Event timing's interval of a spread it did not resolve.
    spread_unresolved: Option<[f64; 2]>,
    noise: NoiseIntervals,
    /// The leak's growth with the light the search held, if the timing measured one.
    leak_growth: Option<crate::fit::effects::leak::LeakGrowth>,
}

/// The parameters the data do not identify, with why: the model's unidentified settings,
/// leak the recording cannot measure, the count effects' checks', a spread unseen or measured but
/// not modelled; intervals reach 0 where a look-alike or an undetermined threshold leaves
/// a parameter free, and an undetermined threshold loses its interval.
fn undetermined(
    simulation: &Simulation,
    state: &mut State,
    from: Undetermined,
    ambiguities: &mut [super::Ambiguity],
    assumptions: &mut Vec<String>,
) -> BTreeMap<String, String> {
    let mut not_identified = not_identified(state, from.fixed);
    if let Some((note, unmeasured)) = super::leak_report::check(simulation, state, from.leak_growth)
    {
        assumptions.push(note);
        if let Some(why) = unmeasured {
            not_identified
                .entry("leak_rate_hz".into())
                .and_modify(|w| *w = format!("{w}; and {why}"))
                .or_insert(why);
            state.uncertainty.remove("leak_rate_hz");
        }
    }
    assumptions.extend(super::leak_report::growth(
        state,
        from.leak_growth,
        &mut not_identified,
    ));
    for (key, why) in from.noise.undetermined {
        not_identified.entry(key).or_insert(why);
    }
    let spread = state.model.params.ct_sigma;
    not_identified.extend(super::spread_report::unseen(
        spread,
        from.steps,
        from.spread_unresolved,
    ));
    if let Some((why, measured)) =
        super::spread_report::measured_not_modelled(spread, from.steps, from.measured_spread)
    {
        not_identified.insert("ct_sigma".into(), why);
        state.uncertainty.insert("ct_sigma".into(), measured);
    }
    assumptions.extend(super::hot_report::reach_zero_where_thresholds_undetermined(
        &mut state.uncertainty,
        &not_identified,
    ));
    assumptions.extend(super::alternatives::reach_zero_where_not_separated(
        &mut state.uncertainty,
        ambiguities,
        (&not_identified, from.noise.measured),
    ));
    for k in ["ct_on", "ct_off"] {
        if not_identified.contains_key(k) {
            state.uncertainty.remove(k);
        }
    }
    not_identified
}

/// The widest 95 % interval (hi / lo) a measured parameter may have: a standard error of
/// its logarithm of 1 (a factor e either side at one sigma, e^(2 x 1.96) = 50 across the
/// interval). Wider, the value is a model setting the data do not pin down.
pub const UNMEASURED_SPAN: f64 = 50.0;

/// Why a fitted value is not a measurement, where its 95 % interval says so: it spans more
/// than [`UNMEASURED_SPAN`], or it bounds the value on neither side (from 0, or open
/// below, to open above: no effect and as much as the search allowed both explain the
/// recording within chance, as for draw 6029's shot noise, [0, open] beside a value of
/// 1.86 Hz where the draw has none). An interval with one side bounded is a bound, kept.
pub(super) fn unmeasured(u: &Uncertain) -> Option<String> {
    match u.ci95? {
        [Some(lo), Some(hi)] if lo > 0.0 && hi / lo > UNMEASURED_SPAN => Some(format!(
            "its 95 % interval, {lo:.4e} to {hi:.4e}, spans more than a factor {UNMEASURED_SPAN:.0} (its standard error and the terms that widen it, each in `assumptions`): the recording does not pin it down, so it is not a measurement (the model keeps the value {:.4e})",
            u.value
        )),
        [lo, None] if lo.is_none_or(|lo| lo <= 0.0) => Some(format!(
            "its 95 % interval reaches 0 and is open above: the fit error changes by no more than chance from none of the effect to the end of its searched range, so the recording does not measure it (the model keeps the effect at {:.4e})",
            u.value
        )),
        _ => None,
    }
}

/// Parameters the data do not identify, and why.
fn not_identified(state: &State, fixed: bool) -> BTreeMap<String, String> {
    let mut why = BTreeMap::new();
    if fixed {
        for k in ["ct_on", "ct_off"] {
            why.insert(
                k.to_string(),
                "the recording does not show the thresholds (a static scene, or frames that explain almost none of its events): the model simulated them at a start value".to_string(),
            );
        }
    }
    if !fixed {
        for k in ["ct_on", "ct_off"] {
            if state
                .uncertainty
                .get(k)
                .is_none_or(|u| u.standard_error.is_none())
            {
                why.insert(
                    k.to_string(),
                    format!(
                        "the fit blocks have too few events of this polarity to fix {k} (fewer than 3 count cells with 5 events): the model kept the value its search started from, not a measurement"
                    ),
                );
            }
        }
    }
    for (key, u) in &state.uncertainty {
        if let Some(reason) = unmeasured(u) {
            why.entry(key.clone()).or_insert(reason);
        }
    }
    if !fixed {
        why.extend(thresholds_at_bound(&state.model.params));
    }
    for (key, bound) in &state.at_bound {
        why.insert(
            key.clone(),
            format!(
                "the search ended at the bound {bound:.6} of its range: the data ask for at least (or at most) this much, a bound rather than a measurement"
            ),
        );
    }
    // a static scene's effects are measured on noise alone, whatever the thresholds
    if !fixed {
        for (key, reason) in confounded_with_thresholds(&why, &state.uncertainty) {
            why.entry(key).or_insert(reason);
        }
    }
    if let Some(reason) = hot_rate_unmeasured(&why, &state.uncertainty) {
        why.insert(HOT_RATE.into(), reason);
    }
    why
}

/// Why each fitted count effect is not a measurement when a threshold of a moving scene is
/// not determined (`why` holds it): the effect was fitted against a threshold the data did
/// not fix, so it absorbed that threshold's error. On the coverage study's draws (seeds 1-100
/// and 1001-1080) 5 of the 6 such effect intervals missed the truth, draw 1007's cutoff by 44
/// half-widths (3.7 Hz for 74 Hz, fitted on 618 events with both thresholds at their start
/// values).
fn confounded_with_thresholds(
    why: &BTreeMap<String, String>,
    uncertainty: &BTreeMap<String, Uncertain>,
) -> Vec<(String, String)> {
    let undetermined: Vec<&str> = ["ct_on", "ct_off"]
        .into_iter()
        .filter(|k| why.contains_key(*k))
        .collect();
    if undetermined.is_empty() {
        return Vec::new();
    }
    super::count_effects::COUNT_EFFECTS
        .into_iter()
        .filter_map(Effect::parameter)
        .filter(|k| uncertainty.contains_key(*k))
        .map(|k| {
            (
                k.to_string(),
                format!(
                    "fitted against {} that the data do not determine (see its reason): this effect changes the event counts as a threshold does, so it took up the threshold's error and is not a measurement (the model keeps it at {:.4e})",
                    undetermined.join(" and "),
                    uncertainty[k].value
                ),
            )
        })
        .collect()
}

/// Why each threshold of `params` that its profile left at an end of [`THRESHOLD_RANGE`]
/// is a bound rather than a measurement.
fn thresholds_at_bound(params: &crate::sim::PixelParams) -> Vec<(String, String)> {
    [("ct_on", params.ct_on), ("ct_off", params.ct_off)]
        .into_iter()
        .filter_map(|(key, value)| {
            let bound = threshold_at_bound(value)?;
            Some((
                key.to_string(),
                format!(
                    "the threshold profile ended at the bound {bound} of its range ({} to {}): the model matches the recording's counts of this polarity at no threshold inside it (too {} events for any threshold: events the model lacks, or changes the frames show and the sensor did not see), so {value:.4} is a bound rather than a measurement",
                    THRESHOLD_RANGE.0,
                    THRESHOLD_RANGE.1,
                    if bound == THRESHOLD_RANGE.1 { "few" } else { "many" },
                ),
            ))
        })
        .collect()
}

/// The end of [`THRESHOLD_RANGE`] that `value` sits at, if any.
fn threshold_at_bound(value: f64) -> Option<f64> {
    let (lo, hi) = THRESHOLD_RANGE;
    if value >= hi * (1.0 - 1e-9) {
        Some(hi)
    } else if value <= lo * (1.0 + 1e-9) {
        Some(lo)
    } else {
        None
    }
}

pub(in crate::fit) const HOT_FRACTION: &str = "hot_pixel_fraction";
pub(in crate::fit) const HOT_RATE: &str = "hot_pixel_rate_hz";

/// Why the hot pixels' rate is not a measurement: no pixel is counted as hot (the fraction
/// is measured, the rate of none is not), or the count of hot pixels is not
/// determined (its interval spans more than [`UNMEASURED_SPAN`]) or reaches none: the named
/// pixels may then be none of them hot, and their rate is that of pixels a low threshold of
/// the scene can make as well (on the 38 hot-pixel coverage draws, 2 of the 5 fits that
/// named a single pixel named a scene pixel, at 6 and 8 times the true rate:
/// `benches/coverage/hot-lag-2026-11-29`).
pub(in crate::fit) fn hot_rate_unmeasured(
    why: &BTreeMap<String, String>,
    uncertainty: &BTreeMap<String, Uncertain>,
) -> Option<String> {
    let fraction = uncertainty.get(HOT_FRACTION)?;
    let Some(rate) = uncertainty.get(HOT_RATE) else {
        return Some(format!(
            "no named pixel is counted as hot beyond the model's own outliers (hot_pixel_fraction {}), so there is no hot pixels' rate to report",
            fraction.value
        ));
    };
    let reaches_none = matches!(fraction.ci95, Some([Some(lo), _]) if lo <= 0.0);
    if !why.contains_key(HOT_FRACTION) && !reaches_none {
        return None;
    }
    Some(format!(
        "the named pixels fire at {:.1} Hz, but the data do not determine whether any of them is hot (hot_pixel_fraction {}): a pixel with a low threshold under mismatch can fire as fast on the scene's changes, so this is not reported as the hot pixels' rate",
        rate.value,
        if reaches_none {
            "reaches 0 at its 95 % lower end"
        } else {
            "is not determined"
        }
    ))
}

fn split_assumptions(simulation: &Simulation, options: &FitOptions) -> Vec<String> {
    let g = simulation.geometry;
    let chance = if g.blocks_of(Role::Fit).len() >= 3 {
        format!(
            "an effect is kept when its error on the selection blocks falls by more than twice the chance spread of the per-block difference between the two models (measured on the fit blocks, over sqrt of the selection blocks), and by at least {:.0} % (parsimony floor)",
            100.0 * PARSIMONY
        )
    } else {
        format!(
            "under three fit blocks, chance cannot be measured: an effect is kept when its error on the selection blocks falls by {:.0} % (a fixed floor)",
            100.0 * UNMEASURED_CHANCE
        )
    };
    let mut out = vec![
        format!(
            "the frames simulated after upsampling along the optical flow (0.5 px steps); {} simulations, one seed ({}) for all",
            simulation.count.get(),
            options.seed
        ),
        format!(
            "time in {} blocks: fit {:.2} s (the first {:.0} % of the frames' span; the starting thresholds, the frames' alignment and offset and every search use it alone), selection {:.2} s (judges effects and refits), test {:.2} s (error_before and error_after only); {:.2} s of guard intervals between them unused; statistics over {} pixels",
            g.blocks,
            g.duration_of(Subset::Fit),
            100.0 * (1.0 - options.holdout),
            g.duration_of(Subset::Selection),
            g.duration_of(Subset::Test),
            g.guard_seconds,
            g.kept_pixels()
        ),
        chance,
    ];
    if g.judging() == Subset::Fit {
        out.push("the frames' span left no selection block (too few frame intervals): effects were judged on the fit blocks they were fitted on".into());
    }
    match g.testing() {
        Subset::Test => {}
        subset => out.push(format!(
            "the frames' span left no test block (too few frame intervals): error_before and error_after are measured on the {} blocks, which chose the model, not on unseen data",
            if subset == Subset::Selection { "selection" } else { "fit" }
        )),
    }
    out
}

fn holdout(simulation: &Simulation, options: &FitOptions) -> Holdout {
    let g = simulation.geometry;
    let selection = g.blocks_of(Role::Selection);
    let test = g.blocks_of(Role::Test);
    let mut held_out: Vec<usize> = selection.iter().chain(&test).copied().collect();
    held_out.sort_unstable();
    Holdout {
        fraction: options.holdout,
        blocks: g.blocks,
        held_out_blocks: held_out,
        selection_blocks: selection,
        test_blocks: test,
        fit_seconds: g.duration_of(Subset::Fit),
        held_out_seconds: g.duration_of(Subset::Selection) + g.duration_of(Subset::Test),
        selection_seconds: g.duration_of(Subset::Selection),
        test_seconds: g.duration_of(Subset::Test),
        guard_seconds: g.guard_seconds,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn uncertain(value: f64, lo: f64, hi: f64) -> Uncertain {
        Uncertain::with_interval(value, None, [Some(lo), Some(hi)])
    }

    /// A start like coverage draw 49's: ON 0.133 where event timing at the ends of the
    /// offset's range reads 0.5 and 5.9 times that (the draw's own: 0.56 and 5.68); the
    /// interval [0.089, 0.178] reaches 0.0665 and 0.785 in quadrature in ln C (ln 2 and
    /// ln 5.9 against the interval's own half-widths) and holds the true 0.711; OFF with no
    /// reach is unchanged.
    #[test]
    fn an_unconfirmed_offset_s_ends_are_reached() {
        let mut u = BTreeMap::from([
            ("ct_on".to_string(), uncertain(0.133, 0.089, 0.178)),
            ("ct_off".to_string(), uncertain(0.121, 0.077, 0.164)),
        ]);
        let note = reach_for_unconfirmed_offset(&mut u, [[0.5, 5.9], [1.0, 1.0]]).unwrap();
        let [Some(lo), Some(hi)] = u["ct_on"].ci95.unwrap() else {
            panic!("{:?}", u["ct_on"])
        };
        let lo_expected = 0.133 * (-(0.133f64 / 0.089).ln().hypot(2f64.ln())).exp();
        let hi_expected = 0.133 * (0.178f64 / 0.133).ln().hypot(5.9f64.ln()).exp();
        assert!((lo - lo_expected).abs() < 1e-12 && (hi - hi_expected).abs() < 1e-12);
        assert!(lo < 0.0665 * 1.01 && hi > 0.711, "[{lo}, {hi}]");
        assert_eq!(u["ct_off"].ci95, Some([Some(0.077), Some(0.164)]));
        assert!(
            note.contains("ON 0.50 .. 5.90 and OFF 1.00 .. 1.00"),
            "{note}"
        );
        assert!(
            note.ends_with(&format!("ct_on [0.0890, 0.1780] -> [{lo:.4}, {hi:.4}]")),
            "{note}"
        );
        // no reach, no note
        assert!(reach_for_unconfirmed_offset(&mut u, [[1.0; 2]; 2]).is_none());
    }

    /// A threshold the profile left at an end of its range (draw 1028 of the coverage study:
    /// OFF 4.999999999999999 for a true 0.50, reported with an interval [3.99, 6.26]) is a
    /// bound; one a hair inside is a value.
    #[test]
    fn a_threshold_at_the_end_of_the_profile_range_is_a_bound() {
        assert_eq!(threshold_at_bound(4.999999999999999), Some(5.0));
        assert_eq!(threshold_at_bound(0.02), Some(0.02));
        assert_eq!(threshold_at_bound(4.99), None);
        assert_eq!(threshold_at_bound(0.0201), None);
        assert_eq!(threshold_at_bound(0.35), None);
    }

    /// With a threshold not determined, the count effects fitted beside it are not either;
    /// hot pixels (their own pixels' excess) are; with both thresholds determined nothing is
    /// added.
    #[test]
    fn count_effects_fitted_against_an_undetermined_threshold_are_not_measurements() {
        let mut fitted = BTreeMap::new();
        fitted.insert("cutoff_hz".to_string(), uncertain(3.7, 2.5, 5.6));
        fitted.insert(
            "hot_pixel_fraction".to_string(),
            uncertain(1e-3, 5e-4, 2e-3),
        );
        let mut why = BTreeMap::new();
        assert!(confounded_with_thresholds(&why, &fitted).is_empty());
        why.insert("ct_off".to_string(), "too few events".to_string());
        let found = confounded_with_thresholds(&why, &fitted);
        assert_eq!(found.len(), 1);
        assert_eq!(found[0].0, "cutoff_hz");
        assert!(found[0].1.contains("ct_off") && found[0].1.contains("3.7000e0"));
    }

    /// An interval that bounds neither side, or spans more than a factor 50, is not a
    /// measurement; one bounded on one side is a bound, and a narrow one a value.
    #[test]
    fn a_value_whose_interval_bounds_neither_side_is_not_a_measurement() {
        let open = |lo: Option<f64>, hi: Option<f64>| {
            unmeasured(&Uncertain::with_interval(1.86, None, [lo, hi]))
        };
        assert!(
            open(Some(0.0), None)
                .unwrap()
                .contains("reaches 0 and is open above")
        );
        assert!(
            open(None, None)
                .unwrap()
                .contains("reaches 0 and is open above")
        );
        assert!(
            open(Some(0.01), Some(0.6))
                .unwrap()
                .contains("more than a factor 50")
        );
        assert_eq!(open(Some(0.0), Some(3.0)), None);
        assert_eq!(open(Some(0.5), None), None);
        assert_eq!(open(Some(1.2), Some(2.9)), None);
        assert_eq!(unmeasured(&Uncertain::positive(1.86, None)), None);
    }

    /// Draw 59's single named pixel (a fraction spanning a factor 200) and draw 94's five
    /// (a fraction reaching 0) leave the rate unmeasured; draw 62's 18 pixels do not; no
    /// pixel in excess of the model's outliers has no rate.
    #[test]
    fn the_rate_of_hot_pixels_is_measured_only_where_their_count_is() {
        let rate = uncertain(435.0, 337.0, 533.0);
        let single = BTreeMap::from([
            (HOT_FRACTION.to_string(), uncertain(3e-5, 7.5e-7, 1.6e-4)),
            (HOT_RATE.to_string(), rate.clone()),
        ]);
        let spans = BTreeMap::from([(HOT_FRACTION.to_string(), "spans".to_string())]);
        let why = hot_rate_unmeasured(&spans, &single).unwrap();
        assert!(
            why.contains("435.0 Hz") && why.contains("not determined"),
            "{why}"
        );
        let reaching_none = BTreeMap::from([
            (HOT_FRACTION.to_string(), uncertain(2.9e-4, 0.0, 1.1e-3)),
            (HOT_RATE.to_string(), rate.clone()),
        ]);
        let why = hot_rate_unmeasured(&BTreeMap::new(), &reaching_none).unwrap();
        assert!(why.contains("reaches 0"), "{why}");
        let many = BTreeMap::from([
            (HOT_FRACTION.to_string(), uncertain(4.6e-4, 2.8e-4, 7.3e-4)),
            (HOT_RATE.to_string(), uncertain(83.0, 67.0, 93.0)),
        ]);
        assert_eq!(hot_rate_unmeasured(&BTreeMap::new(), &many), None);
        assert_eq!(hot_rate_unmeasured(&spans, &BTreeMap::new()), None);
        // every named pixel within the model's own outliers: a fraction of 0, no rate
        let none_hot = BTreeMap::from([(HOT_FRACTION.to_string(), uncertain(0.0, 0.0, 1e-4))]);
        let why = hot_rate_unmeasured(&BTreeMap::new(), &none_hot).unwrap();
        assert!(why.contains("no hot pixels' rate"), "{why}");
    }
}
