//! What the fit says of the threshold mismatch `ct_sigma` where its final model has none.
//!
//! A model without mismatch matched the counts as well as one with it, which is not a
//! measurement of no spread: per-pixel counts show a spread only where pixels fire many
//! events each (a count of `n` threshold crossings spreads by about `n sigma`, against its
//! own Poisson-like scatter `sqrt(n)`), while event timing reads every pixel's thresholds
//! from its events' timing against the frames (Lichtsteiner, Posch & Delbruck, JSSC 2008;
//! [`crate::estimate::timing`]) and measures a spread from a few events per pixel. So:
//!
//! - where event timing measured a spread (the start, `estimate aps` on the fit blocks),
//!   that measurement is the fit's statement of the spread: `ct_sigma` is `null` (the
//!   simulated model has none), its `why` says why the model has none and gives the
//!   measurement, and `uncertainties.ct_sigma` carries the measured value and 95 % interval
//!   ([`measured_not_modelled`]);
//! - where neither event timing nor the counts could show one, `ct_sigma` is `null` with
//!   that reason ([`unseen`]).
//!
//! On the 40 draws of seeds 7001-7040 (every one with mismatch, 0.002-0.08), the fit kept
//! mismatch in none of the 31 draws with frames; event timing had measured 0.033-0.038 with
//! an interval above zero in 7001, 7027, 7033 and 7037 (evidence 2.2-2.5 of 5 standard
//! errors), and the JSON said nothing of the spread.

use super::super::Step;
use super::super::Uncertain;
use super::super::effects::{EVIDENCE_THRESHOLD, Effect, mismatch::TOO_FEW_TO_COMPARE};
use super::super::wording::timing_limit_in_words;

/// The last step that judged mismatch, if any.
fn mismatch_step(steps: &[Step]) -> Option<&Step> {
    steps
        .iter()
        .rev()
        .find(|s| s.effect == Effect::Mismatch.name())
}

/// Whether the model's spread (`PixelParams::ct_sigma`) is one.
fn has_spread(model_spread: Option<f64>) -> bool {
    model_spread.is_some_and(|s| s > 0.0)
}

/// `ct_sigma` where the model has no mismatch because the recording could not show one:
/// event timing measured no spread and the fit blocks have too few events per pixel to
/// compare the counts' dispersion with the model's. The model's spread of none is then not
/// a measurement, and the configurations write the simulator's default with the reason.
pub(super) fn unseen(
    model_spread: Option<f64>,
    steps: &[Step],
    unresolved: Option<[f64; 2]>,
) -> Option<(String, String)> {
    if has_spread(model_spread) {
        return None;
    }
    let unseen = steps
        .iter()
        .any(|s| s.effect == Effect::Mismatch.name() && s.evidence == TOO_FEW_TO_COMPARE);
    let timing = unresolved.map_or("event timing measured none and".to_string(), |interval| {
        format!("{} and", timing_limit_in_words(interval))
    });
    unseen.then(|| {
        (
            "ct_sigma".to_string(),
            format!("the recording does not show a threshold spread: {timing} the fit blocks have too few events per pixel to compare the counts' dispersion with the model's; the model has no mismatch, which is not a measurement"),
        )
    })
}

/// Where the final model has no mismatch and event timing measured a spread (value, 95 %
/// interval): why `ct_sigma` is `null` in the model, and the measured spread as its
/// uncertainty (standard error a quarter of the interval's width, as its ends are 1.96
/// standard errors either side).
pub(super) fn measured_not_modelled(
    model_spread: Option<f64>,
    steps: &[Step],
    measured: Option<(f64, [f64; 2])>,
) -> Option<(String, Uncertain)> {
    if has_spread(model_spread) {
        return None;
    }
    let (value, [lo, hi]) = measured
        .filter(|(v, [lo, hi])| v.is_finite() && lo.is_finite() && hi.is_finite() && lo <= hi)?;
    let judged = match mismatch_step(steps) {
        Some(step) if step.kept => return None,
        Some(step) => format!(
            "the selection did not add it (evidence {:.1} standard errors, {EVIDENCE_THRESHOLD} needed: {})",
            step.score, step.reason
        ),
        None => "it was not judged".to_string(),
    };
    let why = format!(
        "the fitted model has no threshold mismatch: {judged}; counts that do not need a spread are not a measurement of none; event timing measures {value:.4} (95 % interval {lo:.4} to {hi:.4}), given as its uncertainty"
    );
    let measured = Uncertain::with_interval(value, Some((hi - lo) / 3.92), [Some(lo), Some(hi)]);
    Some((why, measured))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(evidence: &str, score: f64, kept: bool) -> Step {
        Step {
            kept,
            reason: "not called for by the residuals".to_string(),
            ..Step::untried(
                Effect::Mismatch.name().to_string(),
                evidence.to_string(),
                score,
            )
        }
    }

    #[test]
    fn a_measured_spread_the_model_lacks_is_the_uncertainty_with_its_reason() {
        // coverage draw 7027: event timing 0.0356 [0.0057, 0.0654], evidence 2.3, not kept
        let steps = [step("event timing measures 0.0356", 2.34, false)];
        let (why, u) =
            measured_not_modelled(None, &steps, Some((0.0356, [0.0057, 0.0654]))).unwrap();
        assert_eq!(u.value, 0.0356);
        assert_eq!(u.ci95, Some([Some(0.0057), Some(0.0654)]));
        // (0.0654 - 0.0057) / 3.92
        assert!((u.standard_error.unwrap() - 0.015229591836734694).abs() < 1e-15);
        assert!(
            why.contains("evidence 2.3 standard errors, 5 needed"),
            "{why}"
        );
        assert!(
            why.contains("measures 0.0356 (95 % interval 0.0057 to 0.0654)"),
            "{why}"
        );
    }

    #[test]
    fn a_kept_mismatch_or_no_measurement_says_nothing_more() {
        let kept = [step("event timing measures 0.0356", 9.0, true)];
        assert!(measured_not_modelled(None, &kept, Some((0.0356, [0.02, 0.05]))).is_none());
        let judged = [step("per-pixel counts are 3 % more dispersed", 1.5, false)];
        assert!(measured_not_modelled(None, &judged, None).is_none());
        assert!(measured_not_modelled(None, &judged, Some((f64::NAN, [0.0, 0.1]))).is_none());
        let spread = Some(0.03);
        assert!(measured_not_modelled(spread, &judged, Some((0.03, [0.02, 0.04]))).is_none());
        // a spread of 0 written is none
        assert!(measured_not_modelled(Some(0.0), &judged, Some((0.03, [0.02, 0.04]))).is_some());
    }

    #[test]
    fn too_few_events_to_compare_leaves_the_spread_unseen() {
        let too_few = [step(TOO_FEW_TO_COMPARE, 0.0, false)];
        let (_, why) = unseen(None, &too_few, None).unwrap();
        assert!(
            why.contains(": event timing measured none and the fit blocks have too few"),
            "{why}"
        );
        // coverage draw 5: event timing's interval [0, 0.0909] on the fit run
        let (_, why) = unseen(None, &too_few, Some([0.0, 0.0909])).unwrap();
        assert!(
            why.contains("allows at most 0.0909 (such a limit held on"),
            "{why}"
        );
        let alike = [step("per-pixel counts are alike", 0.5, false)];
        assert!(unseen(None, &alike, None).is_none());
    }
}
