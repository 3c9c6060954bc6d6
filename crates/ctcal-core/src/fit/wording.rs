//! How the fit's sentences (`why`, `not_detected`, `assumptions`) write what they share: a
//! number that spans decades, such as a noise rate bound, to three significant digits (so
//! that 0.000042 Hz is not written as 0.0000), and a noise effect's `at_most_hz` with what
//! measures it and how often such a limit held.

use super::effects::Effect;
use super::effects::leak::DRIFT_LIMIT_HELD;

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
