//! Honest intervals: each estimate carries its statistical standard error (bootstrap or
//! curvature) and its systematic error (what the method gets wrong by construction, measured
//! rather than assumed), and its 95 % interval covers both,
//! `value +- 1.96 sqrt(se^2 + systematic^2)`.
//!
//! - Frame-rate systematic: the estimate is repeated with every 2nd and every 3rd frame; a
//!   straight line through the three values is extrapolated to infinite frame rate, and the
//!   distance of the full-rate value from that limit, plus the scatter about the line, is
//!   the systematic error of interpolating between frames.
//! - Combination of methods: inverse-variance weighting, with the uncertainty scaled up by
//!   the Birge ratio `sqrt(chi^2 / (n - 1))` when the methods disagree beyond their errors
//!   (the scale factor of the Particle Data Group, Workman et al., PTEP 2022, Sec. 5.2).

use serde::Serialize;
use statrs::distribution::{ContinuousCDF, Normal};

/// The two-sided 95 % quantile of the standard normal distribution.
pub fn z95() -> f64 {
    Normal::standard().inverse_cdf(0.975)
}

/// A value with its statistical and systematic errors and the 95 % interval of both.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Measured {
    pub value: f64,
    pub standard_error: f64,
    pub systematic: f64,
    pub ci95: [f64; 2],
}

impl Measured {
    pub fn new(value: f64, standard_error: f64, systematic: f64) -> Self {
        let half = z95() * standard_error.hypot(systematic);
        Self {
            value,
            standard_error,
            systematic,
            ci95: [value - half, value + half],
        }
    }

    /// A positive value whose errors are relative (standard deviations of its logarithm):
    /// the interval is `value exp(+-1.96 total)`, asymmetric as a multiplicative error is;
    /// `standard_error` and `systematic` hold the errors' linear sizes at the value.
    pub fn log_normal(value: f64, ln_standard_error: f64, ln_systematic: f64) -> Self {
        let half = z95() * ln_standard_error.hypot(ln_systematic);
        Self {
            value,
            standard_error: value * ln_standard_error,
            systematic: value * ln_systematic,
            ci95: [value * (-half).exp(), value * half.exp()],
        }
    }

    /// The total standard deviation.
    pub fn total_error(&self) -> f64 {
        self.standard_error.hypot(self.systematic)
    }

    /// The interval reaching `ratio` times the value on the side that lies ([`ln_reach`]);
    /// `systematic` grows by the reach's linear size over 1.96. As it is where the value or
    /// the ratio is not positive and finite.
    pub fn reaching(mut self, ratio: f64) -> Self {
        if !(self.value > 0.0 && ratio.is_finite() && ratio > 0.0) || ratio == 1.0 {
            return self;
        }
        let [lo, hi] = ln_reach(self.value, [Some(self.ci95[0]), Some(self.ci95[1])], ratio);
        self.ci95 = [lo.unwrap_or(0.0), hi.unwrap_or(f64::INFINITY)];
        self.systematic = self.systematic.hypot(self.value * ratio.ln().abs() / z95());
        self
    }

    /// The interval extended to hold `[lo, hi]` (another reading's interval, under a model
    /// the data cannot rule out), on each side where that is wider. The systematic grows,
    /// in quadrature in the logarithm, by the larger of what the extension adds to either
    /// side (a side that becomes open adds nothing it can size).
    pub fn spanning(mut self, [lo, hi]: [f64; 2]) -> Self {
        let value = self.value;
        if value.is_nan() || value <= 0.0 {
            return self;
        }
        let z = z95();
        // what reaching `to` from `end` adds, in ln units of one standard deviation
        let added = |end: f64, to: f64| {
            let (wide, narrow) = ((to / value).ln().abs() / z, (end / value).ln().abs() / z);
            if wide.is_finite() && narrow.is_finite() {
                (wide * wide - narrow * narrow).max(0.0).sqrt()
            } else {
                0.0
            }
        };
        let [below, above] = self.ci95;
        let mut grown = 0f64;
        if lo < below {
            grown = grown.max(added(below, lo));
            self.ci95[0] = lo.max(0.0);
        }
        if hi > above {
            grown = grown.max(added(above, hi));
            self.ci95[1] = hi;
        }
        self.systematic = self.systematic.hypot(value * grown);
        self
    }
}

/// A 95 % interval `[lo, hi]` about a positive `value` widened by `add` in the logarithm, in
/// quadrature on each side: `value exp(-+ sqrt(ln(value / lo)^2 + add^2))`. A lower end at
/// or below 0 becomes 0, and an open side (`None`) stays open.
pub fn ln_widened(value: f64, [lo, hi]: [Option<f64>; 2], add: f64) -> [Option<f64>; 2] {
    [
        lo.map(|lo| widened_side(value, lo, add, Side::Lower)),
        hi.map(|hi| widened_side(value, hi, add, Side::Upper)),
    ]
}

/// A 95 % interval about a positive `value` reaching `ratio` times it on that side only, in
/// quadrature in the logarithm (an effect known to move the value one way: the side away
/// from it stays).
pub fn ln_reach(value: f64, [lo, hi]: [Option<f64>; 2], ratio: f64) -> [Option<f64>; 2] {
    let add = ratio.ln().abs();
    if ratio > 1.0 {
        [lo, hi.map(|hi| widened_side(value, hi, add, Side::Upper))]
    } else {
        [lo.map(|lo| widened_side(value, lo, add, Side::Lower)), hi]
    }
}

enum Side {
    Lower,
    Upper,
}

/// One end of an interval about `value` widened by `add` in quadrature in the logarithm; a
/// lower end at or below 0 stays 0.
fn widened_side(value: f64, end: f64, add: f64, side: Side) -> f64 {
    match side {
        Side::Lower if end > 0.0 => value * (-(value / end).ln().hypot(add)).exp(),
        Side::Lower => 0.0,
        Side::Upper => value * (end / value).ln().hypot(add).exp(),
    }
}

/// One point of a frame-rate series: every `step`-th frame used, and the estimate.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameRatePoint {
    pub frame_step: usize,
    pub frame_interval_s: f64,
    pub value: f64,
}

/// The frame-rate systematic of a series whose first point is the full-rate estimate: the
/// extrapolated infinite-rate value and the systematic error (distance to it plus the
/// scatter about the line).
pub fn frame_rate_systematic(series: &[FrameRatePoint]) -> (Option<f64>, f64) {
    if series.len() < 2 {
        return (None, 0.0);
    }
    let n = series.len() as f64;
    let xs: Vec<f64> = series.iter().map(|p| p.frame_interval_s).collect();
    let ys: Vec<f64> = series.iter().map(|p| p.value).collect();
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return (None, 0.0);
    }
    let slope = xs
        .iter()
        .zip(&ys)
        .map(|(x, y)| (x - mx) * (y - my))
        .sum::<f64>()
        / sxx;
    let limit = my - slope * mx;
    let scatter = if series.len() > 2 {
        let rss: f64 = xs
            .iter()
            .zip(&ys)
            .map(|(x, y)| (y - (limit + slope * x)).powi(2))
            .sum();
        (rss / (n - 2.0)).sqrt()
    } else {
        0.0
    };
    (Some(limit), (series[0].value - limit).abs() + scatter)
}

/// Inverse-variance combination of estimates of one quantity, with the Birge-ratio scale
/// when they disagree. Returns the combined value and its total standard error.
pub fn combine(estimates: &[&Measured]) -> Option<(f64, f64)> {
    let usable: Vec<&&Measured> = estimates
        .iter()
        .filter(|m| m.value.is_finite() && m.total_error() > 0.0)
        .collect();
    if usable.is_empty() {
        return None;
    }
    let weights: Vec<f64> = usable.iter().map(|m| m.total_error().powi(-2)).collect();
    let total: f64 = weights.iter().sum();
    let value = usable
        .iter()
        .zip(&weights)
        .map(|(m, w)| m.value * w)
        .sum::<f64>()
        / total;
    let mut error = total.powf(-0.5);
    if usable.len() > 1 {
        let chi2: f64 = usable
            .iter()
            .zip(&weights)
            .map(|(m, w)| w * (m.value - value).powi(2))
            .sum();
        let birge = (chi2 / (usable.len() - 1) as f64).sqrt();
        if birge > 1.0 {
            error *= birge;
        }
        // methods measuring the same quantity differ by their systematics at least: half
        // their range stays in the error (so the interval spans about the range)
        let (lo, hi) = usable
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), m| {
                (lo.min(m.value), hi.max(m.value))
            });
        error = error.max(0.5 * (hi - lo));
    }
    Some((value, error))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand-computed: 0.2 in [0.1, 0.4] (ln 2 each side) widened by ln 2 * sqrt(3) gives
    /// ln 2 * 2 each side, [0.05, 0.8]; a lower end at 0 stays there, an open side open.
    #[test]
    fn intervals_widen_in_the_logarithm() {
        let add = 2f64.ln() * 3f64.sqrt();
        let [lo, hi] = ln_widened(0.2, [Some(0.1), Some(0.4)], add);
        assert!((lo.unwrap() - 0.05).abs() < 1e-12 && (hi.unwrap() - 0.8).abs() < 1e-12);
        assert_eq!(ln_widened(0.2, [Some(0.0), None], add)[0], Some(0.0));
        assert_eq!(ln_widened(0.2, [Some(0.1), None], add)[1], None);
        // reaching 4 times the value: the upper end only, ln 2 and ln 4 -> ln 2 sqrt(5)
        let [lo, hi] = ln_reach(0.2, [Some(0.1), Some(0.4)], 4.0);
        assert_eq!(lo, Some(0.1));
        assert!((hi.unwrap() - 0.2 * (2f64.ln() * 5f64.sqrt()).exp()).abs() < 1e-12);
        let [lo, hi] = ln_reach(0.2, [Some(0.1), Some(0.4)], 0.25);
        assert!((lo.unwrap() - 0.2 * (-(2f64.ln() * 5f64.sqrt())).exp()).abs() < 1e-12);
        assert_eq!(hi, Some(0.4));
        let m = Measured::new(0.2, 0.0, 0.2 * 0.5 / z95()).reaching(4.0);
        assert!(
            (m.ci95[0] - 0.1).abs() < 1e-12 && m.ci95[1] > 0.8 && m.ci95[1] < 0.9,
            "{m:?}"
        );
        assert_eq!(
            Measured::new(0.2, 0.01, 0.0).reaching(1.0),
            Measured::new(0.2, 0.01, 0.0)
        );
    }

    #[test]
    fn intervals_cover_both_kinds_of_error() {
        let m = Measured::new(0.3, 0.003, 0.004);
        assert!((m.ci95[1] - 0.3 - 1.959_964 * 0.005).abs() < 1e-6);
    }

    #[test]
    fn a_frame_rate_trend_is_extrapolated() {
        let series: Vec<FrameRatePoint> = [(1, 0.29), (2, 0.28), (3, 0.27)]
            .iter()
            .map(|&(s, v)| FrameRatePoint {
                frame_step: s,
                frame_interval_s: 0.02 * s as f64,
                value: v,
            })
            .collect();
        let (limit, systematic) = frame_rate_systematic(&series);
        assert!((limit.unwrap() - 0.30).abs() < 1e-9);
        assert!((systematic - 0.01).abs() < 1e-9);
    }

    #[test]
    fn disagreeing_methods_widen_the_combined_error() {
        let a = Measured::new(0.30, 0.001, 0.0);
        let b = Measured::new(0.31, 0.001, 0.0);
        let (value, error) = combine(&[&a, &b]).unwrap();
        assert!((value - 0.305).abs() < 1e-9);
        // without the Birge scale the error would be 0.0007; the methods are 7 sigma apart
        assert!(error > 0.004, "{error}");
        let (_, agreeing) = combine(&[&a, &Measured::new(0.3005, 0.001, 0.0)]).unwrap();
        assert!((agreeing - 0.001 / 2f64.sqrt()).abs() < 1e-9);
    }
}
