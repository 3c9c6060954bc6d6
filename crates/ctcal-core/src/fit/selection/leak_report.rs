//! Whether the final model's leak is a measurement: the recording's still pixels must be
//! able to show it, and not contradict it ([`crate::fit::effects::leak::StillBalance`]).
//! A leak the distance kept where neither holds stays in the model (the thresholds were
//! fitted beside it) and is reported as not determinable, with the counts.

use super::State;
use crate::estimate::interval::z95;
use crate::fit::Uncertain;
use crate::fit::effects::Effect;
use crate::fit::effects::leak::{DARK_SHARE_FLOOR, LeakGrowth, StillBalance};
use crate::fit::search::Simulation;
use std::collections::BTreeMap;

/// The final model's leak checked at the still pixels: what was counted (for
/// `assumptions`), and why `leak_rate_hz` is not a measurement, where it is not. The model
/// without its leak (nothing else changed, the same seed) is simulated once and the still
/// pixels of the judging blocks compared. `None` where the model has no leak.
pub fn check(
    simulation: &Simulation,
    state: &State,
    growth: Option<LeakGrowth>,
) -> Option<(String, Option<String>)> {
    let params = &state.model.params;
    let dark = params.leak_rate_hz.filter(|&r| r > 0.0)?;
    // the rate at the frames' median DN, where a leak grows with the light
    let rate = dark + params.leak_rate_hz_per_dn() * growth.map_or(0.0, |g| g.median_dn);
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
        "leak {rate:.4} Hz checked where only leak makes events, on the judging blocks: {}; a leak is a measurement only where these counts show it ({} standard errors) and the recording does not lack it",
        still.text(),
        super::super::effects::leak::STILL_Z
    );
    Some((note, still.unmeasured(rate)))
}

/// `leak_rate_hz_per_dn`: the leak's growth with the light.
const GROWTH_KEY: &str = "leak_rate_hz_per_dn";

/// The leak's growth with the light in the report, where the final model's leak has one
/// (the search held the event timing's growth, [`LeakGrowth`]). The search measured the
/// leak's scale, which pins the leak near the frames' median DN; the ratio it held has its
/// own error `e` (relative), which at that leak moves the dark part by `e` times the
/// light's share and the growth by `e` times the dark part's (in the logarithm). So
/// `leak_rate_hz_per_dn` takes the searched dark part's interval scaled by the ratio and
/// widened by the second, the dark part's widened by the first (in quadrature); either is
/// then not identified if it spans more than [`super::finish::UNMEASURED_SPAN`]. Where
/// the dark part is not identified otherwise, neither is the growth (the same reason);
/// where the floor held the dark part ([`DARK_SHARE_FLOOR`]) the dark part alone is not a
/// measurement (the growth, which then carries nearly all the leak, keeps its interval).
/// Returns the assumption.
pub fn growth(
    state: &mut State,
    growth: Option<LeakGrowth>,
    not_identified: &mut BTreeMap<String, String>,
) -> Option<String> {
    let params = &state.model.params;
    let per_dn = params.leak_rate_hz_per_dn.filter(|&g| g > 0.0)?;
    let dark = params.leak_rate_hz.filter(|&r| r > 0.0)?;
    let g = growth?;
    if let Some(why) = not_identified.get("leak_rate_hz").cloned() {
        not_identified.insert(GROWTH_KEY.into(), why);
    } else if let Some(u) = state.uncertainty.get("leak_rate_hz").cloned() {
        let e = g.ratio_relative_error;
        for (key, value, moved) in [
            (GROWTH_KEY, per_dn, e * g.dark_share()),
            ("leak_rate_hz", dark, e * (1.0 - g.dark_share())),
        ] {
            let w = widened(&u, value, moved);
            match super::finish::unmeasured(&w) {
                Some(why) => {
                    not_identified.insert(key.into(), why);
                    state.uncertainty.remove(key);
                }
                None => {
                    state.uncertainty.insert(key.into(), w);
                }
            }
        }
    }
    if g.dark_floored {
        let why = format!(
            "the event timing's drift at DN 0 is below {DARK_SHARE_FLOOR} of its drift at the frames' median DN ({:.0} DN): the dark part was held at that share of the leak there, a floor, not a measurement",
            g.median_dn
        );
        not_identified
            .entry("leak_rate_hz".into())
            .and_modify(|w| *w = format!("{w}; and {why}"))
            .or_insert(why);
        state.uncertainty.remove("leak_rate_hz");
    }
    Some(format!(
        "the leak grows with the light as the event timing's drift measured it: leak_rate_hz_per_dn / leak_rate_hz = {:.4} per DN ({:.0} % of the leak at the frames' median, {:.0} DN, is the dark part), held while the search scaled the leak; the ratio's error ({:.0} %) widens both parts' intervals{}",
        g.per_dn_over_dark,
        100.0 * g.dark_share(),
        g.median_dn,
        100.0 * g.ratio_relative_error,
        if g.dark_floored {
            format!(
                "; the dark part was held at {DARK_SHARE_FLOOR} of the leak at the median DN, a floor: the timing's drift at DN 0 was below that share"
            )
        } else {
            String::new()
        }
    ))
}

/// The interval `u` of a parameter scaled to `value`, each end moved out by a relative
/// error `relative` in the logarithm (in quadrature with the end's own distance); a side
/// at 0 or open stays so.
fn widened(u: &Uncertain, value: f64, relative: f64) -> Uncertain {
    let extra = z95() * relative;
    let end = |end: Option<f64>, sign: f64| -> Option<f64> {
        let e = end?;
        if e <= 0.0 || u.value <= 0.0 {
            return Some(0.0);
        }
        let width = (e / u.value).ln().abs();
        Some(value * (sign * width.hypot(extra)).exp())
    };
    let se = u
        .standard_error
        .filter(|_| u.value > 0.0)
        .map(|se| value * (se / u.value).hypot(relative));
    match u.interval() {
        Some([lo, hi]) => Uncertain::with_interval(value, se, [end(lo, -1.0), end(hi, 1.0)]),
        None => Uncertain::positive(value, se),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dark part of 0.2 Hz with 95 % interval [0.1, 0.4] (a factor 2 each way, ln 2 =
    /// 0.693 in the logarithm) and a growth known to 20 % (1.96 x 0.2 = 0.392): the growth's
    /// interval is its value times exp(-+hypot(0.693, 0.392)) = a factor 2.217 each way; an
    /// open end stays open and an end at 0 stays at 0.
    #[test]
    fn the_growth_s_interval_is_the_dark_part_s_widened_by_the_growth_s_error() {
        let dark = Uncertain::with_interval(0.2, Some(0.07), [Some(0.1), Some(0.4)]);
        let g = widened(&dark, 0.01, 0.2);
        let factor = (2f64.ln().hypot(z95() * 0.2)).exp();
        let [lo, hi] = g.ci95.unwrap();
        assert!((lo.unwrap() - 0.01 / factor).abs() < 1e-12, "{lo:?}");
        assert!((hi.unwrap() - 0.01 * factor).abs() < 1e-12, "{hi:?}");
        assert!((factor - 2.217).abs() < 1e-3, "{factor}");
        assert!((g.standard_error.unwrap() - 0.01 * (0.35f64).hypot(0.2)).abs() < 1e-12);
        let open = Uncertain::with_interval(0.2, None, [Some(0.0), None]);
        assert_eq!(widened(&open, 0.01, 0.2).ci95, Some([Some(0.0), None]));
    }
}
