//! `estimate eppps`: the contrast threshold from how many events a recording makes for the
//! motion it shows (Stoffregen et al., ECCV 2020, Sec. 3.1 and Fig. 2: events per pixel per
//! second against simulated scenes), with its two mismatches corrected and its prior made
//! explicit:
//!
//! 1. the recording ([`recording`]): events per pixel of scene travel, noise taken out, per
//!    polarity, over the pixels that fired (events-only) or every reliable pixel (frames):
//!    dividing by travel removes the speed of the motion, counting only pixels that fired
//!    removes blank and static parts of the view;
//! 2. the calibration ([`calibration`], [`scans`]): ideal pixels along line scans with the
//!    recording's own travel and directions, through the recording's frames when it has them
//!    (its contrast measured, through the log response the events' timing measured, or
//!    through both ends of what sensors use where it does not, [`calibration::Response`])
//!    and otherwise through natural images ([`prior`]) -- or, where the recording has
//!    frames whose flow cannot be followed, through those frames' images scanned as the
//!    photographs are ([`prior::frame_images`]) -- at 31
//!    thresholds from 0.03 to 9.5; without frames each image is read at the recording's
//!    own sharpness, the blur at which its scans burst as often as the recording's events
//!    do ([`sharpness`]);
//! 3. the threshold at which the scans make the recording's rate, per polarity; without
//!    frames one per prior image and log-response floor, combined in their logarithm, and the
//!    spread between them is the prior's share of the interval (events alone cannot separate
//!    a scene's contrast from the threshold). The interval also holds the recording's sampling error (bootstrap
//!    over 32 px patches) and the flow's precision.

mod balance;
pub mod calibration;
pub mod prior;
pub mod recording;
pub mod scans;
pub mod sharpness;
pub mod still;

use super::interval::{Measured, z95};
use super::{CtEstimate, Determinable, EstimateError, EstimatorReport, Progress};
use crate::estimate::frames::PreparedFrames;
use crate::estimate::photoreceptor::{self, SlowPhotoreceptor};
use crate::events::{EventChunk, Sensor};
use rayon::prelude::*;
use recording::RecordingRates;
use scans::{CurvePoint, Inverted, ScanPixel, Side, curve, invert, log_slope, threshold_grid};
use serde::Serialize;
use serde_json::json;
use sharpness::{PriorTag, Reading, Selection};

/// The method's own systematic error with frames, in ln C: what ideal-pixel line scans
/// along the frames' flow miss of a real pixel's events (flow and exposure blur of the
/// frames, where scans start, how polarities share the turns, and the sensor effects the
/// scans leave out: bandwidth and refractory period thin the events, leak and noise add to
/// them) beyond the interval's measured terms. Measured on the coverage study's draws
/// (`benches/coverage/eppps-systematic-2026-11-29`, its `systematic.py`: seeds 1-100 and
/// 1001-1080, 262 polarity-cases of random scenes, brightness, speed and effects read
/// through their frames): the smallest term at which 95 % of them are covered (0.10:
/// 72.1 %, 0.20: 87.4 %, 0.30: 92.0 %, 0.37: 95.4 %); on 80 draws it was not measured on
/// (seeds 2001-2080) it covers Cp / Cn 89.7 / 89.6 %. The errors have heavy tails (median
/// |ln error| 0.14, 90th percentile 0.59), and they are not concentrated where the data
/// show a cause: draws whose events lag their frames (a slow photoreceptor's signature)
/// need 0.26 in the first study, the others 0.29; draws without an effect that changes the
/// counts 0.26; strongly asymmetric thresholds (|ln(Cn/Cp)| > 0.7) 0.37, the others 0.33.
/// So the term is one, in every interval with frames of 20 DN or more (dimmer frames carry
/// [`METHOD_LN_SYSTEMATIC_DIM`]). It replaces 0.10 measured on six clean polarity-cases.
pub const METHOD_LN_SYSTEMATIC: f64 = 0.37;

/// The method's own systematic error without frames, in ln C, beside the prior's spread
/// (which dominates there): the 0.10 of the six clean polarity-cases; with the prior's
/// prediction interval it covered 89.7 / 92.1 % (Cp / Cn) of 60 draws read without frames
/// (`benches/coverage/eppps-2026-11-27`).
pub const METHOD_LN_SYSTEMATIC_WITHOUT_FRAMES: f64 = 0.10;

/// Frames whose median is below this many DN show a dim scene (`estimate eppps` with
/// frames, [`METHOD_LN_SYSTEMATIC_DIM`]). A photoreceptor's cutoff is proportional to its
/// photocurrent (Lichtsteiner, Posch & Delbruck, JSSC 2008): in the dark it falls to a few
/// hertz, slower than a moving edge, and thins the events the ideal scans count, while
/// leak and noise weigh more against the fewer events of a dim scene. The same 20 DN
/// bounds the scope of the reading without frames (`benches/coverage/eppps-scope-2026-12-04`).
pub const DIM_FRAMES_DN: f64 = 20.0;

/// The method's systematic error with frames whose median is under [`DIM_FRAMES_DN`], in
/// ln C, in place of [`METHOD_LN_SYSTEMATIC`]: the smallest term that covers 95 % of such
/// polarity-cases of the coverage study (`benches/coverage/eppps-dim-frames-2026-12-05`:
/// with 0.37 the dim ones were covered 79 %, the others 94 %, of 404 polarity-cases read
/// through their frames; their misses read 2-4 times high, a photoreceptor slowed by the
/// dark).
pub const METHOD_LN_SYSTEMATIC_DIM: f64 = 0.46;

/// The frames' median brightness where it is under [`DIM_FRAMES_DN`] (a dim scene).
fn dim_frames_dn(frames_median_dn: Option<f64>) -> Option<f64> {
    frames_median_dn.filter(|&dn| dn < DIM_FRAMES_DN)
}

/// The method systematic of an estimate from `calibrations` (with frames or a prior) of a
/// recording whose frames' median brightness is `frames_median_dn`.
fn method_systematic(
    calibrations: &[Calibration],
    frames_median_dn: Option<f64>,
    frame_images: bool,
) -> f64 {
    if images_read(calibrations) > 0 && !frame_images {
        METHOD_LN_SYSTEMATIC_WITHOUT_FRAMES
    } else if dim_frames_dn(frames_median_dn).is_some() {
        METHOD_LN_SYSTEMATIC_DIM
    } else {
        METHOD_LN_SYSTEMATIC
    }
}

/// How the assumption begins that says the frames' log response was neither measured nor
/// given (a caller may add how to give it).
pub const RESPONSE_NOT_MEASURED: &str =
    "log response of the frames not measured (the events' timing did not fix it) nor given";

/// The fixed presets of the paper's Fig. 2.
pub const PRESETS: [f64; 5] = [0.2, 0.5, 0.75, 1.0, 1.5];

/// Settings of `estimate eppps`.
#[derive(Clone, Debug)]
pub struct EpppsOptions {
    /// Prior images used without frames (at most [`prior::COUNT`]).
    pub scenes: usize,
    /// Use the frames' contrast and flow when there are frames.
    pub use_frames: bool,
    pub seed: u64,
}

impl Default for EpppsOptions {
    fn default() -> Self {
        Self {
            scenes: prior::COUNT,
            use_frames: true,
            seed: crate::DEFAULT_SEED,
        }
    }
}

/// What `estimate eppps` reads.
pub struct EpppsInput<'a> {
    pub sensor: Sensor,
    pub events: &'a EventChunk,
    /// The recording's frames, prepared (when it has frames and they are used).
    pub frames: Option<&'a PreparedFrames>,
    /// Whether the frames' log response is known (given, or measured from the events'
    /// timing): otherwise the frames are scanned through both ends of what sensors use.
    pub response_known: bool,
    /// Whether the frames' offset (`PreparedFrames::offset`) was fitted to the events'
    /// timing, its range `PreparedFrames::offset_range` (the 95 % interval and both
    /// polarities' offsets, the prior's end where a side is open): where that range moves
    /// the frames' contrast, they are scanned at its ends too ([`offset_bracket`]). An
    /// offset the timing did not determine is read at the frames' own (see
    /// [`OFFSET_NOT_BRACKETED`]).
    pub offset_fitted: bool,
    pub excluded: &'a [bool],
    /// The recording's grey frames as images (empty: none, or not to be used): where the
    /// prepared `frames` are absent (their flow could not be followed) or the motion
    /// outruns their flow, their images stand in for the prior's photographs
    /// ([`prior::frame_images`]).
    pub frame_images: &'a [crate::events::Frame],
}

/// One calibration curve: what it ran through, and the curve.
struct Calibration {
    name: String,
    /// The prior's photograph it scanned (`None`: the recording's frames).
    image: Option<usize>,
    curve: Vec<CurvePoint>,
}

/// One point of the calibration curve as reported: events per pixel per second the
/// recording would make (its travel, its counted pixels) at threshold `ct`.
#[derive(Clone, Debug, Serialize)]
pub struct ReportedPoint {
    pub ct: f64,
    /// Mean over calibrations, and their range.
    pub events_per_pixel_per_second: f64,
    pub lo: f64,
    pub hi: f64,
}

/// Where the recording falls against one fixed preset of the paper's Fig. 2.
#[derive(Clone, Debug, Serialize)]
pub struct PresetPoint {
    pub ct: f64,
    pub events_per_pixel_per_second: f64,
}

/// Estimates the threshold of `input` from its events per pixel of travel.
pub fn estimate(
    input: &EpppsInput,
    options: &EpppsOptions,
    progress: Progress,
) -> Result<CtEstimate, EstimateError> {
    let (excluded, hot) = super::exclude_hot_pixels(input.events, input.sensor, input.excluded);
    check_length(input.events)?;
    progress("flow and travel", 0.0);
    let outrun = input.frames.and_then(PreparedFrames::motion_outruns_flow);
    let frames = input
        .frames
        .filter(|_| options.use_frames && outrun.is_none());
    let mut rates = recording_rates(input, frames, &excluded)?;
    let frame_images = frames_as_prior(input, options, frames, &mut rates);
    let refractory = refractory_edge(input.events, input.sensor);
    let pixel = ScanPixel {
        ratio: 1.0,
        refractory_s: refractory.as_ref().map_or(0.0, |e| e.edge_us * 1e-6),
    };
    let response = match frames {
        Some(f) if input.response_known => {
            let bracket = input
                .offset_fitted
                .then(|| offset_bracket(f, rates.frames_median_dn))
                .flatten();
            FramesResponse::Known(bracket)
        }
        _ => FramesResponse::Unknown,
    };
    let basis = Basis::new(frames, frame_images, response, &excluded, options);
    let mut scanned = scan_thresholds(&basis, rates, pixel, progress);
    let mut slow = frames.and_then(|f| {
        progress("photoreceptor bandwidth", 0.8);
        slow_photoreceptor(input.events, f, &basis, &scanned)
    });
    if let Some(slow) = &mut slow {
        slow.adopt(&mut scanned.on, &mut scanned.off);
    }
    progress("inverting the calibration curves", 0.9);
    let mut result = assemble(&scanned, &basis, refractory.as_ref(), hot);
    if let Some((followed, too_fast)) = outrun.filter(|_| options.use_frames) {
        result.assumptions.push(format!(
            "the frames' optical flow is not used: the motion between them is too large for it on {too_fast} intervals and it follows {followed}, so travel is read from the events, as without frames, and the scene's contrast from the frames' images, scanned as the prior's photographs are"
        ));
    }
    if let Some(slow) = &slow {
        result.assumptions.push(slow.assumption());
    }
    result.extra.insert(
        "photoreceptor_slow".into(),
        json!(slow.as_ref().map(SlowReach::report)),
    );
    progress("done", 1.0);
    Ok(result)
}

/// Where the recording's frames are not followed (`frames` not used) but there are frames
/// to use, their images in the prior's place ([`prior::frame_images`]), and `rates` marked
/// as read against them, with their median brightness.
fn frames_as_prior(
    input: &EpppsInput,
    options: &EpppsOptions,
    frames: Option<&PreparedFrames>,
    rates: &mut RecordingRates,
) -> Option<Vec<prior::PriorImage>> {
    let images = (options.use_frames && frames.is_none())
        .then(|| prior::frame_images(input.frame_images, options.scenes.max(1)))
        .filter(|images| !images.is_empty())?;
    rates.frame_images = true;
    rates.frames_median_dn = prior::median_reliable_dn(input.frame_images);
    Some(images)
}

/// The recording's events per pixel of travel, through its frames where they are used.
fn recording_rates(
    input: &EpppsInput,
    frames: Option<&PreparedFrames>,
    excluded: &[bool],
) -> Result<RecordingRates, EstimateError> {
    match frames {
        Some(f) => recording::from_frames(input.events, f, input.sensor, excluded),
        None => recording::from_events(input.events, input.sensor, excluded),
    }
    .ok_or_else(|| {
        EstimateError::new(
            "no motion to measure: no part of the view has a flow that sharpens its events (a static scene, flicker or noise)",
            "use a part of the recording where the scene or the camera moves",
        )
    })
}

/// What the scans read: the calibrations (ON = OFF, the ones shown), the recording's rates
/// (with the still pixels' background where the frames show them), both polarities'
/// thresholds, the OFF/ON ratio they gave (measured, held) and the pixel scanned last.
struct Scanned {
    calibrations: Vec<Calibration>,
    reading: Option<Reading>,
    rates: RecordingRates,
    on: Polarity,
    off: Polarity,
    measured_ratio: f64,
    ratio: f64,
    pixel: ScanPixel,
    /// An ON/OFF imbalance the events cannot attribute (without frames), in words.
    balance: Option<String>,
}

/// The thresholds at which the calibration scans make the recording's rates: ON = OFF
/// first (read at the recording's sharpness without frames), then again at the OFF/ON
/// ratio that gave, since the two thresholds interact in every pixel (see
/// [`scans::count`]).
fn scan_thresholds(
    basis: &Basis,
    rates: RecordingRates,
    pixel: ScanPixel,
    progress: Progress,
) -> Scanned {
    progress("calibration scans (ON = OFF)", 0.3);
    let raw = basis.calibrate(&rates, pixel, None);
    let reading = basis.select(&raw, &rates);
    let selections = reading.as_ref().map(|r| &r.kept[..]);
    let symmetric = match selections {
        Some(s) => sharpness::mix(&raw, &basis.tags, s),
        None => raw,
    };
    let (on, off) = measure_both(&symmetric, &rates);
    // with frames, the sensor's background where they are still, the scene's own events
    // there read at the thresholds just found
    let still = rates.with_still_background([on.measured.value, off.measured.value]);
    let (rates, (on, off)) = match still {
        Some(rates) => {
            let both = measure_both(&symmetric, &rates);
            (rates, both)
        }
        None => (rates, (on, off)),
    };
    progress("calibration scans (OFF/ON ratio measured)", 0.6);
    let (measured_ratio, ratio) = ratio_of(&on, &off);
    let ((mut on, mut off), pixel) = at_ratio((on, off), ratio, pixel, |pixel| {
        measure_both(&basis.calibrate(&rates, pixel, selections), &rates)
    });
    // without frames an imbalance may be the scene's or a leak's, not the thresholds'
    let balance = basis
        .frames
        .is_none()
        .then(|| balance::symmetric(&symmetric, &rates))
        .flatten()
        .and_then(|shared| balance::widen(&mut on, &mut off, &shared));
    Scanned {
        calibrations: symmetric,
        reading,
        rates,
        on,
        off,
        measured_ratio,
        ratio,
        pixel,
        balance,
    }
}

/// The OFF/ON ratio of two thresholds, and as it is scanned (held to 0.2-5).
fn ratio_of(on: &Polarity, off: &Polarity) -> (f64, f64) {
    let measured = off.measured.value / on.measured.value;
    (measured, measured.clamp(0.2, 5.0))
}

/// Both thresholds read again by `measure` with `pixel`'s OFF threshold `ratio` times its
/// ON one, where that ratio is known and not 1 (`read`, the ON = OFF reading, otherwise):
/// the two thresholds interact in every pixel ([`scans::count`]).
fn at_ratio(
    read: (Polarity, Polarity),
    ratio: f64,
    mut pixel: ScanPixel,
    measure: impl FnOnce(ScanPixel) -> (Polarity, Polarity),
) -> ((Polarity, Polarity), ScanPixel) {
    if !(ratio.is_finite() && ratio.ln().abs() > 0.02) {
        return (read, pixel);
    }
    pixel.ratio = ratio;
    (measure(pixel), pixel)
}

/// The estimate from what the scans read, with its notes and assumptions.
fn assemble(
    scanned: &Scanned,
    basis: &Basis,
    refractory: Option<&crate::fit::events_only::refractory::Edge>,
    hot: usize,
) -> CtEstimate {
    let Scanned {
        calibrations,
        rates,
        on,
        off,
        pixel,
        ..
    } = scanned;
    let grid = threshold_grid();
    let mut result = CtEstimate::from_parts(
        "eppps",
        &on.measured,
        &off.measured,
        Determinable {
            lo: grid[0] * pixel.ratio.min(1.0),
            hi: grid[grid.len() - 1] * pixel.ratio.max(1.0),
            what: "the calibration curve",
        },
    );
    polarity_notes(&mut result, (on, off), calibrations.len());
    result.assumptions.extend(scanned.balance.clone());
    result
        .assumptions
        .extend(assumptions(rates, calibrations, basis, hot));
    result.assumptions.extend(scan_assumptions(
        basis.frames.is_none().then_some(&scanned.reading),
        rates,
        (scanned.measured_ratio, scanned.ratio, pixel.ratio),
        refractory,
    ));
    report(
        &mut result,
        rates,
        calibrations,
        (on, off),
        basis.frames.is_some(),
    );
    result
}

/// A photoreceptor much slower than the scene ([`photoreceptor::check`] on the frames),
/// what the frames' scans, passed through that low-pass, read at the recording's rates (a
/// polarity's `why` says where they read nothing), and what the ideal scans had read (once
/// [`SlowReach::adopt`] has run).
struct SlowReach {
    found: SlowPhotoreceptor,
    on: Polarity,
    off: Polarity,
    ideal: [Option<Measured>; 2],
}

/// The check on `frames`, and where it finds a cutoff, the scans again through it, at the
/// rates and refractory period `scanned` read the thresholds with: ON = OFF, then at the
/// OFF/ON ratio that gives.
fn slow_photoreceptor(
    events: &EventChunk,
    frames: &PreparedFrames,
    basis: &Basis,
    scanned: &Scanned,
) -> Option<SlowReach> {
    let found = photoreceptor::check(events, frames, basis.excluded)?;
    let rates = &scanned.rates;
    let read = |pixel| {
        let calibrations = basis.calibrate_frames(pixel, Some(found.cutoff_hz));
        measure_both(&calibrations, rates)
    };
    let symmetric = read(ScanPixel {
        ratio: 1.0,
        ..scanned.pixel
    });
    let (_, ratio) = ratio_of(&symmetric.0, &symmetric.1);
    let ((on, off), _) = at_ratio(symmetric, ratio, scanned.pixel, read);
    Some(SlowReach {
        found,
        on,
        off,
        ideal: [None, None],
    })
}

impl SlowReach {
    /// Each polarity the low-passed scans read becomes their reading, its interval
    /// extended to hold the ideal scans' ([`Measured::spanning`]). Where the check fires,
    /// the low-passed reading halves the ideal one's median error on simulated recordings
    /// (`benches/coverage/eppps-slow-photoreceptor-2026-12-06`: 0.286 -> 0.129 in ln C over
    /// 42 polarity-cases), with or without a cutoff in their truth: the check also fires
    /// where other effects spread a pixel's events over frames (other simulators' latency,
    /// refractory periods, leak and noise), and the low-pass stands in for them too. The
    /// data do not rule the ideal pixel out, so the interval holds both readings. A
    /// polarity either reads nothing for stays as it was.
    fn adopt(&mut self, on: &mut Polarity, off: &mut Polarity) {
        for (k, (polarity, slow)) in [(on, &self.on), (off, &self.off)].into_iter().enumerate() {
            if polarity.why.is_some() || slow.why.is_some() {
                continue;
            }
            self.ideal[k] = Some(polarity.measured.clone());
            let ideal = polarity.measured.ci95;
            *polarity = Polarity {
                measured: slow.measured.clone().spanning(ideal),
                ..slow.clone()
            };
        }
    }

    /// The low-passed scans' threshold of each polarity (`None` where they read none).
    fn thresholds(&self) -> [Option<f64>; 2] {
        [&self.on, &self.off].map(|p| p.why.is_none().then_some(p.measured.value))
    }

    fn assumption(&self) -> String {
        let f = &self.found;
        let read = |v: Option<f64>| v.map_or("none".to_string(), |v| format!("{v:.4}"));
        let ideal = self.ideal.clone().map(|m| m.map(|m| m.value));
        format!(
            "the photoreceptor may be slower than the scene: the events follow the frames low-passed at a cutoff of {} Hz at white ({:.2} Hz at the middle frame's median DN; {} .. {} Hz within 2 standard errors) better than the frames themselves, by {:.1} standard errors of the tile-by-tile count distance of an ideal quantiser on the frames' samples; such a pixel averages the scene and fires less than the frames' change, so ideal scans read its thresholds high; the scans through that low-pass read ON {} and OFF {} (the ideal scans {} and {}); each polarity they read is theirs, its interval holding the ideal scans' too, which the data do not rule out (where the check fired on simulated recordings the low-passed reading halved the ideal one's median error, with or without a cutoff in their truth: other simulators' latency, refractory periods, leak and noise spread a pixel's events over frames too, `benches/coverage/eppps-slow-photoreceptor-2026-12-06`)",
            f.cutoff_hz,
            f.cutoff_at_median_dn_hz,
            f.cutoff_range_hz[0],
            f.cutoff_range_hz[1],
            f.significance,
            read(self.thresholds()[0]),
            read(self.thresholds()[1]),
            read(ideal[0]),
            read(ideal[1]),
        )
    }

    fn report(&self) -> serde_json::Value {
        let polarity = |p: &Polarity| match &p.why {
            None => json!({"value": p.measured.value, "ci95": p.measured.ci95}),
            Some(why) => json!({"value": null, "why": why}),
        };
        json!({
            "check": self.found,
            "scanned": {"on": polarity(&self.on), "off": polarity(&self.off)},
            "ideal": {"on": self.ideal[0], "off": self.ideal[1]},
        })
    }
}

/// A polarity without a value gets its reason under `why`; one whose recording makes more
/// or fewer events than some calibrations give at the grid's ends says so: those count at
/// the end, a bound, and its interval is open that way.
fn polarity_notes(result: &mut CtEstimate, (on, off): (&Polarity, &Polarity), calibrations: usize) {
    for (key, polarity) in [("ct_on", on), ("ct_off", off)] {
        if let Some(why) = &polarity.why {
            result.why.insert(key.into(), why.clone());
            continue;
        }
        let b = polarity.beyond_grid;
        for (count, side, end, open) in [
            (b.above, "fewer", ("highest", b.top), "above"),
            (b.below, "more", ("lowest", b.bottom), "below"),
        ] {
            if count > 0 {
                result.assumptions.push(format!(
                    "{key}: the recording makes {side} events than {count} of the {calibrations} calibrations even at the {} threshold simulated ({:.3}); they count at it, a bound, so the interval is open {open}",
                    end.0,
                    end.1
                ));
            }
        }
    }
}

/// What the scans assumed: the prior read at the recording's sharpness (`reading`, only
/// without frames; `Some(None)` where too few bursts allowed it), the OFF/ON ratio scanned
/// (`(measured, held, scanned)`), and the refractory period simulated.
fn scan_assumptions(
    reading: Option<&Option<Reading>>,
    rates: &RecordingRates,
    (measured_ratio, ratio, scanned): (f64, f64, f64),
    refractory: Option<&crate::fit::events_only::refractory::Edge>,
) -> Vec<String> {
    let mut notes = Vec::new();
    if let Some(reading) = reading {
        notes.push(match reading {
            Some(r) => r.describe(),
            None => format!(
                "prior not read at the recording's sharpness: {} consecutive same-polarity event pairs at a pixel, fewer than the {MIN_BURST_PAIRS} needed to measure it; every blur of the images (0-{:.0} px) is part of the prior",
                rates.bursts.map_or(0, |b| b.pairs),
                prior::BLUR_PX[prior::BLUR_PX.len() - 1]
            ),
        });
    }
    let clamped = if measured_ratio.is_finite() && measured_ratio != ratio {
        format!(", held to 0.2-5 from {measured_ratio:.3}")
    } else {
        String::new()
    };
    notes.push(format!(
        "thresholds read from scans with OFF = {scanned:.3} x ON (the ratio the ON = OFF scans gave{clamped}; a pixel's ON count depends on its OFF threshold wherever the profile turns); the calibration curve shown is the ON = OFF one of the paper's Fig. 2"
    ));
    notes.push(match refractory {
        Some(e) => format!(
            "refractory period {:.3} ms simulated in the scans: the lower edge of the recording's same-pixel intervals, with the pile-up just above it that a refractory period leaves ({} intervals below it, {} in the octave above)",
            e.edge_us * 1e-3,
            e.below,
            e.above
        ),
        None => "no refractory period in the scans: the recording's same-pixel intervals show no lower edge with a pile-up above it".to_string(),
    });
    notes
}

fn check_length(events: &EventChunk) -> Result<(), EstimateError> {
    let duration = match (events.t.first(), events.t.last()) {
        (Some(a), Some(b)) => (b - a) as f64 * 1e-6,
        _ => 0.0,
    };
    if events.len() < 1000 || duration <= 0.0 {
        return Err(EstimateError::new(
            format!(
                "{} events over {duration:.3} s are too few to measure a rate",
                events.len()
            ),
            "use a longer part of the recording",
        ));
    }
    Ok(())
}

/// The refractory period the recording shows: the lower edge of its same-pixel intervals
/// with the pile-up above it ([`crate::fit::events_only::refractory::edge`]); `None` when
/// there is no such edge.
fn refractory_edge(
    events: &EventChunk,
    sensor: Sensor,
) -> Option<crate::fit::events_only::refractory::Edge> {
    use crate::fit::events_only::refractory;
    let pixels = sensor.width as usize * sensor.height as usize;
    let mut last = vec![crate::events::TimeUs::MIN; pixels];
    let inside = events.len();
    let mut intervals =
        refractory::intervals(events, 0..inside, sensor.width as usize, &mut last, None);
    refractory::edge(&mut intervals, refractory::timestamp_step(events)).filter(|e| e.found)
}

/// How the frames' log response is known.
#[derive(Clone, Copy, Debug, PartialEq)]
enum FramesResponse {
    /// Neither measured nor given: both ends of what sensors use are scanned.
    Unknown,
    /// Measured or given; with the fitted offset's range where it moves the contrast.
    Known(Option<OffsetBracket>),
}

/// A fitted offset's 95 % range where it moves the frames' contrast by more than
/// [`OFFSET_BRACKET_RATIO`].
#[derive(Clone, Copy, Debug, PartialEq)]
struct OffsetBracket {
    lo: f32,
    hi: f32,
    /// `(median DN + hi) / (median DN + lo)`: how far the range moves the contrast.
    ratio: f64,
}

impl OffsetBracket {
    /// The offsets scanned: both ends and the fitted `offset`, each once.
    fn offsets(&self, offset: f32) -> Vec<f32> {
        let mut offsets = vec![self.lo, offset.clamp(self.lo, self.hi), self.hi];
        offsets.dedup();
        offsets
    }
}

/// Why an offset the events' timing did not determine is read at the frames' own, not
/// bracketed over the prior range (0-60 DN) as `aps` brackets it: on 109 kept coverage
/// draws (80 of the 221 whose offset was not determined, at random, and the 29 with the
/// widest fitted ranges), bracketing those widened the intervals 2.4x (median hi/lo 4.8
/// -> 11.5), opened 44 lower ends and moved 118 of 148 readings away from the truth, for
/// 3 misses of 203 fewer (study `benches/coverage/eppps-offset-bracket-2026-12-06`). The
/// simulators' responses have no offset; a sensor whose frames carry a black level does,
/// and reads thresholds high by (DN + b) / DN, which this assumption states.
pub const OFFSET_NOT_BRACKETED: &str = "the frames' log offset b was not determined by the events' timing: eppps reads the frames at the frames' own offset, and its interval does not hold the prior range 0-60 DN that aps carries (bracketing it widened intervals 2.4x on simulated recordings, whose responses have no offset, and moved most readings away from the truth); frames that carry a black level of b DN read thresholds high by (DN + b) / DN at their median DN";

/// How far (a factor) a fitted offset's range must move the frames' contrast at their
/// median DN for the scans to run at its ends too. The offset b in ln(DN + b) scales a
/// log change by DN / (DN + b); in dim frames a range of tens of DN is a factor of
/// several. Read through the point alone, eppps missed on coverage draws 13037 (11 DN, b =
/// 35 DN, range 0-60: ON 0.105 [0.042, 0.261] for 0.524), 11012 and 1028, and read 0.45-0.55x
/// the truth on 77 and 1046 (9-10 DN): the fitted offsets of dim frames run high
/// (a photoreceptor's lag looks like a larger offset, [`crate::estimate::timing`]).
const OFFSET_BRACKET_RATIO: f64 = 1.25;

/// The fitted offset's range as a bracket of the frames' response, where it moves their
/// contrast at `median_dn` by more than [`OFFSET_BRACKET_RATIO`].
fn offset_bracket(frames: &PreparedFrames, median_dn: Option<f64>) -> Option<OffsetBracket> {
    let dn = median_dn?;
    let (lo, hi) = frames.offset_range;
    // no negative offset is scanned, and none under 1 DN through a pure log, whose
    // ln(DN + b) has no value at a black pixel (the lin-log is linear there)
    let floor = match frames.log_map.response() {
        crate::sim::params::LogResponse::V2e => 0.0,
        _ => 1.0,
    };
    let lo = lo.min(frames.offset).max(floor);
    let hi = hi.max(frames.offset);
    let ratio = (dn + hi as f64) / (dn + lo as f64).max(0.5);
    (ratio > OFFSET_BRACKET_RATIO).then_some(OffsetBracket { lo, hi, ratio })
}

/// What the scans at a fitted offset's ends assume.
fn offset_bracket_assumption(bracket: &OffsetBracket, median_dn: Option<f64>) -> String {
    format!(
        "the frames' log offset b fitted to the events' timing leaves a range {:.1} .. {:.1} DN (its 95 % interval and the ON and OFF samples' own, the prior's end 0 or 60 DN where the data leave a side open; no negative offset scanned, none under 1 DN through a pure log) that moves their contrast at the median {:.0} DN by a factor {:.2}: they are scanned at both ends and at the fitted offset, the threshold is the readings' geometric mean and their spread is in the interval",
        bracket.lo,
        bracket.hi,
        median_dn.unwrap_or(f64::NAN),
        bracket.ratio
    )
}

/// What a recording is compared with: its frames, or the prior's images under every blur
/// and floor (and what each of them is).
struct Basis<'a> {
    frames: Option<&'a PreparedFrames>,
    /// How the frames' log response is known.
    response: FramesResponse,
    /// The log responses the frames are read through, and their names.
    responses: Vec<(calibration::Response, String)>,
    excluded: &'a [bool],
    options: &'a EpppsOptions,
    priors: Vec<prior::PriorImage>,
    tags: Vec<PriorTag>,
}

/// Consecutive event pairs a recording needs for its burst share to choose the prior's
/// blur (a share of 0.5 from 200 pairs is known to +-0.07 at 95 %).
const MIN_BURST_PAIRS: usize = 200;

impl<'a> Basis<'a> {
    /// The basis of the recording's `frames` where their flow is followed, else of the
    /// prior: the recording's `frame_images` (frames whose flow is not followed) or the
    /// natural photographs.
    fn new(
        frames: Option<&'a PreparedFrames>,
        frame_images: Option<Vec<prior::PriorImage>>,
        response: FramesResponse,
        excluded: &'a [bool],
        options: &'a EpppsOptions,
    ) -> Self {
        let responses = match (frames, response) {
            (Some(f), FramesResponse::Known(None)) => vec![(
                calibration::Response::of(f),
                "the recording's frames".to_string(),
            )],
            (Some(f), FramesResponse::Known(Some(bracket))) => {
                let at = |offset_dn: f32| calibration::Response {
                    offset_dn,
                    ..calibration::Response::of(f)
                };
                bracket
                    .offsets(f.offset)
                    .into_iter()
                    .map(|b| (at(b), format!("the recording's frames at b = {b:.1} DN")))
                    .collect()
            }
            (Some(_), FramesResponse::Unknown) => calibration::Response::ends()
                .into_iter()
                .map(|(r, name)| (r, format!("the recording's frames through {name}")))
                .collect(),
            (None, _) => Vec::new(),
        };
        let priors = match (frames, frame_images) {
            (Some(_), _) => Vec::new(),
            (None, Some(images)) => images,
            (None, None) => prior::images(options.scenes.max(1)),
        };
        let tags = priors.iter().map(prior::PriorImage::tag).collect();
        Basis {
            frames,
            response,
            responses,
            excluded,
            options,
            priors,
            tags,
        }
    }

    /// The calibration curves for `pixel`: one through the frames; without frames one per
    /// prior image, blur and floor (`selections` `None`), or per image and floor read at
    /// the blurs `selections` chose.
    fn calibrate(
        &self,
        rates: &RecordingRates,
        pixel: ScanPixel,
        selections: Option<&[Selection]>,
    ) -> Vec<Calibration> {
        if self.frames.is_some() {
            return self.calibrate_frames(pixel, None);
        }
        let grid = threshold_grid();
        let scan = |images: &[&prior::PriorImage]| -> Vec<Calibration> {
            images
                .par_iter()
                .map(|image| Calibration {
                    name: image.label(),
                    image: Some(image.image),
                    // one photograph's blurs and floors scan the same places (common
                    // random numbers): their differences are theirs alone
                    curve: scans::block_curve(
                        &image.log,
                        &calibration::prior_blocks(
                            &image.log,
                            rates,
                            self.options.seed + image.image as u64,
                        ),
                        &grid,
                        pixel,
                    ),
                })
                .collect()
        };
        match selections {
            None => scan(&self.priors.iter().collect::<Vec<_>>()),
            Some(selections) => {
                let (list, renumbered) = sharpness::used(selections);
                let images: Vec<&prior::PriorImage> =
                    list.iter().map(|&k| &self.priors[k]).collect();
                let tags: Vec<PriorTag> = list.iter().map(|&k| self.tags[k]).collect();
                sharpness::mix(&scan(&images), &tags, &renumbered)
            }
        }
    }

    /// The calibration curves through the frames (one per log response; none without
    /// frames), for a photoreceptor whose cutoff at white is `photoreceptor_hz` where one
    /// is given ([`calibration::low_pass`]).
    fn calibrate_frames(
        &self,
        pixel: ScanPixel,
        photoreceptor_hz: Option<f64>,
    ) -> Vec<Calibration> {
        let Some(f) = self.frames else {
            return Vec::new();
        };
        let grid = threshold_grid();
        self.responses
            .iter()
            .map(|(response, name)| Calibration {
                name: name.clone(),
                image: None,
                curve: curve(
                    &calibration::frame_profiles(f, self.excluded, response, photoreceptor_hz),
                    &grid,
                    false,
                    pixel,
                ),
            })
            .collect()
    }

    /// How many prior images the calibrations scan (0 with frames).
    fn images(&self) -> usize {
        self.tags.iter().map(|t| t.image + 1).max().unwrap_or(0)
    }

    /// Without frames, each prior image and floor read at the blur whose burst share is the
    /// recording's; `None` with frames, or where the recording has too few consecutive
    /// events to measure its share (then every blur is part of the prior).
    fn select(&self, raw: &[Calibration], rates: &RecordingRates) -> Option<Reading> {
        let bursts = rates.bursts.filter(|b| b.pairs >= MIN_BURST_PAIRS)?;
        (self.frames.is_none() && !self.tags.is_empty()).then(|| {
            let all = sharpness::select(raw, &self.tags, rates, bursts.fraction());
            Reading::new(bursts.fraction(), bursts.pairs, all, &self.tags)
        })
    }
}

/// One polarity's threshold: per calibration, and combined.
#[derive(Clone)]
struct Polarity {
    /// Each calibration's threshold (`null` where it is only bounded by the grid's end).
    per_calibration: Vec<Option<f64>>,
    measured: Measured,
    /// Standard deviation of ln C between calibrations (the prior's spread), widened to a
    /// prediction for one more scene ([`prediction_scale`]).
    prior_ln_sd: f64,
    /// Calibrations the recording lies beyond the grid's top (fewer events than even the
    /// highest threshold makes) or bottom: the grid's end stands in for them, a bound, and
    /// the interval is open on that side.
    beyond_grid: Beyond,
    /// Why there is no value, where there is none.
    why: Option<String>,
}

/// How many calibrations a recording lies beyond, at either end of the grid, and the
/// thresholds of those ends (this polarity's: the OFF grid is the ON grid times the ratio).
#[derive(Clone, Copy, Debug, Default)]
struct Beyond {
    above: usize,
    below: usize,
    top: f64,
    bottom: f64,
}

/// Both polarities' thresholds from `calibrations`.
fn measure_both(calibrations: &[Calibration], rates: &RecordingRates) -> (Polarity, Polarity) {
    (
        measure(
            calibrations,
            rates,
            Side::On,
            rates.on_per_px,
            rates.ln_se_on,
        ),
        measure(
            calibrations,
            rates,
            Side::Off,
            rates.off_per_px,
            rates.ln_se_off,
        ),
    )
}

/// The calibrations' thresholds (the grid's end where the recording lies beyond it; the
/// middle of two grid points where the curve drops to no events between them), or why
/// they give none: a calibration with no threshold at all, or more than half of them only
/// bounded.
fn classify(
    inverted: &[Inverted],
    beyond: Beyond,
    target: f64,
    side: Side,
) -> Result<Vec<f64>, String> {
    let polarity = match side {
        Side::On => "ON",
        Side::Off => "OFF",
    };
    if target.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(format!(
            "the recording has no supported {polarity} events in the windows with a flow"
        ));
    }
    let values: Vec<f64> = inverted.iter().filter_map(|i| i.value()).collect();
    let n = inverted.len();
    if values.len() < n || n == 0 {
        return Err(format!(
            "{} of the {n} calibrations make no {polarity} events to compare with the recording's {target:.4} per pixel of travel",
            n - values.len()
        ));
    }
    if beyond.below * 2 > n {
        return Err(format!(
            "the recording makes more {polarity} events per pixel of travel ({target:.4}) than {} of the {n} calibrations make at the lowest threshold simulated ({:.3}): below the method's range",
            beyond.below, beyond.bottom
        ));
    }
    if beyond.above * 2 > n {
        return Err(format!(
            "the recording makes fewer {polarity} events per pixel of travel ({target:.4}) than {} of the {n} calibrations make at the highest threshold simulated ({:.2}): above the method's range",
            beyond.above, beyond.top
        ));
    }
    Ok(values)
}

/// Inverts every calibration at the recording's `target` rate and combines them in the
/// logarithm: the statistical error is the recording's (bootstrap), turned into threshold
/// by the curve's slope; the systematic holds the spread between calibrations and the
/// flow's precision. A calibration the recording lies beyond counts at the grid's end, and
/// the interval is then open on that side.
fn measure(
    calibrations: &[Calibration],
    rates: &RecordingRates,
    side: Side,
    target: f64,
    ln_se: f64,
) -> Polarity {
    let inverted: Vec<Inverted> = calibrations
        .iter()
        .map(|c| invert(&c.curve, side, target))
        .collect();
    let beyond = Beyond::of(calibrations, &inverted, side);
    let per_calibration = inverted
        .iter()
        .map(|i| match i {
            Inverted::At(_) | Inverted::Between(..) => i.value(),
            _ => None,
        })
        .collect();
    let classified = match &rates.noise[side.index()].why {
        Some(why) => Err(why.clone()),
        None => classify(&inverted, beyond, target, side),
    };
    let (measured, prior_ln_sd, why) = match classified {
        Ok(values) => {
            let (measured, prior_ln_sd) =
                combined_in_log(&values, calibrations, rates, side, ln_se, beyond);
            (measured, prior_ln_sd, None)
        }
        Err(why) => (Measured::new(f64::NAN, f64::NAN, 0.0), f64::NAN, Some(why)),
    };
    Polarity {
        per_calibration,
        measured,
        prior_ln_sd,
        beyond_grid: beyond,
        why,
    }
}

impl Beyond {
    /// How many of the `inverted` calibrations the recording lies beyond, and the grid's
    /// ends (the first calibration's).
    fn of(calibrations: &[Calibration], inverted: &[Inverted], side: Side) -> Beyond {
        let ends = calibrations.first().map(|c| &c.curve[..]).unwrap_or(&[]);
        let count = |wanted: fn(&Inverted) -> bool| inverted.iter().filter(|i| wanted(i)).count();
        Beyond {
            above: count(|i| matches!(i, Inverted::Above(_))),
            below: count(|i| matches!(i, Inverted::Below(_))),
            top: ends.last().map_or(f64::NAN, |p| side.threshold(p)),
            bottom: ends.first().map_or(f64::NAN, |p| side.threshold(p)),
        }
    }
}

/// The calibrations' threshold `values` combined in the logarithm, and the spread between
/// them widened to a prediction for the recording's scene (`prior_ln_sd`): the
/// statistical error is the recording's (`ln_se`, bootstrap) through the curves' mean
/// slope; the systematic holds that spread, the travel's and noise's precision and the
/// method's own. Open on the side where the recording lies beyond a calibration.
fn combined_in_log(
    values: &[f64],
    calibrations: &[Calibration],
    rates: &RecordingRates,
    side: Side,
    ln_se: f64,
    beyond: Beyond,
) -> (Measured, f64) {
    let logs: Vec<f64> = values.iter().map(|v| v.ln()).collect();
    let n = logs.len() as f64;
    let mean = logs.iter().sum::<f64>() / n;
    let prior_ln_sd = if logs.len() > 1 {
        (logs.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    } else {
        0.0
    };
    let scale = prediction_scale(calibrations);
    let prior_ln_sd = prior_ln_sd * scale;
    let value = mean.exp();
    let slope = calibrations
        .iter()
        .map(|c| log_slope(&c.curve, side, value))
        .sum::<f64>()
        / n;
    let stat = ln_se / slope.abs();
    let travel = rates
        .travel_relative_error
        .hypot(rates.noise[side.index()].relative_error)
        / slope.abs();
    let mut measured = Measured::log_normal(
        value,
        stat,
        prior_ln_sd.hypot(travel).hypot(method_systematic(
            calibrations,
            rates.frames_median_dn,
            rates.frame_images,
        )),
    );
    if beyond.above > 0 {
        measured.ci95[1] = f64::INFINITY;
    }
    if beyond.below > 0 {
        measured.ci95[0] = 0.0;
    }
    (measured, prior_ln_sd)
}

/// What the estimate assumed; `images`: the prior's images (0: the recording's frames).
/// How much the spread between a prior's `k` photographs is widened to be a 95 %
/// prediction interval for the recording's scene, one more draw from the scenes they
/// stand for: `t(0.975, k - 1) sqrt(1 + 1/k) / 1.96` (1.42 for six images, 2.5 for three),
/// the spread being measured on `k` of them and their mean taken; 1 for the recording's
/// frames (no photographs: its calibrations bracket a response, they are not draws).
fn prediction_scale(calibrations: &[Calibration]) -> f64 {
    let k = images_read(calibrations);
    if k < 2 {
        return 1.0;
    }
    crate::stats::jackknife::t95_scale(k) * (1.0 + 1.0 / k as f64).sqrt()
}

/// How many of the prior's photographs `calibrations` scanned.
fn images_read(calibrations: &[Calibration]) -> usize {
    let mut images: Vec<usize> = calibrations.iter().filter_map(|c| c.image).collect();
    images.sort_unstable();
    images.dedup();
    images.len()
}

/// What the noise bracket assumed and how wide it is, per polarity.
fn noise_assumption(rates: &RecordingRates, frames: bool) -> String {
    let polarity = |k: usize| match rates.noise[k].why {
        Some(_) => "may be all noise (not determinable)".to_string(),
        None => format!(
            "up to {:.1} % noise, +-{:.1} % systematic",
            100.0 * rates.noise[k].noise_share,
            100.0 * rates.noise[k].half_range()
        ),
    };
    format!(
        "noise: an event is supported by a neighbour's within {:.0} ms before or after; {} count, {:.1} % of their events unsupported; a noise event finds support by chance {:.0} % of the time there, so the unsupported events over the time no neighbour covers (97.5 % upper end) bound the noise; the rate is the middle of none and all of it: ON {}, OFF {}",
        rates.support_window_us as f64 / 1e3,
        if frames {
            "the reliable pixels"
        } else {
            "the 8 x 8 px tiles with a supported event"
        },
        100.0 * rates.unsupported_share,
        100.0 * rates.chance_support,
        polarity(0),
        polarity(1),
    ) + &still_assumption(rates)
}

/// What the frames' still pixels showed of the sensor's background (with frames), and
/// where it decided the noise bracket.
fn still_assumption(rates: &RecordingRates) -> String {
    let Some(still) = rates.still.as_ref().filter(|s| s.total().pixels > 0) else {
        return String::new();
    };
    let total = still.total();
    let decided: Vec<&str> = (0..2)
        .filter(|&k| rates.still_decides[k])
        .map(|k| ["ON", "OFF"][k])
        .collect();
    format!(
        "; the sensor's background where the frames show a still scene (log range under {:.2} along the pixel's path): {} pixels, {:.0} pixel-s, {:.0} ON and {:.0} OFF events ({:.4} and {:.4} per pixel-second; an ideal pixel there fires none); {}",
        still::STILL_LN,
        total.pixels,
        total.exposure_s,
        total.events[0],
        total.events[1],
        total.events[0] / total.exposure_s,
        total.events[1] / total.exposure_s,
        if decided.is_empty() {
            "within the support filter's bound".to_string()
        } else {
            format!(
                "beyond the support filter's bound for {}, so that many events per pixel-second (95 % interval, less the most the still pixels' own scene makes: their log range over the threshold read without them) come off the counted ones there: between half its lower end (leak delays OFF events while the light falls, instead of adding ON ones) and all its upper end; {}",
                decided.join(" and "),
                by_brightness(still)
            )
        }
    )
}

/// The still pixels' background per brightness range, in words.
fn by_brightness(still: &still::StillPixels) -> String {
    let ranges: Vec<String> = still
        .ranges
        .iter()
        .filter(|r| r.exposure_s > 0.0)
        .map(|r| {
            format!(
                "{:.0}-{:.0} DN {:.3} ON and {:.3} OFF ({} pixels)",
                r.dn[0],
                r.dn[1],
                r.events[0] / r.exposure_s,
                r.events[1] / r.exposure_s,
                r.pixels
            )
        })
        .collect();
    format!(
        "the background is read per brightness (ranges a factor 1.41 in DN apart; one with under {} still pixels, and the pixels under {DIM_FRAMES_DN:.0} DN, take the nearest range's), each counted pixel taking its own brightness's rate, since leak grows with the light and shot noise in the dark: {}",
        still::MIN_RANGE_PIXELS,
        ranges.join(", ")
    )
}

fn assumptions(
    rates: &RecordingRates,
    calibrations: &[Calibration],
    basis: &Basis,
    hot: usize,
) -> Vec<String> {
    let images = basis.images();
    let frames = images == 0;
    let mut out = Vec::new();
    if hot > 0 {
        out.push(format!("{hot} hot pixels left out"));
    }
    out.push(noise_assumption(rates, frames));
    out.push(format!(
        "travel from the flow of {}: median speed {:.1} px/s; {}",
        rates.flow_source,
        rates.speed_median_px_s,
        if frames {
            format!("{} reliable pixels of the {} kept count", rates.counted_units, rates.kept_pixels)
        } else {
            format!(
                "{} of the {} 8 x 8 px tiles the flow moves have signal and count (blank parts of the view do not; static ones have no travel)",
                rates.counted_units, rates.units
            )
        },
    ));
    if frames {
        out.push("calibration: ideal pixels along each pixel's own path through the frames (the scene's contrast measured); ON = OFF threshold in the scans".into());
    }
    if let (true, FramesResponse::Known(Some(bracket))) = (frames, basis.response) {
        out.push(offset_bracket_assumption(&bracket, rates.frames_median_dn));
    } else if frames && calibrations.len() > 1 {
        out.push(format!(
            "{RESPONSE_NOT_MEASURED}: they are scanned through both ends of what sensors and simulators use, v2e's lin-log (linear below 20 DN, as an offset of about 20 DN; DVS-Voltmeter fits ln(DN + 20-23 DN)) and a pure log (ESIM's ln(I + 0.001)); the threshold is their geometric mean and their spread ({} calibrations) is in the interval; they differ where the scene is dim (a response given where the sensor's is known replaces them)",
            calibrations.len()
        ));
    } else if !frames {
        out.extend(prior_assumptions(rates, calibrations, images));
    }
    out.push(format!(
        "scans start from the state {} px of the same motion left (the recording is part of a longer one); ideal pixels: bandwidth, refractory period and noise of the real sensor are not in the scans",
        scans::BURN_IN_PX
    ));
    out.push(method_systematic_assumption(
        rates,
        frames || rates.frame_images,
    ));
    out
}

/// Without frames: what the natural-image prior stands for (the scenes' contrast, the
/// response's floor) and the flow's precision.
fn prior_assumptions(
    rates: &RecordingRates,
    calibrations: &[Calibration],
    images: usize,
) -> Vec<String> {
    let mut out = Vec::new();
    if rates.frame_images {
        out.extend(frame_image_assumptions(calibrations, images));
        out.push(flow_precision_assumption(rates));
        return out;
    }
    out.push(format!(
        "prior: events alone do not fix the scene's log contrast, so line scans through {images} natural images (calib/priors/natural) stand for it, with the recording's travel and flow directions; their spread is in the interval as a 95 % prediction interval for one more scene ({} images read: Student t with one degree of freedom fewer, and the spread of their mean, x {:.2} the spread); the interval holds for scenes of the photographs' contrast (log-luminance standard deviation {:.2}-{:.2} over the floors scanned): a scene k times less contrasty (a smooth texture, fog, a low-contrast pattern) reads a threshold k times too high, a more contrasty one (a printed pattern, a high-contrast lab scene) k times too low",
        images_read(calibrations),
        prediction_scale(calibrations),
        prior::log_std_range().0,
        prior::log_std_range().1,
    ));
    let (lo, hi) = prior::FLOOR_RANGE_OF_MEAN;
    out.push(format!(
        "prior: the pixel's log response ln(light + floor), the floor (dark current and lens glare) {:.0}-{:.0} % of the scene's mean light (log-uniform; scanned at {}); not measured without frames, its spread is in the interval: sRGB photographs decoded to linear luminance, each under every floor ({} calibrations)",
        100.0 * lo,
        100.0 * hi,
        prior::floors_scanned(),
        calibrations.len()
    ));
    out.push(flow_precision_assumption(rates));
    out
}

/// What the recording's own frames, scanned in the photographs' place, stand for.
fn frame_image_assumptions(calibrations: &[Calibration], images: usize) -> [String; 2] {
    let (lo, hi) = prior::FLOOR_RANGE_OF_MEAN;
    [
        format!(
            "contrast: line scans through {images} of the recording's own frames (evenly spread over it; their flow not followed) stand for the scene's log contrast in the natural photographs' place, with the travel and flow directions the events give; their spread is in the interval as the photographs' is (x {:.2}); a frame blurred by its exposure along the motion is smoother than the scene and reads the threshold low, a photoreceptor or refractory period that thins the events reads it high: the method systematic of frames holds both",
            prediction_scale(calibrations),
        ),
        format!(
            "the pixel's log response ln(DN + floor), the floor (the frames' offset b, dark current and glare) {:.0}-{:.0} % of each frame's mean (log-uniform; scanned at {}): the events' timing that measures b needs the frames' flow; its spread is in the interval ({} calibrations)",
            100.0 * lo,
            100.0 * hi,
            prior::floors_scanned(),
            calibrations.len()
        ),
    ]
}

/// How precisely the events' flow gives the travel.
fn flow_precision_assumption(rates: &RecordingRates) -> String {
    format!(
        "flow precision: half a pixel of displacement per window, or the split-half spread where larger: {:.1} % of the travel, a systematic error",
        100.0 * rates.travel_relative_error
    )
}

/// The method systematic term in every interval, and what it was measured on.
fn method_systematic_assumption(rates: &RecordingRates, frames: bool) -> String {
    if let Some(dn) = dim_frames_dn(rates.frames_median_dn).filter(|_| frames) {
        format!(
            "method systematic: {:.0} % (in ln C) in every interval, for frames under {DIM_FRAMES_DN:.0} DN (median {dn:.0} DN): a dim scene, where a photoreceptor whose cutoff falls with the light thins the events the ideal scans count and leak and noise weigh more; the smallest term that covers 95 % of such polarity-cases of simulated recordings with random scenes and sensor effects read through their frames (coverage study, benches/coverage/eppps-dim-frames-2026-12-05; the {:.0} % of brighter frames covered 79 % of them); a frame's DN depends on exposure and gain, so short exposures of a bright scene are held to this wider term too",
            100.0 * METHOD_LN_SYSTEMATIC_DIM,
            100.0 * METHOD_LN_SYSTEMATIC
        )
    } else if frames {
        format!(
            "method systematic: {:.0} % (in ln C) in every interval, the scans' error beyond their own intervals on simulated recordings with known thresholds, random scenes and random sensor effects read through their frames (coverage study, 262 polarity-cases: the smallest term that covers 95 % of them; 90 % of 80 draws it was not measured on); a sensor whose bandwidth, refractory period, leak or noise lies far outside that study's range moves the count further",
            100.0 * METHOD_LN_SYSTEMATIC
        )
    } else {
        format!(
            "method systematic: {:.0} % (in ln C) in every interval beside the prior's spread, the scans' error on simulated recordings with known thresholds and no other effect (six polarity-cases); bandwidth or a refractory period, which thin the events further, is not in it. Scope, from 55 coverage draws read without frames: the intervals held 27 of 27 ON and 26 of 27 OFF thresholds of scenes as contrasty as the prior's photographs and at 20 DN or more of their frames, and 15 of 18 and 12 of 18 of the rest: a texture 1.8-2.4 times less contrasty than the least contrasty photograph read 3-5 times high, and under 20 DN a photoreceptor slowed by the dark thinned the events (read 3-5 times high) or leak added to few (read 4-5 times low) (benches/coverage/eppps-scope-2026-12-04)",
            100.0 * METHOD_LN_SYSTEMATIC_WITHOUT_FRAMES
        )
    }
}

/// The curve in the recording's terms: events per kept pixel per second it would make.
fn reported_curve(rates: &RecordingRates, calibrations: &[Calibration]) -> Vec<ReportedPoint> {
    let scale =
        rates.counted_travel_px / (rates.kept_pixels.max(1) as f64 * rates.duration_s.max(1e-9));
    let grid = threshold_grid();
    (0..grid.len())
        .map(|k| {
            let values: Vec<f64> = calibrations
                .iter()
                .map(|c| (c.curve[k].on_per_px + c.curve[k].off_per_px) * scale)
                .collect();
            ReportedPoint {
                ct: grid[k],
                events_per_pixel_per_second: values.iter().sum::<f64>()
                    / values.len().max(1) as f64,
                lo: values.iter().copied().fold(f64::INFINITY, f64::min),
                hi: values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            }
        })
        .collect()
}

/// The reported curve at `ct`, interpolated in log-log.
fn curve_at(curve: &[ReportedPoint], ct: f64) -> Option<f64> {
    curve
        .windows(2)
        .find(|w| w[0].ct <= ct && ct <= w[1].ct)
        .and_then(|w| {
            let (a, b) = (
                w[0].events_per_pixel_per_second,
                w[1].events_per_pixel_per_second,
            );
            (a > 0.0 && b > 0.0).then(|| {
                let f = (ct.ln() - w[0].ct.ln()) / (w[1].ct.ln() - w[0].ct.ln());
                (a.ln() + f * (b.ln() - a.ln())).exp()
            })
        })
}

/// The estimate's report: the estimator with its calibrations, the calibration curve and
/// where the recording's rate lies among the simulator presets, and the recording's rates.
fn report(
    result: &mut CtEstimate,
    rates: &RecordingRates,
    calibrations: &[Calibration],
    (on, off): (&Polarity, &Polarity),
    frames_used: bool,
) {
    let curve = reported_curve(rates, calibrations);
    let compared = (rates.on_per_px + rates.off_per_px) * rates.counted_travel_px
        / (rates.kept_pixels.max(1) as f64 * rates.duration_s.max(1e-9));
    let (presets, position) = preset_position(&curve, compared);
    result.estimators = vec![estimator_report(rates, calibrations, (on, off))];
    result
        .extra
        .insert("calibration_curve".into(), json!(curve));
    result.extra.insert("presets".into(), json!(presets));
    result
        .extra
        .insert("preset_position".into(), json!(position));
    result.extra.insert(
        "recording".into(),
        recording_report(rates, compared, frames_used),
    );
}

/// The calibration `curve`'s rate at each simulator preset, and where the recording's
/// `compared` rate lies among them.
fn preset_position(curve: &[ReportedPoint], compared: f64) -> (Vec<PresetPoint>, String) {
    let presets: Vec<PresetPoint> = PRESETS
        .iter()
        .filter_map(|&ct| {
            Some(PresetPoint {
                ct,
                events_per_pixel_per_second: curve_at(curve, ct)?,
            })
        })
        .collect();
    let position = presets
        .windows(2)
        .find(|w| {
            w[0].events_per_pixel_per_second >= compared
                && compared >= w[1].events_per_pixel_per_second
        })
        .map(|w| format!("between the presets CT {} and CT {}", w[0].ct, w[1].ct))
        .unwrap_or_else(|| match presets.first() {
            Some(p) if compared > p.events_per_pixel_per_second => {
                format!("above the CT {} preset", PRESETS[0])
            }
            _ => format!("below the CT {} preset", PRESETS[PRESETS.len() - 1]),
        });
    (presets, position)
}

/// The one estimator: its thresholds, the calibrations' own and their spread, and the
/// still pixels' background.
fn estimator_report(
    rates: &RecordingRates,
    calibrations: &[Calibration],
    (on, off): (&Polarity, &Polarity),
) -> EstimatorReport {
    EstimatorReport {
        name: "events_per_pixel_of_travel",
        description: "the threshold at which ideal pixels along line scans with the recording's travel make its ON (OFF) events per pixel of travel, noise taken out; one per calibration, combined in the logarithm",
        ct_on: on.measured.clone(),
        ct_off: off.measured.clone(),
        frame_rate_series_on: Vec::new(),
        frame_rate_series_off: Vec::new(),
        details: json!({
            "calibrations": calibrations.iter().map(|c| c.name.clone()).collect::<Vec<_>>(),
            "per_calibration_on": on.per_calibration,
            "per_calibration_off": off.per_calibration,
            "prior_ln_sd_on": on.prior_ln_sd,
            "prior_ln_sd_off": off.prior_ln_sd,
            "prior_prediction_scale": prediction_scale(calibrations),
            "frames_median_dn": rates.frames_median_dn,
            "still_pixels": rates.still.as_ref().map(|s| (s, s.total())).map(|(s, t)| json!({
                "pixels": t.pixels,
                "pixel_seconds": t.exposure_s,
                "events": {"on": t.events[0], "off": t.events[1]},
                "by_brightness": s.ranges,
                "decides_noise": {"on": rates.still_decides[0], "off": rates.still_decides[1]},
            })),
            "z95": z95(),
        }),
    }
}

/// The recording's rates as compared, with how they were counted.
fn recording_report(rates: &RecordingRates, compared: f64, frames_used: bool) -> serde_json::Value {
    json!({
            "events_per_pixel_per_second": compared,
            "supported_events_per_pixel_per_second": rates.events_per_pixel_per_second,
            "on_per_pixel_of_travel": rates.on_per_px,
            "off_per_pixel_of_travel": rates.off_per_px,
            "counted_units": rates.counted_units,
            "counted_unit": if frames_used { "pixel" } else { "8 x 8 px tile" },
            "kept_pixels": rates.kept_pixels,
            "travel_px": rates.counted_travel_px,
            "speed_median_px_s": rates.speed_median_px_s,
            "flow": rates.flow_source,
            "support_window_ms": rates.support_window_us as f64 / 1e3,
            "unsupported_share": rates.unsupported_share,
            "chance_support": rates.chance_support,
            "noise_share_at_most": {"on": rates.noise[0].noise_share, "off": rates.noise[1].noise_share},
            "counted": "the events of the units that count (every reliable pixel with frames, 8 x 8 px tiles with a supported event without), in the windows with a flow, with the noise taken out: the middle of all of them and all but the most noise they can hold (unsupported events over the time no neighbour's window covers, 97.5 % upper end; chance_support is how often a noise event finds a neighbour by chance); supported_events_per_pixel_per_second is the supported events per kept pixel per second, events_per_pixel_per_second the compared rate per kept pixel per second",
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frames at 11 DN whose fitted offset 35.1 DN has the range -2.3 .. 60 DN (coverage
    /// draw 13037): the range moves their contrast by (11 + 60) / (11 + 0) = 6.45 (no
    /// negative offset scanned), so they are scanned at 0, 35.1 and 60 DN; at 200 DN the
    /// same range moves it by 260 / 200 = 1.3, still bracketed; a range of 30 .. 40 DN at
    /// 100 DN moves it by 1.077 and the fitted offset is read alone.
    #[test]
    fn a_fitted_offset_is_bracketed_where_its_range_moves_the_contrast() {
        let mut frames = crate::fit::effects::fixture::static_frames(4, 4, 0.3, 11.0);
        frames.offset = 35.1;
        frames.offset_range = (-2.3, 60.0);
        let bracket = offset_bracket(&frames, Some(11.0)).unwrap();
        assert_eq!((bracket.lo, bracket.hi), (0.0, 60.0));
        assert!((bracket.ratio - 71.0 / 11.0).abs() < 1e-9, "{bracket:?}");
        assert!((offset_bracket(&frames, Some(200.0)).unwrap().ratio - 1.3).abs() < 1e-9);
        assert_eq!(offset_bracket(&frames, None), None);
        frames.offset = 34.0;
        frames.offset_range = (30.0, 40.0);
        assert_eq!(offset_bracket(&frames, Some(100.0)), None);

        frames.offset = 35.1;
        frames.offset_range = (-2.3, 60.0);
        let options = EpppsOptions::default();
        let excluded = vec![false; 16];
        let response = FramesResponse::Known(offset_bracket(&frames, Some(11.0)));
        let basis = Basis::new(Some(&frames), None, response, &excluded, &options);
        let offsets: Vec<f32> = basis.responses.iter().map(|(r, _)| r.offset_dn).collect();
        assert_eq!(offsets, vec![0.0, 35.1, 60.0]);
        let single = Basis::new(
            Some(&frames),
            None,
            FramesResponse::Known(None),
            &excluded,
            &options,
        );
        assert_eq!(single.responses.len(), 1);
        assert_eq!(single.responses[0].0.offset_dn, 35.1);
    }

    fn beyond(above: usize, below: usize) -> Beyond {
        Beyond {
            above,
            below,
            top: 9.49,
            bottom: 0.03,
        }
    }

    /// Where the low-passed scans read a polarity, it takes their reading and an interval
    /// that holds both: ideal 1.0 [0.7, 1.4] beside low-passed 0.5 [0.35, 0.7] becomes 0.5
    /// [0.35, 1.4], its systematic grown by sqrt(ln(1.4 / 0.5)^2 - ln(0.7 / 0.5)^2) / 1.96
    /// = 0.4965 in ln, 0.2482 at 0.5; a polarity the low-passed scans read nothing for
    /// keeps the ideal reading.
    #[test]
    fn a_slow_photoreceptor_s_reading_is_taken_with_an_interval_holding_both() {
        let polarity = |value: f64, ci95: [f64; 2], why: Option<&str>| {
            let mut measured = Measured::log_normal(value, 0.1, 0.0);
            measured.ci95 = ci95;
            measured.systematic = 0.0;
            Polarity {
                per_calibration: vec![Some(value)],
                measured,
                prior_ln_sd: 0.0,
                beyond_grid: Beyond::default(),
                why: why.map(String::from),
            }
        };
        let mut slow = SlowReach {
            found: SlowPhotoreceptor {
                cutoff_hz: 5.0,
                cutoff_range_hz: [3.0, 7.0],
                cutoff_at_median_dn_hz: 1.0,
                distance_without: 2.0,
                distance_at_cutoff: 1.0,
                significance: 5.0,
                threshold_ratios: [0.5, 0.5],
                quantiser_thresholds: [0.1, 0.1],
                block_row_step: 1,
            },
            on: polarity(0.5, [0.35, 0.7], None),
            off: polarity(f64::NAN, [f64::NAN; 2], Some("no events")),
            ideal: [None, None],
        };
        let (mut on, mut off) = (
            polarity(1.0, [0.7, 1.4], None),
            polarity(1.0, [0.7, 1.4], None),
        );
        slow.adopt(&mut on, &mut off);
        assert_eq!(on.measured.value, 0.5);
        assert_eq!(on.measured.ci95, [0.35, 1.4]);
        assert!(
            (on.measured.systematic - 0.2482).abs() < 1e-3,
            "{:?}",
            on.measured
        );
        assert_eq!((off.measured.value, off.measured.ci95), (1.0, [0.7, 1.4]));
        assert_eq!(slow.thresholds(), [Some(0.5), None]);
        assert_eq!(slow.ideal[0].as_ref().map(|m| m.value), Some(1.0));
        assert!(slow.ideal[1].is_none());
    }

    #[test]
    fn dim_frames_widen_the_method_systematic_and_a_prior_keeps_its_own() {
        let calibration = |image| Calibration {
            name: String::new(),
            image,
            curve: Vec::new(),
        };
        let frames = [calibration(None)];
        assert_eq!(
            method_systematic(&frames, Some(19.0), false),
            METHOD_LN_SYSTEMATIC_DIM
        );
        assert_eq!(
            method_systematic(&frames, Some(20.0), false),
            METHOD_LN_SYSTEMATIC
        );
        assert_eq!(
            method_systematic(&frames, None, false),
            METHOD_LN_SYSTEMATIC
        );
        let prior = [calibration(Some(0)), calibration(Some(1))];
        assert_eq!(
            method_systematic(&prior, Some(5.0), false),
            METHOD_LN_SYSTEMATIC_WITHOUT_FRAMES
        );
        // the recording's own frames scanned as photographs keep the frames' terms
        assert_eq!(
            method_systematic(&prior, Some(15.0), true),
            METHOD_LN_SYSTEMATIC_DIM
        );
        assert_eq!(
            method_systematic(&prior, Some(80.0), true),
            METHOD_LN_SYSTEMATIC
        );
    }

    #[test]
    fn calibrations_give_their_thresholds_or_a_reason() {
        let at = [
            Inverted::At(0.3),
            Inverted::Between(0.4, 0.8),
            Inverted::Above(9.49),
        ];
        let values = classify(&at, beyond(1, 0), 0.05, Side::On).unwrap();
        assert_eq!(values.len(), 3);
        assert!((values[1] - 0.32f64.sqrt()).abs() < 1e-12 && values[2] == 9.49);
        // a calibration without events to compare with: no value, and the count said
        let why = classify(
            &[Inverted::At(0.3), Inverted::Outside],
            beyond(0, 0),
            0.05,
            Side::Off,
        )
        .unwrap_err();
        assert!(
            why.contains("1 of the 2 calibrations make no OFF events"),
            "{why}"
        );
        // more than half only bounded: beyond the method's range, on the side it lies
        let why = classify(
            &[
                Inverted::Above(9.49),
                Inverted::Above(9.49),
                Inverted::At(3.0),
            ],
            beyond(2, 0),
            1e-4,
            Side::On,
        )
        .unwrap_err();
        assert!(why.contains("above the method's range"), "{why}");
        let why = classify(
            &[
                Inverted::Below(0.03),
                Inverted::Below(0.03),
                Inverted::At(0.05),
            ],
            beyond(0, 2),
            9.0,
            Side::On,
        )
        .unwrap_err();
        assert!(why.contains("below the method's range"), "{why}");
        // no events of the polarity at all
        let why = classify(&at, beyond(0, 0), 0.0, Side::On).unwrap_err();
        assert!(why.contains("no supported ON events"), "{why}");
    }
}
