//! Leak: junction leakage in the pixel's reset switch makes the memorised level drift, so
//! a pixel in a static scene emits ON events at a steady rate (Nozaki & Delbruck, "Temperature
//! and parasitic photocurrent effects in dynamic vision sensors", IEEE TED 2017). As in v2e,
//! the reference falls by `leak_rate_hz * factor * theta_on` per second: one ON event per
//! `1 / (leak_rate_hz * factor)` seconds, with a per-pixel lognormal `factor = 10^(s N(0,1))`
//! (`s` = `leak_spread_decades`, 0.1 by default). v2e also jitters the drift of every frame
//! by 10 %; that averages out over a threshold's worth of frames and is not modelled.
//!
//! The leak also grows with the light (`leak_rate_hz_per_dn`): the reset switch's junction
//! collects part of the photocurrent, so the leak rate rises with illumination and, in
//! bright light, exceeds the dark leak (Nozaki & Delbruck 2017, their parasitic
//! photocurrent; DVS-Voltmeter's drift `k4 + k5 L`, Lin et al., ECCV 2022). The rate is then
//! `leak_rate_hz + leak_rate_hz_per_dn * DN` at the pixel's present intensity, with the one
//! per-pixel factor.

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

    /// A static scene whose left half is at 40 DN and right half at 160 DN, 10 s in 100 ms
    /// samples: with a leak of 0.05 Hz in the dark and 0.01 Hz per DN (no spread), the left
    /// pixels fire ON at 0.45 Hz and the right at 1.65 Hz, one event per period from the
    /// first sample on (4 and 16 events each in 10 s), and never OFF.
    #[test]
    fn a_leak_that_grows_with_the_light_fires_at_its_rate_at_each_pixels_brightness() {
        use crate::sim::{PixelMaps, PixelParams, Sample, Simulator, pixel::Transition};
        let (w, h) = (8usize, 4usize);
        let dn: Vec<f32> = (0..w * h)
            .map(|i| if i % w < w / 2 { 40.0 } else { 160.0 })
            .collect();
        let samples: Vec<Sample> = (0..=100)
            .map(|k| Sample {
                t: 100_000 * k,
                dn: dn.clone(),
                transition: Transition::Linear,
            })
            .collect();
        let params = PixelParams {
            leak_rate_hz: Some(0.05),
            leak_rate_hz_per_dn: Some(0.01),
            leak_spread_decades: Some(0.0),
            ..PixelParams::ideal(0.3, 0.3)
        };
        let events = Simulator::new(&params, w, h, PixelMaps::default())
            .run_all(&samples)
            .unwrap();
        let mut counts = vec![0usize; w * h];
        for k in 0..events.len() {
            let (x, y) = (events.x[k] as usize, events.y[k] as usize);
            assert!(events.on[k], "an OFF event at ({x}, {y})");
            counts[y * w + x] += 1;
        }
        for (i, &n) in counts.iter().enumerate() {
            let expected = if i % w < w / 2 { 4 } else { 16 };
            assert_eq!(n, expected, "pixel {i}");
        }
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
