//! Refractory period: after an event the pixel is blind while its reset switch is held;
//! a change inside that time fires when it ends (v2e's semantics,
//! [`crate::sim::effects::refractory`]) or is dropped (IEBCS, DVS-Voltmeter).
//!
//! Signature: a gap in the shortest same-pixel intervals (and a count deficit at high
//! local rates): the recording has far fewer intervals below some time than a model
//! without it, whatever the brightness. Evidence: the largest interval bin below which the
//! recording holds less than a quarter of the model's share, with the model's share above
//! 2 %; the difference of the shares in binomial standard errors. Start: the recording's
//! shortest same-pixel intervals ([`shortest_interval_s`]: no interval is shorter than the
//! period, and v2e's pile-up puts many exactly at it), else that bin's upper edge.

use super::{Context, Effect, Evidence};
use crate::events::{EventChunk, TimeUs};
use crate::fit::metric::normalised;
use crate::fit::observe::{INTERVAL_BINS, interval_bin_start};

/// The recording's shortest same-pixel intervals, seconds: the lower edge of the intervals
/// between consecutive events of each `kept` pixel of time-sorted `events` on a
/// `step_us` timestamp grid, found as the events-only fit finds it
/// ([`crate::fit::events_only::refractory::edge`]: the longest gap with a plateau above it,
/// its edge the 2nd percentile of the intervals around it; without a gap, the shortest
/// interval). `None` with too few intervals. A refractory period leaves no interval below
/// it (v2e piles the held-back events up at it: Hu, Liu & Delbruck, "v2e", CVPRW 2021); a
/// timestamp jitter of standard deviation s moves the edge about 2 s below the period.
pub fn shortest_interval_s(
    events: &EventChunk,
    width: usize,
    kept: &[bool],
    step_us: u32,
) -> Option<f64> {
    let mut last = vec![TimeUs::MIN; kept.len()];
    let mut intervals = crate::fit::events_only::refractory::intervals(
        events,
        0..events.len(),
        width,
        &mut last,
        Some(kept),
    );
    crate::fit::events_only::refractory::edge(&mut intervals, step_us).map(|e| e.edge_us * 1e-6)
}

pub fn evidence(c: &Context) -> Evidence {
    let real_counts = c.real.intervals_of(c.geometry, c.subset);
    let n: f64 = real_counts.iter().map(|&v| v as f64).sum();
    let (real, sim) = (
        normalised(&real_counts),
        normalised(&c.sim.intervals_of(c.geometry, c.subset)),
    );
    let (mut real_cdf, mut sim_cdf) = (0.0, 0.0);
    let mut found = None;
    for k in 0..INTERVAL_BINS - 1 {
        real_cdf += real[k];
        sim_cdf += sim[k];
        if sim_cdf >= 0.02 && real_cdf < 0.25 * sim_cdf {
            found = Some((k, real_cdf, sim_cdf));
        } else if found.is_some() {
            break;
        }
    }
    let Some((k, real_share, sim_share)) = found else {
        return Evidence::none(
            Effect::Refractory,
            "the shortest same-pixel intervals are as common as the model makes them",
        );
    };
    let edge = interval_bin_start(k + 1);
    let se = (sim_share * (1.0 - sim_share) / n.max(1.0))
        .sqrt()
        .max(1e-9);
    Evidence {
        effect: Effect::Refractory,
        score: (sim_share - real_share) / se,
        relevant: sim_share - real_share > 0.02,
        text: format!(
            "{:.1} % of the recording's same-pixel intervals are shorter than {:.3} ms against {:.1} % in the model",
            100.0 * real_share,
            edge * 1e3,
            100.0 * sim_share
        ),
        start: Some(c.shortest_interval_s.unwrap_or(edge)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::effects::EVIDENCE_THRESHOLD;
    use crate::fit::effects::fixture::{Fixture, chunk, poisson_times, rng, static_frames};

    /// Every pixel of a 16 x 12 static scene fires at 200 Hz for 1 s (the model); the
    /// recording is the same changes through a refractory period of `period_s`: a change
    /// inside it fires when it ends (the pile-up).
    fn model_and_refractory(period_s: f64) -> (EventChunk, EventChunk) {
        let mut rng = rng(11);
        let (mut model, mut recording) = (Vec::new(), Vec::new());
        let period = (period_s * 1e6) as TimeUs;
        for y in 0..12u16 {
            for x in 0..16u16 {
                let mut free = TimeUs::MIN;
                for (i, t) in poisson_times(&mut rng, 200.0, 0.0, 1.0)
                    .into_iter()
                    .enumerate()
                {
                    let on = i % 2 == 0;
                    model.push((t, x, y, on));
                    let fired = t.max(free);
                    recording.push((fired, x, y, on));
                    free = fired + period;
                }
            }
        }
        (chunk(model), chunk(recording))
    }

    #[test]
    fn a_two_ms_gap_with_a_pile_up_calls_for_refractory_and_starts_near_two_ms() {
        let (model, recording) = model_and_refractory(2e-3);
        let f = Fixture::new(&static_frames(16, 12, 1.0, 100.0), &recording, &model);
        let e = evidence(&f.context());
        assert!(e.calls_for(), "{e:?}");
        assert!(e.score > EVIDENCE_THRESHOLD, "{e:?}");
        let start = e.start.unwrap();
        // the lower edge of the interval bin holding 2 ms (1.78 ms)
        assert!(start > 2e-3 / 1.5 && start < 2e-3 * 1.5, "{start}");
    }

    #[test]
    fn a_half_ms_refractory_period_starts_near_half_a_ms() {
        let (model, recording) = model_and_refractory(0.5e-3);
        let f = Fixture::new(&static_frames(16, 12, 1.0, 100.0), &recording, &model);
        let e = evidence(&f.context());
        assert!(e.calls_for(), "{e:?}");
        let start = e.start.unwrap();
        assert!(start > 0.5e-3 / 1.5 && start < 0.5e-3 * 1.5, "{start}");
    }

    #[test]
    fn a_model_with_the_recordings_intervals_does_not_call_for_refractory() {
        let (_, recording) = model_and_refractory(2e-3);
        let f = Fixture::new(&static_frames(16, 12, 1.0, 100.0), &recording, &recording);
        let e = evidence(&f.context());
        assert!(!e.calls_for(), "{e:?}");
        assert_eq!(e.score, 0.0);
        assert_eq!(e.start, None);
    }

    #[test]
    fn the_shortest_intervals_read_the_period_and_leave_out_pixels_not_compared() {
        let (model, recording) = model_and_refractory(2e-3);
        let kept = vec![true; 16 * 12];
        // every interval of the recording is at least 2 ms, and piled up at 2 ms
        let q = shortest_interval_s(&recording, 16, &kept, 1).unwrap();
        assert!((q - 2e-3).abs() < 1e-6, "{q}");
        // the model (Poisson at 200 Hz) has no gap: its shortest interval, a few us
        let q = shortest_interval_s(&model, 16, &kept, 1).unwrap();
        assert!(q < 20e-6, "{q}");
        // one pixel kept: about 200 intervals, still enough; none kept: none
        let mut one = vec![false; 16 * 12];
        one[5] = true;
        assert!(shortest_interval_s(&recording, 16, &one, 1).is_some_and(|q| q >= 2e-3));
        assert_eq!(
            shortest_interval_s(&recording, 16, &[false; 16 * 12], 1),
            None
        );
    }

    #[test]
    fn the_evidence_starts_at_the_measured_shortest_intervals() {
        let (model, recording) = model_and_refractory(2e-3);
        let f = Fixture::new(&static_frames(16, 12, 1.0, 100.0), &recording, &model);
        let context = Context {
            shortest_interval_s: Some(2.1e-3),
            ..f.context()
        };
        assert_eq!(evidence(&context).start, Some(2.1e-3));
    }
}
