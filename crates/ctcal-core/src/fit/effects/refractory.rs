//! Refractory period: after an event the pixel is blind while its reset switch is held;
//! a change inside that time fires when it ends (v2e's semantics,
//! [`crate::sim::effects::refractory`]) or is dropped (IEBCS, DVS-Voltmeter).
//!
//! Signature: a gap in the shortest same-pixel intervals (and a count deficit at high
//! local rates): the recording has far fewer intervals below some time than a model
//! without it, whatever the brightness. Evidence: the largest interval bin below which the
//! recording holds less than a quarter of the model's share, with the model's share above
//! 2 %; the difference of the shares in binomial standard errors. A gap that moves with
//! the pixels' brightness is the photoreceptor's bandwidth, not a period
//! ([`moves_with_brightness`]). Start: the recording's
//! shortest same-pixel intervals ([`shortest_interval_s`]: no interval is shorter than the
//! period, and v2e's pile-up puts many exactly at it), else that bin's upper edge.

use super::{Context, Effect, Evidence};
use crate::events::{EventChunk, TimeUs};
use crate::fit::metric::normalised;
use crate::fit::observe::{
    INTENSITY_BINS, INTERVAL_BINS, INTERVAL_BINS_PER_DECADE, interval_bin_start,
};

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
    interval_edge(events, width, kept, step_us).map(|e| e.edge_us * 1e-6)
}

/// The lower edge of the same-pixel intervals of `events` at the pixels `kept`
/// ([`crate::fit::events_only::refractory::edge`]).
pub fn interval_edge(
    events: &EventChunk,
    width: usize,
    kept: &[bool],
    step_us: u32,
) -> Option<crate::fit::events_only::refractory::Edge> {
    let mut last = vec![TimeUs::MIN; kept.len()];
    let mut intervals = crate::fit::events_only::refractory::intervals(
        events,
        0..events.len(),
        width,
        &mut last,
        Some(kept),
    );
    crate::fit::events_only::refractory::edge(&mut intervals, step_us)
}

pub fn evidence(c: &Context) -> Evidence {
    let real_counts = c.real.intervals_of(c.geometry, c.subset);
    let n: f64 = real_counts.iter().map(|&v| v as f64).sum();
    let sim_counts = c.sim.intervals_of(c.geometry, c.subset);
    let Some(found) = Gap::of(&real_counts, &sim_counts) else {
        return Evidence::none(
            Effect::Refractory,
            "the shortest same-pixel intervals are as common as the model makes them",
        );
    };
    let edge = interval_bin_start(found.bin + 1);
    let se = (found.sim_share * (1.0 - found.sim_share) / n.max(1.0))
        .sqrt()
        .max(1e-9);
    let text = format!(
        "{:.1} % of the recording's same-pixel intervals are shorter than {:.3} ms against {:.1} % in the model",
        100.0 * found.real_share,
        edge * 1e3,
        100.0 * found.sim_share
    );
    if let Some(moves) = moves_with_brightness(c) {
        return Evidence::none(Effect::Refractory, format!("{text}; {moves}"));
    }
    Evidence {
        effect: Effect::Refractory,
        score: (found.sim_share - found.real_share) / se,
        relevant: found.sim_share - found.real_share > 0.02,
        text,
        other_start: None,
        start: Some(c.shortest_interval_s.unwrap_or(edge)),
    }
}

/// A gap in the shortest same-pixel intervals: the largest interval bin below which the
/// recording holds less than a quarter of the model's share, with the model's share above
/// 2 % (the bins below it gapped too).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Gap {
    bin: usize,
    real_share: f64,
    sim_share: f64,
}

impl Gap {
    fn of(real: &[u32], sim: &[u32]) -> Option<Gap> {
        let (real, sim) = (normalised(real), normalised(sim));
        let (mut real_cdf, mut sim_cdf) = (0.0, 0.0);
        let mut found = None;
        for k in 0..INTERVAL_BINS - 1 {
            real_cdf += real[k];
            sim_cdf += sim[k];
            if sim_cdf >= 0.02 && real_cdf < 0.25 * sim_cdf {
                found = Some(Gap {
                    bin: k,
                    real_share: real_cdf,
                    sim_share: sim_cdf,
                });
            } else if found.is_some() {
                break;
            }
        }
        found
    }
}

/// Intervals an intensity bin needs in the recording and in the model for its own gap to
/// be read.
const MIN_CLASS_INTERVALS: u32 = 300;

/// Interval bins between the gaps of a dimmer and a brighter intensity bin from which the
/// gap moves with brightness (a factor 1.8, where a refractory period leaves one edge and
/// the bins' quantisation at most one bin between them).
const MOVED_BINS: usize = 2;

/// Intervals a brighter intensity bin must hold below the gap's edge (where the model puts
/// them too) to show that the gap is not there.
const MIN_UNGAPPED_INTERVALS: u32 = 10;

/// Why the gap is not a refractory period's, where the intensity bins tell: a refractory
/// period blinds the pixel for one time at every brightness, while the photoreceptor's
/// low-pass, whose cutoff is proportional to the photocurrent (Lichtsteiner, Posch &
/// Delbruck, JSSC 2008), thins short intervals out to a time that grows as the light falls
/// (coverage draw 6006, a 25 DN texture with a 20 Hz cutoff at white and no refractory
/// period, was given a 20 ms period beside the bandwidth: its pixels under 20 DN had 0.6 %
/// of their intervals below 32 ms where the model had 3.5 %, those at 40-80 DN 2.4 % for
/// the model's 3.2 %). Of the intensity bins with enough intervals, the gap moves when
/// - a brighter bin's gap ends at least [`MOVED_BINS`] bins before a dimmer one's, their
///   intensities far enough apart for a cutoff proportional to `DN + 20` to move it so far;
/// - or a bin brighter than every gapped one keeps the short intervals the model gives it:
///   at least half the model's share (2 % or more) below the brightest gap's edge.
///
/// `None`: the gap is alike at every brightness, or the bins cannot tell. Where a period
/// and a slow photoreceptor are both there, the period is called for once the bandwidth
/// is in the model and the gap left is alike at every brightness.
fn moves_with_brightness(c: &Context) -> Option<String> {
    let real = c.real.intervals_by_intensity_of(c.geometry, c.subset);
    let sim = c.sim.intervals_by_intensity_of(c.geometry, c.subset);
    let readable: Vec<usize> = (0..INTENSITY_BINS)
        .filter(|&i| {
            real[i].iter().sum::<u32>() >= MIN_CLASS_INTERVALS
                && sim[i].iter().sum::<u32>() >= MIN_CLASS_INTERVALS
        })
        .collect();
    let gaps: Vec<(usize, Gap)> = readable
        .iter()
        .filter_map(|&i| Gap::of(&real[i], &sim[i]).map(|g| (i, g)))
        .collect();
    let &(bright, bright_gap) = gaps.last()?;
    let dn = |i: usize| c.geometry.intensity_centres[i];
    let edge_ms = |g: &Gap| interval_bin_start(g.bin + 1) * 1e3;
    let bins_apart = |dim: usize, bright: usize| {
        ((dn(bright) + 20.0) / (dn(dim) + 20.0)).log10() * INTERVAL_BINS_PER_DECADE as f64
    };
    const BANDWIDTH: &str = "as a photoreceptor's bandwidth thins short intervals in the dark (a refractory period leaves one gap at every brightness)";
    if let Some(&(dim, dim_gap)) = gaps.iter().find(|(i, g)| {
        bins_apart(*i, bright) >= MOVED_BINS as f64 && g.bin >= bright_gap.bin + MOVED_BINS
    }) {
        return Some(format!(
            "but the gap moves with brightness: below {:.3} ms at about {:.0} DN, below {:.3} ms at about {:.0} DN, {BANDWIDTH}",
            edge_ms(&dim_gap),
            dn(dim),
            edge_ms(&bright_gap),
            dn(bright)
        ));
    }
    let below = |h: &[u32]| h[..=bright_gap.bin].iter().sum::<u32>();
    let share = |h: &[u32]| below(h) as f64 / h.iter().sum::<u32>().max(1) as f64;
    let ungapped = readable
        .iter()
        .copied()
        .filter(|&i| i > bright)
        .find(|&i| {
            share(&sim[i]) >= 0.02
                && share(&real[i]) >= 0.5 * share(&sim[i])
                && below(&real[i]) >= MIN_UNGAPPED_INTERVALS
        })?;
    Some(format!(
        "but only in dim pixels: at about {:.0} DN {:.1} % of the intervals are below {:.3} ms against the model's {:.1} %, {BANDWIDTH}",
        dn(ungapped),
        100.0 * share(&real[ungapped]),
        edge_ms(&bright_gap),
        100.0 * share(&sim[ungapped])
    ))
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
        model_and_dead_time(|_| period_s)
    }

    /// [`model_and_refractory`] with a dead time of `period_s(x)` seconds in column `x`.
    fn model_and_dead_time(period_s: impl Fn(u16) -> f64) -> (EventChunk, EventChunk) {
        let mut rng = rng(11);
        let (mut model, mut recording) = (Vec::new(), Vec::new());
        for y in 0..12u16 {
            for x in 0..16u16 {
                let period = (period_s(x) * 1e6) as TimeUs;
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

    /// The scene's first `dim_columns` of 16 at 15 DN, the others at 200 DN.
    fn dim_and_bright(dim_columns: usize) -> crate::estimate::frames::PreparedFrames {
        let times = crate::fit::effects::fixture::frame_times(1.0, 0.1);
        let dn = move |x: usize, _: usize, _: usize| if x < dim_columns { 15.0 } else { 200.0 };
        crate::fit::effects::fixture::frames(16, 12, &times, dn)
    }

    /// Short intervals thinned out to 8 ms in the dim half and to 8 ms x 35 / 220 (1.3 ms)
    /// in the bright half, as a cutoff proportional to `DN + 20` would: not a period.
    #[test]
    fn a_gap_that_moves_with_brightness_does_not_call_for_refractory() {
        let (model, recording) =
            model_and_dead_time(|x| if x < 8 { 8e-3 } else { 8e-3 * 35.0 / 220.0 });
        let f = Fixture::new(&dim_and_bright(8), &recording, &model);
        let e = evidence(&f.context());
        assert!(!e.calls_for(), "{e:?}");
        assert!(e.text.contains("moves with brightness"), "{e:?}");
        // thinned out in the dark only (14 of the 16 columns dim, so that the gap shows
        // over all pixels): the bright columns as the model has them
        let (model, recording) = model_and_dead_time(|x| if x < 14 { 8e-3 } else { 0.0 });
        let f = Fixture::new(&dim_and_bright(14), &recording, &model);
        let e = evidence(&f.context());
        assert!(!e.calls_for(), "{e:?}");
        assert!(e.text.contains("only in dim pixels"), "{e:?}");
    }

    /// The same 2 ms period at 15 and at 200 DN: a refractory period.
    #[test]
    fn a_gap_alike_at_every_brightness_calls_for_refractory() {
        let (model, recording) = model_and_refractory(2e-3);
        let f = Fixture::new(&dim_and_bright(8), &recording, &model);
        let e = evidence(&f.context());
        assert!(e.calls_for(), "{e:?}");
        assert!(!e.text.contains("brightness"), "{e:?}");
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
