//! The frozen threshold mismatch `ct_sigma` from both polarities' per-pixel spreads.
//!
//! Each polarity gives an excess variance `v = Var_p(C_p) - mean_p(s^2 / n_p)` (the
//! between-pixel variance of its threshold map less the pixels' estimation noise, see
//! [`super`]) with a bootstrap standard error. The model has one mismatch for both
//! polarities (v2e's `sigma_thres`; Lichtsteiner et al., JSSC 2008, one comparator offset
//! spread), so the polarities are combined, in variance space where their noise is
//! symmetric, by inverse variance with the Birge ratio: polarities that disagree beyond
//! their errors widen the result, they are not averaged away.
//!
//! A polarity whose excess variance lies more than [`OVERSHOOT_Z`] standard errors below
//! zero shows that the noise subtraction removed more than the noise there, which a
//! variance cannot do by chance: consecutive samples of a pixel share an event, so the
//! pooled within-pixel variance (from busy pixels) overstates the noise of pixels with one
//! or two samples (`benches/coverage/aps-sigma-2026-11-27`, cause A). Such a polarity is
//! left out of the value, and what it overshot by is kept as the size by which the other
//! polarity, whose noise was subtracted alike, may read low: it raises the interval's upper
//! side. Before this (2026-11-28) the two polarities' spreads were averaged with the clipped
//! zero of such a polarity, which halved `ct_sigma` on the draws where it happens.

use super::{PolarityEstimate, TimingEstimate};
use crate::estimate::interval::z95;

/// How many standard errors below zero an excess variance must lie to show that the noise
/// subtraction overshoots (a 3-sigma departure: 0.13 % of polarities with a right noise
/// model and no mismatch).
pub const OVERSHOOT_Z: f64 = 3.0;

/// The two polarities' excess variances combined.
#[derive(Clone, Debug, PartialEq)]
pub struct Spread {
    /// The combined excess variance (unclipped) and its standard error, Birge-scaled where
    /// the polarities disagree. `NaN` when neither polarity is usable.
    pub excess_variance: f64,
    pub excess_variance_standard_error: f64,
    /// `sqrt(max(excess_variance, 0))`, and its standard error (the delta method,
    /// `se(v) / (2 sigma)`, at most `sqrt(se(v))`, the scale of the variance's noise).
    pub sigma: f64,
    pub sigma_standard_error: f64,
    /// Which polarities went into the value: ON, OFF.
    pub used: [bool; 2],
    /// The 95 % upper size of the largest overshoot a left-out polarity showed (`-v +
    /// 1.96 se(v)`), log units squared; 0 where none.
    pub overshoot: f64,
}

impl Spread {
    /// Whether a polarity was left out for an overshooting noise subtraction.
    pub fn has_overshoot(&self) -> bool {
        self.overshoot > 0.0
    }

    /// The upper side of a 95 % interval whose upper side without the overshoot is `hi`:
    /// the overshoot added in variance.
    pub fn raised(&self, hi: f64) -> f64 {
        (hi.max(0.0).powi(2) + self.overshoot).sqrt()
    }
}

/// The inverse-variance mean of `kept` and its standard error, scaled by the Birge ratio
/// where they disagree beyond their errors; the plain mean without an error where none has
/// one (too few pixels for a bootstrap); `NaN` where nothing is kept. Unlike
/// [`crate::estimate::interval::combine`], which joins different methods and keeps half
/// their range as a systematic, the polarities are two samples of one spread: their
/// disagreement counts through the Birge ratio alone.
fn inverse_variance(kept: &[(f64, f64)]) -> (f64, f64) {
    let with_error: Vec<(f64, f64)> = kept
        .iter()
        .copied()
        .filter(|(v, se)| v.is_finite() && *se > 0.0)
        .collect();
    if with_error.is_empty() {
        return match kept.len() {
            0 => (f64::NAN, f64::NAN),
            n => (kept.iter().map(|k| k.0).sum::<f64>() / n as f64, 0.0),
        };
    }
    let weights: Vec<f64> = with_error.iter().map(|(_, se)| se.powi(-2)).collect();
    let total: f64 = weights.iter().sum();
    let v = with_error
        .iter()
        .zip(&weights)
        .map(|((v, _), w)| v * w)
        .sum::<f64>()
        / total;
    let chi2: f64 = with_error
        .iter()
        .zip(&weights)
        .map(|((x, _), w)| w * (x - v).powi(2))
        .sum();
    let birge = match with_error.len() {
        1 => 1.0,
        n => (chi2 / (n - 1) as f64).sqrt().max(1.0),
    };
    (v, birge * total.powf(-0.5))
}

/// Whether one polarity's excess variance shows an overshooting noise subtraction.
fn overshoots(p: &PolarityEstimate) -> bool {
    p.excess_variance_standard_error > 0.0
        && p.excess_variance < -OVERSHOOT_Z * p.excess_variance_standard_error
}

impl TimingEstimate {
    /// Both polarities' spreads combined (see the module's doc).
    pub fn spread(&self) -> Spread {
        combined(&self.on, &self.off)
    }
}

/// The ON and OFF spreads combined (see the module's doc).
pub fn combined(on: &PolarityEstimate, off: &PolarityEstimate) -> Spread {
    let polarities = [on, off];
    let has_error = |p: &PolarityEstimate| p.excess_variance_standard_error > 0.0;
    // a polarity without a bootstrap error counts only where neither has one
    let any_error = polarities.iter().any(|p| has_error(p));
    let used = polarities.map(|p| !overshoots(p) && (has_error(p) || !any_error));
    let overshoot = polarities
        .iter()
        .filter(|p| overshoots(p))
        .map(|p| -p.excess_variance + z95() * p.excess_variance_standard_error)
        .fold(0.0, f64::max);
    let kept: Vec<(f64, f64)> = polarities
        .iter()
        .zip(used)
        .filter(|(_, u)| *u)
        .map(|(p, _)| (p.excess_variance, p.excess_variance_standard_error))
        .collect();
    let (v, se) = inverse_variance(&kept);
    let sigma = v.max(0.0).sqrt();
    let sigma_standard_error = if sigma > 0.0 {
        (se / (2.0 * sigma)).min(se.sqrt())
    } else {
        se.sqrt()
    };
    Spread {
        excess_variance: v,
        excess_variance_standard_error: se,
        sigma: if v.is_nan() { f64::NAN } else { sigma },
        sigma_standard_error,
        used,
        overshoot,
    }
}

/// The combined spread's change across the frames' offset range, a systematic: at each
/// end the polarities' spreads (`ends`, ON and OFF) combined with the bootstrap errors of
/// the spread at the offset (`excess_se`, ON and OFF), against `at_offset` combined alike;
/// the larger change over 1.96 (as for the thresholds), or 0 where the spread at the
/// offset is not determined.
pub fn offset_systematic<'a>(
    ends: impl IntoIterator<Item = &'a [PolarityEstimate; 2]>,
    at_offset: [&PolarityEstimate; 2],
    excess_se: [f64; 2],
) -> f64 {
    let sigma = |[on, off]: [&PolarityEstimate; 2]| {
        let with_error = |p: &PolarityEstimate, se: f64| PolarityEstimate {
            excess_variance_standard_error: se,
            ..p.clone()
        };
        combined(
            &with_error(on, excess_se[0]),
            &with_error(off, excess_se[1]),
        )
        .sigma
    };
    let centre = sigma(at_offset);
    if !centre.is_finite() {
        return 0.0;
    }
    ends.into_iter()
        .map(|[on, off]| sigma([on, off]))
        .filter(|s| s.is_finite())
        .map(|s| (s - centre).abs())
        .fold(0.0, f64::max)
        / 1.96
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_spreads_offset_systematic_is_its_largest_change_at_the_ends_over_1_96() {
        // at the offset both polarities 0.04^2; at the ends 0.05^2 and 0.035^2 (their own
        // bootstrap errors replaced by the offset's)
        let at = [polarity(1.6e-3, 1e-4), polarity(1.6e-3, 1e-4)];
        let ends = [
            [polarity(2.5e-3, 9.0), polarity(2.5e-3, 9.0)],
            [polarity(1.225e-3, 0.0), polarity(1.225e-3, 0.0)],
        ];
        let s = offset_systematic(&ends, [&at[0], &at[1]], [1e-4, 1e-4]);
        assert!((s - 0.01 / 1.96).abs() < 1e-12, "{s}");
        // no ends: none
        assert_eq!(offset_systematic(&[], [&at[0], &at[1]], [1e-4, 1e-4]), 0.0);
        // a spread not determined at the offset (both polarities overshoot): none
        let overshooting = polarity(-1e-3, 1e-5);
        assert_eq!(
            offset_systematic(&ends, [&overshooting, &overshooting], [1e-5, 1e-5]),
            0.0
        );
    }

    fn polarity(excess_variance: f64, se: f64) -> PolarityEstimate {
        PolarityEstimate {
            ct: 0.3,
            standard_error: 0.01,
            between_blocks_standard_error: None,
            offset_systematic: 0.0,
            offset_reach: [1.0; 2],
            sigma: excess_variance.max(0.0).sqrt(),
            sigma_standard_error: 0.0,
            excess_variance,
            excess_variance_standard_error: se,
            samples: 1000,
            pixels: 500,
            rejected: 0,
            sample_spread: 0.1,
            interpolation_share: 0.0,
            peak: None,
        }
    }

    fn spread(on: (f64, f64), off: (f64, f64)) -> Spread {
        combined(&polarity(on.0, on.1), &polarity(off.0, off.1))
    }

    #[test]
    fn agreeing_polarities_combine_by_inverse_variance() {
        // 9e-4 +- 1e-4 and 1.2e-3 +- 2e-4 (1.3 standard errors apart: no Birge scaling)
        let s = spread((9e-4, 1e-4), (1.2e-3, 2e-4));
        let v = (9e-4 / 1e-8 + 1.2e-3 / 4e-8) / (1.0 / 1e-8 + 1.0 / 4e-8);
        assert!((s.excess_variance - v).abs() < 1e-12, "{s:?}");
        assert!((s.sigma - v.sqrt()).abs() < 1e-12);
        assert_eq!(s.used, [true, true]);
        assert_eq!(s.overshoot, 0.0);
    }

    #[test]
    fn an_overshooting_polarity_is_left_out_and_raises_the_upper_side() {
        // draw 59 of the coverage study: ON 6.33e-4 +- 6.1e-6, OFF -2.23e-3 +- 2.3e-4
        // (truth 0.0521); the average of the clipped spreads read 0.0193
        let s = spread((6.33e-4, 6.1e-6), (-2.23e-3, 2.3e-4));
        assert_eq!(s.used, [true, false]);
        assert!((s.sigma - 6.33e-4f64.sqrt()).abs() < 1e-9, "{s:?}");
        let overshoot = 2.23e-3 + 1.96 * 2.3e-4;
        assert!((s.overshoot - overshoot).abs() < 1e-4 * overshoot, "{s:?}");
        let hi = s.raised(s.sigma + 1.96 * s.sigma_standard_error);
        assert!(hi > 0.0521 && hi < 0.06, "{hi}");
    }

    #[test]
    fn a_spread_near_zero_is_not_an_overshoot() {
        // -2 standard errors: what no mismatch gives by chance
        let s = spread((-2e-5, 1e-5), (1e-5, 1e-5));
        assert_eq!(s.used, [true, true]);
        assert_eq!(s.overshoot, 0.0);
        assert_eq!(s.sigma, 0.0);
        assert!(s.sigma_standard_error > 0.0);
    }

    #[test]
    fn both_polarities_overshooting_leave_no_value() {
        let s = spread((-1e-3, 1e-4), (-2e-3, 1e-4));
        assert_eq!(s.used, [false, false]);
        assert!(s.sigma.is_nan() && s.excess_variance.is_nan());
        assert!(s.has_overshoot());
    }
}
