//! Shot noise: photon and dark-current shot noise makes pixels fire at random, both
//! polarities, more often in the dark (Graca & Delbruck, IISW 2021;
//! [`crate::sim::effects::shot_noise`]).
//!
//! Signature: an excess of both ON and OFF events among the events without
//! spatio-temporal support, stronger in the dark. Evidence: the smaller of the two excesses
//! (shot noise makes both alike; leak only ON), in Poisson standard errors; it matters
//! above 0.005 events per pixel-second. Start: twice that excess rate, divided by the
//! simulator's brightness factor averaged over the recording's intensities.
//!
//! The isolated events of all pixels are also the misses of other effects (a lagging
//! photoreceptor, a leak, thresholds off at sparse edges), so the count of isolated OFF
//! events at the recording's quiet pixels ([`super::quiet_noise`]) rules shot noise out
//! where it finds none that matters, calls for it where it finds more than the model has
//! (starting the search at the dark rate it gives), and is the effect's signature when the
//! keep rule judges it on the selection blocks.

use super::{Context, Effect, Evidence, background_totals};
use crate::fit::observe::INTENSITY_BINS;
use crate::sim::effects::shot_noise::brightness_factor;

/// The evidence for shot noise: the isolated events of all pixels
/// (`isolated_evidence`), then the quiet pixels' count, which rules it out or calls for
/// it whatever those show (`with_quiet_pixels`).
pub fn evidence(c: &Context) -> Evidence {
    let (totals, exposure) = background_totals(c);
    if exposure <= 0.0 {
        return Evidence::none(
            Effect::ShotNoise,
            "no reliable pixel-time to count isolated events",
        );
    }
    with_quiet_pixels(c, isolated_evidence(c, totals, exposure))
}

/// The evidence of the isolated events of all pixels, `[real OFF, real ON, model OFF,
/// model ON]` over `exposure` pixel-seconds: the smaller excess in standard errors
/// ([`score`]), relevant above [`RELEVANT_HZ`], the search started at the dark rate.
fn isolated_evidence(c: &Context, [r_off, r_on, s_off, s_on]: [f64; 4], exposure: f64) -> Evidence {
    let (excess_on, excess_off) = (r_on - s_on, r_off - s_off);
    let (score, rate) = score([r_off, r_on, s_off, s_on], exposure);
    // the dark rate: the observed rate is the dark rate times the brightness factor
    let factor = mean_brightness_factor(c, exposure);
    Evidence {
        effect: Effect::ShotNoise,
        score,
        relevant: rate > RELEVANT_HZ,
        text: format!(
            "isolated ON and OFF events exceed the model's by {:.4} and {:.4} Hz per pixel: {score:.1} standard errors",
            excess_on / exposure,
            excess_off / exposure,
        ),
        other_start: None,
        start: Some((rate / factor.max(0.1) / 0.9).max(1e-3)),
    }
}

/// The simulator's shot-noise brightness factor averaged over the recording's
/// intensities, each bin weighted by its pixel-seconds (`exposure` in all).
fn mean_brightness_factor(c: &Context, exposure: f64) -> f64 {
    let bright = c.model.shot_noise_bright_factor() as f32;
    (0..INTENSITY_BINS)
        .map(|b| {
            let e = c.geometry.exposure_of(b, c.subset);
            e * brightness_factor(c.geometry.intensity_centres[b] as f32, bright) as f64
        })
        .sum::<f64>()
        / exposure
}

/// `evidence` as the isolated OFF events at the recording's quiet pixels change it:
/// ruled out where they find no noise that matters (its start kept for a listed try),
/// called for where they find more than the model has (the stronger score, searched from
/// their dark rate), else as it is.
fn with_quiet_pixels(c: &Context, evidence: Evidence) -> Evidence {
    // ruled out by the quiet pixels: not called for, its start kept for a listed try
    if let Some(why) = super::quiet_noise::rules_out(c, RELEVANT_HZ) {
        return Evidence {
            score: 0.0,
            relevant: false,
            text: why,
            ..evidence
        };
    }
    // found at the quiet pixels, whatever the isolated events of all pixels show: the
    // stronger of the two, searched from the count's dark rate
    match super::quiet_noise::finds(c, RELEVANT_HZ) {
        Some(found) => Evidence {
            score: found.z.max(if evidence.relevant {
                evidence.score
            } else {
                0.0
            }),
            relevant: true,
            text: format!("{}; {}", found.text, evidence.text),
            start: Some(found.start_hz),
            ..evidence
        },
        None => evidence,
    }
}

/// The isolated-event rate (ON + OFF excess over the model) below which shot noise does
/// not matter, events per pixel-second.
pub const RELEVANT_HZ: f64 = 0.005;

/// The evidence's score (the smaller of the ON and OFF excesses, doubled, in Poisson
/// standard errors of all four counts) and the excess rate it stands for, from the
/// isolated events `[real OFF, real ON, model OFF, model ON]` over `exposure`
/// pixel-seconds.
pub fn score([r_off, r_on, s_off, s_on]: [f64; 4], exposure: f64) -> (f64, f64) {
    let both = (r_on - s_on).min(r_off - s_off);
    let sigma = (r_on + s_on + r_off + s_off + 1.0).sqrt();
    (2.0 * both / sigma, 2.0 * both / exposure)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::events::TimeUs;
    use crate::fit::effects::EVIDENCE_THRESHOLD;
    use crate::fit::effects::fixture::{Fixture, chunk, poisson_times, rng, static_frames};
    use rand::RngExt;

    type Events = Vec<(TimeUs, u16, u16, bool)>;

    /// The scene: 16 x 12 pixels, static at 100 DN, for 10 s.
    const DN: f32 = 100.0;

    /// Isolated ON events at 0.05 Hz per pixel (a leak both sets share).
    fn leak_floor() -> Events {
        let mut rng = rng(31);
        let mut events = Vec::new();
        for y in 0..12u16 {
            for x in 0..16u16 {
                for t in poisson_times(&mut rng, 0.05, 0.0, 10.0) {
                    events.push((t, x, y, true));
                }
            }
        }
        events
    }

    /// Shot noise of dark rate `rate_hz` (the simulator's `shot_noise_rate_hz`): at 100 DN
    /// each pixel fires at `rate_hz` times the brightness factor (0.67), each event ON or
    /// OFF alike.
    fn shot_noise(rate_hz: f64) -> Events {
        let observed = rate_hz * brightness_factor(DN, 0.25) as f64;
        let mut rng = rng(32);
        let mut events = Vec::new();
        for y in 0..12u16 {
            for x in 0..16u16 {
                for t in poisson_times(&mut rng, observed, 0.0, 10.0) {
                    events.push((t, x, y, rng.random::<bool>()));
                }
            }
        }
        events
    }

    /// ON events once every 5 s at every pixel (a leak of 0.2 Hz).
    fn on_only() -> Events {
        let mut rng = rng(33);
        let mut events = Vec::new();
        for y in 0..12u16 {
            for x in 0..16u16 {
                let mut t = 5.0 * rng.random::<f64>();
                while t < 10.0 {
                    events.push(((t * 1e6) as TimeUs, x, y, true));
                    t += 5.0;
                }
            }
        }
        events
    }

    fn with(mut base: Events, extra: Events) -> Events {
        base.extend(extra);
        base
    }

    #[test]
    fn isolated_events_of_both_polarities_call_for_shot_noise_starting_near_the_dark_rate() {
        let model = chunk(leak_floor());
        let recording = chunk(with(leak_floor(), shot_noise(0.5)));
        let f = Fixture::new(&static_frames(16, 12, 10.0, DN), &recording, &model);
        let e = evidence(&f.context());
        // about 320 ON and 320 OFF events more than the model
        assert!(e.calls_for(), "{e:?}");
        assert!(e.score > EVIDENCE_THRESHOLD, "{e:?}");
        let start = e.start.unwrap();
        assert!(start > 0.5 / 2.0 && start < 0.5 * 2.0, "{start}");
    }

    /// The same excess with the recording's quiet pixels holding no isolated OFF event in
    /// 10,000 pixel-s: shot noise is at most 3.69 / 10,000 / 0.5 = 0.0007 Hz there, and the
    /// excess is another effect's.
    #[test]
    fn no_isolated_off_event_at_quiet_pixels_rules_shot_noise_out() {
        let model = chunk(leak_floor());
        let recording = chunk(with(leak_floor(), shot_noise(0.5)));
        let f = Fixture::new(&static_frames(16, 12, 10.0, DN), &recording, &model);
        let mut c = f.context();
        c.quiet_off = Some(crate::fit::events_only::QuietOff {
            rate_hz: 0.0,
            se_hz: 1e-4,
            pixel_seconds: 10_000.0,
            support_window_ms: 30.0,
            support_radius_px: 1,
            upper_bound: false,
            ..Default::default()
        });
        let e = evidence(&c);
        assert!(!e.calls_for(), "{e:?}");
        assert!(
            e.text
                .contains("quiet pixels hold 0.0000 isolated OFF events"),
            "{e:?}"
        );
    }

    #[test]
    fn the_model_as_the_recording_does_not_call_for_shot_noise() {
        let recording = chunk(with(leak_floor(), shot_noise(0.5)));
        let f = Fixture::new(&static_frames(16, 12, 10.0, DN), &recording, &recording);
        let e = evidence(&f.context());
        assert!(!e.calls_for(), "{e:?}");
        assert_eq!(e.score, 0.0);
    }

    /// The model's isolated events as the recording's (a busy scene's own isolated events
    /// offsetting the noise), while the quiet pixels hold 0.1 isolated OFF events per
    /// pixel-second over 1,000 pixel-s: the count calls for shot noise (z 9.95) and starts
    /// its search at the dark rate it gives, 0.33 Hz.
    #[test]
    fn isolated_off_events_at_quiet_pixels_call_for_shot_noise_the_comparison_misses() {
        let recording = chunk(with(leak_floor(), shot_noise(0.5)));
        let f = Fixture::new(&static_frames(16, 12, 10.0, DN), &recording, &recording);
        let mut c = f.context();
        c.quiet_off = Some(crate::fit::events_only::QuietOff {
            rate_hz: 0.1,
            se_hz: 0.01,
            pixel_seconds: 1000.0,
            support_window_ms: 30.0,
            support_radius_px: 1,
            upper_bound: false,
            ..Default::default()
        });
        let e = evidence(&c);
        assert!(e.calls_for(), "{e:?}");
        assert!((e.score - 100.0 / 101f64.sqrt()).abs() < 1e-9, "{e:?}");
        // the one intensity bin, 80 to 160 DN: brightness factors 0.727273 and 0.509091
        // at its edges, the search started at 0.1 / 0.5 / sqrt(0.727273 x 0.509091)
        assert!((e.start.unwrap() - 0.328688).abs() < 1e-5, "{e:?}");
        assert!(e.text.contains("quiet pixels hold 0.1000"), "{e:?}");
    }

    #[test]
    fn an_excess_of_on_events_only_is_leak_and_does_not_call_for_shot_noise() {
        let model = chunk(leak_floor());
        let recording = chunk(with(leak_floor(), on_only()));
        let f = Fixture::new(&static_frames(16, 12, 10.0, DN), &recording, &model);
        let e = evidence(&f.context());
        // 384 ON events more, no OFF excess: the smaller excess is nil
        assert!(!e.calls_for(), "{e:?}");
        assert!(e.score.abs() < 1e-9, "{e:?}");
    }
}
