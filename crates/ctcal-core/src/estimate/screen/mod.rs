//! `estimate screen`: thresholds from a recording of an on-screen stimulus (Stoffregen et
//! al. 2020, Sec. 3.1, the "on-screen checkerboard"): the stimulus `ctcal calib
//! checkerboard` wrote is played on a monitor and recorded; its frames are simulated and
//! the thresholds matched to the recorded events.
//!
//! The paper simulated the stimulus as if its pixel values were the light reaching the
//! camera, and found thresholds (~0.5) that disagreed with its other estimates (0.2-0.5 for
//! the same sensor). Between stimulus and camera sits a display: a gamma curve and a black
//! level change the log contrast the camera sees. Here both are fitted:
//!
//! 1. time: the stimulus clock is aligned with the events by the correlation of the event
//!    rate with the stimulus's change at each refresh (events burst at refreshes);
//! 2. naive: the stimulus frames simulated directly (no display), thresholds by a Brent root
//!    of the median count log ratio per region and refresh ([`super::resim`]) -- the paper's
//!    method, reported as `naive_ct`;
//! 3. display: thresholds, black level, optical blur and the camera DN of white fitted
//!    together by Nelder-Mead (argmin) on the squared log ratios of every region's count
//!    over the stimulus, through ctcal's display model ([`crate::sim::display`]) and the
//!    sensor's log response (declared, or both candidates: [`ResponsePrior`]), each fit
//!    started on its black level ([`display_fit`]); then the thresholds refined by the
//!    Brent root. The stimulus has three levels (black, grey 128,
//!    white 255): white-grey transitions fix `gamma / C` (a power-law display changes their
//!    log contrast by `gamma ln(255/128)`), transitions to black fix their log contrast over
//!    `C`, which depends on how bright white is imaged against the sensor's dark response.
//!    Gamma and white trade off along a valley the counts cannot resolve (on the coverage
//!    study's cases a fit of both drifted to gamma 0.9 with white at 30 DN or 2.6 at 255 DN,
//!    its thresholds from 0.47 to 0.84 for a true 0.72, and a fit of white at a fixed gamma
//!    ends where its start leads it), so gamma is a prior ([`GammaPrior`]): the fit is made
//!    at its centre and, from a dim and a bright white, at both ends; the best fit is
//!    reported, and the spread of the fits that explain the counts as well is in the
//!    intervals. A measured screen model (its photometered gamma and white) fixes white
//!    and gamma within +-0.1.
//! 4. lag: a photoreceptor slowed in the black squares fires fewer events than ideal pixels
//!    and reads too large thresholds; its cutoff is measured from when the events come
//!    after the refreshes and the changes ([`lag`]), and the thresholds are matched again
//!    through the fitted display with that photoreceptor.

mod bursts;
mod coarse;
mod display_fit;
pub mod dlt;
mod images;
pub mod lag;
pub mod located;
mod matching;
pub mod register;
pub mod span;
#[cfg(test)]
mod tests;

use super::interval::Measured;
use super::resim::{Cells, Counts, Intervals, cell_spread, log_ratio};
use super::root::{Crossing, Search, threshold_root};
use super::{CtEstimate, Determinable, EstimateError, EstimatorReport, Progress};
use crate::events::{EventChunk, Frame, Sensor, TimeUs};
use crate::hint::{Hint, Text};
use crate::sim::display::DisplayModel;
use crate::sim::footprints::Footprints;
use crate::sim::log_response::LogMap;
use crate::sim::pixel::Transition;
use crate::sim::screen_geometry::ScreenWarp;
use crate::sim::source::{DisplaySource, MemoryFrames};
use crate::sim::{DisplayParams, LogResponse, PixelMaps, PixelParams};
use argmin::core::{CostFunction, Error as ArgminError};
use display_fit::{DisplayFits, Joint, fit_displays};
use located::Located;
use register::Registration;
use serde_json::json;
use std::sync::atomic::Ordering::Relaxed;

/// The camera DN of white the fits start from beside the screen model's: a dim and a bright
/// exposure of the screen (the fit moves white along a valley whose end it reaches from
/// where it starts; see [`fit_displays`]).
const WHITE_STARTS_DN: [f64; 2] = [50.0, 300.0];

/// Side of the counting tiles, pixels: small enough to keep each region's own transitions,
/// large enough to average the pixels' threshold mismatch.
const TILE_PX: usize = 4;

/// What `estimate screen` reads.
pub struct ScreenInput<'a> {
    pub sensor: Sensor,
    pub events: &'a EventChunk,
    /// The stimulus frames, times from 0 at its first refresh.
    pub stimulus: &'a [Frame],
    /// The screen model to start from (black level, blur and the camera DN of white are
    /// fitted; gamma is `gamma_prior`'s).
    pub screen: DisplayParams,
    /// What is known of the display's gamma.
    pub gamma_prior: GammaPrior,
    /// What is known of the sensor's log response in the dark.
    pub response: ResponsePrior,
    /// The refresh rate, when not the stimulus's frame rate.
    pub refresh_hz: Option<f64>,
    pub excluded: &'a [bool],
}

/// What is known of the display's gamma, which the counts cannot tell from the camera DN of
/// white (see the module docs): the thresholds are fitted at [`GammaPrior::centre`] and at
/// both ends of [`GammaPrior::range`], and the spread of the fits that explain the counts
/// as well as the best, in the prior's standard deviations, is a systematic of the
/// intervals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GammaPrior {
    /// No measured display: gamma 2.2 (sRGB, IEC 61966-2-1) within 1.8-2.6, the span of
    /// displays in use: 1.8 (Mac OS before 10.6), 2.4 (ITU-R BT.1886), CRTs measured at
    /// 2.35-2.55 (Poynton, *Digital Video and HD*, 2012) and 2.6 (DCI cinema).
    Displays,
    /// The screen model's gamma was measured (a photometer over the grey levels): within
    /// +-0.1.
    Measured(f64),
}

impl GammaPrior {
    /// sRGB's effective gamma.
    pub const SRGB: f64 = 2.2;

    pub fn centre(self) -> f64 {
        match self {
            GammaPrior::Displays => Self::SRGB,
            GammaPrior::Measured(g) => g,
        }
    }

    pub fn range(self) -> [f64; 2] {
        match self {
            GammaPrior::Displays => [1.8, 2.6],
            GammaPrior::Measured(g) => [g - 0.1, g + 0.1],
        }
    }

    /// How many standard deviations the range's ends lie from its centre: a uniform prior
    /// over the displays in use has sqrt(3) (its standard deviation is the half-range over
    /// sqrt(3)); a measured gamma's +-0.1 is one.
    pub fn ends_in_sigmas(self) -> f64 {
        match self {
            GammaPrior::Displays => 3f64.sqrt(),
            GammaPrior::Measured(_) => 1.0,
        }
    }

    fn says(self) -> String {
        let [lo, hi] = self.range();
        match self {
            GammaPrior::Displays => format!(
                "the display's gamma is not measured: {:.1} (sRGB) with {lo:.1}-{hi:.1} (the displays in use: Mac OS 1.8 to BT.1886 2.4, CRTs 2.35-2.55, DCI 2.6), and the camera DN of white, which the counts trade against gamma and the threshold, fitted from {:.0} and {:.0} DN at both ends: the best fit is reported, and the spread of the fits within 3x its cost is in the intervals (as a uniform prior's standard deviation); give the measured display as the screen model to narrow them",
                self.centre(),
                WHITE_STARTS_DN[0],
                WHITE_STARTS_DN[1]
            ),
            GammaPrior::Measured(g) => format!(
                "the display's gamma {g:.2} and the camera DN of white from the screen model, taken as measured (gamma +-0.1, one standard deviation, fitted too; the best fit is reported, and the spread of the fits within 3x its cost is in the intervals)"
            ),
        }
    }
}

/// What is known of the sensor's log response, which sets how much log contrast the
/// stimulus's dark squares carry. v2e's lin-log (linear below 20 DN; Hu, Liu & Delbruck
/// 2021) gives a transition to a black square of a few camera DN a larger log change than
/// a photoreceptor's `ln(I + I_dark)` (the dark current is an offset under the log;
/// Lichtsteiner, Posch & Delbruck 2008) with a small offset; thresholds matched
/// through the wrong one read up to 3x too high on the coverage study's on-screen draws.
/// Through a display, `ln(W (b + (1 - b) x^gamma) + offset)` depends on the black level
/// `b` and the offset only through `(W b + offset) / (W (1 - b))`: the fitted black level
/// absorbs the dark offset, and the camera DN of white `W` drops out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ResponsePrior {
    /// Named by the user: only it is simulated (white and black level fitted as before).
    Declared(LogMap),
    /// Not named: both are fitted, v2e's lin-log (white fitted) and a pure log whose dark
    /// offset the black level absorbs ([`ABSORBED_DARK_OFFSET`]); the better fit is
    /// reported, and the other's thresholds join the intervals' spread when it explains
    /// the counts as well ([`display_fit::COMPATIBLE_COST`]).
    Unknown,
}

/// The `eps` of the pure log fitted when the response is not named: 2.6e-3 DN, about 1e-5
/// of a white of 220-255 DN, at the lowest black level the fit tries, so the fitted black
/// level carries the dark offset.
pub const ABSORBED_DARK_OFFSET: f64 = 1e-5;

impl ResponsePrior {
    /// The responses fitted, each with whether the camera DN of white is fitted with it
    /// (not under the pure log whose offset the black level absorbs: white drops out).
    fn candidates(self) -> Vec<(LogMap, bool)> {
        match self {
            ResponsePrior::Declared(log) => vec![(log, true)],
            ResponsePrior::Unknown => vec![
                (LogMap::new(LogResponse::V2e, 0.001), true),
                (LogMap::new(LogResponse::Eps, ABSORBED_DARK_OFFSET), false),
            ],
        }
    }

    fn says(self, chosen: LogMap, others_compatible: bool) -> String {
        match self {
            ResponsePrior::Declared(log) => {
                format!(
                    "the sensor's log response as declared: {}",
                    response_name(log)
                )
            }
            ResponsePrior::Unknown => format!(
                "the sensor's log response is not declared: v2e's lin-log and a pure log with a dark offset (absorbed by the fitted black level) were both fitted; {} explains the counts best{}; declaring the sensor's response fits only it",
                response_name(chosen),
                if others_compatible {
                    ", the other as well within 3x its cost, and its thresholds are in the intervals' spread"
                } else {
                    ", the other at more than 3x its cost"
                }
            ),
        }
    }
}

/// The response the naive simulation (the stimulus values as the camera's) is made
/// through: the declared one, else v2e's lin-log (the paper's).
fn naive_response(prior: ResponsePrior) -> LogMap {
    prior.candidates()[0].0
}

/// Whether `log` is the undeclared pure log whose dark offset the black level carries
/// (under which the camera DN of white drops out and is not fitted).
fn offset_in_black_level(prior: ResponsePrior, log: LogMap) -> bool {
    prior == ResponsePrior::Unknown && log.response() == LogResponse::Eps
}

/// A response in words.
fn response_name(log: LogMap) -> String {
    match log.response() {
        LogResponse::V2e => "v2e's lin-log (ln DN above 20 DN, linear below)".into(),
        LogResponse::Eps if log.eps() <= ABSORBED_DARK_OFFSET * 1.01 => {
            "a pure log, ln(DN + offset), the offset in the black level".into()
        }
        LogResponse::Eps => format!("ln(DN / 255 + {})", log.eps() as f32),
    }
}

/// The stimulus's frame rate, Hz.
fn stimulus_rate(stimulus: &[Frame]) -> Option<f64> {
    let mut gaps: Vec<TimeUs> = stimulus.windows(2).map(|w| w[1].t - w[0].t).collect();
    gaps.sort_unstable();
    let median = *gaps.get(gaps.len() / 2)?;
    (median > 0).then(|| 1e6 / median as f64)
}

/// The recording time of the stimulus's t = 0: where the event bursts line up with the
/// refreshes at which the stimulus changes most. Coarse 1 ms search over every possible
/// shift, then 20 us refinement.
fn align(events: &EventChunk, stimulus: &[Frame]) -> Option<TimeUs> {
    // the change the stimulus makes at each frame
    let changes: Vec<(TimeUs, f64)> = stimulus
        .windows(2)
        .map(|w| {
            let d: f64 = w[0]
                .pixels
                .iter()
                .zip(&w[1].pixels)
                .map(|(&a, &b)| (a as f64 - b as f64).abs())
                .sum();
            (w[1].t, d)
        })
        .filter(|(_, d)| *d > 0.0)
        .collect();
    if changes.is_empty() || events.is_empty() {
        return None;
    }
    let (first, last) = (events.t[0], events.t[events.len() - 1]);
    let score = |shift: TimeUs, window: TimeUs| -> f64 {
        changes
            .iter()
            .map(|&(t, d)| {
                let a = events.t.partition_point(|&e| e < t + shift);
                let b = events.t.partition_point(|&e| e < t + shift + window);
                d * (b - a) as f64
            })
            .sum()
    };
    let stimulus_end = stimulus[stimulus.len() - 1].t;
    let (lo, hi) = (first - stimulus_end, last - stimulus[0].t);
    let mut best = (lo, f64::NEG_INFINITY);
    let mut shift = lo;
    while shift <= hi {
        let s = score(shift, 1000);
        if s > best.1 {
            best = (shift, s);
        }
        shift += 1000;
    }
    let mut refined = best;
    let mut shift = best.0 - 1000;
    while shift <= best.0 + 1000 {
        let s = score(shift, 200);
        if s > refined.1 {
            refined = (shift, s);
        }
        shift += 20;
    }
    Some(refined.0)
}

/// Everything one simulation of the stimulus needs.
struct Setup<'a> {
    input: &'a ScreenInput<'a>,
    /// The stimulus on the recording's clock (for the naive simulation).
    shifted: Vec<Frame>,
    cells: Cells,
    real: Counts,
    offset_us: TimeUs,
    refresh_hz: f64,
    /// The screen seen at an angle (`None`: 1:1).
    warp: Option<Seen>,
    /// The photoreceptor's cutoff at 255 camera DN ([`lag`]; `None`: ideal pixels).
    cutoff_hz: Option<f64>,
    /// The sensor's log response (the best fit's once the display is fitted).
    log: LogMap,
    /// Each pixel's factor on the thresholds ([`threshold_dither`]).
    dither: Vec<f32>,
    evaluations: std::sync::atomic::AtomicUsize,
    /// The events of the latest simulation (room made for as many in the next: a hint).
    latest_events: std::sync::atomic::AtomicUsize,
}

impl Setup<'_> {
    /// The stimulus's refreshes on the recording's clock.
    fn refresh_clock(&self) -> lag::RefreshClock {
        let period = 1e6 / self.refresh_hz;
        let start_us = self.offset_us + self.input.stimulus[0].t;
        lag::RefreshClock {
            start_us,
            period_us: period,
            end_us: start_us + (self.input.stimulus.len() as f64 * period).round() as TimeUs,
        }
    }

    /// Counts simulated with thresholds and a display (`None`: the naive simulation, the
    /// stimulus values as the camera's), with the setup's photoreceptor.
    fn counts(
        &self,
        ct: (f64, f64),
        display: Option<&DisplayParams>,
    ) -> Result<Counts, EstimateError> {
        self.counts_through(ct, display, self.log)
    }

    /// [`Self::counts`] through the log response `log`.
    fn counts_through(
        &self,
        ct: (f64, f64),
        display: Option<&DisplayParams>,
        log: LogMap,
    ) -> Result<Counts, EstimateError> {
        Ok(self
            .cells
            .count(&self.events_through(ct, display, self.cutoff_hz, log)?))
    }

    /// The events simulated with thresholds, a display and the photoreceptor's cutoff at
    /// 255 camera DN (`None`: ideal pixels), through the setup's log response.
    fn events_at(
        &self,
        ct: (f64, f64),
        display: Option<&DisplayParams>,
        cutoff_hz: Option<f64>,
    ) -> Result<EventChunk, EstimateError> {
        self.events_through(ct, display, cutoff_hz, self.log)
    }

    /// [`Self::events_at`] through the log response `log`.
    fn events_through(
        &self,
        ct: (f64, f64),
        display: Option<&DisplayParams>,
        cutoff_hz: Option<f64>,
        log: LogMap,
    ) -> Result<EventChunk, EstimateError> {
        self.evaluations
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let bug = |e: crate::sim::SimError| {
            EstimateError::new(format!("screen simulation: {e}"), "report this as a bug")
        };
        // the naive simulation of a screen seen at an angle: the stimulus values as the
        // camera's, resampled onto the sensor
        let identity;
        let display = match (display, &self.warp) {
            (None, Some(_)) => {
                identity = DisplayParams {
                    refresh_hz: self.refresh_hz,
                    gamma: 1.0,
                    black_level: 0.0,
                    white_dn: 255.0,
                    blur_px: None,
                    time_offset_s: None,
                };
                Some(&identity)
            }
            (display, _) => display,
        };
        let frames = match display {
            None => MemoryFrames::new(&self.shifted, Transition::Hold),
            Some(_) => MemoryFrames::new(self.input.stimulus, Transition::Hold),
        }
        .map_err(bug)?;
        let params = PixelParams {
            cutoff_hz,
            log_response: Some(log.response()),
            log_eps: Some(log.eps()),
            ..PixelParams::ideal(ct.0, ct.1)
        };
        let mut events = EventChunk::with_capacity(self.latest_events.load(Relaxed));
        let mut sink = |chunk: &EventChunk| -> Result<(), crate::sim::SimError> {
            events.extend_from(chunk);
            Ok(())
        };
        match display {
            None => {
                let mut source = frames;
                crate::sim::run(&mut source, &params, self.dithered(ct), &mut sink, |_| {})
                    .map_err(bug)?;
            }
            Some(d) => {
                let mut d = d.clone();
                d.refresh_hz = self.refresh_hz;
                d.time_offset_s = Some(self.offset_us as f64 * 1e-6);
                let mut source = DisplaySource::new(frames, DisplayModel::new(&d));
                if let Some(seen) = &self.warp {
                    source = source.seen_with(seen.warp.clone(), seen.footprints.clone());
                }
                crate::sim::run(&mut source, &params, self.dithered(ct), &mut sink, |_| {})
                    .map_err(bug)?;
            }
        }
        events.sort_by_time();
        self.latest_events.store(events.len(), Relaxed);
        Ok(events)
    }

    /// Thresholds `ct` spread evenly over +-[`THRESHOLD_DITHER`] across the pixels (a
    /// golden-ratio sequence in pixel order, so every tile holds the whole spread): a
    /// region's count then changes in steps of one pixel, not of all its pixels at once,
    /// as a threshold or the display moves, and the fits' cost is smooth enough for a
    /// simplex to descend. The same dither in every simulation (common random numbers).
    fn dithered(&self, ct: (f64, f64)) -> PixelMaps {
        let scaled = |c: f64| Some(self.dither.iter().map(|&f| f * c as f32).collect());
        PixelMaps {
            ct_on: scaled(ct.0),
            ct_off: scaled(ct.1),
            leak_factor: None,
        }
    }

    /// The roots of the ON and OFF median log ratios ([`super::root`]), the display fixed;
    /// [`Unmatched::Beyond`] where no threshold in [`THRESHOLD_LIMITS`] matches the counts.
    fn thresholds(
        &self,
        start: (f64, f64),
        display: Option<&DisplayParams>,
    ) -> Result<(f64, f64), Unmatched> {
        let mut ct = [start.0, start.1];
        for slot in 0..2 {
            let problem = Root {
                setup: self,
                display,
                other: ct[1 - slot],
                on: slot == 0,
            };
            let cost = |c: f64| {
                problem
                    .cost(&c)
                    .map_err(|e| EstimateError::new(e.to_string(), "report this as a bug"))
            };
            let search = Search {
                first_log_step: 0.25,
                limits: THRESHOLD_LIMITS,
                relative_tolerance: 0.002,
                max_iterations: 25,
            };
            ct[slot] = match threshold_root(cost, ct[slot], &search)? {
                Crossing::Root(c) => c,
                Crossing::Beyond { reached, too_many } => {
                    return Err(Unmatched::Beyond(format!(
                        "the simulated stimulus makes {} {} events than the recording even at a threshold of {reached} (the {} tried){}",
                        if too_many { "more" } else { "fewer" },
                        if slot == 0 { "ON" } else { "OFF" },
                        if too_many { "largest" } else { "smallest" },
                        if too_many {
                            ": the recording has fewer events than any threshold ctcal tries would make (check that the stimulus is the one the recording shows)"
                        } else {
                            ": the recording has more events than the stimulus can make (background events such as leak or noise, or another stimulus than the one given)"
                        },
                    )));
                }
            };
        }
        Ok((ct[0], ct[1]))
    }
}

/// Why thresholds were not matched: no threshold within [`THRESHOLD_LIMITS`] makes the
/// recording's counts (the estimate is then not determinable, with this reason), or an
/// error.
enum Unmatched {
    Beyond(String),
    Failed(EstimateError),
}

impl From<EstimateError> for Unmatched {
    fn from(e: EstimateError) -> Self {
        Unmatched::Failed(e)
    }
}

/// The screen seen at an angle, with the stimulus frames' footprints through it (each
/// simulation renders their uniform footprints once per DN: [`crate::sim::footprints`]).
struct Seen {
    warp: std::sync::Arc<ScreenWarp>,
    footprints: std::sync::Arc<[Footprints]>,
}

impl Seen {
    fn new(warp: std::sync::Arc<ScreenWarp>, stimulus: &[Frame]) -> Self {
        let footprints = Footprints::of_frames(&warp, stimulus).into();
        Self { warp, footprints }
    }
}

/// The factors of [`Setup::dithered`] for `pixels` pixels: a golden-ratio sequence over
/// +-[`THRESHOLD_DITHER`].
fn threshold_dither(pixels: usize) -> Vec<f32> {
    (0..pixels)
        .map(|p| {
            let u = (p as f64 * 0.618_033_988_749_895).fract();
            (1.0 + THRESHOLD_DITHER * (2.0 * u - 1.0)) as f32
        })
        .collect()
}

/// The half-width of the simulations' threshold dither ([`Setup::dithered`]), relative: a
/// uniform spread of +-5 % has a standard deviation of 2.9 % of the threshold, below the
/// mismatch of real sensors (Lichtsteiner, Posch & Delbruck 2008: 2.1 % contrast at a 15 %
/// threshold, 14 % of it), and moves an ideal pixel's mean count (proportional to the mean
/// of 1 / threshold) by 0.08 %.
const THRESHOLD_DITHER: f64 = 0.05;

/// The thresholds the stimulus may be simulated at: below 0.03 a black-white transition
/// fires some 180 events per pixel (the simulation's cost grows with them), above 6 one
/// event takes a 400-fold change of light; thresholds in use lie far inside (v2e's presets
/// 0.2-0.5, Hu et al. 2021). A recording that needs a threshold outside is refused with the
/// side it lies on.
const THRESHOLD_LIMITS: [f64; 2] = [0.03, 6.0];

/// The median log ratio of one polarity as a function of its threshold.
struct Root<'a, 'b> {
    setup: &'b Setup<'a>,
    display: Option<&'b DisplayParams>,
    other: f64,
    on: bool,
}

impl CostFunction for Root<'_, '_> {
    type Param = f64;
    type Output = f64;
    fn cost(&self, c: &f64) -> Result<f64, ArgminError> {
        let ct = if self.on {
            (*c, self.other)
        } else {
            (self.other, *c)
        };
        let simulated = self.setup.counts(ct, self.display)?;
        Ok(if self.on {
            log_ratio(&self.setup.real.on, &simulated.on)
        } else {
            log_ratio(&self.setup.real.off, &simulated.off)
        })
    }
}

/// The total variation of the log intensity a simulation sees (for saying how much the
/// display changes the contrast).
fn log_variation(stimulus: &[Frame], display: Option<&DisplayParams>, log: LogMap) -> f64 {
    let model = display.map(DisplayModel::new);
    let camera: Vec<Vec<f32>> = stimulus
        .iter()
        .map(|f| {
            let dn: Vec<f32> = f.pixels.iter().map(|&p| p as f32).collect();
            match &model {
                Some(m) => m.camera_dn(&dn, f.width as usize, f.height as usize),
                None => dn,
            }
        })
        .collect();
    camera
        .windows(2)
        .map(|w| {
            w[0].iter()
                .zip(&w[1])
                .map(|(&a, &b)| (log.apply(b) - log.apply(a)).abs() as f64)
                .sum::<f64>()
        })
        .sum()
}

/// Estimates the thresholds from a recording of `input.stimulus` on a screen.
pub fn estimate(input: &ScreenInput, progress: Progress) -> Result<CtEstimate, EstimateError> {
    let refresh_hz = refresh_rate(input)?;
    progress("aligning the stimulus with the events", 0.0);
    let offset_us = align(input.events, input.stimulus).ok_or_else(|| {
        EstimateError::new(
            "the events do not line up with the stimulus's changes",
            Text::from("check that this recording shows this stimulus").aside(Hint::Stimulus),
        )
    })?;
    span::check(input.events, input.stimulus, offset_us, refresh_hz)?;
    let (hot_mask, hot) = super::exclude_hot_pixels(input.events, input.sensor, input.excluded);
    progress("finding the screen on the sensor", 0.05);
    let inputs = register::Inputs {
        events: input.events,
        sensor: (input.sensor.width as usize, input.sensor.height as usize),
        excluded: &hot_mask,
        stimulus: input.stimulus,
        offset_us,
        refresh_hz,
        log: naive_response(input.response),
    };
    let mut screen_model = input.screen.clone();
    screen_model.refresh_hz = refresh_hz;
    let mut located = match Located::find(&inputs, &screen_model) {
        Ok(located) => located,
        Err(reason) => return Ok(unregistered(&reason)),
    };
    let (setup, excluded) = counting_setup(input, &hot_mask, &located, offset_us, refresh_hz);
    let matched = match matched_thresholds(setup, &excluded, &inputs, &mut located, progress) {
        Ok(matched) => matched,
        Err(Unmatched::Beyond(why)) => return Ok(CtEstimate::not_determinable("screen", &why)),
        Err(Unmatched::Failed(e)) => return Err(e),
    };
    // the final model's events, for the cells' spread and the bursts alike
    let final_events = matched.setup.events_at(
        matched.fitted,
        Some(&matched.display),
        matched.setup.cutoff_hz,
    )?;
    let (on, off) = measured(&matched, &final_events, input.gamma_prior)?;
    let mut estimate = CtEstimate::from_parts("screen", &on, &off, Determinable::POSITIVE);
    describe(&mut estimate, &matched, &located, hot, (on, off));
    withhold_cut_bursts(&mut estimate, &matched, &final_events, &excluded);
    progress("done", 1.0);
    Ok(estimate)
}

/// The stimulus's refresh rate: given, or its frames' median interval.
fn refresh_rate(input: &ScreenInput) -> Result<f64, EstimateError> {
    match input.refresh_hz.or_else(|| stimulus_rate(input.stimulus)) {
        Some(r) if r.is_finite() && r > 0.0 => Ok(r),
        _ => Err(EstimateError::new(
            "the stimulus does not give its refresh rate (fewer than two frames)",
            Text::default().act(Hint::RefreshHz),
        )),
    }
}

/// The real counts in cells of tiles x refresh intervals (each interval starting half a
/// refresh before the refresh whose burst it holds), over the pixels on the screen and
/// not hot, and what the simulations need to count alike; and the pixels left out.
fn counting_setup<'a>(
    input: &'a ScreenInput<'a>,
    hot_mask: &[bool],
    located: &Located,
    offset_us: TimeUs,
    refresh_hz: f64,
) -> (Setup<'a>, Vec<bool>) {
    let period = 1e6 / refresh_hz;
    let count = input.stimulus.len() + 1;
    let times: Vec<TimeUs> = (0..=count)
        .map(|k| offset_us + input.stimulus[0].t + ((k as f64 - 0.5) * period).round() as TimeUs)
        .collect();
    let excluded: Vec<bool> = hot_mask
        .iter()
        .zip(&located.on_screen)
        .map(|(&hot, &on)| hot || !on)
        .collect();
    // each small region's count over the whole stimulus: through the known geometry, a
    // region's count is the response to the transitions it saw, which pins the display's
    // curve
    let intervals = times.len() - 1;
    let cells = Cells::with_layout(
        Intervals::all(times),
        input.sensor,
        &excluded,
        5_000,
        TILE_PX,
        intervals,
    );
    let real = cells.count(input.events);
    let setup = Setup {
        input,
        shifted: input
            .stimulus
            .iter()
            .map(|f| Frame {
                t: f.t + offset_us,
                ..f.clone()
            })
            .collect(),
        cells,
        real,
        offset_us,
        refresh_hz,
        warp: located.warp.clone().map(|w| Seen::new(w, input.stimulus)),
        cutoff_hz: None,
        log: naive_response(input.response),
        dither: threshold_dither(input.sensor.width as usize * input.sensor.height as usize),
        evaluations: std::sync::atomic::AtomicUsize::new(0),
        latest_events: std::sync::atomic::AtomicUsize::new(input.events.len()),
    };
    (setup, excluded)
}

/// The thresholds matched through the display, and how they were reached.
struct Matched<'a> {
    /// The final setup (the screen registered again, the photoreceptor measured).
    setup: Setup<'a>,
    /// Without a display model (the paper's on-screen method).
    naive: (f64, f64),
    fits: DisplayFits,
    display: DisplayParams,
    /// Through the fitted display, with ideal pixels.
    ideal: (f64, f64),
    /// Through the fitted display, with the measured photoreceptor (`ideal` where no lag
    /// was found).
    fitted: (f64, f64),
    lag_profile: lag::LagProfile,
}

/// The thresholds in stages: the naive estimate; thresholds, white and black level fitted
/// together (every gamma of the prior); the screen registered again through the best
/// display; the thresholds refined; the photoreceptor's lag measured from the events'
/// timing (over the pixels not `excluded` where the screen was first found) and, where
/// found, the thresholds matched again with it.
fn matched_thresholds<'a>(
    setup: Setup<'a>,
    excluded: &[bool],
    inputs: &register::Inputs,
    located: &mut Located,
    progress: Progress,
) -> Result<Matched<'a>, Unmatched> {
    let input = setup.input;
    progress("naive estimate (no display model)", 0.1);
    // through the setup's first response: `naive_response`
    let naive = setup.thresholds((0.3, 0.3), None)?;
    progress("fitting thresholds, white and black level", 0.3);
    let fits = fit_displays(
        &setup,
        &input.screen,
        (input.gamma_prior, input.response),
        naive,
    )?;
    let best = fits.best();
    let display = Joint {
        setup: &setup,
        screen: &input.screen,
        gamma: best.gamma,
        log: best.log,
    }
    .display(&best.param);
    let setup = Setup {
        log: best.log,
        ..setup
    };
    progress(
        "refining the screen's position through the fitted display",
        0.75,
    );
    let setup = match reregister(inputs, &display, best.log, located) {
        Some(warp) => Setup {
            warp: Some(Seen::new(warp, input.stimulus)),
            ..setup
        },
        None => setup,
    };
    progress("refining the thresholds", 0.8);
    let ideal = setup.thresholds((best.param[0].exp(), best.param[1].exp()), Some(&display))?;
    progress(
        "measuring the photoreceptor's lag from the events' timing",
        0.85,
    );
    let clock = setup.refresh_clock();
    let included = excluded.iter().map(|&e| !e).collect();
    let recorded = lag::Recorded::new(input.events, clock, included, input.sensor);
    let lag_profile = lag::profile(&setup, &recorded, ideal, Some(&display))?;
    // the display was fitted with ideal pixels; the thresholds are matched again through
    // it with the photoreceptor that lags
    let (setup, fitted) = match lag_profile.cutoff_hz() {
        Some(cutoff) => {
            let slow = Setup {
                cutoff_hz: Some(cutoff),
                ..setup
            };
            let ct = slow.thresholds(ideal, Some(&display))?;
            (slow, ct)
        }
        None => (setup, ideal),
    };
    Ok(Matched {
        setup,
        naive,
        fits,
        display,
        ideal,
        fitted,
        lag_profile,
    })
}

/// ON and OFF with their intervals: the standard error from the cells' spread about the
/// final simulation (NaN where no cell holds 5 events), and as systematic the largest
/// change over the display fits as good as the best (the priors' effect, see
/// [`GammaPrior::ends_in_sigmas`]; where the other log response is among them, its change
/// is scaled alike: a two-way choice's standard deviation is half the change, close to
/// its sqrt(3)rd) with a share of the photoreceptor's correction.
fn measured(
    m: &Matched,
    final_events: &EventChunk,
    prior: GammaPrior,
) -> Result<(Measured, Measured), EstimateError> {
    let variants = m.fits.compatible();
    // the fits were made with ideal pixels: their spread is taken about the ideal pixels'
    // thresholds and scaled to the final ones
    let spread = |pick: fn(&(f64, f64)) -> f64, value: f64, ideal: f64| -> f64 {
        variants
            .iter()
            .map(|v| (pick(v) - ideal).abs() * value / ideal)
            .fold(0.0, f64::max)
            / prior.ends_in_sigmas()
    };
    let simulated = m.setup.cells.count(final_events);
    let standard_error = |r: &[u32], s: &[u32], c: f64| {
        cell_spread(r, s).map_or(f64::NAN, |spread| c * spread.relative_standard_error)
    };
    let (fitted, ideal, real) = (m.fitted, m.ideal, &m.setup.real);
    let on = Measured::new(
        fitted.0,
        standard_error(&real.on, &simulated.on, fitted.0),
        spread(|v| v.0, fitted.0, ideal.0).hypot(lag::CORRECTION_SYSTEMATIC * (fitted.0 - ideal.0)),
    );
    let off = Measured::new(
        fitted.1,
        standard_error(&real.off, &simulated.off, fitted.1),
        spread(|v| v.1, fitted.1, ideal.1).hypot(lag::CORRECTION_SYSTEMATIC * (fitted.1 - ideal.1)),
    );
    Ok((on, off))
}

/// What the estimate says of how it was made: the registration, the stimulus clock, the
/// display, the prior and the lag first among the assumptions; the estimator's details;
/// and its [`extras`].
fn describe(
    estimate: &mut CtEstimate,
    m: &Matched,
    located: &Located,
    hot: usize,
    (on, off): (Measured, Measured),
) {
    let (setup, display, naive) = (&m.setup, &m.display, m.naive);
    let prior = setup.input.gamma_prior;
    let (offset_us, refresh_hz) = (setup.offset_us, setup.refresh_hz);
    let absorbed = offset_in_black_level(setup.input.response, setup.log);
    estimate.assumptions.splice(0..0, [
        located.assumption(),
        format!(
            "the stimulus clock starts {:.6} s into the recording (found from the event bursts at its refreshes)",
            offset_us as f64 * 1e-6
        ),
        format!(
            "the display: sample-and-hold at {refresh_hz:.3} Hz; black level{} ({:.4}) and optical blur ({:.2} px) fitted, the camera DN of white ({:.0}) {}, at gamma {:.2}",
            if absorbed { " with the sensor's dark offset" } else { "" },
            display.black_level,
            display.blur_px.unwrap_or(0.0),
            display.white_dn,
            match prior {
                _ if absorbed => "the screen model's (it drops out under a pure log)",
                GammaPrior::Displays => "fitted",
                GammaPrior::Measured(_) => "the screen model's",
            },
            display.gamma,
        ),
        prior.says(),
        setup
            .input
            .response
            .says(setup.log, m.fits.other_response_compatible()),
        m.lag_profile.says(),
    ]);
    if hot > 0 {
        estimate
            .assumptions
            .push(format!("{hot} hot pixels left out"));
    }
    estimate.estimators = vec![EstimatorReport {
        name: "screen_resimulation",
        description: "the stimulus simulated through the display model (white, black level and blur fitted with the thresholds, gamma from its prior); thresholds whose counts match the recording's in every region and refresh",
        ct_on: on,
        ct_off: off,
        frame_rate_series_on: Vec::new(),
        frame_rate_series_off: Vec::new(),
        details: json!({
            "naive_ct_on": naive.0,
            "naive_ct_off": naive.1,
            "display_fits": m.fits.json(),
            "lag": m.lag_profile.json(),
            "cutoff_hz": setup.cutoff_hz,
            "ideal_pixels_ct": [m.ideal.0, m.ideal.1],
            "simulations": setup.evaluations.load(std::sync::atomic::Ordering::Relaxed),
        }),
    }];
    let ct = estimate.ct.unwrap_or(f64::NAN);
    for (key, value) in extras(m, located, ct) {
        estimate.extra.insert(key.into(), value);
    }
}

/// The display, the naive thresholds, the photoreceptor, the registration, and how much of
/// the difference between the naive thresholds and `ct` the display explains.
fn extras(m: &Matched, located: &Located, ct: f64) -> [(&'static str, serde_json::Value); 5] {
    let (setup, display, naive) = (&m.setup, &m.display, m.naive);
    let stimulus = setup.input.stimulus;
    let naive_ct = 0.5 * (naive.0 + naive.1);
    let contrast = log_variation(stimulus, Some(display), setup.log)
        / log_variation(stimulus, None, naive_response(setup.input.response)).max(1e-12);
    let gap = (ct / naive_ct).ln();
    let explained = if gap.abs() > 1e-6 {
        contrast.ln() / gap
    } else {
        1.0
    };
    [
        (
            "display",
            json!({
                "response": response_name(setup.log),
                "gamma": display.gamma,
                "black_level": display.black_level,
                "refresh_hz": setup.refresh_hz,
                "time_offset_s": setup.offset_us as f64 * 1e-6,
                "white_dn": display.white_dn,
                "blur_px": display.blur_px,
            }),
        ),
        ("naive_ct", json!(naive_ct)),
        (
            "photoreceptor",
            json!({
                "cutoff_hz": setup.cutoff_hz,
                "ideal_pixels_ct_on": m.ideal.0,
                "ideal_pixels_ct_off": m.ideal.1,
            }),
        ),
        ("registration", located.json()),
        (
            "display_explains",
            json!(format!(
                "without a display model the thresholds come out at {naive_ct:.3} (the paper's on-screen method); through the fitted display (gamma {:.2}, black level {:.4}) the camera sees {:.2} times the stimulus's log contrast, which accounts for {:.0} % of the difference to {:.3}",
                display.gamma,
                display.black_level,
                contrast,
                100.0 * explained,
                ct
            )),
        ),
    ]
}

/// A threshold whose bursts the recording cuts short ([`bursts`]) is withdrawn: its counts
/// bound it from above only. The recording's and the fitted model's (`model_events`)
/// repeats are reported under `bursts` either way.
fn withhold_cut_bursts(
    estimate: &mut CtEstimate,
    m: &Matched,
    model_events: &EventChunk,
    excluded: &[bool],
) {
    let included: Vec<bool> = excluded.iter().map(|&e| !e).collect();
    let width = m.setup.input.sensor.width as usize;
    let clock = m.setup.refresh_clock();
    let recorded = bursts::repeats(m.setup.input.events, clock, &included, width);
    let model = bursts::repeats(model_events, clock, &included, width);
    let mut cut = [false; 2];
    for (slot, name) in ["ON", "OFF"].into_iter().enumerate() {
        cut[slot] = bursts::cut_short(recorded[slot], model[slot]);
        let (value, ci) = if slot == 0 {
            (estimate.ct_on, estimate.ct_on_ci95)
        } else {
            (estimate.ct_off, estimate.ct_off_ci95)
        };
        let bound = match (value, ci.and_then(|ci| ci[1])) {
            (Some(v), Some(hi)) => format!("{v:.3}, at most {hi:.3} with its interval"),
            (Some(v), None) => format!("{v:.3}"),
            _ => "not read".into(),
        };
        if cut[slot] {
            estimate.withhold_polarity(
                slot == 0,
                &format!(
                    "the recording's bursts are cut short: {:.1} % of its {name} events repeat a pixel's {name} event within one refresh where the fitted model's repeat {:.1} % (under half by {:.1} standard errors), so the pixels answer a step with fewer events than its crossings (a refractory period that drops what comes within it, with a photoreceptor fast against it, or a response that compresses large steps); the counts then bound the threshold from above only (read {bound})",
                    100.0 * recorded[slot].share(),
                    100.0 * model[slot].share(),
                    bursts::shortfall_z(recorded[slot], model[slot])
                ),
            );
        }
    }
    estimate.assumptions.push(format!(
        "bursts: {:.1} % of the ON and {:.1} % of the OFF events repeat a pixel's polarity within one refresh, against the fitted model's {:.1} % and {:.1} %; a polarity whose share falls under {} of the model's by more than {} standard errors (the shares' noise over {} blocks of refreshes) is withdrawn as an upper bound (its bursts cut short)",
        100.0 * recorded[0].share(),
        100.0 * recorded[1].share(),
        100.0 * model[0].share(),
        100.0 * model[1].share(),
        bursts::TRUNCATED_BELOW,
        bursts::Z_CUT,
        bursts::NOISE_BLOCKS
    ));
    let repeats = |r: bursts::Repeats| {
        json!({
            "events": r.events,
            "repeats": r.repeats,
            "share": r.share(),
            "share_se": r.share_se,
        })
    };
    let side = |slot: usize| {
        let mut v = repeats(recorded[slot]);
        v["shortfall_z"] = json!(bursts::shortfall_z(recorded[slot], model[slot]));
        v["cut_short"] = json!(cut[slot]);
        v
    };
    estimate.extra.insert(
        "bursts".into(),
        json!({
            "recorded": {"on": side(0), "off": side(1)},
            "model": {"on": repeats(model[0]), "off": repeats(model[1])},
            "truncated_below": bursts::TRUNCATED_BELOW,
            "z_cut": bursts::Z_CUT,
            "noise_blocks": bursts::NOISE_BLOCKS,
        }),
    );
}

/// The result when the screen is not found: nothing determinable, and why.
fn unregistered(reason: &str) -> CtEstimate {
    let why = format!("the screen could not be found on the sensor: {reason}");
    let mut estimate = CtEstimate::not_determinable("screen", &why);
    estimate
        .extra
        .insert("registration".into(), json!({ "error": reason }));
    estimate
}

/// The screen registered again through the fitted display (the joint refinement of
/// geometry and display); the new warp when the screen's corners moved more than 0.05 px.
fn reregister(
    inputs: &register::Inputs,
    display: &DisplayParams,
    log: LogMap,
    located: &mut Located,
) -> Option<std::sync::Arc<ScreenWarp>> {
    located.warp.as_ref()?;
    let (real, bounds) = register::event_images(inputs);
    let start = located.registration.geometry.clone();
    let through = register::Through { display, log };
    let again =
        register::refine(&real, &bounds, inputs.stimulus, through, start.clone(), 3).ok()?;
    let change = register::corner_change(&start, &again.geometry);
    located.refined_change_px = Some(change);
    if change <= 0.05 {
        return None;
    }
    let coarse_score = located.registration.coarse_score;
    located.registration = Registration {
        coarse_score,
        ..again
    };
    located.warp = Some(located.registration.warp.clone());
    located.warp.clone()
}
