//! The rate timeline: events per pixel per second in consecutive windows from the first
//! selected event, and the frame timing summary.

use crate::events::{TimeUs, us_to_s};
use serde::Serialize;

/// One window of the rate timeline.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RateWindow {
    /// Window start, seconds after the first event.
    pub t_s: f64,
    /// Window length in seconds (the last window absorbs the remainder: between half and
    /// one and a half windows).
    pub window_s: f64,
    pub events: u64,
    /// Null for a window of zero length (the selected events span no time).
    pub events_per_pixel_per_second: Option<f64>,
}

/// A rate timeline and the window it used.
#[derive(Clone, Debug, PartialEq)]
pub struct Timeline {
    pub windows: Vec<RateWindow>,
    /// The window used, microseconds: the one asked for, or a whole multiple of it when
    /// that would have given more than [`MAX_WINDOWS`] windows.
    pub window_us: TimeUs,
}

impl Timeline {
    /// What was changed, when the window used is not the one asked for (`asked_us`).
    pub fn note(&self, asked_us: TimeUs) -> Option<String> {
        (self.window_us != asked_us).then(|| {
            format!(
                "windows of {} us asked for; {} us used: the selected span would have given more than {MAX_WINDOWS} windows",
                asked_us, self.window_us
            )
        })
    }
}

/// The most windows a rate timeline has; a longer recording (or one whose timestamps jump)
/// gets proportionally wider windows, so output stays bounded whatever the time span.
pub const MAX_WINDOWS: usize = 100_000;

/// Counts of the non-empty windows of a rate timeline, as `(window index, events)` in
/// increasing index order: memory follows the events, not the time span they cover.
#[derive(Clone, Debug, Default)]
pub struct SparseTimeline {
    pub windows: Vec<(u64, u64)>,
}

impl SparseTimeline {
    /// Adds `events` to window `index` (indices never decrease).
    #[inline]
    pub fn add(&mut self, index: u64, events: u64) {
        match self.windows.last_mut() {
            Some((last, count)) if *last == index => *count += events,
            _ => self.windows.push((index, events)),
        }
    }
}

/// Window rates over the selected span `span_us` from the sparse per-window counts of
/// `window_us` windows: the windows are `round(span / window)` (at least one) and the
/// remainder joins the last window, so every window is between half and one and a half
/// windows long. Beyond [`MAX_WINDOWS`] windows, `factor` windows are merged into one.
pub fn rate_timeline(
    counts: &SparseTimeline,
    window_us: TimeUs,
    span_us: TimeUs,
    offset_s: f64,
    pixels: f64,
) -> Timeline {
    let natural = ((span_us as f64 / window_us as f64).round() as u64).max(1);
    let factor = natural.div_ceil(MAX_WINDOWS as u64).max(1);
    let window_us = window_us.saturating_mul(factor as TimeUs);
    let windows = ((span_us as f64 / window_us as f64).round() as usize).clamp(1, MAX_WINDOWS);
    let mut merged = vec![0u64; windows];
    for &(index, events) in &counts.windows {
        let k = ((index / factor) as usize).min(windows - 1);
        merged[k] += events;
    }
    let n = merged.len();
    let windows = merged
        .iter()
        .enumerate()
        .map(|(k, &events)| {
            let length_us = if k + 1 < n {
                window_us
            } else {
                (span_us - (n as TimeUs - 1) * window_us).max(0)
            };
            let window_s = us_to_s(length_us);
            RateWindow {
                t_s: offset_s + us_to_s(k as TimeUs * window_us),
                window_s,
                events,
                events_per_pixel_per_second: (window_s > 0.0)
                    .then(|| events as f64 / (pixels * window_s)),
            }
        })
        .collect();
    Timeline { windows, window_us }
}

/// Frame timing.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameSummary {
    pub count: usize,
    pub median_interval_s: Option<f64>,
}

/// Count and median interval of the frame times of the selected window; `None` when the
/// recording has no frames (`recording_has_frames` false), a count of 0 when it has some but
/// none in the window.
pub fn frame_summary(times: &[TimeUs], recording_has_frames: bool) -> Option<FrameSummary> {
    if !recording_has_frames {
        return None;
    }
    let mut gaps: Vec<TimeUs> = times.windows(2).map(|w| w[1] - w[0]).collect();
    let median_interval_s = (!gaps.is_empty()).then(|| {
        gaps.sort_unstable();
        let n = gaps.len();
        let median = if n % 2 == 1 {
            gaps[n / 2] as f64
        } else {
            (gaps[n / 2 - 1] + gaps[n / 2]) as f64 / 2.0
        };
        median * 1e-6
    });
    Some(FrameSummary {
        count: times.len(),
        median_interval_s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_huge_gap_costs_no_memory_and_the_output_stays_bounded() {
        // two bursts 1e7 s apart: 1e9 windows of 10 ms
        let mut sparse = SparseTimeline::default();
        sparse.add(0, 5);
        sparse.add(0, 5);
        sparse.add(1_000_000_000, 7);
        assert_eq!(sparse.windows, vec![(0, 10), (1_000_000_000, 7)]);
        let span = 10_000_000_000_000; // 1e7 s in us
        let timeline = rate_timeline(&sparse, 10_000, span, 0.0, 1.0);
        // 1e9 natural windows merged by 10,000 into 100 s windows, and said
        assert_eq!(timeline.window_us, 100_000_000);
        assert_eq!(
            timeline.note(10_000).unwrap(),
            "windows of 10000 us asked for; 100000000 us used: the selected span would have given more than 100000 windows"
        );
        let windows = timeline.windows;
        assert_eq!(windows.len(), MAX_WINDOWS);
        assert_eq!(windows[0].events, 10);
        assert_eq!(windows.last().unwrap().events, 7);
        assert_eq!(windows.iter().map(|w| w.events).sum::<u64>(), 17);
        assert!(
            (windows[0].window_s - 100.0).abs() < 1e-9,
            "{}",
            windows[0].window_s
        );
    }

    #[test]
    fn a_zero_length_span_has_one_window_without_a_rate() {
        let mut sparse = SparseTimeline::default();
        sparse.add(0, 1);
        let timeline = rate_timeline(&sparse, 10_000, 0, 0.0, 100.0);
        assert_eq!(timeline.note(10_000), None);
        assert_eq!(
            timeline.windows,
            vec![RateWindow {
                t_s: 0.0,
                window_s: 0.0,
                events: 1,
                events_per_pixel_per_second: None
            }]
        );
    }

    #[test]
    fn frames_of_the_window_are_counted_and_a_window_without_frames_says_zero() {
        assert_eq!(frame_summary(&[], false), None);
        assert_eq!(
            frame_summary(&[], true),
            Some(FrameSummary {
                count: 0,
                median_interval_s: None
            })
        );
        assert_eq!(
            frame_summary(&[0, 40_000, 80_000, 130_000], true),
            Some(FrameSummary {
                count: 4,
                median_interval_s: Some(0.04)
            })
        );
    }
}
