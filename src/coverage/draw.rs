//! Drawing a random case from a seed ([`CaseSpec::draw`]): the ranges of the study.
//!
//! Every recording is 96x72 to 240x180 pixels and 0.4-1.5 s long, so that a case costs
//! seconds. Thresholds `ct_on`, `ct_off` are drawn independently in 0.1-0.9 (asymmetry
//! included), the mismatch `ct_sigma` in 0-0.08, and each effect is present with probability
//! [`EFFECT_PROBABILITY`] at a log-uniform strength. Scene brightness is log-uniform in
//! 8-200 DN, speed in 10-600 px/s; on-screen cases draw the display.

use super::case::{CaseSpec, Generator, RecordingSpec, SceneFamily};
use super::draw_peer::draw_peer;
use super::draw_scene::{Look, draw_scene};
use crate::sim::scene::stimulus::StimulusSpec;
use crate::sim::{DisplayParams, LogResponse, PixelParams};
use rand::{Rng, RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Chance that each effect (bandwidth, leak, shot noise, refractory period, hot pixels,
/// timestamp jitter, the `eps` log response) is present in a case.
pub const EFFECT_PROBABILITY: f64 = 0.4;

/// Sensor sizes drawn from (4:3, small enough to be quick).
pub const SENSOR_SIZES: [(usize, usize); 5] =
    [(96, 72), (128, 96), (160, 120), (192, 144), (240, 180)];

/// Relative frequency of each scene family.
const FAMILY_WEIGHTS: [(SceneFamily, f64); 7] = [
    (SceneFamily::Texture, 0.22),
    (SceneFamily::Rotation, 0.12),
    (SceneFamily::NaturalImage, 0.14),
    (SceneFamily::Checkerboard, 0.10),
    (SceneFamily::MultiObject, 0.12),
    (SceneFamily::MultiObjectNatural, 0.10),
    (SceneFamily::Screen, 0.20),
];

pub(super) fn uniform(rng: &mut impl Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

pub(super) fn log_uniform(rng: &mut impl Rng, lo: f64, hi: f64) -> f64 {
    uniform(rng, lo.ln(), hi.ln()).exp()
}

fn chance(rng: &mut impl Rng, p: f64) -> bool {
    rng.random::<f64>() < p
}

/// With probability [`EFFECT_PROBABILITY`], a log-uniform strength in `lo..hi`.
fn maybe(rng: &mut impl Rng, lo: f64, hi: f64) -> Option<f64> {
    chance(rng, EFFECT_PROBABILITY).then(|| log_uniform(rng, lo, hi))
}

fn draw_family(rng: &mut impl Rng) -> SceneFamily {
    let total: f64 = FAMILY_WEIGHTS.iter().map(|(_, w)| w).sum();
    let mut pick = uniform(rng, 0.0, total);
    for (family, weight) in FAMILY_WEIGHTS {
        if pick < weight {
            return family;
        }
        pick -= weight;
    }
    SceneFamily::Texture
}

/// Thresholds, mismatch and every effect at a random strength.
pub fn draw_params(rng: &mut impl Rng, seed: u64) -> PixelParams {
    let mut p = PixelParams::ideal(uniform(rng, 0.1, 0.9), uniform(rng, 0.1, 0.9));
    p.ct_sigma = Some(uniform(rng, 0.0, 0.08));
    p.seed = Some(seed);
    p.cutoff_hz = maybe(rng, 5.0, 500.0);
    p.leak_rate_hz = maybe(rng, 0.01, 1.0);
    p.shot_noise_rate_hz = maybe(rng, 0.05, 3.0);
    p.refractory_s = maybe(rng, 1e-4, 5e-3);
    if let Some(fraction) = maybe(rng, 2e-4, 2e-3) {
        p.hot_pixel_fraction = Some(fraction);
        p.hot_pixel_rate_hz = Some(log_uniform(rng, 5.0, 100.0));
    }
    p.timestamp_jitter_s = maybe(rng, 1e-5, 1e-3);
    if let Some(eps) = maybe(rng, 1e-3, 3e-2) {
        p.log_response = Some(LogResponse::Eps);
        p.log_eps = Some(eps);
    }
    p
}

/// A display: gamma 1.8-2.6, black level 0.001-0.05, refresh 60-144 Hz, blur 0-1.5 px,
/// white set so that the grey background is about `brightness_dn`.
pub fn draw_display(rng: &mut impl Rng, brightness_dn: f64) -> DisplayParams {
    DisplayParams {
        refresh_hz: uniform(rng, 60.0, 144.0).round(),
        gamma: uniform(rng, 1.8, 2.6),
        black_level: log_uniform(rng, 0.001, 0.05),
        white_dn: (brightness_dn * 4.5).clamp(20.0, 255.0),
        blur_px: Some(uniform(rng, 0.0, 1.5)),
        time_offset_s: None,
    }
}

/// The calibration checkerboard (as `ctcal calib checkerboard` makes it) for this screen.
fn draw_stimulus(rng: &mut impl Rng, look: &Look, refresh_hz: f64) -> StimulusSpec {
    let square_px = uniform(rng, 6.0, 20.0).round();
    let fit = |side: usize, most: usize| {
        ((0.8 * side as f64 / square_px).floor() as usize).clamp(2, most)
    };
    StimulusSpec {
        width: look.width,
        height: look.height,
        refresh_hz,
        duration_s: look.duration_s,
        square_px,
        squares: [fit(look.width, 8), fit(look.height, 6)],
        speed_px_s: look.speed_px_s,
    }
}

/// Mixed into a case's seed for the stream that chooses its generator and draws a peer's
/// parameters.
const GENERATOR_STREAM: u64 = 0x9e37_79b9_7f4a_7c15;

/// Significant digits a drawn number keeps.
const DIGITS: usize = 6;

/// Every number of `value` to [`DIGITS`] significant digits.
fn round_numbers(value: &mut serde_json::Value) {
    use serde_json::Value;
    match value {
        Value::Number(n) if n.is_f64() => {
            let x = n.as_f64().expect("a float");
            let rounded: f64 = format!("{x:.prec$e}", prec = DIGITS - 1)
                .parse()
                .expect("a float prints as one");
            *value = serde_json::json!(rounded);
        }
        Value::Array(items) => items.iter_mut().for_each(round_numbers),
        Value::Object(map) => map.values_mut().for_each(round_numbers),
        _ => {}
    }
}

/// The case with every number short, so that its JSON (read without serde_json's
/// `float_roundtrip`) gives back exactly the same case.
fn tidy(case: CaseSpec) -> CaseSpec {
    let mut value = serde_json::to_value(&case).expect("cases serialise");
    round_numbers(&mut value);
    serde_json::from_value(value).expect("a rounded case is a case")
}

impl CaseSpec {
    /// Draws one random recording; the same seed gives the same case, and so does its JSON.
    pub fn draw(seed: u64) -> CaseSpec {
        tidy(Self::draw_exact(seed))
    }

    /// Draws the case of `seed` made by one of `generators`, chosen at random. The scene,
    /// thresholds and effects are those of [`CaseSpec::draw`] (the generator and the peer's
    /// own parameters come from streams of their own), so `[Generator::Ctcal]` gives exactly
    /// [`CaseSpec::draw`]'s case.
    pub fn draw_from(seed: u64, generators: &[Generator]) -> CaseSpec {
        let mut case = Self::draw_exact(seed);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ GENERATOR_STREAM);
        let generator = match generators {
            [] => Generator::Ctcal,
            [only] => *only,
            _ => generators[rng.random_range(0..generators.len())],
        };
        if let Some((peer, params)) = draw_peer(&mut rng, generator, &case.params) {
            case.generator = generator;
            case.peer = Some(peer);
            case.params = params;
        }
        tidy(case)
    }

    fn draw_exact(seed: u64) -> CaseSpec {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let family = draw_family(&mut rng);
        let (width, height) = SENSOR_SIZES[rng.random_range(0..SENSOR_SIZES.len())];
        let look = Look {
            width,
            height,
            duration_s: (uniform(&mut rng, 0.4, 1.5) * 100.0).round() / 100.0,
            speed_px_s: log_uniform(&mut rng, 10.0, 600.0),
            brightness_dn: log_uniform(&mut rng, 8.0, 200.0),
        };
        let mut params = draw_params(&mut rng, seed);
        let recording = if family == SceneFamily::Screen {
            let display = draw_display(&mut rng, look.brightness_dn);
            let stimulus = draw_stimulus(&mut rng, &look, display.refresh_hz);
            params.display = Some(display);
            RecordingSpec::Screen { stimulus }
        } else {
            RecordingSpec::Scene {
                scene: Box::new(draw_scene(&mut rng, family, &look, seed)),
            }
        };
        CaseSpec {
            id: format!("case-{seed}"),
            seed,
            generator: Generator::Ctcal,
            family,
            params,
            speed_px_s: look.speed_px_s,
            brightness_dn: look.brightness_dn,
            recording,
            peer: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::peers::Peer;

    #[test]
    fn a_case_is_reproducible_from_its_seed_and_its_json() {
        let a = CaseSpec::draw(7);
        assert_eq!(a, CaseSpec::draw(7));
        let json = serde_json::to_string(&a).unwrap();
        assert_eq!(serde_json::from_str::<CaseSpec>(&json).unwrap(), a);
        assert_ne!(a, CaseSpec::draw(8));
    }

    #[test]
    fn every_case_survives_its_json() {
        for seed in 0..300 {
            let case = CaseSpec::draw(seed);
            let json = serde_json::to_string_pretty(&case).unwrap();
            assert_eq!(serde_json::from_str::<CaseSpec>(&json).unwrap(), case);
        }
    }

    #[test]
    fn peer_cases_keep_the_scene_and_carry_the_drawn_thresholds() {
        let all = Generator::ALL;
        assert_eq!(
            CaseSpec::draw_from(7, &[Generator::Ctcal]),
            CaseSpec::draw(7)
        );
        let mut seen = std::collections::BTreeSet::new();
        for seed in 0..40 {
            let plain = CaseSpec::draw(seed);
            let case = CaseSpec::draw_from(seed, &all);
            seen.insert(case.generator);
            assert_eq!(case.recording, plain.recording);
            assert_eq!(case.params.display, plain.params.display);
            assert_eq!(case.peer.is_some(), case.generator != Generator::Ctcal);
            let json = serde_json::to_string(&case).unwrap();
            assert_eq!(serde_json::from_str::<CaseSpec>(&json).unwrap(), case);
            match &case.peer {
                Some(Peer::Voltmeter(v)) => {
                    // one threshold, 1 / k1, the mean of the two drawn
                    let mean = (plain.params.ct_on + plain.params.ct_off) / 2.0;
                    assert!((case.params.ct_on - mean).abs() < 1e-4 * mean);
                    assert_eq!(case.params.ct_on, case.params.ct_off);
                    assert!((5.0..=40.0).contains(&v.k[1]));
                }
                Some(_) => {
                    assert_eq!(
                        (case.params.ct_on, case.params.ct_off),
                        (plain.params.ct_on, plain.params.ct_off)
                    );
                }
                None => assert_eq!(case, plain),
            }
        }
        assert_eq!(seen.len(), 4, "{seen:?}");
    }

    #[test]
    fn draws_stay_in_the_study_ranges() {
        for seed in 0..300 {
            let c = CaseSpec::draw(seed);
            let p = &c.params;
            assert!((0.1..=0.9).contains(&p.ct_on) && (0.1..=0.9).contains(&p.ct_off));
            assert!((0.0..=0.08).contains(&p.ct_sigma.unwrap()));
            assert!((10.0..=600.0).contains(&c.speed_px_s));
            assert!((8.0..=200.0).contains(&c.brightness_dn));
            assert!(p.cutoff_hz.is_none_or(|c| (5.0..=500.0).contains(&c)));
            assert_eq!(c.is_screen(), p.display.is_some());
            if let RecordingSpec::Scene { scene } = &c.recording {
                let aps = scene.aps.as_ref().unwrap();
                assert!((10.0..=100.0).contains(&aps.rate_hz));
                assert!(aps.exposure_s <= 0.01 && aps.exposure_s * aps.rate_hz <= 1.0);
            }
        }
    }
}
