//! Spatio-temporal support of each event (the background-activity filter of Delbruck,
//! "Frame-free dynamic digital vision", 2008): an event is supported when one of its 8
//! neighbours fired within the preceding window. Moving edges give their events neighbours
//! within a few pixel-crossing times; shot-noise, leak and hot-pixel events are isolated.
//! The statistics pass counts the unsupported events ([`super::StatsAccumulator`]); the
//! estimators use the flags to keep noise out of their samples. Events with the same
//! timestamp support each other whatever their order in the file (a display refresh makes
//! whole regions fire at one instant).
//!
//! The 8-neighbourhood's passes keep, for every cell, the time of its neighbours' newest
//! event: each event writes its time into its neighbours' cells and reads its support from
//! its own (as the statistics kernel does; the events come in time order, so the last time
//! written is the newest). The events of one timestamp all write before any of them reads.

use crate::events::{EventChunk, Sensor, TimeUs};
use rayon::prelude::*;

/// For each event of the time-sorted `events`, whether a neighbour fired in the `window_us`
/// before it (or at the same time).
pub fn supported(events: &EventChunk, sensor: Sensor, window_us: TimeUs) -> Vec<bool> {
    supported_in(events, sensor, window_us, rayon::current_num_threads())
}

/// Fewer events than this are filtered in one stretch.
const MIN_STRETCH: usize = 1 << 14;

/// [`supported`] in at most `threads` stretches of time-sorted events, on the pool. A
/// stretch's flags depend only on the marks of the `window_us` before it, so each stretch
/// first replays the events of that window (marks only) and then flags its own: the
/// flags of one pass in order. Stretches begin where the timestamp changes, so that the
/// events of one instant stay together.
fn supported_in(
    events: &EventChunk,
    sensor: Sensor,
    window_us: TimeUs,
    threads: usize,
) -> Vec<bool> {
    debug_assert!(
        events.is_time_sorted(),
        "the support filter needs time-sorted events"
    );
    let grid = Grid::new(events, sensor);
    let stretches = events.time_stretches(threads, MIN_STRETCH);
    if stretches.len() == 1 {
        return grid.pass::<FORWARD>(&events.t, window_us);
    }
    let parts: Vec<Vec<bool>> = stretches
        .into_par_iter()
        .map(|stretch| grid.forward_stretch(events, window_us, stretch))
        .collect();
    parts.concat()
}

/// For each event of the time-sorted `events`, whether a neighbour fired within `window_us`
/// before or after it: the causal filter run forwards and on the time-reversed stream. An
/// estimator comparing counts uses it so that an edge's first event, or any event near the
/// start of a short recording, is not taken for noise for want of a past. The two passes
/// run on two threads where there are.
pub fn supported_two_sided(events: &EventChunk, sensor: Sensor, window_us: TimeUs) -> Vec<bool> {
    debug_assert!(
        events.is_time_sorted(),
        "the support filter needs time-sorted events"
    );
    let grid = Grid::new(events, sensor);
    let (mut flags, backward) = rayon::join(
        || grid.pass::<FORWARD>(&events.t, window_us),
        || grid.pass::<BACKWARD>(&events.t, window_us),
    );
    for (flag, &b) in flags.iter_mut().zip(&backward) {
        *flag |= b;
    }
    flags
}

/// [`supported_two_sided`] over a wider neighbourhood: the `(2 radius + 1)^2 - 1` pixels
/// within `radius` (Chebyshev distance) of the event's own. Radius 1 is the 8-neighbourhood
/// above; a wider one also supports the scene's events that fire without any of their 8
/// neighbours (an edge whose change crosses a pixel's threshold but not its neighbours',
/// at high thresholds and under mismatch), which a noise event, independent of its
/// surroundings, is not more likely to have near it than any moment of its pixel.
pub fn supported_two_sided_within(
    events: &EventChunk,
    sensor: Sensor,
    window_us: TimeUs,
    radius: usize,
) -> Vec<bool> {
    if radius == 1 {
        return supported_two_sided(events, sensor, window_us);
    }
    wide_support(events, sensor, window_us, radius)
}

/// [`supported_two_sided_within`] by one pass each way over a grid with a `radius` border,
/// looking at every neighbour (the 8-neighbourhood's passes are tuned, this one is not).
fn wide_support(
    events: &EventChunk,
    sensor: Sensor,
    window_us: TimeUs,
    radius: usize,
) -> Vec<bool> {
    let grid = WideGrid::new(events, sensor, radius);
    let mut flags = vec![false; events.len()];
    let n = events.len();
    grid.sweep(
        &events.t,
        0..n,
        TimeUs::MIN,
        |mark, t| mark >= t - window_us,
        &mut flags,
    );
    grid.sweep(
        &events.t,
        (0..n).rev(),
        TimeUs::MAX,
        |mark, t| mark <= t + window_us,
        &mut flags,
    );
    flags
}

/// Every event's cell in a grid with a `radius` border, and the offsets of the cells
/// around a cell (its own left out).
struct WideGrid {
    cells: Vec<usize>,
    offsets: Vec<isize>,
    size: usize,
}

impl WideGrid {
    fn new(events: &EventChunk, sensor: Sensor, radius: usize) -> Self {
        let stride = sensor.width as usize + 2 * radius;
        let r = radius as isize;
        Self {
            cells: events
                .x
                .iter()
                .zip(&events.y)
                .map(|(&x, &y)| (y as usize + radius) * stride + x as usize + radius)
                .collect(),
            offsets: (-r..=r)
                .flat_map(|dy| (-r..=r).map(move |dx| (dy, dx)))
                .filter(|&d| d != (0, 0))
                .map(|(dy, dx)| dy * stride as isize + dx)
                .collect(),
            size: stride * (sensor.height as usize + 2 * radius),
        }
    }

    /// Walks the events in `order`, flagging one where a neighbour cell's mark (the time of
    /// its last event walked, `never` before any) is `near` its time; then marks its cell.
    fn sweep(
        &self,
        times: &[TimeUs],
        order: impl Iterator<Item = usize>,
        never: TimeUs,
        near: impl Fn(TimeUs, TimeUs) -> bool,
        flags: &mut [bool],
    ) {
        let mut marks = vec![never; self.size];
        for i in order {
            let (t, c) = (times[i], self.cells[i]);
            flags[i] |= self
                .offsets
                .iter()
                .any(|&o| near(marks[c.wrapping_add_signed(o)], t));
            marks[c] = t;
        }
    }
}

/// Which way a pass walks the events: backwards it reads them from the last, with times
/// negated (so that they still grow).
const FORWARD: bool = false;
const BACKWARD: bool = true;

/// The cell of every event in a grid with a one-cell border (so that every event has eight
/// neighbour cells), computed once for both passes.
struct Grid {
    stride: usize,
    size: usize,
    cells: Vec<u32>,
}

/// Tells the 8 neighbours of cell `k` (in `told`, the time of each cell's neighbours' newest
/// event) that one of theirs fired at `t`; its own cell is not told. The statistics kernel
/// tells its grid the same way (border cells never fire; they are told, and keep it for
/// when its grid grows over them).
#[inline(always)]
pub(super) fn tell_neighbours(told: &mut [TimeUs], k: usize, stride: usize, t: TimeUs) {
    for start in [k - stride - 1, k + stride - 1] {
        told[start..start + 3].fill(t);
    }
    let here: &mut [TimeUs; 3] = (&mut told[k - 1..k + 2]).try_into().expect("three cells");
    here[0] = t;
    here[2] = t;
}

impl Grid {
    fn new(events: &EventChunk, sensor: Sensor) -> Self {
        let stride = sensor.width as usize + 2;
        let cells = events
            .x
            .iter()
            .zip(&events.y)
            .map(|(&x, &y)| ((y as usize + 1) * stride + x as usize + 1) as u32)
            .collect();
        Self {
            stride,
            size: stride * (sensor.height as usize + 2),
            cells,
        }
    }

    /// The forward pass's flags of the events in `stretch` (which begins where the
    /// timestamp changes), its cells first told by the events of the window before it.
    fn forward_stretch(
        &self,
        events: &EventChunk,
        window_us: TimeUs,
        stretch: std::ops::Range<usize>,
    ) -> Vec<bool> {
        let mut told = vec![TimeUs::MIN; self.size];
        let Some(&first) = events.t.get(stretch.start) else {
            return Vec::new();
        };
        let from =
            events.t[..stretch.start].partition_point(|&t| t < first.saturating_sub(window_us));
        for j in from..stretch.start {
            tell_neighbours(&mut told, self.cells[j] as usize, self.stride, events.t[j]);
        }
        self.flag::<FORWARD>(&mut told, &events.t, stretch, window_us)
    }

    /// One causal pass over the events at `times`, forwards or [`BACKWARD`]: each event's
    /// flag, in the events' order.
    fn pass<const BACKWARDS: bool>(&self, times: &[TimeUs], window_us: TimeUs) -> Vec<bool> {
        let mut told = vec![TimeUs::MIN; self.size];
        self.flag::<BACKWARDS>(&mut told, times, 0..times.len(), window_us)
    }

    /// Flags the events of `range` read forwards or backwards (each flag at its event's
    /// place in the range) against the newest neighbour times in `told`, each event
    /// telling its neighbours. The events of one timestamp all tell before any reads, so
    /// that they see each other whatever their order.
    fn flag<const BACKWARDS: bool>(
        &self,
        told: &mut [TimeUs],
        times: &[TimeUs],
        range: std::ops::Range<usize>,
        window_us: TimeUs,
    ) -> Vec<bool> {
        let stride = self.stride;
        let n = range.len();
        let cells = &self.cells[range.clone()];
        let times = &times[range];
        // the place in the range of the `j`-th event read, and its time as the pass sees it
        let place = |j: usize| if BACKWARDS { n - 1 - j } else { j };
        let time = |j: usize| {
            if BACKWARDS {
                -times[n - 1 - j]
            } else {
                times[j]
            }
        };
        let mut flags = vec![false; n];
        let mut j = 0;
        while j < n {
            let t = time(j);
            let oldest = t.saturating_sub(window_us);
            if j + 1 == n || time(j + 1) != t {
                // alone at its time (most events): it tells only its neighbours, so it may
                // read first
                let i = place(j);
                let k = cells[i] as usize;
                flags[i] = told[k] >= oldest;
                tell_neighbours(told, k, stride, t);
                j += 1;
                continue;
            }
            let mut end = j + 2;
            while end < n && time(end) == t {
                end += 1;
            }
            for r in j..end {
                tell_neighbours(told, cells[place(r)] as usize, stride, t);
            }
            for r in j..end {
                let i = place(r);
                flags[i] = told[cells[i] as usize] >= oldest;
            }
            j = end;
        }
        flags
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::events::Event;
    use rand::{RngExt, SeedableRng};
    use rand_xoshiro::Xoshiro256PlusPlus;

    #[test]
    fn a_wider_neighbourhood_supports_what_the_eight_neighbours_do_and_more() {
        let sensor = Sensor::new(30, 20);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        let mut t = 0;
        let events: EventChunk = (0..4000)
            .map(|_| {
                t += rng.random_range(0..400);
                Event {
                    t,
                    x: rng.random_range(0..30),
                    y: rng.random_range(0..20),
                    on: rng.random(),
                }
            })
            .collect();
        let eight = supported_two_sided(&events, sensor, 3_000);
        assert_eq!(wide_support(&events, sensor, 3_000, 1), eight);
        let wider = supported_two_sided_within(&events, sensor, 3_000, 2);
        assert!(eight.iter().zip(&wider).all(|(&a, &b)| !a || b));
        let (n8, n24) = (
            eight.iter().filter(|&&s| s).count(),
            wider.iter().filter(|&&s| s).count(),
        );
        assert!(n24 > n8 + 200, "{n8} -> {n24}");
        // a neighbour two pixels away supports at radius 2 only, before or after
        let pair: EventChunk = [(0, 5, 5), (2_000, 7, 3), (50_000, 0, 0)]
            .into_iter()
            .map(|(t, x, y)| Event { t, x, y, on: true })
            .collect();
        let s = Sensor::new(10, 10);
        assert_eq!(supported_two_sided_within(&pair, s, 3_000, 1), [false; 3]);
        assert_eq!(
            supported_two_sided_within(&pair, s, 3_000, 2),
            [true, true, false]
        );
    }

    #[test]
    fn a_neighbour_within_the_window_supports_an_event() {
        let events: EventChunk = [(0, 1, 1), (5_000, 2, 2), (30_000, 0, 0), (31_000, 3, 3)]
            .into_iter()
            .map(|(t, x, y)| Event { t, x, y, on: true })
            .collect();
        let flags = supported(&events, Sensor::new(4, 4), 10_000);
        assert_eq!(flags, vec![false, true, false, false]);
        // two neighbours at one instant support each other in either order; a pixel does
        // not support itself
        let burst: EventChunk = [(0, 1, 1), (0, 2, 1), (0, 3, 3), (5, 3, 3)]
            .into_iter()
            .map(|(t, x, y)| Event { t, x, y, on: true })
            .collect();
        assert_eq!(
            supported(&burst, Sensor::new(4, 4), 10_000),
            vec![true, true, false, false]
        );
        // two-sided: the first event is supported by the one 5 ms after it
        assert_eq!(
            supported_two_sided(&events, Sensor::new(4, 4), 10_000),
            vec![true, true, false, false]
        );
    }

    #[test]
    fn two_sided_support_is_a_neighbour_event_within_the_window_either_side() {
        // 3,000 events on 10 x 8, three to a timestamp, pixels drawn with a fixed seed:
        // the definition checked by brute force
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
        let events: EventChunk = (0..3000)
            .map(|i| Event {
                t: (i / 3) * 700,
                x: rng.random_range(0..10),
                y: rng.random_range(0..8),
                on: true,
            })
            .collect();
        let window = 2_000;
        let flags = supported_two_sided(&events, Sensor::new(10, 8), window);
        assert_eq!(flags, by_definition(&events, 1, window, true));
        assert!(flags.iter().any(|&f| f) && flags.iter().any(|&f| !f));
    }

    #[test]
    fn stretches_flag_what_one_pass_flags() {
        // 400,000 events on 20 x 10 pixels over 2 s, with runs of equal timestamps, so
        // that both supported and isolated events are many
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        let events: EventChunk = (0..400_000u64)
            .map(|i| {
                let r = rng.random::<u64>() >> 33;
                Event {
                    t: (i / 3 * 15) as TimeUs,
                    x: (r % 20) as u16,
                    y: ((r >> 5) % 10) as u16,
                    on: true,
                }
            })
            .collect();
        let sensor = Sensor::new(20, 10);
        let one = supported_in(&events, sensor, 100, 1);
        let kept = one.iter().filter(|&&f| f).count();
        assert!(kept > 50_000 && kept < 350_000, "{kept} supported");
        for threads in [2, 3, 5] {
            assert_eq!(
                supported_in(&events, sensor, 100, threads),
                one,
                "{threads} stretches"
            );
        }
    }

    /// `n` events on `sensor` (small, so that many lie on its border) with runs of equal
    /// timestamps of random length (seven in ten events share the time of the one before).
    fn crowded(seed: u64, n: usize, sensor: Sensor) -> EventChunk {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let mut t = 1_000;
        (0..n)
            .map(|_| {
                if rng.random_bool(0.3) {
                    t += rng.random_range(1..300);
                }
                Event {
                    t,
                    x: rng.random_range(0..sensor.width),
                    y: rng.random_range(0..sensor.height),
                    on: rng.random(),
                }
            })
            .collect()
    }

    /// The definition by brute force: whether another pixel within `radius` fired within
    /// `window` before the event or at its time (or after it, `two_sided`).
    fn by_definition(
        events: &EventChunk,
        radius: i32,
        window: TimeUs,
        two_sided: bool,
    ) -> Vec<bool> {
        (0..events.len())
            .map(|i| {
                let ti = events.t[i];
                let from = events.t.partition_point(|&t| t < ti - window);
                let to = events
                    .t
                    .partition_point(|&t| t <= if two_sided { ti + window } else { ti });
                (from..to).any(|j| {
                    let dx = events.x[j] as i32 - events.x[i] as i32;
                    let dy = events.y[j] as i32 - events.y[i] as i32;
                    (dx, dy) != (0, 0) && dx.abs() <= radius && dy.abs() <= radius
                })
            })
            .collect()
    }

    #[test]
    fn flags_are_the_definition_with_many_equal_timestamps_and_at_the_borders() {
        for (seed, sensor) in [
            (1, Sensor::new(6, 5)),
            (2, Sensor::new(1, 9)),
            (3, Sensor::new(9, 1)),
            (4, Sensor::new(2, 2)),
            (5, Sensor::new(24, 13)),
        ] {
            let events = crowded(seed, 3000, sensor);
            let grid = Grid::new(&events, sensor);
            for window in [0, 40, 300, 2_000] {
                let causal = by_definition(&events, 1, window, false);
                assert_eq!(supported(&events, sensor, window), causal);
                // the stretches' passes, each told by the window before it
                for count in [2, 7] {
                    let stretches = events.time_stretches(count, 100);
                    assert!(stretches.len() > 1);
                    let parts: Vec<Vec<bool>> = stretches
                        .into_iter()
                        .map(|s| grid.forward_stretch(&events, window, s))
                        .collect();
                    assert_eq!(parts.concat(), causal, "{count} stretches");
                }
                let two_sided = by_definition(&events, 1, window, true);
                assert_eq!(supported_two_sided(&events, sensor, window), two_sided);
                assert!(two_sided.iter().zip(&causal).all(|(&a, &b)| a || !b));
                for radius in [2, 3] {
                    assert_eq!(
                        supported_two_sided_within(&events, sensor, window, radius),
                        by_definition(&events, radius as i32, window, true),
                        "{sensor:?} window {window} radius {radius}"
                    );
                }
            }
        }
    }
}
