//! The fitted thresholds beside the starting ones. The two come from different methods on
//! the same fit run: the start times events between frames (`estimate aps`: the event
//! timing and a re-simulation check), the fit matches event counts of the frames
//! re-simulated, which loses contrast wherever the frames do (motion blur within an
//! exposure, optical flow that fails between frames many pixels apart: Stoffregen et al.,
//! ECCV 2020, sec. 4, name frame quality as the limit of re-simulation). Where the two
//! disagree beyond both their intervals' chance, an effect neither models is at work and
//! these data do not say which method it biases: each threshold's interval then spans both
//! methods' intervals. Where they agree, nothing changes (a clean case keeps its interval).

use super::super::Uncertain;
use crate::estimate::Interval;
use crate::estimate::interval::z95;
use std::collections::BTreeMap;

/// The starting thresholds as measured: (value, 95 % interval) for ON and OFF.
pub type Measured = [(f64, Interval); 2];

/// The standard error of ln(value) behind a closed 95 % interval.
fn ln_se(interval: Interval) -> Option<f64> {
    let [Some(lo), Some(hi)] = interval else {
        return None;
    };
    (lo > 0.0 && hi >= lo).then(|| (hi / lo).ln() / (2.0 * z95()))
}

/// How far apart the fitted and the starting value are, in standard errors of their
/// log ratio.
fn disagreement(fitted: &Uncertain, start: (f64, Interval)) -> Option<f64> {
    let fit_se = ln_se(fitted.interval()?)?;
    let start_se = ln_se(start.1)?;
    let combined = fit_se.hypot(start_se);
    (combined > 0.0 && fitted.value > 0.0 && start.0 > 0.0)
        .then(|| (fitted.value / start.0).ln().abs() / combined)
}

/// Widens the thresholds' intervals to span the start's where the fit and the start
/// disagree (beyond 1.96 standard errors of their log ratio, for either polarity: one cause
/// acts on both); returns the assumption that says so, with the sizes. `what` names the
/// start's measurement in the assumption (the start's thresholds, or its event timing's),
/// `short` beside each value. A start value that is not a positive number spans nothing,
/// nor does a fitted interval that is not closed, positive and finite.
pub fn reconcile(
    uncertainty: &mut BTreeMap<String, Uncertain>,
    start: &Measured,
    (short, what): (&str, &str),
) -> Option<String> {
    let keys = ["ct_on", "ct_off"];
    let z: Vec<Option<f64>> = keys
        .iter()
        .zip(start)
        .map(|(k, s)| disagreement(uncertainty.get(*k)?, *s))
        .collect();
    let worst = z.iter().flatten().copied().fold(0.0_f64, f64::max);
    if worst <= z95() {
        return None;
    }
    let mut spans = Vec::new();
    let mut fitted = Vec::new();
    for (key, (value, interval)) in keys.iter().zip(start) {
        let Some(u) = uncertainty.get_mut(*key) else {
            continue;
        };
        if !(value.is_finite() && *value > 0.0) {
            continue;
        }
        let Some([Some(lo), Some(hi)]) = u.interval() else {
            continue;
        };
        if !(lo > 0.0 && hi.is_finite()) {
            continue;
        }
        let [s_lo, s_hi] = *interval;
        let span = [
            Some(s_lo.map_or(lo, |s| s.min(lo))),
            Some(s_hi.map_or(hi, |s| s.max(hi))),
        ];
        u.ci95 = Some(span);
        let name = if *key == "ct_on" { "ON" } else { "OFF" };
        fitted.push(format!("{name} {:.4} ({short} {value:.4})", u.value));
        spans.push(format!(
            "{name} {:.4} .. {:.4}",
            span[0].unwrap_or(lo),
            span[1].unwrap_or(hi)
        ));
    }
    Some(format!(
        "the fitted thresholds ({}) and {what} disagree by {worst:.1} standard errors of their log ratio: an effect neither models (frames blurred by motion, optical flow failing between frames far apart, noise the frames carry, events lost or added where the counts are matched) biases one of them and these data do not say which, so each threshold's 95 % interval spans both methods' intervals ({}); the standard errors given are the fit's alone",
        fitted.join(", "),
        spans.join(", ")
    ))
}

/// The smallest interpolation share that moves an interval (0.5 %: below the thresholds'
/// usual standard errors).
const MIN_INTERPOLATION_SHARE: f64 = 0.005;

/// Raises the upper ends of the thresholds' intervals by the share of each threshold the
/// start's event timing found the frames' interpolation to miss (`share`, ON and OFF;
/// [`crate::estimate::aps::ApsResult::interpolation_share`]): the fit matches counts of the
/// same interpolated frames, so its thresholds may be that much low, and only low. Shares
/// under 0.5 % or of 50 % and more (not the interpolation's) leave the intervals alone.
/// Returns the assumption that says so, with the sizes.
pub fn reach_for_interpolation(
    uncertainty: &mut BTreeMap<String, Uncertain>,
    share: [f64; 2],
) -> Option<String> {
    let mut moved = Vec::new();
    for (key, s) in ["ct_on", "ct_off"].into_iter().zip(share) {
        if !(MIN_INTERPOLATION_SHARE..0.5).contains(&s) {
            continue;
        }
        if let Some(Some(hi)) = uncertainty
            .get_mut(key)
            .and_then(|u| u.ci95.as_mut())
            .map(|c| c[1].as_mut())
        {
            *hi /= 1.0 - s;
            moved.push(format!("{key} {:.1} %", 100.0 * s));
        }
    }
    (!moved.is_empty()).then(|| {
        format!(
            "the fit matches event counts of the frames interpolated along the optical flow, which the start's event timing found to miss part of the change between frames ({}): the thresholds' intervals reach up by that share, since a missed change only lowers count-matched thresholds",
            moved.join(", ")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fitted(value: f64, lo: f64, hi: f64) -> Uncertain {
        Uncertain::with_interval(value, None, [Some(lo), Some(hi)])
    }

    /// Fitted ON and OFF thresholds, each `(value, lo, hi)`, as the fit's uncertainties.
    fn thresholds(on: (f64, f64, f64), off: (f64, f64, f64)) -> BTreeMap<String, Uncertain> {
        BTreeMap::from([
            ("ct_on".to_string(), fitted(on.0, on.1, on.2)),
            ("ct_off".to_string(), fitted(off.0, off.1, off.2)),
        ])
    }

    /// The count fit of coverage draw 13034 (before the method systematic).
    fn draw_13034() -> BTreeMap<String, Uncertain> {
        thresholds((0.3126, 0.2213, 0.4416), (0.9070, 0.4385, 1.7549))
    }

    /// The coverage study's case 85 (natural-image objects at 50 Hz): the fit's OFF 0.330
    /// [0.317, 0.343] for a true 0.343; the start's timing found the interpolation to miss
    /// 4 % of ON and 3 % of OFF.
    #[test]
    fn the_intervals_reach_up_by_what_the_interpolation_misses() {
        let mut u = thresholds((0.805, 0.703, 0.923), (0.330, 0.317, 0.343));
        let note = reach_for_interpolation(&mut u, [0.04, 0.03]).unwrap();
        assert!(note.contains("ct_on 4.0 %, ct_off 3.0 %"), "{note}");
        let [lo, hi] = u["ct_off"].ci95.unwrap();
        assert_eq!(lo, Some(0.317));
        assert!((hi.unwrap() - 0.343 / 0.97).abs() < 1e-12);
        assert_eq!(u["ct_off"].value, 0.330);
        // nothing to reach for, or a share that is not the interpolation's
        let before = u.clone();
        assert!(reach_for_interpolation(&mut u, [0.001, 0.6]).is_none());
        assert_eq!(u, before);
    }

    /// The coverage study's case 13 (dim, 9 px of motion between frames): the count fit
    /// at 0.220 / 0.1075 for a true 0.309 / 0.131, the start at 0.276 / 0.131.
    #[test]
    fn methods_that_disagree_give_an_interval_spanning_both() {
        let mut u = thresholds((0.2200, 0.1944, 0.2489), (0.1075, 0.1015, 0.1138));
        let start = [
            (0.2759, [Some(0.2174), Some(0.3345)]),
            (0.1310, [Some(0.1234), Some(0.1386)]),
        ];
        let note = reconcile(&mut u, &start, ("start", "the start's event timing"))
            .expect("OFF disagrees by about 5 standard errors");
        assert!(note.contains("disagree by 4.8 standard errors"), "{note}");
        assert_eq!(u["ct_on"].ci95, Some([Some(0.1944), Some(0.3345)]));
        assert_eq!(u["ct_off"].ci95, Some([Some(0.1015), Some(0.1386)]));
        // the values stay the fit's, and now the truth is inside
        assert_eq!(u["ct_on"].value, 0.2200);
        let inside = |k: &str, t: f64| {
            let [lo, hi] = u[k].ci95.unwrap();
            lo.unwrap() <= t && t <= hi.unwrap()
        };
        assert!(inside("ct_on", 0.309) && inside("ct_off", 0.131));
    }

    /// Within chance of each other, the fit keeps its own interval (case 15 of the study:
    /// fit 0.246 / 0.398, start 0.236 / 0.370).
    #[test]
    fn methods_that_agree_leave_the_interval_alone() {
        let before = thresholds((0.246, 0.212, 0.286), (0.398, 0.348, 0.454));
        let mut u = before.clone();
        let start = [
            (0.236, [Some(0.230), Some(0.242)]),
            (0.370, [Some(0.351), Some(0.390)]),
        ];
        assert_eq!(reconcile(&mut u, &start, ("start", "the start")), None);
        assert_eq!(u, before);
        // an open side of the start's interval measures no disagreement
        let open = [(0.5, [Some(0.4), None]), (0.9, [None, Some(1.0)])];
        assert_eq!(reconcile(&mut u, &open, ("start", "the start")), None);
    }

    /// Coverage draw 13034 (ESIM at 20 DN, thresholds 0.191 / 0.567 redrawn every sample
    /// interval with a spread of 0.080: a draw below the change already gained strands the
    /// pixel, so ESIM loses events and the count fit reads ON 0.313). `estimate aps` reported
    /// no thresholds, but its event timing read ON 0.152 [0.139, 0.165], OFF 0.537
    /// [0.457, 0.616] (on the whole recording): the fit's interval reaches it, and the truth.
    #[test]
    fn count_thresholds_far_from_the_event_timing_span_it() {
        let mut u = draw_13034();
        let timing = [
            (0.152, [Some(0.139), Some(0.165)]),
            (0.537, [Some(0.457), Some(0.616)]),
        ];
        let note = reconcile(
            &mut u,
            &timing,
            ("event timing", "the start's event timing"),
        )
        .expect("ON disagrees");
        assert!(note.contains("ON 0.3126 (event timing 0.1520)"), "{note}");
        assert_eq!(u["ct_on"].ci95, Some([Some(0.139), Some(0.4416)]));
        assert_eq!(u["ct_off"].ci95, Some([Some(0.4385), Some(1.7549)]));
        let [lo, hi] = u["ct_on"].ci95.unwrap();
        assert!(lo.unwrap() <= 0.191 && 0.191 <= hi.unwrap());
    }

    /// A start value that is not a positive number (an event timing that failed) measures
    /// no disagreement and spans nothing, though the other polarity's does.
    #[test]
    fn a_start_value_that_is_not_positive_spans_nothing() {
        let mut u = draw_13034();
        let timing = [
            (0.152, [Some(0.139), Some(0.165)]),
            (f64::NAN, [None, None]),
        ];
        let note = reconcile(
            &mut u,
            &timing,
            ("event timing", "the start's event timing"),
        )
        .expect("ON disagrees");
        assert!(!note.contains("NaN") && !note.contains("OFF"), "{note}");
        assert_eq!(u["ct_off"].ci95, Some([Some(0.4385), Some(1.7549)]));
    }
}
