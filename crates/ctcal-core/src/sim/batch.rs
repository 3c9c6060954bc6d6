//! A whole run of samples simulated at once, for callers that hold the samples in memory
//! (the re-simulation of a recording's upsampled frames, `estimate aps` and `fit`).
//!
//! [`Simulator::step`] updates the rows of one sample on the pool and merges their events
//! between samples. On a small sensor one sample's work (tens of microseconds) is shorter
//! than waking a second thread, so the pool's other thread mostly sleeps. Each row's pixels
//! are independent of the other rows and every row owns its random generator
//! ([`super::rng`]), so a row can instead be advanced through a batch of samples as one
//! task, and the rows' events merged once per batch, in the order `step` gives them
//! (by sample, then time, row, column; a pixel's events in generation order). The result
//! is the same events, bit for bit, as `start` + `step` per sample + `finish` (tested
//! below).
//!
//! The merge of a batch's events (a sort) and their release (through the jitter buffer)
//! take one thread; they run beside the advance of the next batch's rows, which depends
//! only on the rows, so that the pool's other thread does not wait on them.

use super::SimError;
use super::effects::jitter::JitterBuffer;
use super::log_response::LogMap;
use super::pixel::PixelModel;
use super::row::{Row, Step};
use super::simulator::Simulator;
use super::source::Sample;
use crate::events::{Event, EventChunk, TimeUs};
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;

/// Samples a row is advanced through per task: enough work to keep every thread busy,
/// few enough that the events held for merging stay a small part of the run's.
const BATCH: usize = 32;

impl Simulator {
    /// Simulates `samples` (times non-decreasing, each frame `width x height`): the
    /// events of [`Self::start`] on the first sample, [`Self::step`] on each later one and
    /// [`Self::finish`], with each row advanced through 32 samples at a time on the
    /// pool, beside the merge and release of the previous batch's events.
    pub fn run_all(&mut self, samples: &[Sample]) -> Result<EventChunk, SimError> {
        let Some((first, rest)) = samples.split_first() else {
            return Err(SimError::Invalid("the input has no frames".into()));
        };
        let pixels = self.width * self.height;
        if let Some(bad) = samples.iter().position(|s| s.dn.len() != pixels) {
            return Err(SimError::Invalid(format!(
                "sample {bad} has {} values for a {}x{} sensor",
                samples[bad].dn.len(),
                self.width,
                self.height
            )));
        }
        self.start(first.t, &first.dn);
        let windows = self.windows(first, rest)?;
        let mut out = EventChunk::default();
        let mut pending: Option<(&[Sample], RowEvents)> = None;
        for (batch, spans) in rest.chunks(BATCH).zip(windows.chunks(BATCH)) {
            let (mut rows, jitter) = self.rows_and_jitter();
            let (per_row, ()) = rayon::join(
                || rows.advance(batch, spans),
                || {
                    if let Some((previous, events)) = pending.take() {
                        emit(jitter, previous, &sort_merged(events.concat()), &mut out);
                    }
                },
            );
            pending = Some((batch, per_row));
        }
        if let Some((previous, events)) = pending {
            emit(
                &mut self.jitter,
                previous,
                &sort_merged(events.concat()),
                &mut out,
            );
        }
        if let Some((buffer, _)) = &mut self.jitter {
            buffer.flush(&mut out);
        }
        Ok(out)
    }

    /// The rows with what advancing them reads, and apart from them the jitter buffer
    /// that releases their events: the two halves of a batch's work in [`Self::run_all`].
    fn rows_and_jitter(&mut self) -> (Rows<'_>, &mut Jitter) {
        let rows = Rows {
            rows: &mut self.rows,
            log_frame: &mut self.log_frame,
            width: self.width,
            model: &self.model,
            log_map: self.log_map,
            origin: self.origin.expect("started"),
        };
        (rows, &mut self.jitter)
    }

    /// Each later sample's interval `(t0, t1]` in microseconds since the origin, as
    /// [`Self::step`] computes it; an error where sample times go backwards.
    fn windows(&mut self, first: &Sample, rest: &[Sample]) -> Result<Vec<(f64, f64)>, SimError> {
        let origin = self.origin.expect("started");
        let mut last = first.t;
        let mut windows = Vec::with_capacity(rest.len());
        for sample in rest {
            if sample.t < last {
                return Err(SimError::Invalid(format!(
                    "input sample times go backwards ({} us after {} us)",
                    sample.t, last
                )));
            }
            last = sample.t;
            let t1 = ((sample.t - origin) as f64).max(self.previous_us);
            windows.push((self.previous_us, t1));
            self.previous_us = t1;
        }
        Ok(windows)
    }
}

/// Each row's events of a batch, tagged with their sample's index in the batch.
type RowEvents = Vec<Vec<(u32, Event)>>;

/// The timestamp-jitter buffer and its generator, where the simulation has jitter.
type Jitter = Option<(JitterBuffer, Xoshiro256PlusPlus)>;

/// A simulator's rows and what advancing them reads.
struct Rows<'a> {
    rows: &'a mut [Row],
    log_frame: &'a mut [f32],
    width: usize,
    model: &'a PixelModel,
    log_map: LogMap,
    origin: TimeUs,
}

impl Rows<'_> {
    /// Every row through the samples of `batch`, one row a task: each row's events (in
    /// generation order) tagged with their sample's index in the batch, to be merged by
    /// [`sort_merged`].
    fn advance(&mut self, batch: &[Sample], spans: &[(f64, f64)]) -> RowEvents {
        let (width, model, log_map, origin) = (self.width, self.model, self.log_map, self.origin);
        self.rows
            .par_iter_mut()
            .zip(self.log_frame.par_chunks_mut(width))
            .enumerate()
            .map(|(y, (row, log_row))| {
                let mut events = Vec::new();
                for (k, (sample, &(t0, t1))) in batch.iter().zip(spans).enumerate() {
                    let step = Step {
                        model,
                        log_map,
                        origin,
                        t0,
                        t1,
                        transition: sample.transition,
                    };
                    let dn_row = &sample.dn[y * width..(y + 1) * width];
                    row.advance(&step, dn_row, log_row);
                    events.extend(row.events.iter().map(|&e| (k as u32, e)));
                }
                events
            })
            .collect()
    }
}

/// Appends the merged events of `batch` to `out` as `step` emits them: as they are,
/// or through the timestamp-jitter buffer one sample at a time.
fn emit(jitter: &mut Jitter, batch: &[Sample], merged: &[(u32, Event)], out: &mut EventChunk) {
    let Some((buffer, rng)) = jitter else {
        for &(_, e) in merged {
            out.push_event(e);
        }
        return;
    };
    let mut staged = EventChunk::default();
    let mut next = 0;
    for (k, sample) in batch.iter().enumerate() {
        staged.clear();
        while let Some(&(_, e)) = merged.get(next).filter(|(s, _)| *s == k as u32) {
            staged.push_event(e);
            next += 1;
        }
        buffer.push(&staged, sample.t, rng, out);
    }
}

/// `events` in the order of a stable sort by (sample, time, row, column): a pixel's events
/// keep their generation order (their order in `events`) when their times tie.
///
/// Each event's key and position are packed into one `u128` (sample 8 bits, time since the
/// batch's earliest 56, row 16, column 16, position 32) and the keys sorted unstably:
/// keys with the position are distinct, so any sort gives the stable sort's order, and an
/// unstable sort of integers costs a fraction of the stable parallel merge sort of the
/// events by a tuple key (which was a tenth of `estimate aps`). A batch whose fields do
/// not fit is sorted the stable way.
fn sort_merged(mut events: Vec<(u32, Event)>) -> Vec<(u32, Event)> {
    let earliest = events.iter().map(|(_, e)| e.t).min().unwrap_or(0);
    let latest = events.iter().map(|(_, e)| e.t).max().unwrap_or(0);
    let fits = events.len() <= u32::MAX as usize
        && events.iter().all(|&(k, _)| k < 1 << 8)
        && latest.abs_diff(earliest) < 1 << 56;
    if !fits {
        events.par_sort_by_key(|&(k, e)| (k, e.t, e.y, e.x));
        return events;
    }
    let mut keys: Vec<u128> = events
        .iter()
        .enumerate()
        .map(|(i, &(k, e))| {
            (k as u128) << 120
                | (e.t.abs_diff(earliest) as u128) << 64
                | (e.y as u128) << 48
                | (e.x as u128) << 32
                | i as u128
        })
        .collect();
    keys.par_sort_unstable();
    keys.iter()
        .map(|&key| events[key as u32 as usize])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{PixelMaps, PixelParams, Transition};

    /// Moving bright bars over a 37 x 11 sensor: enough events per row and sample for
    /// ties, refractory, noise and jitter to matter.
    fn samples(n: usize) -> Vec<Sample> {
        let (w, h) = (37usize, 11usize);
        (0..n)
            .map(|k| Sample {
                t: 1_000 + 700 * k as i64,
                dn: (0..w * h)
                    .map(|i| {
                        let (x, y) = ((i % w) as f32, (i / w) as f32);
                        40.0 + 150.0 * (0.5 + 0.5 * ((x + 0.3 * y - 0.9 * k as f32) * 0.5).sin())
                    })
                    .collect(),
                transition: Transition::Linear,
            })
            .collect()
    }

    fn stepped(params: &PixelParams, samples: &[Sample], stream: u64) -> EventChunk {
        let mut sim = Simulator::new(params, 37, 11, PixelMaps::default()).noise_stream(stream);
        sim.start(samples[0].t, &samples[0].dn);
        let mut all = EventChunk::default();
        for s in &samples[1..] {
            all.extend_from(sim.step(s.t, &s.dn, s.transition));
        }
        all.extend_from(sim.finish());
        all
    }

    fn batch(params: &PixelParams, samples: &[Sample], stream: u64) -> EventChunk {
        Simulator::new(params, 37, 11, PixelMaps::default())
            .noise_stream(stream)
            .run_all(samples)
            .unwrap()
    }

    #[test]
    fn the_same_events_as_stepping_with_and_without_effects() {
        let samples = samples(60);
        let ideal = PixelParams::ideal(0.2, 0.25);
        let noisy = PixelParams {
            ct_sigma: Some(0.03),
            refractory_s: Some(200e-6),
            shot_noise_rate_hz: Some(2.0),
            timestamp_jitter_s: Some(150e-6),
            cutoff_hz: Some(400.0),
            leak_rate_hz: Some(0.5),
            leak_rate_hz_per_dn: Some(0.004),
            hot_pixel_fraction: Some(0.02),
            hot_pixel_rate_hz: Some(80.0),
            ..ideal.clone()
        };
        for (params, stream) in [(&ideal, 0), (&noisy, 0), (&noisy, 3)] {
            let a = stepped(params, &samples, stream);
            assert!(
                a.len() > 500,
                "{} events: the case exercises too little",
                a.len()
            );
            assert_eq!(a, batch(params, &samples, stream));
        }
    }

    /// Events with ties of sample, time and pixel (the two polarities of one pixel at one
    /// time, in generation order): the packed sort, and the stable one it falls back to
    /// when times span more than 56 bits, give the stable sort's order.
    #[test]
    fn the_packed_sort_is_the_stable_sort() {
        use rand::RngExt;
        let mut rng = crate::sim::rng::generator(5, crate::sim::rng::Stream::Scene, 0);
        let events: Vec<(u32, Event)> = (0..5000)
            .map(|_| {
                let e = Event {
                    t: 1_000_000 + rng.random_range(0..40i64),
                    x: rng.random_range(0..3u16),
                    y: rng.random_range(0..3u16),
                    on: rng.random_range(0..2u8) == 1,
                };
                (rng.random_range(0..4u32), e)
            })
            .collect();
        for far in [0, i64::MAX - 2_000_000] {
            let mut events = events.clone();
            events[17].1.t += far;
            let mut stable = events.clone();
            stable.sort_by_key(|&(k, e)| (k, e.t, e.y, e.x));
            assert_eq!(sort_merged(events), stable);
        }
    }

    #[test]
    fn errors_name_backward_times_and_wrong_sizes() {
        let mut s = samples(3);
        s[2].t = 0;
        let p = PixelParams::ideal(0.2, 0.2);
        let e = Simulator::new(&p, 37, 11, PixelMaps::default()).run_all(&s);
        assert!(e.unwrap_err().to_string().contains("backwards"));
        let mut s = samples(3);
        s[1].dn.pop();
        let e = Simulator::new(&p, 37, 11, PixelMaps::default()).run_all(&s);
        assert!(
            e.unwrap_err()
                .to_string()
                .contains("sample 1 has 406 values")
        );
        assert!(
            Simulator::new(&p, 37, 11, PixelMaps::default())
                .run_all(&[])
                .is_err()
        );
    }
}
