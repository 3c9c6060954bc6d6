//! Each pixel's rate of log-intensity change per frame interval, the axis of the fit's
//! count cells, read from 8-bit frames without the frames' quantisation deciding it.
//!
//! A frame difference resolves changes of one grey level: ln((m + 0.5) / (m - 0.5)) in
//! log intensity at m DN, 0.1 at 10 DN. Over one interval of a 79 Hz recording that is a
//! rate of 7.9 per second, above the top edge of the change bins, so a dim pixel's
//! interval reads either as still (no grey level crossed) or as fast (one crossed), and
//! which of the two flips from frame to frame. A recording's events fire when the scene's
//! log intensity crosses a threshold, which need not be in the interval where the
//! quantised frames step; a re-simulation from the frames fires where they step. The
//! two then fill different cells although they make the same events, and the difference
//! grows in the dark as a simulated low-pass would shape it (fresh draw 6017, a 10 DN
//! scene rendered without quantisation: the fit added a 252 Hz bandwidth the draw does
//! not have).
//!
//! The rate is therefore the total variation of the frames' log intensity per second over
//! a window centred on the interval, widened one interval on each side (within the run of
//! consecutive used intervals) until it holds at least [`STEPS`] grey-level steps of
//! change or reaches [`MAX_HALF_WIDTH`] intervals a side: a pixel that changes by several
//! grey levels per interval keeps its own interval's rate, a slow one is measured over as
//! many intervals as its grey levels need (the change-rate estimate of a quantised signal
//! is the change counted over the time it takes to cross a few quanta). The frames' grey
//! levels are whole numbers (every reader delivers 8-bit frames), so the step is known,
//! not a prior.

use super::{CHANGE_EDGES, bin_of};
use crate::estimate::frames::PreparedFrames;
use rayon::prelude::*;

/// Grey-level steps of change a rate is measured over, at least (where the window allows).
pub const STEPS: f32 = 2.0;
/// Widest window: this many intervals on each side of the interval measured.
pub const MAX_HALF_WIDTH: usize = 8;

/// The change bin ([`CHANGE_EDGES`]) of every pixel in every interval of the run of
/// consecutive used intervals `first..end`, indexed `[interval - first][pixel]`.
pub fn run_change_bins(frames: &PreparedFrames, first: usize, end: usize) -> Vec<Vec<u8>> {
    let (w, h) = (frames.width, frames.height);
    let seconds: Vec<f32> = (first..end)
        .map(|k| ((frames.times[k + 1] - frames.times[k]) as f32 * 1e-6).max(1e-6))
        .collect();
    // row by row on every core, each row's bins for the whole run (`[interval * w + x]`)
    let rows: Vec<Vec<u8>> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut bins = vec![0u8; (end - first) * w];
            let mut changes = vec![0.0f32; end - first];
            let mut logs = vec![0.0f32; end - first + 1];
            for x in 0..w {
                let p = y * w + x;
                // each frame's log once (it ends one interval and starts the next)
                for (log, k) in logs.iter_mut().zip(first..=end) {
                    *log = frames.log(frames.dn[k].data[p]);
                }
                for (change, pair) in changes.iter_mut().zip(logs.windows(2)) {
                    *change = (pair[1] - pair[0]).abs();
                }
                for (i, k) in (first..end).enumerate() {
                    let middle = 0.5 * (frames.dn[k].data[p] + frames.dn[k + 1].data[p]);
                    let enough = STEPS * grey_level_step(frames, middle);
                    let rate = windowed_rate(&changes, &seconds, i, enough);
                    bins[i * w + x] = bin_of(&CHANGE_EDGES, rate);
                }
            }
            bins
        })
        .collect();
    (0..end - first)
        .map(|i| {
            rows.iter()
                .flat_map(|row| row[i * w..(i + 1) * w].iter().copied())
                .collect()
        })
        .collect()
}

/// The log-intensity step of one grey level at `dn` (with the frames' offset).
fn grey_level_step(frames: &PreparedFrames, dn: f32) -> f32 {
    let dn = dn.max(1.0);
    frames.log(dn + 0.5) - frames.log(dn - 0.5)
}

/// The change per second over the window centred on interval `i`, widened until it holds
/// `enough` change or [`MAX_HALF_WIDTH`] intervals a side (less at the run's ends).
///
/// Only intervals that change by less than `enough` on their own join the window: one
/// that changes by more has a rate the frames resolve alone (an edge passing, a fast
/// change), which is not the slow drift being measured, so a side stops before it (a
/// still pixel beside an edge's transit stays still).
///
/// Where the last widening brought in the change that made it enough, the grey level was
/// crossed somewhere inside the intervals it added, on average at their middle, so half of
/// what they added is counted (a window stopped on a step would otherwise overstate a
/// slow pixel's rate by up to the share of that step, 1.6x on a staircase).
fn windowed_rate(changes: &[f32], seconds: &[f32], i: usize, enough: f32) -> f32 {
    let (mut change, mut time) = (changes[i], seconds[i]);
    // each side's next interval while it may still widen
    let mut before = i.checked_sub(1);
    let mut after = Some(i + 1).filter(|&j| j < changes.len());
    let mut side = 1;
    while change < enough && side <= MAX_HALF_WIDTH {
        let mut added = 0.0;
        for next in [&mut before, &mut after] {
            let Some(j) = *next else { continue };
            if changes[j] >= enough {
                *next = None;
                continue;
            }
            added += changes[j];
            time += seconds[j];
            *next = if j < i {
                j.checked_sub(1)
            } else {
                Some(j + 1).filter(|&j| j < changes.len())
            };
        }
        if before.is_none() && after.is_none() && added == 0.0 {
            break;
        }
        change += added;
        if change >= enough {
            return (change - 0.5 * added) / time;
        }
        side += 1;
    }
    change / time
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pixel_that_steps_every_interval_keeps_its_own_rate() {
        let changes = [0.3, 0.3, 0.3, 0.3];
        let seconds = [0.01; 4];
        assert!((windowed_rate(&changes, &seconds, 1, 0.2) - 30.0).abs() < 1e-4);
    }

    #[test]
    fn a_staircase_of_one_grey_level_every_fourth_interval_reads_as_its_mean_slope() {
        // 10 DN: a grey level is 0.1 in log; the scene rises 0.025 per 10 ms interval
        // (2.5 per second), which 8-bit frames show as one step every fourth interval
        let changes: Vec<f32> = (0..20)
            .map(|i| if i % 4 == 3 { 0.1 } else { 0.0 })
            .collect();
        let seconds = vec![0.01; 20];
        for i in 4..16 {
            let rate = windowed_rate(&changes, &seconds, i, 0.2);
            assert!((1.8..=2.9).contains(&rate), "interval {i}: {rate}");
        }
        // one interval alone reads 0 or 10 per second
        assert_eq!(changes[4] / seconds[4], 0.0);
        assert!((changes[7] / seconds[7] - 10.0).abs() < 1e-4);
    }

    #[test]
    fn a_still_pixel_reads_zero_and_the_window_stops_at_its_widest_and_at_the_run_ends() {
        let seconds = vec![0.01; 30];
        assert_eq!(windowed_rate(&[0.0; 30], &seconds, 15, 0.2), 0.0);
        // one step far from the centre is outside the widest window
        let mut changes = vec![0.0; 30];
        changes[15 + MAX_HALF_WIDTH + 1] = 0.1;
        assert_eq!(windowed_rate(&changes, &seconds, 15, 0.2), 0.0);
        // at the run's first interval only the later side widens
        changes = vec![0.0; 3];
        changes[2] = 0.1;
        let rate = windowed_rate(&changes, &seconds[..3], 0, 0.2);
        assert!((rate - 0.1 / 0.03).abs() < 1e-3, "{rate}");
        // a window that reaches enough counts half of the change its last widening added
        let rate = windowed_rate(&[0.0, 0.0, 0.15, 0.1, 0.0], &seconds[..5], 0, 0.2);
        assert!((rate - 0.2 / 0.04).abs() < 1e-3, "{rate}");
    }

    #[test]
    fn a_still_pixel_beside_an_edge_passing_stays_still() {
        // an edge crosses the pixel in interval 12 (a change of 1 in log); every other
        // interval is still
        let mut changes = vec![0.0; 30];
        changes[12] = 1.0;
        let seconds = vec![0.01; 30];
        for i in (0..30).filter(|&i| i != 12) {
            assert_eq!(
                windowed_rate(&changes, &seconds, i, 0.2),
                0.0,
                "interval {i}"
            );
        }
        assert!((windowed_rate(&changes, &seconds, 12, 0.2) - 100.0).abs() < 1e-3);
    }
}
