//! Whether a polarity's samples show a threshold at all: a peak above the noise beneath it.
//!
//! Between two consecutive events of a pixel its log intensity changed by exactly its
//! threshold when the second event is a crossing (Lichtsteiner et al., JSSC 2008; the
//! event generation model of Gallego et al., TPAMI 2022). An event the light did not cause
//! (shot noise, a leak event, a hot pixel; Graca & Delbruck, IISW 2021) fires before the
//! change reached the threshold, so its sample lies anywhere below it, densest near zero
//! where the light barely moved. A polarity whose events are crossings shows a peak at its
//! threshold above that falling floor; one whose events are mostly noise shows the floor
//! alone, and the mode of its samples ([`super::model::mode`]) is then wherever the falling
//! density's relative window holds the most samples, not a threshold (a dim, slowly moving
//! texture with 0.76 Hz of shot noise per pixel: 88 % of the events noise, the ON samples
//! all below 0.3 and their mode 0.07 for a threshold of 0.48).
//!
//! The test: the samples within `h` of the mode (`m (1 +- h)`) against the counts that
//! four bands between zero and the mode predict, each scaled to the window's width (the
//! bands `[0.10, 0.25)`, `[0.25, 0.40)`, `[0.40, 0.55)`, `[0.55, 0.70)` of the mode). Where
//! the samples are noise the density falls from zero through every band to the mode, and
//! no band predicts fewer than the window holds; where they are crossings, some band between
//! zero and the threshold holds only the noise and the peak stands out of it. Bands rather
//! than the density just below the mode, because a lagging photoreceptor splits a dim
//! scene's samples into two peaks about the threshold (0.22 and 0.5 for 0.35 in a
//! bandwidth-limited texture at mid-dim light; the fit's lag term puts them back), and the
//! lower one fills the band just below the upper. Two widths: 15 % for a sharp peak (a
//! simulator's exact thresholds), 30 % for one the frames' interpolation broadens (10-30 %
//! on recordings; see [`super::PolarityEstimate::sample_spread`]). A polarity stands out
//! when any of the eight comparisons exceeds its prediction by [`PEAK_Z`] Poisson standard
//! errors.

use serde::Serialize;

/// The excess (Poisson standard errors) by which a peak must stand out of a band below it.
/// On a floor as dense at the mode as in every band (uniform samples, 2,000 draws each) the
/// best of the eight comparisons passes in 1.4 % of draws of 3,000 samples, 3.6 % of 300
/// and 14 % of 100: a polarity with few samples needs a clear peak (nine in a window with
/// an empty band) to stand out.
pub const PEAK_Z: f64 = 3.0;

/// The half-widths of the windows about the mode, relative to it.
const HALF_WIDTHS: [f64; 2] = [0.15, 0.30];

/// The bands between zero and the mode whose densities predict the noise within the
/// windows, relative to the mode.
const BANDS: [(f64, f64); 4] = [(0.10, 0.25), (0.25, 0.40), (0.40, 0.55), (0.55, 0.70)];

/// How far a polarity's samples peak at their mode above the noise between zero and it: the
/// comparison of a window and a band that stands out most.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Peak {
    /// The mode of the polarity's positive samples (log units).
    pub mode: f64,
    /// The samples within the window, and its half-width (relative to the mode).
    pub in_window: usize,
    pub half_width: f64,
    /// The band below the mode (relative), its samples, and what they predict within the
    /// window.
    pub band: (f64, f64),
    pub in_band: usize,
    pub expected_from_band: f64,
    /// The window's excess over the prediction in Poisson standard errors.
    pub z: f64,
}

impl Peak {
    /// The peak of `samples` (one polarity's, in any order) at their `mode`; `None` without
    /// a positive mode.
    pub fn of(samples: &[f64], mode: f64) -> Option<Peak> {
        if !(mode > 0.0 && mode.is_finite()) {
            return None;
        }
        let count = |lo: f64, hi: f64| samples.iter().filter(|&&v| v >= lo && v < hi).count();
        let in_bands = BANDS.map(|(lo, hi)| count(lo * mode, hi * mode));
        HALF_WIDTHS
            .iter()
            .flat_map(|&h| {
                let in_window = count(mode * (1.0 - h), mode * (1.0 + h));
                BANDS.iter().zip(in_bands).map(move |(&band, in_band)| {
                    let scale = 2.0 * h / (band.1 - band.0);
                    let expected = scale * in_band as f64;
                    let variance = in_window as f64 + scale * scale * in_band as f64;
                    Peak {
                        mode,
                        in_window,
                        half_width: h,
                        band,
                        in_band,
                        expected_from_band: expected,
                        z: (in_window as f64 - expected) / variance.max(1.0).sqrt(),
                    }
                })
            })
            .max_by(|a, b| a.z.total_cmp(&b.z))
    }

    /// Whether the peak stands out of the noise beneath it.
    pub fn stands_out(&self) -> bool {
        self.z >= PEAK_Z
    }

    /// What the samples of polarity `name` (ON, OFF) show, for a withheld threshold's
    /// reason.
    pub fn describe(&self, name: &str) -> String {
        format!(
            "the {name} samples (the log change between a pixel's consecutive events) show no threshold peak above the noise between zero and their mode {:.3}: at best {} within {:.0} % of it where the band {:.2}-{:.2} of it predicts {:.0} ({:.1} standard errors, {PEAK_Z} needed); the {name} events are mostly noise (shot noise, leak, hot pixels), not threshold crossings",
            self.mode,
            self.in_window,
            100.0 * self.half_width,
            self.band.0,
            self.band.1,
            self.expected_from_band,
            self.z
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_xoshiro::Xoshiro256PlusPlus;

    /// Samples of a noise floor falling from zero (half-normal, scale `floor`) and of
    /// crossings at `threshold` spread by `spread` (relative), `crossings` of `total`.
    fn samples(
        total: usize,
        crossings: usize,
        threshold: f64,
        spread: f64,
        floor: f64,
    ) -> Vec<f64> {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        let mut normal = || {
            // Box-Muller
            let (u, v): (f64, f64) = (rng.random::<f64>().max(1e-12), rng.random());
            (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        };
        (0..total)
            .map(|i| {
                if i < crossings {
                    threshold * (1.0 + spread * normal())
                } else {
                    (floor * normal()).abs()
                }
            })
            .collect()
    }

    #[test]
    fn a_noise_floor_alone_has_no_peak_where_its_mode_lands_on_the_fall() {
        // 800 noise samples falling from zero with scale 0.1, no crossing: at a mode on the
        // falling floor every band below holds a higher density than the window
        let noise = samples(800, 0, 0.5, 0.0, 0.1);
        for mode in [0.1, 0.15, 0.2] {
            let peak = Peak::of(&noise, mode).unwrap();
            assert!(!peak.stands_out(), "mode {mode}: {peak:?}");
            assert!(peak.z < 0.0, "{peak:?}");
        }
    }

    #[test]
    fn crossings_stand_out_of_a_noise_floor_several_times_larger() {
        // 120 crossings at 0.6 (10 % spread) among 700 noise samples of scale 0.15 (the
        // shape of a dim recording's samples whose threshold is still read right): the
        // band 0.33-0.42 holds the floor's tail, 700 x 2 (Phi(2.8) - Phi(2.2)) = 16; the
        // narrow window 120 x 0.87 = 104 crossings, against 32 predicted
        let mixed = samples(820, 120, 0.6, 0.1, 0.15);
        let peak = Peak::of(&mixed, 0.6).unwrap();
        assert!(peak.stands_out(), "{peak:?}");
        assert_eq!(peak.band, (0.55, 0.70));
        assert!((8..28).contains(&peak.in_band), "{peak:?}");
        assert!(peak.z > 4.0, "{peak:?}");
    }

    #[test]
    fn the_upper_of_two_lag_peaks_stands_out_of_the_empty_band_near_zero() {
        // a lagging photoreceptor splits the samples about the threshold (0.35): peaks at
        // 0.22 and 0.5, nothing near zero; the band just below the upper peak holds the
        // lower one, the lowest band almost nothing
        let mut split = samples(3000, 3000, 0.22, 0.15, 0.1);
        split.extend(samples(3000, 3000, 0.5, 0.12, 0.1));
        let peak = Peak::of(&split, 0.5).unwrap();
        assert!(peak.stands_out(), "{peak:?}");
        assert_eq!(peak.band, (0.10, 0.25));
    }

    #[test]
    fn a_flat_floor_passes_for_a_peak_in_few_draws() {
        // the null: samples as dense at the mode as in every band; 200 draws of 3,000
        // uniform samples on [-1, 1.5) with the mode at 0.5 (1.4 % expected to pass)
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        let passed = (0..200)
            .filter(|_| {
                let flat: Vec<f64> = (0..3000).map(|_| rng.random::<f64>() * 2.5 - 1.0).collect();
                Peak::of(&flat, 0.5).unwrap().stands_out()
            })
            .count();
        assert!(passed <= 8, "{passed} of 200");
    }

    #[test]
    fn a_broad_peak_stands_out_through_the_wide_window() {
        // crossings spread by 25 % (interpolated frames): the 30 % window holds most of them
        let broad = samples(1000, 300, 0.4, 0.25, 0.08);
        let peak = Peak::of(&broad, 0.4).unwrap();
        assert!(peak.stands_out(), "{peak:?}");
        assert_eq!(peak.half_width, 0.30);
    }

    #[test]
    fn no_positive_mode_is_no_peak_to_test() {
        assert!(Peak::of(&[0.1, 0.2], 0.0).is_none());
        assert!(Peak::of(&[0.1, 0.2], f64::NAN).is_none());
    }
}
