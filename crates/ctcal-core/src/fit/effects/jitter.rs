//! Timestamp jitter: the time a sensor stamps on an event varies around the crossing time
//! (arbiter and readout delays; [`crate::sim::effects::jitter`]).
//!
//! Signature: a smeared interval histogram: same-pixel intervals shorter than the
//! recording's stamps otherwise allow. A recording whose stamps lie on a grid (a
//! simulator's frames) has no jitter. Evidence: the recording's share of same-pixel
//! intervals below 50 us against the model's, in binomial standard errors. Start: 100 us.

use super::{Context, Effect, Evidence};
use crate::fit::observe::interval_bin;

pub fn evidence(c: &Context) -> Evidence {
    if let Some(period) = c.timestamp_grid_us {
        return Evidence::none(
            Effect::TimestampJitter,
            format!("the timestamps lie on a {period} us grid: no jitter"),
        );
    }
    let (real, sim) = (
        c.real.intervals_of(c.geometry, c.subset),
        c.sim.intervals_of(c.geometry, c.subset),
    );
    let short = interval_bin(50e-6);
    let share = |h: &[u32]| {
        let n: f64 = h.iter().map(|&v| v as f64).sum();
        (
            h[..short].iter().map(|&v| v as f64).sum::<f64>() / n.max(1.0),
            n,
        )
    };
    let ((r, n), (s, _)) = (share(&real), share(&sim));
    let se = (s.max(1e-4) * (1.0 - s) / n.max(1.0)).sqrt();
    Evidence {
        effect: Effect::TimestampJitter,
        score: (r - s) / se,
        relevant: r > 2.0 * s + 0.005,
        text: format!(
            "{:.2} % of same-pixel intervals are below 50 us against {:.2} % in the model",
            100.0 * r,
            100.0 * s
        ),
        start: Some(100e-6),
    }
}
