//! What threshold mismatch a fit with frames leaves out, where its final model has none and
//! the start's event timing resolved no spread (a resolved spread the model lacks is the
//! fit's statement of `ct_sigma`, [`super::spread_report`]).
//!
//! A configuration written from such a fit sets `ct_sigma` to 0, and that zero is not a
//! measurement. Two things bound or question it:
//!
//! - **What event timing allows.** `estimate aps` on the fit run reads every pixel's
//!   thresholds from its events' timing against the frames and removes each pixel's
//!   estimation noise from their spread ([`crate::estimate::timing`]; Lichtsteiner, Posch &
//!   Delbruck, JSSC 2008). Where the spread left is within its noise the value is `null`
//!   and its 95 % interval reaches 0: the interval's upper end is the most the recording
//!   allows, whatever the counts show. Its record on the coverage draws is
//!   [`crate::fit::effects::mismatch::TIMING_LIMIT_HELD`].
//! - **What the counts still call for.** Mismatch widens the spread of per-pixel counts
//!   within a tile ([`crate::fit::effects::mismatch::evidence`]). Read beside the final
//!   model, that evidence may still call for a spread the selection did not keep (its fall
//!   in error within chance on few blocks): then a spread may be present and this recording
//!   does not determine it; the spread the fit blocks chose, where the loop tried one, is
//!   given. On the real DAVIS346 sample (three frames) event timing allows at most 0.029,
//!   while the counts are 44 % more dispersed than the model's and a spread of 0.054 lowered
//!   the selection blocks' error by 12 %, under the 17 % chance allows: before,
//!   `not_detected` said only "not measured".

use super::super::effects::{Context, Effect, mismatch};
use super::super::wording::spread_in_words;
use super::super::{MismatchDetection, Step};

/// The mismatch detection of the final model, and the assumption that states it; `None`
/// where the model has a spread or event timing resolved one.
pub fn detect(
    context: &Context,
    steps: &[Step],
    unresolved: Option<[f64; 2]>,
) -> Option<(MismatchDetection, String)> {
    let has_spread = Effect::Mismatch
        .value(context.model)
        .is_some_and(|s| s > 0.0);
    if has_spread || context.mismatch_estimate.is_some() {
        return None;
    }
    let evidence = mismatch::evidence(context);
    let read = evidence.text != mismatch::TOO_FEW_TO_COMPARE;
    let tried = steps
        .iter()
        .rev()
        .find(|s| s.effect == Effect::Mismatch.name() && s.simulations > 0 && !s.kept);
    let detection = MismatchDetection {
        at_most: unresolved.map(|[_, hi]| hi),
        timing_ci95: unresolved,
        recording_evidence: read.then_some(evidence.score),
        counts_call_for_it: evidence.calls_for(),
        evidence: evidence.text,
        tried_spread: tried.and_then(|s| s.parameters.get("ct_sigma").copied()),
        why: unresolved.is_none().then(|| NO_TIMING_INTERVAL.to_string()),
        meaning: MEANING,
    };
    let note = format!(
        "threshold mismatch left out of the model: {}",
        spread_in_words(&detection)
    );
    Some((detection, note))
}

const NO_TIMING_INTERVAL: &str = "event timing on the fit run gave no interval of the threshold spread (too few pixels with enough events against the frames, a polarity whose samples are mostly noise, or thresholds that are a start value: the start's step says which), so nothing bounds it from above";

const MEANING: &str = "where the final model has no threshold mismatch and event timing resolved no spread: at_most, the upper end of the 95 % interval of the frozen per-pixel threshold spread (log units) that event timing on the fit run measures (timing_ci95; null with why where it gave none); recording_evidence and evidence: the per-pixel counts' dispersion within tiles against the final model's, in standard errors (null where too few events per pixel to compare); counts_call_for_it: that evidence calls for mismatch (a spread may be present that the selection did not keep); tried_spread: the spread the fit blocks chose where the loop tried mismatch and did not keep it";

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::effects::fixture::{Fixture, static_frames};
    use crate::fit::effects::mismatch::tests::model_and_mismatched;

    /// A mismatch step the loop tried (three simulations) and did not keep, its fit blocks
    /// having chosen `spread`.
    fn tried(spread: f64) -> Step {
        Step {
            simulations: 3,
            parameters: [("ct_sigma".to_string(), spread)].into(),
            ..Step::untried(Effect::Mismatch.name().into(), String::new(), 9.0)
        }
    }

    /// Thresholds spread by 3 % beside a model without spread (about 1000 events a pixel:
    /// the counts 90 % more dispersed), and event timing's interval [0, 0.05]: the limit is
    /// the interval's upper end, and the counts still call for a spread, with the one the
    /// fit blocks chose.
    #[test]
    fn an_unresolved_spread_is_bounded_by_its_interval_and_the_counts_are_said() {
        let (model, recording) = model_and_mismatched(0.03);
        let f = Fixture::new(&static_frames(16, 16, 2.0, 100.0), &recording, &model);
        let (d, note) = detect(&f.context(), &[tried(0.028)], Some([0.0, 0.05])).unwrap();
        assert_eq!(d.at_most, Some(0.05));
        assert!(d.counts_call_for_it, "{d:?}");
        assert!(d.recording_evidence.unwrap() > 5.0, "{d:?}");
        assert_eq!(d.tried_spread, Some(0.028));
        assert!(d.why.is_none());
        assert!(
            note.contains("its 95 % interval 0 to 0.0500 allows at most 0.0500"),
            "{note}"
        );
        assert!(
            note.contains("the spread the fit blocks chose, 0.0280,"),
            "{note}"
        );
        assert!(
            note.ends_with("so a spread may be present that this recording does not determine")
        );
        // a chosen spread above the limit is said to be more than event timing allows
        let (d, _) = detect(&f.context(), &[tried(0.054)], Some([0.0, 0.029])).unwrap();
        assert!(
            spread_in_words(&d).contains("chose, 0.0540 (more than event timing allows"),
            "{d:?}"
        );
    }

    /// The model's own events as the recording, and no interval from event timing: nothing
    /// bounds the spread, and the counts call for none.
    #[test]
    fn without_an_interval_the_reason_is_the_statement() {
        let (model, _) = model_and_mismatched(0.0);
        let f = Fixture::new(&static_frames(16, 16, 2.0, 100.0), &model, &model);
        let (d, note) = detect(&f.context(), &[], None).unwrap();
        assert_eq!((d.at_most, d.tried_spread), (None, None));
        assert!(!d.counts_call_for_it);
        assert_eq!(spread_in_words(&d), NO_TIMING_INTERVAL);
        assert!(note.ends_with(NO_TIMING_INTERVAL), "{note}");
    }

    /// A model with a spread, or a spread event timing resolved (the fit's statement of
    /// `ct_sigma` elsewhere), has no detection.
    #[test]
    fn a_model_with_a_spread_or_a_resolved_one_has_none() {
        let (model, recording) = model_and_mismatched(0.03);
        let mut f = Fixture::new(&static_frames(16, 16, 2.0, 100.0), &recording, &model);
        let resolved = Context {
            mismatch_estimate: Some((0.03, [0.02, 0.04])),
            ..f.context()
        };
        assert!(detect(&resolved, &[], Some([0.0, 0.05])).is_none());
        f.model.ct_sigma = Some(0.03);
        assert!(detect(&f.context(), &[], Some([0.0, 0.05])).is_none());
    }
}
