//! Scoring one parameter of one run against the truth: which population it belongs to,
//! and whether its interval covered the true value.

use crate::coverage::method::{MISMATCH_LIMIT, effect_of, truth_key};
use crate::coverage::record::RunRecord;
use crate::coverage::reported::Reported;
use crate::coverage::truth::Truth;

/// One (run, parameter) scored.
#[derive(Clone, Debug, PartialEq)]
pub enum Score<'a> {
    /// The command failed (or the case could not be written).
    Failed,
    NotReported,
    NotDeterminable(&'a str),
    /// A value: `reported` is an interval or a bare value.
    Value {
        value: f64,
        truth: f64,
        reported: &'a Reported,
        covered: bool,
    },
}

/// Whether `record` is scored on `parameter`: the method reports it, and the truth defines
/// it; a fitted effect parameter only where the effect is present.
pub fn in_population(record: &RunRecord, parameter: &str) -> bool {
    if !record.method.parameters().contains(&parameter) {
        return false;
    }
    let Some(truth) = &record.truth else {
        return true;
    };
    // a spread is scored whether or not the draw has one (a ctcal draw without mismatch
    // has a true spread of 0; the other simulators' truths give none, and are not scored)
    let effect_needed =
        record.method.is_fit() && !["ct_sigma", MISMATCH_LIMIT].contains(&parameter);
    truth.value(truth_key(parameter)).is_some()
        && (!effect_needed || effect_of(parameter).is_none_or(|e| truth.has_effect(e)))
}

/// The score of `parameter` in `record` (`None`: not in its population).
pub fn score<'a>(record: &'a RunRecord, parameter: &str) -> Option<Score<'a>> {
    if !in_population(record, parameter) {
        return None;
    }
    let (Some(truth), None) = (&record.truth, record.failure()) else {
        return Some(Score::Failed);
    };
    let truth = scored_truth(record, truth, parameter)?;
    Some(match record.reported.get(parameter) {
        None | Some(Reported::NotReported) => Score::NotReported,
        Some(Reported::NotDeterminable { why }) => Score::NotDeterminable(why),
        Some(reported) => Score::Value {
            value: reported.value().expect("a value"),
            truth,
            reported,
            covered: reported.covers(truth),
        },
    })
}

/// The true value `parameter` is scored against: the truth's, except a fit's hot-pixel
/// fraction, which counts a hot pixel of rate `r` as `min(1, 2 p(r))` of one, `p(r)` the
/// share of pixels at which its search names such a pixel (the fit's
/// `hot_pixel_detection.probability`, interpolated in the rate's logarithm): the truth's
/// fraction times that share of its pixels (all of one rate).
fn scored_truth(record: &RunRecord, truth: &Truth, parameter: &str) -> Option<f64> {
    let value = truth.value(truth_key(parameter))?;
    let (Some(curve), "hot_pixel_fraction") = (&record.hot_detection, parameter) else {
        return Some(value);
    };
    let Some(rate) = truth.value("hot_pixel_rate_hz") else {
        return Some(value);
    };
    Some(value * (2.0 * detected_share(curve, rate)).min(1.0))
}

/// `p(rate)` from `[rate, p]` points in increasing rate: linear in ln(rate) between them,
/// held at the ends (0 at a rate of 0).
fn detected_share(curve: &[[f64; 2]], rate: f64) -> f64 {
    let Some(&[first_rate, first]) = curve.first() else {
        return 1.0;
    };
    if rate <= first_rate {
        return if rate > 0.0 { first } else { 0.0 };
    }
    for pair in curve.windows(2) {
        let ([r0, p0], [r1, p1]) = (pair[0], pair[1]);
        if rate <= r1 {
            let f = (rate / r0).ln() / (r1 / r0).ln();
            return p0 + f * (p1 - p0);
        }
    }
    curve.last().map_or(1.0, |p| p[1])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coverage::record::committed;

    /// Draw 3 of the fit study of 2026-11-28: 17 hot pixels at 9.08 Hz (fraction 6.28e-4)
    /// that the fit did not find, reporting 0 [0, 1.33e-4].
    fn draw_3() -> RunRecord {
        committed("benches/coverage/fit-2026-11-28/results.compact.jsonl", 3)
    }

    #[test]
    fn a_hot_pixel_fraction_counts_the_truths_pixels_as_its_search_sees_them() {
        let mut record = draw_3();
        let scored = |r: &RunRecord| match score(r, "hot_pixel_fraction") {
            Some(Score::Value { truth, covered, .. }) => (truth, covered),
            other => panic!("{other:?}"),
        };
        // without the fit's detection probabilities: the truth's 17 pixels, missed
        assert_eq!(scored(&record), (0.000628032, false));
        // a search that names a 9.08 Hz pixel at 1 % of the pixels (5 -> 10 Hz: 0 -> 1.17 %,
        // linear in ln rate) counts 2 % of them: 1.26e-5, inside [0, 1.33e-4]
        record.hot_detection = Some(vec![[5.0, 0.0], [10.0, 0.0117], [20.0, 0.6]]);
        let share = 0.0117 * (9.08107f64 / 5.0).ln() / 2f64.ln();
        let (truth, covered) = scored(&record);
        assert!((truth - 0.000628032 * 2.0 * share).abs() < 1e-12, "{truth}");
        assert!(covered);
        // one that names it at half the pixels or more counts them all
        record.hot_detection = Some(vec![[5.0, 0.5], [10.0, 0.9]]);
        assert_eq!(scored(&record), (0.000628032, false));
    }
}
