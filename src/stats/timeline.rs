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
    pub events_per_pixel_per_second: f64,
}

/// Window rates over the selected span `span_us` from per-window `counts`; the windows are
/// `round(span / window)` (at least one) and the remainder joins the last window, so every
/// window is between half and one and a half windows long.
pub fn rate_timeline(
    counts: &[u64],
    window_us: TimeUs,
    span_us: TimeUs,
    offset_s: f64,
    pixels: f64,
) -> Vec<RateWindow> {
    let windows = ((span_us as f64 / window_us as f64).round() as usize).max(1);
    let mut merged: Vec<u64> = counts.iter().take(windows).copied().collect();
    let tail: u64 = counts.iter().skip(windows).sum();
    if let Some(last) = merged.last_mut() {
        *last += tail;
    }
    let n = merged.len();
    merged
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
                events_per_pixel_per_second: if window_s > 0.0 {
                    events as f64 / (pixels * window_s)
                } else {
                    0.0
                },
            }
        })
        .collect()
}

/// Frame timing.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameSummary {
    pub count: usize,
    pub median_interval_s: Option<f64>,
}

/// Count and median interval of the frame times.
pub fn frame_summary(times: &[TimeUs]) -> Option<FrameSummary> {
    if times.is_empty() {
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
