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
    let decimal = Decimal::at_front(digits)?;
    if decimal.whole_digits == 0 && decimal.fraction_digits == 0 {
        return None;
    }
    if decimal.len != digits.len() {
        return float_fallback(s);
    }
    let magnitude = decimal.microseconds()?;
    Some(if negative { -magnitude } else { magnitude })
}

/// An unsigned decimal at the front of a field: digits, then optionally `.` and digits,
/// read to the microsecond digit by digit (the seventh decimal decides the rounding).
struct Decimal {
    whole: i64,
    /// The first six decimals as microseconds (padded with zeros).
    micro: i64,
    /// The seventh decimal is 5 or more: the magnitude rounds up (ties away from 0).
    round_up: bool,
    whole_digits: usize,
    fraction_digits: usize,
    /// Bytes read: the digits and the point.
    len: usize,
}

impl Decimal {
    /// The decimal at the front of `s`; `None` where its whole part overflows.
    #[inline(always)]
    fn at_front(s: &[u8]) -> Option<Decimal> {
        let mut i = 0;
        let mut whole: i64 = 0;
        while i < s.len() && s[i].is_ascii_digit() {
            whole = whole.checked_mul(10)?.checked_add((s[i] - b'0') as i64)?;
            i += 1;
        }
        let whole_digits = i;
        let (mut micro, mut round_up, mut fraction_digits) = (0i64, false, 0);
        if i < s.len() && s[i] == b'.' {
            i += 1;
            while i < s.len() && s[i].is_ascii_digit() {
                let d = (s[i] - b'0') as i64;
                if fraction_digits < 6 {
                    micro = micro * 10 + d;
                } else if fraction_digits == 6 {
                    round_up = d >= 5;
                }
                fraction_digits += 1;
                i += 1;
            }
        }
        micro *= 10i64.pow(6 - fraction_digits.min(6) as u32);
        Some(Decimal {
            whole,
            micro,
            round_up,
            whole_digits,
            fraction_digits,
            len: i,
        })
    }

    /// The magnitude in microseconds; `None` where it overflows.
    #[inline(always)]
    fn microseconds(&self) -> Option<i64> {
        self.whole
            .checked_mul(1_000_000)?
            .checked_add(self.micro + self.round_up as i64)
    }
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

/// The usual event line in one pass: `SECONDS X Y P`, single spaces, the time an unsigned
/// decimal with digits before its point (and after it, where it has one), x and y of at most 9 digits, P `0` or `1`, nothing
/// after it. Returns (time in us, x, y, ON), exactly what [`split_fields`],
/// [`seconds_to_us`], [`parse_u32`] and [`parse_polarity`] make of it; `None` for any other
/// layout (signs, tabs, commas, `\r`, exponents, `-1`, comments, a `width height` line,
/// errors), which those parse instead. It is a fast path: the general parse walks the line
/// once to split it and again per field, and its time is most of a text file's decoding.
#[inline]
pub fn event_line(line: &[u8]) -> Option<(i64, u32, u32, bool)> {
    let time = Decimal::at_front(line)?;
    // digits before the point, and after it where there is one
    let pointed = time.len > time.whole_digits;
    if time.whole_digits == 0 || (pointed && time.fraction_digits == 0) {
        return None;
    }
    let t = time.microseconds()?;
    let (x, i) = space_then_u32(line, time.len)?;
    let (y, i) = space_then_u32(line, i)?;
    if i + 2 != line.len() || line[i] != b' ' {
        return None;
    }
    let on = match line[i + 1] {
        b'0' => false,
        b'1' => true,
        _ => return None,
    };
    Some((t, x, y, on))
}

/// A single space at `i`, then 1 to 9 digits: their value and the index after them.
#[inline(always)]
fn space_then_u32(line: &[u8], i: usize) -> Option<(u32, usize)> {
    if line.get(i) != Some(&b' ') {
        return None;
    }
    let mut j = i + 1;
    let mut value: u32 = 0;
    while j < line.len() && line[j].is_ascii_digit() {
        if j - i > 9 {
            return None;
        }
        value = value * 10 + (line[j] - b'0') as u32;
        j += 1;
    }
    (j > i + 1).then_some((value, j))
}

/// The UTF-8 byte-order mark some editors put at the start of a text file.
const BYTE_ORDER_MARK: &[u8] = b"\xEF\xBB\xBF";

/// A short, printable excerpt of a line for error messages; a byte-order mark at its start
/// (invisible when printed) is named.
pub fn excerpt(line: &[u8]) -> String {
    if let Some(rest) = line.strip_prefix(BYTE_ORDER_MARK) {
        return format!(
            "<U+FEFF: a byte-order mark; save without it>{}",
            excerpt(rest)
        );
    }
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

    /// A byte-order mark prints as nothing: the excerpt names it.
    #[test]
    fn an_excerpt_names_a_byte_order_mark() {
        assert_eq!(excerpt(b"0.5 1 2 1"), "0.5 1 2 1");
        let marked = excerpt(b"\xEF\xBB\xBF0.5 1 2 1");
        assert_eq!(
            marked,
            "<U+FEFF: a byte-order mark; save without it>0.5 1 2 1"
        );
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

    /// Marsaglia's xorshift64, enough to vary test lines.
    struct XorShift(u64);

    impl XorShift {
        fn below(&mut self, n: usize) -> usize {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 % n as u64) as usize
        }

        fn pick<'a>(&mut self, choices: &[&'a [u8]]) -> &'a [u8] {
            choices[self.below(choices.len())]
        }

        /// Up to `most - 1` random digits.
        fn digits(&mut self, line: &mut Vec<u8>, most: usize) {
            for _ in 0..self.below(most) {
                let d = self.below(10) as u8;
                line.push(b'0' + d);
            }
        }
    }

    /// What the general parse makes of a line that holds an event.
    fn general(line: &[u8]) -> Option<(i64, u32, u32, bool)> {
        let mut f = [&b""[..]; 4];
        if split_fields(line, &mut f) != 4 {
            return None;
        }
        Some((
            seconds_to_us(f[0])?,
            parse_u32(f[1])?,
            parse_u32(f[2])?,
            parse_polarity(f[3])?,
        ))
    }

    #[test]
    fn the_fast_event_line_is_the_general_parse_or_declines() {
        let lines: [&[u8]; 24] = [
            b"0.003811000 45 12 1",
            b"2.0971630009999997 239 179 0",
            b"13.595874999000001 1 1 1",
            b"0.0000005 0 0 0",
            b"0.0000004999 0 0 1",
            b"12 3 4 1",
            b"999999999999.9999995 9 9 1",
            b"1589163147.368868 1 2 0",
            b"0.5 123456789 0 1",
            b"0.5 1234567890 0 1",
            b"0.5 4294967296 0 1",
            b"0.5 1 2 -1",
            b"0.5 1 2 2",
            b"0.5 1 2 1 ",
            b"0.5 1 2 1\r",
            b"0.5\t1 2 1",
            b"0.5  1 2 1",
            b"0.5,1,2,1",
            b".5 1 2 1",
            b"5. 1 2 1",
            b"-0.5 1 2 1",
            b"1.5e-3 1 2 1",
            b"0.5 1 2",
            b"# 0.5 1 2 1",
        ];
        let mut fast = 0;
        for line in lines {
            if let Some(event) = event_line(line) {
                fast += 1;
                assert_eq!(Some(event), general(line), "{}", excerpt(line));
            }
        }
        assert_eq!(fast, 9, "the first nine take the fast path");
        // random lines: fields of random lengths, separators and endings
        let mut rng = XorShift(0x2545_f491_4f6c_dd1d);
        let mut taken = 0;
        for _ in 0..100_000 {
            let mut line = Vec::new();
            rng.digits(&mut line, 15);
            if rng.below(4) > 0 {
                line.push(b'.');
                rng.digits(&mut line, 11);
            }
            for _ in 0..2 {
                line.extend_from_slice(rng.pick(&[b" ", b" ", b" ", b"  ", b"\t", b","]));
                rng.digits(&mut line, 12);
            }
            line.extend_from_slice(rng.pick(&[b" ", b" ", b" ", b","]));
            line.extend_from_slice(rng.pick(&[b"0", b"1", b"2", b"-1"]));
            line.extend_from_slice(rng.pick(&[b"", b"", b" ", b"\r"]));
            if let Some(event) = event_line(&line) {
                taken += 1;
                assert_eq!(Some(event), general(&line), "{}", excerpt(&line));
            }
        }
        assert!(taken > 100, "{taken} random lines took the fast path");
    }

    #[test]
    fn fields_split_on_blanks_commas_and_carriage_returns() {
        let mut f = [&b""[..]; 4];
        assert_eq!(split_fields(b"0.1 2\t3,1\r", &mut f), 4);
        assert_eq!(f, [&b"0.1"[..], b"2", b"3", b"1"]);
        assert_eq!(split_fields(b"   ", &mut f), 0);
    }
}
