//! A display in the light path: an on-screen stimulus reaches the camera at the monitor's
//! refresh rate through its gamma and black level ([`crate::sim::display`]).
//!
//! Signature: a spectral line at the refresh rate in the event-rate spectrum that the model
//! lacks. Evidence: the strongest line between 20 and 500 Hz in the recording's spectrum
//! (power over the spectrum's median), against the model's at that frequency. A display's
//! parameters are fitted from the stimulus that was played (`ctcal estimate screen`); the
//! fit names the line and the frequency. Not assessed on timestamps quantised to a coarse
//! grid, whose own lines fill the spectrum.

use super::{Context, Effect, Evidence};
use crate::fit::residuals::power_spectrum;

/// The frequency and normalised power of the recording's strongest line, and the model's
/// power there, over the context's blocks.
pub fn line(c: &Context) -> Option<(f64, f64, f64)> {
    let (f, real) = power_spectrum(c.real.timeline_of(c.geometry, c.subset));
    let (_, sim) = power_spectrum(c.sim.timeline_of(c.geometry, c.subset));
    let (k, &power) = real
        .iter()
        .enumerate()
        .filter(|&(i, _)| (20.0..=500.0).contains(&f[i]))
        .max_by(|a, b| a.1.total_cmp(b.1))?;
    Some((f[k], power, sim.get(k).copied().unwrap_or(0.0)))
}

/// Timestamp grids at least this coarse (us) fill the event-rate spectrum with their own
/// lines (a simulator's frames stamp events at fixed fractions of each interval: v2e), so a
/// display cannot be told from them.
const GRID_HIDES_DISPLAY_US: i64 = 100;

pub fn evidence(c: &Context) -> Evidence {
    if let Some(grid) = c.timestamp_grid_us.filter(|&g| g >= GRID_HIDES_DISPLAY_US) {
        return Evidence::none(
            Effect::Display,
            format!(
                "the timestamps lie on a {grid} us grid (a simulator's frames): the event-rate spectrum shows the grid's lines, not a display's"
            ),
        );
    }
    match line(c) {
        Some((frequency, power, simulated)) => Evidence {
            effect: Effect::Display,
            score: power / simulated.max(1.0),
            relevant: power > 50.0 && power > 10.0 * simulated,
            text: format!(
                "the event rate has a spectral line at {frequency:.1} Hz ({power:.0} times the median power; the model: {simulated:.1})"
            ),
            other_start: None,
            start: Some(frequency),
        },
        None => Evidence::none(Effect::Display, "too short a recording for a spectrum"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::events::EventChunk;
    use crate::fit::effects::EVIDENCE_THRESHOLD;
    use crate::fit::effects::fixture::{Fixture, chunk, poisson_times, rng, static_frames};
    use rand::RngExt;

    /// A 16 x 12 scene for 4 s. The model: every pixel fires at 100 Hz, steadily (Poisson).
    /// The recording: the same arrivals with the rate modulated by half at `refresh_hz`
    /// (`100 (1 + 0.5 sin(2 pi f t))`, by thinning arrivals at 150 Hz), a display's refresh;
    /// `seed` draws the arrivals.
    fn model_and_flickering(refresh_hz: f64, seed: u64) -> (EventChunk, EventChunk) {
        let mut rng = rng(seed);
        let (mut model, mut recording) = (Vec::new(), Vec::new());
        for y in 0..12u16 {
            for x in 0..16u16 {
                for t in poisson_times(&mut rng, 150.0, 0.0, 4.0) {
                    let u = 150.0 * rng.random::<f64>();
                    let s = t as f64 * 1e-6;
                    let flicker =
                        100.0 * (1.0 + 0.5 * (std::f64::consts::TAU * refresh_hz * s).sin());
                    let on = rng.random::<bool>();
                    if u < 100.0 {
                        model.push((t, x, y, on));
                    }
                    if u < flicker {
                        recording.push((t, x, y, on));
                    }
                }
            }
        }
        (chunk(model), chunk(recording))
    }

    #[test]
    fn a_sixty_hz_rate_line_calls_for_a_display_at_sixty_hz() {
        let (model, recording) = model_and_flickering(60.0, 61);
        let f = Fixture::new(&static_frames(16, 12, 4.0, 100.0), &recording, &model);
        let e = evidence(&f.context());
        assert!(e.calls_for(), "{e:?}");
        assert!(e.score > EVIDENCE_THRESHOLD, "{e:?}");
        // the spectrum's frequencies are 1.25 Hz apart (4 s in 1 ms bins, grouped by 5)
        let start = e.start.unwrap();
        assert!((start - 60.0).abs() < 1.5, "{start}");
    }

    #[test]
    fn a_line_at_144_hz_is_found_at_144_hz() {
        let (model, recording) = model_and_flickering(144.0, 61);
        let f = Fixture::new(&static_frames(16, 12, 4.0, 100.0), &recording, &model);
        let e = evidence(&f.context());
        assert!(e.calls_for(), "{e:?}");
        let start = e.start.unwrap();
        assert!((start - 144.0).abs() < 1.5, "{start}");
    }

    #[test]
    fn the_model_as_the_recording_does_not_call_for_a_display() {
        let (_, recording) = model_and_flickering(60.0, 61);
        let f = Fixture::new(&static_frames(16, 12, 4.0, 100.0), &recording, &recording);
        let e = evidence(&f.context());
        assert!(!e.calls_for(), "{e:?}");
    }

    #[test]
    fn a_steady_recording_against_a_steady_model_does_not_call_for_a_display() {
        // two independent steady realisations: no line in either
        let (model, _) = model_and_flickering(0.0, 61);
        let (_, other) = model_and_flickering(0.0, 62);
        let f = Fixture::new(&static_frames(16, 12, 4.0, 100.0), &other, &model);
        let e = evidence(&f.context());
        assert!(!e.calls_for(), "{e:?}");
    }

    #[test]
    fn stamps_on_a_millisecond_grid_do_not_call_for_a_display() {
        let (model, recording) = model_and_flickering(60.0, 61);
        let f = Fixture::new(&static_frames(16, 12, 4.0, 100.0), &recording, &model);
        let context = Context {
            timestamp_grid_us: Some(1000),
            ..f.context()
        };
        let e = evidence(&context);
        assert!(!e.calls_for(), "{e:?}");
        assert_eq!(e.score, 0.0);
    }
}
