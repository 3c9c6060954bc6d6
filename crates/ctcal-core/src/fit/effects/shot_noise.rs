//! Shot noise: photon and dark-current shot noise makes pixels fire at random, both
//! polarities, more often in the dark (Graca & Delbruck, IISW 2021;
//! [`crate::sim::effects::shot_noise`]).
//!
//! Signature: an excess of both ON and OFF events among the events without
//! spatio-temporal support, stronger in the dark. Evidence: the smaller of the two excesses
//! (shot noise makes both alike; leak only ON), in Poisson standard errors; it matters
//! above 0.005 events per pixel-second. Start: twice that excess rate, divided by the
//! simulator's brightness factor averaged over the recording's intensities.

use super::{Context, Effect, Evidence, background_totals};
use crate::fit::observe::INTENSITY_BINS;
use crate::sim::effects::shot_noise::brightness_factor;

pub fn evidence(c: &Context) -> Evidence {
    let ([r_off, r_on, s_off, s_on], exposure) = background_totals(c);
    if exposure <= 0.0 {
        return Evidence::none(
            Effect::ShotNoise,
            "no reliable pixel-time to count isolated events",
        );
    }
    let (excess_on, excess_off) = (r_on - s_on, r_off - s_off);
    let both = excess_on.min(excess_off);
    let sigma = (r_on + s_on + r_off + s_off + 1.0).sqrt();
    let rate = 2.0 * both / exposure;
    // the dark rate: the observed rate is the dark rate times the brightness factor
    let bright = c.model.shot_noise_bright_factor() as f32;
    let factor = (0..INTENSITY_BINS)
        .map(|b| {
            let e = c.geometry.exposure_of(b, c.subset);
            e * brightness_factor(c.geometry.intensity_centres[b] as f32, bright) as f64
        })
        .sum::<f64>()
        / exposure;
    Evidence {
        effect: Effect::ShotNoise,
        score: 2.0 * both / sigma,
        relevant: rate > 0.005,
        text: format!(
            "isolated ON and OFF events exceed the model's by {:.4} and {:.4} Hz per pixel: {:.1} standard errors",
            excess_on / exposure,
            excess_off / exposure,
            2.0 * both / sigma
        ),
        start: Some((rate / factor.max(0.1) / 0.9).max(1e-3)),
    }
}
