//! A display in the light path: an on-screen stimulus reaches the camera at the monitor's
//! refresh rate through its gamma and black level ([`crate::sim::display`]).
//!
//! Signature: a spectral line at the refresh rate in the event-rate spectrum that the model
//! lacks. Evidence: the strongest line between 20 and 500 Hz in the recording's spectrum
//! (power over the spectrum's median), against the model's at that frequency. A display's
//! parameters are fitted from the stimulus that was played (`ctcal estimate screen`); the
//! fit names the line and the frequency. Not assessed on timestamps quantised to a coarse
//! grid, whose own lines fill the spectrum.

use super::{Context, Effect, Evidence};
use crate::fit::residuals::power_spectrum;

/// The frequency and normalised power of the recording's strongest line, and the model's
/// power there.
pub fn line(c: &Context) -> Option<(f64, f64, f64)> {
    let (f, real) = power_spectrum(&c.real.timeline);
    let (_, sim) = power_spectrum(&c.sim.timeline);
    let (k, &power) = real
        .iter()
        .enumerate()
        .filter(|&(i, _)| (20.0..=500.0).contains(&f[i]))
        .max_by(|a, b| a.1.total_cmp(b.1))?;
    Some((f[k], power, sim.get(k).copied().unwrap_or(0.0)))
}

/// Timestamp grids at least this coarse (us) fill the event-rate spectrum with their own
/// lines (a simulator's frames stamp events at fixed fractions of each interval: v2e), so a
/// display cannot be told from them.
const GRID_HIDES_DISPLAY_US: i64 = 100;

pub fn evidence(c: &Context) -> Evidence {
    if let Some(grid) = c.timestamp_grid_us.filter(|&g| g >= GRID_HIDES_DISPLAY_US) {
        return Evidence::none(
            Effect::Display,
            format!(
                "the timestamps lie on a {grid} us grid (a simulator's frames): the event-rate spectrum shows the grid's lines, not a display's"
            ),
        );
    }
    match line(c) {
        Some((frequency, power, simulated)) => Evidence {
            effect: Effect::Display,
            score: power / simulated.max(1.0),
            relevant: power > 50.0 && power > 10.0 * simulated,
            text: format!(
                "the event rate has a spectral line at {frequency:.1} Hz ({power:.0} times the median power; the model: {simulated:.1})"
            ),
            start: Some(frequency),
        },
        None => Evidence::none(Effect::Display, "too short a recording for a spectrum"),
    }
}
