//! Timestamp jitter: the time a sensor stamps on an event varies around the crossing time
//! (arbiter and readout delays; [`crate::sim::effects::jitter`]).
//!
//! Signature: a smeared interval histogram: same-pixel intervals shorter than the
//! recording's stamps otherwise allow. A recording whose stamps lie on a grid (a
//! simulator's frames) has no jitter. Evidence: the recording's share of same-pixel
//! intervals below 50 us against the model's, in binomial standard errors. Start: 100 us.

use super::{Context, Effect, Evidence};
use crate::fit::observe::interval_bin;

pub fn evidence(c: &Context) -> Evidence {
    if let Some(period) = c.timestamp_grid_us {
        return Evidence::none(
            Effect::TimestampJitter,
            format!("the timestamps lie on a {period} us grid: no jitter"),
        );
    }
    let (real, sim) = (
        c.real.intervals_of(c.geometry, c.subset),
        c.sim.intervals_of(c.geometry, c.subset),
    );
    let short = interval_bin(50e-6);
    let share = |h: &[u32]| {
        let n: f64 = h.iter().map(|&v| v as f64).sum();
        (
            h[..short].iter().map(|&v| v as f64).sum::<f64>() / n.max(1.0),
            n,
        )
    };
    let ((r, n), (s, _)) = (share(&real), share(&sim));
    let se = (s.max(1e-4) * (1.0 - s) / n.max(1.0)).sqrt();
    Evidence {
        effect: Effect::TimestampJitter,
        score: (r - s) / se,
        relevant: r > 2.0 * s + 0.005,
        text: format!(
            "{:.2} % of same-pixel intervals are below 50 us against {:.2} % in the model",
            100.0 * r,
            100.0 * s
        ),
        other_start: None,
        start: Some(100e-6),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::events::{EventChunk, TimeUs};
    use crate::fit::effects::EVIDENCE_THRESHOLD;
    use crate::fit::effects::fixture::{Fixture, chunk, rng, static_frames};
    use rand::RngExt;

    /// A 16 x 12 static scene for 1 s. The model: every pixel fires bursts of 4 events
    /// 300 us apart every 50 ms (an edge crossing several thresholds), so no same-pixel
    /// interval is shorter than 300 us. The recording: the same events with Gaussian
    /// timestamp jitter of `jitter_us` standard deviation, re-sorted.
    fn model_and_jittered(jitter_us: f64) -> (EventChunk, EventChunk) {
        let mut rng = rng(51);
        let (mut model, mut recording) = (Vec::new(), Vec::new());
        for y in 0..12u16 {
            for x in 0..16u16 {
                let phase = 1_000 + (rng.random::<f64>() * 45_000.0) as TimeUs;
                for burst in 0..19 {
                    for k in 0..4 {
                        let t = phase + burst * 50_000 + k * 300;
                        let (u1, u2) = (1.0 - rng.random::<f64>(), rng.random::<f64>());
                        let z = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                        let on = burst % 2 == 0;
                        model.push((t, x, y, on));
                        recording.push((t + (z * jitter_us).round() as TimeUs, x, y, on));
                    }
                }
            }
        }
        (chunk(model), chunk(recording))
    }

    #[test]
    fn a_hundred_us_of_jitter_makes_intervals_below_50_us_and_calls_for_jitter() {
        let (model, recording) = model_and_jittered(100.0);
        let f = Fixture::new(&static_frames(16, 12, 1.0, 100.0), &recording, &model);
        let e = evidence(&f.context());
        // about 2 % of the recording's intervals below 42 us (the bins below 50 us), none of
        // the model's
        assert!(e.calls_for(), "{e:?}");
        assert!(e.score > EVIDENCE_THRESHOLD, "{e:?}");
        let start = e.start.unwrap();
        assert!(start > 100e-6 / 2.0 && start < 100e-6 * 2.0, "{start}");
    }

    #[test]
    fn the_model_as_the_recording_does_not_call_for_jitter() {
        let (_, recording) = model_and_jittered(100.0);
        let f = Fixture::new(&static_frames(16, 12, 1.0, 100.0), &recording, &recording);
        let e = evidence(&f.context());
        assert!(!e.calls_for(), "{e:?}");
        assert_eq!(e.score, 0.0);
    }

    #[test]
    fn stamps_on_a_grid_do_not_call_for_jitter() {
        let (model, recording) = model_and_jittered(100.0);
        let f = Fixture::new(&static_frames(16, 12, 1.0, 100.0), &recording, &model);
        let context = Context {
            timestamp_grid_us: Some(50),
            ..f.context()
        };
        let e = evidence(&context);
        assert!(!e.calls_for(), "{e:?}");
        assert_eq!(e.score, 0.0);
    }
}
