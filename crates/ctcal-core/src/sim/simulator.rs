//! The simulator: a sensor of pixels driven by a sequence of intensity frames.
//!
//! Pixel state is kept per row ([`super::row`]), rows updated in parallel with rayon in
//! groups: the vectorised phase of every row of a group, then the full updates of its busy
//! pixels. Each row owns its random generator (see [`super::rng`]), so output is identical
//! whatever the thread count; events go to reused per-row buffers and are merged in time
//! order.

use super::effects::{hot_pixels, jitter::JitterBuffer, leak, mismatch, shot_noise};
use super::log_response::LogMap;
use super::params::PixelParams;
use super::pixel::{PixelModel, PixelState, Transition, exponential_us};
use super::rng::{Stream, generator};
use super::row::{Cold, Row, Step};
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

/// A running simulation.
pub struct Simulator {
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) model: PixelModel,
    pub(super) log_map: LogMap,
    pub(super) rows: Vec<Row>,
    pub(super) origin: Option<TimeUs>,
    pub(super) previous_us: f64,
    pub(super) jitter: Option<(JitterBuffer, Xoshiro256PlusPlus)>,
    merged: Vec<Event>,
    staged: EventChunk,
    out: EventChunk,
    pub(super) log_frame: Vec<f32>,
    seed: u64,
    /// Which draw of the pixels' random updates (shot noise, temporal threshold noise,
    /// hot-pixel trains, jitter) this simulation takes; the frozen draws (thresholds, leak
    /// factors, which pixels are hot) do not depend on it. See [`Self::noise_stream`].
    noise_stream: u64,
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
            fast_path_effects: params.has_leak()
                || params.shot_noise_rate_hz() > 0.0
                || params.hot_pixels().is_some(),
            intensity_window: params.cutoff_hz().is_none()
                && !params.has_leak()
                && params.shot_noise_rate_hz() <= 0.0
                && params.hot_pixels().is_none(),
            per_pixel_history: params.refractory_s() > 0.0
                || params.ct_sigma_temporal.is_some_and(|s| s > 0.0)
                || params.shot_noise_rate_hz() > 0.0
                || params.hot_pixels().is_some(),
        };
        let jitter = params.timestamp_jitter_s.filter(|&s| s > 0.0).map(|s| {
            (
                JitterBuffer::new(s),
                generator(params.seed(), Stream::Jitter, 0),
            )
        });
        Self {
            width,
            height,
            model,
            log_map: LogMap::new(params.log_response(), params.log_eps()),
            rows: Vec::new(),
            origin: None,
            previous_us: 0.0,
            jitter,
            merged: Vec::new(),
            staged: EventChunk::default(),
            out: EventChunk::default(),
            log_frame: vec![0.0; width * height],
            seed: params.seed(),
            noise_stream: 0,
            params: params.clone(),
            maps,
        }
    }

    /// The same sensor (thresholds, leak factors, hot pixels) with the `k`-th independent
    /// draw of its random updates: separate runs of one recording (blocks of frames, runs
    /// between dropped intervals) are independent stretches of time, whose noise must not
    /// repeat from run to run. Stream 0 is the draw of a simulation that sets none.
    pub fn noise_stream(mut self, k: u64) -> Self {
        self.noise_stream = k;
        if let Some((_, rng)) = &mut self.jitter {
            *rng = generator(self.seed, Stream::Jitter, k);
        }
        self
    }

    /// The index of a row's (or the noise set-up's) generator in the noise stream.
    fn noise_index(&self, index: u64) -> u64 {
        index ^ self.noise_stream.rotate_left(32)
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    /// The state of pixel (x, y) (for inspection and tests).
    pub fn pixel(&self, x: usize, y: usize) -> PixelState {
        self.rows[y].load(x, &self.model, &self.log_map)
    }

    /// The first sample: sets every pixel's reference and filter to this frame (no events).
    pub fn start(&mut self, t: TimeUs, dn: &[f32]) {
        assert_eq!(dn.len(), self.width * self.height, "frame size");
        self.origin = Some(t);
        self.previous_us = 0.0;
        if let Some((buffer, _)) = &mut self.jitter {
            buffer.start(t);
        }
        let draws = self.draw_pixels();
        let this = &*self;
        let rows: Vec<Row> = (0..self.height)
            .into_par_iter()
            .map(|y| this.row_at_start(y, dn, &draws))
            .collect();
        self.rows = rows;
    }

    /// Every pixel's thresholds, leak factor, noise rate and first noise and hot-train
    /// times, each from its own seeded stream (so that one effect's draws do not move
    /// another's).
    fn draw_pixels(&self) -> PixelDraws {
        let (theta_on, theta_off) = self.draw_thresholds();
        let leak_factors = self.draw_leak_factors();
        let hot_next = self.draw_hot_trains();
        let (rates, next_noise) = self.draw_noise(&theta_on, &theta_off);
        PixelDraws {
            theta_on,
            theta_off,
            leak_factors,
            hot_next,
            rates,
            next_noise,
        }
    }

    /// Every pixel's ON and OFF thresholds: the given map (each value at least
    /// [`mismatch::MIN_THRESHOLD`]), or draws around the nominal threshold with the
    /// mismatch `ct_sigma`, ON then OFF from the one thresholds stream.
    fn draw_thresholds(&self) -> (Vec<f32>, Vec<f32>) {
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
        (theta_on, theta_off)
    }

    /// Every pixel's leak-rate factor: the given map, or draws from the leak stream when
    /// leak is on, or 1.
    fn draw_leak_factors(&self) -> Vec<f32> {
        let params = &self.params;
        let n = self.width * self.height;
        match (&self.maps.leak_factor, params.has_leak()) {
            (Some(map), _) => map.clone(),
            (None, true) => {
                let mut rng = generator(self.seed, Stream::Leak, 0);
                (0..n)
                    .map(|_| leak::draw_factor(params.leak_spread_decades(), &mut rng))
                    .collect()
            }
            (None, false) => vec![1.0; n],
        }
    }

    /// The first event time of every pixel's hot train (infinite where the pixel is not
    /// hot): the hot pixels chosen, then their first times drawn, from the hot-pixel
    /// stream.
    fn draw_hot_trains(&self) -> Vec<f64> {
        let n = self.width * self.height;
        let mut hot_next = vec![f64::INFINITY; n];
        if let Some((fraction, _)) = self.params.hot_pixels() {
            let mut rng = generator(self.seed, Stream::HotPixels, 0);
            for index in hot_pixels::choose(n, fraction, &mut rng) {
                hot_next[index] = exponential_us(self.model.hot_rate_per_us, &mut rng);
            }
        }
        hot_next
    }

    /// Every pixel's shot-noise rate per microsecond and ON share (from its thresholds,
    /// on the pool), then its first noise time, drawn in pixel order from the one set-up
    /// generator of this simulation's noise stream.
    fn draw_noise(&self, theta_on: &[f32], theta_off: &[f32]) -> (Vec<(f64, f32)>, Vec<f64>) {
        let params = &self.params;
        let n = self.width * self.height;
        let mut noise_rng = generator(self.seed, Stream::Rows, self.noise_index(u64::MAX));
        let noise_rate = params.shot_noise_rate_hz();
        let rates: Vec<(f64, f32)> = (0..n)
            .into_par_iter()
            .map(|i| {
                if noise_rate > 0.0 {
                    shot_noise::pixel_rates(
                        noise_rate,
                        params.ct_on,
                        params.ct_off,
                        theta_on[i],
                        theta_off[i],
                    )
                } else {
                    (0.0, 0.5)
                }
            })
            .collect();
        let next_noise: Vec<f64> = rates
            .iter()
            .map(|&(rate, _)| exponential_us(rate, &mut noise_rng))
            .collect();
        (rates, next_noise)
    }

    /// Row `y` at the first sample `dn`: its references and filters at the frame, its
    /// pixels' draws.
    fn row_at_start(&self, y: usize, dn: &[f32], draws: &PixelDraws) -> Row {
        let (width, log_map) = (self.width, self.log_map);
        let (leak_rate, leak_per_dn) = (
            self.params.leak_rate_hz(),
            self.params.leak_rate_hz_per_dn(),
        );
        let range = y * width..(y + 1) * width;
        let input: Vec<f32> = dn[range.clone()]
            .iter()
            .map(|&d| log_map.apply(d))
            .collect();
        let cold: Vec<Cold> = range
            .clone()
            .map(|i| Cold {
                frozen_on: draws.theta_on[i],
                frozen_off: draws.theta_off[i],
                noise_rate_per_us: draws.rates[i].0,
                noise_on_share: draws.rates[i].1,
                last_event_us: f64::NEG_INFINITY,
                next_noise_us: draws.next_noise[i],
                next_hot_us: draws.hot_next[i],
            })
            .collect();
        let mut row = Row {
            y: y as u16,
            reference: input.clone(),
            filtered: input.clone(),
            input,
            dn: dn[range.clone()].to_vec(),
            theta_on: draws.theta_on[range.clone()].to_vec(),
            theta_off: draws.theta_off[range.clone()].to_vec(),
            leak: range
                .clone()
                .map(|i| leak::drift_per_us(leak_rate, draws.leak_factors[i], draws.theta_on[i]))
                .collect(),
            leak_per_dn: range
                .clone()
                .map(|i| leak::drift_per_us(leak_per_dn, draws.leak_factors[i], draws.theta_on[i]))
                .collect(),
            next_interrupt: cold
                .iter()
                .map(|c| c.next_noise_us.min(c.next_hot_us))
                .collect(),
            window_low: vec![0.0; width],
            window_high: vec![0.0; width],
            busy: vec![0; width],
            filter_end: vec![0.0; width],
            cold,
            rng: generator(self.seed, Stream::Rows, self.noise_index(y as u64)),
            events: Vec::new(),
        };
        if self.model.intensity_window {
            for x in 0..width {
                row.update_window(x, &log_map);
            }
        }
        row
    }

    /// The next sample at time `t`: returns the events in (previous sample, `t`], sorted
    /// by time (then row, then column).
    pub fn step(&mut self, t: TimeUs, dn: &[f32], transition: Transition) -> &EventChunk {
        let origin = self.origin.expect("start() before step()");
        assert_eq!(dn.len(), self.width * self.height, "frame size");
        let (t0, t1) = (
            self.previous_us,
            ((t - origin) as f64).max(self.previous_us),
        );
        let width = self.width;
        let model = &self.model;
        let log_map = self.log_map;
        let log_frame = &mut self.log_frame;
        self.rows
            .par_iter_mut()
            .zip(log_frame.par_chunks_mut(width))
            .zip(dn.par_chunks(width))
            .with_min_len(4)
            .for_each(|((row, log_row), dn_row)| {
                let step = Step {
                    model,
                    log_map,
                    origin,
                    t0,
                    t1,
                    transition,
                };
                row.advance(&step, dn_row, log_row);
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
}
/// Every pixel's draws at the first sample (row-major).
struct PixelDraws {
    theta_on: Vec<f32>,
    theta_off: Vec<f32>,
    leak_factors: Vec<f32>,
    /// The first event time of each pixel's hot train (infinite: not a hot pixel).
    hot_next: Vec<f64>,
    /// Each pixel's shot-noise rate per microsecond and ON share.
    rates: Vec<(f64, f32)>,
    next_noise: Vec<f64>,
}
