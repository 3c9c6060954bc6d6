//! `estimate aps`: contrast thresholds from a recording's grey (APS) frames, two independent
//! ways, then combined (Stoffregen et al. 2020, Sec. 3.1, made automatic):
//!
//! 1. event timing ([`super::timing`]): per-pixel threshold samples from the log change
//!    between consecutive events of a pixel, measured on the frames interpolated along the
//!    optical flow; gives the maps and the frozen mismatch `ct_sigma`;
//! 2. re-simulation ([`super::resim`]): the frames, upsampled along the flow, are simulated
//!    with the thresholds whose counts match the real ones region by region.
//!
//! Each estimate's interval includes its systematic error, measured: the change of the
//! estimate when only every 2nd or 3rd frame is used (extrapolated to infinite frame rate,
//! [`super::interval`]), and for event timing the bias found by running the estimator on a
//! simulation of the same frames with known thresholds (and the recording's own timestamp
//! grid). The least-squares fit of Wang et al. (ACRA 2019, [`super::lsq`]) cross-checks
//! the maps and gives a third, timing-free global value.
//!
//! Interpolating frames along the flow misses part of the scene's change between them
//! (occlusions, rotation, fine texture), at any frame rate: event timing fits its samples
//! against their events' distance from the frames and reads the thresholds at the frames
//! ([`super::timing::model`]); the re-simulation, whose counts come from the same
//! interpolated frames, gets back the share the timing found missing, and keeps half that
//! correction in its interval.
//!
//! The frames' log offset `b` in `ln(DN + b)` is fitted by event timing where its samples
//! stop depending on brightness; a photoreceptor lag pushes that fit up, and counts hardly
//! see a lag, so the re-simulation checks it: where its dark cells disagree with its bright
//! ones, the offset the counts give joins the thresholds' systematic, and replaces the
//! timing's where the timing finds a lag ([`count_offset`]).

use super::frames::{FrameOptions, PreparedFrames};
use super::resim::{Cells, Intervals, Resimulation};
use super::timing::{ThresholdMaps, TimingEstimate, TimingOptions};
use super::{CtEstimate, EstimateError, Progress, quantise, timestamp_grid};
use crate::events::{EventChunk, Frame, Sensor, TimeUs};
use crate::hint::{Analysis, Hint, Text};
use crate::sim::log_response::LogMap;
use crate::sim::{PixelParams, Sample};
use report::{Findings, assemble, blocks_assumption, resimulation_report, timing_report};
use serde_json::json;

mod count_offset;
mod report;

use super::photoreceptor;
pub use super::photoreceptor::SlowPhotoreceptor;

/// Settings of `estimate aps`.
#[derive(Clone, Debug)]
pub struct ApsOptions {
    pub log_map: LogMap,
    /// A description of the log response, for the assumptions.
    pub log_response_name: String,
    /// Whether a pure `ln(DN + b)` may replace `log_map` where it explains the events
    /// better (false when the user named the response).
    pub choose_response: bool,
    pub frames: FrameOptions,
    pub timing: TimingOptions,
    /// The exposure, where the file gives none (the user's setting).
    pub exposure_us: Option<TimeUs>,
    /// Shift to add to the frames' times, seconds; `None`: found from the data
    /// ([`super::align`]).
    pub frame_time_offset_s: Option<f64>,
    /// DN to add to the frames before the log (a subtracted black level); `None`: estimate
    /// it where the events constrain it ([`super::timing`]: thresholds that do not depend on
    /// brightness).
    pub frame_offset_dn: Option<f64>,
    /// Memory for the upsampled frames of the re-simulation, bytes.
    pub max_upsampled_bytes: usize,
    /// Seed of every simulation.
    pub seed: u64,
}

impl Default for ApsOptions {
    fn default() -> Self {
        Self {
            log_map: LogMap::new(crate::sim::LogResponse::V2e, 0.001),
            log_response_name: "v2e lin-log: ln(DN) above 20 DN, linear below".into(),
            choose_response: true,
            frames: FrameOptions::default(),
            timing: TimingOptions::default(),
            exposure_us: None,
            frame_time_offset_s: None,
            frame_offset_dn: None,
            max_upsampled_bytes: 768 << 20,
            seed: 20_200_823,
        }
    }
}

/// What `estimate aps` reads.
pub struct ApsInput<'a> {
    pub sensor: Sensor,
    /// Time-sorted events of the frames' time span.
    pub events: &'a EventChunk,
    /// Grey frames, time-sorted, one size (the sensor's).
    pub frames: &'a [Frame],
    /// Pixels to leave out (outside a region of interest, masked).
    pub excluded: &'a [bool],
    /// Spans between blocks of frames read from a longer recording whose events were not
    /// read (empty: read whole). See [`PreparedFrames::unread`].
    pub unread: &'a [(TimeUs, TimeUs)],
}

/// The estimate and the per-pixel maps.
pub struct ApsResult {
    pub estimate: CtEstimate,
    pub maps: ThresholdMaps,
    /// The share of each threshold (ON, OFF) the frames' interpolation took from the event
    /// timing's samples ([`super::timing::PolarityEstimate::interpolation_share`]): what a
    /// method matching counts of the interpolated frames misses.
    pub interpolation_share: [f64; 2],
    /// The frames' log offset the thresholds were read at, DN, and the offsets their
    /// systematic error spans (the timing's, or the counts' where they disagree:
    /// [`count_offset::reconcile`]).
    pub frame_offset_dn: (f32, (f32, f32)),
    /// Where a polarity gave no offset, each threshold (ON, OFF) at the ends of the
    /// offset's range (reaching down to no offset) over the value, lower first
    /// ([`super::timing::PolarityEstimate::offset_reach`]); `[1, 1]` otherwise.
    pub offset_reach: [[f64; 2]; 2],
    /// The memorised level's drift the event timing measured (leak's signature in the
    /// events' timing: ON events early, OFF events late).
    pub leak_drift: super::timing::Drift,
    /// Whether each polarity's (ON, OFF) event-timing samples show no threshold peak above
    /// the noise ([`super::timing::peak::Peak::stands_out`]): its events are mostly noise,
    /// and its threshold is withheld.
    pub noise_polarities: [bool; 2],
}

/// The fewest usable frame intervals the frame-based thresholds rest on.
pub(crate) const MIN_USED_INTERVALS: usize = 3;

/// The support window of the re-simulation counts: a few pixel-crossing times of the
/// recording's typical motion (10-100 ms).
fn support_window_us(frames: &PreparedFrames) -> TimeUs {
    let mut speeds: Vec<f64> = frames
        .intervals
        .iter()
        .filter(|i| i.used && i.t_end_s > i.t_start_s)
        .map(|i| i.motion_px / (i.t_end_s - i.t_start_s))
        .collect();
    if speeds.is_empty() {
        return 30_000;
    }
    speeds.sort_by(f64::total_cmp);
    let speed = speeds[speeds.len() / 2].max(1e-3);
    ((3.0 / speed) * 1e6).clamp(10_000.0, 100_000.0) as TimeUs
}

/// The timing and re-simulation estimates of one set of frames.
struct Pass {
    timing: TimingEstimate,
    resim: Option<super::resim::ResimEstimate>,
    interval_s: f64,
    /// The re-simulation's cells and the recording's counts in them.
    cells: Cells,
    real: super::resim::Counts,
}

/// The timing and re-simulation estimates of `frames`, with `runs` their frames upsampled
/// along the flow ([`PreparedFrames::upsample_runs`]).
fn run_pass(
    input: &ApsInput,
    excluded: &[bool],
    frames: &PreparedFrames,
    runs: &[Vec<Sample>],
    options: &ApsOptions,
    start: Option<(f64, f64, f64)>,
) -> Result<Pass, EstimateError> {
    let timing = super::timing::estimate(input.events, frames, input.sensor, excluded, &options.timing)
        .ok_or_else(|| {
            EstimateError::new(
                "too few events between consecutive frames to measure thresholds (fewer than 10 pixels with a sample of each polarity)",
                Text::from("use a longer or busier part of the recording")
                    .aside(Hint::TimeWindow)
                    .words(", or use ")
                    .name(Hint::Analysis(Analysis::Eppps)),
            )
        })?;
    let (cp, cn, sigma) = start.unwrap_or((timing.on.ct, timing.off.ct, simulated_sigma(&timing)));
    let cells = Cells::new(
        Intervals::of_frames(frames, input.sensor),
        input.sensor,
        excluded,
        support_window_us(frames),
        input.events,
    );
    let real = cells.count(input.events);
    let resim = Resimulation::new(
        runs,
        (frames.width, frames.height),
        &cells,
        &real,
        timestamp_grid(input.events),
        frames.log_map,
    );
    let resim = super::resim::fit(&resim, (cp, cn), sigma).ok();
    let used: Vec<f64> = frames
        .intervals
        .iter()
        .filter(|i| i.used)
        .map(|i| i.t_end_s - i.t_start_s)
        .collect();
    let interval_s = used.iter().sum::<f64>() / used.len().max(1) as f64;
    Ok(Pass {
        timing,
        resim,
        interval_s,
        cells,
        real,
    })
}

/// Estimates the contrast thresholds of `input` from its frames, in stages: the frames
/// prepared and checked; the full frames' pass (event timing and re-simulation), its
/// frames' offset checked against the counts, with the self-calibration's simulation; the frame-time alignment's systematic; the passes over
/// every 2nd and 3rd frame; the self-calibration; each estimator's value with its
/// interval; their combination and the report.
pub fn estimate(
    input: &ApsInput,
    options: &ApsOptions,
    progress: Progress,
) -> Result<ApsResult, EstimateError> {
    progress("frames: selection and optical flow", 0.0);
    let mut checked = checked_frames(input, options)?;

    progress("event timing and re-simulation", 0.2);
    let mut first = FullPass::run(input, &mut checked, options, progress)?;
    let calibration_events = first.calibration_events.take();

    progress("frame-rate check (every 2nd and 3rd frame)", 0.5);
    let subsampled = subsampled_passes(
        input,
        &checked.excluded,
        &checked.frames,
        options,
        &first.full,
    );
    let mut passes = vec![(1usize, &first.full)];
    passes.extend(subsampled.iter().map(|(s, p)| (*s, p)));

    // self-calibration of the timing estimator on a simulation of the same frames
    progress("self-calibration on a simulation of the frames", 0.8);
    let (estimators, sigma_bias) = estimator_reports(
        input,
        &mut checked,
        options,
        &first,
        calibration_events,
        &passes,
    );
    let sigma_series = report::series(&passes, |p| {
        Some(p.timing.spread().sigma).filter(|s| s.is_finite())
    });
    let result = first.finish(input, checked, estimators, (sigma_bias, sigma_series));
    progress("done", 1.0);
    Ok(result)
}

/// The full frames' pass, and what is found along with it: the frames' offset from the
/// counts, the self-calibration's simulated events, the photoreceptor check and the
/// frame-time alignment's systematic.
struct FullPass {
    full: Pass,
    grid: Option<(TimeUs, TimeUs)>,
    offset_from_counts: Option<count_offset::FromCounts>,
    spread: super::timing::spread::Spread,
    sigma: f64,
    calibration_events: Option<EventChunk>,
    slow: Option<Slow>,
    alignment_error: (f64, f64),
}

impl FullPass {
    /// Runs the full frames' pass (event timing and re-simulation, the frames upsampled
    /// once for it and the self-calibration's simulation), checks its offset against the
    /// counts, then the photoreceptor and the frame-time alignment.
    fn run(
        input: &ApsInput,
        checked: &mut Checked,
        options: &ApsOptions,
        progress: Progress,
    ) -> Result<Self, EstimateError> {
        let (excluded, frames) = (&checked.excluded, &mut checked.frames);
        let mut runs = frames.upsample_runs(0.5, options.max_upsampled_bytes);
        let mut full = run_pass(input, excluded, frames, &runs, options, None)?;
        let grid = timestamp_grid(input.events);
        let offset_from_counts = count_offset::offset_from_counts(
            input,
            excluded,
            frames,
            options,
            (&mut runs, &mut full),
            checked.offset_report.as_ref(),
            grid,
        )?;
        checked.assumptions.extend(
            offset_from_counts
                .as_ref()
                .map(|c| count_offset::assumption(c, frames)),
        );
        let spread = full.timing.spread();
        let sigma = simulated_sigma(&full.timing);
        let calibration_events =
            calibration_events(&runs, frames, options, &full.timing, sigma, grid);
        progress("does the photoreceptor follow the frames", 0.45);
        let slow = slow_photoreceptor(input, excluded, frames, (&runs, &full), sigma, grid);
        drop(runs);
        let alignment_error =
            alignment_systematic(input, excluded, frames, options, checked.alignment.as_ref());
        Ok(Self {
            full,
            grid,
            offset_from_counts,
            spread,
            sigma,
            calibration_events,
            slow,
            alignment_error,
        })
    }

    /// The result: the least-squares cross-check, the estimators combined with the
    /// findings ([`assemble`]), and the full pass's maps.
    fn finish(
        self,
        input: &ApsInput,
        checked: Checked,
        estimators: Vec<super::EstimatorReport>,
        (sigma_bias, sigma_series): (f64, Vec<super::interval::FrameRatePoint>),
    ) -> ApsResult {
        let Self {
            full,
            spread,
            offset_from_counts,
            slow,
            ..
        } = self;
        let frames = &checked.frames;
        // the least-squares cross-check
        let lsq = super::lsq::fit(
            input.events,
            frames,
            input.sensor,
            &checked.excluded,
            Some((&full.timing.maps.ct_on, &full.timing.maps.ct_off)),
        );
        let estimate = assemble(
            estimators,
            checked.assumptions,
            frames,
            &full,
            Findings {
                spread,
                sigma_bias,
                sigma_series,
                sigma_offset_systematic: full.timing.sigma_offset_systematic,
                lsq,
                alignment: json!(checked.alignment),
                offset: checked.offset_report,
                offset_from_counts: offset_from_counts.map(|c| c.found),
                other_response: checked.other_response,
                slow,
            },
        );
        let offset_reach = full.timing.offset_reach();
        ApsResult {
            estimate,
            interpolation_share: [
                full.timing.on.interpolation_share,
                full.timing.off.interpolation_share,
            ],
            maps: full.timing.maps,
            frame_offset_dn: (frames.offset, frames.offset_range),
            offset_reach,
            noise_polarities: [&full.timing.on, &full.timing.off]
                .map(|p| p.peak.is_some_and(|peak| !peak.stands_out())),
            leak_drift: full.timing.drift,
        }
    }
}

/// The estimators' reports: event timing's, corrected by the self-calibration's bias
/// (whose spread bias is returned too), and the re-simulation's where it ran, with the
/// assumptions they add.
fn estimator_reports(
    input: &ApsInput,
    checked: &mut Checked,
    options: &ApsOptions,
    first: &FullPass,
    calibration_events: Option<EventChunk>,
    passes: &[(usize, &Pass)],
) -> (Vec<super::EstimatorReport>, f64) {
    let calibrating = Calibrating {
        input,
        excluded: &checked.excluded,
        options,
        sigma: first.sigma,
        alignment: checked.alignment.as_ref(),
        grid: first.grid,
    };
    let assumptions = &mut checked.assumptions;
    let bias = calibrating.bias(
        &mut checked.frames,
        &first.full,
        calibration_events,
        assumptions,
    );
    assumptions.extend(blocks_assumption(&first.full.timing));
    let mut estimators = vec![timing_report(passes, bias, first.alignment_error)];
    if let Some(r) = &first.full.resim {
        let (report, note) = resimulation_report(passes, r);
        assumptions.extend(note);
        estimators.push(report);
    }
    (estimators, bias.2)
}

/// The frames prepared for estimation and checked to measure thresholds, with the pixels
/// left out and the assumptions so far.
struct Checked {
    excluded: Vec<bool>,
    frames: PreparedFrames,
    alignment: Option<super::align::Alignment>,
    offset_report: Option<super::timing::Offset>,
    other_response: Option<super::timing::OtherResponse>,
    assumptions: Vec<String>,
}

/// Hot pixels left out, the frames prepared ([`prepare`]), and refused where they show a
/// static scene or too few usable intervals.
fn checked_frames(input: &ApsInput, options: &ApsOptions) -> Result<Checked, EstimateError> {
    let mut assumptions = Vec::new();
    let (excluded, hot) = super::exclude_hot_pixels(input.events, input.sensor, input.excluded);
    if hot > 0 {
        assumptions.push(format!("{hot} hot pixels left out"));
    }
    let Prepared {
        frames,
        alignment,
        offset: offset_report,
        other_response,
        assumptions: prepared_notes,
    } = prepare(input, &excluded, options)?;
    assumptions.extend(prepared_notes);
    let change = super::dynamics::from_frames(&frames, 0.5).map_or(0.0, |d| d.log_change_rate);
    if change < super::dynamics::STATIC_CHANGE_RATE {
        return Err(EstimateError::new(
            format!(
                "the frames show a static scene (log intensity changes by {change:.4} per pixel per second): nothing crosses a threshold, so the events are noise and do not measure thresholds"
            ),
            Text::from("use a part of the recording where the scene moves")
                .aside(Hint::TimeWindow)
                .words("; measure the noise with ")
                .name(Hint::Analysis(Analysis::Fit))
                .words(" or ")
                .name(Hint::Analysis(Analysis::Stats)),
        ));
    }
    let used = frames.intervals.iter().filter(|i| i.used).count();
    if used < MIN_USED_INTERVALS {
        return Err(too_few_intervals(used, frames.intervals.len()));
    }
    if let Some((followed, too_fast)) = frames.motion_outruns_flow() {
        return Err(motion_outruns_frames(followed, too_fast));
    }
    assumptions.extend(frame_assumptions(input, options, &frames, used));
    Ok(Checked {
        excluded,
        frames,
        alignment,
        offset_report,
        other_response,
        assumptions,
    })
}

/// The error of frames with fewer than [`MIN_USED_INTERVALS`] usable intervals, `used` of
/// `total`.
fn too_few_intervals(used: usize, total: usize) -> EstimateError {
    let why = if used == total {
        format!("the recording (or the part read) has only {total} frame intervals")
    } else {
        format!(
            "only {used} of {total} frame intervals can be used (the flow between the frames fails: motion too fast for the frame rate, or frames too dark or blurred)"
        )
    };
    EstimateError::new(
        format!(
            "{why}; thresholds from frames need {MIN_USED_INTERVALS} at least, or they rest on a single stretch of motion whose flow nothing checks"
        ),
        if used == total {
            "read a longer part of the recording; without enough frames estimate with the eppps or screen method"
        } else {
            "use a recording, or a part of one, with more frames per unit of motion; without usable frames estimate with the eppps or screen method"
        },
    )
}

/// The error of frames whose motion outruns the optical flow
/// ([`PreparedFrames::motion_outruns_flow`]): the intervals it follows are not taken to
/// stand for the rest. Coverage draws 4004 and 4077 (399 and 324 px/s; the flow follows 3
/// intervals of each and moves too far on 68 and 32) read OFF 0.55 [0.33, 0.78] for 0.78
/// and ON 0.32 [0.22, 0.43] for 0.43 from the three it followed.
fn motion_outruns_frames(followed: usize, too_fast: usize) -> EstimateError {
    EstimateError::new(
        format!(
            "the motion outruns the frames: the optical flow moves too far on {too_fast} frame intervals and follows only {followed}, which may be the few it happened to match or a periodic pattern aliased to a smaller step; thresholds from them are not taken to stand for the recording"
        ),
        Text::from("use a recording with more frames per unit of motion, or ")
            .name(Hint::Analysis(Analysis::Eppps)),
    )
}

/// What the frames are taken to be: their log response, times and exposure, and the scene
/// moving along the flow between them.
fn frame_assumptions(
    input: &ApsInput,
    options: &ApsOptions,
    frames: &PreparedFrames,
    used: usize,
) -> [String; 3] {
    let exposure = super::frames::exposure_of(input.frames, options.exposure_us);
    [
        format!(
            "log response: {}, of the frame value plus the frames' log offset b (DN + b; b as its own line says)",
            if frames.log_map.response() == options.log_map.response() {
                options.log_response_name.as_str()
            } else {
                "a pure ln(DN + b), chosen from the events' timing (its own line says why)"
            }
        ),
        format!(
            "frames: {} of {} intervals used; frame times are exposure midpoints (as the file gives them); {}",
            used,
            frames.intervals.len(),
            match exposure {
                Some(e) => format!("exposure {:.3} ms, treated as instantaneous (motion during it blurs frames slightly)", e as f64 / 1e3),
                None => "exposure unknown (give the frame exposure where it is known); frames treated as instantaneous".into(),
            }
        ),
        "between frames the scene moves along the optical flow (pyramidal Lucas-Kanade on log frames); frames are linear in intensity up to the offset b (no gamma: a gamma scales every log change alike, so it cannot be told from the thresholds by events and frames; frames encoded with gamma g give thresholds 1/g times the true ones)".into(),
    ]
}

/// The frame-time alignment's precision as a systematic error of event timing (ON, OFF):
/// half the change of the thresholds between the frames shifted by its precision either
/// way; 0 without an alignment found, or where a shifted estimate fails.
fn alignment_systematic(
    input: &ApsInput,
    excluded: &[bool],
    frames: &mut PreparedFrames,
    options: &ApsOptions,
    alignment: Option<&super::align::Alignment>,
) -> (f64, f64) {
    let Some(a) = alignment.filter(|a| a.precision_s > 0.0) else {
        return (0.0, 0.0);
    };
    let precision = (a.precision_s * 1e6).round() as TimeUs;
    let mut at = |shift: TimeUs| {
        frames.shift_times(shift);
        // the thresholds alone: their errors are not needed here
        let t = super::timing::thresholds(
            input.events,
            frames,
            input.sensor,
            excluded,
            &options.timing,
        );
        frames.shift_times(-shift);
        t
    };
    match (at(precision), at(-precision)) {
        (Some(a), Some(b)) => (
            0.5 * (a.ct_on - b.ct_on).abs(),
            0.5 * (a.ct_off - b.ct_off).abs(),
        ),
        _ => (0.0, 0.0),
    }
}

/// The passes over every 2nd and every 3rd frame (those that can be made), the
/// re-simulation started at the full pass's thresholds.
fn subsampled_passes(
    input: &ApsInput,
    excluded: &[bool],
    frames: &PreparedFrames,
    options: &ApsOptions,
    full: &Pass,
) -> Vec<(usize, Pass)> {
    let start = full
        .resim
        .as_ref()
        .map(|r| (r.ct_on, r.ct_off, simulated_sigma(&full.timing)));
    [2usize, 3]
        .iter()
        .filter_map(|&step| {
            let f = frames.every(step, &options.frames)?;
            let runs = f.upsample_runs(0.5, options.max_upsampled_bytes);
            run_pass(input, excluded, &f, &runs, options, start)
                .ok()
                .map(|p| (step, p))
        })
        .collect()
}

/// Frames ready for estimation, and what was found about them.
pub struct Prepared {
    pub frames: PreparedFrames,
    pub alignment: Option<super::align::Alignment>,
    pub offset: Option<super::timing::Offset>,
    /// The log response not chosen, where the events cannot rule it out.
    pub other_response: Option<super::timing::OtherResponse>,
    pub assumptions: Vec<String>,
}

/// Prepares `input.frames` as every frame-based method needs them: selection and flow
/// ([`PreparedFrames`]), the frame-time alignment ([`super::align`]) and the log offset
/// `b` of `ln(DN + b)` ([`super::timing`]), each unless `options` sets it.
pub fn prepare(
    input: &ApsInput,
    excluded: &[bool],
    options: &ApsOptions,
) -> Result<Prepared, EstimateError> {
    let mut assumptions = Vec::new();
    let mut frames = PreparedFrames::new(
        input.frames,
        &input.events.t,
        input.unread,
        options.log_map,
        &options.frames,
    )?;
    let alignment = aligned(input, excluded, options, &mut frames, &mut assumptions);
    let (offset, other_response) =
        offset_found(input, excluded, options, &mut frames, &mut assumptions);
    Ok(Prepared {
        frames,
        alignment,
        offset,
        other_response,
        assumptions,
    })
}

/// The frames shifted to the events' clock: by the offset `options` gives, or where the
/// events agree best with them ([`super::align`]); the alignment found, and its assumption.
fn aligned(
    input: &ApsInput,
    excluded: &[bool],
    options: &ApsOptions,
    frames: &mut PreparedFrames,
    assumptions: &mut Vec<String>,
) -> Option<super::align::Alignment> {
    if let Some(shift) = options.frame_time_offset_s {
        frames.shift_times((shift * 1e6).round() as TimeUs);
        assumptions.push(format!(
            "frame times shifted by {:.3} ms (the frame time offset given)",
            shift * 1e3
        ));
        return None;
    }
    let found = super::align::align(
        input.events,
        frames,
        input.sensor,
        excluded,
        &options.timing,
    );
    if let Some(a) = &found {
        frames.shift_times((a.shift_s * 1e6).round() as TimeUs);
        assumptions.push(format!(
            "frame times shifted by {:+.2} ms (+- {:.2} ms), where the events agree best with the frames (sample spread {:.3} -> {:.3}); a frame time offset given overrides it",
            a.shift_s * 1e3,
            a.precision_s * 1e3,
            a.spread_unshifted,
            a.spread_aligned
        ));
    }
    found
}

/// The frames' log offset `b` of `ln(DN + b)` and their response: as `options` gives, or
/// fitted to the events' timing ([`super::timing`]); the offset found, the response not
/// chosen where the events cannot rule it out, and their assumptions.
fn offset_found(
    input: &ApsInput,
    excluded: &[bool],
    options: &ApsOptions,
    frames: &mut PreparedFrames,
    assumptions: &mut Vec<String>,
) -> (
    Option<super::timing::Offset>,
    Option<super::timing::OtherResponse>,
) {
    if let Some(o) = options.frame_offset_dn {
        frames.offset = o as f32;
        frames.offset_range = (o as f32, o as f32);
        assumptions.push(format!("frames offset by {o} DN before the log (as given)"));
        return (None, None);
    }
    let fitting = TimingOptions {
        fit_offset: true,
        choose_response: options.choose_response,
        ..options.timing.clone()
    };
    // the response and the offset alone: the thresholds' errors are not needed here
    let found = super::timing::thresholds(input.events, frames, input.sensor, excluded, &fitting);
    let mut other_response = None;
    if let Some(t) = &found {
        if t.log_map != frames.log_map {
            assumptions.push(format!("the frames' response: a pure ln(DN + b) explains the events' timing better than the lin-log response (its linear part below 20 DN){}; used throughout", if t.other_response.is_some() { ", though not beyond the pixels' noise: the thresholds the other gives are carried into the intervals" } else { "" }));
            frames.log_map = t.log_map;
        }
        let own = frames.offset;
        frames.offset = t.offset.offset_dn;
        frames.offset_range = t.offset.systematic_range;
        frames.offset_reached = t.offset.unconfirmed;
        let offset = match masked_by_slow_photoreceptor(input, excluded, frames, &t.offset, own) {
            Some((offset, why)) => {
                frames.offset = offset.offset_dn;
                frames.offset_range = offset.systematic_range;
                frames.offset_reached = offset.unconfirmed;
                assumptions.push(why);
                offset
            }
            None => {
                assumptions.push(offset_assumption(&t.offset));
                t.offset.clone()
            }
        };
        other_response = t.other_response.clone();
        return (Some(offset), other_response);
    }
    (None, other_response)
}

/// [`super::timing::Offset::source`] of a fitted offset that a photoreceptor slower than
/// the scene makes untrustworthy ([`masked_by_slow_photoreceptor`]).
pub const SLOW_MASKS_OFFSET: &str = "not determined: a photoreceptor slower than the scene";

/// The offset not determined where the timing fitted one but the events follow the frames
/// low-passed better than the frames themselves ([`photoreceptor::check`] on the frames at
/// the fitted offset): a photoreceptor whose time constant nears the time the light takes
/// to change, beyond what the timing's first-order lag term holds, makes dark pixels'
/// thresholds look larger as a too small offset would, and the fitted offset absorbs it
/// (IEBCS draw 15006, `tau` 25 ms at its median DN: the check found 5.6 Hz there, the
/// timing's lag term 64 Hz; the fitted b = 29 DN for a true 0 read ON 0.214 [0.151, 0.273]
/// for 0.321, b = 0 reads 0.283 [0.208, 0.358]). The frames' own offset `own` is kept and
/// the prior range spanned; with it the assumption. `None` where the offset stands.
fn masked_by_slow_photoreceptor(
    input: &ApsInput,
    excluded: &[bool],
    frames: &PreparedFrames,
    fitted: &super::timing::Offset,
    own: f32,
) -> Option<(super::timing::Offset, String)> {
    if fitted.source != "fitted" {
        return None;
    }
    let slow = photoreceptor::check(input.events, frames, excluded)?;
    let prior = super::timing::OFFSET_PRIOR;
    let range = (prior.0.min(own), prior.1.max(own));
    let why = format!(
        "the frames' log offset b in ln(DN + b) is not determined: the timing fitted b = {:.1} DN (95 % {} .. {}), but the events follow the frames low-passed at {:.1} Hz at their median DN better than the frames themselves ({:.1} standard errors), and a photoreceptor that slow makes dark pixels' thresholds look larger as a too small offset would; b = {own:.1} DN kept, and the thresholds' change over the prior range {:.0} .. {:.0} DN is in their intervals",
        fitted.offset_dn,
        offset_end(fitted.ci95[0]),
        offset_end(fitted.ci95[1]),
        slow.cutoff_at_median_dn_hz,
        slow.significance,
        range.0,
        range.1,
    );
    let offset = super::timing::Offset {
        offset_dn: own,
        ci95: [None, None],
        systematic_range: range,
        by_polarity: fitted.by_polarity,
        unconfirmed: false,
        source: SLOW_MASKS_OFFSET,
    };
    Some((offset, why))
}

/// The model event timing measured: its thresholds and mismatch, and the photoreceptor's
/// cutoff and the leak where they are significant (three standard errors), in the
/// simulator's terms (cutoff `cutoff_hz (DN + 20) / 275`, leak `leak_rate_hz * ct_on` per
/// second).
fn measured_model(timing: &TimingEstimate, sigma: f64) -> PixelParams {
    let mut params = PixelParams::ideal(timing.on.ct, timing.off.ct);
    if sigma > 0.0 {
        params.ct_sigma = Some(sigma);
    }
    let lag = &timing.lag;
    if let Some(f) = lag_resolved(lag) {
        params.cutoff_hz = Some(f * 275.0 / (lag.median_dn + 20.0));
    }
    let drift = &timing.drift;
    if drift.at_median_dn > 3.0 * drift.standard_error && timing.on.ct > 0.0 {
        params.leak_rate_hz = Some(drift.at_median_dn / timing.on.ct);
    }
    params
}

/// A photoreceptor much slower than the scene ([`photoreceptor::check`]), with the
/// thresholds the re-simulation finds when it simulates that cutoff (started from its
/// ideal thresholds times the check's ratios; `None` where it finds none).
pub(crate) struct Slow {
    pub(crate) found: SlowPhotoreceptor,
    pub(crate) thresholds: Option<[f64; 2]>,
}

fn slow_photoreceptor(
    input: &ApsInput,
    excluded: &[bool],
    frames: &PreparedFrames,
    (runs, full): (&[Vec<Sample>], &Pass),
    sigma: f64,
    grid: Option<(TimeUs, TimeUs)>,
) -> Option<Slow> {
    let found = photoreceptor::check(input.events, frames, excluded)?;
    let start = full
        .resim
        .as_ref()
        .map_or((full.timing.on.ct, full.timing.off.ct), |r| {
            (r.ct_on, r.ct_off)
        });
    let resim = Resimulation::new(
        runs,
        (frames.width, frames.height),
        &full.cells,
        &full.real,
        grid,
        frames.log_map,
    );
    let [ron, roff] = found.threshold_ratios;
    let [qon, qoff] = found.quantiser_thresholds;
    // from the estimators' thresholds scaled as the check asks, else from the check's own
    let thresholds = [(start.0 * ron, start.1 * roff), (qon, qoff)]
        .into_iter()
        .find_map(|start| {
            super::resim::fit_with(&resim, start, sigma, Some(found.cutoff_hz), 1).ok()
        })
        .map(|r| [r.ct_on, r.ct_off]);
    Some(Slow { found, thresholds })
}

/// The photoreceptor cutoff at the median DN (Hz) where the timing's lag is significant
/// (three standard errors) and slower than 1 kHz (faster, it is the frames' own timing
/// noise rather than a photoreceptor).
fn lag_resolved(lag: &super::timing::Lag) -> Option<f64> {
    lag.cutoff_hz_at_median_dn
        .filter(|&f| lag.tau_times_dn > 3.0 * lag.standard_error && f < 1000.0)
}

/// One end of an offset's interval in words: DN to one decimal, or `open`.
fn offset_end(end: Option<f32>) -> String {
    end.map_or("open".to_string(), |v| format!("{v:.1}"))
}

/// The offset, in words for the assumptions.
fn offset_assumption(o: &super::timing::Offset) -> String {
    let side = offset_end;
    match o.source {
        "fitted" => format!(
            "frames read as ln(DN + b), b = {:.1} DN (95 % {} .. {}; the ON samples alone give {}, the OFF samples {}): the offset at which thresholds do not depend on brightness; the thresholds' change over {:.1} .. {:.1} DN (the interval, both polarities' offsets, and the offset -+ their difference within the prior range {:.0} .. {:.0} DN: anything else that depends on brightness moves the fitted offset, and shows as the two disagreeing{}) is in their intervals",
            o.offset_dn,
            side(o.ci95[0]),
            side(o.ci95[1]),
            o.by_polarity[0].map_or("none".into(), |b| format!("{b:.1}")),
            o.by_polarity[1].map_or("none".into(), |b| format!("{b:.1}")),
            o.systematic_range.0,
            o.systematic_range.1,
            super::timing::OFFSET_PRIOR.0,
            super::timing::OFFSET_PRIOR.1,
            if o.unconfirmed {
                "; a polarity that gives no offset anywhere in the search makes the offset a compromise, not a measurement: the range reaches down to no offset, and the intervals reach the thresholds read at its ends"
            } else {
                ""
            },
        ),
        "not determined: the photoreceptor's lag" => format!(
            "the frames' log offset b in ln(DN + b) is not determined: the photoreceptor's lag (a bandwidth limit) makes dark pixels' thresholds look larger as a too small offset would; b = {:.1} DN kept, and the thresholds' change over the prior range {:.0} .. {:.0} DN is in their intervals",
            o.offset_dn, o.systematic_range.0, o.systematic_range.1
        ),
        "not determined: the fitted offset lies outside the range met in practice" => format!(
            "the frames' log offset b in ln(DN + b) is not determined: the offset at which thresholds stop depending on brightness lies outside the prior range {:.0} .. {:.0} DN (DVS-Voltmeter's real-sensor fits and DAVIS black levels), more likely an effect the timing model lacks (refractory delays, a nonlinear response) than a black level; b = {:.1} DN kept, and the thresholds' change over {:.1} .. {:.1} DN (prior and fitted) is in their intervals",
            super::timing::OFFSET_PRIOR.0,
            super::timing::OFFSET_PRIOR.1,
            o.offset_dn,
            o.systematic_range.0,
            o.systematic_range.1
        ),
        super::timing::NOT_BOUNDED => format!(
            "the frames' log offset b in ln(DN + b) is not determined: the 95 % interval of the offset at which the thresholds stop depending on brightness spans the prior range on both sides (the frames' brightness range or the events are too few to bound it; below 20 DN the lin-log response's linear part hides what an offset does); b = {:.1} DN kept, and the thresholds' change over the prior range {:.0} .. {:.0} DN is in their intervals",
            o.offset_dn, o.systematic_range.0, o.systematic_range.1
        ),
        _ => format!(
            "the frames' log offset b in ln(DN + b) is not determined (no offset makes the thresholds independent of brightness); b = {:.1} DN kept, and the thresholds' change over the prior range {:.0} .. {:.0} DN is in their intervals",
            o.offset_dn, o.systematic_range.0, o.systematic_range.1
        ),
    }
}

/// The events of the self-calibration: `runs` (the frames upsampled along the flow)
/// simulated with the model the timing found (and `sigma`), stamped on the recording's
/// timestamp grid. `None` when the simulation fails.
fn calibration_events(
    runs: &[Vec<Sample>],
    frames: &PreparedFrames,
    options: &ApsOptions,
    timing: &TimingEstimate,
    sigma: f64,
    grid: Option<(TimeUs, TimeUs)>,
) -> Option<EventChunk> {
    let mut params = super::resim::read_as_frames(&measured_model(timing, sigma), frames.log_map);
    params.seed = Some(options.seed);
    let mut simulated = super::resim::simulate(runs, frames.width, frames.height, &params).ok()?;
    if let Some(grid) = grid {
        quantise(&mut simulated, grid);
    }
    Some(simulated)
}

/// The mismatch the re-simulation and the self-calibration simulate: the timing's combined
/// spread ([`super::timing::spread`]), or none where neither polarity determines it (the
/// simulations then have no mismatch, and the spread is reported as not determinable).
fn simulated_sigma(timing: &TimingEstimate) -> f64 {
    let sigma = timing.spread().sigma;
    if sigma.is_finite() { sigma } else { 0.0 }
}

/// What the self-calibration needs beside the frames and the full pass.
struct Calibrating<'a> {
    input: &'a ApsInput<'a>,
    excluded: &'a [bool],
    options: &'a ApsOptions,
    /// The measured threshold spread the simulation draws with.
    sigma: f64,
    alignment: Option<&'a super::align::Alignment>,
    grid: Option<(TimeUs, TimeUs)>,
}

impl Calibrating<'_> {
    /// The timing estimator's own bias (ON, OFF, spread) on `simulated`, a simulation of
    /// the same frames with the measured model ([`self_calibrate`]); none where it could
    /// not run, which `assumptions` then says (as it says the simulation's timestamp grid).
    fn bias(
        &self,
        frames: &mut PreparedFrames,
        full: &Pass,
        simulated: Option<EventChunk>,
        assumptions: &mut Vec<String>,
    ) -> (f64, f64, f64) {
        if let Some((period, _)) = self.grid {
            assumptions.push(format!(
                "timestamps are quantised to {period} us (events share stamps: a simulator's frames); the self-calibration simulation is quantised alike"
            ));
        }
        let shift = self
            .alignment
            .map_or(0, |a| (a.shift_s * 1e6).round() as TimeUs);
        let calibration = simulated.and_then(|simulated| {
            self_calibrate(
                self.input,
                self.excluded,
                frames,
                self.options,
                &full.timing,
                self.sigma,
                simulated,
                (shift, self.alignment.is_some()),
            )
        });
        if calibration.is_none() {
            assumptions.push("the self-calibration (a simulation of these frames with the measured model) could not be run: the event timing's thresholds and spread are not corrected for the method's own bias, and no bias is in their intervals".into());
        }
        calibration.unwrap_or((0.0, 0.0, 0.0))
    }
}

/// The timing estimator's bias, found by running the same pipeline on `simulated`, a
/// simulation of the same frames with the thresholds `timing` found
/// ([`calibration_events`]): the simulation sees the frames where the alignment put them,
/// the estimator starts from the file's frame times and aligns again (when the recording
/// was aligned), as it did on the real events. Returns (ON bias, OFF bias, sigma bias);
/// `frames` are left as they were.
#[allow(clippy::too_many_arguments)]
fn self_calibrate(
    input: &ApsInput,
    excluded: &[bool],
    frames: &mut PreparedFrames,
    options: &ApsOptions,
    timing: &TimingEstimate,
    sigma: f64,
    simulated: EventChunk,
    (shift, realign): (TimeUs, bool),
) -> Option<(f64, f64, f64)> {
    // back to the file's frame times, then the same alignment as for the real events
    frames.shift_times(-shift);
    let again_shift = if realign {
        super::align::align(&simulated, frames, input.sensor, excluded, &options.timing)
            .map_or(0, |a| (a.shift_s * 1e6).round() as TimeUs)
    } else {
        shift
    };
    frames.shift_times(again_shift);
    let again =
        super::timing::estimate(&simulated, frames, input.sensor, excluded, &options.timing);
    frames.shift_times(shift - again_shift);
    let again = again?;
    // NaN where the simulation's spread is not determined: no bias is then known
    let sigma_again = again.spread().sigma;
    Some((
        again.on.ct - timing.on.ct,
        again.off.ct - timing.off.ct,
        sigma_again - sigma,
    ))
}
