//! Spatio-temporal support of each event (the background-activity filter of Delbruck,
//! "Frame-free dynamic digital vision", 2008): an event is supported when one of its 8
//! neighbours fired within the preceding window. Moving edges give their events neighbours
//! within a few pixel-crossing times; shot-noise, leak and hot-pixel events are isolated.
//! The statistics pass counts the unsupported events ([`super::StatsAccumulator`]); the
//! estimators use the flags to keep noise out of their samples. Events with the same
//! timestamp support each other whatever their order in the file (a display refresh makes
//! whole regions fire at one instant).

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
    let grid = Grid::new(events, sensor);
    let stretches = events.time_stretches(threads, MIN_STRETCH);
    if stretches.len() == 1 {
        return grid.pass(events, window_us, Direction::Forward);
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
    let grid = Grid::new(events, sensor);
    let (mut flags, backward) = rayon::join(
        || grid.pass(events, window_us, Direction::Forward),
        || grid.pass(events, window_us, Direction::Backward),
    );
    // the backward pass flags events in reversed order
    for (flag, &b) in flags.iter_mut().zip(backward.iter().rev()) {
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
#[derive(Clone, Copy, PartialEq)]
enum Direction {
    Forward,
    Backward,
}

/// The cell of every event in a grid with a one-cell border (so that every event has eight
/// neighbour cells), computed once for both passes.
struct Grid {
    stride: usize,
    size: usize,
    cells: Vec<u32>,
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
    /// timestamp changes), its marks first set by the events of the window before it.
    fn forward_stretch(
        &self,
        events: &EventChunk,
        window_us: TimeUs,
        stretch: std::ops::Range<usize>,
    ) -> Vec<bool> {
        let mut last = vec![TimeUs::MIN; self.size];
        let Some(&first) = events.t.get(stretch.start) else {
            return Vec::new();
        };
        let from =
            events.t[..stretch.start].partition_point(|&t| t < first.saturating_sub(window_us));
        for j in from..stretch.start {
            last[self.cells[j] as usize] = events.t[j];
        }
        self.flag(
            &mut last,
            stretch.len(),
            |j| stretch.start + j,
            |j| events.t[stretch.start + j],
            window_us,
        )
    }

    /// One causal pass: each event's flag, in the order the pass reads them. The events of
    /// one timestamp are marked first, so that they see each other.
    fn pass(&self, events: &EventChunk, window_us: TimeUs, direction: Direction) -> Vec<bool> {
        let n = events.len();
        let index = |j: usize| match direction {
            Direction::Forward => j,
            Direction::Backward => n - 1 - j,
        };
        let time = |j: usize| match direction {
            Direction::Forward => events.t[j],
            Direction::Backward => -events.t[n - 1 - j],
        };
        let mut last = vec![TimeUs::MIN; self.size];
        self.flag(&mut last, n, index, time, window_us)
    }

    /// Flags `n` events read in order (`index(j)` the `j`-th read, `time(j)` its time)
    /// against the marks in `last`, marking each.
    fn flag(
        &self,
        last: &mut [TimeUs],
        n: usize,
        index: impl Fn(usize) -> usize,
        time: impl Fn(usize) -> TimeUs,
        window_us: TimeUs,
    ) -> Vec<bool> {
        let stride = self.stride;
        let mut flags = Vec::with_capacity(n);
        // the marks the events of one timestamp replaced (reused: runs are short)
        let mut own = Vec::new();
        let mut start = 0;
        while start < n {
            let t = time(start);
            let mut end = start + 1;
            while end < n && time(end) == t {
                end += 1;
            }
            own.clear();
            for j in start..end {
                let k = self.cells[index(j)] as usize;
                own.push(last[k]);
                last[k] = t;
            }
            for (j, &before) in (start..end).zip(&own) {
                let k = self.cells[index(j)] as usize;
                // the pixel's own mark is not a neighbour's: restore it while looking around
                let mark = std::mem::replace(&mut last[k], before);
                let newest = last[k - stride - 1]
                    .max(last[k - stride])
                    .max(last[k - stride + 1])
                    .max(last[k - 1])
                    .max(last[k + 1])
                    .max(last[k + stride - 1])
                    .max(last[k + stride])
                    .max(last[k + stride + 1]);
                last[k] = mark;
                flags.push(newest >= t.saturating_sub(window_us));
            }
            start = end;
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
        for (i, &flag) in flags.iter().enumerate() {
            let (xi, yi, ti) = (events.x[i] as i32, events.y[i] as i32, events.t[i]);
            let expected = (0..events.len()).any(|j| {
                let (dx, dy) = (events.x[j] as i32 - xi, events.y[j] as i32 - yi);
                (dx, dy) != (0, 0)
                    && dx.abs() <= 1
                    && dy.abs() <= 1
                    && (events.t[j] - ti).abs() <= window
            });
            assert_eq!(flag, expected, "event {i}");
        }
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
}
