//! The raw material of event timing: for consecutive events of one pixel, the frame values
//! (camera DN, interpolated along the optical flow) at both event times, the time between
//! them and the polarity of the second. The log response is applied later, with whatever
//! offset is being tried ([`super::model`]).

use crate::estimate::frames::PreparedFrames;
use crate::events::{EventChunk, Sensor, TimeUs};
use crate::stats::support::supported;
use rayon::prelude::*;

/// One pair of consecutive events of a pixel.
#[derive(Clone, Copy, Debug)]
pub struct Pair {
    pub pixel: u32,
    /// Polarity of the second event.
    pub on: bool,
    /// Frame DN (without offset) at the first and the second event.
    pub dn0: f32,
    pub dn1: f32,
    /// Seconds between the two events.
    pub dt: f32,
    /// DN a little before and after each event (at `t -+ h`, [`RATE_SPAN_S`] = `2 h`
    /// apart), for the rate of change there:
    /// `[before first, after first, before second, after second]`.
    pub around: [f32; 4],
    /// The block of frames read that the pair lies in (0 when the recording was read
    /// whole; see [`PreparedFrames::unread`]).
    pub block: u16,
    /// How far each event lies from a frame: `4 a (1 - a)`, `a` its phase within its frame
    /// interval (0 at a frame, 1 midway; see [`Pair::interpolation`]).
    pub interp: [f32; 2],
}

impl Pair {
    /// The pair's mean distance from the frames, `(w0 + w1) / 2` with `w = 4 a (1 - a)`.
    /// The frames are measured at their times and interpolated between them; an
    /// interpolation that misses part of the scene's change between frames (a flow that
    /// smooths occlusions, rotation or fine texture, a cross-fade where the flow fails)
    /// changes samples in proportion to how far from a frame their events lie, and not at
    /// all at the frames. Fitting the samples against it and reading the model at 0 gives
    /// the thresholds the frames measure where they were taken, at any frame rate.
    #[inline]
    pub fn interpolation(&self) -> f64 {
        0.5 * (self.interp[0] + self.interp[1]) as f64
    }
}

/// Half the span over which a rate of change is measured, microseconds.
const HALF_SPAN_US: TimeUs = 1000;

/// The span over which a rate of change is measured ([`Pair::around`]), seconds.
pub const RATE_SPAN_S: f32 = (2 * HALF_SPAN_US) as f32 * 1e-6;

/// DN just before and after `t` along the flow (one-sided at the ends of a used interval);
/// `t` on the frames' own clock.
fn around(frames: &PreparedFrames, x: u16, y: u16, t: TimeUs) -> Option<(f32, f32)> {
    let before = frames
        .dn_at(x, y, t - HALF_SPAN_US)
        .or_else(|| frames.dn_at(x, y, t))?;
    let after = frames
        .dn_at(x, y, t + HALF_SPAN_US)
        .or_else(|| frames.dn_at(x, y, t))?;
    Some((before, after))
}

/// What the frames say at one event: its DN (NaN when unknown or noise), the DN around it
/// and its distance from a frame ([`phase_weight`]).
#[derive(Clone, Copy)]
struct Reading {
    dn: f32,
    near: (f32, f32),
    weight: f32,
}

/// Events read against the frames per stretch: each stretch's readings (interpolated DN, the
/// costly part) on the pool, then paired in event order; memory is one stretch's readings.
const READ_STRETCH: usize = 1 << 16;

/// What a pass over the pairs reads at each event besides its DN.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Read {
    /// Everything a [`Pair`] holds (the DN around each event, its phase).
    Full,
    /// The DN at the events only ([`Pair::around`] holds the DN itself, the phases 0): what
    /// the samples alone need, without the two extra frame readings per event.
    DnOnly,
}

/// Every usable pair of `events` (time-sorted) against `frames` with their times moved by
/// `shift` (an event at `t` is read at `t - shift` on the frames' own clock, exactly what
/// frames whose times were shifted give, without changing them): both events in used
/// intervals at a reliable pixel, and supported when `support_window_us` is set.
pub fn collect(
    events: &EventChunk,
    frames: &PreparedFrames,
    shift: TimeUs,
    sensor: Sensor,
    excluded: &[bool],
    support_window_us: Option<TimeUs>,
) -> Vec<Pair> {
    // grown as they come (reserving one per event would hold far more than the pairs
    // where few events pair up), and the unused tail given back before the fits run on
    // them
    let mut pairs = Vec::new();
    let source = PairSource {
        events,
        frames,
        shift,
        sensor,
        excluded,
        support_window_us,
    };
    source.for_each(Read::Full, |pair| pairs.push(pair));
    pairs.shrink_to_fit();
    pairs
}

/// Where pairs come from: events against frames whose times are moved by `shift`, and what
/// to leave out (see [`collect`]).
pub struct PairSource<'a> {
    pub events: &'a EventChunk,
    pub frames: &'a PreparedFrames,
    pub shift: TimeUs,
    pub sensor: Sensor,
    pub excluded: &'a [bool],
    pub support_window_us: Option<TimeUs>,
}

impl PairSource<'_> {
    /// Hands every usable pair to `sink`, in event order, without keeping them: memory is
    /// one stretch's readings and the previous reading of each pixel.
    pub fn for_each(&self, read: Read, mut sink: impl FnMut(Pair)) {
        let (events, frames) = (self.events, self.frames);
        let support = self
            .support_window_us
            .map(|w| supported(events, self.sensor, w));
        let width = self.sensor.width as usize;
        // the previous event of each pixel: its reading and time
        let unknown = Reading {
            dn: f32::NAN,
            near: (0.0, 0.0),
            weight: 0.0,
        };
        let mut previous = vec![(unknown, 0 as TimeUs); self.sensor.pixels()];
        for first in (0..events.len()).step_by(READ_STRETCH) {
            let stretch = first..(first + READ_STRETCH).min(events.len());
            let readings: Vec<Option<Reading>> = stretch
                .clone()
                .into_par_iter()
                .map(|i| self.reading(i, support.as_deref(), read))
                .collect();
            for (i, reading) in stretch.zip(readings) {
                let Some(now) = reading else { continue };
                let (x, y, t) = (events.x[i], events.y[i], events.t[i]);
                let pixel = y as usize * width + x as usize;
                let (before, t_before) = previous[pixel];
                let block = frames.read_block(t);
                // a pixel's change across a span whose events were not read is unknown
                if before.dn.is_finite()
                    && now.dn.is_finite()
                    && frames.read_block(t_before) == block
                {
                    sink(Pair {
                        pixel: pixel as u32,
                        on: events.on[i],
                        dn0: before.dn,
                        dn1: now.dn,
                        dt: ((t - t_before) as f64 * 1e-6) as f32,
                        around: [before.near.0, before.near.1, now.near.0, now.near.1],
                        block: u16::try_from(block).unwrap_or(u16::MAX),
                        interp: [before.weight, now.weight],
                    });
                }
                previous[pixel] = (now, t);
            }
        }
    }

    /// What the frames say at event `i` (`None` at an excluded pixel): its DN, NaN where
    /// the frames do not know it or `support` says it is noise, and as much more as `read`
    /// asks for.
    fn reading(&self, i: usize, support: Option<&[bool]>, read: Read) -> Option<Reading> {
        let (events, frames) = (self.events, self.frames);
        let (x, y, t) = (events.x[i], events.y[i], events.t[i] - self.shift);
        if self.excluded[y as usize * self.sensor.width as usize + x as usize] {
            return None;
        }
        let dn = match frames.dn_at(x, y, t) {
            Some(dn) if support.is_none_or(|s| s[i]) => dn,
            _ => f32::NAN,
        };
        if read == Read::DnOnly || !dn.is_finite() {
            let weight = if read == Read::DnOnly {
                0.0
            } else {
                phase_weight(frames, t)
            };
            return Some(Reading {
                dn,
                near: (dn, dn),
                weight,
            });
        }
        let near = around(frames, x, y, t).unwrap_or((dn, dn));
        Some(Reading {
            dn,
            near,
            weight: phase_weight(frames, t),
        })
    }
}

/// `4 a (1 - a)`, `a` the phase of `t` within its frame interval (0 at a frame, 1 midway).
fn phase_weight(frames: &PreparedFrames, t: TimeUs) -> f32 {
    frames.interval_of(t).map_or(0.0, |k| {
        let (t0, t1) = (frames.times[k], frames.times[k + 1]);
        let a = (t - t0) as f32 / (t1 - t0) as f32;
        4.0 * a * (1.0 - a)
    })
}
