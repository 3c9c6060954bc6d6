//! The refractory period from events alone: after an event a pixel cannot fire for a
//! while (Lichtsteiner et al. 2008; v2e's `refractory_period_s`), so its same-pixel
//! intervals have a lower edge whatever the brightness. Without a refractory period the
//! density of short intervals is smooth down to zero: as many intervals fall in `[0, e)` as
//! in `[e, 2e)` (flat) or more (falling). The edge is the longest `e` below which the
//! recording holds under a tenth of what `[e, 2e)` holds, with at least
//! [`MIN_PLATEAU`] intervals above it: sharpness that a smooth density, and a photoreceptor
//! bandwidth limit (which thins short intervals gradually, more in the dark), do not have.
//!
//! Other things leave a gap too: timestamps on a grid (no interval under one step), a
//! leak that fires periodically, a slow scene whose brightness cannot change by a threshold
//! faster than some time. What tells a refractory period apart is the pile-up: a change
//! that comes during it fires when it ends (the pixel's reset releases; v2e keeps the change
//! pending), so the events that would have come sooner pile up just above the edge, where
//! the others' density rises or stays flat. The edge counts as a refractory period only with
//! that pile-up ([`PILE_UP`]) and above twice the timestamp step.

/// Intervals `[e, 2e)` needs to show an edge.
pub const MIN_PLATEAU: usize = 30;
/// At most this share of `[e, 2e)`'s count below `e` makes a gap.
pub const GAP_RATIO: f64 = 0.1;
/// The density just above the edge (its first quarter) must be this many times the
/// density over the rest of `[edge, 2 edge)`.
pub const PILE_UP: f64 = 2.0;
/// Candidate edges per decade (from 1 µs to 1 s).
const PER_DECADE: usize = 40;

/// The lower edge of the same-pixel intervals.
#[derive(Clone, Debug, PartialEq)]
pub struct Edge {
    /// The edge, µs, and the range where the short intervals come back: from the longest
    /// candidate with almost none (a fiftieth) below it to the first with a third.
    pub edge_us: f64,
    pub range_us: [f64; 2],
    /// Intervals below the edge and in `[edge, 2 edge)`.
    pub below: usize,
    pub above: usize,
    /// Whether the gap is there with its pile-up (else `edge_us` bounds any refractory
    /// period from above).
    pub found: bool,
    /// Why a gap is not taken for a refractory period.
    pub not_refractory: Option<String>,
    pub intervals: usize,
}

/// Same-pixel intervals (µs) of the events `range` (of the pixels `kept`, where given);
/// `last` carries each pixel's previous event across blocks.
pub fn intervals(
    clean: &crate::events::EventChunk,
    range: std::ops::Range<usize>,
    width: usize,
    last: &mut [crate::events::TimeUs],
    kept: Option<&[bool]>,
) -> Vec<u32> {
    let mut out = Vec::new();
    for i in range {
        let p = clean.y[i] as usize * width + clean.x[i] as usize;
        if kept.is_some_and(|k| !k.get(p).copied().unwrap_or(false)) {
            continue;
        }
        if last[p] != crate::events::TimeUs::MIN {
            out.push((clean.t[i] - last[p]).clamp(0, u32::MAX as crate::events::TimeUs) as u32);
        }
        last[p] = clean.t[i];
    }
    out
}

/// The common step of the timestamps (µs; 1 when they are not on a coarser grid): the
/// greatest common divisor of the first 100,000 differences between distinct timestamps.
pub fn timestamp_step(events: &crate::events::EventChunk) -> u32 {
    fn gcd(a: u64, b: u64) -> u64 {
        if b == 0 { a } else { gcd(b, a % b) }
    }
    let mut step = 0u64;
    for d in events
        .t
        .windows(2)
        .map(|w| (w[1] - w[0]) as u64)
        .filter(|&d| d > 0)
        .take(100_000)
    {
        step = gcd(step, d);
        if step == 1 {
            break;
        }
    }
    step.clamp(1, u32::MAX as u64) as u32
}

impl Edge {
    /// The gap in Poisson standard errors: how far below `[e, 2e)`'s count the count under
    /// `e` is.
    pub fn score(&self) -> f64 {
        (self.above as f64 - self.below as f64) / ((self.above + self.below) as f64).sqrt().max(1.0)
    }
}

/// Finds the edge of `intervals` (µs; sorted here) of timestamps on a `step_us` grid,
/// `None` with under [`MIN_PLATEAU`].
pub fn edge(intervals: &mut [u32], step_us: u32) -> Option<Edge> {
    if intervals.len() < MIN_PLATEAU {
        return None;
    }
    intervals.sort_unstable();
    let sorted = Sorted(intervals);
    let candidates: Vec<f64> = (0..=6 * PER_DECADE)
        .map(|k| 10f64.powf(k as f64 / PER_DECADE as f64))
        .collect();
    let Some(&found) = candidates.iter().rev().find(|&&e| sorted.gap(e)) else {
        return Some(sorted.no_gap());
    };
    // the edge itself: the lower end (2nd percentile) of the intervals around the gap
    let near = &intervals[sorted.below(found / 2.0)..sorted.below(2.0 * found)];
    let edge_us = near[(near.len() as f64 * 0.02) as usize].max(1) as f64;
    let not_refractory = sorted.not_refractory(edge_us, step_us);
    let [low, high] = sorted.range(&candidates, found);
    let (under, above) = sorted.ratio_at(edge_us);
    Some(Edge {
        edge_us,
        range_us: [low.min(edge_us), high.max(edge_us)],
        below: under,
        above,
        found: not_refractory.is_none(),
        not_refractory,
        intervals: intervals.len(),
    })
}

/// Same-pixel intervals (µs), sorted: counted below an edge and in the octave above it.
struct Sorted<'a>(&'a [u32]);

impl Sorted<'_> {
    /// The intervals under `e`.
    fn below(&self, e: f64) -> usize {
        self.0.partition_point(|&v| (v as f64) < e)
    }

    /// The intervals under `e` and in `[e, 2e)`.
    fn ratio_at(&self, e: f64) -> (usize, usize) {
        let (under, upto) = (self.below(e), self.below(2.0 * e));
        (under, upto - under)
    }

    /// Whether `e` has a gap below it: [`MIN_PLATEAU`] intervals in `[e, 2e)` and at most
    /// [`GAP_RATIO`] of them under `e`.
    fn gap(&self, e: f64) -> bool {
        let (under, above) = self.ratio_at(e);
        above >= MIN_PLATEAU && (under as f64) <= GAP_RATIO * above as f64
    }

    /// The intervals under `e` over those in `[e, 2e)`.
    fn share(&self, e: f64) -> f64 {
        let (under, above) = self.ratio_at(e);
        under as f64 / above.max(1) as f64
    }

    /// Intervals per µs in `[from, to)`.
    fn density(&self, from: f64, to: f64) -> f64 {
        (self.below(to) - self.below(from)) as f64 / (to - from)
    }

    /// No gap at any candidate: the edge at the shortest interval, not found.
    fn no_gap(&self) -> Edge {
        let shortest = self.0[0].max(1) as f64;
        let (under, above) = self.ratio_at(shortest);
        Edge {
            edge_us: shortest,
            range_us: [0.0, shortest],
            below: under,
            above,
            found: false,
            not_refractory: None,
            intervals: self.0.len(),
        }
    }

    /// Why the gap ending at `edge_us` is not a refractory period: within two timestamp
    /// steps of `step_us`, or without the pile-up above it ([`PILE_UP`]).
    fn not_refractory(&self, edge_us: f64, step_us: u32) -> Option<String> {
        let pile = self.density(edge_us, 1.25 * edge_us);
        let rest = self.density(1.25 * edge_us, 2.0 * edge_us);
        if edge_us <= 2.0 * step_us as f64 {
            Some(format!(
                "the gap ends at {edge_us:.0} us, within two steps of the timestamps' {step_us} us grid"
            ))
        } else if pile < PILE_UP * rest {
            Some(format!(
                "no pile-up above the gap at {edge_us:.0} us (density {:.2} of the next three quarters'): periodic firing or a slow scene, not events held back",
                pile / rest.max(1e-12)
            ))
        } else {
            None
        }
    }

    /// Where the short intervals come back around the gap at `found`: the longest of the
    /// `candidates` up to it with almost none (a fiftieth) below, the first beyond it with
    /// a third (each `found` where there is none).
    fn range(&self, candidates: &[f64], found: f64) -> [f64; 2] {
        let low = candidates
            .iter()
            .rev()
            .find(|&&e| e <= found && self.share(e) <= GAP_RATIO / 5.0)
            .copied()
            .unwrap_or(found);
        let high = candidates
            .iter()
            .find(|&&e| e > found && self.share(e) >= 1.0 / 3.0)
            .copied()
            .unwrap_or(found);
        [low, high]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    fn exponential(rate_hz: f64, n: usize, dead_us: f64, seed: u64) -> Vec<u32> {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
        (0..n)
            .map(|_| (dead_us - (1.0 - rng.random::<f64>()).ln() / rate_hz * 1e6) as u32)
            .collect()
    }

    /// A pixel driven at 2 kHz (Poisson) with a 1 ms refractory period that holds events
    /// back until it ends: intervals max(1 ms, exponential).
    fn held_back(rate_hz: f64, n: usize, refractory_us: f64, seed: u64) -> Vec<u32> {
        exponential(rate_hz, n, 0.0, seed)
            .into_iter()
            .map(|v| (v as f64).max(refractory_us) as u32 + 1)
            .collect()
    }

    #[test]
    fn a_refractory_period_that_holds_events_back_is_found() {
        let mut v = held_back(2000.0, 20_000, 1000.0, 1);
        let e = edge(&mut v, 1).unwrap();
        assert!(e.found, "{e:?}");
        assert!((e.edge_us / 1000.0 - 1.0).abs() < 0.02, "{e:?}");
        assert!(e.range_us[0] <= 1000.0 && e.range_us[1] >= 1000.0, "{e:?}");
        assert!(e.score() > 20.0);
    }

    #[test]
    fn no_dead_time_no_edge() {
        let mut v = exponential(200.0, 20_000, 0.0, 2);
        let e = edge(&mut v, 1).unwrap();
        assert!(!e.found, "{e:?}");
        assert!(e.edge_us <= 5.0, "{e:?}");
    }

    #[test]
    fn a_dead_time_without_pile_up_or_a_timestamp_grid_is_not_a_refractory_period() {
        // Poisson at 200 Hz shifted by 1 ms: a gap, but events were not held back
        let mut v = exponential(200.0, 20_000, 1000.0, 3);
        let e = edge(&mut v, 1).unwrap();
        assert!(!e.found && e.not_refractory.is_some(), "{e:?}");
        // refractory-like pile-up on a 1 ms grid: one step
        let mut grid: Vec<u32> = held_back(2000.0, 20_000, 1000.0, 4)
            .into_iter()
            .map(|v| v.div_ceil(1000) * 1000)
            .collect();
        let e = edge(&mut grid, 1000).unwrap();
        assert!(!e.found, "{e:?}");
        assert!(e.not_refractory.unwrap().contains("grid"));
    }

    #[test]
    fn timestamp_steps_are_found() {
        let mut e = crate::events::EventChunk::default();
        for t in [4000, 8000, 8000, 16000, 40000] {
            e.push(t, 0, 0, true);
        }
        assert_eq!(timestamp_step(&e), 4000);
        e.push(40001, 0, 0, true);
        assert_eq!(timestamp_step(&e), 1);
    }

    #[test]
    fn too_few_intervals_say_nothing() {
        assert_eq!(edge(&mut [5, 7, 9], 1), None);
    }
}
