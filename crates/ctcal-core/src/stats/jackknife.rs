//! The delete-one-block jackknife: the standard error of an estimate made from blocks of a
//! series (time blocks of a recording), which sees what resampling within the blocks cannot
//! (what changes from block to block: the scene each shows, drifts, an effect the model
//! lacks acting unevenly). Shared by the event-timing estimate and the fit.

use statrs::distribution::{ContinuousCDF, StudentsT};

/// The delete-m_j jackknife's standard error (Busing et al. 1999, eq. 6-8): `whole` the
/// estimate on all blocks, `left_out[j]` without block `j`, `sizes[j]` block `j`'s size.
/// With equal sizes it is the ordinary delete-one jackknife,
/// `sqrt((g - 1) / g * sum (left_out - mean)^2)`.
pub fn weighted_jackknife_se(whole: f64, left_out: &[f64], sizes: &[f64]) -> f64 {
    let g = left_out.len() as f64;
    let n: f64 = sizes.iter().sum();
    let h: Vec<f64> = sizes.iter().map(|&m| n / m).collect();
    let corrected = g * whole
        - left_out
            .iter()
            .zip(sizes)
            .map(|(&t, &m)| (1.0 - m / n) * t)
            .sum::<f64>();
    let variance = left_out
        .iter()
        .zip(&h)
        .map(|(&t, &h)| {
            let pseudo = h * whole - (h - 1.0) * t;
            (pseudo - corrected).powi(2) / (h - 1.0)
        })
        .sum::<f64>()
        / g;
    variance.max(0.0).sqrt()
}

/// `t(0.975, blocks - 1) / 1.96`: with few blocks the jackknife's own error is large, and
/// this scale makes `+-1.96` of the scaled error a 95 % interval (2.57 / 1.96 for six
/// blocks); 1 below two blocks.
pub fn t95_scale(blocks: usize) -> f64 {
    if blocks < 2 {
        return 1.0;
    }
    StudentsT::new(0.0, 1.0, (blocks - 1) as f64).map_or(1.0, |t| t.inverse_cdf(0.975) / 1.96)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_blocks_give_the_ordinary_jackknife() {
        // the mean of 4 equal blocks with means 1, 2, 3, 6: whole 3, left out 11/3, 10/3,
        // 3, 2; ordinary jackknife sqrt(3/4 * sum (t - 3)^2) = sqrt(3/4 * 14/9)
        let left_out = [11.0 / 3.0, 10.0 / 3.0, 3.0, 2.0];
        let se = weighted_jackknife_se(3.0, &left_out, &[5.0; 4]);
        assert!((se - (0.75f64 * 14.0 / 9.0).sqrt()).abs() < 1e-12, "{se}");
        // which is the standard error of a mean of 4 block means, sd / sqrt(4)
        let sd = ((4.0 + 1.0 + 0.0 + 9.0) / 3.0f64).sqrt();
        assert!((se - sd / 2.0).abs() < 1e-12);
    }

    #[test]
    fn unequal_blocks_weigh_the_larger_more() {
        // a weighted mean over blocks of sizes 1, 1, 2 with block means 0, 0, 4: whole 2;
        // its standard error by the delta method is larger than with the big block split
        let left_out = [8.0 / 3.0, 8.0 / 3.0, 0.0];
        let se = weighted_jackknife_se(2.0, &left_out, &[1.0, 1.0, 2.0]);
        assert!(se.is_finite() && se > 1.0 && se < 3.0, "{se}");
    }
}
