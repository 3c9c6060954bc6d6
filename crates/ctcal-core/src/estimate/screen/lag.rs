//! The photoreceptor's lag, measured from when an on-screen recording's events come.
//!
//! A DVS photoreceptor's bandwidth grows with its photocurrent (Delbruck & Mead 1995;
//! Lichtsteiner et al., JSSC 2008, Sec. III; v2e models it as a low-pass whose cutoff
//! follows intensity, Hu et al. 2021). A screen's black squares are 0.1-5 % of its white,
//! so there the photoreceptor is many times slower than in white. A screen changes only at
//! its refreshes: an ideal pixel fires every event of a change at the refresh, a slow one
//! spreads them over the following milliseconds, and when the board moves on before a dark
//! pixel has settled it crosses fewer thresholds than an ideal one would -- thresholds
//! matched with ideal pixels come out too large (on the coverage study's on-screen draws
//! with a 17-140 Hz cutoff at white: 1.4-2.6 times the truth).
//!
//! So the events' phase within the refresh period is histogrammed ([`PhaseHistogram`]):
//! ideal pixels put every event in the refresh's bin, a cutoff at white of 370 Hz already
//! gives a decay over the period, one of 20 Hz an almost flat histogram. The recording's
//! histogram is compared with the simulation's at each cutoff of a grid (the display and
//! thresholds fixed), after two things ideal simulations lack are fitted to it
//! ([`ShapeFit`]): timestamp jitter (a symmetric blur, Gaussian) and events that do not
//! follow the refreshes at all (shot noise and leak: a flat share). A flat histogram is
//! also what a very slow pixel gives, so the flat share may not exceed what the
//! recording's isolated events allow ([`noise_share_bound`]); without that bound every
//! recording could be explained as ideal pixels plus noise. A pixel so slow that its
//! events spread evenly over the period (a cutoff at white under ~100 Hz) is told apart by
//! a second histogram, of the refresh periods since the region last changed ([`Changes`]).
//! The cutoff whose two histograms match best (their summed distances) is taken, refined
//! between its grid neighbours, and only when it halves ideal pixels' distance
//! ([`DECISIVE`]).
//!
//! Measured on the coverage study's on-screen draws (`benches/coverage/screen-lag-2026-11-27`):
//! the cutoff comes within a factor 2-3 of the truth (20 -> 53 Hz, 28 -> 18 Hz, 27 -> 56 Hz,
//! 139 -> 178 Hz, 194 -> 300 Hz, 368 -> 300 Hz), no lag is read into draws with ideal pixels,
//! refractory periods or 0.76 ms of jitter, and the thresholds move toward the truth but,
//! since the display is still fitted with ideal pixels, not all the way.

use super::Setup;
use crate::estimate::EstimateError;
use crate::events::{EventChunk, Sensor, TimeUs};
use crate::sim::DisplayParams;
use rayon::prelude::*;
use serde_json::json;

/// Bins of the refresh period.
pub const BINS: usize = 32;

/// The cutoffs profiled, Hz at 255 camera DN: half decades from 1 Hz (a pixel that takes
/// seconds to settle in black) to 3 kHz (faster than any display's refresh even in black).
pub const GRID_HZ: [f64; 8] = [3000.0, 1000.0, 300.0, 100.0, 30.0, 10.0, 3.0, 1.0];

/// A cutoff is taken only when its histogram's distance is at most this share of ideal
/// pixels': below it, the difference is within what the fitted jitter and noise absorb.
pub const DECISIVE: f64 = 0.5;

/// The systematic error of the lag's correction, as a share of the correction (one
/// standard deviation): the display is fitted with ideal pixels, and the cutoff's grid
/// and the phases' saturation under slow pixels leave it uncertain; on the coverage
/// study's on-screen draws with a cutoff the corrected thresholds missed the truth by up
/// to this share of the correction in most draws (see the module docs).
pub const CORRECTION_SYSTEMATIC: f64 = 0.5;

/// The refresh times on the recording's clock.
#[derive(Clone, Copy, Debug)]
pub struct RefreshClock {
    /// The first refresh.
    pub start_us: TimeUs,
    pub period_us: f64,
    /// The end of the last refresh's period.
    pub end_us: TimeUs,
}

/// Events per phase bin of the refresh period, per polarity; bin 0 is centred on the
/// refresh.
#[derive(Clone, Debug, PartialEq)]
pub struct PhaseHistogram {
    pub on: [u64; BINS],
    pub off: [u64; BINS],
}

impl PhaseHistogram {
    /// The histogram of `events` at `included` pixels (row-major, `width` wide), within the
    /// clock's span.
    pub fn of(events: &EventChunk, clock: RefreshClock, included: &[bool], width: usize) -> Self {
        let mut h = PhaseHistogram {
            on: [0; BINS],
            off: [0; BINS],
        };
        for i in 0..events.len() {
            let t = events.t[i];
            let pixel = events.y[i] as usize * width + events.x[i] as usize;
            if t < clock.start_us || t >= clock.end_us || !included[pixel] {
                continue;
            }
            let phase = ((t - clock.start_us) as f64 / clock.period_us).fract();
            let bin = ((phase + 0.5 / BINS as f64) * BINS as f64) as usize % BINS;
            if events.on[i] {
                h.on[bin] += 1;
            } else {
                h.off[bin] += 1;
            }
        }
        h
    }
}

/// How well a simulated phase histogram, blurred by jitter and mixed with a flat share,
/// explains a recorded one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeFit {
    /// The squared Hellinger distance of the two normalised histograms (0 to 2).
    pub cost: f64,
    /// The timestamp jitter's standard deviation, µs.
    pub jitter_us: f64,
    /// The flat share.
    pub noise_share: f64,
}

/// Jitter standard deviations tried, in bins (0: none).
const JITTER_BINS: [f64; 7] = [0.0, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0];

/// `histogram` blurred by a Gaussian of `sigma` bins, wrapped around the period.
fn blurred(histogram: &[f64; BINS], sigma: f64) -> [f64; BINS] {
    if sigma <= 0.0 {
        return *histogram;
    }
    let n = BINS as isize;
    let weight = |d: isize| -> f64 {
        (-1..=1)
            .map(|m| {
                let z = (d + m * n) as f64 / sigma;
                (-0.5 * z * z).exp()
            })
            .sum()
    };
    let kernel: Vec<f64> = (0..n).map(weight).collect();
    let total: f64 = kernel.iter().sum();
    let mut out = [0.0; BINS];
    for (i, o) in out.iter_mut().enumerate() {
        *o = (0..BINS)
            .map(|j| histogram[j] * kernel[(i as isize - j as isize).rem_euclid(n) as usize])
            .sum::<f64>()
            / total;
    }
    out
}

fn normalised<const N: usize>(counts: &[u64; N]) -> Option<[f64; N]> {
    let total: u64 = counts.iter().sum();
    (total > 0).then(|| counts.map(|c| c as f64 / total as f64))
}

/// The jitter and flat share (at most `noise_max`) that bring `simulated` closest to
/// `real`; `None` when either holds no events.
pub fn shape_fit(
    real: &[u64; BINS],
    simulated: &[u64; BINS],
    period_us: f64,
    noise_max: f64,
) -> Option<ShapeFit> {
    let simulated = normalised(simulated)?;
    let flat = [1.0 / BINS as f64; BINS];
    let shapes =
        JITTER_BINS.map(|sigma| (sigma * period_us / BINS as f64, blurred(&simulated, sigma)));
    mixture_fit(real, &shapes, &flat, noise_max)
}

/// The shape of `shapes` (each with its jitter, µs) and the share (at most `noise_max`) of
/// `flat` whose mixture is closest to `real` in squared Hellinger distance.
fn mixture_fit<const N: usize>(
    real: &[u64; N],
    shapes: &[(f64, [f64; N])],
    flat: &[f64; N],
    noise_max: f64,
) -> Option<ShapeFit> {
    let root_real = normalised(real)?.map(f64::sqrt);
    let mut best = ShapeFit {
        cost: f64::INFINITY,
        jitter_us: 0.0,
        noise_share: 0.0,
    };
    let shares = (noise_max.clamp(0.0, 1.0) * 100.0).floor() as usize;
    for (jitter_us, shape) in shapes {
        for k in 0..=shares {
            let u = k as f64 / 100.0;
            let cost: f64 = (0..N)
                .map(|i| (((1.0 - u) * shape[i] + u * flat[i]).sqrt() - root_real[i]).powi(2))
                .sum();
            if cost < best.cost {
                best = ShapeFit {
                    cost,
                    jitter_us: *jitter_us,
                    noise_share: u,
                };
            }
        }
    }
    Some(best)
}

/// Lower edges of the delay buckets, in refresh periods since the region last changed:
/// single periods up to 3, then about 1.5 times wider each.
pub const DELAY_EDGES: [u32; 10] = [0, 1, 2, 3, 4, 6, 9, 14, 22, 35];

/// What the phase within a refresh period cannot tell: a photoreceptor so slow that its
/// events are spread evenly over the period (a cutoff at white under ~100 Hz) still
/// fires them within a few of its time constants of the change that caused them, so the
/// events are counted by how many refresh periods after the last change of their region
/// (a [`super::TILE_PX`]-pixel tile) they come. A region changes where the ideal
/// simulation fires.
pub struct Changes {
    tile_px: usize,
    tiles_x: usize,
    width: usize,
    clock: RefreshClock,
    refreshes: usize,
    /// Per tile and refresh period, the last period at or before it with a change.
    last: Vec<Option<u32>>,
    /// Per tile, its included pixels.
    pixels: Vec<u32>,
}

/// Events per delay bucket ([`DELAY_EDGES`]), per polarity.
#[derive(Clone, Debug, PartialEq)]
pub struct DelayHistogram {
    pub on: [u64; DELAY_EDGES.len()],
    pub off: [u64; DELAY_EDGES.len()],
}

impl Changes {
    /// The changes the ideal simulation's `ideal` events mark.
    pub fn from_ideal(
        ideal: &EventChunk,
        clock: RefreshClock,
        sensor: (usize, usize),
        tile_px: usize,
        included: &[bool],
    ) -> Self {
        let (width, height) = sensor;
        let tiles_x = width.div_ceil(tile_px);
        let tiles = tiles_x * height.div_ceil(tile_px);
        let refreshes =
            ((clock.end_us - clock.start_us) as f64 / clock.period_us).ceil() as usize + 1;
        let mut changed = vec![false; tiles * refreshes];
        let mut changes = Changes {
            tile_px,
            tiles_x,
            width,
            clock,
            refreshes,
            last: Vec::new(),
            pixels: vec![0; tiles],
        };
        for (p, _) in included.iter().enumerate().filter(|(_, i)| **i) {
            let tile = changes.tile(p % width, p / width);
            changes.pixels[tile] += 1;
        }
        for i in 0..ideal.len() {
            if let Some(k) = changes.period(ideal.t[i]) {
                let tile = changes.tile(ideal.x[i] as usize, ideal.y[i] as usize);
                changed[tile * refreshes + k] = true;
            }
        }
        changes.last = (0..tiles * refreshes)
            .scan(None, |last, slot| {
                if slot % refreshes == 0 {
                    *last = None;
                }
                if changed[slot] {
                    *last = Some((slot % refreshes) as u32);
                }
                Some(*last)
            })
            .collect();
        changes
    }

    fn tile(&self, x: usize, y: usize) -> usize {
        (y / self.tile_px) * self.tiles_x + x / self.tile_px
    }

    /// The refresh period of time `t`, each starting half a period before its refresh
    /// (a change's events and their jitter fall in its own).
    fn period(&self, t: TimeUs) -> Option<usize> {
        let k = ((t - self.clock.start_us) as f64 / self.clock.period_us + 0.5).floor();
        (k >= 0.0 && (k as usize) < self.refreshes).then_some(k as usize)
    }

    fn bucket(delay: u32) -> usize {
        DELAY_EDGES.partition_point(|&e| e <= delay) - 1
    }

    /// The delay histogram of `events` at included pixels (events in a region before its
    /// first change are left out).
    pub fn histogram(&self, events: &EventChunk, included: &[bool]) -> DelayHistogram {
        let mut h = DelayHistogram {
            on: [0; DELAY_EDGES.len()],
            off: [0; DELAY_EDGES.len()],
        };
        for i in 0..events.len() {
            let (x, y) = (events.x[i] as usize, events.y[i] as usize);
            let Some(k) = self.period(events.t[i]) else {
                continue;
            };
            let tile = self.tile(x, y);
            let (true, Some(last)) = (
                included[y * self.width + x],
                self.last[tile * self.refreshes + k],
            ) else {
                continue;
            };
            let bucket = Self::bucket(k as u32 - last);
            if events.on[i] {
                h.on[bucket] += 1;
            } else {
                h.off[bucket] += 1;
            }
        }
        h
    }

    /// Where events unrelated to the changes fall: the included pixels' refresh periods
    /// per bucket, as shares.
    pub fn flat(&self) -> [f64; DELAY_EDGES.len()] {
        let mut slots = [0.0; DELAY_EDGES.len()];
        for (slot, last) in self.last.iter().enumerate() {
            if let Some(last) = last {
                let tile = slot / self.refreshes;
                slots[Self::bucket((slot % self.refreshes) as u32 - last)] +=
                    self.pixels[tile] as f64;
            }
        }
        let total: f64 = slots.iter().sum::<f64>().max(1e-12);
        slots.map(|s| s / total)
    }
}

/// How well a simulated delay histogram, mixed with events unrelated to the changes,
/// explains a recorded one.
pub fn delay_fit(
    real: &[u64; DELAY_EDGES.len()],
    simulated: &[u64; DELAY_EDGES.len()],
    flat: &[f64; DELAY_EDGES.len()],
    noise_max: f64,
) -> Option<ShapeFit> {
    mixture_fit(real, &[(0.0, normalised(simulated)?)], flat, noise_max)
}

/// The largest share of events that may be unrelated to the refreshes: twice the share of
/// recorded events no neighbour supports within `window_us` either side (noise is isolated
/// in quiet regions and supported by chance in busy ones, so the isolated share is its
/// lower part), plus 2 %.
pub fn noise_share_bound(
    events: &EventChunk,
    sensor: Sensor,
    window_us: TimeUs,
    included: &[bool],
) -> f64 {
    let supported = crate::stats::support::supported_two_sided(events, sensor, window_us);
    let width = sensor.width as usize;
    let (mut kept, mut isolated) = (0usize, 0usize);
    for (i, &s) in supported.iter().enumerate() {
        if included[events.y[i] as usize * width + events.x[i] as usize] {
            kept += 1;
            isolated += usize::from(!s);
        }
    }
    (2.0 * isolated as f64 / kept.max(1) as f64 + 0.02).min(0.95)
}

/// One cutoff's match: the phases and the delays, per polarity.
#[derive(Clone, Copy, Debug)]
pub struct LagPoint {
    /// `None`: ideal pixels.
    pub cutoff_hz: Option<f64>,
    pub on: Option<ShapeFit>,
    pub off: Option<ShapeFit>,
    pub on_delay: Option<ShapeFit>,
    pub off_delay: Option<ShapeFit>,
}

impl LagPoint {
    /// The four distances' sum (infinite where a polarity has no events).
    pub fn cost(&self) -> f64 {
        [self.on, self.off, self.on_delay, self.off_delay]
            .iter()
            .map(|f| f.map_or(f64::INFINITY, |f| f.cost))
            .sum()
    }
}

/// The match of every cutoff tried.
#[derive(Clone, Debug)]
pub struct LagProfile {
    pub points: Vec<LagPoint>,
    pub noise_max: f64,
}

impl LagProfile {
    fn ideal(&self) -> Option<&LagPoint> {
        self.points.iter().find(|p| p.cutoff_hz.is_none())
    }

    fn best(&self) -> Option<&LagPoint> {
        self.points
            .iter()
            .filter(|p| p.cost().is_finite())
            .min_by(|a, b| a.cost().total_cmp(&b.cost()))
    }

    /// The cutoff the timing calls for: `None` when ideal pixels explain it as well (within
    /// [`DECISIVE`]).
    pub fn cutoff_hz(&self) -> Option<f64> {
        let best = self.best()?;
        let ideal = self.ideal().map_or(f64::INFINITY, LagPoint::cost);
        best.cutoff_hz.filter(|_| best.cost() <= DECISIVE * ideal)
    }

    /// The pixel model the thresholds were matched with, in words for the assumptions.
    pub fn says(&self) -> String {
        let grid = format!(
            "{} to {} Hz at 255 camera DN",
            GRID_HZ[GRID_HZ.len() - 1],
            GRID_HZ[0]
        );
        match self.cutoff_hz() {
            Some(c) => format!(
                "pixels without noise (the thresholds dithered +-5 %; the log response above) whose photoreceptor lags: a cutoff of {c:.0} Hz at 255 camera DN, scaling as (DN + 20) / 275, measured from when the events come (the cutoff of {grid}, refined a quarter decade either side, whose simulated events match best in their phase within the refresh period and in the refresh periods since their region last changed, jitter and a flat share of at most {:.0} % fitted); the display was fitted with ideal pixels and the thresholds matched again through it with this photoreceptor, half the correction taken as a systematic error",
                100.0 * self.noise_max
            ),
            None => format!(
                "ideal pixels (no noise or photoreceptor lag, the thresholds dithered +-5 %; the log response above): when the events come shows no lag (no cutoff of {grid} matches their phase within the refresh period and the refresh periods since their region last changed better than ideal pixels by a factor {:.0}, jitter and a flat share of at most {:.0} % fitted)",
                1.0 / DECISIVE,
                100.0 * self.noise_max
            ),
        }
    }

    pub fn json(&self) -> serde_json::Value {
        let fit = |f: &Option<ShapeFit>| {
            f.map(
                |f| json!({"cost": f.cost, "jitter_us": f.jitter_us, "noise_share": f.noise_share}),
            )
        };
        json!({
            "noise_share_max": self.noise_max,
            "points": self.points.iter().map(|p| json!({
                "cutoff_hz": p.cutoff_hz,
                "on": fit(&p.on),
                "off": fit(&p.off),
                "on_delay": fit(&p.on_delay),
                "off_delay": fit(&p.off_delay),
            })).collect::<Vec<_>>(),
        })
    }
}

/// What the profile compares against: the recording's events at the included pixels,
/// their phase histogram and the bound of their flat share.
pub(super) struct Recorded<'a> {
    events: &'a EventChunk,
    histogram: PhaseHistogram,
    clock: RefreshClock,
    included: Vec<bool>,
    sensor: (usize, usize),
    noise_max: f64,
}

impl<'a> Recorded<'a> {
    /// `events` at the `included` pixels; isolated events are those without a neighbour
    /// within two refresh periods (at least 5 ms) either side.
    pub fn new(
        events: &'a EventChunk,
        clock: RefreshClock,
        included: Vec<bool>,
        sensor: Sensor,
    ) -> Self {
        let width = sensor.width as usize;
        let window_us = (2.0 * clock.period_us).max(5_000.0) as TimeUs;
        Self {
            histogram: PhaseHistogram::of(events, clock, &included, width),
            noise_max: noise_share_bound(events, sensor, window_us, &included),
            events,
            clock,
            included,
            sensor: (width, sensor.height as usize),
        }
    }
}

/// The recording's delays and what the simulations' are compared with.
struct Reference<'a> {
    recorded: &'a Recorded<'a>,
    changes: Changes,
    delays: DelayHistogram,
    flat: [f64; DELAY_EDGES.len()],
}

impl Reference<'_> {
    /// The match of simulated `events` made at `cutoff_hz`.
    fn point(&self, cutoff_hz: Option<f64>, events: &EventChunk) -> LagPoint {
        let r = self.recorded;
        let phases = PhaseHistogram::of(events, r.clock, &r.included, r.sensor.0);
        let delays = self.changes.histogram(events, &r.included);
        let period = r.clock.period_us;
        LagPoint {
            cutoff_hz,
            on: shape_fit(&r.histogram.on, &phases.on, period, r.noise_max),
            off: shape_fit(&r.histogram.off, &phases.off, period, r.noise_max),
            on_delay: delay_fit(&self.delays.on, &delays.on, &self.flat, r.noise_max),
            off_delay: delay_fit(&self.delays.off, &delays.off, &self.flat, r.noise_max),
        }
    }
}

/// The profile over [`GRID_HZ`] and ideal pixels, refined a quarter decade either side of
/// the best grid cutoff; every simulation at thresholds `ct`, through `display` (`None`:
/// the naive simulation).
pub(super) fn profile(
    setup: &Setup,
    recorded: &Recorded,
    ct: (f64, f64),
    display: Option<&DisplayParams>,
) -> Result<LagProfile, EstimateError> {
    let ideal = setup.events_at(ct, display, None)?;
    let changes = Changes::from_ideal(
        &ideal,
        recorded.clock,
        recorded.sensor,
        super::TILE_PX,
        &recorded.included,
    );
    let reference = Reference {
        delays: changes.histogram(recorded.events, &recorded.included),
        flat: changes.flat(),
        changes,
        recorded,
    };
    let at = |cutoff_hz: f64| -> Result<LagPoint, EstimateError> {
        let events = setup.events_at(ct, display, Some(cutoff_hz))?;
        Ok(reference.point(Some(cutoff_hz), &events))
    };
    let mut points = vec![reference.point(None, &ideal)];
    points.extend(
        GRID_HZ
            .par_iter()
            .map(|&c| at(c))
            .collect::<Result<Vec<_>, _>>()?,
    );
    let mut profile = LagProfile {
        points,
        noise_max: recorded.noise_max,
    };
    if let Some(c) = profile.best().and_then(|p| p.cutoff_hz) {
        let step = 10f64.powf(0.25);
        let refined = [c / step, c * step]
            .par_iter()
            .map(|&c| at(c))
            .collect::<Result<Vec<_>, _>>()?;
        profile.points.extend(refined);
    }
    Ok(profile)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn delta() -> [u64; BINS] {
        let mut h = [0; BINS];
        h[0] = 10_000;
        h
    }

    #[test]
    fn a_histogram_fits_itself_at_no_cost() {
        let h = delta();
        let fit = shape_fit(&h, &h, 8000.0, 0.5).unwrap();
        assert_eq!(fit.cost, 0.0);
        assert_eq!((fit.jitter_us, fit.noise_share), (0.0, 0.0));
    }

    #[test]
    fn jitter_and_a_flat_share_are_found() {
        // ideal events blurred by 2 bins (500 us of an 8 ms period) and 20 % flat
        let mut blur = [0.0; BINS];
        blur[0] = 1.0;
        let blur = blurred(&blur, 2.0);
        let real: [u64; BINS] =
            std::array::from_fn(|i| ((0.8 * blur[i] + 0.2 / BINS as f64) * 1e6).round() as u64);
        let fit = shape_fit(&real, &delta(), 8000.0, 0.5).unwrap();
        assert!((fit.jitter_us - 500.0).abs() < 1.0, "{fit:?}");
        assert!((fit.noise_share - 0.2).abs() < 0.011, "{fit:?}");
        assert!(fit.cost < 1e-4, "{fit:?}");
        // with the flat share bounded below the truth, the fit is worse
        let bounded = shape_fit(&real, &delta(), 8000.0, 0.05).unwrap();
        assert!(bounded.cost > 10.0 * fit.cost.max(1e-6), "{bounded:?}");
    }

    #[test]
    fn delays_count_refresh_periods_since_the_region_changed() {
        // one 4-pixel tile of an 8x4 sensor changes at the refreshes 2 and 10 (10 ms period)
        let clock = RefreshClock {
            start_us: 0,
            period_us: 10_000.0,
            end_us: 200_000,
        };
        let mut ideal = EventChunk::default();
        ideal.push(20_000, 1, 1, true);
        ideal.push(100_000, 2, 2, false);
        let included = vec![true; 32];
        let changes = Changes::from_ideal(&ideal, clock, (8, 4), 4, &included);
        let mut events = EventChunk::default();
        // before the first change (left out), at it (delay 0), 4 ms early for it (its own
        // period), 5 periods later (bucket [4, 6)), after the second change (delay 1), and
        // in the other tile, which never changes (left out)
        for (t, x) in [
            (5_000, 0),
            (20_000, 0),
            (16_000, 3),
            (70_000, 1),
            (110_000, 1),
            (20_000, 5),
        ] {
            events.push(t, x, 0, true);
        }
        let h = changes.histogram(&events, &included);
        assert_eq!(h.on[..5], [2, 1, 0, 0, 1]);
        assert_eq!(h.on.iter().sum::<u64>(), 4);
        // the flat share: the changing tile's periods from its first change on
        let flat = changes.flat();
        assert!((flat.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        // periods 2..=20 (19 of them): delays 0-7 after the first change, 0-10 after the
        // second: delay 0 twice
        assert!((flat[0] - 2.0 / 19.0).abs() < 1e-12, "{flat:?}");
    }

    #[test]
    fn phases_are_binned_around_the_refresh() {
        let mut events = EventChunk::default();
        // refreshes every 10 ms from 1 ms: an event at a refresh, one 1/32 period after,
        // one just before the next refresh (bin 0, centred on the refresh)
        for (t, p) in [(1_000, true), (1_000 + 312, true), (10_990, false)] {
            events.push(t, 0, 0, p);
        }
        let clock = RefreshClock {
            start_us: 1_000,
            period_us: 10_000.0,
            end_us: 101_000,
        };
        let h = PhaseHistogram::of(&events, clock, &[true], 1);
        assert_eq!(h.on[0], 1);
        assert_eq!(h.on[1], 1);
        assert_eq!(h.off[0], 1);
    }
}
