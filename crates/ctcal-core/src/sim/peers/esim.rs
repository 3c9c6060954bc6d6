//! ESIM's pixel model (Rebecq, Gehrig & Scaramuzza, "ESIM: an open event camera
//! simulator", CoRL 2018), re-implemented from `event_camera_simulator/esim/src/
//! event_simulator.cpp` and the flags of `esim_ros/src/esim_node.cpp` in uzh-rpg/rpg_esim,
//! commit 4cf0b8952e9f58f674c3098f1b027a4b6db53427 (MIT licence; no code copied).
//!
//! - Log response: the image is read as `I = DN / 255` (float) and the pixel compares
//!   `L = ln(eps + I)` (`use_log_image`, `log_eps` = 1e-3 by default), i.e. `ln(DN + 255 eps)`
//!   up to a constant: `log_offset_dn = 0.255`. Without `use_log_image` it compares `I`
//!   (thresholds in units of `DN / 255`, no log offset).
//! - Time discretisation: between two samples `L` is linear in time. Every pixel keeps a
//!   reference `r` (the last crossing level, starting at the first image); when
//!   `|L_b - L_a| > 1e-6` the crossings `r + k p C` (`p` the sign of `L_b - L_a`) that lie in
//!   `(L_a, L_b]` fire at `t_a + (r + k p C - L_a) (t_b - t_a) / (L_b - L_a)` (nanoseconds,
//!   computed in f32 and truncated), and `r` moves to the last one. Crossings between `r`
//!   and `L_a` that were not reached inside an interval are never fired.
//! - Threshold noise: temporal, not frozen. When `sigma_C > 0`, every pixel draws
//!   `C = C_p + N(0, sigma_C)` (floor 0.01) once per sample interval in which it changes, for
//!   the polarity of that change, and uses it for all of that interval's crossings.
//!   ESIM's search starts at `r + p C` and stops at the first level outside `(L_a, L_b]`, so
//!   a draw smaller than the change already gained since the last crossing (`C < L_a - r`)
//!   fires nothing and leaves `r` where it was; on a monotonic ramp the pixel then stays
//!   silent until the signal turns. On the side-by-side texture of `tests/cli/peers.rs`
//!   (C = 0.3) the default `sigma_C` = 0.021 gives 3130 events against 4614 without noise
//!   (-32 %); without noise ESIM matches ctcal's ideal pixel with the eps response (4598:
//!   ties where 8-bit frames return to a level exactly).
//! - Refractory: a crossing less than `refractory_period_ns` after the pixel's last event is
//!   dropped, but the reference still moves to it (the change is lost, not delayed). A
//!   last-event time of exactly 0 counts as "never fired", as in ESIM.
//! - No leak, no shot noise, no bandwidth limit, no latency.
//!
//! Event times: ESIM works in nanoseconds; ctcal rounds them to the nearest microsecond.
//! The input is taken as given: ESIM's own renderer and adaptive frame sampling
//! (`simulation_adaptive_sampling_lambda`) are not reproduced, so the frame rate is the
//! scene's `render_hz`.

use super::super::rng::{Stream, generator};
use super::super::{FrameSource, SimError};
use crate::events::EventChunk;
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// ESIM's event-simulator configuration, with the defaults of `esim_node.cpp`'s flags.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Params {
    /// `contrast_threshold_pos` (default 1.0).
    pub contrast_threshold_pos: f64,
    /// `contrast_threshold_neg` (default 1.0).
    pub contrast_threshold_neg: f64,
    /// `contrast_threshold_sigma_pos` (default 0.021).
    pub contrast_threshold_sigma_pos: f64,
    /// `contrast_threshold_sigma_neg` (default 0.021).
    pub contrast_threshold_sigma_neg: f64,
    /// `refractory_period_ns` (default 0).
    pub refractory_period_ns: u64,
    /// `use_log_image` (default true).
    pub use_log_image: bool,
    /// `log_eps` (default 0.001).
    pub log_eps: f64,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            contrast_threshold_pos: 1.0,
            contrast_threshold_neg: 1.0,
            contrast_threshold_sigma_pos: 0.021,
            contrast_threshold_sigma_neg: 0.021,
            refractory_period_ns: 0,
            use_log_image: true,
            log_eps: 0.001,
        }
    }
}

/// ESIM's smallest contrast threshold after noise.
const MINIMUM_CONTRAST_THRESHOLD: f32 = 0.01;
/// ESIM's tolerance below which a pixel is taken as unchanged.
const TOLERANCE: f32 = 1e-6;

impl Params {
    /// The value ESIM compares for intensity `dn` (camera DN), in f32 as ESIM computes it.
    pub fn preprocess(&self, dn: f32) -> f32 {
        let intensity = dn * (1.0 / 255.0);
        if self.use_log_image {
            (self.log_eps as f32 + intensity).ln()
        } else {
            intensity
        }
    }

    pub(super) fn check(&self) -> Result<(), SimError> {
        let ok = [
            self.contrast_threshold_pos,
            self.contrast_threshold_neg,
            self.contrast_threshold_sigma_pos,
            self.contrast_threshold_sigma_neg,
            self.log_eps,
        ]
        .iter()
        .all(|v| v.is_finite() && *v >= 0.0)
            && self.contrast_threshold_pos > 0.0
            && self.contrast_threshold_neg > 0.0;
        if ok {
            Ok(())
        } else {
            Err(SimError::Invalid(
                "ESIM parameters: thresholds must be positive and sigmas and log_eps finite and >= 0".into(),
            ))
        }
    }
}

/// One ESIM pixel: its reference level and last event time (ns, 0 = never).
#[derive(Clone, Copy, Debug)]
struct Pixel {
    reference: f32,
    last_event_ns: u64,
}

/// The crossings of one pixel between samples `(t_a, l_a)` and `(t_b, l_b)` (ns), as
/// `event_simulator.cpp` finds them; `emit(t_ns, on)` receives each event.
fn crossings(
    pixel: &mut Pixel,
    params: &Params,
    (t_a, l_a): (u64, f32),
    (t_b, l_b): (u64, f32),
    rng: &mut impl Rng,
    mut emit: impl FnMut(u64, bool),
) {
    if (l_a - l_b).abs() <= TOLERANCE {
        return;
    }
    let on = l_b >= l_a;
    let pol = if on { 1.0f32 } else { -1.0 };
    let (c, sigma) = if on {
        (
            params.contrast_threshold_pos,
            params.contrast_threshold_sigma_pos,
        )
    } else {
        (
            params.contrast_threshold_neg,
            params.contrast_threshold_sigma_neg,
        )
    };
    let mut c = c as f32;
    if sigma > 0.0 {
        let z: f32 = StandardNormal.sample(rng);
        c = (c + sigma as f32 * z).max(MINIMUM_CONTRAST_THRESHOLD);
    }
    let delta_t_ns = t_b - t_a;
    let mut cross = pixel.reference;
    loop {
        cross += pol * c;
        let inside = if on {
            cross > l_a && cross <= l_b
        } else {
            cross < l_a && cross >= l_b
        };
        if !inside {
            return;
        }
        // f32 arithmetic then truncation to an integer duration, as ESIM
        let edt = ((cross - l_a) * delta_t_ns as f32 / (l_b - l_a)) as u64;
        let t = t_a + edt;
        let since = t.saturating_sub(pixel.last_event_ns);
        if pixel.last_event_ns == 0 || since >= params.refractory_period_ns {
            emit(t, on);
            pixel.last_event_ns = t;
        }
        pixel.reference = cross;
    }
}

/// Runs ESIM's event simulator over `source`; the first sample sets the references.
pub fn simulate(
    source: &mut dyn FrameSource,
    params: &Params,
    seed: u64,
) -> Result<EventChunk, SimError> {
    params.check()?;
    let (width, _) = source.size();
    let Some(first) = source.next_frame()? else {
        return Err(SimError::Invalid("the input has no frames".into()));
    };
    let mut last: Vec<f32> = first.dn.iter().map(|&d| params.preprocess(d)).collect();
    let mut pixels: Vec<Pixel> = last
        .iter()
        .map(|&reference| Pixel {
            reference,
            last_event_ns: 0,
        })
        .collect();
    let mut rng = generator(seed, Stream::Thresholds, 0);
    let mut out = EventChunk::default();
    let mut t_a = first.t as u64 * 1000;
    let mut interval: Vec<(u64, usize, bool)> = Vec::new();
    while let Some(sample) = source.next_frame()? {
        let t_b = sample.t as u64 * 1000;
        if t_b <= t_a {
            return Err(SimError::Invalid(format!(
                "ESIM needs strictly increasing sample times ({} us after {} us)",
                sample.t,
                t_a / 1000
            )));
        }
        interval.clear();
        for (i, (pixel, &dn)) in pixels.iter_mut().zip(&sample.dn).enumerate() {
            let l_b = params.preprocess(dn);
            crossings(
                pixel,
                params,
                (t_a, last[i]),
                (t_b, l_b),
                &mut rng,
                |t, on| interval.push((t, i, on)),
            );
            last[i] = l_b;
        }
        interval.sort_by_key(|&(t, i, _)| (t, i));
        for &(t_ns, i, on) in &interval {
            let t_us = (t_ns + 500) / 1000;
            out.push(t_us as i64, (i % width) as u16, (i / width) as u16, on);
        }
        t_a = t_b;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::pixel::Transition;
    use crate::sim::source::{ReplaySamples, Sample};

    fn ideal(c: f64) -> Params {
        Params {
            contrast_threshold_pos: c,
            contrast_threshold_neg: c,
            contrast_threshold_sigma_pos: 0.0,
            contrast_threshold_sigma_neg: 0.0,
            ..Params::default()
        }
    }

    /// One pixel whose ESIM log value goes through `levels` at `times` (us).
    fn one_pixel(params: &Params, times: &[i64], levels: &[f32], seed: u64) -> EventChunk {
        let eps = params.log_eps as f32;
        let samples: Vec<Sample> = times
            .iter()
            .zip(levels)
            .map(|(&t, &l)| Sample {
                t,
                dn: vec![255.0 * (l.exp() - eps)],
                transition: Transition::Linear,
            })
            .collect();
        simulate(&mut ReplaySamples::new(&samples, 1, 1), params, seed).unwrap()
    }

    #[test]
    fn a_ramp_of_1_05_fires_three_events_at_the_interpolated_times() {
        // L from ln(0.2 + eps) up by 1.05 over 1 ms, C = 0.3: crossings at 0.3, 0.6, 0.9
        // of the way, i.e. 1000 us * k 0.3 / 1.05 after the first sample
        let p = ideal(0.3);
        let l0 = p.preprocess(51.0);
        let events = one_pixel(&p, &[0, 1000], &[l0, l0 + 1.05], 1);
        assert_eq!(events.len(), 3);
        assert!(events.on.iter().all(|&on| on));
        let expected: Vec<i64> = (1..=3)
            .map(|k| (1000.0 * 0.3 * k as f64 / 1.05).round() as i64)
            .collect();
        assert_eq!(events.t, expected); // 286, 571, 857
    }

    #[test]
    fn crossings_not_reached_in_an_interval_are_skipped_later() {
        // up 0.29 (no event), then down to -0.1 (none), then down to -0.35: one OFF at the
        // reference minus C = -0.3, interpolated in the last interval
        let p = ideal(0.3);
        let l0 = p.preprocess(100.0);
        let events = one_pixel(
            &p,
            &[0, 1000, 2000, 3000],
            &[l0, l0 + 0.29, l0 - 0.1, l0 - 0.35],
            1,
        );
        assert_eq!(events.len(), 1);
        assert!(!events.on[0]);
        assert_eq!(events.t[0], 2000 + (1000.0f64 * 0.2 / 0.25).round() as i64);
    }

    #[test]
    fn refractory_drops_the_event_but_moves_the_reference() {
        // up 0.65 in 1 ms: crossings at 462 us and 923 us; a 600 us refractory drops the
        // second, and the reference still sits at +0.6, so a further rise to +0.95 fires at
        // +0.9 (in the next interval), not at the dropped +0.6
        let p = Params {
            refractory_period_ns: 600_000,
            ..ideal(0.3)
        };
        let l0 = p.preprocess(60.0);
        let events = one_pixel(&p, &[0, 1000, 2000], &[l0, l0 + 0.65, l0 + 0.95], 1);
        let expected = [
            (1000.0f64 * 0.3 / 0.65).round() as i64,
            1000 + (1000.0f64 * 0.25 / 0.3).round() as i64,
        ];
        assert_eq!(events.t, expected);
    }

    #[test]
    fn threshold_noise_can_strand_a_pixel_on_a_ramp() {
        // a ramp of +0.07 per interval: with a fixed C = 0.3 it fires every 0.3 (46 events
        // over 13.93); with C redrawn every interval, a draw below the level already gained
        // since the last crossing (C < L_a - r) ends the search before it starts, and once
        // the gain exceeds every likely draw the pixel never fires again on this ramp
        let l0 = ideal(0.3).preprocess(60.0);
        let times: Vec<i64> = (0..200).map(|k| k * 1000).collect();
        let levels: Vec<f32> = (0..200).map(|k| l0 + 0.07 * k as f32).collect();
        assert_eq!(one_pixel(&ideal(0.3), &times, &levels, 7).len(), 46);
        let noisy = Params {
            contrast_threshold_sigma_pos: 0.05,
            ..ideal(0.3)
        };
        let stranded = one_pixel(&noisy, &times, &levels, 7);
        assert!(stranded.len() <= 5, "{}", stranded.len());
    }

    #[test]
    fn threshold_noise_is_deterministic_for_a_seed() {
        let p = Params {
            contrast_threshold_sigma_pos: 0.05,
            contrast_threshold_sigma_neg: 0.05,
            ..ideal(0.3)
        };
        let l0 = p.preprocess(60.0);
        let times: Vec<i64> = (0..400).map(|k| k * 1000).collect();
        let levels: Vec<f32> = (0..400)
            .map(|k| l0 + 1.5 * (k as f32 * 0.05).sin())
            .collect();
        let a = one_pixel(&p, &times, &levels, 7);
        assert!(a.len() > 5, "{}", a.len());
        assert_eq!(a, one_pixel(&p, &times, &levels, 7));
        assert_ne!(a, one_pixel(&p, &times, &levels, 8));
    }
}
