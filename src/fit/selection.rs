//! Model selection, the closed loop: from the ideal model with the estimated thresholds,
//! read every effect's evidence from the residuals of the current model, try the effect
//! with the strongest (its parameter searched with the thresholds), and keep it only if the
//! held-out distance falls by at least 2 % (and by more than 0.002); repeat until no
//! untried effect is called for. Every step is recorded: the effect, its evidence, the
//! held-out error before and after, kept or not and why.

use super::effects::{self, Context, Effect};
use super::metric::{ERROR_METRIC, cell_ratios};
use super::observe::{Geometry, Observed, Subset};
use super::residuals::residuals;
use super::search::{Simulated, Simulation, search};
use super::{
    AddedEffect, EffectChoice, FitError, FitInput, FitOptions, FitResult, Holdout, Step,
    StepResiduals, Uncertain,
};
use crate::estimate::aps::{self, ApsInput};
use crate::estimate::{Progress, dynamics, timestamp_grid};
use crate::sim::PixelParams;
use crate::stats::hot_pixels::HotPixel;
use std::cell::Cell;
use std::collections::BTreeMap;

/// A kept effect must lower the held-out distance by this fraction...
const MIN_RELATIVE_GAIN: f64 = 0.02;
/// ...and by at least this much.
const MIN_ABSOLUTE_GAIN: f64 = 0.002;

/// What is known besides the residuals: the estimators' mismatch (value, 95 % interval)
/// and the recording's timestamp grid.
#[derive(Clone, Copy)]
struct Known {
    mismatch: Option<(f64, [f64; 2])>,
    grid: Option<(i64, i64)>,
}

/// What trying an effect produced.
struct Candidate {
    model: Simulated,
    masked: Vec<bool>,
    kept: Vec<bool>,
    real: Observed,
    hot: Vec<HotPixel>,
    uncertain: Option<(String, Uncertain)>,
}

/// The fit's state between steps.
struct State {
    model: Simulated,
    /// Pixels masked (hot) and pixels compared.
    masked: Vec<bool>,
    kept: Vec<bool>,
    real: Observed,
    hot: Vec<HotPixel>,
    uncertainty: BTreeMap<String, Uncertain>,
}

fn sorted_thresholds(params: &PixelParams) -> BTreeMap<String, f64> {
    BTreeMap::from([
        ("ct_on".to_string(), params.ct_on),
        ("ct_off".to_string(), params.ct_off),
    ])
}

/// Standard errors of the thresholds from the spread of the count-cell log ratios.
fn threshold_errors(
    real: &Observed,
    sim: &Observed,
    g: &Geometry,
    params: &PixelParams,
) -> [Option<f64>; 2] {
    let ratios = cell_ratios(real, sim, g, Subset::Fit);
    [0, 1].map(|pol| {
        let mut v: Vec<f64> = ratios
            .iter()
            .filter(|(_, r, i)| i % 2 == pol && *r >= 5)
            .map(|c| c.0)
            .collect();
        if v.len() < 3 {
            return None;
        }
        let mid = v.len() / 2;
        let median = *v.select_nth_unstable_by(mid, f64::total_cmp).1;
        let mut deviations: Vec<f64> = v.iter().map(|x| (x - median).abs()).collect();
        let mad = *deviations.select_nth_unstable_by(mid, f64::total_cmp).1;
        let c = if pol == 1 {
            params.ct_on
        } else {
            params.ct_off
        };
        Some(c * 1.2533 * 1.4826 * mad / (v.len() as f64).sqrt())
    })
}

/// Fits the simulator to `input` (see the module docs of [`crate::fit`]).
pub fn fit(
    input: &FitInput,
    options: &FitOptions,
    progress: Progress,
) -> Result<FitResult, FitError> {
    if input.frames.len() < 2 {
        return Err(FitError::new(
            "`ctcal fit` simulates the recording from its grey frames; it has none",
            "fit a recording with APS frames (IJRR folder, event_utils/MVSEC HDF5, AEDAT4 with frames, ROS bag with images); for event-only recordings use `ctcal estimate eppps` and `ctcal stats` (background rate, hot pixels, intervals)",
        ));
    }
    let pixels = input.sensor.pixels();
    let mut assumptions = Vec::new();
    let mut steps = Vec::new();
    progress("frames: selection and optical flow", 0.0);
    let aps_input = ApsInput {
        sensor: input.sensor,
        events: input.events,
        frames: input.frames,
        excluded: input.excluded,
    };
    let prepared = aps::prepare(&aps_input, input.excluded, &options.aps)?;
    assumptions.extend(prepared.assumptions.iter().cloned());
    let frames = prepared.frames;
    let change_rate = dynamics::from_frames(&frames, 0.5).map_or(0.0, |d| d.log_change_rate);
    let static_scene = change_rate < dynamics::STATIC_CHANGE_RATE;

    // the starting thresholds
    let default = options.default_threshold;
    let mut fixed = static_scene;
    let mut mismatch_estimate = None;
    let start = if static_scene {
        steps.push(Step {
            effect: "thresholds".into(),
            evidence: format!("the frames change by {change_rate:.4} log units per pixel per second"),
            score: 0.0,
            parameters: BTreeMap::new(),
            error_before: None,
            error_after: None,
            components_after: None,
            kept: false,
            reason: format!(
                "a static scene does not show the thresholds: left at {default} (leak and shot-noise rates do not depend on them)"
            ),
            simulations: 0,
            residuals_before: None,
            residuals_after: None,
        });
        PixelParams::ideal(default, default)
    } else {
        progress("starting thresholds (estimate aps)", 0.05);
        let found = aps::estimate(&aps_input, &options.aps, &|_, _| {}).and_then(|found| {
            let e = found.estimate;
            match e.thresholds() {
                Some(t) => Ok((e, t)),
                None => Err(FitError::new(
                    format!(
                        "estimate aps determined no thresholds: {}",
                        e.why.values().cloned().collect::<Vec<_>>().join("; ")
                    ),
                    "",
                )),
            }
        });
        match found {
            Ok((e, (ct_on, ct_off))) => {
                mismatch_estimate = e.ct_sigma.zip(e.ct_sigma_ci95);
                let ci = |c: Option<crate::estimate::Interval>| {
                    let [lo, hi] = c.unwrap_or([None, None]);
                    let side = |v: Option<f64>| v.map_or("open".to_string(), |v| format!("{v:.4}"));
                    format!("[{}, {}]", side(lo), side(hi))
                };
                steps.push(Step {
                    effect: "thresholds".into(),
                    evidence: format!(
                        "estimate aps: ON {ct_on:.4} {}, OFF {ct_off:.4} {}",
                        ci(e.ct_on_ci95),
                        ci(e.ct_off_ci95)
                    ),
                    score: 0.0,
                    parameters: BTreeMap::from([
                        ("ct_on".to_string(), ct_on),
                        ("ct_off".to_string(), ct_off),
                    ]),
                    error_before: None,
                    error_after: None,
                    components_after: None,
                    kept: true,
                    reason: "the starting point; refitted with every effect".into(),
                    simulations: 0,
                    residuals_before: None,
                    residuals_after: None,
                });
                PixelParams::ideal(ct_on, ct_off)
            }
            Err(error) => {
                steps.push(Step {
                    effect: "thresholds".into(),
                    evidence: format!("estimate aps: {}", error.problem),
                    score: 0.0,
                    parameters: BTreeMap::new(),
                    error_before: None,
                    error_after: None,
                    components_after: None,
                    kept: false,
                    reason: format!("started from {default}; fitted to the counts"),
                    simulations: 0,
                    residuals_before: None,
                    residuals_after: None,
                });
                PixelParams::ideal(default, default)
            }
        }
    };
    let start = PixelParams {
        log_response: Some(options.aps.log_map.response()),
        log_eps: Some(options.aps.log_map.eps()),
        ..start
    };

    progress("the ideal model", 0.2);
    let geometry = Geometry::new(&frames, input.excluded, options.blocks, options.holdout);
    let runs = frames.upsample_runs(0.5, options.aps.max_upsampled_bytes);
    let grid = timestamp_grid(input.events);
    let no_mask = vec![false; pixels];
    let real = Observed::new(input.events, &geometry, &no_mask);
    let mut simulation = Simulation {
        runs: &runs,
        width: frames.width,
        height: frames.height,
        geometry: &geometry,
        events: input.events,
        real,
        grid,
        seed: options.seed,
        count: Cell::new(0),
    };
    let mut ideal = simulation.profile(&start, &no_mask, fixed)?;
    if !fixed
        && ideal.observed.total(&geometry, Subset::All) * 20
            < simulation.real.total(&geometry, Subset::All)
    {
        // the frames explain almost none of the events: the counts cannot fix thresholds
        fixed = true;
        ideal = simulation.profile(&start, &no_mask, true)?;
        assumptions.push(
            "the frames explain under 5 % of the events: thresholds kept where they started".into(),
        );
    }
    let kept: Vec<bool> = input.excluded.iter().map(|&e| !e).collect();
    let before = simulation.distance(&ideal.observed, Subset::HeldOut, &kept);
    let residuals_before = residuals(&simulation.real, &ideal.observed, &geometry, Subset::Fit);
    // how much the distance moves by chance: its spread over the fit blocks
    let noise = {
        let per_block: Vec<f64> = (0..geometry.blocks)
            .filter(|&b| !geometry.held_out[b])
            .map(|b| {
                simulation
                    .distance(&ideal.observed, Subset::Block(b), &kept)
                    .total
            })
            .collect();
        let n = per_block.len() as f64;
        let mean = per_block.iter().sum::<f64>() / n.max(1.0);
        if per_block.len() > 1 {
            (per_block.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
                / n.sqrt()
        } else {
            0.02 * mean
        }
    };
    // the frames' own noise becomes events when they are simulated: say so when the ideal
    // model already makes more isolated events than the recording
    {
        let (r, s) = (
            simulation.real.background_of(&geometry, Subset::All),
            ideal.observed.background_of(&geometry, Subset::All),
        );
        let (r, s): (f64, f64) = (
            r.iter().map(|&v| v as f64).sum(),
            s.iter().map(|&v| v as f64).sum(),
        );
        if s > 1.2 * r && s - r > 5.0 * (r + s + 1.0).sqrt() {
            assumptions.push(format!(
                "the ideal model already makes {:.0} % more isolated events than the recording: the frames' own noise (read noise) becomes events when they are simulated, so sensor noise below that level cannot be measured",
                100.0 * (s / r.max(1.0) - 1.0)
            ));
        }
    }
    let [se_off, se_on] =
        threshold_errors(&simulation.real, &ideal.observed, &geometry, &ideal.params);
    let mut uncertainty = BTreeMap::new();
    uncertainty.insert(
        "ct_on".into(),
        Uncertain {
            value: ideal.params.ct_on,
            standard_error: se_on,
        },
    );
    uncertainty.insert(
        "ct_off".into(),
        Uncertain {
            value: ideal.params.ct_off,
            standard_error: se_off,
        },
    );
    let mut state = State {
        model: ideal,
        masked: no_mask,
        kept,
        real: simulation.real.clone(),
        hot: Vec::new(),
        uncertainty,
    };

    // the loop
    let known = Known {
        mismatch: mismatch_estimate,
        grid,
    };
    let mut added: Vec<AddedEffect> = Vec::new();
    let mut tried: Vec<Effect> = Vec::new();
    let planned: Vec<Effect> = match &options.effects {
        EffectChoice::Auto => Effect::ALL.to_vec(),
        EffectChoice::None => Vec::new(),
        EffectChoice::List(list) => list.clone(),
    };
    let forced = matches!(options.effects, EffectChoice::List(_));
    for round in 0..planned.len() {
        progress(
            &format!("effects: round {} of at most {}", round + 1, planned.len()),
            0.25 + 0.7 * round as f64 / planned.len().max(1) as f64,
        );
        let context = context_of(&state, &geometry, known);
        let candidates: Vec<effects::Evidence> = planned
            .iter()
            .filter(|e| !tried.contains(e))
            .map(|&e| effects::evidence(e, &context))
            .collect();
        let next = if forced {
            candidates.into_iter().next()
        } else {
            // effects measured directly come first: hot pixels (masked, not simulated) and
            // the mismatch event timing measures; then the strongest residual signature
            let called: Vec<effects::Evidence> =
                candidates.into_iter().filter(|e| e.calls_for()).collect();
            let direct = [Effect::HotPixels, Effect::Mismatch]
                .into_iter()
                .find_map(|d| called.iter().find(|e| e.effect == d).cloned());
            direct.or_else(|| {
                called
                    .into_iter()
                    .max_by(|a, b| a.score.total_cmp(&b.score))
            })
        };
        let Some(evidence) = next else { break };
        tried.push(evidence.effect);
        let step = try_effect(&mut simulation, &mut state, &evidence, known, fixed, noise)?;
        if step.kept {
            added.push(AddedEffect {
                effect: evidence.effect,
                evidence: evidence.text.clone(),
                error_after: step.error_after.unwrap_or(f64::NAN),
            });
        }
        steps.push(step);
    }
    // effects added early were fitted without the later ones (mismatch before the noise
    // it partly stood in for): each searched parameter is fitted once more with all the
    // others in place, and the new value kept if the held-out error falls
    let searched: Vec<Effect> = added
        .iter()
        .map(|a| a.effect)
        .filter(|e| e.parameter().is_some())
        .collect();
    if searched.len() > 1 {
        progress("refitting the effects together", 0.9);
        for effect in searched {
            let step = refit(&simulation, &mut state, effect, fixed, noise)?;
            if step.kept
                && let Some(entry) = added.iter_mut().find(|a| a.effect == effect)
            {
                entry.error_after = step.error_after.unwrap_or(entry.error_after);
            }
            steps.push(step);
        }
    }
    // effects not called for, for the record
    if !forced {
        let context = context_of(&state, &geometry, known);
        for &effect in planned.iter().filter(|e| !tried.contains(e)) {
            let evidence = effects::evidence(effect, &context);
            steps.push(Step {
                effect: effect.name().into(),
                evidence: evidence.text.clone(),
                score: evidence.score,
                parameters: BTreeMap::new(),
                error_before: None,
                error_after: None,
                components_after: None,
                kept: false,
                reason: if evidence.score >= effects::EVIDENCE_THRESHOLD && !evidence.relevant {
                    "measurable but too small to matter".into()
                } else {
                    "not called for by the residuals".into()
                },
                simulations: 0,
                residuals_before: None,
                residuals_after: None,
            });
        }
    }

    progress("residuals of the final model", 0.97);
    let after = distance_of(&simulation, &state);
    let residuals_after = residuals(&state.real, &state.model.observed, &geometry, Subset::Fit);
    let [se_off, se_on] = threshold_errors(
        &state.real,
        &state.model.observed,
        &geometry,
        &state.model.params,
    );
    state.uncertainty.insert(
        "ct_on".into(),
        Uncertain {
            value: state.model.params.ct_on,
            standard_error: se_on,
        },
    );
    state.uncertainty.insert(
        "ct_off".into(),
        Uncertain {
            value: state.model.params.ct_off,
            standard_error: se_off,
        },
    );
    let mut params = state.model.params.clone();
    params.seed = None;
    if !state.hot.is_empty() {
        let kept_pixels = input.excluded.iter().filter(|&&e| !e).count().max(1);
        let mut rates: Vec<f64> = state.hot.iter().map(|h| h.rate_hz).collect();
        rates.sort_by(f64::total_cmp);
        params.hot_pixel_fraction = Some(state.hot.len() as f64 / kept_pixels as f64);
        params.hot_pixel_rate_hz = Some(rates[rates.len() / 2]);
    }
    if fixed {
        state.uncertainty.remove("ct_on");
        state.uncertainty.remove("ct_off");
    }
    assumptions.push(format!(
        "the frames simulated after upsampling along the optical flow (0.5 px steps); {} simulations, one seed ({}) for all",
        simulation.count.get(),
        options.seed
    ));
    assumptions.push(format!(
        "time cut into {} blocks, {} held out ({:.2} s of {:.2} s); statistics over {} pixels",
        geometry.blocks,
        geometry.held_out.iter().filter(|&&h| h).count(),
        geometry.duration_of(Subset::HeldOut),
        geometry.duration_of(Subset::All),
        geometry.kept_pixels()
    ));
    progress("done", 1.0);
    let not_identified: BTreeMap<String, String> = if fixed {
        ["ct_on", "ct_off"]
            .into_iter()
            .map(|k| {
                (
                    k.to_string(),
                    "the recording does not show the thresholds (a static scene, or frames that explain almost none of its events): the model simulated them at a start value".to_string(),
                )
            })
            .collect()
    } else {
        BTreeMap::new()
    };
    // every parameter the model sets (PARAMS.toml keys)
    let identified = serde_json::to_value(&params)
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
    Ok(FitResult {
        why: not_identified.clone(),
        identified,
        params: super::FittedParams {
            model: params,
            not_identified,
        },
        uncertainties: state.uncertainty,
        effects_added: added,
        error_metric: ERROR_METRIC,
        error_before: before.total,
        error_after: after.total,
        components_before: before,
        components_after: after,
        steps,
        hot_pixels_masked: state.hot,
        residuals_before,
        residuals_after,
        assumptions,
        holdout: Holdout {
            fraction: options.holdout,
            blocks: geometry.blocks,
            held_out_blocks: (0..geometry.blocks)
                .filter(|&b| geometry.held_out[b])
                .collect(),
            fit_seconds: geometry.duration_of(Subset::Fit),
            held_out_seconds: geometry.duration_of(Subset::HeldOut),
        },
        simulations: simulation.count.get(),
        frame_exposure_us: input
            .frames
            .iter()
            .find_map(|f| f.exposure_us)
            .or(options.aps.exposure_us),
    })
}

/// The held-out distance of the current model.
fn distance_of(simulation: &Simulation, state: &State) -> super::metric::Components {
    super::metric::distance(
        &state.real,
        &state.model.observed,
        simulation.geometry,
        Subset::HeldOut,
        &state.kept,
    )
}

/// The evidence context of the current state.
fn context_of<'a>(state: &'a State, geometry: &'a Geometry, known: Known) -> Context<'a> {
    Context {
        real: &state.real,
        sim: &state.model.observed,
        geometry,
        kept: &state.kept,
        model: &state.model.params,
        mismatch_estimate: known.mismatch,
        timestamp_grid_us: known.grid.map(|g| g.0),
        subset: Subset::Fit,
    }
}

/// Tries one effect: fits it, compares held-out errors, and updates `state` if kept.
fn try_effect(
    simulation: &mut Simulation,
    state: &mut State,
    evidence: &effects::Evidence,
    known: Known,
    fixed: bool,
    noise: f64,
) -> Result<Step, FitError> {
    let effect = evidence.effect;
    let count_before = simulation.count.get();
    let before = distance_of(simulation, state);
    let residuals_before = StepResiduals::from(&residuals(
        &state.real,
        &state.model.observed,
        simulation.geometry,
        Subset::Fit,
    ));
    let mut step = Step {
        effect: effect.name().into(),
        evidence: evidence.text.clone(),
        score: evidence.score,
        parameters: BTreeMap::new(),
        error_before: Some(before.total),
        error_after: None,
        components_after: None,
        kept: false,
        reason: String::new(),
        simulations: 0,
        residuals_before: Some(residuals_before),
        residuals_after: None,
    };
    // what the effect changes: the model (and its uncertainty), the mask
    let candidate = match effect {
        Effect::Display => {
            let context = context_of(state, simulation.geometry, known);
            step.reason = match effects::display::line(&context) {
                Some((frequency, _, _)) => format!(
                    "a display (or flickering light) at {frequency:.1} Hz is fitted from the stimulus that was played: run `ctcal estimate screen` with it; not added"
                ),
                None => "no spectral line".into(),
            };
            return Ok(step);
        }
        Effect::HotPixels => {
            let hot = effects::hot_pixels::find(&context_of(state, simulation.geometry, known));
            let mut masked = state.masked.clone();
            let mut kept = state.kept.clone();
            let width = simulation.geometry.sensor.width as usize;
            for h in &hot {
                let p = h.y as usize * width + h.x as usize;
                masked[p] = true;
                kept[p] = false;
            }
            let real = simulation.observe_real(&masked);
            let previous = std::mem::replace(&mut simulation.real, real.clone());
            let model = simulation.profile(&state.model.params, &masked, fixed);
            let model = match model {
                Ok(m) => m,
                Err(e) => {
                    simulation.real = previous;
                    return Err(e);
                }
            };
            step.parameters
                .insert("hot_pixels".into(), hot.len() as f64);
            Candidate {
                model,
                masked,
                kept,
                real,
                hot,
                uncertain: None,
            }
        }
        _ => {
            let Some(key) = effect.parameter() else {
                unreachable!("every other effect has a parameter");
            };
            let start = evidence.start.unwrap_or(1.0);
            let searched = search(
                simulation,
                &state.model.params,
                effect,
                effect.range(start),
                &state.masked,
                &state.kept,
                fixed,
                noise,
            )?;
            step.parameters.insert(key.into(), searched.value);
            let uncertain = Uncertain {
                value: searched.value,
                standard_error: searched.standard_error,
            };
            Candidate {
                model: searched.model,
                masked: state.masked.clone(),
                kept: state.kept.clone(),
                real: state.real.clone(),
                hot: Vec::new(),
                uncertain: Some((key.to_string(), uncertain)),
            }
        }
    };
    step.parameters
        .extend(sorted_thresholds(&candidate.model.params));
    let after = super::metric::distance(
        &candidate.real,
        &candidate.model.observed,
        simulation.geometry,
        Subset::HeldOut,
        &candidate.kept,
    );
    step.error_after = Some(after.total);
    step.components_after = Some(after.clone());
    step.residuals_after = Some(StepResiduals::from(&residuals(
        &candidate.real,
        &candidate.model.observed,
        simulation.geometry,
        Subset::Fit,
    )));
    step.simulations = simulation.count.get() - count_before;
    let gain = before.total - after.total;
    step.kept = gain > MIN_RELATIVE_GAIN * before.total && gain > MIN_ABSOLUTE_GAIN;
    step.reason = if step.kept {
        format!(
            "held-out error {:.4} -> {:.4} ({:+.1} %)",
            before.total,
            after.total,
            -100.0 * gain / before.total
        )
    } else {
        format!(
            "held-out error {:.4} -> {:.4}: not enough better (needs -{:.0} %)",
            before.total,
            after.total,
            100.0 * MIN_RELATIVE_GAIN
        )
    };
    if step.kept {
        state.model = candidate.model;
        state.masked = candidate.masked;
        state.kept = candidate.kept;
        state.real = candidate.real;
        state.hot.extend(candidate.hot);
        if let Some((key, value)) = candidate.uncertain {
            state.uncertainty.insert(key, value);
        }
    } else if effect == Effect::HotPixels {
        simulation.real = state.real.clone();
    }
    Ok(step)
}

/// Fits `effect`'s parameter again with every other parameter as it now is; keeps the new
/// value if the held-out error falls.
fn refit(
    simulation: &Simulation,
    state: &mut State,
    effect: Effect,
    fixed: bool,
    noise: f64,
) -> Result<Step, FitError> {
    let key = effect.parameter().expect("a searched effect");
    let current = match effect {
        Effect::Mismatch => state.model.params.ct_sigma,
        Effect::Refractory => state.model.params.refractory_s,
        Effect::Bandwidth => state.model.params.cutoff_hz,
        Effect::Leak => state.model.params.leak_rate_hz,
        Effect::ShotNoise => state.model.params.shot_noise_rate_hz,
        Effect::TimestampJitter => state.model.params.timestamp_jitter_s,
        Effect::HotPixels | Effect::Display => None,
    }
    .expect("a kept effect has its parameter");
    let count_before = simulation.count.get();
    let before = distance_of(simulation, state);
    let searched = search(
        simulation,
        &state.model.params,
        effect,
        (current / 3.0, current * 3.0),
        &state.masked,
        &state.kept,
        fixed,
        noise,
    )?;
    let after = simulation.distance(&searched.model.observed, Subset::HeldOut, &state.kept);
    let kept = after.total < before.total;
    let mut parameters = sorted_thresholds(&searched.model.params);
    parameters.insert(key.into(), searched.value);
    let step = Step {
        effect: format!("{} (refit)", effect.name()),
        evidence: format!("{key} was {current:.6} when the effect was added"),
        score: 0.0,
        parameters,
        error_before: Some(before.total),
        error_after: Some(after.total),
        components_after: Some(after.clone()),
        kept,
        reason: if kept {
            format!(
                "{key} {current:.6} -> {:.6}; held-out error {:.4} -> {:.4}",
                searched.value, before.total, after.total
            )
        } else {
            format!(
                "{key} stays {current:.6}: the refit ({:.6}) does not lower the held-out error ({:.4} -> {:.4})",
                searched.value, before.total, after.total
            )
        },
        simulations: simulation.count.get() - count_before,
        residuals_before: None,
        residuals_after: None,
    };
    if kept {
        state.model = searched.model;
        state.uncertainty.insert(
            key.into(),
            Uncertain {
                value: searched.value,
                standard_error: searched.standard_error,
            },
        );
    }
    Ok(step)
}
