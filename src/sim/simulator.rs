//! The simulator: a sensor of [`PixelState`]s driven by a sequence of intensity frames.
//!
//! Pixel state lives in one flat array updated row-parallel with rayon; each row has its own
//! random generator (see [`super::rng`]), so the output is identical whatever the thread
//! count. Events of an interval are gathered per row into reused buffers (no allocation per
//! event) and merged in time order.

use super::effects::{hot_pixels, jitter::JitterBuffer, leak, mismatch, shot_noise};
use super::log_response::LogMap;
use super::params::PixelParams;
use super::pixel::{EventSink, PixelModel, PixelState, Transition, exponential_us};
use super::rng::{Stream, generator};
use crate::events::{Event, EventChunk, TimeUs};
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;

/// Per-pixel values given instead of drawn: a camera's (or an oracle's) realised pixels.
#[derive(Clone, Debug, Default)]
pub struct PixelMaps {
    /// ON thresholds, row-major W x H.
    pub ct_on: Option<Vec<f32>>,
    /// OFF thresholds.
    pub ct_off: Option<Vec<f32>>,
    /// Leak-rate factors.
    pub leak_factor: Option<Vec<f32>>,
}

struct Row {
    rng: Xoshiro256PlusPlus,
    events: Vec<Event>,
}

/// A running simulation.
pub struct Simulator {
    width: usize,
    height: usize,
    model: PixelModel,
    log_map: LogMap,
    pixels: Vec<PixelState>,
    rows: Vec<Row>,
    origin: Option<TimeUs>,
    previous_us: f64,
    jitter: Option<(JitterBuffer, Xoshiro256PlusPlus)>,
    merged: Vec<Event>,
    staged: EventChunk,
    out: EventChunk,
    log_frame: Vec<f32>,
    seed: u64,
    params: PixelParams,
    maps: PixelMaps,
}

impl Simulator {
    /// A `width x height` sensor with `params`; `maps` override drawn per-pixel values.
    pub fn new(params: &PixelParams, width: usize, height: usize, maps: PixelMaps) -> Self {
        let model = PixelModel {
            refractory_us: params.refractory_s() * 1e6,
            cutoff_hz: params.cutoff_hz().map(|c| c as f32),
            sigma_temporal: params
                .ct_sigma_temporal
                .filter(|&s| s > 0.0)
                .map(|s| s as f32),
            noise_bright_factor: params.shot_noise_bright_factor() as f32,
            hot_rate_per_us: params.hot_pixels().map_or(0.0, |(_, r)| r * 1e-6),
            substep_tolerance: 0.002,
            max_substeps: 256,
        };
        let seed = params.seed();
        let rows = (0..height)
            .map(|y| Row {
                rng: generator(seed, Stream::Rows, y as u64),
                events: Vec::new(),
            })
            .collect();
        let jitter = params
            .timestamp_jitter_s
            .filter(|&s| s > 0.0)
            .map(|s| (JitterBuffer::new(s), generator(seed, Stream::Jitter, 0)));
        Self {
            width,
            height,
            model,
            log_map: LogMap::new(params.log_response(), params.log_eps()),
            pixels: Vec::new(),
            rows,
            origin: None,
            previous_us: 0.0,
            jitter,
            merged: Vec::new(),
            staged: EventChunk::default(),
            out: EventChunk::default(),
            log_frame: vec![0.0; width * height],
            seed,
            params: params.clone(),
            maps,
        }
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    /// The pixels' current state (for inspection and tests).
    pub fn pixels(&self) -> &[PixelState] {
        &self.pixels
    }

    /// The first sample: sets every pixel's reference and filter to this frame (no events).
    pub fn start(&mut self, t: TimeUs, dn: &[f32]) {
        assert_eq!(dn.len(), self.width * self.height, "frame size");
        self.origin = Some(t);
        self.previous_us = 0.0;
        let params = &self.params;
        let n = self.width * self.height;
        let mut threshold_rng = generator(self.seed, Stream::Thresholds, 0);
        let sigma = params.ct_sigma.unwrap_or(0.0);
        let mut draw_map = |given: &Option<Vec<f32>>, nominal: f64| -> Vec<f32> {
            match given {
                Some(map) => map
                    .iter()
                    .map(|&v| v.max(mismatch::MIN_THRESHOLD))
                    .collect(),
                None => (0..n)
                    .map(|_| mismatch::draw_threshold(nominal, sigma, &mut threshold_rng))
                    .collect(),
            }
        };
        let theta_on = draw_map(&self.maps.ct_on, params.ct_on);
        let theta_off = draw_map(&self.maps.ct_off, params.ct_off);
        let leak_rate = params.leak_rate_hz();
        let leak_factors: Vec<f32> = match (&self.maps.leak_factor, leak_rate > 0.0) {
            (Some(map), _) => map.clone(),
            (None, true) => {
                let mut rng = generator(self.seed, Stream::Leak, 0);
                (0..n)
                    .map(|_| leak::draw_factor(params.leak_spread_decades(), &mut rng))
                    .collect()
            }
            (None, false) => vec![1.0; n],
        };
        let mut noise_rng = generator(self.seed, Stream::Rows, u64::MAX);
        let noise_rate = params.shot_noise_rate_hz();
        self.pixels = (0..n)
            .map(|i| {
                let u = self.log_map.apply(dn[i]);
                let mut p = PixelState::new(u, dn[i], theta_on[i], theta_off[i]);
                p.leak_per_us = leak::drift_per_us(leak_rate, leak_factors[i], theta_on[i]);
                if noise_rate > 0.0 {
                    let (rate, on_share) = shot_noise::pixel_rates(
                        noise_rate,
                        params.ct_on,
                        params.ct_off,
                        theta_on[i],
                        theta_off[i],
                    );
                    p.noise_rate_per_us = rate;
                    p.noise_on_share = on_share;
                    p.next_noise_us = exponential_us(rate, &mut noise_rng);
                }
                p
            })
            .collect();
        if let Some((fraction, _)) = params.hot_pixels() {
            let mut rng = generator(self.seed, Stream::HotPixels, 0);
            for index in hot_pixels::choose(n, fraction, &mut rng) {
                self.pixels[index].next_hot_us =
                    exponential_us(self.model.hot_rate_per_us, &mut rng);
            }
        }
    }

    /// The next sample at time `t`: returns the events in (previous sample, `t`], sorted
    /// by time (then row, then column).
    pub fn step(&mut self, t: TimeUs, dn: &[f32], transition: Transition) -> &EventChunk {
        let origin = self.origin.expect("start() before step()");
        assert_eq!(dn.len(), self.width * self.height, "frame size");
        let (t0, t1) = (self.previous_us, (t - origin) as f64);
        let t1 = t1.max(t0);
        let width = self.width;
        let model = &self.model;
        let log_map = self.log_map;
        self.log_frame
            .par_chunks_mut(width)
            .zip(dn.par_chunks(width))
            .for_each(|(out, dn)| {
                log_map.apply_frame(dn, out);
            });
        let log_frame = &self.log_frame;
        self.pixels
            .par_chunks_mut(width)
            .zip(self.rows.par_iter_mut())
            .enumerate()
            .with_min_len(4)
            .for_each(|(y, (pixels, row))| {
                row.events.clear();
                let base = y * width;
                for (x, pixel) in pixels.iter_mut().enumerate() {
                    let mut sink = EventSink {
                        events: &mut row.events,
                        origin_us: origin,
                        x: x as u16,
                        y: y as u16,
                    };
                    pixel.advance(
                        model,
                        t0,
                        t1,
                        log_frame[base + x],
                        dn[base + x],
                        transition,
                        &mut row.rng,
                        &mut sink,
                    );
                }
            });
        self.previous_us = t1;
        self.merged.clear();
        for row in &self.rows {
            self.merged.extend_from_slice(&row.events);
        }
        // stable: a pixel's events keep their generation order when times tie
        self.merged.sort_by_key(|e| (e.t, e.y, e.x));
        self.out.clear();
        match &mut self.jitter {
            None => {
                for &e in &self.merged {
                    self.out.push_event(e);
                }
            }
            Some((buffer, rng)) => {
                self.staged.clear();
                for &e in &self.merged {
                    self.staged.push_event(e);
                }
                buffer.push(&self.staged, t, rng, &mut self.out);
            }
        }
        &self.out
    }

    /// Releases events still held back (timestamp jitter); call after the last step.
    pub fn finish(&mut self) -> &EventChunk {
        self.out.clear();
        if let Some((buffer, _)) = &mut self.jitter {
            buffer.flush(&mut self.out);
        }
        &self.out
    }

    /// Number of pixel rows (for progress reporting).
    pub fn rows(&self) -> usize {
        self.height
    }
}
