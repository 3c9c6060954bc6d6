//! Counting one event set into its [`Observed`] statistics, on the pool: the time-sorted
//! events are cut into consecutive stretches, each stretch counted on its own (every count
//! is a sum of integers, the same in any order), and the one statistic that reaches across
//! stretches, a pixel's interval from its previous event, completed in order afterwards
//! for each pixel's first event of a stretch. The counts are those of one pass over the
//! events in order (tested against it).

use super::lag::LagKeys;
use super::{
    CELLS, Geometry, INTENSITY_BINS, INTERVAL_BINS, INTERVAL_CLASSES, Observed, REGIONS,
    SUPPORT_US, TIMELINE_BIN_US, cell_index, interval_bin,
};
use crate::estimate::frames::read_block;
use crate::events::{EventChunk, TimeUs};
use crate::stats::support::supported;
use rayon::prelude::*;

/// Fewer events than this are counted in one stretch (cutting them costs more than it
/// saves).
const MIN_STRETCH: usize = 1 << 14;

/// A counted event whose pixel had no earlier event in its stretch: its interval is
/// completed in order afterwards.
struct FirstOfPixel {
    pixel: u32,
    block: u32,
    class: u8,
    t: TimeUs,
}

/// A stretch's counts, and what it leaves to be completed in order: the counted events
/// whose pixel had no earlier event in the stretch, and each pixel's last event time in
/// the stretch.
struct Part {
    observed: Observed,
    first_of_pixel: Vec<FirstOfPixel>,
    last: Vec<TimeUs>,
}

impl Observed {
    /// The statistics of the time-sorted `events`, leaving out the pixels `masked` flags
    /// (hot pixels) besides the geometry's own exclusions.
    pub fn new(events: &EventChunk, geometry: &Geometry, masked: &[bool]) -> Self {
        let support = supported(events, geometry.sensor, SUPPORT_US);
        Self::counted(
            events,
            &support,
            geometry,
            masked,
            rayon::current_num_threads(),
        )
    }

    /// [`Self::new`] of a simulation, with the recording's lag behind it ([`super::lag`]; the
    /// recording's side in `real`). The counts and the lag are made side by side: each has
    /// a part on one thread (the stretches' merge, the grouping of the events).
    pub fn paired(
        events: &EventChunk,
        geometry: &Geometry,
        masked: &[bool],
        real: &LagKeys,
    ) -> Self {
        let support = supported(events, geometry.sensor, SUPPORT_US);
        let threads = rayon::current_num_threads();
        let (mut o, lag) = rayon::join(
            || Self::counted(events, &support, geometry, masked, threads),
            || real.histograms(events, &support, geometry, masked),
        );
        o.lag = lag;
        o
    }

    /// The recording's side of [`Self::paired`]: its supported events, grouped.
    pub fn lag_keys(events: &EventChunk, geometry: &Geometry) -> LagKeys {
        let support = supported(events, geometry.sensor, SUPPORT_US);
        LagKeys::new(events, &support, geometry)
    }

    /// [`Self::new`] in at most `threads` stretches, with the events' `support` flags.
    fn counted(
        events: &EventChunk,
        support: &[bool],
        geometry: &Geometry,
        masked: &[bool],
        threads: usize,
    ) -> Self {
        let mut o = Self::empty(geometry);
        if events.is_empty() {
            return o;
        }
        let parts: Vec<Part> = events
            .time_stretches(threads, MIN_STRETCH)
            .into_par_iter()
            .map(|range| count_stretch(events, support, range, geometry, masked))
            .collect();
        let mut last = vec![TimeUs::MIN; geometry.sensor.pixels()];
        for part in parts {
            o.add(&part.observed);
            for f in &part.first_of_pixel {
                let previous = last[f.pixel as usize];
                o.count_interval(geometry, f.block as usize, f.class as usize, previous, f.t);
            }
            for (l, &t) in last.iter_mut().zip(&part.last) {
                if t != TimeUs::MIN {
                    *l = t;
                }
            }
        }
        o
    }

    /// No events on `g`.
    fn empty(g: &Geometry) -> Self {
        let blocks = g.blocks;
        Self {
            blocks,
            cells: vec![0; blocks * CELLS],
            background: vec![0; blocks * INTENSITY_BINS * 2],
            by_region: vec![0; blocks * REGIONS * 2],
            intervals: vec![0; blocks * INTERVAL_CLASSES * INTERVAL_BINS],
            pixel_counts: vec![0; blocks * g.sensor.pixels()],
            polarity: vec![[0; 2]; blocks],
            still: vec![[0; 2]; blocks],
            timeline: vec![0; ((g.span.1 - g.span.0) / TIMELINE_BIN_US).max(0) as usize + 1],
            lag: Default::default(),
        }
    }

    /// Adds `other`'s counts (of the same geometry).
    fn add(&mut self, other: &Self) {
        let sum = |a: &mut Vec<u32>, b: &Vec<u32>| a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
        sum(&mut self.cells, &other.cells);
        sum(&mut self.background, &other.background);
        sum(&mut self.by_region, &other.by_region);
        sum(&mut self.intervals, &other.intervals);
        sum(&mut self.pixel_counts, &other.pixel_counts);
        sum(&mut self.timeline, &other.timeline);
        for (a, b) in self.polarity.iter_mut().zip(&other.polarity) {
            a[0] += b[0];
            a[1] += b[1];
        }
        for (a, b) in self.still.iter_mut().zip(&other.still) {
            a[0] += b[0];
            a[1] += b[1];
        }
    }

    /// Counts the same-pixel interval `previous -> t` in `block` and intensity `class`,
    /// unless there is no previous event or a span whose events were not read lies between
    /// (unknown).
    fn count_interval(
        &mut self,
        g: &Geometry,
        block: usize,
        class: usize,
        previous: TimeUs,
        t: TimeUs,
    ) {
        if previous != TimeUs::MIN && read_block(&g.unread, previous) == read_block(&g.unread, t) {
            let bin = interval_bin((t - previous) as f64 * 1e-6);
            self.intervals[(block * INTERVAL_CLASSES + class) * INTERVAL_BINS + bin] += 1;
        }
    }

    /// Counts an event at `t` in its timeline bin (none past the span's last).
    fn count_time(&mut self, g: &Geometry, t: TimeUs) {
        let slot = ((t - g.span.0) / TIMELINE_BIN_US) as usize;
        if let Some(bin) = self.timeline.get_mut(slot) {
            *bin += 1;
        }
    }

    /// Counts an event of polarity `pol` at pixel `p` with a reliable intensity, in `block`
    /// and frame interval `k`: as still where the brightness does not change, and by cell
    /// and region where `supported`, else as background.
    fn count_scene(
        &mut self,
        g: &Geometry,
        (block, k): (usize, usize),
        p: usize,
        pol: usize,
        supported: bool,
    ) {
        let intensity = g.intensity[k][p] as usize;
        let change = g.change[k][p] as usize;
        if change == 0 {
            self.still[block][pol] += 1;
        }
        if supported {
            self.cells[block * CELLS + cell_index(intensity, change, pol)] += 1;
            self.by_region[(block * REGIONS + g.region[p] as usize) * 2 + pol] += 1;
        } else {
            self.background[(block * INTENSITY_BINS + intensity) * 2 + pol] += 1;
        }
    }
}

/// Counts the events of `range` as one pass in order would, except the intervals of each
/// pixel's first event in the stretch (left in [`Part::first_of_pixel`]).
fn count_stretch(
    events: &EventChunk,
    support: &[bool],
    range: std::ops::Range<usize>,
    g: &Geometry,
    masked: &[bool],
) -> Part {
    let mut o = Observed::empty(g);
    let pixels = g.sensor.pixels();
    let width = g.sensor.width as usize;
    let mut last = vec![TimeUs::MIN; pixels];
    let mut first_of_pixel = Vec::new();
    let mut k = first_interval(events, &range, g);
    for i in range {
        let t = events.t[i];
        let p = events.y[i] as usize * width + events.x[i] as usize;
        let previous = std::mem::replace(&mut last[p], t);
        // the frame interval of t (events arrive sorted)
        while k + 1 < g.times.len() && g.times[k + 1] <= t {
            k += 1;
        }
        let Some(block) = counted_block(g, k, t, p, masked) else {
            continue;
        };
        let pol = events.on[i] as usize;
        o.pixel_counts[block * pixels + p] += 1;
        o.polarity[block][pol] += 1;
        let intensity = g.intensity[k][p];
        let class = (intensity as usize).min(INTENSITY_BINS);
        if previous == TimeUs::MIN {
            first_of_pixel.push(FirstOfPixel {
                pixel: p as u32,
                block: block as u32,
                class: class as u8,
                t,
            });
        } else {
            o.count_interval(g, block, class, previous, t);
        }
        o.count_time(g, t);
        if intensity != u8::MAX {
            o.count_scene(g, (block, k), p, pol, support[i]);
        }
    }
    Part {
        observed: o,
        first_of_pixel,
        last,
    }
}

/// The frame interval of the first event of `range`: the last frame at or before it.
fn first_interval(events: &EventChunk, range: &std::ops::Range<usize>, g: &Geometry) -> usize {
    range.clone().next().map_or(0, |i| {
        let t = events.t[i];
        g.times.partition_point(|&s| s <= t).saturating_sub(1)
    })
}

/// The block an event at `t` of pixel `p` in frame interval `k` is counted in: `None`
/// outside the frames, in an interval of no block, or at an excluded or `masked` pixel.
fn counted_block(g: &Geometry, k: usize, t: TimeUs, p: usize, masked: &[bool]) -> Option<usize> {
    if t < g.times[0] || k + 1 >= g.times.len() {
        return None;
    }
    let block = g.interval_block[k]?;
    (!g.excluded[p] && !masked[p]).then_some(block)
}

#[cfg(test)]
mod tests {
    use super::super::{CHANGE_BINS, Role};
    use super::*;
    use crate::events::{Event, Sensor};
    use rand::{RngExt, SeedableRng};
    use rand_xoshiro::Xoshiro256PlusPlus;

    /// 8 x 4 pixels, four frame intervals of 10 ms (the third unused), an unread span in
    /// the fourth; some pixels without a reliable intensity, one excluded, one masked.
    fn geometry() -> (Geometry, Vec<bool>) {
        let pixels = 32;
        let bins = |m: usize| (0..pixels).map(|p| (p % m) as u8).collect::<Vec<u8>>();
        let mut intensity = bins(INTENSITY_BINS);
        intensity[5] = u8::MAX;
        let mut excluded = vec![false; pixels];
        excluded[7] = true;
        let mut masked = vec![false; pixels];
        masked[12] = true;
        let g = Geometry {
            sensor: Sensor::new(8, 4),
            times: vec![0, 10_000, 20_000, 30_000, 40_000],
            interval_block: vec![Some(0), Some(1), None, Some(2)],
            blocks: 3,
            role: vec![Role::Fit, Role::Selection, Role::Test],
            guard_seconds: 0.0,
            region: bins(REGIONS),
            excluded,
            intensity: vec![intensity.clone(), intensity.clone(), vec![], intensity],
            change: vec![
                bins(CHANGE_BINS),
                bins(CHANGE_BINS),
                vec![],
                bins(CHANGE_BINS),
            ],
            exposure: vec![[0.0; INTENSITY_BINS]; 3],
            still_exposure: vec![0.0; 3],
            span: (0, 40_000),
            frame_interval_s: 0.01,
            unread: vec![(33_000, 34_000)],
            intensity_centres: [0.0; INTENSITY_BINS],
            change_centres: [0.0; CHANGE_BINS],
        };
        (g, masked)
    }

    #[test]
    fn stretches_count_what_one_pass_counts() {
        let (g, masked) = geometry();
        // 300,000 events over 45 ms (some after the last frame), pixels and polarities
        // from a seeded generator; times non-decreasing with ties
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(12345);
        let events: EventChunk = (0..300_000u64)
            .map(|i| {
                let r = rng.random::<u64>() >> 33;
                Event {
                    t: (i * 45_000 / 300_000) as TimeUs,
                    x: (r % 8) as u16,
                    y: ((r >> 3) % 4) as u16,
                    on: (r >> 5) & 1 == 1,
                }
            })
            .collect();
        let support = supported(&events, g.sensor, SUPPORT_US);
        let one = Observed::counted(&events, &support, &g, &masked, 1);
        assert!(one.polarity.iter().map(|p| p[0] + p[1]).sum::<u64>() > 150_000);
        assert!(one.intervals.iter().sum::<u32>() > 150_000);
        // pixels 0, 7, 14, ... are still (change bin 0): about a seventh of the events
        let still: u64 = one.still.iter().map(|p| p[0] + p[1]).sum();
        assert!(still > 15_000 && still < 45_000, "{still}");
        for threads in [2, 3, 4] {
            let many = Observed::counted(&events, &support, &g, &masked, threads);
            assert_eq!(events.time_stretches(threads, MIN_STRETCH).len(), threads);
            assert_eq!(many.cells, one.cells);
            assert_eq!(many.background, one.background);
            assert_eq!(many.by_region, one.by_region);
            assert_eq!(many.intervals, one.intervals);
            assert_eq!(many.pixel_counts, one.pixel_counts);
            assert_eq!(many.polarity, one.polarity);
            assert_eq!(many.still, one.still);
            assert_eq!(many.timeline, one.timeline);
        }
    }
}
