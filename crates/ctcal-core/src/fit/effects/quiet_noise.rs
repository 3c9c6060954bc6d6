//! What the recording's isolated OFF events at quiet pixels say of shot noise in a fit with
//! frames: a count of the noise that needs no model of the scene
//! ([`crate::fit::events_only::QuietOff`]).
//!
//! The fit's shot-noise evidence compares isolated events (no 8-neighbour event within
//! 10 ms) between the recording and the model; any scene event the model misses and no
//! neighbour supports reads there as noise: a photoreceptor lagging the scene in the dark,
//! a leak the model lacks, wrong thresholds at sparse edges. Coverage draws 8027 and 8002
//! (no shot noise; leak and a 234 Hz cutoff at 17 DN, a 326 Hz cutoff at 40 DN) were given
//! 0.63 and 0.021 Hz with intervals excluding none, while their quiet pixels held no
//! isolated OFF event. Shot noise fires OFF and ON alike at every pixel, moving or not; leak
//! only ON. So:
//!
//! - shot noise is not tried where the quiet OFF rate bounds it below the rate that
//!   matters ([`rules_out`]);
//! - a fitted shot-noise rate's interval holds the dark rate the quiet OFF rate gives
//!   ([`direct_dark_rate`], [`widen`]): on draw 8007 (2.78 Hz) the search's 4.05
//!   [3.68, 4.27] against the count's 2.5-3.8.

use crate::estimate::Interval;
use crate::fit::Uncertain;
use crate::fit::effects::Context;
use crate::fit::events_only::QuietOff;
use crate::fit::observe::{Geometry, INTENSITY_BINS, Subset};
use crate::sim::PixelParams;
use crate::sim::effects::shot_noise::brightness_factor;
use crate::stats::binomial::poisson95;
use std::collections::BTreeMap;

/// The share of shot noise that is OFF: each polarity's rate goes as its nominal threshold
/// over the pixel's ([`crate::sim::effects::shot_noise::pixel_rates`], as v2e), so a
/// nominal pixel fires OFF half the time whatever Cp and Cn are.
const OFF_SHARE: f64 = 0.5;

/// The smallest and largest brightness factor (observed over dark rate) of the intensity
/// bins with pixel time on the fit blocks: the quiet pixels' own brightness lies within.
fn factor_range(geometry: &Geometry, model: &PixelParams) -> Option<[f64; 2]> {
    let bright = model.shot_noise_bright_factor() as f32;
    let factors: Vec<f64> = (0..INTENSITY_BINS)
        .filter(|&b| geometry.exposure_of(b, Subset::Fit) > 0.0)
        .map(|b| brightness_factor(geometry.intensity_centres[b] as f32, bright) as f64)
        .filter(|&f| f > 0.0)
        .collect();
    let lo = factors.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = factors.iter().copied().fold(0.0, f64::max);
    (hi > 0.0).then_some([lo, hi])
}

/// Garwood's exact 95 % interval of the quiet OFF rate, events per pixel-second.
fn off_rate95(quiet: &QuietOff) -> (f64, f64) {
    let n = (quiet.rate_hz * quiet.pixel_seconds).round().max(0.0) as usize;
    let (lo, hi) = poisson95(n);
    (lo / quiet.pixel_seconds, hi / quiet.pixel_seconds)
}

/// The most shot noise (ON + OFF events per pixel-second, averaged over the recording's
/// brightness) the quiet OFF count allows: the upper end of its exact 95 % interval over
/// the OFF share, times how much brighter the quiet pixels may be than the rest.
pub(crate) fn most_observed_hz(c: &Context, quiet: &QuietOff) -> Option<f64> {
    let [lo, hi] = factor_range(c.geometry, c.model)?;
    Some(off_rate95(quiet).1 / OFF_SHARE * hi / lo)
}

/// Why shot noise is not tried, where the quiet OFF count keeps it below `relevant_hz`.
pub(crate) fn rules_out(c: &Context, relevant_hz: f64) -> Option<String> {
    let quiet = c.quiet_off?;
    let most = most_observed_hz(c, &quiet)?;
    (most < relevant_hz).then(|| {
        format!(
            "the recording's quiet pixels hold {:.4} isolated OFF events per pixel-second ({:.0} pixel-s without a neighbour event within {:.0} ms and {} px): shot noise, which fires OFF as often as ON at every pixel, is below {most:.4} Hz (95 %), under the {relevant_hz} Hz that matters; the model's missing isolated events are another effect's (leak fires ON only; a photoreceptor lagging the scene, or thresholds off at sparse edges, leave scene events no neighbour supports)",
            quiet.rate_hz,
            quiet.pixel_seconds,
            quiet.support_window_ms,
            quiet.support_radius_px
        )
    })
}

/// The dark shot-noise rate (the simulator's `shot_noise_rate_hz`) the quiet OFF count
/// gives, 95 %: its exact interval over the OFF share and the brightness factor's range
/// (the quiet pixels' own brightness unknown within the frames'). `None` where the count
/// is an upper bound only (it may hold the scene's slow events) or the frames give no
/// brightness.
pub(crate) fn direct_dark_rate(
    quiet: &QuietOff,
    geometry: &Geometry,
    model: &PixelParams,
) -> Option<[f64; 2]> {
    if quiet.upper_bound {
        return None;
    }
    let [f_lo, f_hi] = factor_range(geometry, model)?;
    let (lo, hi) = off_rate95(quiet);
    Some([lo / OFF_SHARE / f_hi, hi / OFF_SHARE / f_lo])
}

/// Widens the fitted shot-noise rate's interval to hold [`direct_dark_rate`], where they
/// differ; the note says both.
pub(crate) fn widen(
    uncertainty: &mut BTreeMap<String, Uncertain>,
    quiet: Option<QuietOff>,
    geometry: &Geometry,
    model: &PixelParams,
) -> Option<String> {
    let quiet = quiet?;
    model.shot_noise_rate_hz?;
    let u = uncertainty.get_mut("shot_noise_rate_hz")?;
    let [lo, hi] = direct_dark_rate(&quiet, geometry, model)?;
    let [search_lo, search_hi] = u.ci95.unwrap_or([Some(u.value), Some(u.value)]);
    let widened = [search_lo.map(|s| s.min(lo)), search_hi.map(|s| s.max(hi))];
    if Some(widened) == u.ci95 {
        return None;
    }
    let said = |i: Interval| {
        let side = |v: Option<f64>| v.map_or("open".to_string(), |v| format!("{v:.4}"));
        format!("{} to {}", side(i[0]), side(i[1]))
    };
    let note = format!(
        "shot_noise_rate_hz: its interval holds the dark rate the recording's quiet pixels give ({lo:.4} to {hi:.4} Hz: {:.4} isolated OFF events per pixel-second over {:.0} pixel-s without a neighbour event within {:.0} ms and {} px, exact Poisson 95 %, half the noise OFF, over the brightness factors of the frames' intensities), beside the simulation search's {} Hz: the search reads every isolated event the model lacks as noise, and where another effect leaves such events (a lagging photoreceptor, leak) it does not hold the truth (coverage draw 8007: 4.05 [3.68, 4.27] for 2.78)",
        quiet.rate_hz,
        quiet.pixel_seconds,
        quiet.support_window_ms,
        quiet.support_radius_px,
        said(u.ci95.unwrap_or([None, None]))
    );
    u.ci95 = Some(widened);
    Some(note)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::events::EventChunk;
    use crate::fit::effects::fixture::{Fixture, static_frames};

    fn quiet(rate_hz: f64, se_hz: f64, upper_bound: bool) -> QuietOff {
        QuietOff {
            rate_hz,
            se_hz,
            pixel_seconds: 1000.0,
            support_window_ms: 30.0,
            support_radius_px: 1,
            upper_bound,
        }
    }

    /// A static scene at 15 DN: one intensity bin, centred at sqrt(10 x 20) = 14.14 DN,
    /// brightness factor 1 - 0.75 x 34.14 / 275 = 0.90689.
    fn dim() -> Fixture {
        let none = EventChunk::default();
        Fixture::new(&static_frames(16, 12, 2.0, 15.0), &none, &none)
    }

    /// Hand-computed on draw 8007's numbers: 1,264 quiet OFF events in 1,000 pixel-s,
    /// Garwood's 95 % interval [1194.9, 1335.9] (chi2(0.025; 2528) / 2, chi2(0.975; 2530) / 2),
    /// half the noise OFF: 1.1949 / 0.5 / 0.90689 = 2.6352 to 1.3359 / 0.5 / 0.90689 = 2.9461;
    /// the search's [3.68, 4.27] widened to [2.6352, 4.27], which holds the true 2.78.
    #[test]
    fn the_quiet_count_widens_the_searched_rate_to_the_dark_rate_it_gives() {
        let f = dim();
        let mut model = PixelParams::ideal(0.6121, 0.8469);
        model.shot_noise_rate_hz = Some(4.05);
        let [lo, hi] = direct_dark_rate(&quiet(1.264, 0.0355, false), &f.geometry, &model).unwrap();
        assert!(
            (lo - 2.6352).abs() < 2e-3 && (hi - 2.9461).abs() < 2e-3,
            "{lo} {hi}"
        );
        let mut u = BTreeMap::from([(
            "shot_noise_rate_hz".to_string(),
            Uncertain::with_interval(4.05, None, [Some(3.68), Some(4.27)]),
        )]);
        let note = widen(
            &mut u,
            Some(quiet(1.264, 0.0355, false)),
            &f.geometry,
            &model,
        );
        assert!(note.unwrap().contains("3.6800 to 4.2700"));
        let ci = u["shot_noise_rate_hz"].ci95.unwrap();
        assert!(
            (ci[0].unwrap() - 2.6352).abs() < 2e-3 && ci[1] == Some(4.27),
            "{ci:?}"
        );
        // an upper bound says nothing of the dark rate: no widening (the oracle
        // c_noisy_static's [0.90, 1.12] was widened to [0, 1.60] by one)
        assert!(direct_dark_rate(&quiet(1.264, 0.0355, true), &f.geometry, &model).is_none());
        // within the search's interval: nothing to widen
        let mut inside = BTreeMap::from([(
            "shot_noise_rate_hz".to_string(),
            Uncertain::with_interval(3.0, None, [Some(2.0), Some(4.0)]),
        )]);
        assert!(
            widen(
                &mut inside,
                Some(quiet(1.264, 0.0355, false)),
                &f.geometry,
                &model
            )
            .is_none()
        );
    }

    /// No isolated OFF event in 7,546 quiet pixel-seconds (draw 8027): at most
    /// chi2(0.975; 2) / 2 / 7546 / 0.5 = 3.6889 / 7546 / 0.5 = 0.00098 Hz of shot noise,
    /// under the 0.005 that matters; zero in 1,000 pixel-s allows 0.0074 and is not ruled out
    /// (two expected events show none 13.5 % of the time).
    #[test]
    fn no_quiet_off_event_rules_shot_noise_out() {
        let f = dim();
        let mut c = f.context();
        let none = QuietOff {
            pixel_seconds: 7546.0,
            ..quiet(0.0, 1.0 / 7546.0, false)
        };
        c.quiet_off = Some(none);
        let most = most_observed_hz(&c, &none).unwrap();
        assert!((most - 0.000978).abs() < 1e-5, "{most}");
        assert!(rules_out(&c, 0.005).unwrap().contains("7546 pixel-s"));
        c.quiet_off = Some(quiet(0.0, 0.001, false));
        assert!(rules_out(&c, 0.005).is_none());
        c.quiet_off = None;
        assert!(rules_out(&c, 0.005).is_none());
    }
}
