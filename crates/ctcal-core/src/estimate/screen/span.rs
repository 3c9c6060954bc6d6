//! Whether the stimulus given covers what the screen showed while the camera recorded.
//! `estimate screen` counts the events of each refresh interval of the stimulus, aligned to
//! the recording; a recording that goes on changing beyond the stimulus's span (a stimulus
//! file shorter than what was shown, or played in a loop) lets the alignment land on any
//! stretch that resembles it, and the last interval catch the next, unknown refresh. On a
//! checkerboard recording with its first 2, 5 and 12 stimulus frames given, thresholds of
//! 0.3 read 0.09, 0.16 and 0.21 with intervals excluding 0.3.

use super::super::EstimateError;
use crate::events::{EventChunk, Frame, TimeUs};

/// The event rate beyond the stimulus's span, as a share of the rate within it, above which
/// the screen is taken to have gone on changing there: a screen held still or dark between
/// recordings leaves the sensor's noise, a small share of the bursts at every refresh.
pub const OUTSIDE_RATE_SHARE: f64 = 0.25;

/// The share of the events beyond the stimulus's span under which it is not checked (a lead
/// in or out of a few refreshes).
const OUTSIDE_EVENT_SHARE: f64 = 0.05;

/// Refuses a recording whose events beyond the aligned stimulus's span (from half a
/// refresh before its first frame to a refresh and a half after its last, as the counts
/// run) come at [`OUTSIDE_RATE_SHARE`] of the rate within it or more, and are more than
/// [`OUTSIDE_EVENT_SHARE`] of the events.
pub fn check(
    events: &EventChunk,
    stimulus: &[Frame],
    offset_us: TimeUs,
    refresh_hz: f64,
) -> Result<(), EstimateError> {
    let (Some(first), Some(last)) = (stimulus.first(), stimulus.last()) else {
        return Ok(());
    };
    if events.is_empty() {
        return Ok(());
    }
    let period = 1e6 / refresh_hz;
    let start = offset_us + first.t - (0.5 * period).round() as TimeUs;
    let end = offset_us + last.t + (1.5 * period).round() as TimeUs;
    let (t0, t1) = (events.t[0], events.t[events.len() - 1]);
    let inside_s = (end.min(t1) - start.max(t0)).max(1) as f64 * 1e-6;
    let outside_s = ((t1 - t0) as f64 * 1e-6 - inside_s).max(1e-6);
    let inside = events.t.partition_point(|&t| t < end) - events.t.partition_point(|&t| t < start);
    let outside = events.len() - inside;
    let (inside_rate, outside_rate) = (inside as f64 / inside_s, outside as f64 / outside_s);
    if (outside as f64) <= OUTSIDE_EVENT_SHARE * events.len() as f64
        || outside_rate < OUTSIDE_RATE_SHARE * inside_rate
    {
        return Ok(());
    }
    Err(EstimateError::new(
        format!(
            "the recording goes on changing beyond the stimulus given: {outside} of its {} events lie outside the stimulus's {:.3} s as aligned ({:.0} events/s there against {:.0} within it), so the stimulus is shorter than what the screen showed and its alignment is not unique",
            events.len(),
            (last.t - first.t) as f64 * 1e-6,
            outside_rate,
            inside_rate
        ),
        "give the whole stimulus the screen showed, or cut the recording to the stimulus's span",
    ))
}
