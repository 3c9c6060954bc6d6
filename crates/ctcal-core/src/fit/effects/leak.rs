//! Leak: junction leakage makes the memorised level drift down, so pixels emit ON events
//! at a steady rate even in a static scene (Nozaki & Delbruck, IEEE TED 2017;
//! [`crate::sim::effects::leak`]).
//!
//! Signature: an excess of ON events among the events without spatio-temporal support
//! (isolated events), beyond any excess of OFF events (which shot noise would make
//! alike), growing with the time since a pixel's last event. Evidence: the ON excess
//! minus the OFF excess, in Poisson standard errors; it matters above 0.005 events per
//! pixel-second. Start: that excess rate (one leak event per period, most of them isolated).

use super::{Context, Effect, Evidence, background_totals};

pub fn evidence(c: &Context) -> Evidence {
    let ([r_off, r_on, s_off, s_on], exposure) = background_totals(c);
    if exposure <= 0.0 {
        return Evidence::none(
            Effect::Leak,
            "no reliable pixel-time to count isolated events",
        );
    }
    let excess_on = r_on - s_on;
    let excess_off = (r_off - s_off).max(0.0);
    let (score, rate) = score([r_off, r_on, s_off, s_on], exposure);
    Evidence {
        effect: Effect::Leak,
        score,
        relevant: rate > RELEVANT_HZ,
        text: format!(
            "isolated ON events exceed the model's by {:.4} Hz per pixel beyond the OFF excess ({:.4} Hz): {score:.1} standard errors",
            excess_on / exposure,
            excess_off / exposure,
        ),
        start: Some((rate / 0.9).max(1e-3)),
    }
}

/// The ON excess rate (beyond any OFF excess) below which leak does not matter, events per
/// pixel-second.
pub const RELEVANT_HZ: f64 = 0.005;

/// The evidence's score (the ON excess over the model beyond any OFF excess, in Poisson
/// standard errors of all four counts) and the excess rate it stands for, from the
/// isolated events `[real OFF, real ON, model OFF, model ON]` over `exposure`
/// pixel-seconds.
pub fn score([r_off, r_on, s_off, s_on]: [f64; 4], exposure: f64) -> (f64, f64) {
    let leak = (r_on - s_on) - (r_off - s_off).max(0.0);
    let sigma = (r_on + s_on + r_off + s_off + 1.0).sqrt();
    (leak / sigma, leak / exposure)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::events::TimeUs;
    use crate::fit::effects::EVIDENCE_THRESHOLD;
    use crate::fit::effects::fixture::{Fixture, chunk, poisson_times, rng, static_frames};
    use rand::RngExt;

    type Events = Vec<(TimeUs, u16, u16, bool)>;

    /// A 16 x 12 static scene at 100 DN for 10 s whose pixels fire isolated events of both
    /// polarities at 0.05 Hz each (the model).
    fn noise_floor() -> Events {
        let mut rng = rng(21);
        let mut events = Vec::new();
        for y in 0..12u16 {
            for x in 0..16u16 {
                for t in poisson_times(&mut rng, 0.05, 0.0, 10.0) {
                    events.push((t, x, y, rng.random::<bool>()));
                }
            }
        }
        events
    }

    /// A leak of `rate_hz`: every pixel fires an ON event once per period, at a random
    /// phase.
    fn leak(rate_hz: f64) -> Events {
        let mut rng = rng(22);
        let mut events = Vec::new();
        for y in 0..12u16 {
            for x in 0..16u16 {
                let mut t = rng.random::<f64>() / rate_hz;
                while t < 10.0 {
                    events.push(((t * 1e6) as TimeUs, x, y, true));
                    t += 1.0 / rate_hz;
                }
            }
        }
        events
    }

    /// Isolated events of both polarities at `rate_hz` (ON and OFF together) per pixel.
    fn balanced_noise(rate_hz: f64) -> Events {
        let mut rng = rng(23);
        let mut events = Vec::new();
        for y in 0..12u16 {
            for x in 0..16u16 {
                for t in poisson_times(&mut rng, rate_hz, 0.0, 10.0) {
                    events.push((t, x, y, rng.random::<bool>()));
                }
            }
        }
        events
    }

    fn with(mut base: Events, extra: Events) -> Events {
        base.extend(extra);
        base
    }

    #[test]
    fn isolated_on_events_at_a_fifth_of_a_hertz_call_for_leak_starting_near_that_rate() {
        let model = chunk(noise_floor());
        let recording = chunk(with(noise_floor(), leak(0.2)));
        let f = Fixture::new(&static_frames(16, 12, 10.0, 100.0), &recording, &model);
        let e = evidence(&f.context());
        // 384 leak events against a floor of about 96 events in each set
        assert!(e.calls_for(), "{e:?}");
        assert!(e.score > EVIDENCE_THRESHOLD, "{e:?}");
        let start = e.start.unwrap();
        assert!(start > 0.2 / 2.0 && start < 0.2 * 2.0, "{start}");
    }

    #[test]
    fn the_model_as_the_recording_does_not_call_for_leak() {
        let recording = chunk(with(noise_floor(), leak(0.2)));
        let f = Fixture::new(&static_frames(16, 12, 10.0, 100.0), &recording, &recording);
        let e = evidence(&f.context());
        assert!(!e.calls_for(), "{e:?}");
        assert_eq!(e.score, 0.0);
    }

    #[test]
    fn an_excess_of_both_polarities_is_shot_noise_and_does_not_call_for_leak() {
        let model = chunk(noise_floor());
        let recording = chunk(with(noise_floor(), balanced_noise(0.4)));
        let f = Fixture::new(&static_frames(16, 12, 10.0, 100.0), &recording, &model);
        let e = evidence(&f.context());
        // about 384 ON and 384 OFF events more: the ON excess is the OFF excess
        assert!(!e.calls_for(), "{e:?}");
        assert!(e.score.abs() < 3.0, "{e:?}");
    }
}
