//! The fit of a recording without grey frames (Prophesee EVK3/EVK4/Gen4.1, DVXplorer, a
//! DAVIS recording without APS), or with frames whose motion outruns the optical flow
//! (see `fit::selection::frames_not_followed`): everything the events alone identify,
//! measured on the fit blocks and checked on held-out blocks like the frame-based fit.
//!
//! - **Hot pixels**, named: far above their neighbours' counts
//!   ([`crate::stats::hot_pixels`]), each with its rate and ON share.
//! - **Shot noise and leak**: isolated events (no event within ±10-300 ms at the pixels
//!   within 1-3 px, the narrowest support after which a wider one no longer lowers the
//!   rate) over the time their pixel was not covered by a neighbour's event ([`measure`]):
//!   an upper bound where the rate was still falling. Shot noise is
//!   symmetric in polarity (v2e, Hu et al. 2021), leak fires ON only (the reference drifts),
//!   so the OFF rate gives the shot noise and the ON excess the leak.
//! - **Refractory period**: the lower edge of the same-pixel intervals ([`refractory`]).
//! - **Cp/Cn**: the ON/OFF balance of the scene's own (supported) events. Where brightness
//!   returns over the recording, `N_on * Cp = N_off * Cn`, so `Cp / Cn = N_off / N_on`.
//! - **Absolute thresholds**: from a method that measures them (`estimate screen` on an
//!   on-screen recording), else `estimate eppps` with its natural-image prior on the fit
//!   run, and said which.
//!
//! Mismatch, photoreceptor bandwidth, timestamp jitter and the brightness dependence of
//! shot noise need the brightness each pixel saw or a known stimulus: not identified.
//! Each effect enters a noise model ([`model`]) and is kept when the model's distance to
//! the selection blocks falls by more than measured chance ([`steps`]); the test blocks
//! give `error_before` (ideal pixel) and `error_after`, both with the model simulated back
//! onto the test blocks' scene events and measured like the recording ([`simulate_back`]).

mod blocks;
mod candidates;
mod leak_onset;
mod measure;
mod model;
pub mod refractory;
mod result;
mod simulate_back;
mod steps;

use super::effects::hot_pixels::HotTrain;
use super::observe::Role;
use super::selection::hot_excess;
use super::{FitError, FitInput, FitOptions, FitResult, Uncertain};
use crate::estimate::eppps::{EpppsInput, EpppsOptions};
use crate::estimate::{CtEstimate, Interval, Progress};
use crate::stats::hot_pixels::{HotPixel, find_hot_pixels};
use crate::stats::robust::sample_std_dev;
use blocks::Blocks;
use measure::{BlockMeasure, Isolation, Measuring};
use model::Reference;
use serde::Serialize;
use steps::Judging;

/// The shortest recording the blocks can be cut from.
pub const MIN_SPAN_US: i64 = 20_000;
/// Events a fit without frames needs at least.
pub const MIN_EVENTS: usize = 1_000;

/// What a fit without frames measured beyond the model's parameters.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EventsOnly {
    /// Where the absolute thresholds come from.
    pub thresholds_source: String,
    pub ct_on_ci95: Option<Interval>,
    pub ct_off_ci95: Option<Interval>,
    /// Cp / Cn from the ON/OFF balance of the scene's events (fit blocks), with its
    /// standard error over the fit blocks; `None` with the reason.
    pub ct_ratio: Option<Uncertain>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ct_ratio_why: Option<String>,
    /// Isolated-event rates at quiet pixels, per pixel per second, on the fit blocks and
    /// (checked) on the test blocks.
    pub noise_on_hz: Option<Uncertain>,
    pub noise_off_hz: Option<Uncertain>,
    pub noise_on_test_hz: Option<f64>,
    /// The rates may include the scene's own slow events: upper bounds.
    pub noise_upper_bound: bool,
    pub noise_off_test_hz: Option<f64>,
    /// The test blocks' distances of the ideal pixel and the final model read from their
    /// parameters (`error_before`/`error_after` simulate them back, [`simulate_back`]).
    pub predicted_error_before: f64,
    pub predicted_error_after: f64,
    /// Why the models were not simulated back (the errors are then the predicted ones).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub simulated_back_why: Option<String>,
    /// Pixel-seconds of quiet, uncovered time the rates rest on (fit blocks), and the
    /// support window and radius that leave the scene's own events out.
    pub quiet_pixel_seconds: f64,
    /// Their share of the fit blocks' pixel time (kept pixels times seconds).
    pub quiet_share: f64,
    pub support_window_ms: f64,
    /// The neighbourhood's radius (Chebyshev, px) within which an event counts as support.
    pub support_radius_px: usize,
    /// The timestamps' common step, µs.
    pub timestamp_step_us: u32,
    /// The lower edge of the same-pixel intervals (fit blocks), µs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interval_edge: Option<IntervalEdge>,
}

/// The refractory edge as reported.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct IntervalEdge {
    pub edge_us: f64,
    pub range_us: [f64; 2],
    pub found: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_refractory: Option<String>,
    pub below: usize,
    pub above: usize,
    pub intervals: usize,
}

/// What the fit blocks measured.
pub(super) struct FitRun {
    hot: Vec<HotPixel>,
    /// The named hot pixels' positions (x, y), in the order of `hot` and `trains`.
    hot_positions: Vec<(u16, u16)>,
    trains: Vec<HotTrain>,
    /// The fraction and median rate of the named hot pixels, with their intervals.
    hot_found: hot_excess::HotExcess,
    /// Isolated-event rates (OFF, ON) under the chosen support.
    noise: [Option<(f64, f64)>; 2],
    isolation: Isolation,
    /// Why the isolated rate is only an upper bound on the noise, if it is one
    /// ([`measure::choose_isolation`]).
    noise_bound: Option<measure::UpperBound>,
    /// The ON excess rising from the fit blocks to the selection blocks: leak events that
    /// start a period after a reset ([`leak_onset`]).
    leak_onset: Option<leak_onset::Onset>,
    edge: Option<refractory::Edge>,
    /// The timestamps' common step, µs (1: no grid).
    timestamp_step_us: u32,
    /// OFF/ON of supported events and its standard error over the fit blocks.
    balance: Option<(f64, f64)>,
    quiet_pixel_seconds: f64,
    /// Its share of the fit blocks' pixel time ([`measure::quiet_share`]).
    quiet_share: f64,
    /// Supported (scene) events per kept pixel per second over the fit blocks.
    signal_rate_hz: f64,
}

/// Fits the pixel model to a recording without frames.
pub fn fit(
    input: &FitInput,
    options: &FitOptions,
    progress: Progress,
) -> Result<FitResult, FitError> {
    fit_from_events(input, options, progress, None)
}

/// Fits the pixel model to the events alone: of a recording without frames
/// (`frames_unused` `None`), or of one whose frames cannot be used, and why (said in the
/// assumptions and in the reasons of what the frames would have measured).
pub(super) fn fit_from_events(
    input: &FitInput,
    options: &FitOptions,
    progress: Progress,
    frames_unused: Option<String>,
) -> Result<FitResult, FitError> {
    let events = input.events;
    check(events)?;
    let blocks = Blocks::split(events, options.blocks, options.holdout);
    progress("hot pixels", 0.05);
    let (hot, trains, hot_found) = hot_pixels(input, &blocks);
    progress("noise, intervals and balance per block", 0.15);
    let measures = measure_blocks(input, &blocks, &hot);
    let judging = Judging {
        measures: &measures,
        role: &blocks.role,
        reference: Reference {
            edge_us: None,
            isolation: Isolation::default(),
        },
    };
    let step = refractory::timestamp_step(events);
    let run = fit_run(&judging, (hot, trains, hot_found), step);
    let judging = Judging {
        reference: Reference {
            edge_us: run.edge.as_ref().map(|e| e.edge_us),
            isolation: run.isolation,
        },
        ..judging
    };
    progress("absolute thresholds", 0.3);
    let thresholds = thresholds(input, options, &blocks, frames_unused.is_some());
    progress("the loop", 0.9);
    let (steps, model) = candidates::run_loop(&judging, &run);
    Ok(result::result(result::Parts {
        input,
        options,
        blocks: &blocks,
        judging: &judging,
        run,
        thresholds,
        steps,
        model,
        frames_unused,
    }))
}

/// The OFF isolated-event rate at quiet pixels of a stretch of a recording, measured as a
/// fit without frames measures it ([`measure`]: hot pixels taken out, the support chosen
/// by [`measure::choose_isolation`]). Noise is Poisson and independent of its neighbours,
/// so this is shot noise's OFF rate there whatever the scene; leak fires ON only.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct QuietOff {
    /// OFF isolated events per quiet pixel-second, and its Poisson standard error.
    pub rate_hz: f64,
    pub se_hz: f64,
    pub pixel_seconds: f64,
    pub support_window_ms: f64,
    pub support_radius_px: usize,
    /// The rate may hold the scene's own slow events: an upper bound.
    pub upper_bound: bool,
    /// The support chosen (to count a model's events the same way).
    pub isolation: measure::Isolation,
    /// The same count on the events of a model without shot noise over the same stretch
    /// (the scene's own isolated OFF events at quiet pixels, as the model makes them),
    /// where simulated.
    pub scene: Option<SceneFloor>,
}

/// A model's isolated OFF events at its quiet pixels, under a recording's support
/// ([`QuietOff::scene`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SceneFloor {
    pub events: u64,
    pub pixel_seconds: f64,
}

/// [`QuietOff`] of `events` (a time-sorted stretch of `input`'s recording, cut into six
/// blocks for the support's choice); `None` where they are too few or too short.
pub(crate) fn quiet_off(events: &crate::events::EventChunk, input: &FitInput) -> Option<QuietOff> {
    let measures = quiet_measures(events, input)?;
    let all: Vec<&BlockMeasure> = measures.iter().collect();
    let (isolation, bound) = measure::choose_isolation(&all);
    let (rate_hz, se_hz) = BlockMeasure::isolated_rate(&all, isolation, false)?;
    Some(QuietOff {
        rate_hz,
        se_hz,
        pixel_seconds: BlockMeasure::isolated(&all, isolation).pixel_seconds,
        support_window_ms: isolation.window_us() as f64 / 1e3,
        support_radius_px: isolation.radius_px(),
        upper_bound: bound.is_some(),
        isolation,
        scene: None,
    })
}

/// The isolated OFF events at quiet pixels of a model's `events` under the support
/// `isolation` a recording's count chose ([`QuietOff::scene`]); `None` where they are too
/// few or too short to measure.
pub(crate) fn scene_floor(
    events: &crate::events::EventChunk,
    input: &FitInput,
    isolation: measure::Isolation,
) -> Option<SceneFloor> {
    let measures = quiet_measures(events, input)?;
    let all: Vec<&BlockMeasure> = measures.iter().collect();
    let i = BlockMeasure::isolated(&all, isolation);
    (i.pixel_seconds > 0.0).then_some(SceneFloor {
        events: i.off,
        pixel_seconds: i.pixel_seconds,
    })
}

/// The blocks of a stretch measured for the quiet count: six blocks, hot pixels out.
fn quiet_measures(
    events: &crate::events::EventChunk,
    input: &FitInput,
) -> Option<Vec<BlockMeasure>> {
    check(events).ok()?;
    let blocks = Blocks::split(events, 6, 0.0);
    let stretch = FitInput { events, ..*input };
    let (hot, _, _) = hot_pixels(&stretch, &blocks);
    Some(measure_blocks(&stretch, &blocks, &hot))
}

/// Each block of `input`'s events measured ([`measure`]), the `hot` pixels' events left out.
fn measure_blocks(input: &FitInput, blocks: &Blocks, hot: &[HotPixel]) -> Vec<BlockMeasure> {
    let named: Vec<(u16, u16)> = hot.iter().map(|h| (h.x, h.y)).collect();
    measure::measure(
        &Measuring {
            events: input.events,
            sensor: input.sensor,
            excluded: input.excluded,
            hot: &named,
        },
        &blocks.spans,
    )
}

fn check(events: &crate::events::EventChunk) -> Result<(), FitError> {
    if events.len() < MIN_EVENTS {
        return Err(FitError::new(
            format!(
                "{} events: too few to measure noise, intervals and balance (a fit without frames needs {MIN_EVENTS})",
                events.len()
            ),
            "use a longer part of the recording",
        ));
    }
    let span = events.t[events.len() - 1] - events.t[0];
    if span < MIN_SPAN_US {
        return Err(FitError::new(
            format!(
                "the events span {:.1} ms: too short to cut into fit, selection and test blocks (needs {} ms)",
                span as f64 / 1e3,
                MIN_SPAN_US / 1000
            ),
            "use a longer part of the recording",
        ));
    }
    Ok(())
}

/// Hot pixels of the fit run, with their rates and ON shares there, and the fraction and
/// median rate they give with their intervals ([`hot_excess::excess`], as the fit with
/// frames counts them; without a model of the scene at each pixel, no outliers of the
/// model's own are subtracted).
fn hot_pixels(
    input: &FitInput,
    blocks: &Blocks,
) -> (Vec<HotPixel>, Vec<HotTrain>, hot_excess::HotExcess) {
    let (w, h) = (input.sensor.width as usize, input.sensor.height as usize);
    let end = blocks.fit_end();
    let fit_to = input.events.t.partition_point(|&t| t < end);
    let mut counts = vec![0u32; w * h];
    let mut on = vec![0u32; w * h];
    for i in 0..fit_to {
        let p = input.events.y[i] as usize * w + input.events.x[i] as usize;
        if !input.excluded[p] {
            counts[p] += 1;
            on[p] += input.events.on[i] as u32;
        }
    }
    let seconds = blocks.seconds(&blocks.of(Role::Fit));
    // a pixel out-firing its neighbours only while they fire is the scene's (a low
    // threshold on its edges), not a defect
    let (hot, _) = crate::fit::effects::hot_pixels::independent_of_scene(
        &find_hot_pixels(&counts, w, h, seconds),
        input.events,
        0..fit_to,
        input.sensor,
        None,
    );
    let trains = hot
        .iter()
        .map(|p| {
            let k = p.y as usize * w + p.x as usize;
            HotTrain {
                x: p.x,
                y: p.y,
                rate_hz: counts[k] as f64 / seconds,
                on_share: on[k] as f64 / counts[k].max(1) as f64,
            }
        })
        .collect();
    let kept: Vec<bool> = input.excluded.iter().map(|&e| !e).collect();
    let found = hot_excess::excess(&hot_excess::Counts {
        real_named: &hot,
        model: None,
        model_at_allowed_spreads: &[],
        width: w,
        height: h,
        duration_s: seconds,
        kept_pixels: kept.iter().filter(|&&k| k).count(),
        real: &counts,
        kept: &kept,
    });
    (hot, trains, found)
}

/// Everything measured on the fit blocks.
fn fit_run(
    judging: &Judging,
    (hot, trains, hot_found): (Vec<HotPixel>, Vec<HotTrain>, hot_excess::HotExcess),
    timestamp_step_us: u32,
) -> FitRun {
    let fit = judging.of(Role::Fit);
    let mut intervals: Vec<u32> = fit
        .iter()
        .flat_map(|b| b.intervals.iter().copied())
        .collect();
    let edge = refractory::edge(&mut intervals, timestamp_step_us);
    let (isolation, noise_bound) = measure::choose_isolation(&fit);
    FitRun {
        hot_positions: hot.iter().map(|h| (h.x, h.y)).collect(),
        hot,
        trains,
        hot_found,
        noise: [
            BlockMeasure::isolated_rate(&fit, isolation, false),
            BlockMeasure::isolated_rate(&fit, isolation, true),
        ],
        isolation,
        noise_bound,
        leak_onset: leak_onset::onset(&fit, &judging.of(Role::Selection), isolation),
        edge,
        timestamp_step_us,
        balance: balance(&fit),
        quiet_pixel_seconds: BlockMeasure::isolated(&fit, isolation).pixel_seconds,
        quiet_share: measure::quiet_share(&fit, isolation),
        signal_rate_hz: signal_rate_hz(&fit),
    }
}

/// The ON/OFF balance of the supported events of `blocks`, `N_off / N_on`; `None` with
/// fewer than 20 of either.
fn signal_ratio(blocks: &[&BlockMeasure]) -> Option<f64> {
    let (on, off) = blocks.iter().fold((0u64, 0u64), |(a, c), m| {
        (a + m.signal_on, c + m.signal_off)
    });
    (on >= 20 && off >= 20).then(|| off as f64 / on as f64)
}

/// The balance over the fit blocks ([`signal_ratio`]) and its standard error: a jackknife
/// over the blocks (each block's own brightness history moves it, which Poisson counting
/// alone would not show), infinite with fewer than 3 leave-one-out values.
fn balance(fit: &[&BlockMeasure]) -> Option<(f64, f64)> {
    signal_ratio(fit).map(|all| {
        let n = fit.len();
        let leave_one_out: Vec<f64> = (0..n)
            .filter_map(|k| {
                let rest: Vec<&BlockMeasure> = (0..n).filter(|&j| j != k).map(|j| fit[j]).collect();
                signal_ratio(&rest)
            })
            .collect();
        let se = (leave_one_out.len() >= 3)
            .then(|| sample_std_dev(&leave_one_out))
            .flatten()
            .map_or(f64::INFINITY, |s| s * (n as f64 - 1.0) / (n as f64).sqrt());
        (all, se)
    })
}

/// Supported events per kept pixel per second over the fit blocks, each block weighted by
/// its length.
fn signal_rate_hz(fit: &[&BlockMeasure]) -> f64 {
    fit.iter()
        .map(|b| b.signal_rate_hz * b.seconds)
        .sum::<f64>()
        / fit.iter().map(|b| b.seconds).sum::<f64>().max(1e-9)
}

/// The absolute thresholds: given (a method that measured them), else eppps with its
/// prior on the fit run; `Err` with the reason when neither gives them.
fn thresholds(
    input: &FitInput,
    options: &FitOptions,
    blocks: &Blocks,
    frames_not_followed: bool,
) -> Result<CtEstimate, String> {
    if let Some(given) = &options.thresholds {
        return Ok(given.clone());
    }
    let fit_events = input.events.between(input.events.t[0], blocks.fit_end());
    // frames whose flow is not followed still show the scene's contrast: the fit run's
    let frame_images: &[crate::events::Frame] = if frames_not_followed {
        &input.frames[..input.frames.partition_point(|f| f.t <= blocks.fit_end())]
    } else {
        &[]
    };
    crate::estimate::eppps::estimate(
        &EpppsInput {
            sensor: input.sensor,
            events: &fit_events,
            frames: None,
            response_known: false,
            offset_fitted: false,
            excluded: input.excluded,
            frame_images,
        },
        &EpppsOptions {
            seed: options.seed,
            ..EpppsOptions::default()
        },
        &|_, _| {},
    )
    .map_err(|e| format!("estimate eppps on the fit run: {}", e.problem))
}
