//! What qualifies a number of the report, gathered where the page and `report.md` show it:
//! a method's "not determinable" values (`why`) and assumptions (extrapolations among
//! them), the fit's parameters the recording does not identify and its assumptions, what
//! reading the recording warned of, and outputs that could not be made.

use super::model::SequenceReport;
use crate::estimate::CtEstimate;
use crate::fit::FitResult;
use std::collections::{BTreeMap, BTreeSet};

/// The caveats of one method's estimate, each as one line.
pub fn of_estimate(e: &CtEstimate) -> Vec<String> {
    let mut out: Vec<String> = e
        .why
        .iter()
        .map(|(key, why)| format!("{key} not determinable: {why}"))
        .collect();
    out.extend(e.assumptions.iter().cloned());
    out
}

/// The caveats of a fit: where a fit without frames took its thresholds, the parameters it
/// does not identify, the effects it leaves off (`not_detected`), then its assumptions.
pub fn of_fit(f: &FitResult) -> Vec<String> {
    // without frames the absolute thresholds come from elsewhere: say where first
    let mut out: Vec<String> = f
        .events_only
        .iter()
        .map(|e| format!("thresholds from {}", e.thresholds_source))
        .collect();
    out.extend(
        f.why
            .iter()
            .map(|(key, why)| format!("{key} not identified: {why}")),
    );
    out.extend(off_in_the_model(&f.not_detected));
    out.extend(f.ambiguities.iter().map(|a| {
        format!(
            "{} or {}: not separated by this recording (selection error {:.4} with {}, {:.4} with {} = {:.4} instead); {}",
            a.kept, a.alternative, a.error_kept, a.kept, a.error_alternative, a.parameter, a.value, a.separated_by
        )
    }));
    out.extend(f.assumptions.iter().cloned());
    out
}

/// One line per reason of `not_detected`: an effect of two parameters (hot pixels) has one
/// reason, said once wherever its keys sort.
fn off_in_the_model(not_detected: &BTreeMap<String, String>) -> Vec<String> {
    let mut said = BTreeSet::new();
    not_detected
        .values()
        .filter(|why| said.insert(why.as_str()))
        .map(|why| format!("off in the fitted model: {why}"))
        .collect()
}

/// The caveats of a sequence as a whole: what reading it warned of, and its plots that
/// could not be drawn.
pub fn of_sequence(s: &SequenceReport) -> Vec<String> {
    let mut out = s.warnings.clone();
    out.extend(
        s.outputs
            .plots_not_drawn
            .iter()
            .map(|e| format!("plot not drawn: {e}")),
    );
    out
}

/// One line of a caveat (Markdown list items and HTML list items are one line).
pub fn one_line(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reason shared by keys that do not sort side by side is said once, in the order of
    /// its first key.
    #[test]
    fn a_reason_of_several_parameters_is_said_once() {
        let not_detected = BTreeMap::from([
            ("a_first".to_string(), "hot pixels off".to_string()),
            ("b_between".to_string(), "leak off".to_string()),
            ("c_last".to_string(), "hot pixels off".to_string()),
        ]);
        assert_eq!(
            off_in_the_model(&not_detected),
            [
                "off in the fitted model: hot pixels off",
                "off in the fitted model: leak off"
            ]
        );
    }
}
