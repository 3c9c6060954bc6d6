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
use serde::Serialize;

/// A pixel whose frames' log intensity, along its path over every counted interval, stays
/// within this range shows a still scene: 2 % of light, under the smallest thresholds
/// sensors are run at (DAVIS346 and Prophesee Gen4 down to about 0.1-0.15 in ln; ESIM and
/// v2e default to 0.2 and more), so an ideal pixel there fires at most once, and only where
/// its reference lies within 0.02 of a crossing (a share of about 0.02 / C of such pixels).
pub const STILL_LN: f32 = 0.02;

/// The background is read per brightness range, each a factor sqrt(2) in DN above
/// [`super::DIM_FRAMES_DN`] (the still pixels' least; the counted pixels below it form a
/// range of their own, which takes the nearest range's rate). Leak and noise depend on the
/// light: leak grows with it (parasitic photocurrent at the reset switch, Nozaki &
/// Delbruck, IEEE TED 2017; DVS-Voltmeter's drift, Lin et al. ECCV 2022), shot noise grows
/// in the dark (Graca & Delbruck, IISW 2021). Coverage draw 13010 (DVS-Voltmeter, 99.99 %
/// of 127,304 events ON) fired 2.7 ON events per pixel-second at 40-80 DN and 11.1 at
/// 200-255 DN, still pixels and moving ones alike at each brightness; its still pixels,
/// pooled and trimmed to one rate, gave 5.5 and left a fifth of the ON events to the scene.
const RANGE_FACTOR: f64 = std::f64::consts::SQRT_2;
/// Brightness ranges, the one under [`super::DIM_FRAMES_DN`] included (255 DN falls in the
/// last).
const RANGES: usize = 9;
/// A brightness range reads its own background from at least this many still pixels; the
/// still pixels and counted time of one with fewer join the nearest range that has them
/// (all of them pooled where none has).
pub const MIN_RANGE_PIXELS: usize = 10;

/// The still pixels of one brightness range (after ranges with too few were joined to it)
/// and the counted pixels' time there.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct BrightnessRange {
    /// The DN range of the pixels it holds, `[lo, hi)` (joined ranges included).
    pub dn: [f64; 2],
    pub pixels: usize,
    /// Still pixel-seconds.
    pub exposure_s: f64,
    /// ON and OFF events at its still pixels.
    pub events: [f64; 2],
    /// Its still pixels' log ranges, summed ([`StillPixels::log_range_sum`]).
    pub log_range_sum: f64,
    /// The counted pixels' time at this brightness, pixel-seconds.
    pub counted_s: f64,
}

/// The still pixels' events and time, per polarity (ON, OFF), per brightness range
/// ([`RANGE_FACTOR`]), with the counted pixels' time in each; the background of the
/// counted pixels is each range's rate over its counted time. A still pixel fires for its
/// scene at most about its log range / C times (a camera's pixel starts from any
/// reference, so one within its range of a crossing fires once).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StillPixels {
    pub ranges: Vec<BrightnessRange>,
}

/// One pixel of the count: its ON and OFF events, counted seconds, brightness (DN) and,
/// where its frames are still, its log range.
#[derive(Clone, Copy, Debug)]
struct PixelTally {
    events: [f64; 2],
    exposure_s: f64,
    dn: f64,
    still_range: Option<f64>,
}

impl StillPixels {
    /// Every range together (its `dn` spanning them all).
    pub fn total(&self) -> BrightnessRange {
        self.ranges.iter().fold(
            BrightnessRange {
                dn: [f64::INFINITY, 0.0],
                ..BrightnessRange::default()
            },
            |t, r| BrightnessRange {
                dn: [t.dn[0].min(r.dn[0]), t.dn[1].max(r.dn[1])],
                pixels: t.pixels + r.pixels,
                exposure_s: t.exposure_s + r.exposure_s,
                events: [t.events[0] + r.events[0], t.events[1] + r.events[1]],
                log_range_sum: t.log_range_sum + r.log_range_sum,
                counted_s: t.counted_s + r.counted_s,
            },
        )
    }

    /// The still pixels among those counted (`exposure_s[pixel] > 0`, not excluded) and
    /// their events (`counts[pixel]`: ON, OFF, over the pixel's counted intervals), per
    /// brightness range with every counted pixel's time, less those whose count no uniform
    /// background of their range explains (see [`trim_outliers`]).
    pub fn measure(
        frames: &PreparedFrames,
        counts: &[[f64; 2]],
        exposure_s: &[f64],
        excluded: &[bool],
    ) -> Self {
        let counted: Vec<PixelTally> = (0..frames.width * frames.height)
            .filter(|&p| !excluded[p] && exposure_s[p] > 0.0)
            .filter_map(|p| {
                Some(PixelTally {
                    events: counts[p],
                    exposure_s: exposure_s[p],
                    dn: pixel_dn(frames, p)?,
                    still_range: still_range(frames, p).map(f64::from),
                })
            })
            .collect();
        Self::from_pixels(&counted)
    }

    /// Sums `counted` by brightness range, joined as [`MIN_RANGE_PIXELS`] says, each
    /// range's still pixels trimmed to one rate.
    fn from_pixels(counted: &[PixelTally]) -> Self {
        let home = joined_ranges(counted);
        let mut out = StillPixels::default();
        for (r, &h) in home.iter().enumerate() {
            if h != r {
                continue;
            }
            let members: Vec<&PixelTally> = counted
                .iter()
                .filter(|p| home[range_of(p.dn)] == r)
                .collect();
            if members.is_empty() {
                continue;
            }
            let still = trim_outliers(
                members
                    .iter()
                    .filter_map(|p| Some((p.events, p.exposure_s, p.still_range?)))
                    .collect(),
            );
            let mut range = BrightnessRange {
                dn: members.iter().fold([f64::INFINITY, 0.0], |[lo, hi], p| {
                    let (a, b) = range_bounds(range_of(p.dn));
                    [lo.min(a), hi.max(b)]
                }),
                counted_s: members.iter().map(|p| p.exposure_s).sum(),
                ..BrightnessRange::default()
            };
            for (events, exposure, log_range) in still {
                range.pixels += 1;
                range.exposure_s += exposure;
                range.log_range_sum += log_range;
                range.events = [range.events[0] + events[0], range.events[1] + events[1]];
            }
            out.ranges.push(range);
        }
        out
    }

    /// The background rate of polarity `k` at the counted pixels (events per counted
    /// pixel-second): each brightness range's still count, less the most its scene makes
    /// at threshold `threshold` (see [`Self::log_range_sum`]), over its still time, weighted
    /// by the counted time at that brightness; the 95 % interval of that standardised rate
    /// (Fay & Feuer's, [`crate::stats::binomial::weighted_poisson95`]; Garwood's for one
    /// range). `None` without still time.
    pub fn rate95(&self, k: usize, threshold: f64) -> Option<(f64, f64)> {
        let counted_s: f64 = self.ranges.iter().map(|r| r.counted_s).sum();
        let weighted: Vec<(f64, f64)> = self
            .ranges
            .iter()
            .filter(|r| r.exposure_s > 0.0 && r.counted_s > 0.0)
            .map(|r| {
                let scene = r.log_range_sum / threshold.max(1e-3);
                let count = (r.events[k] - scene).max(0.0).round();
                (count, r.counted_s / r.exposure_s)
            })
            .collect();
        let (lo, hi) = crate::stats::binomial::weighted_poisson95(&weighted)?;
        Some((lo / counted_s, hi / counted_s))
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
            let total = self.total();
            return Some(NoiseBracket::undetermined(format!(
                "the sensor's background may be every {polarity} event: pixels whose frames do not change fire {:.3} {polarity} events per pixel-second ({:.0} in {:.0} pixel-s; an ideal pixel there fires none), {:.3} to {:.3} at the counted pixels' brightness, up to {most:.0} of the {all:.0} counted (leak or noise that the support filter does not see)",
                total.events[k] / total.exposure_s,
                total.events[k],
                total.exposure_s,
                lo,
                hi
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

/// The brightness range of a pixel of `dn`: 0 under [`super::DIM_FRAMES_DN`], then one
/// per [`RANGE_FACTOR`].
fn range_of(dn: f64) -> usize {
    if dn < super::DIM_FRAMES_DN {
        return 0;
    }
    let steps = ((dn / super::DIM_FRAMES_DN).ln() / RANGE_FACTOR.ln()).floor() as usize;
    (1 + steps).min(RANGES - 1)
}

/// The DN bounds of range `r` (the last reaches 256).
fn range_bounds(r: usize) -> (f64, f64) {
    let at = |i: usize| super::DIM_FRAMES_DN * RANGE_FACTOR.powi(i as i32);
    match r {
        0 => (0.0, super::DIM_FRAMES_DN),
        r if r == RANGES - 1 => (at(r - 1), 256.0),
        r => (at(r - 1), at(r)),
    }
}

/// For each brightness range, the range it joins: itself where it holds at least
/// [`MIN_RANGE_PIXELS`] still pixels, else the nearest such (the brighter of two as near,
/// since leak, which the still pixels mostly show, grows with the light), or range 0 for
/// all where none does (one pooled rate).
fn joined_ranges(counted: &[PixelTally]) -> [usize; RANGES] {
    let mut still = [0usize; RANGES];
    for p in counted.iter().filter(|p| p.still_range.is_some()) {
        still[range_of(p.dn)] += 1;
    }
    let own: Vec<usize> = (0..RANGES)
        .filter(|&r| still[r] >= MIN_RANGE_PIXELS)
        .collect();
    std::array::from_fn(|r| {
        own.iter()
            .copied()
            .min_by_key(|&o| (o.abs_diff(r), std::cmp::Reverse(o)))
            .unwrap_or(0)
    })
}

/// Pixel `pixel`'s mean DN over the frames of the used intervals where it is reliable
/// (`None` where there are none).
fn pixel_dn(frames: &PreparedFrames, pixel: usize) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for k in (0..frames.flows.len()).filter(|&k| frames.flows[k].is_some()) {
        if frames.reliable(k, pixel) {
            sum += (frames.dn[k].data[pixel] + frames.dn[k + 1].data[pixel]) as f64;
            n += 2;
        }
    }
    (n > 0).then(|| sum / n as f64)
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

    /// Still pixels of one brightness range, with 10,000 counted pixel-seconds.
    fn one_range(pixels: usize, exposure_s: f64, events: [f64; 2], log_range: f64) -> StillPixels {
        let range = BrightnessRange {
            dn: [20.0, 256.0],
            pixels,
            exposure_s,
            events,
            log_range_sum: log_range,
            counted_s: 10_000.0,
        };
        StillPixels {
            ranges: vec![range],
        }
    }

    /// `n` pixels at `dn`, each with `on` ON events in one second, still or not.
    fn pixels(n: usize, dn: f64, on: f64, still: bool) -> Vec<PixelTally> {
        vec![
            PixelTally {
                events: [on, 0.0],
                exposure_s: 1.0,
                dn,
                still_range: still.then_some(0.0),
            };
            n
        ]
    }

    /// Ranges with too few still pixels join the nearest that has enough: 12 still pixels
    /// at 25 DN (range 20-28.3) and 12 at 150 DN (113-160); 2 at 60 DN (56.6-80) are two
    /// ranges from 150 DN and three from 25 DN, so they join 150 DN, with the moving
    /// pixels at 60 DN; the moving ones at 10 DN join 25 DN.
    #[test]
    fn ranges_with_too_few_still_pixels_join_the_nearest() {
        let counted = [
            pixels(12, 25.0, 1.0, true),
            pixels(12, 150.0, 4.0, true),
            pixels(2, 60.0, 2.0, true),
            pixels(30, 60.0, 9.0, false),
            pixels(40, 10.0, 9.0, false),
        ]
        .concat();
        let still = StillPixels::from_pixels(&counted);
        assert_eq!(still.ranges.len(), 2, "{:?}", still.ranges);
        let (dim, bright) = (still.ranges[0], still.ranges[1]);
        assert_eq!((dim.pixels, dim.counted_s, dim.events[0]), (12, 52.0, 12.0));
        assert_eq!(dim.dn[0], 0.0);
        assert!((dim.dn[1] - 20.0 * std::f64::consts::SQRT_2).abs() < 1e-9);
        assert_eq!(
            (bright.pixels, bright.counted_s, bright.events[0]),
            (14, 44.0, 52.0)
        );
        assert!((bright.dn[0] - 40.0 * std::f64::consts::SQRT_2).abs() < 1e-9);
        assert!((bright.dn[1] - 160.0).abs() < 1e-9);
        let total = still.total();
        assert_eq!((total.pixels, total.events[0]), (26, 64.0));
    }

    /// A background that grows with the light is read at the counted pixels' brightness:
    /// 50 ON events in 100 still pixel-seconds at one brightness and 200 in 100 at another,
    /// with 1,000 and 3,000 counted pixel-seconds there, is (1000 x 0.5 + 3000 x 2) / 4000
    /// = 1.625 per counted pixel-second (pooled: 1.25); Fay & Feuer's interval
    /// 1.4211-1.8504 (scipy's gamma quantiles of mean 6500, variance 185,000, w_max 30).
    #[test]
    fn the_background_is_read_at_the_counted_pixels_brightness() {
        let range = |dn: [f64; 2], events: f64, counted_s: f64| BrightnessRange {
            dn,
            pixels: 100,
            exposure_s: 100.0,
            events: [events, 0.0],
            log_range_sum: 0.0,
            counted_s,
        };
        let still = StillPixels {
            ranges: vec![
                range([20.0, 40.0], 50.0, 1000.0),
                range([80.0, 160.0], 200.0, 3000.0),
            ],
        };
        let (lo, hi) = still.rate95(0, 0.3).unwrap();
        assert!(
            (lo - 1.42107).abs() < 1e-4 && (hi - 1.85042).abs() < 1e-4,
            "{lo} {hi}"
        );
    }

    /// 100 ON events in 1,000 still pixel-seconds: Garwood's 95 % interval 81.36-121.63,
    /// so over 10,000 counted pixel-seconds 406.8 (half the lower end) to 1216.3 of 5,000
    /// counted events are background.
    #[test]
    fn a_still_background_beyond_the_support_bound_takes_its_share_off() {
        let still = one_range(500, 1000.0, [100.0, 0.0], 0.0);
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
        let ranged = one_range(500, 1000.0, [100.0, 0.0], 3.0);
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
