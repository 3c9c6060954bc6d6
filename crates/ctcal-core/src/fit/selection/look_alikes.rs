//! The thresholds of the models the data do not separate from the fitted one.
//!
//! Where a kept effect and its look-alike explain the recording equally well within chance
//! ([`super::alternatives`]), both models are named, and the kept effect's interval
//! reaches 0. The thresholds were read from the counts with the kept effect in the model.
//! The model with the look-alike in its place reads them again (a slow photoreceptor
//! thins the fast changes' events where a refractory period drops each pixel's bursts), so
//! the choice between the two models is an uncertainty of the thresholds as well. Each
//! threshold's interval reaches the look-alike model's value on its side, in quadrature in
//! ln C (model uncertainty carried as the span of the models the data allow: Draper,
//! *Assessment and propagation of model uncertainty*, JRSS B 57, 1995). Its thresholds
//! were profiled when it was compared, so this costs no simulation. The kept effect's own
//! count check ([`super::count_effects`]) may also have moved the thresholds towards less
//! of it; both terms are added in quadrature, which errs on the wide side. A look-alike
//! model whose threshold sits at an end of the profile's range (0.02 or 5) is reached
//! like any other value: it bounds the interval there.
//!
//! Measured on the coverage study's draws in `benches/coverage/fit-count-effects-2026-12-07`.

use super::super::Uncertain;
use super::super::effects::Effect;
use super::alternatives::Ambiguity;
use super::method_systematic::reach_ln;
use std::collections::BTreeMap;

/// The thresholds (ON, OFF) divided by the model's.
type Ratios = [f64; 2];

/// Each look-alike the data do not separate from a kept effect, in its place: each
/// threshold's interval reaches the final threshold times the ratio of that model's
/// threshold to the kept model's when the two were compared (the loop may have changed the
/// model since), in ln C in quadrature. A pair whose kept effect the final model no longer
/// has is left out. Returns the assumption (none without such a pair).
pub(super) fn widen(
    uncertainty: &mut BTreeMap<String, Uncertain>,
    ambiguities: &[Ambiguity],
    model: &crate::sim::PixelParams,
) -> Option<String> {
    let mut tried = Vec::new();
    let mut ratios = Vec::new();
    for a in ambiguities {
        let still_kept = Effect::parse(&a.kept).is_some_and(|e| e.value(model).is_some());
        let (Some(ratio), true) = (ratio_of(a), still_kept) else {
            continue;
        };
        tried.push(format!(
            "{} in place of {}: ON x{:.3}, OFF x{:.3}",
            a.alternative, a.kept, ratio[0], ratio[1]
        ));
        ratios.push(ratio);
    }
    if tried.is_empty() {
        return None;
    }
    let widened = reach_all(uncertainty, &ratios);
    Some(format!(
        "the thresholds of the models the data do not separate from the fitted one (each threshold of the look-alike's model over the kept one's when they were compared): {}; {}",
        tried.join("; "),
        widened_text(&widened)
    ))
}

/// The look-alike model's thresholds over the kept model's (ON, OFF), where both are known
/// and positive.
fn ratio_of(a: &Ambiguity) -> Option<Ratios> {
    let ratio = |key: &str| {
        let alt = *a.alternative_thresholds.get(key)?;
        let kept = *a.kept_thresholds.get(key)?;
        (alt > 0.0 && kept > 0.0).then(|| alt / kept)
    };
    Some([ratio("ct_on")?, ratio("ct_off")?])
}

/// Each threshold's interval reaching the furthest ratio on each side among `ratios`, once
/// per side (in quadrature in ln C); returns what changed.
fn reach_all(uncertainty: &mut BTreeMap<String, Uncertain>, ratios: &[Ratios]) -> Vec<String> {
    let mut widened = Vec::new();
    for (pol, key) in ["ct_on", "ct_off"].into_iter().enumerate() {
        let valid = || {
            ratios
                .iter()
                .map(move |r| r[pol])
                .filter(|r| r.is_finite() && *r > 0.0)
        };
        let up = valid().fold(1.0, f64::max);
        let down = valid().fold(1.0, f64::min);
        for r in [up, down] {
            if r != 1.0
                && let Some(change) = reach_ln(uncertainty, key, r)
            {
                widened.push(change);
            }
        }
    }
    widened
}

fn widened_text(widened: &[String]) -> String {
    if widened.is_empty() {
        "no threshold interval widened (a threshold without one is not determined)".into()
    } else {
        format!(
            "the intervals reach them in quadrature in ln C: {}",
            widened.join("; ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn threshold(value: f64, lo: f64, hi: f64) -> Uncertain {
        Uncertain {
            value,
            standard_error: None,
            ci95: Some([Some(lo), Some(hi)]),
        }
    }

    #[test]
    fn each_side_reaches_its_furthest_ratio_once_in_quadrature() {
        // ON 1.0 [0.8, 1.25]: ln half-widths 0.2231 each side
        let mut u = BTreeMap::from([
            ("ct_on".to_string(), threshold(1.0, 0.8, 1.25)),
            ("ct_off".to_string(), threshold(0.5, 0.4, 0.625)),
        ]);
        // ON moved to 0.5 and 0.6 (down) and 1.1 (up): the furthest each way, the lower side
        // sqrt(0.22314^2 + ln 2^2) = 0.72818 -> 0.48279, the upper sqrt(0.22314^2 +
        // ln 1.1^2) = 0.24265 -> 1.27462. OFF unmoved.
        let changed = reach_all(&mut u, &[[0.5, 1.0], [0.6, 1.0], [1.1, 1.0]]);
        assert_eq!(changed.len(), 2, "{changed:?}");
        let [lo, hi] = u["ct_on"].ci95.unwrap();
        assert!((lo.unwrap() - 0.48279).abs() < 1e-4, "{lo:?}");
        assert!((hi.unwrap() - 1.27462).abs() < 1e-4, "{hi:?}");
        assert_eq!(u["ct_off"].ci95, Some([Some(0.4), Some(0.625)]));
    }

    fn ambiguity(kept: &str, thresholds: (f64, f64), alternative: (f64, f64)) -> Ambiguity {
        let map = |(on, off): (f64, f64)| {
            BTreeMap::from([("ct_on".to_string(), on), ("ct_off".to_string(), off)])
        };
        Ambiguity {
            kept: kept.into(),
            alternative: "bandwidth".into(),
            parameter: "cutoff_hz".into(),
            value: 20.0,
            error_kept: 1.0,
            error_alternative: 1.01,
            chance: Some(0.1),
            separated_by: String::new(),
            kept_ci95_if_present: None,
            kept_thresholds: map(thresholds),
            alternative_thresholds: map(alternative),
        }
    }

    /// The look-alike's ON threshold half the kept model's when they were compared (0.4
    /// against 0.8, the final model reading 1.0): the final ON interval reaches 0.5 below,
    /// 0.48279 as above. A pair whose kept effect (leak) the final model lacks is left out.
    #[test]
    fn the_interval_reaches_the_look_alike_by_its_ratio_when_compared() {
        let mut u = BTreeMap::from([
            ("ct_on".to_string(), threshold(1.0, 0.8, 1.25)),
            ("ct_off".to_string(), threshold(0.5, 0.4, 0.625)),
        ]);
        let model = crate::sim::PixelParams {
            refractory_s: Some(1e-3),
            ..crate::sim::PixelParams::ideal(1.0, 0.5)
        };
        let pairs = [
            ambiguity("refractory", (0.8, 0.5), (0.4, 0.5)),
            ambiguity("leak", (0.8, 0.5), (0.1, 0.05)),
        ];
        let note = widen(&mut u, &pairs, &model).unwrap();
        assert!(
            note.contains("bandwidth in place of refractory: ON x0.500, OFF x1.000"),
            "{note}"
        );
        assert!(!note.contains("in place of leak"), "{note}");
        let [lo, hi] = u["ct_on"].ci95.unwrap();
        assert!((lo.unwrap() - 0.48279).abs() < 1e-4, "{lo:?}");
        assert_eq!(hi, Some(1.25));
        assert_eq!(u["ct_off"].ci95, Some([Some(0.4), Some(0.625)]));
    }
}
