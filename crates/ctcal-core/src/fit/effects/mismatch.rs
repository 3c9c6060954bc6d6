//! Threshold mismatch: every pixel's thresholds differ a little (fixed-pattern noise of the
//! comparators), frozen for the sensor's life ([`crate::sim::effects::mismatch`]).
//!
//! Signature: count dispersion beyond what the model's thresholds give. Evidence: the
//! per-pixel threshold spread that event timing measures (`estimate aps`: the spread of
//! per-pixel thresholds with each pixel's estimation noise removed), when its 95 % interval
//! lies above zero, in standard errors of that interval; without it, the excess of the
//! recording's within-tile dispersion of per-pixel counts over the model's. Start: the
//! measured spread.

use super::{Context, Effect, Evidence};
use crate::fit::metric::dispersion;

pub fn evidence(c: &Context) -> Evidence {
    if let Some((sigma, [lo, hi])) = c.mismatch_estimate {
        let se = ((hi - lo) / 3.92).max(1e-6);
        return Evidence {
            effect: Effect::Mismatch,
            score: sigma / se,
            relevant: lo > 0.004 && sigma > 0.008,
            text: format!(
                "event timing measures a frozen per-pixel threshold spread of {sigma:.4} (95 % interval {lo:.4} to {hi:.4})"
            ),
            start: Some(sigma.max(0.005)),
        };
    }
    let (r, s) = (
        c.real.pixels_of(c.geometry, c.subset),
        c.sim.pixels_of(c.geometry, c.subset),
    );
    match (
        dispersion(&r, c.geometry, c.kept),
        dispersion(&s, c.geometry, c.kept),
    ) {
        (Some(dr), Some(ds)) => {
            let excess = (dr / ds).ln();
            Evidence {
                effect: Effect::Mismatch,
                // the pooled dispersion's relative standard error is about 2 %
                score: excess / 0.02,
                relevant: excess > 0.05,
                text: format!(
                    "per-pixel counts are {:.0} % more dispersed within tiles than the model's",
                    100.0 * (excess.exp() - 1.0)
                ),
                start: Some(0.03),
            }
        }
        _ => Evidence::none(
            Effect::Mismatch,
            "too few events per pixel to compare dispersion",
        ),
    }
}
