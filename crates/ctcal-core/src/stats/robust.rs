//! Summary statistics shared by the estimators and the fit: the sample variance and standard deviation,
//! the median and the median absolute deviation (scaled to a normal's sigma: Hampel 1974).

/// The sample standard deviation (n - 1 denominator); `None` below two values.
pub fn sample_std_dev(values: &[f64]) -> Option<f64> {
    sample_variance(values).map(f64::sqrt)
}

/// The sample variance (n - 1 denominator); `None` below two values.
pub fn sample_variance(values: &[f64]) -> Option<f64> {
    if values.len() < 2 {
        return None;
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    Some(values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0))
}

/// The median (the upper middle of an even count); `None` when empty.
pub fn median(values: &[f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mut v = values.to_vec();
    let mid = v.len() / 2;
    Some(*v.select_nth_unstable_by(mid, f64::total_cmp).1)
}

/// The bin holding the median of a histogram (`counts[k]` values in bin `k`): the first bin
/// at which the running count reaches half the total; `None` when the histogram is empty.
pub fn histogram_median(counts: &[u64]) -> Option<usize> {
    let total: u64 = counts.iter().sum();
    let mut seen = 0;
    (total > 0).then(|| {
        counts
            .iter()
            .position(|&n| {
                seen += n;
                2 * seen >= total
            })
            .unwrap_or(counts.len() - 1)
    })
}

/// The median absolute deviation times 1.4826 (a normal's sigma); `None` when empty.
pub fn mad_sigma(values: &[f64]) -> Option<f64> {
    let m = median(values)?;
    let deviations: Vec<f64> = values.iter().map(|v| (v - m).abs()).collect();
    Some(1.4826 * median(&deviations)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_histogram_s_median_is_the_bin_where_half_the_count_is_reached() {
        // 3 of 8 values up to bin 2, under half; bin 3 brings the count to 4
        assert_eq!(histogram_median(&[3, 0, 0, 1, 4]), Some(3));
        assert_eq!(histogram_median(&[0, 5, 0]), Some(1));
        assert_eq!(histogram_median(&[1, 1, 1, 1, 1]), Some(2));
        assert_eq!(histogram_median(&[0, 0]), None);
    }

    #[test]
    fn hand_computed() {
        // mean 5, squares 9+1+1+9 = 20, / 3
        let sd = sample_std_dev(&[2.0, 4.0, 6.0, 8.0]).unwrap();
        assert!((sd - (20.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert_eq!(sample_std_dev(&[1.0]), None);
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        // median 3; deviations 2, 0, 1, 7, 1 -> median 1
        assert_eq!(mad_sigma(&[1.0, 3.0, 2.0, 10.0, 4.0]), Some(1.4826));
    }
}
