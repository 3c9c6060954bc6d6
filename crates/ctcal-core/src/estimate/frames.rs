//! Grey frames prepared for estimation: which frame intervals can be used and why others
//! cannot, the optical flow of every usable interval, the log intensity of any pixel at any
//! time between frames (motion-compensated interpolation along the flow), and the frames
//! upsampled along the flow as simulator input.
//!
//! Linear interpolation in time between frames misses the sub-frame excursions of a moving
//! scene (the simulator loses 2.5 % of events at 50 Hz, 5 % at 30 Hz); interpolating along
//! the optical flow follows the moving content instead, so that estimates no longer depend
//! on the frame rate (Stoffregen et al. 2020 noted the same loss for their APS
//! re-simulation; Gehrig et al., "Video to Events", CVPR 2020, upsample frames by flow for
//! the same reason).
//!
//! A frame is used when at least a fifth of its pixels are not clipped at white, at most
//! 30 % are black, and it is about as sharp as the others; an interval when both its
//! frames are, its motion is small enough to follow, and it holds events. Within a used
//! interval, a pixel that is near black (at most 3 DN) or clipped (at least 254 DN) in
//! either frame has no reliable log intensity and is left out of every estimate for that
//! interval ([`PreparedFrames::reliable`]). Frame times are taken as the frames' own
//! timestamps (exposure midpoints where the file says so).

use super::EstimateError;
use super::flow::{FlowField, FlowOptions, dense_flow, interpolate};
use super::image::Image;
use crate::events::{Frame, TimeUs, us_to_s};
use crate::hint::{Analysis, Hint, Text};
use crate::sim::log_response::LogMap;
use crate::sim::pixel::Transition;
use crate::sim::{FrameSource, Sample, SimError};
use rayon::prelude::*;
use serde::Serialize;

/// The block of frames read that event time `t` falls in, given the `unread` spans between
/// blocks (time-sorted): the number of spans that end by `t`.
#[inline]
pub fn read_block(unread: &[(TimeUs, TimeUs)], t: TimeUs) -> usize {
    if unread.is_empty() {
        return 0;
    }
    unread.partition_point(|&(_, end)| end <= t)
}

/// Limits of frame selection.
#[derive(Clone, Debug)]
pub struct FrameOptions {
    /// Largest share of pixels clipped at white (at least 254.5 DN). The clipped pixels
    /// themselves are left out of every estimate ([`PreparedFrames::reliable`]), so a frame
    /// is refused only when too few are left to follow the motion: at 0.3, bright draws of
    /// the coverage study (3065, 3073, 3078: 44-53 % of the pixels clipped, as outdoor
    /// frames with sky often are) were refused whole; at 0.8 `estimate aps` and `fit` cover
    /// all six of their thresholds (2026-12-01).
    pub max_clipped: f64,
    /// Largest share of pixels at or below 2 DN.
    pub max_dark: f64,
    /// A frame with less than this share of the median gradient energy is blurred.
    pub min_sharpness: f64,
    /// Largest displacement (95th percentile over pixels) of an interval, pixels.
    pub max_motion_px: f64,
    pub flow: FlowOptions,
}

impl Default for FrameOptions {
    fn default() -> Self {
        Self {
            max_clipped: 0.8,
            max_dark: 0.3,
            min_sharpness: 0.4,
            max_motion_px: 12.0,
            flow: FlowOptions::default(),
        }
    }
}

/// One frame interval and whether it is used.
#[derive(Clone, Debug, Serialize)]
pub struct IntervalInfo {
    pub t_start_s: f64,
    pub t_end_s: f64,
    pub used: bool,
    /// Why it was dropped.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// 95th-percentile displacement over the interval, pixels.
    pub motion_px: f64,
}

/// Frames ready for estimation.
pub struct PreparedFrames {
    pub width: usize,
    pub height: usize,
    pub times: Vec<TimeUs>,
    /// Camera DN.
    pub dn: Vec<Image>,
    /// Flow of each interval (`None` where the interval is not used).
    pub flows: Vec<Option<FlowField>>,
    pub intervals: Vec<IntervalInfo>,
    pub log_map: LogMap,
    /// DN added to every frame value before the log response (a subtracted black level
    /// restored, found by [`super::timing`]).
    pub offset: f32,
    /// The offsets the thresholds' systematic error spans (the offset's 95 % interval, or
    /// its prior range where the data do not bound it).
    pub offset_range: (f32, f32),
    /// The thresholds' intervals reach the thresholds at `offset_range`'s ends, not only
    /// spread by them: the offset was fitted and one polarity gave none
    /// ([`super::timing::Offset::unconfirmed`]).
    pub offset_reached: bool,
    /// Event-time spans between blocks of frames read from a longer recording whose events
    /// were not read (time-sorted; empty when the recording was read whole): a pixel's
    /// change across one is unknown.
    pub unread: Vec<(TimeUs, TimeUs)>,
}

/// What decides whether a frame interval is used: the frames' times, log images and
/// problems, the events' times and the spans not read.
struct Intervals<'a> {
    times: &'a [TimeUs],
    logs: &'a [Image],
    frame_problems: &'a [Option<String>],
    event_times: &'a [TimeUs],
    unread: &'a [(TimeUs, TimeUs)],
    options: &'a FrameOptions,
}

impl Intervals<'_> {
    /// Every interval's flow ([`Intervals::flow`]), each on its own thread, kept in order.
    fn every_flow(&self) -> (Vec<Option<FlowField>>, Vec<IntervalInfo>) {
        let results: Vec<(Option<FlowField>, IntervalInfo)> = (0..self.times.len() - 1)
            .into_par_iter()
            .map(|k| self.flow(k))
            .collect();
        results.into_iter().unzip()
    }

    /// Interval `k`'s optical flow where it is used, and why not where it is not: it
    /// crosses a span not read, a frame has a problem, the frames share a time, no event
    /// falls between them, or the motion (95th percentile of the flow) is too large to
    /// interpolate.
    fn flow(&self, k: usize) -> (Option<FlowField>, IntervalInfo) {
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let mut info = IntervalInfo {
            t_start_s: us_to_s(t0),
            t_end_s: us_to_s(t1),
            used: false,
            reason: None,
            motion_px: 0.0,
        };
        if self.unread.iter().any(|&(a, b)| a < t1 && b > t0) {
            info.reason =
                Some("between two blocks of frames read: its events were not read".into());
            return (None, info);
        }
        let problem = self.frame_problems[k]
            .as_ref()
            .map(|p| format!("frame at {:.6} s: {p}", us_to_s(t0)))
            .or_else(|| {
                self.frame_problems[k + 1]
                    .as_ref()
                    .map(|p| format!("frame at {:.6} s: {p}", us_to_s(t1)))
            });
        if let Some(problem) = problem {
            info.reason = Some(problem);
            return (None, info);
        }
        if t1 <= t0 {
            info.reason = Some("the two frames have the same time".into());
            return (None, info);
        }
        let lo = self.event_times.partition_point(|&t| t < t0);
        let hi = self.event_times.partition_point(|&t| t < t1);
        if hi == lo {
            info.reason = Some("no events between the frames".into());
            return (None, info);
        }
        let flow = dense_flow(&self.logs[k], &self.logs[k + 1], &self.options.flow);
        let mut magnitudes = flow.magnitudes();
        magnitudes.sort_by(f32::total_cmp);
        let motion = magnitudes[(magnitudes.len() - 1) * 95 / 100] as f64;
        info.motion_px = motion;
        if motion > self.options.max_motion_px {
            info.reason = Some(format!(
                "motion of {motion:.1} px between the frames is too large to interpolate (limit {} px)",
                self.options.max_motion_px
            ));
            return (None, info);
        }
        info.used = true;
        (Some(flow), info)
    }
}

/// The refusal of a recording with fewer than two grey frames (`frames` of them).
fn too_few_frames(frames: usize) -> EstimateError {
    EstimateError::new(
        format!("needs at least two grey frames; the recording has {frames}"),
        Text::from("use ").name(Hint::Analysis(Analysis::Eppps)),
    )
}

/// Each frame's log image through `log_map`, on every thread, kept in order.
fn log_images(dn: &[Image], log_map: &LogMap) -> Vec<Image> {
    dn.par_iter()
        .map(|d| {
            Image::new(
                d.width,
                d.height,
                d.data.iter().map(|&v| log_map.apply(v)).collect(),
            )
        })
        .collect()
}

/// Why no interval of a recording's frames can be used (its first three reasons), and
/// what to do.
fn no_usable_interval(intervals: &[IntervalInfo]) -> EstimateError {
    let reasons: Vec<String> = intervals
        .iter()
        .filter_map(|i| i.reason.clone())
        .take(3)
        .collect();
    EstimateError::new(
        format!(
            "no usable frame interval among {} ({})",
            intervals.len(),
            reasons.join("; ")
        ),
        Text::from("record with a fixed exposure and moderate motion, or use ")
            .name(Hint::Analysis(Analysis::Eppps)),
    )
}

/// Whether a pixel's values in an interval's two frames, `dn0` and `dn1`, are both reliable
/// intensities: neither near black (at most 3 DN) nor clipped (at least 254 DN).
#[inline]
pub fn reliable_pair(dn0: f32, dn1: f32) -> bool {
    let ok = |v: f32| v > 3.0 && v < 254.0;
    ok(dn0) && ok(dn1)
}

impl PreparedFrames {
    /// Prepares `frames` (time-sorted, one size); `event_times` (sorted) decide which
    /// intervals hold events; an interval across one of the `unread` spans is not used.
    pub fn new(
        frames: &[Frame],
        event_times: &[TimeUs],
        unread: &[(TimeUs, TimeUs)],
        log_map: LogMap,
        options: &FrameOptions,
    ) -> Result<Self, EstimateError> {
        if frames.len() < 2 {
            return Err(too_few_frames(frames.len()));
        }
        let (width, height) = (frames[0].width as usize, frames[0].height as usize);
        let dn: Vec<Image> = frames
            .iter()
            .map(|f| Image::from_u8(width, height, &f.pixels))
            .collect();
        let times: Vec<TimeUs> = frames.iter().map(|f| f.t).collect();
        let frame_problems = frame_problems(&dn, options);
        let logs = log_images(&dn, &log_map);
        let (flows, intervals) = Intervals {
            times: &times,
            logs: &logs,
            frame_problems: &frame_problems,
            event_times,
            unread,
            options,
        }
        .every_flow();
        let prepared = Self {
            width,
            height,
            times,
            dn,
            flows,
            intervals,
            log_map,
            offset: 0.0,
            offset_range: (0.0, 0.0),
            offset_reached: false,
            unread: unread.to_vec(),
        };
        if !prepared.intervals.iter().any(|i| i.used) {
            return Err(no_usable_interval(&prepared.intervals));
        }
        Ok(prepared)
    }

    /// The same recording with only every `step`-th frame (longer intervals, their flow
    /// recomputed): the basis of the frame-rate extrapolation of systematic errors.
    pub fn every(&self, step: usize, options: &FrameOptions) -> Option<PreparedFrames> {
        let keep: Vec<usize> = (0..self.times.len()).step_by(step).collect();
        if keep.len() < 2 {
            return None;
        }
        let width = self.width;
        // each interval's flow on its own thread, kept in order
        let (flows, intervals): (Vec<Option<FlowField>>, Vec<IntervalInfo>) = keep
            .par_windows(2)
            .map(|pair| {
                let (a, b) = (pair[0], pair[1]);
                let mut info = IntervalInfo {
                    t_start_s: us_to_s(self.times[a]),
                    t_end_s: us_to_s(self.times[b]),
                    used: false,
                    reason: None,
                    motion_px: 0.0,
                };
                if !(a..b).all(|k| self.intervals[k].used) {
                    info.reason = Some("spans an interval that is not used".into());
                    return (None, info);
                }
                let log = |k: usize| {
                    Image::new(
                        width,
                        self.height,
                        self.dn[k].data.iter().map(|&v| self.log(v)).collect(),
                    )
                };
                let flow = dense_flow(&log(a), &log(b), &options.flow);
                let mut magnitudes = flow.magnitudes();
                magnitudes.sort_by(f32::total_cmp);
                info.motion_px = magnitudes[(magnitudes.len() - 1) * 95 / 100] as f64;
                info.used = info.motion_px <= options.max_motion_px;
                if !info.used {
                    info.reason = Some("motion too large".into());
                }
                (info.used.then_some(flow), info)
            })
            .unzip();
        if !intervals.iter().any(|i| i.used) {
            return None;
        }
        Some(PreparedFrames {
            width,
            height: self.height,
            times: keep.iter().map(|&k| self.times[k]).collect(),
            dn: keep.iter().map(|&k| self.dn[k].clone()).collect(),
            flows,
            intervals,
            log_map: self.log_map,
            offset: self.offset,
            offset_range: self.offset_range,
            offset_reached: self.offset_reached,
            unread: self.unread.clone(),
        })
    }

    /// The same recording with every frame blurred further by the motion of an exposure of
    /// `exposure_us` (a frame integrates light over its exposure, so a moving scene is
    /// averaged along its path: each pixel becomes the mean of the frame sampled at evenly
    /// spaced points over the displacement `flow * exposure / interval`, centred on the
    /// pixel, in DN as light adds). The flow of the interval a frame opens is used (of the
    /// one it closes for the last frame); a frame next to no used interval is kept as it
    /// is. The basis of the exposure extrapolation of systematic errors: blurring by one
    /// more exposure shows what the exposure already there costs.
    pub fn motion_blurred(&self, exposure_us: TimeUs) -> PreparedFrames {
        let n = self.times.len();
        let dn: Vec<Image> = (0..n)
            .into_par_iter()
            .map(|k| {
                let opened = (k + 1 < n).then_some(k);
                let closed = k.checked_sub(1);
                let Some((flow, interval)) = [opened, closed].into_iter().flatten().find_map(|i| {
                    let gap = self.times[i + 1] - self.times[i];
                    Some((self.flows[i].as_ref()?, gap)).filter(|_| gap > 0)
                }) else {
                    return self.dn[k].clone();
                };
                blurred_along(&self.dn[k], flow, exposure_us as f32 / interval as f32)
            })
            .collect();
        PreparedFrames {
            width: self.width,
            height: self.height,
            times: self.times.clone(),
            dn,
            flows: self.flows.clone(),
            intervals: self.intervals.clone(),
            log_map: self.log_map,
            offset: self.offset,
            offset_range: self.offset_range,
            offset_reached: self.offset_reached,
            unread: self.unread.clone(),
        }
    }

    /// Moves every frame time by `shift` microseconds (frame-time alignment).
    pub fn shift_times(&mut self, shift: TimeUs) {
        for t in &mut self.times {
            *t += shift;
        }
        for i in &mut self.intervals {
            i.t_start_s += us_to_s(shift);
            i.t_end_s += us_to_s(shift);
        }
    }

    /// What shifting the frames by each of `shifts` and back leaves: the frame times as
    /// they were, the intervals' times in seconds off by rounding (a float sum and
    /// difference do not cancel exactly). The alignment search once shifted the frames
    /// themselves; it now reads them at shifted times and replays the shifts here, so that
    /// every result stays the same to the bit.
    pub fn replay_shifts(&mut self, shifts: impl IntoIterator<Item = TimeUs>) {
        for shift in shifts {
            self.shift_times(shift);
            self.shift_times(-shift);
        }
    }

    /// The block of frames read that event time `t` falls in (0 when the recording was read
    /// whole): the number of unread spans that end by `t`.
    #[inline]
    pub fn read_block(&self, t: TimeUs) -> usize {
        read_block(&self.unread, t)
    }

    /// The median frame interval, microseconds.
    pub fn median_interval_us(&self) -> TimeUs {
        let mut gaps: Vec<TimeUs> = self.times.windows(2).map(|w| w[1] - w[0]).collect();
        gaps.sort_unstable();
        gaps.get(gaps.len() / 2).copied().unwrap_or(0)
    }

    /// Where the motion outruns the frames: the flow was measured and moved too far
    /// (beyond [`FrameOptions::max_motion_px`]) on more intervals than it follows, as
    /// `(followed, too fast)`. Intervals dropped for want of events or for a bad frame do
    /// not count: they say nothing about the motion. The followed intervals of such frames
    /// may be the few the flow happened to match, or a periodic pattern aliased to a
    /// smaller step (coverage draw 6028, a checkerboard moving 34 px a frame: its followed
    /// intervals read 108 px/s for 337).
    pub fn motion_outruns_flow(&self) -> Option<(usize, usize)> {
        let followed = self.intervals.iter().filter(|i| i.used).count();
        let too_fast = self
            .intervals
            .iter()
            .filter(|i| !i.used && i.motion_px > 0.0)
            .count();
        (too_fast > followed).then_some((followed, too_fast))
    }

    /// The interval holding time `t` (`t0 <= t < t1`), if it is used.
    #[inline]
    pub fn interval_of(&self, t: TimeUs) -> Option<usize> {
        let k = self.times.partition_point(|&s| s <= t).checked_sub(1)?;
        (k + 1 < self.times.len() && self.flows[k].is_some()).then_some(k)
    }

    /// Whether pixel `index` has a reliable intensity (neither near black nor clipped) in
    /// both frames of interval `k`.
    #[inline]
    pub fn reliable(&self, k: usize, index: usize) -> bool {
        reliable_pair(self.dn[k].data[index], self.dn[k + 1].data[index])
    }

    /// The log response of a frame value (with the offset).
    #[inline]
    pub fn log(&self, dn: f32) -> f32 {
        self.log_map.apply(dn + self.offset)
    }

    /// The log intensity of pixel (x, y) at time `t`, interpolated along the flow of its
    /// interval (`None` outside the used intervals and where the pixel is not reliable).
    #[inline]
    pub fn log_at(&self, x: u16, y: u16, t: TimeUs) -> Option<f32> {
        Some(self.log(self.dn_at(x, y, t)?))
    }

    /// The frame value (DN, without the offset) of pixel (x, y) at time `t`, interpolated
    /// along the flow (`None` outside the used intervals and where the pixel is not
    /// reliable).
    #[inline]
    pub fn dn_at(&self, x: u16, y: u16, t: TimeUs) -> Option<f32> {
        let k = self.interval_of(t)?;
        if !self.reliable(k, y as usize * self.width + x as usize) {
            return None;
        }
        let flow = self.flows[k].as_ref()?;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let a = (t - t0) as f32 / (t1 - t0) as f32;
        let (u, v) = flow.at(x as usize, y as usize);
        let (xf, yf) = (x as f32, y as f32);
        let before = self.dn[k].sample_cubic(xf - a * u, yf - a * v);
        let after = self.dn[k + 1].sample_cubic(xf + (1.0 - a) * u, yf + (1.0 - a) * v);
        Some((1.0 - a) * before + a * after)
    }

    /// Runs of consecutive used intervals, as frame index ranges `first..=last`.
    pub fn runs(&self) -> Vec<(usize, usize)> {
        let mut runs = Vec::new();
        let mut start = None;
        for (k, flow) in self.flows.iter().enumerate() {
            match (flow.is_some(), start) {
                (true, None) => start = Some(k),
                (false, Some(s)) => {
                    runs.push((s, k));
                    start = None;
                }
                _ => {}
            }
        }
        if let Some(s) = start {
            runs.push((s, self.flows.len()));
        }
        runs
    }

    /// The used intervals as `[t_start_s, t_end_s]`.
    pub fn used_intervals(&self) -> Vec<[f64; 2]> {
        self.intervals
            .iter()
            .filter(|i| i.used)
            .map(|i| [i.t_start_s, i.t_end_s])
            .collect()
    }

    /// The frames of run `first..=last` upsampled along the flow, so that no content moves
    /// more than `max_step_px` between two samples: simulator input.
    pub fn upsampled(&self, first: usize, last: usize, max_step_px: f64) -> Upsampled<'_> {
        let steps = (first..last)
            .map(|k| {
                let motion = self.intervals[k].motion_px;
                ((motion / max_step_px).ceil() as usize).max(1)
            })
            .collect();
        Upsampled {
            frames: self,
            first,
            last,
            steps,
            interval: first,
            sub: 0,
            started: false,
            buffer: Vec::new(),
        }
    }
}

impl PreparedFrames {
    /// Every run upsampled along the flow (see [`Self::upsampled`]), held in memory for
    /// repeated simulation. The step grows (coarser upsampling) until the samples fit in
    /// `max_bytes`.
    pub fn upsample_runs(&self, max_step_px: f64, max_bytes: usize) -> Vec<Vec<Sample>> {
        let frame_bytes = self.width * self.height * 4;
        let mut step = max_step_px;
        loop {
            let samples: usize = self
                .runs()
                .iter()
                .map(|&(a, b)| self.upsampled(a, b, step).len_hint().unwrap_or(0) as usize)
                .sum();
            if samples * frame_bytes <= max_bytes || step > 8.0 {
                break;
            }
            step *= 1.5;
        }
        self.runs()
            .iter()
            .map(|&(a, b)| {
                let mut source = self.upsampled(a, b, step);
                let mut samples = Vec::new();
                while let Ok(Some(sample)) = source.next_frame() {
                    samples.push(sample);
                }
                samples
            })
            .collect()
    }
}

/// Samples of a blurred pixel at most (a path of 32 px; a flow that long is not used).
const MAX_BLUR_SAMPLES: usize = 64;

/// `image` averaged along `fraction` of `flow` at each pixel (a linear motion blur of
/// that path, centred on the pixel): one bilinear sample per half pixel of path, at least
/// one, at most [`MAX_BLUR_SAMPLES`]; a pixel whose flow is not finite is kept.
fn blurred_along(image: &Image, flow: &FlowField, fraction: f32) -> Image {
    let (w, h) = (image.width, image.height);
    let mut out = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let (u, v) = flow.at(x, y);
            let (u, v) = (u * fraction, v * fraction);
            let length = u.hypot(v);
            if !length.is_finite() {
                out.push(image.at(x, y));
                continue;
            }
            let samples = ((2.0 * length).ceil() as usize).clamp(1, MAX_BLUR_SAMPLES);
            if samples == 1 {
                out.push(image.at(x, y));
                continue;
            }
            let mut sum = 0.0;
            for i in 0..samples {
                let s = (i as f32 + 0.5) / samples as f32 - 0.5;
                sum += image.sample(x as f32 + s * u, y as f32 + s * v);
            }
            out.push(sum / samples as f32);
        }
    }
    Image::new(w, h, out)
}

/// The frames' exposure: the first the frames carry, else `given` (the user's).
pub fn exposure_of(frames: &[Frame], given: Option<TimeUs>) -> Option<TimeUs> {
    frames.iter().find_map(|f| f.exposure_us).or(given)
}

/// Why a frame cannot be used, if it cannot.
fn frame_problems(dn: &[Image], options: &FrameOptions) -> Vec<Option<String>> {
    let energies: Vec<f64> = dn
        .par_iter()
        .map(|d| {
            let (gx, gy) = d.gradients();
            gx.data
                .iter()
                .zip(&gy.data)
                .map(|(a, b)| (a * a + b * b) as f64)
                .sum::<f64>()
                / d.data.len() as f64
        })
        .collect();
    let mut sorted = energies.clone();
    sorted.sort_by(f64::total_cmp);
    let median_energy = sorted[sorted.len() / 2];
    dn.iter()
        .zip(&energies)
        .map(|(d, &energy)| {
            let n = d.data.len() as f64;
            let clipped = d.data.iter().filter(|&&v| v >= 254.5).count() as f64 / n;
            let dark = d.data.iter().filter(|&&v| v <= 2.0).count() as f64 / n;
            if clipped > options.max_clipped {
                Some(format!(
                    "{:.0} % of the pixels are clipped at white",
                    100.0 * clipped
                ))
            } else if dark > options.max_dark {
                Some(format!("{:.0} % of the pixels are black", 100.0 * dark))
            } else if energy < options.min_sharpness * median_energy {
                Some(format!(
                    "blurred: {:.0} % of the median frame's gradient energy",
                    100.0 * energy / median_energy
                ))
            } else {
                None
            }
        })
        .collect()
}

/// Frames upsampled along the flow (see [`PreparedFrames::upsampled`]).
pub struct Upsampled<'a> {
    frames: &'a PreparedFrames,
    first: usize,
    last: usize,
    /// Sub-steps of each interval of the run.
    steps: Vec<usize>,
    interval: usize,
    sub: usize,
    started: bool,
    buffer: Vec<f32>,
}

impl FrameSource for Upsampled<'_> {
    fn size(&self) -> (usize, usize) {
        (self.frames.width, self.frames.height)
    }

    fn len_hint(&self) -> Option<u64> {
        Some(self.steps.iter().sum::<usize>() as u64 + 1)
    }

    fn next_frame(&mut self) -> Result<Option<Sample>, SimError> {
        let f = self.frames;
        if !self.started {
            self.started = true;
            return Ok(Some(Sample {
                t: f.times[self.first],
                dn: f.dn[self.first].data.iter().map(|v| v + f.offset).collect(),
                transition: Transition::Linear,
            }));
        }
        if self.interval >= self.last {
            return Ok(None);
        }
        let k = self.interval;
        let n = self.steps[k - self.first];
        self.sub += 1;
        let (t0, t1) = (f.times[k], f.times[k + 1]);
        let fraction = self.sub as f64 / n as f64;
        let t = t0 + ((t1 - t0) as f64 * fraction).round() as TimeUs;
        let dn = if self.sub == n {
            f.dn[k + 1].data.iter().map(|v| v + f.offset).collect()
        } else {
            let flow = f.flows[k].as_ref().expect("a run holds used intervals");
            interpolate(
                &f.dn[k],
                &f.dn[k + 1],
                flow,
                fraction as f32,
                &mut self.buffer,
            );
            self.buffer.iter().map(|v| v + f.offset).collect()
        };
        if self.sub == n {
            self.sub = 0;
            self.interval += 1;
        }
        Ok(Some(Sample {
            t,
            dn,
            transition: Transition::Linear,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 32 x 32 frame of a 4-px checker (60 / 120 DN) whose first `clipped_rows` rows are
    /// at 255 DN.
    fn checker_clipped(clipped_rows: usize) -> Image {
        let n = 32;
        Image::new(
            n,
            n,
            (0..n * n)
                .map(|i| {
                    let (x, y) = (i % n, i / n);
                    if y < clipped_rows {
                        255.0
                    } else if (x / 4 + y / 4) % 2 == 0 {
                        60.0
                    } else {
                        120.0
                    }
                })
                .collect(),
        )
    }

    #[test]
    fn a_frame_half_clipped_at_white_is_used_and_one_mostly_clipped_is_not() {
        let frames = [0, 16, 16, 28].map(checker_clipped);
        let problems = frame_problems(&frames, &FrameOptions::default());
        assert_eq!(problems[..3], [None, None, None], "{problems:?}");
        // 28 of 32 rows: 88 % clipped
        assert_eq!(
            problems[3].as_deref(),
            Some("88 % of the pixels are clipped at white")
        );
    }

    #[test]
    fn a_moving_edge_blurs_into_a_ramp_as_long_as_the_motion() {
        // a step from 10 to 90 DN at x = 8, moving 4 px to the right in the interval
        let (w, h) = (16, 3);
        let image = Image::new(
            w,
            h,
            (0..w * h)
                .map(|i| if i % w < 8 { 10.0 } else { 90.0 })
                .collect(),
        );
        let mut flow = FlowField::zero(w, h);
        flow.u.iter_mut().for_each(|u| *u = 4.0);
        let blurred = blurred_along(&image, &flow, 1.0);
        // far from the edge nothing changes; across it the value climbs over 4 px
        assert_eq!(blurred.at(2, 1), 10.0);
        assert_eq!(blurred.at(13, 1), 90.0);
        let ramp: Vec<f32> = (5..11).map(|x| blurred.at(x, 1)).collect();
        assert!(ramp.windows(2).all(|p| p[1] >= p[0]), "{ramp:?}");
        assert!(ramp[0] == 10.0 && ramp[5] == 90.0, "{ramp:?}");
        assert!((blurred.at(7, 1) - 40.0).abs() < 10.5, "{ramp:?}");
        // light is conserved along the row (away from the clamped borders)
        let sum = |img: &Image| (0..w).map(|x| img.at(x, 1)).sum::<f32>();
        assert!((sum(&blurred) - sum(&image)).abs() < 1e-3);
        // no motion, no blur
        assert_eq!(blurred_along(&image, &FlowField::zero(w, h), 1.0), image);
    }
}
