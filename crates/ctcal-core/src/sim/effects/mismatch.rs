//! Threshold mismatch: every pixel's comparators differ slightly, so its ON and OFF
//! thresholds are frozen draws `theta ~ N(ct, sigma)`, clamped to at least 0.01 so no
//! pixel fires without bound (v2e, Hu et al. 2021; ESIM, Rebecq et al. 2018). Optional
//! temporal noise redraws the threshold after every event, `theta' ~ N(theta, sigma_t)`
//! (a model of comparator noise, cf. DVS-Voltmeter, Lin et al. ECCV 2022).

use rand::Rng;
use rand_distr::{Distribution, Normal};

/// The smallest threshold any pixel may have.
pub const MIN_THRESHOLD: f32 = 0.01;

/// Draws one pixel's frozen threshold.
pub fn draw_threshold(nominal: f64, sigma: f64, rng: &mut impl Rng) -> f32 {
    if sigma <= 0.0 {
        return (nominal as f32).max(MIN_THRESHOLD);
    }
    let normal = Normal::new(nominal, sigma).expect("sigma is finite and positive");
    (normal.sample(rng) as f32).max(MIN_THRESHOLD)
}

/// Redraws a threshold around the pixel's frozen value (temporal noise).
#[inline]
pub fn redraw(frozen: f32, sigma_temporal: f32, rng: &mut impl Rng) -> f32 {
    let z: f32 = rand_distr::StandardNormal.sample(rng);
    (frozen + sigma_temporal * z).max(MIN_THRESHOLD)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn draws_have_the_requested_mean_and_spread_and_respect_the_floor() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(1);
        let draws: Vec<f32> = (0..100_000)
            .map(|_| draw_threshold(0.25, 0.03, &mut rng))
            .collect();
        let mean = draws.iter().map(|&v| v as f64).sum::<f64>() / draws.len() as f64;
        let var = draws
            .iter()
            .map(|&v| (v as f64 - mean).powi(2))
            .sum::<f64>()
            / draws.len() as f64;
        assert!((mean - 0.25).abs() < 0.001, "{mean}");
        assert!((var.sqrt() - 0.03).abs() < 0.001, "{}", var.sqrt());
        assert!((0..1000).all(|_| draw_threshold(0.02, 0.5, &mut rng) >= MIN_THRESHOLD));
        assert_eq!(draw_threshold(0.3, 0.0, &mut rng), 0.3);
    }
}
