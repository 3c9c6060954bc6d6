//! Without frames, what an ON/OFF imbalance may be. eppps reads each polarity's threshold
//! from that polarity's events against scans whose log changes go both ways alike (natural
//! images, [`super::prior`]), so a recording with more ON than OFF events reads a lower Cp
//! than Cn. The thresholds may differ so; but the scene may also have brightened over the
//! recording (more of its changes upward), or a leak may have added ON events and delayed
//! OFF ones (Nozaki & Delbruck 2017; DVS-Voltmeter, Lin et al. ECCV 2022). Frames tell these
//! apart (the scans follow each pixel's own brightness); the events alone do not. So each
//! polarity's interval also holds the threshold both polarities would share if the
//! imbalance were not theirs: the mean of the ON and OFF event rates read against the same
//! scans ([`symmetric`]). A balanced recording reads the same there and loses nothing.
//!
//! Measured (`benches/coverage/fresh-12001-12040-2026-12-05`, 40 draws from ctcal, ESIM,
//! DVS-Voltmeter and IEBCS): without frames the OFF intervals held 19 of 24 OFF thresholds,
//! and all five misses were recordings with 66-97 % ON events (four DVS-Voltmeter leaks, one
//! brightening texture), read 3-15 times high.

use super::{Polarity, RecordingRates, Side, measure};
use crate::estimate::Measured;

/// The threshold both polarities would share if the recording's imbalance were the scene's
/// or a leak's: the mean of its ON and OFF rates (per pixel of travel) read against the
/// ON and the OFF curves of `calibrations`, the two readings (and their intervals' ends)
/// averaged in the logarithm. `None` where either polarity has no reading (its noise
/// undetermined, no events).
pub(super) fn symmetric(
    calibrations: &[super::Calibration],
    rates: &RecordingRates,
) -> Option<Measured> {
    let target = 0.5 * (rates.on_per_px + rates.off_per_px);
    let ln_se = 0.5 * rates.ln_se_on.hypot(rates.ln_se_off);
    let read = |side| {
        let polarity = measure(calibrations, rates, side, target, ln_se);
        polarity.why.is_none().then_some(polarity.measured)
    };
    let (on, off) = (read(Side::On)?, read(Side::Off)?);
    let value = (on.value * off.value).sqrt();
    let mut shared = Measured::new(value, 0.5 * (on.standard_error + off.standard_error), 0.0);
    shared.systematic = 0.5 * (on.systematic + off.systematic);
    shared.ci95 = [
        (on.ci95[0].max(0.0) * off.ci95[0].max(0.0)).sqrt(),
        (on.ci95[1] * off.ci95[1]).sqrt(),
    ];
    Some(shared)
}

/// Widens each polarity's interval (that has a value) to hold `shared`'s; returns what
/// `assumptions` says where an interval changed.
pub(super) fn widen(on: &mut Polarity, off: &mut Polarity, shared: &Measured) -> Option<String> {
    let mut changed = Vec::new();
    for (name, polarity) in [("ON", on), ("OFF", off)] {
        if polarity.why.is_some() || !polarity.measured.value.is_finite() {
            continue;
        }
        let before = polarity.measured.ci95;
        let after = union(before, shared.ci95);
        if after != before {
            polarity.measured.ci95 = after;
            changed.push(format!(
                "{name} [{:.3}, {:.3}] -> [{:.3}, {:.3}]",
                before[0], before[1], after[0], after[1]
            ));
        }
    }
    (!changed.is_empty()).then(|| {
        format!(
            "ON/OFF balance: without frames the events cannot tell thresholds that differ from a scene that brightened or darkened over the recording, or from a leak's ON events; each polarity's interval also holds the threshold both would share if the imbalance were not theirs, the mean of the ON and OFF rates read against the same scans: {:.3} [{:.3}, {:.3}] ({})",
            shared.value,
            shared.ci95[0],
            shared.ci95[1],
            changed.join(", ")
        )
    })
}

/// The smallest interval holding both.
fn union(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0].min(b[0]), a[1].max(b[1])]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_union_holds_both_intervals() {
        assert_eq!(union([0.5, 2.0], [0.1, 1.0]), [0.1, 2.0]);
        assert_eq!(union([0.5, 2.0], [0.6, 1.0]), [0.5, 2.0]);
    }
}
