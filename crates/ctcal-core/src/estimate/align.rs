//! Frame-time alignment. Files stamp APS frames by different conventions (start of
//! exposure, its middle, start of readout) and rarely say which; the thresholds measured
//! from frames move by about 2 % per millisecond of misalignment at typical speeds. The
//! event-timing samples ([`super::timing`]) are most consistent, their relative spread
//! smallest, when the frames' times match the events': the shift that minimises the spread
//! over `[-T/4, T/4]` (T the frame interval) is the alignment, refined by a parabola
//! through the best grid point and its neighbours. Its precision (the shift that raises
//! the spread by 2 %, from the parabola's curvature) becomes a systematic error of the
//! estimate.

use super::frames::PreparedFrames;
use super::timing::{TimingOptions, spread};
use crate::events::{EventChunk, Sensor, TimeUs};
use rayon::prelude::*;
use serde::Serialize;

/// The alignment found.
#[derive(Clone, Debug, Serialize)]
pub struct Alignment {
    /// Shift added to the frames' times, seconds.
    pub shift_s: f64,
    /// Its precision, seconds.
    pub precision_s: f64,
    /// Relative sample spread without the shift and with it.
    pub spread_unshifted: f64,
    pub spread_aligned: f64,
}

/// Finds the frame-time shift of `frames` (the grid's shifts are tried on every thread,
/// each reading the frames at shifted times; the frames' times are as they were).
pub fn align(
    events: &EventChunk,
    frames: &mut PreparedFrames,
    sensor: Sensor,
    excluded: &[bool],
    options: &TimingOptions,
) -> Option<Alignment> {
    let quarter = frames.median_interval_us() / 4;
    if quarter < 100 {
        return None;
    }
    let step = quarter / GRID_STEPS;
    let spread_at =
        |frames: &PreparedFrames, shift| spread(events, frames, shift, sensor, excluded, options);
    let grid = spread_grid(frames, step, &spread_at);
    let unshifted = grid.iter().find(|(s, _)| *s == 0)?.1;
    let best = grid
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.1.total_cmp(&b.1.1))?
        .0;
    let (shift, curvature) = parabola_minimum(&grid, best, step);
    let shift = shift.round() as TimeUs;
    let aligned = spread_at(frames, shift);
    frames.replay_shifts([shift]);
    let aligned = aligned.unwrap_or(grid[best].1);
    // the shift at which the spread rises by 2 %: y = a (x - x*)^2 / 2 ... a = curvature
    let precision_us = if curvature > 0.0 {
        (2.0 * 0.02 * aligned / curvature).sqrt()
    } else {
        quarter as f64
    };
    Some(Alignment {
        shift_s: shift as f64 * 1e-6,
        precision_s: precision_us.min(quarter as f64) * 1e-6,
        spread_unshifted: unshifted,
        spread_aligned: aligned,
    })
}

/// Steps of the grid on either side of no shift, over a quarter of the frame interval.
const GRID_STEPS: i64 = 4;

/// The spread at each shift of the grid (`-GRID_STEPS..=GRID_STEPS` times `step`), tried on
/// every thread, the frames then replaying the shifts in order; shifts without one left out.
fn spread_grid(
    frames: &mut PreparedFrames,
    step: TimeUs,
    spread_at: &(dyn Fn(&PreparedFrames, TimeUs) -> Option<f64> + Sync),
) -> Vec<(TimeUs, f64)> {
    let tried: Vec<(TimeUs, Option<f64>)> = (-GRID_STEPS..=GRID_STEPS)
        .into_par_iter()
        .map(|k| (k * step, spread_at(frames, k * step)))
        .collect();
    frames.replay_shifts(tried.iter().map(|t| t.0));
    tried
        .into_iter()
        .filter_map(|(shift, value)| Some((shift, value?)))
        .collect()
}

/// The shift of least spread, microseconds, and the spread's curvature there: of the
/// parabola through the `best` grid point and its neighbours (or the best point, and no
/// curvature, at an edge).
fn parabola_minimum(grid: &[(TimeUs, f64)], best: usize, step: TimeUs) -> (f64, f64) {
    if best > 0 && best + 1 < grid.len() {
        let (x0, y0) = grid[best - 1];
        let (_, y1) = grid[best];
        let (_, y2) = grid[best + 1];
        let h = step as f64;
        let denominator = y0 - 2.0 * y1 + y2;
        let offset = if denominator > 0.0 {
            (0.5 * (y0 - y2) / denominator).clamp(-1.0, 1.0)
        } else {
            0.0
        };
        (x0 as f64 + h * (1.0 + offset), denominator / (h * h))
    } else {
        (grid[best].0 as f64, 0.0)
    }
}
