//! How far the fitted thresholds move with the shot-noise rate. The thresholds are fitted
//! to the event counts the model makes beside its noise, so a polarity whose events are
//! mostly noise is fixed by the small difference of two large counts: the noise rate's own
//! uncertainty moves it, and a profile at one rate does not show that (coverage draw
//! 10023: 1.3 Hz of shot noise at 41 DN made about 80 % of the events; with the noise read
//! 15 % high, ON was fitted at 4.42 [2.57, 7.60] for a true 0.74).
//!
//! Where the final model has shot noise and its thresholds are fitted, they are profiled
//! again with the noise rate at each end of its 95 % interval and at the fitted rate (the
//! same profile each time, so that only the rate differs, as in
//! [`super::frame_quality`]). A threshold that reaches an end of the profile's range at
//! any of them is not determined by the counts beside the noise (at that rate the noise
//! alone makes as many events of its polarity as the recording, or more); otherwise the
//! largest log change, read as 1.96 standard deviations, widens its interval in quadrature
//! in ln C (as the method systematic does). The noise rate is a nuisance parameter
//! profiled over its range, not fixed at its value (profile likelihood, e.g. Cox &
//! Hinkley, *Theoretical Statistics*, 1974, sec. 9.3). A first rule that also withheld a
//! threshold moving by more than a factor 2 withheld two that covered the truth (draws
//! 10006 and 10020, OFF 0.857 and 0.475 for 0.795 and 0.489, moving to 1.71 and 1.20 at
//! the noise's upper end); widened, they still cover.

use super::super::Uncertain;
use super::super::search::{Simulation, THRESHOLD_RANGE};
use super::State;
use super::method_systematic::widen_ln;
use crate::estimate::interval::z95;
use std::collections::BTreeMap;

/// The thresholds (OFF, ON) profiled at the low end of the noise rate, at the fitted rate
/// and at the high end (`None` for an end the interval leaves open).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseProfiles {
    pub rates_hz: [Option<f64>; 3],
    pub off: [Option<f64>; 3],
    pub on: [Option<f64>; 3],
}

/// What the check found: the note for `assumptions`, and the thresholds it leaves
/// undetermined with why.
pub struct NoiseShare {
    pub note: String,
    pub undetermined: Vec<(String, String)>,
}

/// Profiles the final model's thresholds at the ends of its shot-noise interval and
/// applies [`judge`]; `None` where the model has no shot noise or no interval for it.
pub fn check(simulation: &Simulation, state: &mut State) -> Option<NoiseShare> {
    let model = &state.model.params;
    let rate = model.shot_noise_rate_hz.filter(|r| *r > 0.0)?;
    let [lo, hi] = state.uncertainty.get("shot_noise_rate_hz")?.interval()?;
    let rates_hz = [Some(lo.unwrap_or(0.0).max(0.0)), Some(rate), hi];
    let mut off = [None; 3];
    let mut on = [None; 3];
    for (k, r) in rates_hz.iter().enumerate() {
        let Some(r) = *r else { continue };
        let mut params = model.clone();
        params.shot_noise_rate_hz = Some(r);
        if let Ok(profiled) = simulation.profile(&params, &state.masked, false) {
            off[k] = Some(profiled.params.ct_off);
            on[k] = Some(profiled.params.ct_on);
        }
    }
    let profiles = NoiseProfiles { rates_hz, off, on };
    Some(judge(&profiles, &mut state.uncertainty))
}

/// Widens or withholds each threshold by how far `profiles` move it (see the module docs).
pub fn judge(
    profiles: &NoiseProfiles,
    uncertainty: &mut BTreeMap<String, Uncertain>,
) -> NoiseShare {
    let mut parts = Vec::new();
    let mut undetermined = Vec::new();
    for (key, name, values) in [
        ("ct_off", "OFF", profiles.off),
        ("ct_on", "ON", profiles.on),
    ] {
        let (part, why) = judge_one(key, name, values, profiles.rates_hz, uncertainty);
        parts.push(part);
        undetermined.extend(why.map(|why| (key.to_string(), why)));
    }
    let note = format!(
        "noise-rate check: the final model's thresholds profiled again with the shot noise at the low end of its 95 % interval, at the fitted rate and at the high end ({} Hz): {}; a threshold's largest log change, read as 1.96 standard deviations, widens its interval in quadrature, and one that reaches an end of the profile's range is not determined",
        rate_list(profiles.rates_hz),
        parts.join("; ")
    );
    NoiseShare { note, undetermined }
}

/// One threshold's verdict (`key` in `uncertainty`, `name` in the note) from its `values`
/// profiled at `rates_hz`: its part of the note, and why it is not determined where it
/// reaches an end of the profile's range; otherwise its interval widened by its largest
/// log change.
fn judge_one(
    key: &str,
    name: &str,
    values: [Option<f64>; 3],
    rates_hz: [Option<f64>; 3],
    uncertainty: &mut BTreeMap<String, Uncertain>,
) -> (String, Option<String>) {
    let said = format!(
        "{name} {} / {} / {}",
        shown(values[0]),
        shown(values[1]),
        shown(values[2])
    );
    let Some(mid) = values[1] else {
        return (format!("{said} (not profiled at the fitted rate)"), None);
    };
    let at_bound = values
        .iter()
        .flatten()
        .any(|v| *v <= THRESHOLD_RANGE.0 * 1.0001 || *v >= THRESHOLD_RANGE.1 * 0.9999);
    if at_bound {
        let why = format!(
            "the events of this polarity are mostly the shot noise's: profiled again with the noise rate at its 95 % interval's ends and at the fitted rate ({} Hz), {key} reads {} / {} / {}, reaching an end of the profile's range ({} to {}): within the noise rate's interval the noise alone may make the recording's events of this polarity, so the counts do not fix the threshold",
            rate_list(rates_hz),
            shown(values[0]),
            shown(values[1]),
            shown(values[2]),
            THRESHOLD_RANGE.0,
            THRESHOLD_RANGE.1
        );
        return (format!("{said}: not determined"), Some(why));
    }
    let ln_change = values
        .iter()
        .flatten()
        .map(|v| (v / mid).ln().abs())
        .fold(0.0, f64::max);
    let widened = widen_ln(uncertainty, key, ln_change / z95());
    let part = match widened {
        Some(w) if ln_change > 0.0 => format!("{said}: {w}"),
        _ => said,
    };
    (part, None)
}

/// A profiled threshold to four decimals, `-` where there is none.
fn shown(v: Option<f64>) -> String {
    v.map_or("-".to_string(), |v| format!("{v:.4}"))
}

fn rate_list(rates: [Option<f64>; 3]) -> String {
    rates
        .iter()
        .map(|r| r.map_or("open".to_string(), |r| format!("{r:.4}")))
        .collect::<Vec<_>>()
        .join(" / ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn uncertainty() -> BTreeMap<String, Uncertain> {
        BTreeMap::from([
            (
                "ct_off".to_string(),
                Uncertain::with_interval(0.40, None, [Some(0.30), Some(0.55)]),
            ),
            (
                "ct_on".to_string(),
                Uncertain::with_interval(4.42, None, [Some(2.57), Some(7.60)]),
            ),
        ])
    }

    /// OFF moves 0.38 / 0.40 / 0.44: ln(0.44 / 0.40) = 0.09531, a standard deviation of
    /// 0.04863 in ln C, so [0.30, 0.55] becomes 0.40 exp(-hypot(ln(0.40 / 0.30), 1.96 x
    /// 0.04863)) = 0.40 exp(-hypot(0.28768, 0.09531)) = 0.29542 and 0.40 exp(hypot(0.31845,
    /// 0.09531)) = 0.55773; ON moves 1.10 / 4.42 / 5.0 (draw 10023's kind): not determined.
    #[test]
    fn a_threshold_follows_the_noise_rate_into_its_interval_or_out_of_determination() {
        let mut u = uncertainty();
        let profiles = NoiseProfiles {
            rates_hz: [Some(1.39), Some(1.51), Some(1.89)],
            off: [Some(0.38), Some(0.40), Some(0.44)],
            on: [Some(1.10), Some(4.42), Some(5.0)],
        };
        let share = judge(&profiles, &mut u);
        let [lo, hi] = u["ct_off"].ci95.unwrap();
        assert!((lo.unwrap() - 0.29542).abs() < 1e-4, "{lo:?}");
        assert!((hi.unwrap() - 0.55773).abs() < 1e-4, "{hi:?}");
        assert_eq!(share.undetermined.len(), 1);
        assert_eq!(share.undetermined[0].0, "ct_on");
        assert!(share.undetermined[0].1.contains("1.1000 / 4.4200 / 5.0000"));
        assert!(share.note.contains("1.3900 / 1.5100 / 1.8900 Hz"));
        // a factor 2.49 inside the range (draw 10020's OFF): widened by ln 2.49 = 0.91229
        // in quadrature, [0.30, 0.55] about 0.40 -> upper end 0.40 exp(hypot(0.31845,
        // 0.91229)) = 1.0512
        let mut u = uncertainty();
        let far = NoiseProfiles {
            rates_hz: [Some(0.1), Some(0.2), Some(0.4)],
            off: [Some(0.40), Some(0.40), Some(0.996)],
            on: [Some(4.42), Some(4.42), Some(4.42)],
        };
        assert!(judge(&far, &mut u).undetermined.is_empty());
        let [_, hi] = u["ct_off"].ci95.unwrap();
        assert!((hi.unwrap() - 1.0512).abs() < 1e-3, "{hi:?}");
        // a threshold the noise barely moves keeps its interval within rounding
        let mut u = uncertainty();
        let steady = NoiseProfiles {
            rates_hz: [Some(0.0), Some(0.2), None],
            off: [Some(0.40), Some(0.40), None],
            on: [Some(4.30), Some(4.42), None],
        };
        let share = judge(&steady, &mut u);
        assert!(share.undetermined.is_empty());
        assert_eq!(u["ct_off"].ci95, Some([Some(0.30), Some(0.55)]));
        let [lo, _] = u["ct_on"].ci95.unwrap();
        assert!(lo.unwrap() < 2.57, "{lo:?}");
        assert!(share.note.contains("0.0000 / 0.2000 / open Hz"));
    }
}
