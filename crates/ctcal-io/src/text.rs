//! Exact parsing of the numbers in event text files.
//!
//! Times are decimal seconds; ctcal keeps integer microseconds, so the decimal string is
//! rounded to the nearest microsecond digit by digit (no binary floating point in between:
//! `2.0971630009999997` becomes exactly 2097163 us). Only exponent notation falls back to
//! `f64`.

/// Parses decimal seconds into the nearest integer microsecond (ties away from zero).
pub fn seconds_to_us(s: &[u8]) -> Option<i64> {
    let (negative, digits) = match s.first()? {
        b'-' => (true, &s[1..]),
        b'+' => (false, &s[1..]),
        _ => (false, s),
    };
    let mut i = 0;
    let mut whole: i64 = 0;
    while i < digits.len() && digits[i].is_ascii_digit() {
        whole = whole
            .checked_mul(10)?
            .checked_add((digits[i] - b'0') as i64)?;
        i += 1;
    }
    let whole_digits = i;
    let mut micro: i64 = 0;
    let mut micro_digits = 0;
    let mut round_up = false;
    let mut fraction_digits = 0;
    if i < digits.len() && digits[i] == b'.' {
        i += 1;
        let mut rounding_digit: Option<u8> = None;
        while i < digits.len() && digits[i].is_ascii_digit() {
            let d = digits[i] - b'0';
            if micro_digits < 6 {
                micro = micro * 10 + d as i64;
                micro_digits += 1;
            } else if rounding_digit.is_none() {
                rounding_digit = Some(d);
            }
            fraction_digits += 1;
            i += 1;
        }
        // The seventh decimal decides: 5 or more rounds the magnitude up (ties away from 0).
        round_up = rounding_digit.is_some_and(|d| d >= 5);
    }
    if whole_digits == 0 && fraction_digits == 0 {
        return None;
    }
    if i != digits.len() {
        return float_fallback(s);
    }
    while micro_digits < 6 {
        micro *= 10;
        micro_digits += 1;
    }
    let magnitude = whole
        .checked_mul(1_000_000)?
        .checked_add(micro + round_up as i64)?;
    Some(if negative { -magnitude } else { magnitude })
}

#[cold]
fn float_fallback(s: &[u8]) -> Option<i64> {
    let value: f64 = std::str::from_utf8(s).ok()?.parse().ok()?;
    let us = value * 1e6;
    (us.is_finite() && us.abs() < 9.0e18).then(|| us.round() as i64)
}

/// Parses a non-negative decimal integer that fits in `u32`.
#[inline]
pub fn parse_u32(s: &[u8]) -> Option<u32> {
    if s.is_empty() || s.len() > 10 {
        return None;
    }
    let mut value: u64 = 0;
    for &b in s {
        let d = b.wrapping_sub(b'0');
        if d > 9 {
            return None;
        }
        value = value * 10 + d as u64;
    }
    u32::try_from(value).ok()
}

/// Parses a polarity field: `1` is ON; `0` and `-1` are OFF.
#[inline]
pub fn parse_polarity(s: &[u8]) -> Option<bool> {
    match s {
        b"1" | b"+1" => Some(true),
        b"0" | b"-1" => Some(false),
        _ => None,
    }
}

/// Splits a line into whitespace- (or comma-) separated fields, writing at most
/// `fields.len()` of them; returns how many there were in total.
#[inline]
pub fn split_fields<'a>(line: &'a [u8], fields: &mut [&'a [u8]]) -> usize {
    let mut count = 0;
    let mut i = 0;
    let n = line.len();
    while i < n {
        while i < n && matches!(line[i], b' ' | b'\t' | b',' | b'\r') {
            i += 1;
        }
        if i >= n {
            break;
        }
        let start = i;
        while i < n && !matches!(line[i], b' ' | b'\t' | b',' | b'\r') {
            i += 1;
        }
        if count < fields.len() {
            fields[count] = &line[start..i];
        }
        count += 1;
    }
    count
}

/// A short, printable excerpt of a line for error messages.
pub fn excerpt(line: &[u8]) -> String {
    let text = String::from_utf8_lossy(&line[..line.len().min(60)]);
    let text = text.trim_end();
    if line.len() > 60 {
        format!("{text}...")
    } else {
        text.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seconds_round_to_the_nearest_microsecond_exactly() {
        assert_eq!(seconds_to_us(b"2.0971630009999997"), Some(2_097_163));
        assert_eq!(seconds_to_us(b"13.595874999000001"), Some(13_595_875));
        assert_eq!(seconds_to_us(b"0.003811000"), Some(3_811));
        assert_eq!(seconds_to_us(b"0.0000005"), Some(1));
        assert_eq!(seconds_to_us(b"0.0000004999"), Some(0));
        assert_eq!(seconds_to_us(b"12"), Some(12_000_000));
        assert_eq!(seconds_to_us(b".5"), Some(500_000));
        assert_eq!(seconds_to_us(b"-1.25"), Some(-1_250_000));
        assert_eq!(
            seconds_to_us(b"1589163147.368868"),
            Some(1_589_163_147_368_868)
        );
        assert_eq!(seconds_to_us(b"1.5e-3"), Some(1_500));
        assert_eq!(seconds_to_us(b"nan"), None);
        assert_eq!(seconds_to_us(b"inf"), None);
        assert_eq!(seconds_to_us(b"1.2.3"), None);
        assert_eq!(seconds_to_us(b"."), None);
        assert_eq!(seconds_to_us(b""), None);
    }

    #[test]
    fn integers_and_polarities() {
        assert_eq!(parse_u32(b"239"), Some(239));
        assert_eq!(parse_u32(b"-3"), None);
        assert_eq!(parse_u32(b"4294967296"), None);
        assert_eq!(parse_polarity(b"-1"), Some(false));
        assert_eq!(parse_polarity(b"1"), Some(true));
        assert_eq!(parse_polarity(b"2"), None);
    }

    #[test]
    fn fields_split_on_blanks_commas_and_carriage_returns() {
        let mut f = [&b""[..]; 4];
        assert_eq!(split_fields(b"0.1 2\t3,1\r", &mut f), 4);
        assert_eq!(f, [&b"0.1"[..], b"2", b"3", b"1"]);
        assert_eq!(split_fields(b"   ", &mut f), 0);
    }
}
