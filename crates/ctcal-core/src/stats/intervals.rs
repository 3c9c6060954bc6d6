//! Same-pixel inter-event intervals, collected in a log-linear histogram so that quantiles
//! of billions of intervals cost a fixed 60 KB: exact below 128 us, above that bins 1/128
//! of their value wide (0.8 %), like HdrHistogram with 7 significant bits. Adding is one
//! increment of a bin found without a branch; the total is summed when asked for (a running
//! total, which the compiler cannot keep in a register beside the bins, was a fifth of the
//! statistics kernel's time).

/// Intervals below this are counted exactly.
const SUB_BUCKETS: u64 = 128;
const SUB_BITS: u32 = 7;
const BINS: usize = ((64 - SUB_BITS as usize) + 1) * SUB_BUCKETS as usize;

/// Relative resolution of the histogram above the exact range.
pub const RELATIVE_RESOLUTION: f64 = 1.0 / SUB_BUCKETS as f64;

/// A log-linear histogram of non-negative microsecond intervals.
#[derive(Clone, Debug)]
pub struct IntervalHistogram {
    counts: Vec<u64>,
}

impl Default for IntervalHistogram {
    fn default() -> Self {
        Self {
            counts: vec![0; BINS],
        }
    }
}

/// The bin of interval `dt` (microseconds): `dt` itself below 256 (shift 0), else
/// `shift * 128 + (dt >> shift)` with `dt >> shift` in 128..256; one formula, no branch.
#[inline(always)]
fn bin_of(dt: u64) -> usize {
    let exponent = 63 - (dt | 1).leading_zeros();
    let shift = exponent.max(SUB_BITS) - SUB_BITS;
    (shift as usize) * SUB_BUCKETS as usize + (dt >> shift) as usize
}

/// The smallest interval in bin `b` and the bin's width.
fn bin_range(b: usize) -> (u64, u64) {
    let b = b as u64;
    if b < SUB_BUCKETS {
        (b, 1)
    } else {
        let shift = b / SUB_BUCKETS - 1;
        let mantissa = b % SUB_BUCKETS + SUB_BUCKETS;
        (mantissa << shift, 1 << shift)
    }
}

impl IntervalHistogram {
    #[inline(always)]
    pub fn add(&mut self, dt_us: u64) {
        self.counts[bin_of(dt_us)] += 1;
    }

    /// Intervals of exactly 0 us: events repeating their pixel's previous one in the same
    /// microsecond.
    pub fn zeros(&self) -> u64 {
        self.counts[0]
    }

    pub fn merge(&mut self, other: &IntervalHistogram) {
        for (a, b) in self.counts.iter_mut().zip(&other.counts) {
            *a += b;
        }
    }

    /// Intervals added.
    pub fn total(&self) -> u64 {
        self.counts.iter().sum()
    }

    /// The `q`-quantile (0..=1) in microseconds: the midpoint of the bin holding it.
    pub fn quantile_us(&self, q: f64) -> Option<f64> {
        let total = self.total();
        if total == 0 {
            return None;
        }
        let rank = ((q.clamp(0.0, 1.0) * total as f64).ceil() as u64).max(1);
        let mut seen = 0;
        for (b, &c) in self.counts.iter().enumerate() {
            seen += c;
            if seen >= rank {
                let (low, width) = bin_range(b);
                return Some(low as f64 + (width - 1) as f64 / 2.0);
            }
        }
        None
    }

    /// Fraction of intervals strictly below `dt_us` (exact when `dt_us` is a bin edge).
    pub fn fraction_below(&self, dt_us: u64) -> f64 {
        let total = self.total();
        if total == 0 {
            return 0.0;
        }
        let limit = bin_of(dt_us);
        let below: u64 = self.counts[..limit].iter().sum();
        below as f64 / total as f64
    }

    /// Non-empty bins as `(low_us, width_us, count)`, for plots.
    pub fn bins(&self) -> impl Iterator<Item = (u64, u64, u64)> + '_ {
        self.counts
            .iter()
            .enumerate()
            .filter(|(_, c)| **c > 0)
            .map(|(b, &c)| {
                let (low, width) = bin_range(b);
                (low, width, c)
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bins_tile_the_integers_without_gaps() {
        let mut expected_low = 0u64;
        for b in 0..(SUB_BUCKETS as usize * 12) {
            let (low, width) = bin_range(b);
            assert_eq!(low, expected_low, "bin {b}");
            assert_eq!(bin_of(low), b);
            assert_eq!(bin_of(low + width - 1), b);
            expected_low = low + width;
        }
        assert_eq!(bin_of(u64::MAX), BINS - 1);
        // the branch-free formula is the two-case one
        let two_case = |dt: u64| {
            if dt < SUB_BUCKETS {
                dt as usize
            } else {
                let shift = 63 - dt.leading_zeros() - SUB_BITS;
                ((shift as u64 + 1) * SUB_BUCKETS + ((dt >> shift) - SUB_BUCKETS)) as usize
            }
        };
        for shift in 0..64 {
            for dt in [
                1u64 << shift,
                (1u64 << shift) - 1,
                (1u64 << shift) + 1,
                0,
                127,
                128,
            ] {
                assert_eq!(bin_of(dt), two_case(dt), "{dt}");
            }
        }
    }

    #[test]
    fn quantiles_are_exact_below_128_us_and_within_resolution_above() {
        let mut h = IntervalHistogram::default();
        for dt in 1..=100u64 {
            h.add(dt);
        }
        assert_eq!(h.quantile_us(0.05), Some(5.0));
        assert_eq!(h.quantile_us(0.5), Some(50.0));
        let mut h = IntervalHistogram::default();
        for dt in (1..=10_000u64).map(|i| i * 1000) {
            h.add(dt);
        }
        let median = h.quantile_us(0.5).unwrap();
        assert!(
            (median - 5_000_000.0).abs() / 5_000_000.0 < RELATIVE_RESOLUTION,
            "{median}"
        );
        assert!((h.fraction_below(1_000_000) - 0.0999).abs() < 0.002);
    }
}
