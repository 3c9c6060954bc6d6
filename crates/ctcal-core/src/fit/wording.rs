//! How the fit's sentences (`why`, `not_detected`) write a number that spans decades, such
//! as a noise rate bound: to three significant digits, so that 0.000042 Hz is not written
//! as 0.0000.

/// `value` to three significant digits.
pub(crate) fn significant(value: f64) -> String {
    if value == 0.0 || !value.is_finite() {
        return format!("{value}");
    }
    let decimals = (2 - value.abs().log10().floor() as i32).max(0) as usize;
    format!("{value:.decimals$}")
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
