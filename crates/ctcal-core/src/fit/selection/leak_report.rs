//! Whether the final model's leak is a measurement: the recording's still pixels must be
//! able to show it, and not contradict it ([`crate::fit::effects::leak::StillBalance`]).
//! A leak the distance kept where neither holds stays in the model (the thresholds were
//! fitted beside it) and is reported as not determinable, with the counts.

use super::State;
use crate::fit::effects::Effect;
use crate::fit::effects::leak::StillBalance;
use crate::fit::search::Simulation;

/// The final model's leak checked at the still pixels: what was counted (for
/// `assumptions`), and why `leak_rate_hz` is not a measurement, where it is not. The model
/// without its leak (nothing else changed, the same seed) is simulated once and the still
/// pixels of the judging blocks compared. `None` where the model has no leak.
pub fn check(simulation: &Simulation, state: &State) -> Option<(String, Option<String>)> {
    let rate = state.model.params.leak_rate_hz.filter(|&r| r > 0.0)?;
    let mut without = state.model.params.clone();
    Effect::Leak.clear(&mut without);
    let observed = match simulation.observe(&without, &state.masked) {
        Ok(o) => o,
        Err(e) => {
            let why = format!(
                "the model without its leak could not be simulated to check the leak at the still pixels ({e}); the model keeps {rate:.4} Hz as a fitted term, not a measurement"
            );
            return Some((why.clone(), Some(why)));
        }
    };
    let still = StillBalance::judged(
        &simulation.real,
        (&observed, &state.model.observed),
        simulation.geometry,
    );
    let note = format!(
        "leak_rate_hz {rate:.4} Hz checked where only leak makes events, on the judging blocks: {}; a leak is a measurement only where these counts show it ({} standard errors) and the recording does not lack it",
        still.text(),
        super::super::effects::leak::STILL_Z
    );
    Some((note, still.unmeasured(rate)))
}
