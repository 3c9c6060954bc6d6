//! Leak: junction leakage in the pixel's reset switch makes the memorised level drift, so
//! a pixel in a static scene emits ON events at a steady rate (Nozaki & Delbruck, "Temperature
//! and parasitic photocurrent effects in dynamic vision sensors", IEEE TED 2017). As in v2e,
//! the reference falls by `leak_rate_hz * factor * theta_on` per second: one ON event per
//! `1 / (leak_rate_hz * factor)` seconds, with a per-pixel lognormal `factor = 10^(s N(0,1))`
//! (`s` = `leak_spread_decades`, 0.1 by default). v2e also jitters the drift of every frame
//! by 10 %; that averages out over a threshold's worth of frames and is not modelled.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

/// Draws one pixel's leak-rate factor.
pub fn draw_factor(spread_decades: f64, rng: &mut impl Rng) -> f32 {
    let z: f64 = StandardNormal.sample(rng);
    10f64.powf(spread_decades * z) as f32
}

/// Reference drift in log units per microsecond.
#[inline]
pub fn drift_per_us(leak_rate_hz: f64, factor: f32, theta_on: f32) -> f32 {
    (leak_rate_hz * 1e-6) as f32 * factor * theta_on
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn one_threshold_per_leak_period() {
        // 1 Hz, factor 1, theta 0.3: the reference falls 0.3 in 1 s
        assert!((drift_per_us(1.0, 1.0, 0.3) * 1e6 - 0.3).abs() < 1e-6);
    }

    #[test]
    fn factor_is_lognormal_with_the_given_spread() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(3);
        let logs: Vec<f64> = (0..50_000)
            .map(|_| (draw_factor(0.1, &mut rng) as f64).log10())
            .collect();
        let mean = logs.iter().sum::<f64>() / logs.len() as f64;
        let sd = (logs.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / logs.len() as f64).sqrt();
        assert!(
            mean.abs() < 0.002 && (sd - 0.1).abs() < 0.002,
            "{mean} {sd}"
        );
    }
}
