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
//! - shot noise is not tried, and takes no other effect's place, where the quiet OFF count
//!   bounds it below the rate that matters ([`rules_out`]);
//! - it is called for where the count's lower end exceeds what the model makes there by a
//!   rate that matters ([`finds`]), at 5 standard errors as every effect;
//! - every search of its rate stays within the dark rate the count gives, and the fitted
//!   rate's interval is that interval ([`searched_range`], [`direct_dark_rate`],
//!   [`take_count_interval`]): on draw 8007 (2.78 Hz) the search's 4.05 [3.68, 4.27]
//!   beside the count's [2.60, 3.00];
//! - the same count on the selection blocks is its signature for the keep rule
//!   ([`signature`]).
//!
//! The count holds the scene's own events where low thresholds fire isolated events at
//! uncovered pixels, so the same count on the ideal model's events (no shot noise) comes off
//! its lower end ([`noise_rate95`], [`crate::fit::events_only::SceneFloor`]).
//!
//! The count is read through the simulator's noise model (v2e's): the brightness factor
//! `1 - 0.75 (DN + 20) / 275` over the range of the frames' intensity bins, and each
//! polarity's rate scaled by its nominal threshold over the pixel's ([`off_share`]).

use crate::estimate::Interval;
use crate::fit::Uncertain;
use crate::fit::effects::{Context, Effect, Evidence};
use crate::fit::events_only::QuietOff;
use crate::fit::observe::{Geometry, INTENSITY_BINS, INTENSITY_EDGES, Subset};
use crate::sim::PixelParams;
use crate::sim::effects::mismatch::MIN_THRESHOLD;
use crate::sim::effects::shot_noise::brightness_factor;
use crate::stats::binomial::poisson95;
use std::collections::BTreeMap;

/// The share of shot noise the simulator fires OFF, averaged over its pixels: each
/// polarity's rate goes as its nominal threshold over the pixel's
/// ([`crate::sim::effects::shot_noise::pixel_rates`], as v2e), so a nominal pixel fires OFF
/// half the time whatever Cp and Cn are, and under threshold mismatch (`theta ~ N(Cn,
/// sigma)`, at least [`MIN_THRESHOLD`]) the mean OFF rate is `E[Cn / theta]` times that
/// (1.032 at a spread of 17 % of Cn, 1.42 at 37 %): a midpoint sum over the normal, 16,000
/// steps over 8 standard deviations either side.
pub(crate) fn off_share(model: &PixelParams) -> f64 {
    let (ct, sigma) = (model.ct_off, model.ct_sigma.unwrap_or(0.0));
    if !(sigma > 0.0 && ct > 0.0) {
        return 0.5;
    }
    const STEPS: usize = 16_000;
    let dz = 16.0 / STEPS as f64;
    let (mut sum, mut weights) = (0.0, 0.0);
    for k in 0..STEPS {
        let z = -8.0 + (k as f64 + 0.5) * dz;
        let w = (-0.5 * z * z).exp();
        sum += w * ct / (ct + sigma * z).max(MIN_THRESHOLD as f64);
        weights += w;
    }
    0.5 * sum / weights
}

/// The smallest and largest brightness factor (observed over dark rate) of the intensity
/// bins with pixel time on `subset`, at the bins' edges: the quiet pixels' own brightness
/// lies within.
fn factor_range(geometry: &Geometry, model: &PixelParams, subset: Subset) -> Option<[f64; 2]> {
    let bright = model.shot_noise_bright_factor() as f32;
    let factors: Vec<f64> = (0..INTENSITY_BINS)
        .filter(|&b| geometry.exposure_of(b, subset) > 0.0)
        .flat_map(|b| {
            let lower = b.checked_sub(1).map_or(0.0, |e| INTENSITY_EDGES[e]);
            let upper = INTENSITY_EDGES.get(b).copied().unwrap_or(255.0);
            [lower, upper].map(|dn| brightness_factor(dn, bright) as f64)
        })
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

/// The quiet OFF rate the scene itself makes, as the model without shot noise makes it
/// ([`QuietOff::scene`]): its point rate and the upper end of its exact 95 % interval,
/// events per pixel-second (none where not simulated).
fn scene_rate(quiet: &QuietOff) -> (f64, f64) {
    quiet.scene.map_or((0.0, 0.0), |s| {
        let (_, hi) = poisson95(s.events as usize);
        (s.events as f64 / s.pixel_seconds, hi / s.pixel_seconds)
    })
}

/// [`off_rate95`] with the scene's own quiet OFF events taken from its lower end (at their
/// most, [`scene_rate`]): the count's lower end is noise only beyond what the scene makes
/// there. Thresholds low enough for a scene's slow changes to fire isolated events at
/// pixels their neighbours leave uncovered put scene events in the count (coverage draws
/// 9021 and 7009, 0.12 / 0.21 and 0.57 / 0.13: 0.18 [0.13, 0.29] and 0.50 [0.38, 0.67] Hz
/// for 0.093 and 0.26). The upper end is left as it is: the scene only adds to the count,
/// and a model that makes more scene events than the recording must not rule noise out.
fn noise_rate95(quiet: &QuietOff) -> (f64, f64) {
    let (lo, hi) = off_rate95(quiet);
    ((lo - scene_rate(quiet).1).max(0.0), hi)
}

/// The scene floor in words, for the evidence and the interval's note.
fn scene_said(quiet: &QuietOff) -> String {
    quiet.scene.map_or(String::new(), |s| {
        format!(
            ", of which the scene itself makes {:.4} as the model without shot noise makes it ({} events in {:.0} pixel-s; at most {:.4}, taken from the count's lower end)",
            s.events as f64 / s.pixel_seconds,
            s.events,
            s.pixel_seconds,
            scene_rate(quiet).1
        )
    })
}

/// The most shot noise (ON + OFF events per pixel-second, averaged over the recording's
/// brightness) the quiet OFF count allows: the upper end of its exact 95 % interval over
/// the OFF share, times how much brighter the quiet pixels may be than the rest.
pub(crate) fn most_observed_hz(c: &Context, quiet: &QuietOff) -> Option<f64> {
    let [lo, hi] = factor_range(c.geometry, c.model, c.subset)?;
    Some(off_rate95(quiet).1 / off_share(c.model) * hi / lo)
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

/// Shot noise the quiet OFF count finds beyond the model's: its strength, the least excess
/// it allows and where a search starts.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Found {
    /// The count's excess over the most the model's shot noise makes there, over the
    /// count's Poisson standard error.
    pub z: f64,
    /// The least observed shot noise beyond the model's (ON + OFF events per
    /// pixel-second over the recording's brightness) the count allows: the lower end of
    /// its exact 95 % interval over the OFF share, less the model's rate at the brightest
    /// factor, times the smallest-to-largest brightness-factor ratio.
    pub least_hz: f64,
    /// The dark rate the count gives at the geometric mean of the brightness factors.
    pub start_hz: f64,
    pub text: String,
}

/// Shot noise called for by the quiet pixels: more than the model has, by a rate that
/// matters even at the count's lower 95 % end, where the count is noise (not an upper bound
/// that may hold the scene's slow events). The simulation's evidence
/// ([`super::shot_noise::evidence`]) compares the isolated events of all pixels, where a
/// busy scene covers most noise events and the model's own isolated events (the frames'
/// read noise simulated as change) offset the rest; and the distance, of which noise is one
/// component of seven, moves by less than its block-to-block chance: coverage draws 7033,
/// 8014 and 9030 (2.09, 0.53 and 0.14 Hz of shot noise) tried it and did not keep it.
pub(crate) fn finds(c: &Context, relevant_hz: f64) -> Option<Found> {
    let quiet = c.quiet_off?;
    if quiet.upper_bound {
        return None;
    }
    let [f_lo, f_hi] = factor_range(c.geometry, c.model, c.subset)?;
    let share = off_share(c.model);
    let model_hz = c.model.shot_noise_rate_hz.unwrap_or(0.0).max(0.0);
    let n = (quiet.rate_hz * quiet.pixel_seconds).round().max(0.0);
    // the most isolated OFF events the model's own shot noise makes at the quiet pixels,
    // beside those the scene makes there
    let scene = scene_rate(&quiet).0 * quiet.pixel_seconds;
    let expected = model_hz * f_hi * share * quiet.pixel_seconds + scene;
    let (lo, hi) = noise_rate95(&quiet);
    let least_hz = (lo / share - model_hz * f_hi) * f_lo / f_hi;
    let beyond = if model_hz > 0.0 {
        format!(" beyond the model's {model_hz:.4} Hz")
    } else {
        " where the model has none".to_string()
    };
    let dark = [lo / share / f_hi, hi / share / f_lo];
    (least_hz > relevant_hz).then(|| Found {
        z: (n - expected) / (n + scene + 1.0).sqrt(),
        least_hz,
        start_hz: (quiet.rate_hz - scene_rate(&quiet).0).max(lo) / share / (f_lo * f_hi).sqrt(),
        text: format!(
            "the recording's quiet pixels hold {:.4} isolated OFF events per pixel-second ({n:.0} in {:.0} pixel-s without a neighbour event within {:.0} ms and {} px; a wider support does not lower it){}: shot noise, which fires OFF as often as ON at every pixel, of at least {least_hz:.4} Hz (95 %){beyond}, a dark rate of {:.4} to {:.4} Hz",
            quiet.rate_hz,
            quiet.pixel_seconds,
            quiet.support_window_ms,
            quiet.support_radius_px,
            scene_said(&quiet),
            dark[0],
            dark[1]
        ),
    })
}

/// The range a shot-noise search covers: `range` within the dark rate the quiet count
/// gives ([`direct_dark_rate`]), or that rate's interval where the two do not meet;
/// `None` where the count gives none. The count measures the noise directly; the search's
/// distance also reads other effects' misses as noise (coverage draw 8014: the count
/// gives 0.46-0.66 Hz, a search over the effect's own range 0.18, for 0.53 true).
pub(crate) fn searched_range(
    range: (f64, f64),
    quiet: Option<QuietOff>,
    geometry: &Geometry,
    model: &PixelParams,
) -> Option<(f64, f64)> {
    let [lo, hi] = direct_dark_rate(&quiet?, geometry, model)?;
    if hi.is_nan() || lo.is_nan() || hi <= lo {
        return None;
    }
    // no quiet OFF event: the count bounds the rate from above only
    let within = (range.0.max(lo), range.1.min(hi));
    Some(if within.0 < within.1 {
        within
    } else {
        (lo.max(hi * 1e-3), hi)
    })
}

/// Shot noise's own signature ([`crate::fit::effects::Effect::judged_by_signature`]): what
/// the quiet OFF count says of it beside the model, and nothing else (the isolated events
/// of all pixels are also the misses of other effects). Calls for it where the count
/// [`finds`] more than the model has; not where it [`rules_out`] any that matters or where
/// there is no count of noise alone.
pub(crate) fn signature(c: &Context, relevant_hz: f64) -> Evidence {
    if let Some(why) = rules_out(c, relevant_hz) {
        return Evidence::none(Effect::ShotNoise, why);
    }
    if let Some(found) = finds(c, relevant_hz) {
        return Evidence {
            effect: Effect::ShotNoise,
            score: found.z,
            relevant: true,
            text: found.text,
            other_start: None,
            start: Some(found.start_hz),
        };
    }
    let why = match c.quiet_off {
        None => "no count of isolated OFF events at quiet pixels (too few events)".to_string(),
        Some(q) if q.upper_bound => format!(
            "the quiet pixels' {:.4} isolated OFF events per pixel-second may hold the scene's slow events (a wider support could not check them): an upper bound, not a measure of noise",
            q.rate_hz
        ),
        Some(q) => format!(
            "the quiet pixels' {:.4} isolated OFF events per pixel-second ({:.0} pixel-s) hold no shot noise beyond the model's {:.4} Hz that matters",
            q.rate_hz,
            q.pixel_seconds,
            c.model.shot_noise_rate_hz.unwrap_or(0.0)
        ),
    };
    Evidence::none(Effect::ShotNoise, why)
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
    let [f_lo, f_hi] = factor_range(geometry, model, Subset::Fit)?;
    let (lo, hi) = noise_rate95(quiet);
    let share = off_share(model);
    Some([lo / share / f_hi, hi / share / f_lo])
}

/// The most dark shot-noise rate the quiet OFF count allows, 95 %: the upper end of its
/// exact interval over the OFF share and the smallest brightness factor of the frames'
/// intensities. Holds for a count that is only an upper bound too (the scene's slow events
/// only add to it).
pub(crate) fn at_most_dark_hz(
    quiet: Option<QuietOff>,
    geometry: &Geometry,
    model: &PixelParams,
) -> Option<f64> {
    let quiet = quiet?;
    let [f_lo, _] = factor_range(geometry, model, Subset::Fit)?;
    Some(off_rate95(&quiet).1 / off_share(model) / f_lo)
}

/// Gives the fitted shot-noise rate the interval of the dark rate the quiet count gives
/// ([`direct_dark_rate`]), within which it was searched ([`searched_range`]): the count
/// measures the noise directly, while the search's own interval is read off how the
/// distance moves, which other effects' misses move too (coverage draw 9030: [0.008,
/// 12.6] Hz beside the count's, for 0.137). The note says both.
pub(crate) fn take_count_interval(
    uncertainty: &mut BTreeMap<String, Uncertain>,
    quiet: Option<QuietOff>,
    geometry: &Geometry,
    model: &PixelParams,
) -> Option<String> {
    let quiet = quiet?;
    model.shot_noise_rate_hz?;
    let u = uncertainty.get_mut("shot_noise_rate_hz")?;
    let [lo, hi] = direct_dark_rate(&quiet, geometry, model)?;
    let counted = [Some(lo.min(u.value)), Some(hi.max(u.value))];
    let said = |i: Interval| {
        let side = |v: Option<f64>| v.map_or("open".to_string(), |v| format!("{v:.4}"));
        format!("{} to {}", side(i[0]), side(i[1]))
    };
    let note = format!(
        "shot_noise_rate_hz: its interval is the dark rate the recording's quiet pixels give ({lo:.4} to {hi:.4} Hz: {:.4} isolated OFF events per pixel-second over {:.0} pixel-s without a neighbour event within {:.0} ms and {} px{}, exact Poisson 95 %, OFF share {:.4} under the model's threshold mismatch, over the brightness factors at the edges of the frames' intensity bins), within which it was searched; the search's own interval, from how the distance moves, was {} Hz: the distance reads every isolated event the model lacks as noise, where another effect (a lagging photoreceptor, leak) leaves such events too",
        quiet.rate_hz,
        quiet.pixel_seconds,
        quiet.support_window_ms,
        quiet.support_radius_px,
        scene_said(&quiet),
        off_share(model),
        said(u.ci95.unwrap_or([None, None]))
    );
    u.ci95 = Some(counted);
    u.standard_error = None;
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
            ..Default::default()
        }
    }

    /// A static scene at 15 DN: one intensity bin, 10 to 20 DN, brightness factors
    /// 1 - 0.75 x 30 / 275 = 0.918182 and 1 - 0.75 x 40 / 275 = 0.890909 at its edges.
    fn dim() -> Fixture {
        let none = EventChunk::default();
        Fixture::new(&static_frames(16, 12, 2.0, 15.0), &none, &none)
    }

    /// Hand-computed on draw 8007's numbers: 1,264 quiet OFF events in 1,000 pixel-s,
    /// Garwood's 95 % interval [1195.27, 1335.65] (chi2(0.025; 2528) / 2, chi2(0.975; 2530)
    /// / 2), half the noise OFF: 1.19527 / 0.5 / 0.918182 = 2.6036 to 1.33565 / 0.5 /
    /// 0.890909 = 2.9984; the search's [3.68, 4.27] (at 4.05) gives way to [2.6036, 4.05],
    /// which holds the true 2.78.
    #[test]
    fn the_searched_rate_takes_the_dark_rate_the_quiet_count_gives() {
        let f = dim();
        let mut model = PixelParams::ideal(0.6121, 0.8469);
        model.shot_noise_rate_hz = Some(4.05);
        let [lo, hi] = direct_dark_rate(&quiet(1.264, 0.0355, false), &f.geometry, &model).unwrap();
        assert!(
            (lo - 2.6036).abs() < 2e-4 && (hi - 2.9984).abs() < 2e-4,
            "{lo} {hi}"
        );
        let mut u = BTreeMap::from([(
            "shot_noise_rate_hz".to_string(),
            Uncertain::with_interval(4.05, None, [Some(3.68), Some(4.27)]),
        )]);
        let note = take_count_interval(
            &mut u,
            Some(quiet(1.264, 0.0355, false)),
            &f.geometry,
            &model,
        );
        assert!(note.unwrap().contains("was 3.6800 to 4.2700 Hz"));
        let ci = u["shot_noise_rate_hz"].ci95.unwrap();
        assert!(
            (ci[0].unwrap() - 2.6036).abs() < 2e-4 && ci[1] == Some(4.05),
            "{ci:?}"
        );
        assert_eq!(u["shot_noise_rate_hz"].standard_error, None);
        // an upper bound says nothing of the dark rate: no widening (the oracle
        // c_noisy_static's [0.90, 1.12] was widened to [0, 1.60] by one)
        assert!(direct_dark_rate(&quiet(1.264, 0.0355, true), &f.geometry, &model).is_none());
        // the count's interval already: kept, and still said
        let mut inside = BTreeMap::from([(
            "shot_noise_rate_hz".to_string(),
            Uncertain::with_interval(2.8, None, [Some(lo), Some(hi)]),
        )]);
        assert!(
            take_count_interval(
                &mut inside,
                Some(quiet(1.264, 0.0355, false)),
                &f.geometry,
                &model
            )
            .is_some()
        );
        assert_eq!(
            inside["shot_noise_rate_hz"].ci95,
            Some([Some(lo), Some(hi)])
        );
    }

    /// Draw 8007's count beside a scene that itself makes 100 isolated OFF events in 2,000
    /// quiet pixel-s (as a model without shot noise makes them): their Garwood upper end,
    /// 121.6268 (mpmath), is 0.060813 Hz taken from the count's lower end, 1.195270 - 0.060813
    /// = 1.134457, a dark rate of 2.47109 Hz; the upper end stays 2.9984. The count calls
    /// for shot noise with the scene's 0.05 Hz in what the model makes: (1264 - 50) /
    /// sqrt(1264 + 50 + 1) = 33.48 standard errors.
    #[test]
    fn the_scene_s_own_quiet_events_come_off_the_count_s_lower_end() {
        let f = dim();
        let model = PixelParams::ideal(0.6121, 0.8469);
        let floor = QuietOff {
            scene: Some(crate::fit::events_only::SceneFloor {
                events: 100,
                pixel_seconds: 2000.0,
            }),
            ..quiet(1.264, 0.0355, false)
        };
        let [lo, hi] = direct_dark_rate(&floor, &f.geometry, &model).unwrap();
        assert!(
            (lo - 2.47109).abs() < 2e-4 && (hi - 2.9984).abs() < 2e-4,
            "{lo} {hi}"
        );
        let mut c = f.context();
        c.model = &model;
        c.quiet_off = Some(floor);
        let found = finds(&c, 0.005).unwrap();
        assert!(
            (found.z - 1214.0 / 1315f64.sqrt()).abs() < 1e-9,
            "{found:?}"
        );
        assert!(
            found.text.contains("the scene itself makes 0.0500"),
            "{found:?}"
        );
    }

    /// No isolated OFF event in 7,546 quiet pixel-seconds (draw 8027): at most
    /// chi2(0.975; 2) / 2 / 7546 / 0.5 x 0.918182 / 0.890909 = 0.0010076 Hz of shot noise,
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
        assert!((most - 0.0010076).abs() < 1e-6, "{most}");
        assert!(rules_out(&c, 0.005).unwrap().contains("7546 pixel-s"));
        c.quiet_off = Some(quiet(0.0, 0.001, false));
        assert!(rules_out(&c, 0.005).is_none());
        c.quiet_off = None;
        assert!(rules_out(&c, 0.005).is_none());
    }

    /// 100 isolated OFF events in 1,000 quiet pixel-s at 10-20 DN: Garwood's lower end
    /// 81.364, so at least 0.081364 / 0.5 x 0.890909 / 0.918182 = 0.157894 Hz of observed
    /// shot noise where the model has none, z = 100 / sqrt(101) = 9.950, the search started
    /// at 0.1 / 0.5 / sqrt(0.918182 x 0.890909) = 0.221131 Hz. Beside a model with 0.1 Hz
    /// (at most 45.909 of the events), at least (0.162728 - 0.091818) x 0.970297 = 0.068804
    /// Hz more, z = 54.091 / sqrt(101) = 5.3822; beside 0.2 Hz nothing that matters is left,
    /// and the signature says so.
    #[test]
    fn quiet_off_events_call_for_shot_noise_beyond_the_model_s() {
        let f = dim();
        let mut c = f.context();
        c.quiet_off = Some(quiet(0.1, 0.01, false));
        let found = finds(&c, 0.005).unwrap();
        assert!((found.least_hz - 0.157894).abs() < 1e-5, "{found:?}");
        assert!((found.z - 9.950).abs() < 1e-3, "{found:?}");
        assert!((found.start_hz - 0.221131).abs() < 1e-5, "{found:?}");
        assert!(signature(&c, 0.005).calls_for());
        let mut model = PixelParams::ideal(0.3, 0.3);
        model.shot_noise_rate_hz = Some(0.1);
        c.model = &model;
        let found = finds(&c, 0.005).unwrap();
        assert!((found.least_hz - 0.068804).abs() < 1e-5, "{found:?}");
        assert!((found.z - 5.3822).abs() < 1e-3, "{found:?}");
        assert!(
            found.text.contains("beyond the model's 0.1000 Hz"),
            "{found:?}"
        );
        let mut more = model.clone();
        more.shot_noise_rate_hz = Some(0.2);
        c.model = &more;
        assert!(finds(&c, 0.005).is_none());
        let s = signature(&c, 0.005);
        assert!(
            !s.calls_for() && s.text.contains("beyond the model's 0.2000 Hz"),
            "{s:?}"
        );
        // an upper bound may hold the scene's slow events: it calls for nothing
        c.model = &f.model;
        c.quiet_off = Some(quiet(0.1, 0.01, true));
        assert!(finds(&c, 0.005).is_none());
        assert!(signature(&c, 0.005).text.contains("upper bound"));
    }

    /// The search stays within the count's dark rate, 2.6036 to 2.9984 Hz (draw 8007's
    /// count, as above): a range reaching into it is cut to it, one that misses it gives
    /// way to it, and an upper bound leaves the range as it is.
    #[test]
    fn shot_noise_is_searched_within_the_dark_rate_the_count_gives() {
        let f = dim();
        let model = PixelParams::ideal(0.6121, 0.8469);
        let count = Some(quiet(1.264, 0.0355, false));
        let (lo, hi) = searched_range((2.0, 2.8), count, &f.geometry, &model).unwrap();
        assert!((lo - 2.6036).abs() < 2e-4 && hi == 2.8, "{lo} {hi}");
        let (lo, hi) = searched_range((0.05, 1.25), count, &f.geometry, &model).unwrap();
        assert!(
            (lo - 2.6036).abs() < 2e-4 && (hi - 2.9984).abs() < 2e-4,
            "{lo} {hi}"
        );
        let bound = Some(quiet(1.264, 0.0355, true));
        assert_eq!(
            searched_range((0.05, 1.25), bound, &f.geometry, &model),
            None
        );
        // the most the count allows holds for an upper bound too: 2.9984
        let most = at_most_dark_hz(bound, &f.geometry, &model).unwrap();
        assert!((most - 2.9984).abs() < 2e-4, "{most}");
    }

    /// The simulator's OFF share under threshold mismatch, against a sum by hand over the
    /// normal (numpy, 16,000 steps): Cn 0.3 with sigma 0.051 fires OFF 1.03187 times as often
    /// as nominal pixels, Cn 0.4 with sigma 0.148 1.41755 times (the clamp at 0.01 holding
    /// the tail); none without mismatch.
    #[test]
    fn mismatch_raises_the_share_of_noise_fired_off() {
        let mut model = PixelParams::ideal(0.3, 0.3);
        assert_eq!(off_share(&model), 0.5);
        model.ct_sigma = Some(0.051);
        assert!(
            (off_share(&model) / 0.5 - 1.031871).abs() < 1e-4,
            "{}",
            off_share(&model)
        );
        let mut wide = PixelParams::ideal(0.4, 0.4);
        wide.ct_sigma = Some(0.148);
        assert!(
            (off_share(&wide) / 0.5 - 1.417547).abs() < 1e-3,
            "{}",
            off_share(&wide)
        );
    }
}
