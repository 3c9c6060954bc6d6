//! How the fit's sentences (`why`, `not_detected`, `assumptions`) write what they share: a
//! number that spans decades, such as a noise rate bound, to three significant digits (so
//! that 0.000042 Hz is not written as 0.0000), a noise effect's `at_most_hz` with what
//! measures it and how often such a limit held, and what bounds or questions a threshold
//! spread the model left out.

use super::MismatchDetection;
use super::effects::Effect;
use super::effects::leak::DRIFT_LIMIT_HELD;
use super::effects::mismatch::TIMING_LIMIT_HELD;

/// `value` to three significant digits.
pub(crate) fn significant(value: f64) -> String {
    if value == 0.0 || !value.is_finite() {
        return format!("{value}");
    }
    let decimals = (2 - value.abs().log10().floor() as i32).max(0) as usize;
    format!("{value:.decimals$}")
}

/// A noise effect's `at_most_hz` (`limit_hz`) in words: what measures it and how often such
/// a limit held (shot noise: an exact Poisson end; leak: the drift's record on the coverage
/// draws, [`DRIFT_LIMIT_HELD`]).
pub(crate) fn at_most_in_words(effect: Effect, limit_hz: f64) -> String {
    let limit = significant(limit_hz);
    match effect {
        Effect::Leak => {
            let (held, of) = DRIFT_LIMIT_HELD;
            format!(
                "the event timing's drift allows at most {limit} Hz at the frames' median DN (such a limit held on {held} of {of} coverage draws with a leak)"
            )
        }
        _ => format!("the quiet pixels' isolated OFF events allow at most {limit} Hz (95 %)"),
    }
}

/// The most event timing allows of a spread it did not resolve (its 95 % interval `[lo,
/// hi]`), with how often such a limit held on the coverage draws ([`TIMING_LIMIT_HELD`]).
pub(crate) fn timing_limit_in_words([lo, hi]: [f64; 2]) -> String {
    let (held, of) = TIMING_LIMIT_HELD;
    format!(
        "event timing on the fit run resolves no frozen threshold spread: its 95 % interval {} to {} allows at most {} (such a limit held on {held} of {of} coverage draws with a spread)",
        significant(lo),
        significant(hi),
        significant(hi)
    )
}

/// A threshold spread the model left out, in words: the most event timing allows (with how
/// often such a limit held on the coverage draws, [`TIMING_LIMIT_HELD`]) or why nothing
/// bounds it, then, where the counts beside the final model still call for a spread, that
/// one may be present, with the spread the fit blocks chose.
pub(crate) fn spread_in_words(d: &MismatchDetection) -> String {
    let limit = match d.timing_ci95 {
        Some(interval) => timing_limit_in_words(interval),
        None => d.why.clone().unwrap_or_default(),
    };
    let Some(z) = d.recording_evidence.filter(|_| d.counts_call_for_it) else {
        return limit;
    };
    let tried = d.tried_spread.map_or(String::new(), |s| {
        let above = if d.at_most.is_some_and(|limit| s > limit) {
            " (more than event timing allows: the counts' extra dispersion may be another effect the model lacks)"
        } else {
            ""
        };
        format!(
            ", and the spread the fit blocks chose, {}{above}, did not lower the selection blocks' error beyond chance",
            significant(s)
        )
    });
    format!(
        "{limit}; beside the final model the counts call for it ({}: {z:.1} standard errors){tried}, so a spread may be present that this recording does not determine",
        d.evidence
    )
}

#[cfg(test)]
mod tests {
    use super::significant;

    #[test]
    fn three_significant_digits_whatever_the_decade() {
        assert_eq!(significant(0.0000423), "0.0000423");
        assert_eq!(significant(0.0236), "0.0236");
        assert_eq!(significant(0.693), "0.693");
        assert_eq!(significant(32.46), "32.5");
        assert_eq!(significant(1234.5), "1234");
        assert_eq!(significant(0.0), "0");
    }
}
