//! Photoreceptor bandwidth: the photoreceptor is a first-order low-pass filter whose
//! cutoff is proportional to the photocurrent, so in the dark a fast change is smoothed and
//! crosses fewer thresholds (Lichtsteiner, Posch & Delbruck, JSSC 2008; modelled as v2e does,
//! cutoff `cutoff_hz * (DN + 20) / 275`, [`crate::sim::effects::bandwidth`]).
//!
//! Signature: against a model without it, the recording has a count deficit that grows as
//! intensity falls and change gets faster: the filter's time constant goes as one over the
//! intensity, so what it removes depends on the change rate over the intensity. Evidence:
//! the weighted least-squares slope of the count-cell log ratio `ln(simulated / real)`
//! against `ln(change rate / intensity)` is positive (the model over-predicts fast changes
//! in the dark), in standard errors from the scatter of the cells about the line; it matters
//! when the ratio changes by more than 10 % across the cells seen. Noise, which adds events
//! where the scene changes slowly, is kept out: the cells count supported events only.

use super::{Context, Effect, Evidence};
use crate::fit::metric::cell_ratios;
use crate::fit::observe::cell_of;

pub fn evidence(c: &Context) -> Evidence {
    let cells = cell_ratios(c.real, c.sim, c.geometry, c.subset);
    let points: Vec<(f64, f64, f64)> = cells
        .iter()
        .map(|&(ratio, real, index)| {
            let (intensity, change, _) = cell_of(index);
            let g = c.geometry;
            let x = (g.change_centres[change] / g.intensity_centres[intensity]).ln();
            (x, ratio, real as f64 + 0.5)
        })
        .collect();
    let Some((slope, se, spread)) = weighted_slope(&points) else {
        return Evidence::none(Effect::Bandwidth, "too few intensity levels to compare");
    };
    let change = slope * spread;
    Evidence {
        effect: Effect::Bandwidth,
        score: if se > 0.0 { slope / se } else { 0.0 },
        relevant: change > 0.10,
        text: format!(
            "log(simulated/real) counts rise by {slope:.3} (+- {se:.3}) per unit of ln(change rate / intensity): the model makes {:.0} % more events for fast changes in the dark than for slow changes in the bright, relative to the recording",
            100.0 * (change.exp() - 1.0)
        ),
        start: Some(100.0),
    }
}

/// Weighted least-squares slope of `y` on `x` (points `(x, y, weight)`), its standard
/// error from the weighted scatter about the line, and the range of `x`.
pub fn weighted_slope(points: &[(f64, f64, f64)]) -> Option<(f64, f64, f64)> {
    if points.len() < 4 {
        return None;
    }
    let w: f64 = points.iter().map(|p| p.2).sum();
    let mx = points.iter().map(|p| p.0 * p.2).sum::<f64>() / w;
    let my = points.iter().map(|p| p.1 * p.2).sum::<f64>() / w;
    let sxx: f64 = points.iter().map(|p| p.2 * (p.0 - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let slope = points
        .iter()
        .map(|p| p.2 * (p.0 - mx) * (p.1 - my))
        .sum::<f64>()
        / sxx;
    let intercept = my - slope * mx;
    let residual: f64 = points
        .iter()
        .map(|p| p.2 * (p.1 - intercept - slope * p.0).powi(2))
        .sum();
    // the weighted residual variance per unit weight, scaled to the effective sample size
    let n = points.len() as f64;
    let se = (residual / (n - 2.0) / sxx).sqrt();
    let lo = points.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let hi = points.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
    Some((slope, se, hi - lo))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_slope_of_a_line_with_scatter() {
        let points: Vec<(f64, f64, f64)> = (0..20)
            .map(|i| {
                let x = i as f64 * 0.2;
                (
                    x,
                    1.0 - 0.5 * x + if i % 2 == 0 { 0.01 } else { -0.01 },
                    100.0,
                )
            })
            .collect();
        let (slope, se, spread) = weighted_slope(&points).unwrap();
        assert!((slope + 0.5).abs() < 1e-3, "{slope}");
        assert!(se > 0.0 && se < 0.01, "{se}");
        assert!((spread - 3.8).abs() < 1e-9);
    }
}
