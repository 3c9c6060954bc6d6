//! The hot pixels a fit reports: the named ones in excess of the final model's own count
//! outliers ([`super::hot_excess`]), their count's lower end against the most outliers the
//! model makes at a threshold spread the data allow, and the assumption that says how they
//! were counted.

use super::super::FitInput;
use super::super::observe::{Observed, Subset};
use super::super::search::Simulation;
use super::State;
use crate::fit::Uncertain;
use std::collections::BTreeMap;

const HOT_FRACTION: &str = "hot_pixel_fraction";

/// The hot pixels reported: the named ones in excess of the final model's own count
/// outliers ([`super::hot_excess`]), the count's lower end against the most outliers the
/// model makes at a threshold spread the data allow ([`allowed_spreads`]), as a simulator
/// takes them (a fraction of the kept pixels and a median rate); the assumption
/// that says how they were counted.
pub(super) fn hot_pixels(
    simulation: &Simulation,
    state: &mut State,
    input: &FitInput,
    measured_spread: Option<(f64, [f64; 2])>,
    params: &mut crate::sim::PixelParams,
) -> String {
    let g = simulation.geometry;
    let kept_counts = |observed: &Observed| kept_counts(observed, simulation, state);
    let model = kept_counts(&state.model.observed);
    let real = kept_counts(&simulation.real);
    let (spreads, source) = allowed_spreads(state, measured_spread);
    let at_spreads: Vec<Vec<u32>> = spreads
        .iter()
        .filter_map(|&sigma| {
            let mut p = state.model.params.clone();
            p.ct_sigma = Some(sigma);
            let observed = simulation.observe(&p, &state.masked).ok()?;
            Some(kept_counts(&observed))
        })
        .collect();
    let found = super::hot_excess::excess(&super::hot_excess::Counts {
        real_named: &state.hot,
        model: Some(&model),
        model_at_allowed_spreads: &at_spreads,
        width: g.sensor.width as usize,
        height: g.sensor.height as usize,
        duration_s: g.duration_of(Subset::Fit),
        kept_pixels: input.excluded.iter().filter(|&&e| !e).count(),
        real: &real,
        kept: &state.kept,
    });
    params.hot_pixel_fraction = Some(found.fraction.value);
    params.hot_pixel_rate_hz = found.rate.as_ref().map(|r| r.value);
    state
        .uncertainty
        .insert(HOT_FRACTION.into(), found.fraction.clone());
    if let Some(rate) = found.rate.clone() {
        state.uncertainty.insert("hot_pixel_rate_hz".into(), rate);
    }
    state.hot_detection = found.detection.clone();
    hot_pixels_assumption(state.hot.len(), &found, &spreads, source)
}

/// `observed`'s per-pixel counts on the fit blocks, 0 outside the kept pixels.
fn kept_counts(observed: &Observed, simulation: &Simulation, state: &State) -> Vec<u32> {
    let mut counts = observed.pixels_of(simulation.geometry, Subset::Fit);
    for (count, kept) in counts.iter_mut().zip(&state.kept) {
        if !kept {
            *count = 0;
        }
    }
    counts
}

/// Which hot pixels the search would have named, where the final model has none: its
/// reach on the recording's counts of the fit blocks ([`super::hot_excess::search_reach`]).
/// Pixels the search named and the loop did not keep as hot are the scene's, as the fit
/// found them.
pub(super) fn search_reach(
    simulation: &Simulation,
    state: &State,
) -> Option<crate::fit::HotPixelDetection> {
    let g = simulation.geometry;
    super::hot_excess::search_reach(
        &kept_counts(&simulation.real, simulation, state),
        &[],
        &state.kept,
        (g.sensor.width as usize, g.sensor.height as usize),
        g.duration_of(Subset::Fit),
    )
}

/// Threshold spreads (ln units) taken as possible where the recording measures none: from
/// the 2.1 % contrast-threshold mismatch measured on the DVS128 (Lichtsteiner, Posch &
/// Delbruck, IEEE JSSC 2008) through v2e's default 0.03 (Hu, Liu & Delbruck, CVPRW 2021)
/// to four times the first, as a sensor's spread is unknown without a measurement.
pub const UNMEASURED_SPREADS: [f64; 3] = [0.02, 0.04, 0.08];

/// Threshold spreads the data allow besides the model's own, at which the model's outliers
/// are counted, and where they come from: the fitted spread's 95 % interval, or where the
/// model has none the spread event timing measures with its interval (at the interval's
/// ends, the lower one at least half the value, the value, and the geometric middle of the
/// value and the upper end); where neither is measured, [`UNMEASURED_SPREADS`].
fn allowed_spreads(state: &State, measured: Option<(f64, [f64; 2])>) -> (Vec<f64>, &'static str) {
    let model = state.model.params.ct_sigma.unwrap_or(0.0);
    let fitted = state
        .uncertainty
        .get("ct_sigma")
        .filter(|_| model > 0.0)
        .and_then(|u| match u.ci95 {
            Some([Some(lo), Some(hi)]) => Some((u.value, [lo, hi])),
            _ => None,
        });
    spreads_around(model, fitted, measured)
}

/// [`allowed_spreads`] from the model's spread (0: none), the fitted one and the measured
/// one (value, 95 % interval).
fn spreads_around(
    model: f64,
    fitted: Option<(f64, [f64; 2])>,
    measured: Option<(f64, [f64; 2])>,
) -> (Vec<f64>, &'static str) {
    let across = |(value, [lo, hi]): (f64, [f64; 2])| {
        vec![lo.max(value / 2.0), value, (value * hi).sqrt(), hi]
    };
    let (candidates, source) = match (fitted, measured) {
        (Some(fitted), _) => (across(fitted), "across the fitted spread's 95 % interval"),
        (None, Some(measured)) => (
            across(measured),
            "across the 95 % interval of the spread event timing measures",
        ),
        (None, None) => (
            UNMEASURED_SPREADS.to_vec(),
            "not measured here: spreads from the 2.1 % of the DVS128 (Lichtsteiner, Posch & Delbruck 2008) to four times that",
        ),
    };
    let mut spreads: Vec<f64> = candidates
        .into_iter()
        .filter(|s| s.is_finite() && *s > 0.0 && (s - model).abs() > 1e-6)
        .collect();
    spreads.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
    (spreads, source)
}

fn hot_pixels_assumption(
    named: usize,
    found: &super::hot_excess::HotExcess,
    spreads: &[f64],
    source: &str,
) -> String {
    let scope = found.detection.as_ref().map(|d| d.detectable_above_hz).map_or(
        "the search's detection probability not measurable: pixels too weak to stand out from their neighbours are not counted".to_string(),
        |r| format!("each counted 1 / its detection probability at a random kept pixel (Horvitz-Thompson, at least 1/2), so hot pixels at {r:.1} Hz or faster (the rate the search names at half the kept pixels) are counted in full and a slower one as 2 p(r) of one (hot_pixel_detection.probability): slower hot pixels are not determinable on this recording"),
    );
    let tail = match found.model_outliers_at_allowed_spreads {
        Some(m) => {
            let listed: Vec<String> = spreads.iter().map(|s| format!("{s:.4}")).collect();
            format!(
                "; the fraction's lower end counts them against {m}, the most outliers the model makes at a threshold spread the data allow ({}; {source}) and that does not make more outliers than the recording beyond chance: pixels at the low tail of the thresholds fire as hot pixels do",
                listed.join(", ")
            )
        }
        None => String::new(),
    };
    format!(
        "hot pixels: {named} named on the fit blocks (robust z against the busiest neighbour, their excess showing also where no neighbour fires within 30 ms; masked and simulated at their own rates), {} of them in excess of the {} count outliers the final model (mismatch, noise) makes by itself on the same blocks; hot_pixel_fraction and hot_pixel_rate_hz describe those {} (fraction interval: Poisson spread of both counts, Garwood's exact interval when the model makes none{tail}; rate: the median of their rates beyond their 8 neighbours' median, its interval reaching down to the rate the search names at 10 % of the kept pixels where it names that median at under 90 %: the named are then the upper tail of a slower kind), {scope}",
        found.hot.len(),
        found.model_outliers,
        found.hot.len()
    )
}

/// Where a threshold is not determined (`why` holds `ct_on` or `ct_off`), the final model's
/// own count outliers are not known: its events of that polarity rest on a start value (or
/// a bound), and the outliers of a sensor without defects (low thresholds, leak and noise
/// scaled by them) with it. The named pixels still bound the hot ones from above, but not
/// from below: the fraction's lower end is 0. Coverage draws 1028, 1032 and 2029 (no hot
/// pixels, a threshold not determined, 7 to 19 pixels named with an interval above 0).
pub(super) fn reach_zero_where_thresholds_undetermined(
    uncertainty: &mut BTreeMap<String, Uncertain>,
    why: &BTreeMap<String, String>,
) -> Option<String> {
    let undetermined: Vec<&str> = ["ct_on", "ct_off"]
        .into_iter()
        .filter(|k| why.contains_key(*k))
        .collect();
    let fraction = uncertainty.get_mut(HOT_FRACTION)?;
    let Some([Some(lo), hi]) = fraction.ci95 else {
        return None;
    };
    if undetermined.is_empty() || lo <= 0.0 {
        return None;
    }
    fraction.ci95 = Some([Some(0.0), hi]);
    Some(format!(
        "hot_pixel_fraction's lower end is 0 (it was {lo:.3e}): {} is not determined, so the outliers the model makes without any defect are not known, and the named pixels bound the hot ones from above only",
        undetermined.join(" and ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spreads_are_taken_across_the_fitted_then_the_measured_interval_then_the_prior() {
        let close = |a: &[f64], b: &[f64]| {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
        };
        // a fitted 0.04 [0.01, 0.09]: the lower end at least half the value (0.02), the
        // value itself left out (the model's own), the middle sqrt(0.04 x 0.09) = 0.06
        let measured = Some((1.0, [0.5, 2.0]));
        let (s, source) = spreads_around(0.04, Some((0.04, [0.01, 0.09])), measured);
        assert!(close(&s, &[0.02, 0.06, 0.09]), "{s:?}");
        assert!(source.contains("fitted"));
        // no mismatch in the model (draw 1018): event timing's 0.0288 [0.0045, 0.173]
        let (s, source) = spreads_around(0.0, None, Some((0.0288, [0.0045, 0.173])));
        let middle = (0.0288f64 * 0.173).sqrt();
        assert!(close(&s, &[0.0144, 0.0288, middle, 0.173]), "{s:?}");
        assert!(source.contains("event timing"));
        // nothing measured: the prior, named as such
        let (s, source) = spreads_around(0.0, None, None);
        assert_eq!(s, UNMEASURED_SPREADS.to_vec());
        assert!(source.starts_with("not measured"));
    }

    #[test]
    fn a_threshold_not_determined_takes_the_hot_fraction_down_to_zero() {
        let fraction = Uncertain::with_interval(4.6e-4, None, [Some(1.8e-4), Some(9.4e-4)]);
        let mut uncertainty = BTreeMap::from([(HOT_FRACTION.to_string(), fraction.clone())]);
        // thresholds determined: nothing changes
        assert!(
            reach_zero_where_thresholds_undetermined(&mut uncertainty, &BTreeMap::new()).is_none()
        );
        assert_eq!(uncertainty[HOT_FRACTION], fraction);
        let why = BTreeMap::from([("ct_off".to_string(), "too few events".to_string())]);
        let note = reach_zero_where_thresholds_undetermined(&mut uncertainty, &why).unwrap();
        assert!(note.contains("ct_off is not determined"), "{note}");
        assert_eq!(
            uncertainty[HOT_FRACTION].ci95,
            Some([Some(0.0), Some(9.4e-4)])
        );
        assert_eq!(uncertainty[HOT_FRACTION].value, 4.6e-4);
    }
}
