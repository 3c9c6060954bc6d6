//! Dataset statistics in one streaming pass: event counts and rates (events per pixel per
//! second, the quantity Stoffregen et al. 2020 match between real and simulated data), the
//! rate over time, active-pixel fraction, hot pixels, background rate and same-pixel
//! inter-event intervals.
//!
//! Memory is bounded by the sensor (16 bytes per pixel) and a fixed-size interval
//! histogram, not by the recording's length; events must arrive time-sorted.

pub mod hot_pixels;
pub mod intervals;
pub mod pixel_grid;
pub mod timeline;

use crate::events::{EventChunk, Sensor, TimeUs, us_to_s};
use crate::io::ResolvedSensor;
use hot_pixels::HotPixel;
use intervals::IntervalHistogram;
use pixel_grid::PixelGrid;
use serde::Serialize;
pub use timeline::{FrameSummary, RateWindow};

/// Hints the cache to load `value` (no effect on results; a no-op off x86-64).
#[inline(always)]
fn prefetch<T>(value: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: prefetching is a hint and never faults, whatever the address.
    unsafe {
        std::arch::x86_64::_mm_prefetch(
            value as *const T as *const i8,
            std::arch::x86_64::_MM_HINT_T0,
        );
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}

/// What to measure.
#[derive(Clone, Debug)]
pub struct StatsOptions {
    /// Keep events at or after this many seconds from the first event.
    pub start_s: Option<f64>,
    /// Keep events at or before this many seconds from the first event.
    pub end_s: Option<f64>,
    /// Width of the rate-timeline windows, seconds.
    pub window_s: f64,
}

impl Default for StatsOptions {
    fn default() -> Self {
        Self {
            start_s: None,
            end_s: None,
            window_s: 0.01,
        }
    }
}

/// Quantiles of same-pixel intervals between consecutive events (either polarity).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct IntervalSummary {
    pub p5: Option<f64>,
    pub median: Option<f64>,
    pub count: u64,
    /// How the quantiles were computed.
    pub resolution: &'static str,
}

/// Statistics of one event sequence (the `ctcal stats` JSON).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SequenceStats {
    pub width: u16,
    pub height: u16,
    pub sensor_source: String,
    pub events: u64,
    pub on_events: u64,
    pub off_events: u64,
    pub on_fraction: f64,
    pub t_first_us: TimeUs,
    pub t_last_us: TimeUs,
    pub duration_s: f64,
    /// `events / (width * height * duration_s)`; null when the duration is zero.
    pub events_per_pixel_per_second: Option<f64>,
    pub on_per_pixel_per_second: Option<f64>,
    pub off_per_pixel_per_second: Option<f64>,
    pub active_pixel_fraction: f64,
    pub rate_timeline: Vec<RateWindow>,
    pub hot_pixels: Vec<HotPixel>,
    pub hot_pixel_method: &'static str,
    /// Median over all pixels (hot pixels excluded) of each pixel's events / duration_s.
    pub background_rate_hz: f64,
    pub inter_event_interval_s: IntervalSummary,
    pub frames: Option<FrameSummary>,
}

/// Accumulates statistics chunk by chunk.
pub struct StatsAccumulator {
    options: StatsOptions,
    window_us: TimeUs,
    stream_first: Option<TimeUs>,
    select_from: TimeUs,
    select_to: TimeUs,
    first: Option<TimeUs>,
    last: TimeUs,
    events: u64,
    on: u64,
    pixels: PixelGrid,
    /// Scratch: pixel index of each event of the chunk being added.
    indices: Vec<u32>,
    intervals: IntervalHistogram,
    timeline: Vec<u64>,
    window_end: TimeUs,
}

impl StatsAccumulator {
    /// `sensor`: the sensor when known in advance (else the grid grows as events arrive).
    pub fn new(options: StatsOptions, sensor: Option<Sensor>) -> Self {
        let window_us = ((options.window_s * 1e6).round() as TimeUs).max(1);
        let pixels = sensor.map_or_else(PixelGrid::default, |s| {
            PixelGrid::new(s.width as usize, s.height as usize)
        });
        Self {
            options,
            window_us,
            stream_first: None,
            select_from: TimeUs::MIN,
            select_to: TimeUs::MAX,
            first: None,
            last: 0,
            events: 0,
            on: 0,
            pixels,
            indices: Vec::new(),
            intervals: IntervalHistogram::default(),
            timeline: Vec::new(),
            window_end: 0,
        }
    }

    /// Adds a time-sorted chunk (continuing the previous ones).
    pub fn add(&mut self, chunk: &EventChunk) {
        if chunk.is_empty() {
            return;
        }
        if self.stream_first.is_none() {
            let t0 = chunk.t[0];
            self.stream_first = Some(t0);
            if let Some(s) = self.options.start_s {
                self.select_from = t0 + (s * 1e6).round() as TimeUs;
            }
            if let Some(e) = self.options.end_s {
                self.select_to = t0 + (e * 1e6).round() as TimeUs;
            }
        }
        let lo = chunk.t.partition_point(|&t| t < self.select_from);
        let hi = chunk.t.partition_point(|&t| t <= self.select_to);
        if lo >= hi {
            return;
        }
        let (ts, xs, ys) = (&chunk.t[lo..hi], &chunk.x[lo..hi], &chunk.y[lo..hi]);
        if self.first.is_none() {
            self.first = Some(ts[0]);
            self.window_end = ts[0] + self.window_us;
            self.timeline.push(0);
        }
        let max_x = xs.iter().copied().max().expect("non-empty");
        let max_y = ys.iter().copied().max().expect("non-empty");
        self.pixels.ensure(max_x, max_y);
        self.accumulate(ts, xs, ys);
        self.events += ts.len() as u64;
        self.on += chunk.on[lo..hi].iter().map(|&p| p as u64).sum::<u64>();
        self.last = *ts.last().expect("non-empty");
    }

    /// The per-event kernel: counts, same-pixel intervals, timeline.
    #[inline(never)]
    fn accumulate(&mut self, ts: &[TimeUs], xs: &[u16], ys: &[u16]) {
        let width = self.pixels.width;
        // pixel indices first (a vectorised pass), so the main loop can prefetch the cell
        // of an event a few places ahead: events hop between rows, and overlapping those
        // cache misses is most of the kernel's speed
        self.indices.clear();
        self.indices.extend(
            xs.iter()
                .zip(ys)
                .map(|(&x, &y)| y as u32 * width as u32 + x as u32),
        );
        let indices = &self.indices;
        let cells = &mut self.pixels.cells;
        let intervals = &mut self.intervals;
        let mut window_count = *self.timeline.last().expect("started");
        const AHEAD: usize = 16;
        for (i, &t) in ts.iter().enumerate() {
            if let Some(&ahead) = indices.get(i + AHEAD) {
                prefetch(&cells[ahead as usize]);
            }
            let cell = &mut cells[indices[i] as usize];
            if cell.count > 0 {
                intervals.add((t - cell.last) as u64);
            }
            cell.count += 1;
            cell.last = t;
            if t >= self.window_end {
                *self.timeline.last_mut().expect("started") = window_count;
                while t >= self.window_end {
                    self.timeline.push(0);
                    self.window_end += self.window_us;
                }
                window_count = 0;
            }
            window_count += 1;
        }
        *self.timeline.last_mut().expect("started") = window_count;
    }

    /// Events selected so far.
    pub fn events(&self) -> u64 {
        self.events
    }

    /// Final statistics for `sensor`, with the recording's frame times.
    /// `None` when no event was selected.
    pub fn finish(self, sensor: &ResolvedSensor, frame_times: &[TimeUs]) -> Option<SequenceStats> {
        let first = self.first?;
        let (width, height) = (sensor.sensor.width as usize, sensor.sensor.height as usize);
        let pixels = (width * height) as f64;
        let duration_s = us_to_s(self.last - first);
        let per_pixel_per_second =
            |n: u64| (duration_s > 0.0).then(|| n as f64 / (pixels * duration_s));
        let counts = self.pixels.counts(width, height);
        let active = counts.iter().filter(|&&c| c > 0).count();
        let hot = hot_pixels::find_hot_pixels(&counts, width, height, duration_s);
        let background_rate_hz = background_rate(&counts, width, &hot, duration_s);
        let off = self.events - self.on;
        Some(SequenceStats {
            width: sensor.sensor.width,
            height: sensor.sensor.height,
            sensor_source: sensor.source.clone(),
            events: self.events,
            on_events: self.on,
            off_events: off,
            on_fraction: self.on as f64 / self.events as f64,
            t_first_us: first,
            t_last_us: self.last,
            duration_s,
            events_per_pixel_per_second: per_pixel_per_second(self.events),
            on_per_pixel_per_second: per_pixel_per_second(self.on),
            off_per_pixel_per_second: per_pixel_per_second(off),
            active_pixel_fraction: active as f64 / pixels,
            rate_timeline: timeline::rate_timeline(
                &self.timeline,
                self.window_us,
                self.last - first,
                us_to_s(first - self.stream_first.unwrap_or(first)),
                pixels,
            ),
            hot_pixels: hot,
            hot_pixel_method: hot_pixels::METHOD,
            background_rate_hz,
            inter_event_interval_s: IntervalSummary {
                p5: self.intervals.quantile_us(0.05).map(|us| us * 1e-6),
                median: self.intervals.quantile_us(0.5).map(|us| us * 1e-6),
                count: self.intervals.total(),
                resolution: "histogram quantiles: exact below 128 us, above that within 1/128 (0.8 %) of the value",
            },
            frames: timeline::frame_summary(frame_times),
        })
    }
}

/// Median over all pixels, hot ones excluded, of events / duration.
fn background_rate(counts: &[u32], width: usize, hot: &[HotPixel], duration_s: f64) -> f64 {
    if duration_s <= 0.0 {
        return 0.0;
    }
    let mut kept: Vec<u32> = counts.to_vec();
    let mut hot_index: Vec<usize> = hot
        .iter()
        .map(|h| h.y as usize * width + h.x as usize)
        .collect();
    hot_index.sort_unstable();
    let mut write = 0;
    for (i, &c) in counts.iter().enumerate() {
        if hot_index.binary_search(&i).is_err() {
            kept[write] = c;
            write += 1;
        }
    }
    kept.truncate(write);
    if kept.is_empty() {
        return 0.0;
    }
    let mid = kept.len() / 2;
    let upper = *kept.select_nth_unstable(mid).1 as f64;
    let median = if kept.len() % 2 == 1 {
        upper
    } else {
        (*kept[..mid].iter().max().expect("len >= 2") as f64 + upper) / 2.0
    };
    median / duration_s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::events::Event;

    fn resolved(w: u16, h: u16) -> ResolvedSensor {
        ResolvedSensor {
            sensor: Sensor::new(w, h),
            source: "test".into(),
            warning: None,
        }
    }

    #[test]
    fn hand_computed_sequence() {
        // 2x2 sensor, 1 s: pixel (0,0) fires at 0, 0.5, 1.0 s; pixel (1,1) at 0.25 s (OFF)
        let chunk: EventChunk = [
            Event {
                t: 0,
                x: 0,
                y: 0,
                on: true,
            },
            Event {
                t: 250_000,
                x: 1,
                y: 1,
                on: false,
            },
            Event {
                t: 500_000,
                x: 0,
                y: 0,
                on: true,
            },
            Event {
                t: 1_000_000,
                x: 0,
                y: 0,
                on: false,
            },
        ]
        .into_iter()
        .collect();
        let options = StatsOptions {
            window_s: 0.5,
            ..Default::default()
        };
        let mut acc = StatsAccumulator::new(options, Some(Sensor::new(2, 2)));
        acc.add(&chunk);
        let s = acc.finish(&resolved(2, 2), &[0, 40_000, 80_000]).unwrap();
        assert_eq!((s.events, s.on_events, s.off_events), (4, 2, 2));
        assert_eq!(s.duration_s, 1.0);
        assert_eq!(s.events_per_pixel_per_second, Some(1.0));
        assert_eq!(s.active_pixel_fraction, 0.5);
        // two same-pixel intervals, both 0.5 s
        assert_eq!(s.inter_event_interval_s.count, 2);
        let median = s.inter_event_interval_s.median.unwrap();
        assert!((median - 0.5).abs() / 0.5 < intervals::RELATIVE_RESOLUTION);
        // windows [0, 0.5) and [0.5, 1.0]: 2 events each, over 4 pixels and 0.5 s
        assert_eq!(s.rate_timeline.len(), 2);
        assert_eq!(s.rate_timeline[0].events, 2);
        assert_eq!(s.rate_timeline[1].events, 2);
        assert_eq!(s.rate_timeline[1].events_per_pixel_per_second, 1.0);
        // per-pixel counts 3, 0, 0, 1 -> median 0.5 events over 1 s
        assert_eq!(s.background_rate_hz, 0.5);
        assert_eq!(
            s.frames,
            Some(FrameSummary {
                count: 3,
                median_interval_s: Some(0.04)
            })
        );
    }

    #[test]
    fn start_and_end_select_seconds_after_the_first_event() {
        let chunk: EventChunk = (0..10)
            .map(|i| Event {
                t: 1_000_000 + i * 100_000,
                x: 0,
                y: 0,
                on: i % 2 == 0,
            })
            .collect();
        let options = StatsOptions {
            start_s: Some(0.2),
            end_s: Some(0.5),
            window_s: 0.1,
        };
        let mut acc = StatsAccumulator::new(options, None);
        acc.add(&chunk);
        let s = acc.finish(&resolved(1, 1), &[]).unwrap();
        assert_eq!(s.events, 4);
        assert_eq!((s.t_first_us, s.t_last_us), (1_200_000, 1_500_000));
        assert!((s.rate_timeline[0].t_s - 0.2).abs() < 1e-12);
        assert_eq!(s.rate_timeline.len(), 3);
        assert_eq!(s.rate_timeline.iter().map(|w| w.events).sum::<u64>(), 4);
    }
}
