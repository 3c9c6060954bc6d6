//! Timestamp jitter: readout arbitration and the finite clock blur event times. Each event
//! time gets Gaussian noise of standard deviation `timestamp_jitter_s`, truncated at six
//! standard deviations (which changes the spread by less than 1e-6), and stays inside the
//! simulated span (a jittered time before the first sample or after the latest one is
//! clamped to it); events are then re-sorted. Jittered events can move across frame
//! intervals, so they wait in a buffer until no later-generated event can precede them (the
//! truncation bound), which keeps the output sorted.

use crate::events::{Event, EventChunk, TimeUs};
use rand::Rng;
use rand_distr::{Distribution, Normal};

/// Holds jittered events until they can be released in time order.
pub struct JitterBuffer {
    normal: Normal<f64>,
    margin_us: TimeUs,
    pending: Vec<Event>,
    /// The simulated span so far: jittered times stay inside it.
    span: (TimeUs, TimeUs),
}

impl JitterBuffer {
    pub fn new(sigma_s: f64) -> Self {
        let sigma_us = sigma_s * 1e6;
        Self {
            normal: Normal::new(0.0, sigma_us).expect("finite sigma"),
            margin_us: (6.0 * sigma_us).ceil() as TimeUs + 1,
            pending: Vec::new(),
            span: (TimeUs::MIN, TimeUs::MAX),
        }
    }

    /// Sets the time of the first sample: no event is jittered before it.
    pub fn start(&mut self, t: TimeUs) {
        self.span = (t, t);
    }

    /// Jitters `events` (generated up to `generated_until`) and moves every event that no
    /// later event can precede into `out`, sorted.
    pub fn push(
        &mut self,
        events: &EventChunk,
        generated_until: TimeUs,
        rng: &mut impl Rng,
        out: &mut EventChunk,
    ) {
        self.span.1 = self.span.1.max(generated_until);
        let bound = (self.margin_us - 1) as f64;
        for mut e in events.iter() {
            let offset = self.normal.sample(rng).clamp(-bound, bound).round() as TimeUs;
            e.t = (e.t + offset).clamp(self.span.0, self.span.1);
            self.pending.push(e);
        }
        self.release(generated_until - self.margin_us, out);
    }

    /// Releases everything (end of simulation).
    pub fn flush(&mut self, out: &mut EventChunk) {
        self.release(TimeUs::MAX, out);
    }

    fn release(&mut self, before: TimeUs, out: &mut EventChunk) {
        self.pending.sort_by_key(|e| (e.t, e.y, e.x));
        let split = self.pending.partition_point(|e| e.t < before);
        for e in self.pending.drain(..split) {
            out.push_event(e);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn jittered_events_come_out_sorted_with_the_requested_spread() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(9);
        let mut buffer = JitterBuffer::new(100e-6);
        buffer.start(0);
        let mut out = EventChunk::default();
        let mut offsets = Vec::new();
        for block in 0..100 {
            let chunk: EventChunk = (0..100)
                .map(|i| Event {
                    t: block * 1000 + i * 10,
                    x: i as u16,
                    y: 0,
                    on: true,
                })
                .collect();
            buffer.push(&chunk, block * 1000 + 1000, &mut rng, &mut out);
        }
        buffer.flush(&mut out);
        assert_eq!(out.len(), 10_000);
        assert!(out.is_time_sorted());
        // events at t = 0 .. 90 us jittered by 100 us never go before the first sample
        assert_eq!(out.t[0], 0);
        assert!(
            out.t.iter().filter(|&&t| t == 0).count() >= 2,
            "about 4 of the first events jitter below 0 and are clamped"
        );
        assert!(*out.t.last().unwrap() <= 100_000);
        for e in out.iter() {
            let block = (0..100).find(|b| {
                let nominal = b * 1000 + e.x as i64 * 10;
                (e.t - nominal).abs() < 700
            });
            if let Some(b) = block {
                offsets.push((e.t - (b * 1000 + e.x as i64 * 10)) as f64);
            }
        }
        let sd = (offsets.iter().map(|o| o * o).sum::<f64>() / offsets.len() as f64).sqrt();
        assert!((sd - 100.0).abs() < 10.0, "{sd}");
    }
}
