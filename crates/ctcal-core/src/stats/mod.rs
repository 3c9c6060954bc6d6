//! Dataset statistics in one streaming pass: event counts and rates (events per pixel per
//! second, the quantity Stoffregen et al. 2020 match between real and simulated data), the
//! rate over time, active-pixel fraction, hot pixels, background activity and same-pixel
//! inter-event intervals.
//!
//! Background activity is counted as the background-activity filter of Delbruck (2008)
//! defines noise: an event is *supported* when one of its 8 neighbours fired within the
//! preceding support window (default 10 ms); unsupported events per pixel per second, hot
//! pixels excluded, is the background rate. (Edges moving over the sensor give their events
//! neighbours within milliseconds; leak and shot-noise events are isolated.)
//!
//! With a [`PixelSelection`] (region, mask, pixels left out) every per-pixel quantity is
//! taken over the kept pixels only; support still looks at every neighbour.
//!
//! Memory is bounded by the sensor (16 bytes per pixel), a fixed-size interval histogram and
//! the non-empty windows of the rate timeline, never by the time span a file claims; events
//! must arrive time-sorted. Per-pixel state covers the area the events reach, within
//! [`PIXEL_BUDGET`] pixels unless [`StatsOptions::max_pixels`] says otherwise: a sensor
//! claimed (or given) far larger than its events costs only what the events need.

pub mod binomial;
pub mod chance_support;
pub mod hot_pixels;
pub mod intervals;
pub mod jackknife;
mod kernel;
pub mod pixel_grid;
pub mod robust;
pub mod support;
pub mod timeline;

use crate::events::{EventChunk, Sensor, TimeUs, us_to_s};
use crate::selection::PixelSelection;
use hot_pixels::HotPixel;
use intervals::IntervalHistogram;
use kernel::WindowCounter;
use pixel_grid::PixelGrid;
pub use pixel_grid::{BYTES_PER_PIXEL, PIXEL_BUDGET};
use serde::Serialize;
use std::collections::BTreeMap;
pub use timeline::{FrameSummary, RateWindow};

/// How `background_rate_hz` is defined (reported with it).
pub const BACKGROUND_RATE_METHOD: &str = "events without spatio-temporal support (no event of any of the 8 neighbours in the preceding support window, Delbruck 2008's background-activity filter) per pixel per second, hot pixels excluded; the first support window after the first event (its events have no history to be judged by) is left out, its events and its time";

/// What to measure.
#[derive(Clone, Debug)]
pub struct StatsOptions {
    /// Keep events at or after this many seconds from the first event.
    pub start_s: Option<f64>,
    /// Keep events at or before this many seconds from the first event.
    pub end_s: Option<f64>,
    /// Width of the rate-timeline windows, seconds.
    pub window_s: f64,
    /// Support window of the background-activity count, seconds.
    pub support_window_s: f64,
    /// The pixels to measure (default: all).
    pub selection: Option<PixelSelection>,
    /// The time of the recording's first event, when the events added do not start there
    /// (a reader that seeked to `start_s`); `start_s`/`end_s` count from it.
    pub origin_us: Option<TimeUs>,
    /// The most pixels of per-pixel state to keep (`None`: no limit); events beyond it stop
    /// the pass ([`StatsAccumulator::over_budget`]).
    pub max_pixels: Option<usize>,
}

/// The events reach an area whose per-pixel state exceeds [`StatsOptions::max_pixels`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OverBudget {
    /// The largest coordinates seen when the budget was passed.
    pub max_x: u16,
    pub max_y: u16,
    /// Pixels of state that area needs, and the budget.
    pub pixels: u64,
    pub budget: usize,
}

impl OverBudget {
    /// Bytes of state the area needs.
    pub fn bytes(&self) -> u64 {
        self.pixels * BYTES_PER_PIXEL as u64
    }
}

impl Default for StatsOptions {
    fn default() -> Self {
        Self {
            start_s: None,
            end_s: None,
            window_s: 0.01,
            support_window_s: 0.01,
            selection: None,
            origin_us: None,
            max_pixels: Some(PIXEL_BUDGET),
        }
    }
}

/// Quantiles of same-pixel intervals between consecutive events (either polarity).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct IntervalSummary {
    pub p5: Option<f64>,
    pub median: Option<f64>,
    pub count: u64,
    /// Intervals of 0 us: an event at the same pixel and microsecond as the pixel's
    /// previous one. A camera's pixel does not fire twice within its refractory period
    /// (microseconds at the least), so these come from a simulator that gives all events of
    /// a step one time (ctcal's on-screen sample: 23,799 of 76,918 intervals) or from a
    /// writer or converter that duplicated events; every count and estimate takes them as
    /// real. `None` in results written before it was counted.
    pub zero: Option<u64>,
    /// How the quantiles were computed.
    pub resolution: &'static str,
}

/// Statistics of one event sequence (the `ctcal stats` JSON).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SequenceStats {
    /// Sensor biases saved in or beside the recording (filled by the caller that knows the
    /// files; absent when none are found).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub biases: Option<crate::biases::Biases>,
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
    /// The window the rate timeline uses, seconds: the one asked for, unless that would
    /// give more than [`timeline::MAX_WINDOWS`] windows (then a whole multiple of it, said
    /// under `rate_window_note`).
    pub rate_window_s: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rate_window_note: Option<String>,
    pub hot_pixels: Vec<HotPixel>,
    pub hot_pixel_method: &'static str,
    /// Background activity: unsupported events per pixel per second, hot pixels excluded
    /// (see [`BACKGROUND_RATE_METHOD`]); null (reason under `why`) when the duration is zero
    /// or every kept pixel is hot.
    pub background_rate_hz: Option<f64>,
    pub background_rate_method: &'static str,
    /// The support window of `background_rate_hz`, seconds.
    pub support_window_s: f64,
    /// Median over all pixels of each pixel's events / duration_s; null when the duration
    /// is zero.
    pub median_pixel_rate_hz: Option<f64>,
    pub inter_event_interval_s: IntervalSummary,
    pub frames: Option<FrameSummary>,
    /// Pixels every per-pixel quantity divides by (all of the sensor's, unless a region,
    /// mask or exclusion was applied), and what was applied.
    pub pixels_kept: u64,
    pub selection: String,
    /// Hot pixels left out before measuring (the caller's choice), as a first pass found
    /// them.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub excluded_hot_pixels: Vec<HotPixel>,
    /// Why each value reported as null is not determined (key: the field's name).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub why: BTreeMap<String, String>,
}

/// Accumulates statistics chunk by chunk.
pub struct StatsAccumulator {
    options: StatsOptions,
    window_us: TimeUs,
    support_us: TimeUs,
    stream_first: Option<TimeUs>,
    select_from: TimeUs,
    select_to: TimeUs,
    first: Option<TimeUs>,
    /// The first event fed to the kernel plus the support window: from then on every event
    /// has a whole window of history to be judged by (see [`background_rate`]).
    judged_from: Option<TimeUs>,
    last: TimeUs,
    events: u64,
    on: u64,
    pixels: PixelGrid,
    /// The sensor when known in advance (the grid grows towards it).
    sensor: Option<Sensor>,
    /// Set when the events passed the pixel budget (the pass then stops counting).
    over_budget: Option<OverBudget>,
    /// Scratch: pixel index of each event of the chunk being added, and whether it is kept.
    indices: Vec<u32>,
    kept: Vec<bool>,
    /// The selection as one flag per grid cell (border included), when there is one.
    kept_cells: Option<Vec<bool>>,
    intervals: IntervalHistogram,
    windows: WindowCounter,
}

impl StatsAccumulator {
    /// `sensor`: the sensor when known in advance (else the grid grows as events arrive).
    pub fn new(options: StatsOptions, sensor: Option<Sensor>) -> Self {
        let window_us = ((options.window_s * 1e6).round() as TimeUs).max(1);
        let support_us = ((options.support_window_s * 1e6).round() as TimeUs).max(0);
        // a selection fixes the sensor (and its grid); otherwise the sensor a file states
        // is not allocated up front: the grid grows to the area the events reach, within
        // it, so that memory follows the events and not a header's claim (a 1280 x 720
        // recording whose header claimed 4096 x 4096 took 546 MB instead of 46 MB)
        let sensor = options.selection.as_ref().map(|s| s.sensor()).or(sensor);
        let pixels = match (&options.selection, sensor) {
            (Some(_), Some(s)) => PixelGrid::new(s.width as usize, s.height as usize),
            _ => PixelGrid::default(),
        };
        let kept_cells = options.selection.as_ref().map(|selection| {
            let mut cells = vec![false; pixels.cells.len()];
            let width = selection.sensor().width as usize;
            for (i, &keep) in selection.kept_mask().iter().enumerate() {
                cells[pixels.index((i % width) as u16, (i / width) as u16)] = keep;
            }
            cells
        });
        Self {
            options,
            window_us,
            support_us,
            stream_first: None,
            select_from: TimeUs::MIN,
            select_to: TimeUs::MAX,
            first: None,
            judged_from: None,
            last: 0,
            events: 0,
            on: 0,
            pixels,
            sensor,
            over_budget: None,
            indices: Vec::new(),
            kept: Vec::new(),
            kept_cells,
            intervals: IntervalHistogram::default(),
            windows: WindowCounter::default(),
        }
    }

    /// Adds a time-sorted chunk (continuing the previous ones). Once the events pass the
    /// pixel budget ([`Self::over_budget`]) nothing more is counted.
    pub fn add(&mut self, chunk: &EventChunk) {
        if chunk.is_empty() || self.over_budget.is_some() {
            return;
        }
        if self.stream_first.is_none() {
            self.start_stream(chunk.t[0]);
        }
        let lo = chunk.t.partition_point(|&t| t < self.select_from);
        let hi = chunk.t.partition_point(|&t| t <= self.select_to);
        if lo >= hi {
            return;
        }
        let (ts, xs, ys) = (&chunk.t[lo..hi], &chunk.x[lo..hi], &chunk.y[lo..hi]);
        let on = &chunk.on[lo..hi];
        let max_x = xs.iter().copied().max().expect("non-empty");
        let max_y = ys.iter().copied().max().expect("non-empty");
        if !self.grow_to(max_x, max_y) {
            return;
        }
        if self.kept_cells.is_some() {
            self.add_selected(ts, xs, ys, on);
        } else {
            self.add_all(ts, xs, ys, on);
        }
    }

    /// Fixes the stream's origin at its first event `t_first` (or at
    /// [`StatsOptions::origin_us`]) and the selected time span from it.
    fn start_stream(&mut self, t_first: TimeUs) {
        let t0 = self.options.origin_us.unwrap_or(t_first);
        self.stream_first = Some(t0);
        if let Some(s) = self.options.start_s {
            self.select_from = t0 + (s * 1e6).round() as TimeUs;
        }
        if let Some(e) = self.options.end_s {
            self.select_to = t0 + (e * 1e6).round() as TimeUs;
        }
    }

    /// Sets the first counted event's time `t` and the end of its timeline window, unless
    /// an earlier event set them.
    fn note_first(&mut self, t: TimeUs) {
        if self.first.is_none() {
            self.first = Some(t);
            self.windows.end = t.saturating_add(self.window_us);
        }
    }

    /// Adds a selected, non-empty run of events without a pixel selection: every event
    /// counts.
    fn add_all(&mut self, ts: &[TimeUs], xs: &[u16], ys: &[u16], on: &[bool]) {
        self.note_first(ts[0]);
        self.accumulate::<false>(ts, xs, ys);
        self.events += ts.len() as u64;
        self.on += on.iter().map(|&p| p as u64).sum::<u64>();
        self.last = *ts.last().expect("non-empty");
    }

    /// Adds a selected, non-empty run of events with a pixel selection: every event
    /// updates its pixel (support, per-pixel counts), only the kept ones count towards the
    /// totals, the timeline and the intervals.
    fn add_selected(&mut self, ts: &[TimeUs], xs: &[u16], ys: &[u16], on: &[bool]) {
        self.flag_kept(xs, ys);
        if let Some(i) = self.kept.iter().position(|&k| k) {
            self.note_first(ts[i]);
        }
        self.accumulate::<true>(ts, xs, ys);
        let kept = &self.kept;
        self.events += kept.iter().filter(|&&k| k).count() as u64;
        self.on += on.iter().zip(kept).filter(|&(&p, &k)| p && k).count() as u64;
        if let Some(i) = kept.iter().rposition(|&k| k) {
            self.last = ts[i];
        }
    }

    /// Fills `kept` with whether each event's pixel is in the selection.
    fn flag_kept(&mut self, xs: &[u16], ys: &[u16]) {
        let (Some(kept_cells), grid) = (&self.kept_cells, &self.pixels) else {
            return;
        };
        self.kept.clear();
        self.kept.extend(
            xs.iter()
                .zip(ys)
                .map(|(&x, &y)| kept_cells[grid.index(x, y)]),
        );
    }

    /// The per-event kernel over one run of events (see [`kernel`]; with `SELECTED`,
    /// intervals and timeline only for the events `self.kept` flags).
    fn accumulate<const SELECTED: bool>(&mut self, ts: &[TimeUs], xs: &[u16], ys: &[u16]) {
        let stride = self.pixels.stride();
        kernel::cell_indices(xs, ys, stride, &mut self.indices);
        let support_us = self.support_us;
        let judged_from = *self
            .judged_from
            .get_or_insert_with(|| ts[0].saturating_add(support_us));
        let settings = kernel::Settings {
            stride,
            // (with a selection, only read for kept events, which set it)
            first: self.first.unwrap_or(0),
            support_us,
            judged_from,
            window_us: self.window_us,
        };
        kernel::accumulate::<SELECTED>(
            ts,
            &self.indices,
            &self.kept,
            &settings,
            &mut self.pixels,
            &mut self.intervals,
            &mut self.windows,
        );
    }

    /// Makes the grid hold pixel (`max_x`, `max_y`); `false` (and [`Self::over_budget`]
    /// set) when that takes more pixels than the budget.
    fn grow_to(&mut self, max_x: u16, max_y: u16) -> bool {
        let grid = &self.pixels;
        let need_w = (max_x as usize + 1).max(grid.width);
        let need_h = (max_y as usize + 1).max(grid.height);
        if need_w == grid.width && need_h == grid.height {
            return true;
        }
        let budget = self.options.max_pixels.unwrap_or(usize::MAX);
        let pixels = need_w.saturating_mul(need_h);
        if pixels > budget {
            self.over_budget = Some(OverBudget {
                max_x,
                max_y,
                pixels: pixels as u64,
                budget,
            });
            return false;
        }
        let side = crate::events::MAX_SENSOR_SIDE as usize;
        let limit = self
            .sensor
            .map_or((side, side), |s| (s.width as usize, s.height as usize));
        self.pixels.ensure_within(max_x, max_y, limit, budget);
        true
    }

    /// Whether the events passed the pixel budget ([`StatsOptions::max_pixels`]): the
    /// statistics are then incomplete and must not be reported.
    pub fn over_budget(&self) -> Option<OverBudget> {
        self.over_budget
    }

    /// Events selected so far.
    pub fn events(&self) -> u64 {
        self.events
    }

    /// Final statistics for `sensor` (how it is known: `sensor_source`), with the
    /// recording's frame times. `None` when no event was selected, or when the events
    /// passed the pixel budget (the counts are incomplete; see [`Self::over_budget`]).
    pub fn finish(
        mut self,
        sensor: Sensor,
        sensor_source: &str,
        frame_times: &[TimeUs],
    ) -> Option<SequenceStats> {
        if self.over_budget.is_some() {
            return None;
        }
        let first = self.first?;
        self.close_last_window();
        let selection = self.options.selection.take();
        // a selection fixes the sensor
        let sensor = selection.as_ref().map_or(sensor, |s| s.sensor());
        let area = KeptArea::new(sensor, &self.pixels, selection.as_ref());
        let kept_pixels = area.kept_pixels;
        let pixels = kept_pixels.max(1) as f64;
        let duration_s = us_to_s(self.last - first);
        let judged = Judged {
            seconds: us_to_s(self.last - self.judged_from.unwrap_or(first).max(first)),
            support_s: us_to_s(self.support_us),
        };
        let per_pixel = self.per_pixel(&area, duration_s, judged);
        let timeline = self.rate_timeline(first, pixels);
        let frames =
            timeline::frame_summary(&self.frames_selected(frame_times), !frame_times.is_empty());
        let why = undetermined(
            duration_s,
            &per_pixel.background_rate_hz,
            &timeline,
            frames.as_ref(),
        );
        let measured = Measured {
            sensor,
            first,
            duration_s,
            kept_pixels,
            pixels,
            per_pixel,
            timeline,
            frames,
            why,
            selection: selection.map_or_else(|| "the whole sensor".into(), |s| s.description()),
        };
        Some(self.assemble(sensor_source, measured))
    }

    /// Counts the window the last events fell in: the kernel stores a window only when an
    /// event passes its end.
    fn close_last_window(&mut self) {
        if self.windows.count > 0 {
            self.windows
                .timeline
                .add(self.windows.index, self.windows.count);
        }
    }

    /// The per-pixel results over the kept pixels of `area`: the active pixels (at least
    /// one event), the hot pixels (see [`hot_pixels`]; each judged against its real
    /// neighbours, kept or not), the background rate (Delbruck 2008's unsupported events,
    /// see [`background_rate`]) and the median pixel rate (the kept pixels outside the
    /// area, without events, counted as zeros).
    fn per_pixel(&self, area: &KeptArea, duration_s: f64, judged: Judged) -> PixelResults {
        let all_counts = self.pixels.counts(area.width, area.height);
        let unsupported = self.pixels.map(area.width, area.height, |c| c.unsupported);
        let counts: Vec<u32> = (0..all_counts.len())
            .filter(|&i| area.keeps(i))
            .map(|i| all_counts[i])
            .collect();
        // kept pixels outside the area: no events
        let silent = area.kept_pixels - counts.len();
        let active = counts.iter().filter(|&&c| c > 0).count();
        // hot pixels are judged against their real neighbours, kept or not
        let hot: Vec<HotPixel> =
            hot_pixels::find_hot_pixels(&all_counts, area.width, area.height, duration_s)
                .into_iter()
                .filter(|h| area.keeps(h.y as usize * area.width + h.x as usize))
                .collect();
        let keep = |i: usize| area.keeps(i);
        let background_rate_hz = background_rate(
            &unsupported,
            area.width,
            &hot,
            (duration_s, judged),
            &keep,
            area.kept_pixels,
        );
        let median_pixel_rate_hz = median_rate(&counts, silent, duration_s);
        PixelResults {
            active,
            hot,
            background_rate_hz,
            median_pixel_rate_hz,
        }
    }

    /// The rate timeline: events per kept pixel (`pixels`) per second in windows of
    /// `window_us` from the first selected event (`first`), each window's `t_s` offset by
    /// the time from the stream's first event to it (a `--start` window).
    fn rate_timeline(&self, first: TimeUs, pixels: f64) -> timeline::Timeline {
        timeline::rate_timeline(
            &self.windows.timeline,
            self.window_us,
            self.last - first,
            us_to_s(first - self.stream_first.unwrap_or(first)),
            pixels,
        )
    }

    /// Quantiles of the same-pixel inter-event intervals, read from their histogram.
    fn interval_summary(&self) -> IntervalSummary {
        IntervalSummary {
            p5: self.intervals.quantile_us(0.05).map(|us| us * 1e-6),
            median: self.intervals.quantile_us(0.5).map(|us| us * 1e-6),
            count: self.intervals.total(),
            zero: Some(self.intervals.zeros()),
            resolution: "histogram quantiles: exact below 128 us, above that within 1/128 (0.8 %) of the value",
        }
    }

    /// The `ctcal stats` JSON of what [`Self::finish`] measured: the event totals, each
    /// also per kept pixel per second (`events / (pixels * duration_s)`, the rate
    /// Stoffregen et al. 2020 match between real and simulated data; null over no time),
    /// the per-pixel results, the timeline and the interval quantiles.
    fn assemble(self, sensor_source: &str, m: Measured) -> SequenceStats {
        let (pixels, duration_s) = (m.pixels, m.duration_s);
        let per_pixel_per_second =
            |n: u64| (duration_s > 0.0).then(|| n as f64 / (pixels * duration_s));
        let off = self.events - self.on;
        SequenceStats {
            biases: None,
            width: m.sensor.width,
            height: m.sensor.height,
            sensor_source: sensor_source.to_string(),
            events: self.events,
            on_events: self.on,
            off_events: off,
            on_fraction: self.on as f64 / self.events as f64,
            t_first_us: m.first,
            t_last_us: self.last,
            duration_s,
            events_per_pixel_per_second: per_pixel_per_second(self.events),
            on_per_pixel_per_second: per_pixel_per_second(self.on),
            off_per_pixel_per_second: per_pixel_per_second(off),
            active_pixel_fraction: m.per_pixel.active as f64 / pixels,
            rate_window_s: us_to_s(m.timeline.window_us),
            rate_window_note: m.timeline.note(self.window_us),
            rate_timeline: m.timeline.windows,
            hot_pixels: m.per_pixel.hot,
            hot_pixel_method: hot_pixels::METHOD,
            background_rate_hz: m.per_pixel.background_rate_hz.ok(),
            background_rate_method: BACKGROUND_RATE_METHOD,
            support_window_s: us_to_s(self.support_us),
            median_pixel_rate_hz: m.per_pixel.median_pixel_rate_hz,
            pixels_kept: m.kept_pixels as u64,
            selection: m.selection,
            excluded_hot_pixels: Vec::new(),
            inter_event_interval_s: self.interval_summary(),
            frames: m.frames,
            why: m.why,
        }
    }

    /// The frame times within the selected time window (all of them without one).
    fn frames_selected(&self, frame_times: &[TimeUs]) -> Vec<TimeUs> {
        frame_times
            .iter()
            .copied()
            .filter(|t| (self.select_from..=self.select_to).contains(t))
            .collect()
    }
}

/// The pixels [`StatsAccumulator::finish`] measures: the kept ones (the whole sensor's, or
/// a selection's), over the area of the grid that holds per-pixel state.
struct KeptArea<'a> {
    selection: Option<&'a PixelSelection>,
    /// The sensor's width (a row of the selection's mask).
    sensor_width: usize,
    /// The area the per-pixel maps cover (where events are; the rest of the sensor has
    /// none): the whole sensor unless it was too large to allocate.
    width: usize,
    height: usize,
    /// Pixels kept: every per-pixel quantity divides by them.
    kept_pixels: usize,
}

impl<'a> KeptArea<'a> {
    fn new(sensor: Sensor, grid: &PixelGrid, selection: Option<&'a PixelSelection>) -> Self {
        let (width, height) = (sensor.width as usize, sensor.height as usize);
        Self {
            selection,
            sensor_width: width,
            width: width.min(grid.width),
            height: height.min(grid.height),
            kept_pixels: selection.map_or(width * height, |s| s.kept()),
        }
    }

    /// Whether the pixel at index `i` of the area is kept.
    fn keeps(&self, i: usize) -> bool {
        self.selection
            .is_none_or(|s| s.kept_mask()[(i / self.width) * self.sensor_width + i % self.width])
    }
}

/// The per-pixel results of [`StatsAccumulator::finish`], over the kept pixels.
struct PixelResults {
    /// Kept pixels with at least one event.
    active: usize,
    hot: Vec<HotPixel>,
    /// Unsupported events per pixel per second, or why it is not determined.
    background_rate_hz: Result<f64, String>,
    median_pixel_rate_hz: Option<f64>,
}

/// What [`StatsAccumulator::finish`] measured, before [`StatsAccumulator::assemble`] lays
/// it out with the accumulator's totals.
struct Measured {
    /// The sensor (a selection's, when there is one).
    sensor: Sensor,
    /// The first selected event's time.
    first: TimeUs,
    duration_s: f64,
    kept_pixels: usize,
    /// The kept pixels as every per-pixel rate's divisor (at least 1).
    pixels: f64,
    per_pixel: PixelResults,
    timeline: timeline::Timeline,
    frames: Option<FrameSummary>,
    why: BTreeMap<String, String>,
    /// The selection's description.
    selection: String,
}

/// Why a rate of events that span no time is not determined.
const NO_DURATION: &str = "the selected events span no time (first and last at the same microsecond): a rate needs a duration";

/// Why each value the statistics leave null is not determined.
fn undetermined(
    duration_s: f64,
    background_rate_hz: &Result<f64, String>,
    timeline: &timeline::Timeline,
    frames: Option<&FrameSummary>,
) -> BTreeMap<String, String> {
    let mut why = BTreeMap::new();
    if duration_s <= 0.0 {
        for key in [
            "events_per_pixel_per_second",
            "on_per_pixel_per_second",
            "off_per_pixel_per_second",
            "median_pixel_rate_hz",
        ] {
            why.insert(key.to_string(), NO_DURATION.to_string());
        }
    }
    if let Err(reason) = background_rate_hz {
        why.insert("background_rate_hz".into(), reason.clone());
    }
    if timeline
        .windows
        .iter()
        .any(|w| w.events_per_pixel_per_second.is_none())
    {
        why.insert(
            "rate_timeline".into(),
            "a window of zero length (the selected events span no time) has no rate".into(),
        );
    }
    if let Some(f) = frames.filter(|f| f.count < 2) {
        why.insert(
            "frames.median_interval_s".into(),
            format!(
                "{} frame(s) in the selected time window: an interval needs two",
                f.count
            ),
        );
    }
    why
}

/// The time over which events are judged as supported or not: the selected span less the
/// first support window after the first event fed (those events have no history yet, and
/// every one of them would count as unsupported: on the 13 ms IJRR boxes chunk 3,456 of
/// the 3,562 unsupported events, a rate of 6.2 Hz per pixel where the rest of it shows
/// 0.75), seconds, and the window.
#[derive(Clone, Copy, Debug)]
struct Judged {
    seconds: f64,
    support_s: f64,
}

/// Unsupported events per pixel per second over the kept pixels that are not hot (`hot`
/// holds kept pixels only), over the time `judged` (the events of the first support window
/// are not counted by the kernel).
fn background_rate(
    unsupported: &[u32],
    width: usize,
    hot: &[HotPixel],
    (duration_s, judged): (f64, Judged),
    keep: &impl Fn(usize) -> bool,
    kept_pixels: usize,
) -> Result<f64, String> {
    if duration_s <= 0.0 {
        return Err(NO_DURATION.into());
    }
    if judged.seconds <= 0.0 {
        return Err(format!(
            "the selected events span {duration_s:.6} s, within the first support window ({:.3} ms) after the first event: no event has a window of history to be judged by",
            judged.support_s * 1e3
        ));
    }
    let hot_events: u64 = hot
        .iter()
        .map(|h| unsupported[h.y as usize * width + h.x as usize] as u64)
        .sum();
    let total: u64 = (0..unsupported.len())
        .filter(|&i| keep(i))
        .map(|i| unsupported[i] as u64)
        .sum();
    let kept = kept_pixels - hot.len();
    if kept == 0 {
        return Err(format!(
            "every one of the {kept_pixels} kept pixel(s) is hot: no pixel is left to measure background activity on"
        ));
    }
    Ok((total - hot_events) as f64 / (kept as f64 * judged.seconds))
}

/// Median over all pixels of events / duration: the pixels of `counts` and `zeros` more
/// without events.
fn median_rate(counts: &[u32], zeros: usize, duration_s: f64) -> Option<f64> {
    let n = counts.len() + zeros;
    if duration_s <= 0.0 || n == 0 {
        return None;
    }
    // in sorted order the extra zeros come first (no count is smaller)
    let mut sorted = counts.to_vec();
    let mut nth = |k: usize| -> f64 {
        if k < zeros {
            0.0
        } else {
            *sorted.select_nth_unstable(k - zeros).1 as f64
        }
    };
    let mid = n / 2;
    let median = if n % 2 == 1 {
        nth(mid)
    } else {
        (nth(mid - 1) + nth(mid)) / 2.0
    };
    Some(median / duration_s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::events::Event;

    fn event(t: TimeUs, x: u16, y: u16) -> Event {
        Event { t, x, y, on: true }
    }

    #[test]
    fn support_needs_a_neighbour_within_the_window_before() {
        // a 4x3 sensor; window 10 ms
        let chunk: EventChunk = [
            event(0, 1, 1),       // alone, but within the first window: not judged
            event(5_000, 2, 2),   // diagonal neighbour 5 ms before: supported
            event(5_000, 0, 0),   // neighbour (1,1) 5 ms before: supported
            event(30_000, 3, 0),  // neighbours (2,1),(2,0),(3,1) never fired: unsupported
            event(31_000, 1, 1),  // own pixel fired before, neighbours 26 ms ago: unsupported
            event(32_000, 0, 1),  // (1,1) 1 ms before: supported
            event(100_000, 3, 2), // (2,2) fired 95 ms ago: unsupported
        ]
        .into_iter()
        .collect();
        let mut acc = StatsAccumulator::new(StatsOptions::default(), Some(Sensor::new(4, 3)));
        acc.add(&chunk);
        let s = acc.finish(Sensor::new(4, 3), "test", &[]).unwrap();
        // 3 unsupported events over 12 pixels and the 0.09 s after the first window
        let background = s.background_rate_hz.unwrap();
        assert!(
            (background - 3.0 / (12.0 * 0.09)).abs() < 1e-12,
            "{background}"
        );
        assert_eq!(s.support_window_s, 0.01);
    }

    /// Events of the first support window after the first event have no history to be
    /// judged by: a recording that ends inside it has no background rate, with why.
    #[test]
    fn a_recording_within_its_first_support_window_has_no_background_rate() {
        let chunk: EventChunk = [event(0, 1, 1), event(4_000, 3, 0), event(9_999, 0, 2)]
            .into_iter()
            .collect();
        let mut acc = StatsAccumulator::new(StatsOptions::default(), Some(Sensor::new(4, 3)));
        acc.add(&chunk);
        let s = acc.finish(Sensor::new(4, 3), "test", &[]).unwrap();
        assert_eq!(s.background_rate_hz, None);
        assert!(
            s.why["background_rate_hz"].contains("within the first support window (10.000 ms)"),
            "{:?}",
            s.why
        );
        assert!(s.events_per_pixel_per_second.is_some());
    }

    /// Support across a grid that grows (no sensor size given): pixels (63, 0) and (1, 63)
    /// fire while the grid is 64 x 64, so their neighbours (64, 0) and (1, 64) are border
    /// cells; the grid then grows over them, and their events 9.95 ms later are supported.
    #[test]
    fn support_holds_across_a_grid_that_grows_over_the_border() {
        let mut acc = StatsAccumulator::new(StatsOptions::default(), None);
        let first = [event(0, 0, 5), event(100, 63, 0), event(200, 1, 63)];
        acc.add(&first.into_iter().collect());
        assert_eq!((acc.pixels.width, acc.pixels.height), (64, 64));
        // 9.95 ms after their neighbours, just past the first window: judged, supported
        let then = [
            event(10_050, 64, 0),
            event(10_150, 1, 64),
            event(100_000, 0, 5),
        ];
        acc.add(&then.into_iter().collect());
        assert!(acc.pixels.width > 64 && acc.pixels.height > 64);
        let s = acc.finish(Sensor::new(65, 65), "test", &[]).unwrap();
        // the first three fall in the first window (not judged); the two after the growth
        // are supported; (0, 5) 100 ms after itself is not: 1 over 4225 pixels and the
        // 0.09 s after the first window (with the support lost in the growth, the two at
        // 10.05 and 10.15 ms would count too)
        let background = s.background_rate_hz.unwrap();
        assert!(
            (background - 1.0 / (4225.0 * 0.09)).abs() < 1e-12,
            "{background}"
        );
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
        let s = acc
            .finish(Sensor::new(2, 2), "test", &[0, 40_000, 80_000])
            .unwrap();
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
        assert_eq!(s.rate_timeline[1].events_per_pixel_per_second, Some(1.0));
        // per-pixel counts 3, 0, 0, 1 -> median 0.5 events over 1 s
        assert_eq!(s.median_pixel_rate_hz, Some(0.5));
        // (1,1) at 0.25 s has no neighbour event in the 10 ms before it, nor have the two
        // later events of (0,0) (its neighbour (1,1) fired 250 ms before 0.5 s); the first,
        // at 0, is in the first window and not judged: 3 unsupported events over 4 pixels
        // and the 0.99 s after that window
        let background = s.background_rate_hz.unwrap();
        assert!(
            (background - 3.0 / (4.0 * 0.99)).abs() < 1e-12,
            "{background}"
        );
        assert!(s.why.is_empty(), "{:?}", s.why);
        assert_eq!(
            s.frames,
            Some(FrameSummary {
                count: 3,
                median_interval_s: Some(0.04)
            })
        );
    }

    #[test]
    fn a_huge_sensor_costs_only_the_area_its_events_reach() {
        let chunk: EventChunk = (0..200)
            .map(|i| Event {
                t: i * 1000,
                x: (i % 7) as u16,
                y: (i % 5) as u16,
                on: i % 3 == 0,
            })
            .collect();
        let small = Sensor::new(8, 6);
        let huge = Sensor::new(65_535, 65_535);
        let mut a = StatsAccumulator::new(StatsOptions::default(), Some(small));
        a.add(&chunk);
        let a = a.finish(small, "small", &[]).unwrap();
        let mut b = StatsAccumulator::new(StatsOptions::default(), Some(huge));
        b.add(&chunk);
        assert!(b.over_budget().is_none());
        assert!(b.pixels.cells.len() < 10_000, "{}", b.pixels.cells.len());
        // a stated sensor within the budget is not allocated up front either: a header's
        // 4096 x 4096 over events in a corner (it took 0.5 GB)
        let mut stated =
            StatsAccumulator::new(StatsOptions::default(), Some(Sensor::new(4096, 4096)));
        stated.add(&chunk);
        assert!(
            stated.pixels.cells.len() < 10_000,
            "{}",
            stated.pixels.cells.len()
        );
        let b = b.finish(huge, "huge", &[]).unwrap();
        assert_eq!(b.events, a.events);
        assert_eq!(b.hot_pixels, a.hot_pixels);
        assert_eq!(b.inter_event_interval_s, a.inter_event_interval_s);
        let scale = small.pixels() as f64 / huge.pixels() as f64;
        assert!((b.active_pixel_fraction - a.active_pixel_fraction * scale).abs() < 1e-15);
        let (ba, bb) = (a.background_rate_hz.unwrap(), b.background_rate_hz.unwrap());
        assert!((bb - ba * scale).abs() < 1e-12);
        assert_eq!(b.median_pixel_rate_hz, Some(0.0));
        // events far apart on the huge sensor pass the budget: the pass stops
        let far: EventChunk = [event(0, 1, 1), event(10, 60_000, 60_000)]
            .into_iter()
            .collect();
        let mut c = StatsAccumulator::new(StatsOptions::default(), Some(huge));
        c.add(&far);
        let over = c.over_budget().unwrap();
        assert_eq!((over.max_x, over.max_y), (60_000, 60_000));
        assert!(over.bytes() > 100_000_000_000);
        // unless there is no budget
        let options = StatsOptions {
            max_pixels: None,
            ..Default::default()
        };
        let mut d = StatsAccumulator::new(options, Some(Sensor::new(5000, 2)));
        d.add(&[event(0, 4999, 1)].into_iter().collect());
        assert!(d.over_budget().is_none());
    }

    #[test]
    fn median_counts_the_pixels_without_events() {
        assert_eq!(median_rate(&[4, 2, 8], 0, 1.0), Some(4.0));
        assert_eq!(median_rate(&[4, 2, 8], 1, 1.0), Some(3.0));
        assert_eq!(median_rate(&[4, 2, 8], 2, 2.0), Some(1.0));
        assert_eq!(median_rate(&[], 3, 1.0), Some(0.0));
        assert_eq!(median_rate(&[6, 6], 0, 2.0), Some(3.0));
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
            ..Default::default()
        };
        let mut acc = StatsAccumulator::new(options, None);
        acc.add(&chunk);
        let s = acc.finish(Sensor::new(1, 1), "test", &[]).unwrap();
        assert_eq!(s.events, 4);
        assert_eq!((s.t_first_us, s.t_last_us), (1_200_000, 1_500_000));
        assert!((s.rate_timeline[0].t_s - 0.2).abs() < 1e-12);
        assert_eq!(s.rate_timeline.len(), 3);
        assert_eq!(s.rate_timeline.iter().map(|w| w.events).sum::<u64>(), 4);
    }

    #[test]
    fn a_window_of_one_instant_leaves_its_rates_null_and_says_why() {
        let chunk: EventChunk = [event(0, 0, 0), event(500_000, 1, 1), event(900_000, 0, 1)]
            .into_iter()
            .collect();
        let options = StatsOptions {
            start_s: Some(0.5),
            end_s: Some(0.5),
            ..StatsOptions::default()
        };
        let mut acc = StatsAccumulator::new(options, Some(Sensor::new(2, 2)));
        acc.add(&chunk);
        // frames at 0.2, 0.4, 0.6 s: none in the window
        let s = acc
            .finish(Sensor::new(2, 2), "test", &[200_000, 400_000, 600_000])
            .unwrap();
        assert_eq!((s.events, s.duration_s), (1, 0.0));
        assert_eq!(s.events_per_pixel_per_second, None);
        assert_eq!(s.background_rate_hz, None);
        assert_eq!(s.median_pixel_rate_hz, None);
        assert_eq!(s.rate_timeline.len(), 1);
        assert_eq!(s.rate_timeline[0].events_per_pixel_per_second, None);
        assert_eq!(
            s.frames,
            Some(FrameSummary {
                count: 0,
                median_interval_s: None
            })
        );
        let keys: Vec<&str> = s.why.keys().map(String::as_str).collect();
        assert_eq!(
            keys,
            [
                "background_rate_hz",
                "events_per_pixel_per_second",
                "frames.median_interval_s",
                "median_pixel_rate_hz",
                "off_per_pixel_per_second",
                "on_per_pixel_per_second",
                "rate_timeline"
            ]
        );
    }

    #[test]
    fn frames_are_counted_in_the_selected_window() {
        let chunk: EventChunk = (0..10).map(|i| event(i * 100_000, 0, 0)).collect();
        let options = StatsOptions {
            start_s: Some(0.15),
            end_s: Some(0.65),
            ..StatsOptions::default()
        };
        let mut acc = StatsAccumulator::new(options, Some(Sensor::new(1, 1)));
        acc.add(&chunk);
        let frames: Vec<TimeUs> = (0..10).map(|i| i * 100_000 + 50_000).collect();
        let s = acc.finish(Sensor::new(1, 1), "test", &frames).unwrap();
        // frames at 0.15, 0.25, ..., 0.65 s are inside [0.15, 0.65]
        let frames = s.frames.unwrap();
        assert_eq!(frames.count, 6);
        assert!((frames.median_interval_s.unwrap() - 0.1).abs() < 1e-12);
    }
}
