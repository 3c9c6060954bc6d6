//! Test fixture of the effects' evidence: a hand-built [`Geometry`] (frames whose pixel
//! values are given, every interval used with zero flow, every block fitting) and the
//! statistics of a "recording" and of a "model" event set on it, built the way
//! `fit::selection` builds them (`Geometry::new`, `Observed::new` with nothing masked), and
//! the [`Context`] the evidence reads (the fit blocks, every pixel kept).

use super::Context;
use crate::estimate::flow::FlowField;
use crate::estimate::frames::{IntervalInfo, PreparedFrames};
use crate::estimate::image::Image;
use crate::events::{EventChunk, TimeUs};
use crate::fit::observe::{Geometry, Observed, Subset};
use crate::sim::log_response::LogMap;
use crate::sim::{LogResponse, PixelParams};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Time blocks of the fixture's geometry (all of them fit).
pub const BLOCKS: usize = 4;
/// The model's thresholds.
pub const THRESHOLD: f64 = 0.2;

/// Frames of `width x height` at `times`, pixel (x, y) of frame k at `dn(x, y, k)` DN,
/// every interval used (zero flow).
pub fn frames(
    width: usize,
    height: usize,
    times: &[TimeUs],
    dn: impl Fn(usize, usize, usize) -> f32,
) -> PreparedFrames {
    let images = (0..times.len())
        .map(|k| {
            let data = (0..width * height)
                .map(|p| dn(p % width, p / width, k))
                .collect();
            Image::new(width, height, data)
        })
        .collect();
    let intervals = times
        .windows(2)
        .map(|w| IntervalInfo {
            t_start_s: w[0] as f64 * 1e-6,
            t_end_s: w[1] as f64 * 1e-6,
            used: true,
            reason: None,
            motion_px: 0.0,
        })
        .collect();
    PreparedFrames {
        width,
        height,
        times: times.to_vec(),
        dn: images,
        flows: vec![Some(FlowField::zero(width, height)); times.len() - 1],
        intervals,
        log_map: LogMap::new(LogResponse::V2e, 0.0),
        offset: 0.0,
        offset_range: (0.0, 0.0),
        offset_reached: false,
        unread: Vec::new(),
    }
}

/// Frame times every `step_s` seconds from 0 to `seconds`.
pub fn frame_times(seconds: f64, step_s: f64) -> Vec<TimeUs> {
    let n = (seconds / step_s).round() as usize;
    (0..=n)
        .map(|k| (k as f64 * step_s * 1e6).round() as TimeUs)
        .collect()
}

/// A static scene at `dn` DN everywhere: frames every 100 ms from 0 to `seconds`.
pub fn static_frames(width: usize, height: usize, seconds: f64, dn: f32) -> PreparedFrames {
    frames(width, height, &frame_times(seconds, 0.1), |_, _, _| dn)
}

/// Events from `(t, x, y, on)`, sorted by time (then pixel, for a fixed order).
pub fn chunk(mut events: Vec<(TimeUs, u16, u16, bool)>) -> EventChunk {
    events.sort_unstable();
    let mut out = EventChunk::with_capacity(events.len());
    for (t, x, y, on) in events {
        out.push(t, x, y, on);
    }
    out
}

/// A seeded generator (the same events every run).
pub fn rng(seed: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(seed)
}

/// Arrival times of a Poisson process at `rate_hz` over `[start_s, end_s)`, microseconds.
pub fn poisson_times(
    rng: &mut Xoshiro256PlusPlus,
    rate_hz: f64,
    start_s: f64,
    end_s: f64,
) -> Vec<TimeUs> {
    let mut out = Vec::new();
    let mut t = start_s;
    loop {
        t += -(1.0 - rng.random::<f64>()).ln() / rate_hz;
        if t >= end_s {
            return out;
        }
        out.push((t * 1e6) as TimeUs);
    }
}

/// The statistics of a recording and of a model on one geometry.
pub struct Fixture {
    pub geometry: Geometry,
    pub real: Observed,
    pub sim: Observed,
    pub kept: Vec<bool>,
    pub model: PixelParams,
}

impl Fixture {
    /// `recording` and `model` (time-sorted) observed on the geometry of `frames`.
    pub fn new(frames: &PreparedFrames, recording: &EventChunk, model: &EventChunk) -> Self {
        let pixels = frames.width * frames.height;
        let geometry = Geometry::new(frames, &vec![false; pixels], BLOCKS, TimeUs::MAX);
        let no_mask = vec![false; pixels];
        let real = Observed::new(recording, &geometry, &no_mask);
        let keys = Observed::lag_keys(recording, &geometry);
        let sim = Observed::paired(model, &geometry, &no_mask, &keys);
        Self {
            geometry,
            real,
            sim,
            kept: vec![true; pixels],
            model: PixelParams::ideal(THRESHOLD, THRESHOLD),
        }
    }

    /// The evidence context: the fit blocks, nothing measured besides, stamps not on a grid.
    pub fn context(&self) -> Context<'_> {
        Context {
            real: &self.real,
            sim: &self.sim,
            geometry: &self.geometry,
            kept: &self.kept,
            model: &self.model,
            mismatch_estimate: None,
            timestamp_grid_us: None,
            shortest_interval_s: None,
            quiet_off: None,
            leak_drift: None,
            subset: Subset::Fit,
        }
    }
}

#[test]
fn the_fixture_geometry_fits_every_block_and_observes_every_event() {
    let frames = static_frames(4, 3, 1.0, 100.0);
    let events = chunk(vec![(500_000, 1, 1, true), (200_000, 0, 0, false)]);
    let f = Fixture::new(&frames, &events, &EventChunk::default());
    let g = &f.geometry;
    assert_eq!(g.blocks, BLOCKS);
    assert_eq!(g.blocks_of(crate::fit::observe::Role::Fit).len(), BLOCKS);
    assert!((g.duration_of(Subset::Fit) - 1.0).abs() < 1e-9);
    // 12 pixels for 1 s, all in the intensity bin of 100 DN (80 to 160)
    assert!((g.exposure_of(4, Subset::Fit) - 12.0).abs() < 1e-9);
    assert_eq!(f.real.total(g, Subset::Fit), 2);
    assert_eq!(f.sim.total(g, Subset::Fit), 0);
    // both isolated: background, OFF then ON, of intensity bin 4
    assert_eq!(f.real.background_of(g, Subset::Fit)[8..10], [1, 1]);
}
