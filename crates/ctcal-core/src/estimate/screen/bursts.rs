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
//! it ([`TRUNCATED_BELOW`]) by more than the shares' noise ([`Z_CUT`], the noise measured
//! over blocks of refreshes) has its bursts cut, and its thresholds are only upper bounds.
//! A model fitted to such counts reads the threshold high and so repeats less itself
//! (14018 OFF: 3.6 % at 1.16 for a true 0.79, where the recording repeats none), so no
//! floor is set on the model's share: a small share is weighed by its noise.

use super::lag::RefreshClock;
use crate::events::EventChunk;
use serde::Serialize;

/// A recording whose repeat share is under this share of the fitted model's has its bursts
/// cut short. Photoreceptor lag, which the model already has when it was measured, spreads
/// a burst over the period without removing its events; the v2e oracle's checkerboard
/// repeats 50.9 / 51.3 % against its model's 51.7 / 51.7 %.
pub const TRUNCATED_BELOW: f64 = 0.5;

/// The shortfall under [`TRUNCATED_BELOW`] of the model's share must exceed this many
/// standard errors of the difference (one-sided, p < 0.001).
pub const Z_CUT: f64 = 3.09;

/// Fewer events of a polarity than this decide nothing.
pub const MIN_EVENTS: u64 = 1_000;

/// Contiguous blocks of refresh windows over which the shares' noise is measured: a burst
/// puts several repeats into one pixel and refresh, so the events are not independent and
/// the binomial error would be too small.
pub const NOISE_BLOCKS: usize = 16;

/// Of one polarity's events in the refresh windows, those that follow another of the same
/// pixel and polarity in the same window, and the standard error of their share.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Repeats {
    pub events: u64,
    pub repeats: u64,
    /// The share's standard error: the ratio estimator's over [`NOISE_BLOCKS`] blocks of
    /// refreshes, at least the binomial one.
    pub share_se: f64,
}

impl Repeats {
    pub fn share(&self) -> f64 {
        self.repeats as f64 / self.events.max(1) as f64
    }

    /// The share and its standard error from per-block counts (the linearised variance of
    /// a ratio of sums, Cochran, *Sampling Techniques*, 1977, Sec. 6.4).
    fn from_blocks(blocks: &[(u64, u64)]) -> Repeats {
        let events: u64 = blocks.iter().map(|b| b.0).sum();
        let repeats: u64 = blocks.iter().map(|b| b.1).sum();
        let mut r = Repeats {
            events,
            repeats,
            share_se: 0.0,
        };
        if events == 0 {
            return r;
        }
        let share = r.share();
        let used: Vec<_> = blocks.iter().filter(|b| b.0 > 0).collect();
        let n = used.len() as f64;
        let block_var = if used.len() > 1 {
            let sum_sq: f64 = used
                .iter()
                .map(|b| (b.1 as f64 - share * b.0 as f64).powi(2))
                .sum();
            n / (n - 1.0) * sum_sq / (events as f64).powi(2)
        } else {
            0.0
        };
        let binomial_var = share * (1.0 - share) / events as f64;
        r.share_se = block_var.max(binomial_var).sqrt();
        r
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
    let mut blocks = [[(0u64, 0u64); NOISE_BLOCKS]; 2];
    let from = clock.start_us as f64 - 0.5 * clock.period_us;
    let windows = ((clock.end_us as f64 - from) / clock.period_us)
        .ceil()
        .max(1.0);
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
        let block =
            ((window as f64 / windows * NOISE_BLOCKS as f64) as usize).min(NOISE_BLOCKS - 1);
        blocks[slot][block].0 += 1;
        if last_window[pixel][slot] == window {
            blocks[slot][block].1 += 1;
        }
        last_window[pixel][slot] = window;
    }
    blocks.map(|b| Repeats::from_blocks(&b))
}

/// How many standard errors the recording's share falls short of [`TRUNCATED_BELOW`] of
/// the model's (negative when it does not).
pub fn shortfall_z(recorded: Repeats, model: Repeats) -> f64 {
    let gap = TRUNCATED_BELOW * model.share() - recorded.share();
    let se = (TRUNCATED_BELOW * model.share_se).hypot(recorded.share_se);
    if se > 0.0 {
        gap / se
    } else if gap > 0.0 {
        f64::INFINITY
    } else {
        0.0
    }
}

/// Whether one polarity's bursts are cut short: the recording's repeat share under
/// [`TRUNCATED_BELOW`] of the model's by more than [`Z_CUT`] standard errors, with
/// [`MIN_EVENTS`] on each side.
pub fn cut_short(recorded: Repeats, model: Repeats) -> bool {
    recorded.events >= MIN_EVENTS
        && model.events >= MIN_EVENTS
        && shortfall_z(recorded, model) > Z_CUT
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
        let counts = |r: Repeats| (r.events, r.repeats);
        let [on, off] = repeats(&e, clock(), &[true, true], 2);
        assert_eq!(counts(on), (6, 3));
        assert_eq!(counts(off), (1, 0));
        let [on, _] = repeats(&e, clock(), &[true, false], 2);
        assert_eq!(counts(on), (4, 2));
    }

    #[test]
    fn the_shares_noise_is_measured_over_blocks() {
        // two blocks of 100 events: 30 and 10 repeats, share 0.2; residuals 10 and -10,
        // variance 2/1 * 200 / 200^2 = 0.01, above the binomial 0.2 * 0.8 / 200 = 0.0008
        let r = Repeats::from_blocks(&[(100, 30), (0, 0), (100, 10)]);
        assert_eq!((r.events, r.repeats), (200, 40));
        assert!((r.share_se - 0.1).abs() < 1e-12, "{}", r.share_se);
        // blocks that agree fall back to the binomial error
        let r = Repeats::from_blocks(&[(100, 20), (100, 20)]);
        assert!(
            (r.share_se - 0.0008f64.sqrt()).abs() < 1e-12,
            "{}",
            r.share_se
        );
    }

    #[test]
    fn bursts_are_cut_short_below_half_the_models_repeats_beyond_their_noise() {
        let r = |events: u64, repeats: u64, share_se: f64| Repeats {
            events,
            repeats,
            share_se,
        };
        assert!(cut_short(r(10_000, 400, 0.005), r(10_000, 5_000, 0.01)));
        assert!(!cut_short(r(10_000, 2_600, 0.005), r(10_000, 5_000, 0.01)));
        // a small model share counts when its noise is smaller still (14018 OFF: none of
        // 135,802 recorded events repeat, 3.6 % of the model's do)
        assert!(cut_short(r(135_802, 0, 0.0), r(127_290, 4_582, 0.002)));
        // and not when the blocks scatter as much as the shortfall
        assert!(!cut_short(r(10_000, 0, 0.0), r(10_000, 900, 0.04)));
        // too few events tell nothing
        assert!(!cut_short(r(900, 0, 0.0), r(10_000, 5_000, 0.01)));
        assert!((shortfall_z(r(10_000, 0, 0.0), r(10_000, 1_000, 0.01)) - 10.0).abs() < 1e-9);
    }
}
