//! Hot pixels: a few pixels with a defective (leaky) reset fire ON events at a high rate
//! whatever the scene. Modelled as `round(fraction * W * H)` pixels chosen uniformly, each
//! emitting a Poisson train of ON events at `hot_pixel_rate_hz` on top of its normal
//! events (the injection model of the `dev_hot_pixels` oracle).

use rand::Rng;
use rand::seq::index::sample;

/// The indices (y * W + x) of the hot pixels.
pub fn choose(pixels: usize, fraction: f64, rng: &mut impl Rng) -> Vec<usize> {
    let count = ((fraction * pixels as f64).round() as usize).min(pixels);
    let mut chosen = sample(rng, pixels, count).into_vec();
    chosen.sort_unstable();
    chosen
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn chooses_the_rounded_count_of_distinct_pixels() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(5);
        let hot = choose(43_200, 0.001, &mut rng);
        assert_eq!(hot.len(), 43);
        assert!(hot.windows(2).all(|w| w[0] < w[1]));
        assert!(choose(100, 0.0, &mut rng).is_empty());
    }
}
