//! Model selection, the closed loop, in stages:
//!
//! 1. the split ([`start`]): time in blocks, the first `1 - holdout` of the frames' span
//!    fits, the rest is held out as two contiguous runs with a guard interval at each change:
//!    selection (judges every effect and refit) then test (measures the final error once);
//! 2. the start: `estimate aps` on the fit run alone, the frames prepared from its events
//!    (frames whose motion outruns the optical flow are not re-simulated: the events alone
//!    are fitted, [`super::events_only`]);
//! 3. the loop: from the ideal model, every effect's evidence read from the fit blocks'
//!    residuals; the strongest tried (its parameter searched with the thresholds on the fit
//!    blocks) and kept only if the selection error falls by more than chance ([`keep`]);
//!    a refractory period is searched with the mismatch profiled beside the thresholds,
//!    since it narrows the spread of counts that mismatch widens
//!    ([`super::search::search_profiled`]);
//! 4. each searched parameter refitted with all the others in place ([`steps::refit`]),
//!    then each tested for whether it is still needed, the others searched again
//!    ([`steps::prune`]);
//! 5. each kept effect against its look-alikes ([`alternatives`]): replaced where one wins,
//!    named beside it where the data do not separate them;
//! 6. the error before (ideal model) and after (final model) on the test blocks, which
//!    neither fitted nor chose anything.
//!
//! Every step is recorded: the effect, its evidence, the selection error before and after,
//! the chance level it had to beat, kept or not and why.

mod agreement;
mod alternatives;
mod bandwidth_detection;
mod count_effects;
pub use alternatives::Ambiguity;
pub(in crate::fit) mod finish;
mod frame_quality;
pub(in crate::fit) mod hot_excess;
mod hot_report;
pub(in crate::fit) mod keep;
mod leak_report;
mod look_alikes;
mod method_systematic;
mod mismatch_detection;
mod noise_detection;
mod spread_report;
mod start;
mod steps;

use super::effects::{self, Context, Effect, hot_pixels::HotTrain};
use super::observe::{Geometry, Subset};
use super::residuals::residuals;
use super::search::{Simulated, Simulation};
use super::{
    AddedEffect, EffectChoice, FitError, FitInput, FitOptions, FitResult, Step, Uncertain,
};
use crate::estimate::aps::{self, ApsInput};
use crate::estimate::frames::PreparedFrames;
use crate::estimate::{Progress, dynamics, timestamp_grid};
use crate::events::{EventChunk, TimeUs};
use crate::sim::PixelParams;
use crate::stats::hot_pixels::HotPixel;
use std::cell::Cell;
use std::collections::BTreeMap;

/// What is known besides the residuals: the estimators' mismatch (value, 95 % interval),
/// the recording's timestamp grid and its shortest same-pixel intervals on the fit run.
#[derive(Clone, Copy)]
pub(super) struct Known {
    mismatch: Option<(f64, [f64; 2])>,
    /// The 95 % interval of the spread where the estimators' event timing resolved none.
    spread_unresolved: Option<[f64; 2]>,
    grid: Option<(i64, i64)>,
    shortest_interval_s: Option<f64>,
    /// The OFF isolated-event rate at quiet pixels of the fit run.
    quiet_off: Option<super::events_only::QuietOff>,
    /// The same on the judging blocks' events, for shot noise's signature there.
    quiet_off_judging: Option<super::events_only::QuietOff>,
    /// The leak drift the starting estimate's event timing measured.
    leak_drift: Option<effects::leak::TimingDrift>,
}

/// The fit's state between steps.
pub(super) struct State {
    model: Simulated,
    /// Pixels masked from the statistics besides the user's (none today), and compared.
    masked: Vec<bool>,
    kept: Vec<bool>,
    /// Hot pixels named (and simulated as their own event trains).
    hot: Vec<HotPixel>,
    /// Which hot pixels the hot-pixel search sees (set with the fraction).
    hot_detection: Option<super::HotPixelDetection>,
    uncertainty: BTreeMap<String, Uncertain>,
    /// Parameters whose search ended at a bound of its range, and the bound.
    at_bound: BTreeMap<String, f64>,
}

impl State {
    fn set_uncertain(&mut self, key: String, value: Uncertain, bound: Option<f64>) {
        match bound {
            Some(b) => self.at_bound.insert(key.clone(), b),
            None => self.at_bound.remove(&key),
        };
        self.uncertainty.insert(key, value);
    }
}

/// Refuses a fit whose kept pixels (the region, less the mask) hold fewer events than
/// [`super::events_only::MIN_EVENTS`]: too few for any count cell to fix a threshold, so
/// every number would be the search's start (a one-pixel region of slider_depth held 14).
fn check_events(input: &FitInput) -> Result<(), FitError> {
    let w = input.sensor.width as usize;
    let events = input.events;
    let kept = (0..events.len())
        .filter(|&i| !input.excluded[events.y[i] as usize * w + events.x[i] as usize])
        .count();
    let least = super::events_only::MIN_EVENTS;
    if kept < least {
        return Err(FitError::new(
            format!(
                "{kept} events at the pixels fitted: too few to fit thresholds and effects (a fit needs {least})"
            ),
            "fit a larger region or a longer part of the recording",
        ));
    }
    Ok(())
}

/// Fits the simulator to `input` (see the module docs of [`crate::fit`]), and says of each
/// effect the final model lacks why it is off ([`super::not_detected`]).
pub fn fit(
    input: &FitInput,
    options: &FitOptions,
    progress: Progress,
) -> Result<FitResult, FitError> {
    let mut result = fit_as_the_data_allow(input, options, progress)?;
    let refractory_unexplained = result.params.refractory_s.is_none()
        && !result.why.contains_key("refractory_s")
        && result.events_only.is_none();
    let edge = refractory_unexplained
        .then(|| fit_run_interval_edge(input, options, &result.hot_pixels_masked))
        .flatten();
    result.not_detected = super::not_detected::of(&result, edge.as_ref());
    Ok(result)
}

/// The lower edge of the fit run's same-pixel intervals at the kept pixels, the named hot
/// pixels left out: whether the fit run shows the edge a refractory period leaves, which
/// the fit with frames did not add (a fit without frames measures it itself).
fn fit_run_interval_edge(
    input: &FitInput,
    options: &FitOptions,
    hot: &[crate::stats::hot_pixels::HotPixel],
) -> Option<super::events_only::refractory::Edge> {
    let end = start::fit_end(input.frames, options.holdout);
    let first = input.frames.first().map_or(TimeUs::MIN, |f| f.t);
    let events = input.events.between(first, end);
    let width = input.sensor.width as usize;
    let mut kept: Vec<bool> = input.excluded.iter().map(|&e| !e).collect();
    for h in hot.iter().filter(|h| (h.x as usize) < width) {
        if let Some(k) = kept.get_mut(h.y as usize * width + h.x as usize) {
            *k = false;
        }
    }
    let step = super::events_only::refractory::timestamp_step(&events);
    effects::refractory::interval_edge(&events, width, &kept, step)
}

/// The fit with frames where they can be followed, else from the events alone.
fn fit_as_the_data_allow(
    input: &FitInput,
    options: &FitOptions,
    progress: Progress,
) -> Result<FitResult, FitError> {
    options.check()?;
    check_events(input)?;
    if input.frames.len() < 2 {
        return super::events_only::fit(input, options, progress);
    }
    progress("frames: selection and optical flow", 0.0);
    let end = start::fit_end(input.frames, options.holdout);
    let run = start::FitRun::new(input, end);
    match prepare_frames(input, &run, options)? {
        Ok(prepared) => fit_with_frames(input, options, progress, (&run, end), prepared),
        Err(why) => super::events_only::fit_from_events(input, options, progress, Some(why)),
    }
}

/// The fit that re-simulates the frames `prepared` on the fit run `run` (ending at
/// `end`): stages 2-6 of the module docs, from the starting thresholds to the result.
fn fit_with_frames(
    input: &FitInput,
    options: &FitOptions,
    progress: Progress,
    (run, end): (&start::FitRun, TimeUs),
    prepared: FramesToSimulate,
) -> Result<FitResult, FitError> {
    let FramesToSimulate {
        mut frames,
        mut assumptions,
        aligned: frames_aligned,
        other_response,
    } = prepared;
    progress("starting thresholds (estimate aps on the fit run)", 0.05);
    let (start, start_params) = starting_point(input, run, options, &mut frames, &mut assumptions);

    progress("the ideal model", 0.2);
    let geometry = Geometry::new(&frames, input.excluded, options.blocks, end);
    let runs = frames.upsample_runs(0.5, options.aps.max_upsampled_bytes);
    let mut simulation = simulation_of(input, &frames, &runs, &geometry, options.seed);
    let ideal = Ideal::measure(
        &simulation,
        &start_params,
        start.fixed,
        input,
        &mut assumptions,
    )?;
    let mut state = ideal.state;
    let loop_run = LoopRun {
        known: Known::of(
            run,
            input,
            &state,
            &start,
            (&simulation, planned(options).contains(&Effect::ShotNoise)),
        ),
        fixed: ideal.fixed,
        noise: ideal.noise,
        fit_events: &run.events,
        frames: &frames,
    };
    let mut steps = vec![start.step];
    let (added, ambiguities) = choose_effects(
        &mut simulation,
        &mut state,
        options,
        &loop_run,
        &mut steps,
        progress,
    )?;
    let parts = finish::Parts {
        before: ideal.before,
        residuals_before: ideal.residuals_before,
        added,
        steps,
        ambiguities,
        assumptions,
        fixed: ideal.fixed,
        start: start.measured,
        timing: start.timing,
        known: loop_run.known,
        interpolation_share: start.interpolation_share,
        offset_reach: start.offset_reach,
        other_response,
        frame_quality: frame_quality::FrameQuality::default(),
        frames_aligned,
        options,
        input,
    };
    Ok(concluded(
        &simulation,
        state,
        parts,
        (&frames, end),
        progress,
    ))
}

/// The fit's result from the final `state`: the frame checks (unless the thresholds are
/// given) put into `parts`, then the final model measured on the test blocks.
fn concluded(
    simulation: &Simulation,
    state: State,
    mut parts: finish::Parts,
    frames: (&PreparedFrames, TimeUs),
    progress: Progress,
) -> FitResult {
    progress(
        "frame checks (every 2nd and 3rd frame, a doubled exposure)",
        0.96,
    );
    if !parts.fixed {
        parts.frame_quality = frame_checks(parts.input, parts.options, frames, simulation, &state);
    }
    progress("the final model on the test blocks", 0.97);
    let result = finish::result(simulation, state, parts);
    progress("done", 1.0);
    result
}

/// What every simulation of the fit runs on: the frames' upsampled runs, the blocks, and
/// the recording's events measured as each simulation's will be (no pixel masked yet).
fn simulation_of<'a>(
    input: &FitInput<'a>,
    frames: &PreparedFrames,
    runs: &'a [Vec<crate::sim::Sample>],
    geometry: &'a Geometry,
    seed: u64,
) -> Simulation<'a> {
    Simulation {
        runs,
        width: frames.width,
        height: frames.height,
        geometry,
        events: input.events,
        real: super::observe::Observed::new(
            input.events,
            geometry,
            &vec![false; input.sensor.pixels()],
        ),
        grid: timestamp_grid(input.events),
        seed,
        count: Cell::new(0),
        hot_events: EventChunk::default(),
        lag_keys: Default::default(),
    }
}

/// The final model on every 2nd and 3rd frame and a doubled exposure
/// ([`frame_quality`]): how far the fit depends on the frames it was given.
fn frame_checks(
    input: &FitInput,
    options: &FitOptions,
    (frames, fit_end): (&PreparedFrames, TimeUs),
    simulation: &Simulation,
    state: &State,
) -> frame_quality::FrameQuality {
    let check = frame_quality::Check {
        frames,
        input,
        options,
        fit_end,
        masked: &state.masked,
    };
    frame_quality::measure(&check, simulation, &state.model)
}

/// The starting thresholds (`estimate aps` on the fit run) and the model they start, the
/// frames moved to the log offset they were read at (the counts' where a photoreceptor lag
/// distorts the timing's) unless the user gave one.
fn starting_point(
    input: &FitInput,
    run: &start::FitRun,
    options: &FitOptions,
    frames: &mut crate::estimate::frames::PreparedFrames,
    assumptions: &mut Vec<String>,
) -> (start::Start, PixelParams) {
    let change_rate = dynamics::from_frames(frames, 0.5).map_or(0.0, |d| d.log_change_rate);
    let static_scene = change_rate < dynamics::STATIC_CHANGE_RATE;
    let start = start::thresholds(input, run, options, change_rate, static_scene);
    assumptions.extend(start.assumptions.iter().cloned());
    if let Some((offset, range)) = start
        .frame_offset_dn
        .filter(|_| options.aps.frame_offset_dn.is_none())
        && offset != frames.offset
    {
        assumptions.push(format!(
            "frames simulated at the log offset b = {offset:.1} DN where `estimate aps` read the starting thresholds (its offset from the counts, not the event timing's {:.1} DN)",
            frames.offset
        ));
        frames.offset = offset;
        frames.offset_range = range;
    }
    let params = crate::estimate::resim::read_as_frames(&start.params, frames.log_map);
    (start, params)
}

/// The ideal model (the starting thresholds, no effect) measured: the loop's first state,
/// its error on the test blocks and residuals, and the distance's chance spread.
struct Ideal {
    state: State,
    /// Whether the thresholds are given, not fitted.
    fixed: bool,
    /// Its error on the test blocks.
    before: super::Components,
    residuals_before: super::residuals::Residuals,
    noise: f64,
}

impl Ideal {
    fn measure(
        simulation: &Simulation,
        start: &PixelParams,
        start_fixed: bool,
        input: &FitInput,
        assumptions: &mut Vec<String>,
    ) -> Result<Self, FitError> {
        let (ideal, fixed) = ideal_model(simulation, start, start_fixed, assumptions)?;
        let kept: Vec<bool> = input.excluded.iter().map(|&e| !e).collect();
        let geometry = simulation.geometry;
        let before = simulation.distance(&ideal.observed, geometry.testing(), &kept);
        let residuals_before = residuals(&simulation.real, &ideal.observed, geometry, Subset::Fit);
        let noise = distance_noise(simulation, &ideal.observed, &kept);
        let uncertainty = finish::threshold_uncertainty(simulation, &ideal);
        // given thresholds are known; thresholds kept at their start (the frames explain
        // almost no events) or without count cells to fix them are not
        let measured = ["ct_off", "ct_on"].map(|k| {
            start_fixed
                || (!fixed
                    && uncertainty
                        .get(k)
                        .is_some_and(|u| u.standard_error.is_some()))
        });
        finish::read_noise_note(simulation, &ideal, measured, assumptions);
        let state = State {
            uncertainty,
            model: ideal,
            masked: vec![false; input.sensor.pixels()],
            kept,
            hot: Vec::new(),
            hot_detection: None,
            at_bound: BTreeMap::new(),
        };
        Ok(Self {
            state,
            fixed,
            before,
            residuals_before,
            noise,
        })
    }
}

impl Known {
    /// What the fit run tells before any effect is tried: the mismatch's evidence (or the
    /// most an unresolved spread allows), the timestamp grid, the shortest same-pixel
    /// interval of the kept pixels and, where shot noise may be tried, the isolated OFF
    /// events at quiet pixels (on the fit run and on the judging blocks).
    fn of(
        run: &start::FitRun,
        input: &FitInput,
        state: &State,
        start: &start::Start,
        (simulation, shot_noise_planned): (&Simulation, bool),
    ) -> Self {
        let geometry = simulation.geometry;
        let grid = simulation.grid;
        // the scene's own quiet OFF events, as the ideal model (no shot noise) makes them
        let scene = std::cell::OnceCell::new();
        let scene_events = || {
            scene
                .get_or_init(|| {
                    simulation
                        .events_of(&state.model.params, simulation.seed)
                        .ok()
                })
                .as_ref()
        };
        let counted = |events: &EventChunk, (from, to): (TimeUs, TimeUs)| {
            let mut quiet = super::events_only::quiet_off(events, input)?;
            quiet.scene = scene_events().and_then(|model| {
                super::events_only::scene_floor(&model.between(from, to), input, quiet.isolation)
            });
            Some(quiet)
        };
        // without selection blocks the signature would be the count that called for it
        let judging = || {
            if geometry.judging() == Subset::Fit {
                return None;
            }
            let (from, to) = geometry.time_range_of(geometry.judging())?;
            counted(&input.events.between(from, to), (from, to))
        };
        let fit_end = run.events.t.last().map_or(TimeUs::MIN, |&t| t + 1);
        Known {
            mismatch: start.mismatch,
            spread_unresolved: start.spread_unresolved,
            grid,
            shortest_interval_s: effects::refractory::shortest_interval_s(
                &run.events,
                input.sensor.width as usize,
                &state.kept,
                grid.map_or(1, |g| g.0.clamp(1, u32::MAX as i64) as u32),
            ),
            quiet_off: shot_noise_planned
                .then(|| counted(&run.events, (TimeUs::MIN, fit_end)))
                .flatten(),
            quiet_off_judging: shot_noise_planned.then(judging).flatten(),
            leak_drift: start.leak_drift,
        }
    }
}

/// The frames as the simulator reads them: the frame-time alignment, the log offset and
/// the response found on the fit run alone, applied to every frame; `Ok(Err(why))` where
/// the flow does not follow them ([`frames_not_followed`]) or where no interval of the fit
/// run can be used at all (motion beyond the flow's reach on every interval, no events
/// between the frames, frames with a problem): the events can still be read alone (draw
/// 6028 cut to its first 0.6 s, none of its five intervals followed, was refused). With
/// the frames, whether their times were aligned to the fit run's events (no offset given,
/// and the alignment found one).
fn prepare_frames(
    input: &FitInput,
    run: &start::FitRun,
    options: &FitOptions,
) -> Result<Result<FramesToSimulate, String>, FitError> {
    let found = match aps::prepare(&run.aps_input(input), input.excluded, &options.aps) {
        Ok(found) => found,
        Err(unusable) => {
            return Ok(Err(format!(
                "no frame interval of the fit run can be re-simulated: {}",
                unusable.problem
            )));
        }
    };
    let fixed = aps::ApsOptions {
        frame_time_offset_s: options
            .aps
            .frame_time_offset_s
            .or(found.alignment.as_ref().map(|a| a.shift_s))
            .or(Some(0.0)),
        frame_offset_dn: Some(found.frames.offset as f64),
        log_map: found.frames.log_map,
        choose_response: false,
        ..options.aps.clone()
    };
    let all = ApsInput {
        sensor: input.sensor,
        events: input.events,
        frames: input.frames,
        excluded: input.excluded,
        unread: input.unread,
    };
    let prepared = aps::prepare(&all, input.excluded, &fixed)?;
    if let Some(why) = frames_not_followed(&found.frames, &prepared.frames) {
        return Ok(Err(why));
    }
    Ok(Ok(FramesToSimulate {
        frames: prepared.frames,
        assumptions: found.assumptions,
        aligned: options.aps.frame_time_offset_s.is_none() && found.alignment.is_some(),
        other_response: found.other_response,
    }))
}

/// The frames the fit re-simulates ([`prepare_frames`]).
struct FramesToSimulate {
    frames: PreparedFrames,
    /// What preparing them on the fit run assumed.
    assumptions: Vec<String>,
    /// Whether their times were aligned to the fit run's events.
    aligned: bool,
    /// The log response not chosen, where the fit run's events cannot rule it out.
    other_response: Option<crate::estimate::timing::OtherResponse>,
}

/// Why the frames cannot be re-simulated. Either the motion outruns the fit run's frames:
/// the optical flow moves too far on more of its intervals than it follows, which is where
/// `estimate aps` on the fit run refuses (those it follows may be the few it happened to
/// match, or a periodic pattern aliased to a smaller step); re-simulated from them, the
/// thresholds were confidently wrong (coverage draw 7035, a texture at 521 px/s, 5 of 69
/// intervals followed: ON 0.186 [0.089, 0.391] and OFF 0.150 [0.069, 0.324] for a true
/// 0.695 / 0.408; an ESIM draw at 486 px/s, 6 of 25 followed in the fit run: ON 0.055
/// [0.021, 0.147] for 0.309, with a bandwidth limit ESIM does not have). Or the flow
/// follows fewer than [`aps::MIN_USED_INTERVALS`] of the fit run's intervals while over
/// the whole recording the motion outruns it: with one followed interval the fit rested on
/// a few hundredths of a second (draw 6028, a checkerboard at 337 px/s seen at 10 Hz: ON
/// 0.104 [0.073, 0.150] for a true 0.191; draw 6015, 535 px/s: 0.172 / 0.066 for
/// 0.727 / 0.312). The fit then reads the events alone, as for a recording without frames
/// (draw 7035 so: ON 0.43 [0.056, 3.3], OFF 0.30 [0.095, 0.92]). `None` where the flow
/// follows enough intervals, or where a short recording's fit run has few frames but the
/// flow follows as many of them as it loses and most of the recording's (the IJRR
/// slider_depth chunk: one of the fit run's two intervals moves 13.5 px, over the 12 px
/// limit; three of the four are followed).
fn frames_not_followed(fit_run: &PreparedFrames, all: &PreparedFrames) -> Option<String> {
    let used_fit = fit_run.intervals.iter().filter(|i| i.used).count();
    if let Some((followed, too_fast)) = fit_run.motion_outruns_flow() {
        return Some(format!(
            "the motion outruns the fit run's frames: the optical flow moves too far on {too_fast} of its {} frame intervals and follows only {followed} (too fast for the frame rate; those it follows may be the few it happened to match, or a periodic pattern aliased to a smaller step), so the scene between the frames is not known well enough to re-simulate",
            fit_run.intervals.len()
        ));
    }
    let (used_all, too_fast) = all.motion_outruns_flow()?;
    (used_fit < aps::MIN_USED_INTERVALS).then(|| {
        format!(
            "the optical flow follows only {used_fit} of the fit run's {} frame intervals and {used_all} of the recording's {}, the motion between frames too large on {too_fast} (too fast for the frame rate); re-simulating the frames needs {} followed in the fit run",
            fit_run.intervals.len(),
            all.intervals.len(),
            aps::MIN_USED_INTERVALS
        )
    })
}

/// The ideal model with the thresholds profiled, and whether they stay fixed (a static
/// scene, or frames that explain under 5 % of the events: counts cannot fix thresholds).
fn ideal_model(
    simulation: &Simulation,
    start: &PixelParams,
    fixed: bool,
    assumptions: &mut Vec<String>,
) -> Result<(Simulated, bool), FitError> {
    let g = simulation.geometry;
    let no_mask = vec![false; g.sensor.pixels()];
    let mut ideal = simulation.profile(start, &no_mask, fixed)?;
    if !fixed {
        ideal = simulation.settle_flat(start, ideal, &no_mask)?;
    }
    if !fixed && ideal.observed.total(g, Subset::All) * 20 < simulation.real.total(g, Subset::All) {
        assumptions.push(
            "the frames explain under 5 % of the events: thresholds kept where they started (not identified)".into(),
        );
        return Ok((simulation.profile(start, &no_mask, true)?, true));
    }
    Ok((ideal, fixed))
}

/// How much the distance moves by chance: the standard error of its mean over the fit
/// blocks (2 % of it where there is a single fit block).
fn distance_noise(
    simulation: &Simulation,
    observed: &super::observe::Observed,
    kept: &[bool],
) -> f64 {
    let g = simulation.geometry;
    let per_block: Vec<f64> = g
        .blocks_of(super::observe::Role::Fit)
        .into_iter()
        .map(|b| simulation.distance(observed, Subset::Block(b), kept).total)
        .collect();
    let n = per_block.len() as f64;
    match crate::stats::robust::sample_std_dev(&per_block) {
        Some(sd) => sd / n.sqrt(),
        None => 0.02 * per_block.iter().sum::<f64>() / n.max(1.0),
    }
}

/// What every step of the loop shares.
struct LoopRun<'a> {
    known: Known,
    fixed: bool,
    noise: f64,
    fit_events: &'a EventChunk,
    /// The frames, for the named hot pixels' own brightness over time.
    frames: &'a crate::estimate::frames::PreparedFrames,
}

fn planned(options: &FitOptions) -> Vec<Effect> {
    match &options.effects {
        EffectChoice::Auto => Effect::ALL.to_vec(),
        EffectChoice::None => Vec::new(),
        EffectChoice::List(list) => list.clone(),
    }
}

/// The effects chosen: the loop ([`run_loop`]), the added effects refitted together and
/// pruned, the effects that look alike compared (unless the effects were listed), and a
/// record of each planned effect never tried; with the look-alikes not told apart.
fn choose_effects(
    simulation: &mut Simulation,
    state: &mut State,
    options: &FitOptions,
    loop_run: &LoopRun,
    steps: &mut Vec<Step>,
    progress: Progress,
) -> Result<(Vec<AddedEffect>, Vec<Ambiguity>), FitError> {
    let mut added = run_loop(simulation, state, options, loop_run, steps, progress)?;
    refit_together(simulation, state, loop_run, &mut added, steps, progress)?;
    prune_added(simulation, state, loop_run, &mut added, steps)?;
    if matches!(options.effects, EffectChoice::List(_)) {
        return Ok((added, Vec::new()));
    }
    progress("effects that look alike", 0.95);
    let ambiguities = alternatives::compare(
        simulation,
        state,
        loop_run.known,
        &mut added,
        steps,
        (loop_run.fixed, loop_run.noise),
    )?;
    let context = context_of(state, simulation, loop_run.known);
    for &effect in planned(options).iter() {
        if !steps.iter().any(|s| s.effect == effect.name()) {
            steps.push(steps::untried(&effects::evidence(effect, &context)));
        }
    }
    Ok((added, ambiguities))
}

/// The loop: the effect called for most strongly (or the next listed), tried, until none is
/// left.
fn run_loop(
    simulation: &mut Simulation,
    state: &mut State,
    options: &FitOptions,
    run: &LoopRun,
    steps: &mut Vec<Step>,
    progress: Progress,
) -> Result<Vec<AddedEffect>, FitError> {
    let planned = planned(options);
    let forced = matches!(options.effects, EffectChoice::List(_));
    let mut added = Vec::new();
    let mut tried: Vec<Effect> = Vec::new();
    // each effect tried and not kept, with how many effects the model held then
    let mut rejected: Vec<(Effect, usize)> = Vec::new();
    for round in 0..planned.len() {
        progress(
            &format!("effects: round {} of at most {}", round + 1, planned.len()),
            0.25 + 0.65 * round as f64 / planned.len().max(1) as f64,
        );
        let context = context_of(state, simulation, run.known);
        let candidates: Vec<effects::Evidence> = planned
            .iter()
            .filter(|e| !tried.contains(e))
            .map(|&e| effects::evidence(e, &context))
            .collect();
        let Some(evidence) = next_effect(candidates, forced) else {
            break;
        };
        tried.push(evidence.effect);
        let hot = (evidence.effect == Effect::HotPixels)
            .then(|| hot_trains(&context, run, simulation.events));
        let step = steps::try_effect(simulation, state, &evidence, hot, run)?;
        if step.kept {
            added.push(AddedEffect {
                effect: evidence.effect,
                evidence: evidence.text.clone(),
                error_after: step.error_after.unwrap_or(f64::NAN),
            });
        } else {
            rejected.push((evidence.effect, added.len()));
        }
        steps.push(step);
    }
    if !forced {
        second_look(simulation, state, run, &rejected, &mut added, steps)?;
    }
    Ok(added)
}

/// Each effect not kept when it was tried is tried once more where effects joined the
/// model after it and its residual signature still calls for it: an effect judged against
/// a model that lacked another one can lose to what that one explains (coverage draw
/// 6034, every effect at once: its 3.4 ms refractory period was tried before the shot
/// noise was in, searched to 1.6 ms, the edge of its range, and not kept, though no
/// interval of the recording is shorter than 3.2 ms). The same keep rule judges it; the
/// step is named as a second try, with the effects it is tried beside.
fn second_look(
    simulation: &mut Simulation,
    state: &mut State,
    run: &LoopRun,
    rejected: &[(Effect, usize)],
    added: &mut Vec<AddedEffect>,
    steps: &mut Vec<Step>,
) -> Result<(), FitError> {
    for &(effect, held_then) in rejected {
        if added.len() <= held_then || matches!(effect, Effect::HotPixels | Effect::Display) {
            continue;
        }
        let evidence = effects::evidence(effect, &context_of(state, simulation, run.known));
        if !evidence.calls_for() {
            continue;
        }
        let joined: Vec<&str> = added[held_then..].iter().map(|a| a.effect.name()).collect();
        let mut step = steps::try_effect(simulation, state, &evidence, None, run)?;
        step.effect = format!("{} (again, with {} in)", effect.name(), joined.join(", "));
        if step.kept {
            added.push(AddedEffect {
                effect,
                evidence: evidence.text.clone(),
                error_after: step.error_after.unwrap_or(f64::NAN),
            });
        }
        steps.push(step);
    }
    Ok(())
}

/// The next effect: the first listed, or (auto) the directly measured ones first (hot
/// pixels, the mismatch event timing measures), then the strongest residual signature.
fn next_effect(candidates: Vec<effects::Evidence>, forced: bool) -> Option<effects::Evidence> {
    if forced {
        return candidates.into_iter().next();
    }
    let called: Vec<effects::Evidence> = candidates.into_iter().filter(|e| e.calls_for()).collect();
    let direct = [Effect::HotPixels, Effect::Mismatch]
        .into_iter()
        .find_map(|d| called.iter().find(|e| e.effect == d).cloned());
    direct.or_else(|| {
        called
            .into_iter()
            .max_by(|a, b| a.score.total_cmp(&b.score))
    })
}

/// The hot pixels of the fit blocks (robust z-score against the busiest neighbour), each
/// with its rate and ON share in the fit run. Named on the fit blocks, they are confirmed
/// as independent of the scene on the events from the fit blocks' start to the judging
/// blocks' end (`all`: the recording): a defect fires throughout, a low threshold under
/// mismatch in bursts that a short fit run may not show the end of (coverage draw 59: ON
/// at 540 Hz through the fit blocks, silent in the selection blocks), and against their
/// own brightness in the frames of that time.
fn hot_trains(
    context: &Context,
    run: &LoopRun,
    all: &EventChunk,
) -> (Vec<HotPixel>, Vec<HotTrain>) {
    let (g, fit_events, frames) = (context.geometry, run.fit_events, run.frames);
    let named = effects::hot_pixels::find(context);
    let log_at = |x: u16, y: u16, t: TimeUs| frames.log_at(x, y, t);
    let (hot, _) = match (g.time_range_of(Subset::Fit), g.time_range_of(g.judging())) {
        (Some((from, _)), Some((_, to))) => {
            let intervals = frames
                .times
                .windows(2)
                .map(|w| (w[0], w[1]))
                .filter(|&(a, b)| a >= from && b <= to && frames.interval_of(a).is_some());
            let scene = effects::hot_pixels::SceneTrace {
                steps: effects::hot_pixels::SceneTrace::steps_of(intervals),
                log_at: &log_at,
            };
            effects::hot_pixels::independent_of_scene(
                &named,
                all,
                all.t.partition_point(|&t| t < from)..all.t.partition_point(|&t| t < to),
                g.sensor,
                Some(&scene),
            )
        }
        _ => effects::hot_pixels::independent_of_scene(
            &named,
            fit_events,
            0..fit_events.len(),
            g.sensor,
            None,
        ),
    };
    let trains = hot
        .iter()
        .map(|h| {
            let (mut on, mut all) = (0usize, 0usize);
            for i in 0..fit_events.len() {
                if fit_events.x[i] == h.x && fit_events.y[i] == h.y {
                    all += 1;
                    on += fit_events.on[i] as usize;
                }
            }
            HotTrain {
                x: h.x,
                y: h.y,
                rate_hz: h.rate_hz,
                on_share: if all > 0 { on as f64 / all as f64 } else { 0.5 },
            }
        })
        .collect();
    (hot, trains)
}

/// Effects added early were fitted without the later ones (mismatch before the noise it
/// partly stood in for): each searched parameter is fitted once more with all the others in
/// place, and the new value kept if it wins on the selection blocks.
fn refit_together(
    simulation: &Simulation,
    state: &mut State,
    run: &LoopRun,
    added: &mut [AddedEffect],
    steps: &mut Vec<Step>,
    progress: Progress,
) -> Result<(), FitError> {
    let searched = searched_together(added);
    if searched.len() < 2 {
        return Ok(());
    }
    progress("refitting the effects together", 0.9);
    for effect in searched {
        let step = steps::refit(simulation, state, effect, run)?;
        if step.kept
            && let Some(entry) = added.iter_mut().find(|a| a.effect == effect)
        {
            entry.error_after = step.error_after.unwrap_or(entry.error_after);
        }
        steps.push(step);
    }
    Ok(())
}

/// Each searched effect, once all are in, tested for whether it is still needed; those the
/// others explain are removed (see [`steps::prune`]).
fn prune_added(
    simulation: &Simulation,
    state: &mut State,
    run: &LoopRun,
    added: &mut Vec<AddedEffect>,
    steps: &mut Vec<Step>,
) -> Result<(), FitError> {
    let searched = searched_together(added);
    if searched.len() < 2 {
        return Ok(());
    }
    for &effect in &searched {
        let others: Vec<Effect> = searched
            .iter()
            .copied()
            .filter(|&e| e != effect && added.iter().any(|a| a.effect == e))
            .collect();
        let step = steps::prune(simulation, state, effect, &others, run)?;
        if !step.kept {
            added.retain(|a| a.effect != effect);
        }
        steps.push(step);
    }
    Ok(())
}

/// The added effects with a searched parameter, in the order they were added.
fn searched_together(added: &[AddedEffect]) -> Vec<Effect> {
    added
        .iter()
        .map(|a| a.effect)
        .filter(|e| e.parameter().is_some())
        .collect()
}

/// The signature of `effect` on the judging blocks against `model` (for the keep rule by
/// signature, [`keep::by_signature`]), the quiet pixels counted there.
fn judging_evidence(
    state: &State,
    simulation: &Simulation,
    known: Known,
    effect: Effect,
    model: &Simulated,
) -> effects::Evidence {
    let context = Context {
        sim: &model.observed,
        model: &model.params,
        subset: simulation.geometry.judging(),
        quiet_off: known.quiet_off_judging,
        ..context_of(state, simulation, known)
    };
    effects::signature(effect, &context)
}

/// The range `effect`'s parameter is searched over, from `range` (the effect's own about a
/// start) beside the model `params`: shot noise's within the dark rate the fit run's quiet
/// pixels give ([`effects::quiet_noise::searched_range`]), with that rate's interval where
/// the count set the range (an end of it is a measured limit, not a bound of the search's
/// choosing).
fn search_range(
    effect: Effect,
    range: (f64, f64),
    known: Known,
    geometry: &Geometry,
    params: &PixelParams,
) -> ((f64, f64), Option<[f64; 2]>) {
    if effect != Effect::ShotNoise {
        return (range, None);
    }
    let Some(within) =
        effects::quiet_noise::searched_range(range, known.quiet_off, geometry, params)
    else {
        return (range, None);
    };
    let counted = known
        .quiet_off
        .and_then(|q| effects::quiet_noise::direct_dark_rate(&q, geometry, params));
    (within, counted)
}

/// [`search_range`]'s search result: a value at an end of the quiet count's interval is
/// within what the count measured (the interval reported is the count's,
/// [`effects::quiet_noise::take_count_interval`]); an end of the search's own range stays a
/// bound.
fn within_count(
    mut searched: super::search::Searched,
    counted: Option<[f64; 2]>,
) -> super::search::Searched {
    let at_count_end =
        |b: f64| counted.is_some_and(|c| c.iter().any(|&e| (b / e).ln().abs() < 0.05));
    if searched.at_bound.is_some_and(at_count_end) {
        searched.at_bound = None;
    }
    searched
}

/// [`search`](super::search::search) of `effect` from `params` over `range` (the effect's
/// own), shot noise's within the quiet count ([`search_range`], [`within_count`]).
fn search_counted(
    simulation: &Simulation,
    searched: (&PixelParams, Effect, (f64, f64)),
    state: &State,
    known: Known,
    (fixed, noise): (bool, f64),
) -> Result<super::search::Searched, FitError> {
    search_shaped(simulation, searched, state, known, (fixed, false), noise)
}

/// [`search_profiled`](super::search::search_profiled) of `effect` from `params` over
/// `range`, a leak shaped by its growth with the light ([`shaped_for_search`]) and shot
/// noise kept within the quiet count ([`search_range`], [`within_count`]); with `mismatch`
/// the threshold mismatch profiled at every point.
fn search_shaped(
    simulation: &Simulation,
    (params, effect, range): (&PixelParams, Effect, (f64, f64)),
    state: &State,
    known: Known,
    (fixed, mismatch): (bool, bool),
    noise: f64,
) -> Result<super::search::Searched, FitError> {
    let (params, range) = shaped_for_search(effect, params, range, known);
    let (range, counted) = search_range(effect, range, known, simulation.geometry, &params);
    let searched = super::search::search_profiled(
        simulation,
        &params,
        effect,
        range,
        (&state.masked, &state.kept),
        (fixed, mismatch),
        noise,
    )?;
    Ok(within_count(searched, counted))
}

/// `params` and `range` ready for a search of `effect`: a leak that grows with the light
/// (the event timing's [`effects::leak::LeakGrowth`]) is searched through its dark part with
/// the growth's ratio to it held, so a range of rates at the frames' median DN becomes one
/// of dark parts. Any other search, or a leak already in `params`, as given.
fn shaped_for_search(
    effect: Effect,
    params: &PixelParams,
    range: (f64, f64),
    known: Known,
) -> (PixelParams, (f64, f64)) {
    let shaped = (effect == Effect::Leak)
        .then(|| known.leak_drift.and_then(|d| d.growth))
        .flatten()
        .and_then(|g| g.shaped(params));
    match shaped {
        Some((shaped, dark_share)) => (shaped, (range.0 * dark_share, range.1 * dark_share)),
        None => (params.clone(), range),
    }
}

fn context_of<'a>(state: &'a State, simulation: &'a Simulation, known: Known) -> Context<'a> {
    Context {
        real: &simulation.real,
        sim: &state.model.observed,
        geometry: simulation.geometry,
        kept: &state.kept,
        model: &state.model.params,
        mismatch_estimate: known.mismatch,
        timestamp_grid_us: known.grid.map(|g| g.0),
        shortest_interval_s: known.shortest_interval_s,
        quiet_off: known.quiet_off,
        leak_drift: known.leak_drift,
        subset: Subset::Fit,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::effects::fixture::static_frames;

    /// Frames every 100 ms over `seconds`, the flow following the intervals `followed` and
    /// moving too far on the others (but those in `no_events`, dropped for want of events).
    fn frames(seconds: f64, followed: &[usize], no_events: &[usize]) -> PreparedFrames {
        let mut f = static_frames(8, 6, seconds, 100.0);
        for (k, i) in f.intervals.iter_mut().enumerate() {
            i.used = followed.contains(&k);
            i.motion_px = match (i.used, no_events.contains(&k)) {
                (true, _) => 3.0,
                (false, true) => 0.0,
                (false, false) => 34.0,
            };
        }
        f
    }

    /// Coverage draw 6028's frames (a checkerboard at 337 px/s at 10 Hz): one interval of
    /// the fit run's seven followed, two of the recording's thirteen.
    #[test]
    fn frames_the_flow_does_not_follow_are_not_re_simulated() {
        let fit_run = frames(0.7, &[3], &[]);
        let all = frames(1.3, &[3, 9], &[]);
        let why = frames_not_followed(&fit_run, &all).expect("not followed");
        assert!(why.contains("too far on 6 of its 7") && why.contains("follows only 1"));
        // the motion outruns the whole recording, not the fit run: one of its two
        // intervals followed, under the three needed
        let fit_run = frames(0.2, &[0], &[]);
        let all = frames(1.3, &[0, 9], &[]);
        let why = frames_not_followed(&fit_run, &all).expect("not followed");
        assert!(why.contains("1 of the fit run's 2") && why.contains("2 of the recording's 13"));
        // the IJRR slider_depth chunk: one of the fit run's two intervals over the limit,
        // three of the recording's four followed
        let fit_run = frames(0.2, &[0], &[]);
        let all = frames(0.4, &[0, 2, 3], &[]);
        assert_eq!(frames_not_followed(&fit_run, &all), None);
        // intervals without events are not the flow failing
        let fit_run = frames(0.7, &[3], &[0, 1, 2, 4, 5, 6]);
        let all = frames(1.3, &[3, 9], &[0, 1, 2, 4, 5, 6, 7, 8, 10, 11, 12]);
        assert_eq!(frames_not_followed(&fit_run, &all), None);
        // three followed in the fit run, four too fast: the motion outruns its frames
        let fit_run = frames(0.7, &[1, 3, 5], &[]);
        let all = frames(1.3, &[1, 3, 5, 7, 8, 9, 10, 11, 12], &[]);
        let why = frames_not_followed(&fit_run, &all).expect("outrun in the fit run");
        assert!(why.contains("too far on 4 of its 7") && why.contains("follows only 3"));
        // four followed, three too fast: re-simulated
        let fit_run = frames(0.7, &[0, 1, 3, 5], &[]);
        assert_eq!(frames_not_followed(&fit_run, &all), None);
    }

    /// A smooth pattern moving 30 px a frame at 10 Hz (300 px/s, draw 6028's pace cut to
    /// its first half second): no interval is followed, so the frames cannot be prepared
    /// at all; the fit is told why instead of refusing the recording.
    #[test]
    fn frames_no_interval_of_which_is_followed_leave_the_events_to_the_fit() {
        use crate::events::{EventChunk, Frame, Sensor};
        let (width, height) = (96u16, 64u16);
        let times = crate::fit::effects::fixture::frame_times(0.6, 0.1);
        let frames: Vec<Frame> = times
            .iter()
            .enumerate()
            .map(|(k, &t)| Frame {
                t,
                width: width as u32,
                height: height as u32,
                pixels: (0..width as usize * height as usize)
                    .map(|p| {
                        let x = (p % width as usize) as f64 + 30.0 * k as f64;
                        let y = (p / width as usize) as f64;
                        let v = (x / 9.0).sin() * (y / 7.0).cos() + 0.5 * (x / 23.0).cos();
                        (110.0 + 60.0 * v) as u8
                    })
                    .collect(),
                exposure_us: None,
            })
            .collect();
        let mut events = EventChunk::default();
        for k in 0..6000i64 {
            let p = (k * 7919) as usize % (width as usize * height as usize);
            events.push(
                k * 100,
                (p % width as usize) as u16,
                (p / width as usize) as u16,
                k % 3 != 0,
            );
        }
        let sensor = Sensor::new(width, height);
        let excluded = vec![false; sensor.pixels()];
        let input = FitInput {
            sensor,
            events: &events,
            frames: &frames,
            excluded: &excluded,
            unread: &[],
        };
        let options = FitOptions::default();
        let run = start::FitRun::new(&input, start::fit_end(&frames, options.holdout));
        let why = match prepare_frames(&input, &run, &options) {
            Ok(Err(why)) => why,
            Ok(Ok(_)) => panic!("frames moving 30 px a frame were re-simulated"),
            Err(e) => panic!("refused: {e}"),
        };
        assert!(
            why.starts_with("no frame interval of the fit run can be re-simulated")
                && why.contains("too large to interpolate"),
            "{why}"
        );
    }
}
