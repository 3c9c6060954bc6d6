//! Events, frames and sensors: the one representation every reader produces and every later
//! stage (statistics, simulation, estimation) consumes.
//!
//! An event is `(t, x, y, polarity)`: time in integer microseconds in the file's own clock,
//! pixel column `x` and row `y` (origin top-left, y down) and polarity (ON = brightness went
//! up by a contrast threshold, OFF = down). Events travel in [`EventChunk`]s, a struct of
//! arrays, so that statistics stream over bounded memory in tight, vectorisable loops.

use serde::{Deserialize, Serialize};

/// Time in integer microseconds.
pub type TimeUs = i64;

/// Number of events a reader puts in one chunk (a few MB of struct-of-arrays).
pub const CHUNK_EVENTS: usize = 1 << 18;

/// The largest sensor side ctcal accepts from a file's metadata or infers from coordinates
/// (more than any sensor sold); a larger sensor must be given with `--sensor`, so that a
/// damaged header or coordinate cannot make ctcal allocate gigabytes of per-pixel state.
pub const MAX_SENSOR_SIDE: u16 = 4096;

/// Times further than this from zero (2^61 us, about 73,000 years) are damage: keeping
/// every time below it lets any difference of two times fit in an `i64`.
pub const TIME_LIMIT_US: i64 = 1 << 61;

/// A sensor's pixel array size.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Sensor {
    pub width: u16,
    pub height: u16,
}

impl Sensor {
    pub fn new(width: u16, height: u16) -> Self {
        Self { width, height }
    }

    /// Number of pixels.
    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Whether neither side exceeds [`MAX_SENSOR_SIDE`].
    pub fn is_plausible(&self) -> bool {
        self.width <= MAX_SENSOR_SIDE && self.height <= MAX_SENSOR_SIDE
    }

    /// Whether pixel `(x, y)` lies on the sensor.
    pub fn contains(&self, x: u16, y: u16) -> bool {
        x < self.width && y < self.height
    }

    /// Parses `WxH` (e.g. `346x260`).
    pub fn parse(text: &str) -> Option<Self> {
        let (w, h) = text.trim().split_once(['x', 'X'])?;
        let width: u16 = w.trim().parse().ok()?;
        let height: u16 = h.trim().parse().ok()?;
        (width > 0 && height > 0).then_some(Self { width, height })
    }
}

impl std::fmt::Display for Sensor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}", self.width, self.height)
    }
}

/// One event.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Event {
    pub t: TimeUs,
    pub x: u16,
    pub y: u16,
    pub on: bool,
}

/// A run of events as a struct of arrays (`t`, `x`, `y`, `on` have equal lengths).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct EventChunk {
    pub t: Vec<TimeUs>,
    pub x: Vec<u16>,
    pub y: Vec<u16>,
    pub on: Vec<bool>,
}

impl EventChunk {
    pub fn with_capacity(capacity: usize) -> Self {
        Self {
            t: Vec::with_capacity(capacity),
            x: Vec::with_capacity(capacity),
            y: Vec::with_capacity(capacity),
            on: Vec::with_capacity(capacity),
        }
    }

    #[inline]
    pub fn push(&mut self, t: TimeUs, x: u16, y: u16, on: bool) {
        self.t.push(t);
        self.x.push(x);
        self.y.push(y);
        self.on.push(on);
    }

    #[inline]
    pub fn push_event(&mut self, event: Event) {
        self.push(event.t, event.x, event.y, event.on);
    }

    pub fn len(&self) -> usize {
        self.t.len()
    }

    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// How many of the events are ON.
    pub fn on_count(&self) -> usize {
        self.on.iter().filter(|&&on| on).count()
    }

    pub fn clear(&mut self) {
        self.t.clear();
        self.x.clear();
        self.y.clear();
        self.on.clear();
    }

    /// The `i`-th event.
    #[inline]
    pub fn get(&self, i: usize) -> Event {
        Event {
            t: self.t[i],
            x: self.x[i],
            y: self.y[i],
            on: self.on[i],
        }
    }

    pub fn iter(&self) -> impl Iterator<Item = Event> + '_ {
        (0..self.len()).map(move |i| self.get(i))
    }

    /// The time-sorted union of two time-sorted chunks (`a`'s event first on equal times).
    pub fn merged(a: &EventChunk, b: &EventChunk) -> EventChunk {
        let mut out = EventChunk::with_capacity(a.len() + b.len());
        let (mut i, mut j) = (0, 0);
        while i < a.len() || j < b.len() {
            if j == b.len() || (i < a.len() && a.t[i] <= b.t[j]) {
                out.push_event(a.get(i));
                i += 1;
            } else {
                out.push_event(b.get(j));
                j += 1;
            }
        }
        out
    }

    /// The events with `from <= t < to` (the chunk time-sorted).
    pub fn between(&self, from: TimeUs, to: TimeUs) -> EventChunk {
        let start = self.t.partition_point(|&t| t < from);
        let end = self.t.partition_point(|&t| t < to);
        EventChunk {
            t: self.t[start..end].to_vec(),
            x: self.x[start..end].to_vec(),
            y: self.y[start..end].to_vec(),
            on: self.on[start..end].to_vec(),
        }
    }

    pub fn extend_from(&mut self, other: &EventChunk) {
        self.t.extend_from_slice(&other.t);
        self.x.extend_from_slice(&other.x);
        self.y.extend_from_slice(&other.y);
        self.on.extend_from_slice(&other.on);
    }

    /// Whether timestamps never decrease.
    pub fn is_time_sorted(&self) -> bool {
        self.t.windows(2).all(|w| w[0] <= w[1])
    }

    /// How to cut a pass over the time-sorted events among `count` threads: consecutive
    /// stretches of about equal length, each beginning where the timestamp changes (the
    /// events of one instant stay together). One stretch when the events are not
    /// time-sorted or fewer than `min_len` would fall to each.
    pub fn time_stretches(&self, count: usize, min_len: usize) -> Vec<std::ops::Range<usize>> {
        let n = self.len();
        let count = count.min(n / min_len.max(1)).max(1);
        if count == 1 || !self.is_time_sorted() {
            return std::iter::once(0..n).collect();
        }
        let mut starts: Vec<usize> = (0..count)
            .map(|k| {
                let mut s = k * n / count;
                while s > 0 && s < n && self.t[s] == self.t[s - 1] {
                    s += 1;
                }
                s
            })
            .collect();
        starts.push(n);
        starts.dedup();
        starts.windows(2).map(|w| w[0]..w[1]).collect()
    }

    /// Sorts by time; events with equal times keep their order (stable).
    pub fn sort_by_time(&mut self) {
        if self.is_time_sorted() {
            return;
        }
        let mut order: Vec<u32> = (0..self.len() as u32).collect();
        order.sort_by_key(|&i| self.t[i as usize]);
        fn take<T: Copy>(values: &[T], order: &[u32]) -> Vec<T> {
            order.iter().map(|&i| values[i as usize]).collect()
        }
        let t = take(&self.t, &order);
        let x = take(&self.x, &order);
        let y = take(&self.y, &order);
        let on = take(&self.on, &order);
        *self = Self { t, x, y, on };
    }

    /// Largest x and y in the chunk (`None` when empty).
    pub fn max_coordinates(&self) -> Option<(u16, u16)> {
        let max_x = self.x.iter().copied().max()?;
        let max_y = self.y.iter().copied().max()?;
        Some((max_x, max_y))
    }

    /// Events at the same pixel and microsecond as their pixel's previous event (time
    /// order assumed; pixels outside `sensor` are not counted), as `stats` counts them in
    /// `inter_event_interval_s.zero`.
    pub fn same_microsecond_repeats(&self, sensor: Sensor) -> usize {
        let width = sensor.width as usize;
        let mut last: Vec<TimeUs> = vec![TimeUs::MIN; sensor.pixels()];
        let mut repeats = 0;
        for ((&t, &x), &y) in self.t.iter().zip(&self.x).zip(&self.y) {
            if x >= sensor.width || y >= sensor.height {
                continue;
            }
            let previous = &mut last[y as usize * width + x as usize];
            repeats += usize::from(*previous == t);
            *previous = t;
        }
        repeats
    }
}

impl FromIterator<Event> for EventChunk {
    fn from_iter<I: IntoIterator<Item = Event>>(iter: I) -> Self {
        let mut chunk = EventChunk::default();
        for e in iter {
            chunk.push_event(e);
        }
        chunk
    }
}

/// An 8-bit grey frame (APS image, stimulus frame or simulator output).
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Timestamp (microseconds, the recording's clock): for APS frames the exposure midpoint
    /// where the file says so, else the file's frame time.
    pub t: TimeUs,
    pub width: u32,
    pub height: u32,
    /// Row-major grey levels, `width * height` bytes.
    pub pixels: Vec<u8>,
    /// Exposure time in microseconds, where known.
    pub exposure_us: Option<i64>,
}

/// Converts integer microseconds to seconds.
#[inline]
pub fn us_to_s(t: TimeUs) -> f64 {
    t as f64 / 1e6
}

/// Converts seconds to the nearest integer microsecond.
#[inline]
pub fn s_to_us(t: f64) -> TimeUs {
    (t * 1e6).round() as TimeUs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_microsecond_repeats_are_counted_per_pixel() {
        let mut chunk = EventChunk::default();
        // pixel (1, 0) twice at 5 us, then again at 5 us (of the other polarity): two
        // repeats; pixel (2, 0) at 5 us once and pixel (1, 1) at 5 us: none; a pixel outside
        // the sensor is not counted
        for (t, x, y, on) in [
            (5, 1, 0, true),
            (5, 2, 0, true),
            (5, 1, 0, true),
            (5, 1, 1, true),
            (5, 1, 0, false),
            (6, 1, 0, true),
            (6, 9, 0, true),
            (6, 9, 0, true),
        ] {
            chunk.push(t, x, y, on);
        }
        assert_eq!(chunk.same_microsecond_repeats(Sensor::new(4, 2)), 2);
    }

    #[test]
    fn merged_keeps_time_order_and_every_event() {
        let mut a = EventChunk::default();
        let mut b = EventChunk::default();
        for t in [1, 4, 4, 9] {
            a.push(t, 1, 0, true);
        }
        for t in [0, 4, 10] {
            b.push(t, 2, 0, false);
        }
        let m = EventChunk::merged(&a, &b);
        assert_eq!(m.t, [0, 1, 4, 4, 4, 9, 10]);
        assert_eq!(m.x, [2, 1, 1, 1, 2, 1, 2]);
        assert_eq!(m.between(4, 10).t, [4, 4, 4, 9]);
    }

    #[test]
    fn sensor_parses_w_by_h() {
        assert_eq!(Sensor::parse("346x260"), Some(Sensor::new(346, 260)));
        assert_eq!(Sensor::parse(" 1280X720 "), Some(Sensor::new(1280, 720)));
        assert_eq!(Sensor::parse("0x10"), None);
        assert_eq!(Sensor::parse("640"), None);
    }

    #[test]
    fn sort_is_stable_and_keeps_columns_together() {
        let mut c: EventChunk = [
            Event {
                t: 5,
                x: 1,
                y: 1,
                on: true,
            },
            Event {
                t: 3,
                x: 2,
                y: 2,
                on: false,
            },
            Event {
                t: 5,
                x: 3,
                y: 3,
                on: false,
            },
            Event {
                t: 1,
                x: 4,
                y: 4,
                on: true,
            },
        ]
        .into_iter()
        .collect();
        c.sort_by_time();
        assert_eq!(c.t, vec![1, 3, 5, 5]);
        assert_eq!(c.x, vec![4, 2, 1, 3]);
        assert_eq!(c.on, vec![true, false, true, false]);
    }
}
