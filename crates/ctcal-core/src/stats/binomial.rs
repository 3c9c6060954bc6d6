//! Intervals from counting: a binomial proportion (Wilson, JASA 1927: a score interval
//! that stays inside [0, 1] and behaves at 0 and n) and the distribution-free interval of
//! a median from its order statistics (the number of values below the median is
//! Binomial(n, 1/2); Conover, *Practical Nonparametric Statistics*, 3rd ed., sec. 3.2),
//! and the exact interval of a Poisson mean from one count (Garwood, Biometrika 1936), and
//! the exact conditional test of two Poisson counts over equal exposures (Przyborowski &
//! Wilenski, Biometrika 1940), and the gamma interval of a weighted sum of Poisson counts
//! (Fay & Feuer, Statistics in Medicine 1997: a directly standardised rate).

use crate::estimate::interval::z95;

/// The 95 % Wilson interval of `successes` out of `trials` (`None` for no trials).
pub fn wilson95(successes: usize, trials: usize) -> Option<(f64, f64)> {
    if trials == 0 {
        return None;
    }
    let n = trials as f64;
    let p = successes as f64 / n;
    let z = z95();
    let z2 = z * z;
    let denominator = 1.0 + z2 / n;
    let centre = (p + z2 / (2.0 * n)) / denominator;
    let half = z * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt() / denominator;
    // at 0 and n the bound is exactly 0 (1); rounding would leave it a hair away
    let lo = if successes == 0 {
        0.0
    } else {
        (centre - half).max(0.0)
    };
    let hi = if successes >= trials {
        1.0
    } else {
        (centre + half).min(1.0)
    };
    Some((lo, hi))
}

/// Garwood's exact 95 % interval of a Poisson mean from the count `n`:
/// `[chi2(0.025; 2n) / 2, chi2(0.975; 2n + 2) / 2]` (the lower end 0 for `n = 0`).
pub fn poisson95(n: usize) -> (f64, f64) {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    let quantile = |freedom: f64, p: f64| {
        ChiSquared::new(freedom).map_or(f64::NAN, |d| d.inverse_cdf(p)) / 2.0
    };
    let lo = if n == 0 {
        0.0
    } else {
        quantile(2.0 * n as f64, 0.025)
    };
    (lo, quantile(2.0 * n as f64 + 2.0, 0.975))
}

/// The 95 % interval of `sum w_i lambda_i` from independent Poisson counts `n_i` with
/// weights `w_i` (`(n_i, w_i)` pairs): Fay & Feuer's gamma interval (Statistics in Medicine
/// 16, 1997, 791-801), the interval of a directly standardised rate. With `y = sum w_i n_i`
/// and `v = sum w_i^2 n_i`, the lower end is the 2.5 % quantile of a gamma of mean `y` and
/// variance `v`, the upper end the 97.5 % quantile of one of mean `y + w_max` and variance
/// `v + w_max^2`. One count gives Garwood's interval times its weight ([`poisson95`]); the
/// interval is conservative where the weights differ. Pairs with weight 0 count for
/// nothing; `None` where no pair has a positive weight.
pub fn weighted_poisson95(counts: &[(f64, f64)]) -> Option<(f64, f64)> {
    use statrs::distribution::{ContinuousCDF, Gamma};
    let counts: Vec<(f64, f64)> = counts.iter().copied().filter(|&(_, w)| w > 0.0).collect();
    let w_max = counts.iter().map(|&(_, w)| w).fold(0.0, f64::max);
    if w_max <= 0.0 {
        return None;
    }
    let y: f64 = counts.iter().map(|&(n, w)| w * n).sum();
    let v: f64 = counts.iter().map(|&(n, w)| w * w * n).sum();
    // a gamma of this mean and variance (shape mean^2 / variance, rate mean / variance)
    let quantile = |mean: f64, variance: f64, p: f64| {
        Gamma::new(mean * mean / variance, mean / variance).map_or(f64::NAN, |g| g.inverse_cdf(p))
    };
    let lo = if y > 0.0 { quantile(y, v, 0.025) } else { 0.0 };
    Some((lo, quantile(y + w_max, v + w_max * w_max, 0.975)))
}

/// Whether a Poisson count `n` exceeds a count `m` over an equal exposure beyond chance: the
/// exact conditional test (given `n + m`, `n` is Binomial(n + m, 1/2) where the means are
/// equal; Przyborowski & Wilenski, Biometrika 1940), one-sided at 2.5 %, so that it agrees
/// with the lower end of a 95 % interval. Two named against none is chance (P = 0.25); six
/// against none is not (P = 0.016).
pub fn exceeds_by_more_than_chance(n: usize, m: usize) -> bool {
    use statrs::distribution::{Binomial, DiscreteCDF};
    if n == 0 {
        return false;
    }
    Binomial::new(0.5, (n + m) as u64).is_ok_and(|b| b.sf(n as u64 - 1) < 0.025)
}

/// The distribution-free 95 % interval of the median of `values`: `[x_(k), x_(n+1-k)]`
/// with the largest `k` for which `P(Binomial(n, 1/2) < k) <= 0.025`. `None` under six
/// values (even `[min, max]` then holds the median with less than 95 %).
pub fn median_interval95(values: &[f64]) -> Option<(f64, f64)> {
    let n = values.len();
    if n < 6 {
        return None;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    // P(B < k) for B ~ Binomial(n, 1/2), summed in logs (n can be large)
    let ln_half_n = -(n as f64) * std::f64::consts::LN_2;
    let mut ln_choose = 0.0; // ln C(n, 0)
    let mut below = 0.0; // P(B < k)
    let mut k = 0;
    loop {
        let p_k = (ln_choose + ln_half_n).exp();
        if below + p_k > 0.025 {
            break;
        }
        below += p_k;
        k += 1;
        ln_choose += ((n - k + 1) as f64).ln() - (k as f64).ln();
    }
    // k values lie below the interval with probability <= 0.025: it starts at x_(k)
    let k = k.max(1);
    Some((sorted[k - 1], sorted[n - k]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poisson_counts_exceed_each_other_as_the_binomial_tail_says() {
        // P(B(2, 1/2) >= 2) = 0.25, P(B(5, 1/2) >= 5) = 0.031, P(B(6, 1/2) >= 6) = 0.0156
        assert!(!exceeds_by_more_than_chance(2, 0));
        assert!(!exceeds_by_more_than_chance(5, 0));
        assert!(exceeds_by_more_than_chance(6, 0));
        // 20 against 8: P(B(28, 1/2) >= 20) = 0.0178; 19 against 8: 0.0261
        assert!(exceeds_by_more_than_chance(20, 8));
        assert!(!exceeds_by_more_than_chance(19, 8));
        assert!(!exceeds_by_more_than_chance(0, 0));
        assert!(!exceeds_by_more_than_chance(3, 3));
    }

    #[test]
    fn wilson_matches_the_textbook_values() {
        // 19 of 20: 0.764-0.991 (Newcombe 1998, Table I style)
        let (lo, hi) = wilson95(19, 20).unwrap();
        assert!(
            (lo - 0.7639).abs() < 1e-3 && (hi - 0.9911).abs() < 1e-3,
            "{lo} {hi}"
        );
        let (lo, hi) = wilson95(0, 10).unwrap();
        assert_eq!(lo, 0.0);
        assert!((hi - 0.2775).abs() < 1e-3, "{hi}");
        assert_eq!(wilson95(0, 0), None);
    }

    #[test]
    fn garwood_intervals_match_the_tables() {
        // Garwood 1936 / any table of exact Poisson limits: 0 -> [0, 3.689], 10 -> [4.795, 18.39]
        let (lo, hi) = poisson95(0);
        assert_eq!(lo, 0.0);
        assert!((hi - 3.6889).abs() < 1e-3, "{hi}");
        let (lo, hi) = poisson95(10);
        assert!(
            (lo - 4.7954).abs() < 1e-3 && (hi - 18.3904).abs() < 1e-3,
            "{lo} {hi}"
        );
    }

    /// One count is Garwood's interval times its weight; three counts against scipy's
    /// gamma quantiles (y = 59, v = 135.5, w_max = 4: `gamma.ppf(0.025, y*y/v, scale=v/y)`
    /// and `gamma.ppf(0.975, (y+4)**2/(v+16), scale=(v+16)/(y+4))`).
    #[test]
    fn a_weighted_sum_of_counts_takes_fay_and_feuers_gamma_interval() {
        let (lo, hi) = weighted_poisson95(&[(10.0, 3.0)]).unwrap();
        let (glo, ghi) = poisson95(10);
        assert!(
            (lo - 3.0 * glo).abs() < 1e-6 && (hi - 3.0 * ghi).abs() < 1e-6,
            "{lo} {hi}"
        );
        let (lo, hi) =
            weighted_poisson95(&[(12.0, 2.0), (30.0, 0.5), (5.0, 4.0), (7.0, 0.0)]).unwrap();
        assert!(
            (lo - 38.4315).abs() < 1e-3 && (hi - 89.3155).abs() < 1e-3,
            "{lo} {hi}"
        );
        // no count: 0 to the weight times Garwood's upper end of 0
        let (lo, hi) = weighted_poisson95(&[(0.0, 2.0)]).unwrap();
        assert!(lo == 0.0 && (hi - 2.0 * 3.6889).abs() < 1e-3, "{hi}");
        assert!(weighted_poisson95(&[(5.0, 0.0)]).is_none());
    }

    #[test]
    fn the_median_interval_takes_the_order_statistics_of_the_tables() {
        let values: Vec<f64> = (1..=20).map(f64::from).collect();
        // n = 20: P(B <= 5) = 0.0207, P(B <= 6) = 0.0577 -> [x_(6), x_(15)]
        assert_eq!(median_interval95(&values), Some((6.0, 15.0)));
        // n = 6: P(B = 0) = 0.0156 -> [min, max]
        assert_eq!(
            median_interval95(&[3.0, 1.0, 2.0, 6.0, 5.0, 4.0]),
            Some((1.0, 6.0))
        );
        assert_eq!(median_interval95(&[1.0, 2.0, 3.0, 4.0, 5.0]), None);
    }
}
