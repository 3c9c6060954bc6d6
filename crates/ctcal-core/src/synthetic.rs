//! Deterministic synthetic event streams for benchmarks and streaming tests: edges sweeping
//! across the sensor (90 % of events, ON for two edges, OFF for the other two) plus uniform
//! background events, Poisson in time at a given mean rate. Not a physical simulation (see
//! [`crate::sim`] for that); a cheap, reproducible load with realistic locality.

use crate::events::{EventChunk, Sensor};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// An endless source of synthetic events.
pub struct SyntheticEvents {
    rng: Xoshiro256PlusPlus,
    sensor: Sensor,
    rate_per_s: f64,
    t_s: f64,
}

impl SyntheticEvents {
    pub fn new(sensor: Sensor, rate_per_s: f64, seed: u64) -> Self {
        Self {
            rng: Xoshiro256PlusPlus::seed_from_u64(seed),
            sensor,
            rate_per_s,
            t_s: 0.0,
        }
    }

    /// Appends `n` events to `out`.
    pub fn fill(&mut self, out: &mut EventChunk, n: usize) {
        let (w, h) = (self.sensor.width as f64, self.sensor.height as f64);
        for _ in 0..n {
            self.t_s += -(1.0 - self.rng.random::<f64>()).ln() / self.rate_per_s;
            let (x, y, on) = if self.rng.random::<f64>() < 0.9 {
                let edge = self.rng.random_range(0..4u32) as f64;
                let x = ((self.t_s * 200.0 + edge * w / 4.0) % w + self.rng.random::<f64>() * 2.0)
                    .min(w - 1.0);
                (x, self.rng.random::<f64>() * h, edge < 2.0)
            } else {
                (
                    self.rng.random::<f64>() * w,
                    self.rng.random::<f64>() * h,
                    self.rng.random::<bool>(),
                )
            };
            out.push((self.t_s * 1e6) as i64, x as u16, y as u16, on);
        }
    }

    /// `n` events in one chunk.
    pub fn take(&mut self, n: usize) -> EventChunk {
        let mut out = EventChunk::with_capacity(n);
        self.fill(&mut out, n);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn events_are_sorted_inside_the_sensor_at_the_requested_rate() {
        let sensor = Sensor::new(640, 480);
        let events = SyntheticEvents::new(sensor, 1e6, 1).take(100_000);
        assert!(events.is_time_sorted());
        assert!(events.iter().all(|e| sensor.contains(e.x, e.y)));
        let span = (events.t[events.len() - 1] - events.t[0]) as f64 * 1e-6;
        assert!((span - 0.1).abs() < 0.005, "{span}");
        let again = SyntheticEvents::new(sensor, 1e6, 1).take(100_000);
        assert!(again == events);
    }
}
