//! Scoring one parameter of one run against the truth: which population it belongs to,
//! and whether its interval covered the true value.

use crate::coverage::method::{Method, effect_of};
use crate::coverage::record::RunRecord;
use crate::coverage::reported::Reported;

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
    let effect_needed = record.method == Method::Fit && parameter != "ct_sigma";
    truth.value(parameter).is_some()
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
    let truth = truth.value(parameter)?;
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
