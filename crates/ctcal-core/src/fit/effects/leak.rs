//! Leak: junction leakage makes the memorised level drift down, so pixels emit ON events
//! at a steady rate even in a static scene (Nozaki & Delbruck, IEEE TED 2017;
//! [`crate::sim::effects::leak`]).
//!
//! Signature: an excess of ON events among the events without spatio-temporal support
//! (isolated events), beyond any excess of OFF events (which shot noise would make
//! alike), growing with the time since a pixel's last event. Evidence: the ON excess
//! minus the OFF excess, in Poisson standard errors; it matters above 0.005 events per
//! pixel-second. Start: that excess rate (one leak event per period, most of them isolated).

use super::{Context, Effect, Evidence, background_totals};

pub fn evidence(c: &Context) -> Evidence {
    let ([r_off, r_on, s_off, s_on], exposure) = background_totals(c);
    if exposure <= 0.0 {
        return Evidence::none(
            Effect::Leak,
            "no reliable pixel-time to count isolated events",
        );
    }
    let excess_on = r_on - s_on;
    let excess_off = (r_off - s_off).max(0.0);
    let leak = excess_on - excess_off;
    let sigma = (r_on + s_on + r_off + s_off + 1.0).sqrt();
    let rate = leak / exposure;
    Evidence {
        effect: Effect::Leak,
        score: leak / sigma,
        relevant: rate > 0.005,
        text: format!(
            "isolated ON events exceed the model's by {:.4} Hz per pixel beyond the OFF excess ({:.4} Hz): {:.1} standard errors",
            excess_on / exposure,
            excess_off / exposure,
            leak / sigma
        ),
        start: Some((rate / 0.9).max(1e-3)),
    }
}
