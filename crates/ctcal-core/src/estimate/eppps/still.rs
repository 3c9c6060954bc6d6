//! The sensor's background events (leak, noise) measured where the frames show a still
//! scene: with frames, `estimate eppps` knows where the scene does not change, and an ideal
//! pixel there makes no event, so what fires there is the sensor's own. The support filter
//! of [`super::recording`] bounds noise by the events no neighbour supports; it is blind to
//! a background that fires everywhere at once, as leak does in a simulator whose pixels all
//! start from a reset (DVS-Voltmeter's drift made 97 % of one recording's events, nearly
//! every pixel firing one ON event whatever its scene did: `benches/coverage/eppps-still-
//! pixels-2026-12-05`), and to a rate high enough that noise events support each other.
//!
//! Leak moves a pixel's reference towards ON at a steady rate (Nozaki & Delbruck, IEEE
//! TED 2017): at a still pixel it fires ON events at that rate; where the scene moves it
//! adds ON events while the light does not fall and delays OFF events while it falls, so a
//! moving pixel's ON excess is between half and all of the still pixels' rate (half: light
//! falling half the time). Noise fires at its rate whatever the scene does. So a still
//! pixels' rate `r` (Garwood's 95 % interval on their count, less what their own scene may
//! make: a camera's pixel starts from any reference, so one whose light moves by a range `d`
//! fires about `d / C` times for it, `C` the threshold read without the still pixels) takes
//! between half of its lower end and all of its upper end off the counted events.

use super::recording::NoiseBracket;
use crate::estimate::frames::PreparedFrames;

/// A pixel whose frames' log intensity, along its path over every counted interval, stays
/// within this range shows a still scene: 2 % of light, under the smallest thresholds
/// sensors are run at (DAVIS346 and Prophesee Gen4 down to about 0.1-0.15 in ln; ESIM and
/// v2e default to 0.2 and more), so an ideal pixel there fires at most once, and only where
/// its reference lies within 0.02 of a crossing (a share of about 0.02 / C of such pixels).
pub const STILL_LN: f32 = 0.02;

/// The still pixels' events and time, per polarity (ON, OFF).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StillPixels {
    pub pixels: usize,
    /// Their counted time, pixel-seconds.
    pub exposure_s: f64,
    pub events: [f64; 2],
    /// The still pixels' log ranges, summed: a still pixel fires for its scene at most
    /// about range / C times (a camera's pixel starts from any reference, so one within
    /// its range of a crossing fires once).
    pub log_range_sum: f64,
}

impl StillPixels {
    /// The still pixels among those counted (`exposure_s[pixel] > 0`, not excluded) and
    /// their events (`counts[pixel]`: ON, OFF, over the pixel's counted intervals), less
    /// those whose count no uniform background explains (see [`trim_outliers`]).
    pub fn measure(
        frames: &PreparedFrames,
        counts: &[[f64; 2]],
        exposure_s: &[f64],
        excluded: &[bool],
    ) -> Self {
        let still: Vec<([f64; 2], f64, f64)> = (0..frames.width * frames.height)
            .filter(|&p| !excluded[p] && exposure_s[p] > 0.0)
            .filter_map(|p| Some((counts[p], exposure_s[p], still_range(frames, p)? as f64)))
            .collect();
        let mut sum = StillPixels::default();
        for (count, exposure, range) in trim_outliers(still) {
            sum.pixels += 1;
            sum.exposure_s += exposure;
            sum.log_range_sum += range;
            for (total, c) in sum.events.iter_mut().zip(count) {
                *total += c;
            }
        }
        sum
    }

    /// The background rate of polarity `k` (events per pixel-second), Garwood's 95 %
    /// interval on the still pixels' count less the most their scene makes at threshold
    /// `threshold` (see [`Self::log_range_sum`]); `None` without still time.
    pub fn rate95(&self, k: usize, threshold: f64) -> Option<(f64, f64)> {
        (self.exposure_s > 0.0).then(|| {
            let scene = self.log_range_sum / threshold.max(1e-3);
            let count = (self.events[k] - scene).max(0.0).round() as usize;
            let (lo, hi) = crate::stats::binomial::poisson95(count);
            (lo / self.exposure_s, hi / self.exposure_s)
        })
    }

    /// Polarity `k`'s noise bracket over `all` counted events in `exposure_s` counted
    /// pixel-seconds: the support filter's (`support`) where the still pixels' lower end
    /// lies within it (it then bounds the background already), else the counted events
    /// less half the still pixels' lower end to less all of their upper end (see the
    /// module docs); `None` where the still pixels do not decide.
    pub fn bracket(
        &self,
        k: usize,
        support: &NoiseBracket,
        (all, exposure_s): (f64, f64),
        threshold: f64,
    ) -> Option<NoiseBracket> {
        let (lo, hi) = self.rate95(k, threshold)?;
        let (least, most) = (0.5 * lo * exposure_s, hi * exposure_s);
        if all <= 0.0 || support.why.is_some() || least <= support.noise_share * all {
            return None;
        }
        let polarity = ["ON", "OFF"][k];
        let floor = all - most;
        if floor <= 0.0 {
            return Some(NoiseBracket::undetermined(format!(
                "the sensor's background may be every {polarity} event: pixels whose frames do not change fire {:.3} {polarity} events per pixel-second ({:.0} in {:.0} pixel-s; an ideal pixel there fires none), up to {most:.0} of the {all:.0} counted (leak or noise that the support filter does not see)",
                self.events[k] / self.exposure_s,
                self.events[k],
                self.exposure_s
            )));
        }
        let half_range = 0.5 * ((all - least) / floor).ln();
        Some(NoiseBracket {
            middle: ((all - least) * floor).sqrt() / all,
            relative_error: half_range / 3f64.sqrt(),
            noise_share: most / all,
            why: None,
        })
    }
}

/// A still pixel whose count a uniform background puts beyond its 99.9 % Poisson quantile
/// is the pixel's own (a hot pixel the estimate's hot-pixel search left in, a defect), not
/// the background's: left out, twice over (the rate again without them).
const OUTLIER_QUANTILE: f64 = 0.999;

/// The still pixels (ON and OFF counts, counted seconds) whose total count is within
/// [`OUTLIER_QUANTILE`] of the uniform rate the others make.
fn trim_outliers(mut still: Vec<([f64; 2], f64, f64)>) -> Vec<([f64; 2], f64, f64)> {
    use statrs::distribution::{DiscreteCDF, Poisson};
    for _ in 0..2 {
        let (events, exposure) = still
            .iter()
            .fold((0.0, 0.0), |(n, e), (c, s, _)| (n + c[0] + c[1], e + s));
        if events <= 0.0 || exposure <= 0.0 {
            break;
        }
        let rate = events / exposure;
        still.retain(|(c, s, _)| {
            let Ok(poisson) = Poisson::new(rate * s) else {
                return true;
            };
            // kept where P(X >= count) > 1 - quantile under the others' rate
            let count = (c[0] + c[1]).round() as u64;
            count == 0 || poisson.cdf(count - 1) < OUTLIER_QUANTILE
        });
    }
    still
}

/// Pixel `pixel`'s log range where its frames, sampled along its path as the scans sample
/// it ([`super::calibration::path_samples`]) over every used interval where it is
/// reliable, stay within [`STILL_LN`] in log at [`super::DIM_FRAMES_DN`] or more (where the
/// frames' log offset, known only to its interval, changes a log range little: a dim pixel
/// still in the frames' log may not be in the sensor's); `None` where they do not (or it
/// has no sample).
fn still_range(frames: &PreparedFrames, pixel: usize) -> Option<f32> {
    let (x, y) = (pixel % frames.width, pixel / frames.width);
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    let mut still = true;
    for k in 0..frames.flows.len() {
        if frames.flows[k].is_none() || !frames.reliable(k, pixel) {
            continue;
        }
        super::calibration::path_samples(frames, k, x, y, |_, dn| {
            let l = frames.log(dn);
            (lo, hi) = (lo.min(l), hi.max(l));
            still = (dn as f64) >= super::DIM_FRAMES_DN && hi - lo < STILL_LN;
            still
        });
        if !still {
            return None;
        }
    }
    (hi >= lo).then_some(hi - lo)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn support(noise_share: f64) -> NoiseBracket {
        NoiseBracket {
            middle: 1.0,
            relative_error: 0.0,
            noise_share,
            why: None,
        }
    }

    /// 100 ON events in 1,000 still pixel-seconds: Garwood's 95 % interval 81.36-121.63,
    /// so over 10,000 counted pixel-seconds 406.8 (half the lower end) to 1216.3 of 5,000
    /// counted events are background.
    #[test]
    fn a_still_background_beyond_the_support_bound_takes_its_share_off() {
        let still = StillPixels {
            pixels: 500,
            exposure_s: 1000.0,
            events: [100.0, 0.0],
            log_range_sum: 0.0,
        };
        let (lo, hi) = still.rate95(0, 0.3).unwrap();
        assert!((lo * 1000.0 - 81.36).abs() < 0.01 && (hi * 1000.0 - 121.63).abs() < 0.01);
        let b = still
            .bracket(0, &support(0.01), (5000.0, 10_000.0), 0.3)
            .expect("decides");
        let (least, most) = (0.5 * lo * 10_000.0, hi * 10_000.0);
        let expected = ((5000.0 - least) * (5000.0 - most)).sqrt() / 5000.0;
        assert!((b.middle - expected).abs() < 1e-12, "{}", b.middle);
        assert!((b.middle - 0.8338).abs() < 1e-3, "{}", b.middle);
        assert!((b.noise_share - most / 5000.0).abs() < 1e-12);
        let half = 0.5 * ((5000.0 - least) / (5000.0 - most)).ln();
        assert!((b.half_range() - half).abs() < 1e-12);
        // within the support filter's bound (up to 20 % noise): the support decides
        assert!(
            still
                .bracket(0, &support(0.2), (5000.0, 10_000.0), 0.3)
                .is_none()
        );
        // no OFF event where the frames are still: no background to take off
        assert!(
            still
                .bracket(1, &support(0.0), (5000.0, 10_000.0), 0.3)
                .is_none()
        );
        // the scene's own events at still pixels come off first: 500 pixels over a range
        // of 0.006 each may make 10 events at a threshold of 0.3, so 90 are background
        let ranged = StillPixels {
            log_range_sum: 3.0,
            ..still
        };
        let (lo90, _) = crate::stats::binomial::poisson95(90);
        assert!((ranged.rate95(0, 0.3).unwrap().0 - lo90 / 1000.0).abs() < 1e-12);
        // a background that may be every event
        let all = still
            .bracket(0, &support(0.01), (1000.0, 10_000.0), 0.3)
            .unwrap();
        let why = all.why.expect("not determinable");
        assert!(why.contains("may be every ON event"), "{why}");
    }
}
