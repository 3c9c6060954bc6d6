//! Refractory period: after an event the pixel's reset switch is held for a while, so the
//! pixel cannot fire again for `refractory_s` (Lichtsteiner et al. 2008).
//!
//! Semantics (those of v2e, which the `dev_refractory` oracle reproduces): a threshold
//! crossing that happens inside the refractory period is not lost. The memorised level is
//! not moved, so the change stays pending, and the event fires at the first moment the
//! period has ended if the change is then still beyond a threshold. The period starts at
//! every emitted threshold event of either polarity; shot-noise events neither wait for it
//! nor restart it. Consequences: the event count barely changes (217,026 -> 216,652 in the
//! oracle), no same-pixel interval is shorter than the period, and a fast pixel fires at
//! most once per period. (In a real DVS the reference follows the input during reset, which
//! would lose the change instead; v2e's choice is kept so simulations match v2e's.)

/// The earliest time (microseconds) a pixel that last fired at `last_event_us` may fire
/// (its behaviour is tested with the pixel, `pixel.rs`, and against the oracle).
#[inline]
pub fn earliest_event_us(last_event_us: f64, refractory_us: f64) -> f64 {
    last_event_us + refractory_us
}
