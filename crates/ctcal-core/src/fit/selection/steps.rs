//! One step of the loop: an effect tried (its parameter searched with the thresholds on the
//! fit blocks, or hot pixels named and added as their own event trains) and judged on the
//! selection blocks ([`super::keep`]); an added effect refitted with all the others in
//! place; and the record of effects not called for.

use super::super::effects::leak::StillBalance;
use super::super::effects::{self, Effect, hot_pixels::HotTrain};
use super::super::observe::Subset;
use super::super::residuals::residuals;
use super::super::search::{Searched, Simulated, Simulation, search};
use super::super::{FitError, Step, StepResiduals, Uncertain};
use super::keep::{Verdict, by_signature, by_still_pixels, judge};
use super::{Known, LoopRun, State, judging_evidence, search_counted};
use crate::stats::hot_pixels::HotPixel;
use std::collections::BTreeMap;

pub(super) fn thresholds_of(model: &Simulated) -> BTreeMap<String, f64> {
    BTreeMap::from([
        ("ct_on".to_string(), model.params.ct_on),
        ("ct_off".to_string(), model.params.ct_off),
    ])
}

fn fit_residuals(simulation: &Simulation, model: &Simulated) -> StepResiduals {
    StepResiduals::from(&residuals(
        &simulation.real,
        &model.observed,
        simulation.geometry,
        Subset::Fit,
    ))
}

pub(super) fn record(step: &mut Step, verdict: Verdict) {
    step.error_before = Some(verdict.before.total);
    step.error_after = Some(verdict.after.total);
    step.components_after = Some(verdict.after);
    step.chance = verdict.chance;
    step.kept = verdict.kept;
    step.reason = verdict.reason;
}

/// Tries one effect and updates `state` if it is kept.
pub fn try_effect(
    simulation: &mut Simulation,
    state: &mut State,
    evidence: &effects::Evidence,
    hot_found: Option<(Vec<HotPixel>, Vec<HotTrain>)>,
    run: &LoopRun,
) -> Result<Step, FitError> {
    let effect = evidence.effect;
    let count_before = simulation.count.get();
    let mut step = Step::untried(effect.name().into(), evidence.text.clone(), evidence.score);
    step.residuals_before = Some(fit_residuals(simulation, &state.model));
    let searched = match effect {
        Effect::Display => {
            step.reason = "a display's parameters come from the stimulus that was played (the screen method); not added".into();
            return Ok(step);
        }
        Effect::HotPixels => {
            let found = hot_found.unwrap_or_default();
            return try_hot_pixels(simulation, state, step, found, count_before);
        }
        _ => search_effect(simulation, state, evidence, run, &mut step)?,
    };
    judge_searched(
        simulation,
        state,
        (step, count_before),
        effect,
        searched,
        run,
    )
}

/// Hot pixels tried: the pixels found hot on the fit blocks simulated as their own event
/// trains, kept where there are any (the selection error is reported).
fn try_hot_pixels(
    simulation: &mut Simulation,
    state: &mut State,
    mut step: Step,
    (hot, trains): (Vec<HotPixel>, Vec<HotTrain>),
    count_before: usize,
) -> Result<Step, FitError> {
    let previous = std::mem::take(&mut simulation.hot_events);
    simulation.hot_events =
        effects::hot_pixels::events(&trains, simulation.geometry.span, simulation.seed);
    let observed = simulation.observe(&state.model.params, &state.masked)?;
    step.parameters
        .insert("hot_pixels".into(), trains.len() as f64);
    step.parameters.insert(
        "hot_events_per_second".into(),
        trains.iter().map(|t| t.rate_hz).sum(),
    );
    let mut verdict = judge(simulation, &state.model.observed, &observed, &state.kept);
    // measured directly (a robust z-score on the fit blocks): kept whatever the
    // distance says, which a few pixels barely move; the selection error is reported
    verdict.kept = !trains.is_empty();
    verdict.reason = format!(
        "{} pixels hot on the fit blocks, simulated where they are at their own rates; {}",
        trains.len(),
        verdict.reason
    );
    if !verdict.kept {
        simulation.hot_events = previous;
    } else {
        state.hot = hot;
    }
    let model = Simulated {
        params: state.model.params.clone(),
        observed,
    };
    Ok(finish_step(
        simulation,
        state,
        step,
        verdict,
        model,
        None,
        count_before,
    ))
}

/// The effect's parameter searched with the thresholds (and, where the effect needs it,
/// the mismatch) on the fit blocks: the candidate model and the parameter's uncertainty,
/// the value recorded in `step`.
fn search_effect(
    simulation: &Simulation,
    state: &State,
    evidence: &effects::Evidence,
    run: &LoopRun,
    step: &mut Step,
) -> Result<(Simulated, Option<NamedUncertain>), FitError> {
    let effect = evidence.effect;
    let key = effect
        .parameter()
        .expect("every other effect has a parameter");
    let start = evidence.start.unwrap_or(1.0);
    let mut searched = search_from(simulation, state, effect, start, run)?;
    if let Some(other) = evidence.other_start {
        match search_from(simulation, state, effect, other, run) {
            Ok(from_other) => {
                step.evidence.push_str(&format!(
                    "; searched from {start:.4} (ended at {:.4}, fit error {:.4}) and from {other:.4} (ended at {:.4}, fit error {:.4}), the lower error kept",
                    searched.value, searched.fit_error, from_other.value, from_other.fit_error
                ));
                searched = better_of(searched, from_other);
            }
            Err(e) => step.evidence.push_str(&format!(
                "; the search from {other:.4} failed ({e}): the one from {start:.4} kept"
            )),
        }
    }
    record_searched(step, key, &searched);
    let uncertain = uncertain_of(key, &searched);
    Ok((searched.model, Some(uncertain)))
}

/// The searched value in `step`'s parameters under `key`, and a leak's growth with the
/// light beside it where the search held one (the search sets the dark part).
pub(super) fn record_searched(step: &mut Step, key: &str, searched: &Searched) {
    step.parameters.insert(key.into(), searched.value);
    if key == "leak_rate_hz"
        && let Some(g) = searched.model.params.leak_rate_hz_per_dn
    {
        step.parameters.insert("leak_rate_hz_per_dn".into(), g);
    }
}

/// The better of two searches of one parameter from different starts: the one with the
/// lower fit error, the other's evaluated points joined to it. Where the two ends' errors
/// lie within the rise chance gives (`1.96^2 noise`, [`profile_interval`]) the
/// curvature's standard error, one optimum's, is dropped, so that the interval is read
/// off the points of both and holds both ends.
///
/// [`profile_interval`]: crate::fit::search::profile_interval
pub(super) fn better_of(
    first: crate::fit::search::Searched,
    second: crate::fit::search::Searched,
) -> crate::fit::search::Searched {
    let (mut kept, other) = if second.fit_error < first.fit_error {
        (second, first)
    } else {
        (first, second)
    };
    let rise = crate::estimate::interval::z95().powi(2) * kept.noise.max(0.0);
    if other.fit_error - kept.fit_error <= rise {
        kept.standard_error = None;
    }
    kept.evaluations.extend(other.evaluations);
    kept
}

/// `effect`'s parameter searched over its range around `start` ([`search_range`]), with
/// the thresholds (and the mismatch where the effect needs it) on the fit blocks.
fn search_from(
    simulation: &Simulation,
    state: &State,
    effect: Effect,
    start: f64,
    run: &LoopRun,
) -> Result<crate::fit::search::Searched, FitError> {
    super::search_shaped(
        simulation,
        (&state.model.params, effect, effect.range(start)),
        state,
        run.known,
        (run.fixed, effect.searched_with_mismatch()),
        run.noise,
    )
}

/// A searched effect judged on the selection blocks and recorded (kept into `state` where
/// the verdict says so); a kept effect searched with the mismatch has the mismatch
/// searched once more ([`mismatch_searched_again`]).
fn judge_searched(
    simulation: &Simulation,
    state: &mut State,
    (step, count_before): (Step, usize),
    effect: Effect,
    (candidate, uncertain): (Simulated, Option<NamedUncertain>),
    run: &LoopRun,
) -> Result<Step, FitError> {
    let verdict = judge_effect(
        simulation,
        state,
        run.known,
        effect,
        (&state.model, &candidate),
    );
    let mismatch_before = state.model.params.ct_sigma;
    let mut step = finish_step(
        simulation,
        state,
        step,
        verdict,
        candidate,
        uncertain,
        count_before,
    );
    let mismatch_profiled = effect.searched_with_mismatch() && mismatch_before.is_some();
    if step.kept && mismatch_profiled && state.model.params.ct_sigma != mismatch_before {
        mismatch_searched_again(simulation, state, &mut step, mismatch_before, run)?;
    }
    Ok(step)
}

/// After an effect kept with the mismatch profiled in its search
/// ([`search_profiled`]): the mismatch searched once more around its profiled value
/// with the effect in place, for its standard error (the profile's few secant steps give
/// none), and its best value taken where it lowers the distance on the fit blocks. The
/// step records the mismatch it ended with.
fn mismatch_searched_again(
    simulation: &Simulation,
    state: &mut State,
    step: &mut Step,
    before: Option<f64>,
    run: &LoopRun,
) -> Result<(), FitError> {
    let Some(profiled) = state.model.params.ct_sigma else {
        return Ok(());
    };
    let count_before = simulation.count.get();
    let searched = search(
        simulation,
        &state.model.params,
        Effect::Mismatch,
        (profiled / 1.5, profiled * 1.5),
        &state.masked,
        &state.kept,
        run.fixed,
        run.noise,
    )?;
    let error = simulation
        .distance(&state.model.observed, Subset::Fit, &state.kept)
        .total;
    let (key, mut uncertain, bound) = uncertain_of("ct_sigma", &searched);
    if searched.fit_error < error {
        state.model = searched.model;
    } else {
        uncertain = Uncertain::positive(profiled, searched.standard_error);
    }
    let value = uncertain.value;
    state.set_uncertain(key, uncertain, bound);
    step.parameters.insert("ct_sigma".into(), value);
    step.simulations += simulation.count.get() - count_before;
    step.reason = format!(
        "{}; ct_sigma profiled with it: {} -> {value:.6}",
        step.reason,
        before.map_or("none".into(), |b| format!("{b:.6}"))
    );
    Ok(())
}

/// The judgement of `effect`'s model `with` against the model `without` it on the
/// judging blocks: by the distance ([`judge`]), for an effect the distance barely sees
/// also by its signature ([`by_signature`]), and a leak also at the still pixels
/// ([`by_still_pixels`]).
pub(super) fn judge_effect(
    simulation: &Simulation,
    state: &State,
    known: Known,
    effect: Effect,
    (without, with): (&Simulated, &Simulated),
) -> Verdict {
    let verdict = judge(simulation, &without.observed, &with.observed, &state.kept);
    if effect == Effect::Leak {
        let still = StillBalance::judged(
            &simulation.real,
            (&without.observed, &with.observed),
            simulation.geometry,
        );
        return by_still_pixels(verdict, &still);
    }
    if !effect.judged_by_signature() {
        return verdict;
    }
    let before = judging_evidence(state, simulation, known, effect, without);
    let after = judging_evidence(state, simulation, known, effect, with);
    by_signature(verdict, &before, &after)
}

/// The searched value with its standard error, or the bound it sits at.
/// A searched parameter's name, value with its uncertainty, and the bound it stopped at.
type NamedUncertain = (String, Uncertain, Option<f64>);

fn uncertain_of(key: &str, searched: &Searched) -> NamedUncertain {
    (key.to_string(), searched.uncertain(), searched.at_bound)
}

fn finish_step(
    simulation: &Simulation,
    state: &mut State,
    mut step: Step,
    verdict: Verdict,
    candidate: Simulated,
    uncertain: Option<(String, Uncertain, Option<f64>)>,
    count_before: usize,
) -> Step {
    step.parameters.extend(thresholds_of(&candidate));
    step.residuals_after = Some(fit_residuals(simulation, &candidate));
    step.simulations = simulation.count.get() - count_before;
    record(&mut step, verdict);
    if step.kept {
        state.model = candidate;
        if let Some((key, value, bound)) = uncertain {
            state.set_uncertain(key, value, bound);
        }
    }
    step
}

/// Fits `effect`'s parameter again with every other parameter as it now is; keeps the new
/// value if it wins on the selection blocks by more than chance.
pub fn refit(
    simulation: &Simulation,
    state: &mut State,
    effect: Effect,
    run: &LoopRun,
) -> Result<Step, FitError> {
    let key = effect.parameter().expect("a searched effect");
    let current = effect
        .value(&state.model.params)
        .expect("a kept effect has its parameter");
    let count_before = simulation.count.get();
    let searched = search_counted(
        simulation,
        (&state.model.params, effect, (current / 3.0, current * 3.0)),
        state,
        run.known,
        (run.fixed, run.noise),
    )?;
    let verdict = judge(
        simulation,
        &state.model.observed,
        &searched.model.observed,
        &state.kept,
    );
    let mut step = Step::untried(
        format!("{} (refit)", effect.name()),
        format!("{key} was {current:.6} when the effect was added"),
        0.0,
    );
    step.parameters = thresholds_of(&searched.model);
    record_searched(&mut step, key, &searched);
    step.simulations = simulation.count.get() - count_before;
    let value = searched.value;
    record(&mut step, verdict);
    step.reason = if step.kept {
        format!("{key} {current:.6} -> {value:.6}; {}", step.reason)
    } else {
        format!(
            "{key} stays {current:.6} (refit {value:.6}); {}",
            step.reason
        )
    };
    if step.kept {
        let (key, uncertain, bound) = uncertain_of(key, &searched);
        state.model = searched.model;
        state.set_uncertain(key, uncertain, bound);
    }
    Ok(step)
}

/// Tests whether a kept effect is still needed once the others are in (backward
/// elimination): the best model without it (thresholds profiled again, and each of the
/// `others`' parameters searched again, since an effect added early takes over part of what
/// a later one explains: threshold mismatch disperses counts as strong shot noise does, a
/// refractory period drops events as a slow photoreceptor does) against the model with it
/// on the selection blocks. The effect is removed when the model with it no longer wins by
/// more than chance. The step is `kept` when the effect stays.
pub fn prune(
    simulation: &Simulation,
    state: &mut State,
    effect: Effect,
    others: &[Effect],
    run: &LoopRun,
) -> Result<Step, FitError> {
    let key = effect.parameter().expect("a searched effect");
    let count_before = simulation.count.get();
    let mut reduced = state.model.params.clone();
    effect.clear(&mut reduced);
    let (without, refitted) = best_without(simulation, state, &reduced, others, run)?;
    let verdict = judge_effect(
        simulation,
        state,
        run.known,
        effect,
        (&without, &state.model),
    );
    let mut step = Step::untried(
        format!("{} (still needed?)", effect.name()),
        format!(
            "the model without {key} (thresholds profiled again{}) against the model with it",
            refitted
                .iter()
                .map(|(k, u, _)| format!(", {k} searched again: {:.6}", u.value))
                .collect::<String>()
        ),
        0.0,
    );
    step.parameters = thresholds_of(&without);
    step.parameters
        .extend(refitted.iter().map(|(k, u, _)| (k.clone(), u.value)));
    step.simulations = simulation.count.get() - count_before;
    let stays = verdict.kept;
    record(&mut step, verdict);
    step.reason = if stays {
        format!("stays: without it {}", step.reason)
    } else {
        format!(
            "removed: the others explain what it did; without it {}",
            step.reason
        )
    };
    if !stays {
        state.model = without;
        state.uncertainty.remove(key);
        state.at_bound.remove(key);
        for (key, uncertain, bound) in refitted {
            state.set_uncertain(key, uncertain, bound);
        }
    }
    Ok(step)
}

/// A parameter searched again: its key, value with standard error, and the range bound it
/// reached.
type Refitted = (String, Uncertain, Option<f64>);

/// The model `reduced` with its thresholds profiled and each of `others`' parameters
/// searched again (kept where the search lowers the error on the fit blocks), and the
/// parameters that moved.
fn best_without(
    simulation: &Simulation,
    state: &State,
    reduced: &crate::sim::PixelParams,
    others: &[Effect],
    run: &LoopRun,
) -> Result<(Simulated, Vec<Refitted>), FitError> {
    let (fixed, noise) = (run.fixed, run.noise);
    let mut best = simulation.profile(reduced, &state.masked, fixed)?;
    let mut error = simulation
        .distance(&best.observed, Subset::Fit, &state.kept)
        .total;
    let mut refitted = Vec::new();
    for &other in others {
        let (Some(key), Some(current)) = (other.parameter(), other.value(&best.params)) else {
            continue;
        };
        let searched = search_counted(
            simulation,
            (&best.params, other, other.range(current)),
            state,
            run.known,
            (fixed, noise),
        )?;
        if searched.fit_error < error {
            error = searched.fit_error;
            refitted.push(uncertain_of(key, &searched));
            best = searched.model;
        }
    }
    Ok((best, refitted))
}

/// The record of an effect the residuals did not call for.
pub fn untried(evidence: &effects::Evidence) -> Step {
    let mut step = Step::untried(
        evidence.effect.name().into(),
        evidence.text.clone(),
        evidence.score,
    );
    step.reason = if evidence.score >= effects::EVIDENCE_THRESHOLD && !evidence.relevant {
        "measurable but too small to matter".into()
    } else {
        "not called for by the residuals".into()
    };
    step
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::effects::fixture::{Fixture, chunk, static_frames};
    use crate::fit::search::{Evaluation, Searched};
    use crate::sim::params::PixelParams;

    /// A search that ended at `value` with `fit_error` (a curvature error of 0.1), its
    /// evaluated points `(value, fit error)`, the chance noise 0.01 (a rise of 0.0384).
    fn searched(value: f64, fit_error: f64, points: &[(f64, f64)]) -> Searched {
        let f = Fixture::new(
            &static_frames(4, 4, 1.0, 100.0),
            &chunk(Vec::new()),
            &chunk(Vec::new()),
        );
        Searched {
            value,
            model: Simulated {
                params: PixelParams::ideal(0.3, 0.3),
                observed: f.sim,
            },
            fit_error,
            standard_error: Some(0.1),
            at_bound: None,
            evaluations: points
                .iter()
                .map(|&(value, fit_error)| Evaluation {
                    value,
                    fit_error,
                    ct_on: 0.3,
                    ct_off: 0.3,
                })
                .collect(),
            noise: 0.01,
        }
    }

    /// The lower fit error wins, with both searches' points; where the two ends differ by
    /// less than the rise chance gives (1.96^2 x 0.01 = 0.0384), its curvature error is
    /// dropped and the interval read off the points holds both ends (0.5 .. 6.0, the
    /// nearest points beyond the rise on either side); where they differ by more, it is
    /// kept.
    #[test]
    fn the_better_search_keeps_both_searches_points_and_spans_both_ends_within_chance() {
        let first = searched(3.40, 0.354, &[(0.5, 0.9), (3.40, 0.354)]);
        let second = searched(4.01, 0.380, &[(4.01, 0.380), (6.0, 0.9)]);
        let kept = better_of(second, first);
        assert_eq!(kept.value, 3.40);
        assert_eq!(kept.standard_error, None);
        assert_eq!(kept.evaluations.len(), 4);
        let interval =
            crate::fit::search::profile_interval(&kept.evaluations, kept.value, kept.noise);
        assert_eq!(interval, [Some(0.5), Some(6.0)]);

        let first = searched(3.40, 0.354, &[(3.40, 0.354)]);
        let second = searched(4.01, 0.635, &[(4.01, 0.635)]);
        let kept = better_of(first, second);
        assert_eq!((kept.value, kept.standard_error), (3.40, Some(0.1)));
    }
}
