//! Shot noise: photon and dark-current shot noise makes pixels fire at random, more often
//! in the dark (Graca & Delbruck, "Unraveling the paradox of intensity-dependent DVS pixel
//! noise", IISW 2021). As in v2e, the ON+OFF rate at intensity DN is
//! `R(DN) = R * (1 - (1 - b) * (DN + 20) / 275)` with `b` the bright factor (0.25: a quarter
//! of the dark rate at white), each polarity's share scaled by `nominal / pixel threshold`
//! (low-threshold pixels are noisier), and a noise event resets the pixel's reference to its
//! current level. Events are drawn as a Poisson process in continuous time by thinning:
//! candidates arrive at the pixel's maximal rate and are kept with probability `R(DN)/R`.

/// Fraction of the dark rate at intensity `dn`.
#[inline]
pub fn brightness_factor(dn: f32, bright_factor: f32) -> f32 {
    (1.0 - (1.0 - bright_factor) * (dn.max(0.0) + 20.0) / 275.0).clamp(0.0, 1.0)
}

/// A pixel's candidate rate (per microsecond) and the fraction of its noise that is ON.
pub fn pixel_rates(
    rate_hz: f64,
    nominal_on: f64,
    nominal_off: f64,
    theta_on: f32,
    theta_off: f32,
) -> (f64, f32) {
    let on = nominal_on / theta_on as f64;
    let off = nominal_off / theta_off as f64;
    (
        (rate_hz / 2.0) * (on + off) * 1e-6,
        (on / (on + off)) as f32,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rate_falls_from_dark_to_white_as_v2e() {
        assert!((brightness_factor(255.0, 0.25) - 0.25).abs() < 1e-6);
        assert!((brightness_factor(0.0, 0.25) - (1.0 - 0.75 * 20.0 / 275.0)).abs() < 1e-6);
        assert!((brightness_factor(90.0, 0.25) - 0.7).abs() < 1e-6);
    }

    #[test]
    fn nominal_pixels_split_noise_evenly() {
        let (rate, on) = pixel_rates(1.0, 0.3, 0.3, 0.3, 0.3);
        assert!((rate / 1e-6 - 1.0).abs() < 1e-6);
        assert!((on - 0.5).abs() < 1e-6);
        // a pixel with half the ON threshold makes twice the ON noise
        let (_, on) = pixel_rates(1.0, 0.3, 0.3, 0.15, 0.3);
        assert!((on - 2.0 / 3.0).abs() < 1e-6);
    }
}
