//! Refractory period: after an event the pixel is blind while its reset switch is held;
//! a change inside that time fires when it ends (v2e's semantics,
//! [`crate::sim::effects::refractory`]).
//!
//! Signature: a gap in the shortest same-pixel intervals (and a count deficit at high
//! local rates): the recording has far fewer intervals below some time than a model
//! without it. Evidence: the largest interval bin below which the recording holds less
//! than a quarter of the model's share, with the model's share above 2 %; the difference of
//! the shares in binomial standard errors. Start: that bin's upper edge.

use super::{Context, Effect, Evidence};
use crate::fit::metric::normalised;
use crate::fit::observe::{INTERVAL_BINS, interval_bin_start};

pub fn evidence(c: &Context) -> Evidence {
    let real_counts = c.real.intervals_of(c.geometry, c.subset);
    let n: f64 = real_counts.iter().map(|&v| v as f64).sum();
    let (real, sim) = (
        normalised(&real_counts),
        normalised(&c.sim.intervals_of(c.geometry, c.subset)),
    );
    let (mut real_cdf, mut sim_cdf) = (0.0, 0.0);
    let mut found = None;
    for k in 0..INTERVAL_BINS - 1 {
        real_cdf += real[k];
        sim_cdf += sim[k];
        if sim_cdf >= 0.02 && real_cdf < 0.25 * sim_cdf {
            found = Some((k, real_cdf, sim_cdf));
        } else if found.is_some() {
            break;
        }
    }
    let Some((k, real_share, sim_share)) = found else {
        return Evidence::none(
            Effect::Refractory,
            "the shortest same-pixel intervals are as common as the model makes them",
        );
    };
    let edge = interval_bin_start(k + 1);
    let se = (sim_share * (1.0 - sim_share) / n.max(1.0))
        .sqrt()
        .max(1e-9);
    Evidence {
        effect: Effect::Refractory,
        score: (sim_share - real_share) / se,
        relevant: sim_share - real_share > 0.02,
        text: format!(
            "{:.1} % of the recording's same-pixel intervals are shorter than {:.3} ms against {:.1} % in the model",
            100.0 * real_share,
            edge * 1e3,
            100.0 * sim_share
        ),
        start: Some(edge),
    }
}
