//! Bursts cut short: a screen changes in steps, and a pixel whose step spans several
//! thresholds fires them all at the refresh only if nothing stops it. A refractory period
//! that drops what comes within it (ESIM's and IEBCS's, and a real pixel's reset, which
//! stores the level it is reset at) leaves one event of a step when the photoreceptor
//! follows the step faster than the refractory period ends (Lichtsteiner et al., JSSC
//! 2008, Sec. II; the screen's white is the brightest light the pixels see, where they are
//! fastest). A response that compresses large steps does the same (DVS-Voltmeter's
//! per-frame drift, `2x` for `2 atanh(x)`: its steps fire fewer events than their log
//! crossings). The counts then say less about the thresholds than about the steps: matched
//! with pixels that fire every crossing, they read too high (coverage draw 14018, ESIM
//! with a 0.5 ms refractory period at 139 Hz: ON 0.73 for 0.18; 11020, DVS-Voltmeter:
//! 1.39 for 0.65 when the screen reached it as a cross-fade).
//!
//! The signature is in the recording: the share of events that repeat a pixel's polarity
//! within one refresh window. The fitted model predicts it; a recording with under half of
//! it has its bursts cut ([`TRUNCATED_BELOW`]), and its thresholds are only upper bounds.

use super::lag::RefreshClock;
use crate::events::EventChunk;
use serde::Serialize;

/// A recording whose repeat share is under this share of the fitted model's has its bursts
/// cut short. The shares are taken over thousands of events, so chance moves them by a few
/// per cent; photoreceptor lag, which the model already has when it was measured, spreads
/// a burst over the period without removing its events.
pub const TRUNCATED_BELOW: f64 = 0.5;

/// The model must repeat at least this share of its events for a missing repeat to be
/// seen (thresholds near the steps' size repeat rarely in any case).
pub const MIN_MODEL_SHARE: f64 = 0.1;

/// Fewer events of a polarity than this decide nothing.
pub const MIN_EVENTS: u64 = 1_000;

/// Of one polarity's events in the refresh windows, those that follow another of the same
/// pixel and polarity in the same window.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Repeats {
    pub events: u64,
    pub repeats: u64,
}

impl Repeats {
    pub fn share(&self) -> f64 {
        self.repeats as f64 / self.events.max(1) as f64
    }
}

/// ON and OFF [`Repeats`] of time-sorted `events` at the `included` pixels (row-major,
/// `width` wide), in windows of one refresh period centred on the refreshes.
pub fn repeats(
    events: &EventChunk,
    clock: RefreshClock,
    included: &[bool],
    width: usize,
) -> [Repeats; 2] {
    let mut last_window = vec![[i64::MIN; 2]; included.len()];
    let mut out = [Repeats::default(); 2];
    let from = clock.start_us as f64 - 0.5 * clock.period_us;
    for i in 0..events.len() {
        let t = events.t[i];
        if (t as f64) < from || t >= clock.end_us {
            continue;
        }
        let pixel = events.y[i] as usize * width + events.x[i] as usize;
        if !included.get(pixel).copied().unwrap_or(false) {
            continue;
        }
        let slot = usize::from(!events.on[i]);
        let window = ((t as f64 - from) / clock.period_us).floor() as i64;
        out[slot].events += 1;
        if last_window[pixel][slot] == window {
            out[slot].repeats += 1;
        }
        last_window[pixel][slot] = window;
    }
    out
}

/// Whether one polarity's bursts are cut short: the recording's repeat share under
/// [`TRUNCATED_BELOW`] of the model's, where the model repeats enough to tell.
pub fn cut_short(recorded: Repeats, model: Repeats) -> bool {
    recorded.events >= MIN_EVENTS
        && model.events >= MIN_EVENTS
        && model.share() >= MIN_MODEL_SHARE
        && recorded.share() < TRUNCATED_BELOW * model.share()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clock() -> RefreshClock {
        RefreshClock {
            start_us: 10_000,
            period_us: 10_000.0,
            end_us: 50_000,
        }
    }

    #[test]
    fn repeats_count_same_pixel_same_polarity_in_one_window() {
        let mut e = EventChunk::default();
        // pixel 0: three ON in the window of the refresh at 10 ms (5-15 ms), one OFF there,
        // one ON in the next window; pixel 1: two ON in the window of 20 ms (15-25 ms);
        // an event before the first window and one at the end are not counted
        for (t, x, on) in [
            (1_000, 0, true),
            (9_000, 0, true),
            (10_000, 0, true),
            (10_000, 0, false),
            (14_999, 0, true),
            (15_000, 0, true),
            (16_000, 1, true),
            (24_000, 1, true),
            (50_000, 1, true),
        ] {
            e.push(t, x, 0, on);
        }
        let [on, off] = repeats(&e, clock(), &[true, true], 2);
        assert_eq!(
            on,
            Repeats {
                events: 6,
                repeats: 3
            }
        );
        assert_eq!(
            off,
            Repeats {
                events: 1,
                repeats: 0
            }
        );
        let [on, _] = repeats(&e, clock(), &[true, false], 2);
        assert_eq!(
            on,
            Repeats {
                events: 4,
                repeats: 2
            }
        );
    }

    #[test]
    fn bursts_are_cut_short_below_half_the_models_repeats() {
        let r = |events, repeats| Repeats { events, repeats };
        assert!(cut_short(r(10_000, 400), r(10_000, 5_000)));
        assert!(!cut_short(r(10_000, 2_600), r(10_000, 5_000)));
        // a model that hardly repeats, or too few events, tells nothing
        assert!(!cut_short(r(10_000, 0), r(10_000, 900)));
        assert!(!cut_short(r(900, 0), r(10_000, 5_000)));
    }
}
