//! What each block of a recording without frames says about the pixel's noise, measured
//! once so that every model is compared on the same numbers:
//!
//! - **isolated events at quiet pixels**, per polarity, per support window
//!   ([`SUPPORT_WINDOWS_US`]) and neighbourhood radius ([`SUPPORT_RADII_PX`]): events without a
//!   neighbour event within ±window (the background-activity filter of Delbruck 2008,
//!   [`crate::stats::support`]), at pixels whose neighbourhood leaves them uncovered at least
//!   half the time, over the seconds each pixel was uncovered. Noise is Poisson and
//!   independent of the neighbours, so isolated events over uncovered time is its rate
//!   whatever the window and radius (the time a neighbour's event would have hidden a noise
//!   event is taken out exactly, as the union of the ±window spans); the scene's own events
//!   are not: isolated under a short window when the scene moves slowly, they fall away as
//!   the window grows, and isolated from their 8 neighbours when an edge crosses one
//!   pixel's threshold and not theirs (high thresholds, mismatch), they fall away as the
//!   neighbourhood widens ([`choose_isolation`]);
//! - **supported events** per polarity (the scene's own events, for the ON/OFF balance);
//! - **same-pixel intervals** (any polarity), for the refractory period;
//! - **each named hot pixel's events**.
//!
//! Hot pixels' events are taken out before the rest is measured (they would cover their
//! neighbours' time).

use crate::events::{EventChunk, Sensor, TimeUs};
use rayon::prelude::*;

/// The support windows: the first is `ctcal stats`'s (an edge crossing a pixel faster than
/// 100 px/s gives its neighbours events well within it); the longer ones take in slower
/// scenes.
pub const SUPPORT_WINDOWS_US: [TimeUs; 4] = [10_000, 30_000, 100_000, 300_000];
/// The neighbourhoods' radii (Chebyshev distance, px): 1 is the 3 x 3 of the
/// background-activity filter, 2 and 3 the 5 x 5 and 7 x 7.
pub const SUPPORT_RADII_PX: [usize; 3] = [1, 2, 3];

/// Which support an isolated event lacks: indices into [`SUPPORT_WINDOWS_US`] and
/// [`SUPPORT_RADII_PX`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Isolation {
    pub window: usize,
    pub radius: usize,
}

impl Isolation {
    pub fn window_us(self) -> TimeUs {
        SUPPORT_WINDOWS_US[self.window]
    }

    pub fn radius_px(self) -> usize {
        SUPPORT_RADII_PX[self.radius]
    }

    /// Where a block keeps its count (window-major).
    fn index(self) -> usize {
        self.window * SUPPORT_RADII_PX.len() + self.radius
    }
}

/// A pixel is quiet in a block when its neighbours leave it uncovered this share of the time.
pub const QUIET_SHARE: f64 = 0.5;

/// The measurements of one block.
#[derive(Clone, Debug, Default)]
pub struct BlockMeasure {
    pub seconds: f64,
    /// Kept pixels times seconds.
    pub pixel_seconds: f64,
    /// Isolated events at quiet pixels, per support window and radius ([`Isolation`]).
    pub isolated: Vec<Isolated>,
    /// Supported events, ON and OFF (kept pixels).
    pub signal_on: u64,
    pub signal_off: u64,
    /// Same-pixel intervals ending in this block, µs (kept pixels).
    pub intervals: Vec<u32>,
    /// Events of each named hot pixel (the order of the list).
    pub hot_events: Vec<u64>,
    /// Events per kept pixel per second, hot pixels left out.
    pub pixel_rate_hz: f64,
    /// Supported events (under the shortest window) per kept pixel per second.
    pub signal_rate_hz: f64,
}

/// Isolated events at quiet pixels under one support window.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Isolated {
    pub on: u64,
    pub off: u64,
    /// Pixel-seconds the quiet pixels were uncovered.
    pub pixel_seconds: f64,
}

impl BlockMeasure {
    /// Isolated events under `iso` over `blocks`.
    pub fn isolated(blocks: &[&BlockMeasure], iso: Isolation) -> Isolated {
        let k = iso.index();
        blocks.iter().fold(Isolated::default(), |a, b| Isolated {
            on: a.on + b.isolated[k].on,
            off: a.off + b.isolated[k].off,
            pixel_seconds: a.pixel_seconds + b.isolated[k].pixel_seconds,
        })
    }

    /// The isolated-event rate of one polarity under `iso` (Hz per pixel) and its Poisson
    /// standard error, `None` without uncovered time.
    pub fn isolated_rate(blocks: &[&BlockMeasure], iso: Isolation, on: bool) -> Option<(f64, f64)> {
        let i = Self::isolated(blocks, iso);
        let n = if on { i.on } else { i.off };
        (i.pixel_seconds > 0.0).then(|| {
            (
                n as f64 / i.pixel_seconds,
                (n.max(1) as f64).sqrt() / i.pixel_seconds,
            )
        })
    }
}

/// Both polarities' isolated rate under `iso`, its Poisson standard error and the quiet
/// pixel-seconds it was counted over.
fn total_rate(fit: &[&BlockMeasure], iso: Isolation) -> Option<(f64, f64, f64)> {
    let i = BlockMeasure::isolated(fit, iso);
    (i.pixel_seconds > 0.0).then(|| {
        let n = (i.on + i.off) as f64;
        (
            n / i.pixel_seconds,
            n.max(1.0).sqrt() / i.pixel_seconds,
            i.pixel_seconds,
        )
    })
}

/// Whether the rate `to` lies below `from` by more than two standard errors.
fn falls(from: (f64, f64, f64), to: (f64, f64, f64)) -> bool {
    to.0 < from.0 - 2.0 * (from.1 * from.1 + to.1 * to.1).sqrt()
}

/// A wider support is judged only where it keeps this share of the first support's quiet
/// time (less, and its rate is too uncertain to tell a fall from none).
const JUDGED_QUIET: f64 = 0.2;

/// Below this share of the fit blocks' pixel time left quiet, isolated events that no wider
/// support could check are not taken for noise. Noise of `r` Hz a pixel (ON + OFF) leaves a
/// pixel uncovered `exp(-2 N r W)` of the time (`N` neighbours within the support's radius,
/// ±W its window), and a pixel is quiet when uncovered at least [`QUIET_SHARE`] of a block,
/// so quiet pixels stay most of the sensor up to `r = ln 2 / (2 N W)` (4.3 Hz under 3 x 3 and
/// ±10 ms, where noise alone is measured) and their share of the pixel time falls below a
/// tenth at 1.2-1.6 times that (Poisson noise simulated: 5 Hz with 1 s blocks, 7 Hz with
/// 0.1 s blocks, whose uncovered fractions spread more); a scene that covers nearly
/// every pixel nearly all the time leaves quiet only where its activity thins out, and the
/// isolated events there are mostly its own: coverage draw 6024 (61 events per pixel per
/// second, 0.2 % of the pixel time quiet) read 0.84 Hz a polarity where the shot noise is
/// 0.025 Hz a polarity and the leak 0.80 Hz ON.
pub const CONFIRMING_QUIET_SHARE: f64 = 0.1;

/// Why the isolated-event rate is only an upper bound on the noise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum UpperBound {
    /// It was still falling as the support grew, where quiet time ran out or at the widest
    /// radius.
    StillFalling,
    /// The scene left only `quiet_share` of the pixel time quiet, and no wider support kept
    /// enough of it to check the rate ([`CONFIRMING_QUIET_SHARE`]).
    Unconfirmed { quiet_share: f64 },
}

/// The support the noise is measured under, and whether a wider one confirmed it (was
/// judged and did not lower the rate).
struct Chosen {
    index: usize,
    still_falling: bool,
    confirmed: bool,
}

/// The support window the noise is measured under (8 neighbours): the shortest after which
/// a longer one no longer lowers the rate significantly (the scene's slow events are
/// supported by then) while keeping a fifth of the shortest window's quiet time.
/// `still_falling` when the rate was still falling where the quiet time ran out: the rate
/// is then an upper bound.
fn choose_window(fit: &[&BlockMeasure]) -> Chosen {
    let at = |window| Isolation { window, radius: 0 };
    let mut chosen = Chosen {
        index: 0,
        still_falling: false,
        confirmed: false,
    };
    let Some(mut rate) = total_rate(fit, at(0)) else {
        return chosen;
    };
    let first = rate.2;
    for k in 1..SUPPORT_WINDOWS_US.len() {
        let Some(next) = total_rate(fit, at(k)) else {
            chosen.still_falling = true;
            return chosen;
        };
        if !falls(rate, next) {
            chosen.confirmed = next.2 >= JUDGED_QUIET * first;
            return chosen;
        }
        if next.2 < JUDGED_QUIET * first {
            chosen.still_falling = true;
            return chosen;
        }
        (chosen.index, rate) = (k, next);
    }
    chosen
}

/// The support the noise is measured under: the window of [`choose_window`], then the
/// narrowest neighbourhood after which a wider one no longer lowers the rate by two
/// standard errors, keeping a fifth of the 8-neighbourhood's quiet time. An upper bound
/// ([`UpperBound`]) when the window's rate was still falling, when the rate fell at the last
/// step that could be judged (at the widest radius, or where a wider one left too little
/// quiet time), or when no wider support could check it and the scene left less than
/// [`CONFIRMING_QUIET_SHARE`] of the pixel time quiet.
/// Coverage draw 6035 (no noise; a dim texture at 550 px/s, thresholds 0.54 / 0.61 under
/// mismatch), fitted from its events, read 0.16 Hz of shot noise [0.15, 0.65] from events
/// its 8 neighbours did not support: 0.21, 0.05 and 0.02 Hz per pixel (ON + OFF) at radii
/// 1, 2 and 3, where draw 6016 (0.45 Hz of shot noise) reads 0.39 at radii 1 and 3.
pub fn choose_isolation(fit: &[&BlockMeasure]) -> (Isolation, Option<UpperBound>) {
    let window = choose_window(fit);
    let mut chosen = Isolation {
        window: window.index,
        radius: 0,
    };
    if window.still_falling {
        return (chosen, Some(UpperBound::StillFalling));
    }
    let Some(mut rate) = total_rate(fit, chosen) else {
        return (chosen, None);
    };
    let first = rate.2;
    let mut confirmed = window.confirmed;
    let mut fell = false;
    for radius in 1..SUPPORT_RADII_PX.len() {
        let wider = Isolation {
            window: window.index,
            radius,
        };
        let Some(next) = total_rate(fit, wider).filter(|r| r.2 >= JUDGED_QUIET * first) else {
            break;
        };
        if !falls(rate, next) {
            confirmed = true;
            fell = false;
            break;
        }
        (chosen, rate, fell) = (wider, next, true);
    }
    if fell {
        return (chosen, Some(UpperBound::StillFalling));
    }
    let quiet_share = quiet_share(fit, chosen);
    let unconfirmed = !confirmed && quiet_share < CONFIRMING_QUIET_SHARE;
    (
        chosen,
        unconfirmed.then_some(UpperBound::Unconfirmed { quiet_share }),
    )
}

/// The share of the blocks' pixel time (kept pixels times seconds) left quiet under
/// `support`: the time the noise rate rests on.
pub fn quiet_share(fit: &[&BlockMeasure], support: Isolation) -> f64 {
    let pixel_seconds: f64 = fit.iter().map(|b| b.pixel_seconds).sum();
    BlockMeasure::isolated(fit, support).pixel_seconds / pixel_seconds.max(1e-12)
}

/// The recording, split for measuring.
pub struct Measuring<'a> {
    pub events: &'a EventChunk,
    pub sensor: Sensor,
    /// Pixels left out (the user's mask).
    pub excluded: &'a [bool],
    /// Named hot pixels (x, y).
    pub hot: &'a [(u16, u16)],
}

impl Measuring<'_> {
    /// Whether each pixel is measured: not masked, not a named hot pixel.
    pub fn kept_pixels(&self) -> Vec<bool> {
        let w = self.sensor.width as usize;
        let mut kept: Vec<bool> = self.excluded.iter().map(|e| !e).collect();
        for &(x, y) in self.hot {
            kept[y as usize * w + x as usize] = false;
        }
        kept
    }
}

/// Measures every block (`spans`, in time order).
pub fn measure(m: &Measuring, spans: &[(TimeUs, TimeUs)]) -> Vec<BlockMeasure> {
    let w = m.sensor.width as usize;
    let kept = m.kept_pixels();
    let (clean, hot_events) = without_hot_pixels(m, spans, &kept);
    let kept_pixels = kept.iter().filter(|&&k| k).count().max(1);
    let ranges: Vec<std::ops::Range<usize>> = spans
        .iter()
        .map(|span| {
            clean.t.partition_point(|&t| t < span.0)..clean.t.partition_point(|&t| t < span.1)
        })
        .collect();
    let mut blocks = sized_blocks(spans, hot_events, &ranges, kept_pixels);
    let mut last = vec![TimeUs::MIN; w * m.sensor.height as usize];
    for (b, range) in blocks.iter_mut().zip(&ranges) {
        b.intervals = super::refractory::intervals(&clean, range.clone(), w, &mut last, None);
    }
    let measured = isolated_under_every_support(m, &clean, spans, &kept);
    for (k, per_block) in measured.into_iter().enumerate() {
        for (b, (isolated, signal)) in blocks.iter_mut().zip(per_block) {
            b.isolated.push(isolated);
            if k == 0 {
                (b.signal_on, b.signal_off) = signal;
                b.signal_rate_hz =
                    (signal.0 + signal.1) as f64 / (kept_pixels as f64 * b.seconds.max(1e-9));
            }
        }
    }
    blocks
}

/// The events of the kept pixels in the blocks (the clean events, masked and named hot
/// pixels out), and each block's events of each named hot pixel.
fn without_hot_pixels(
    m: &Measuring,
    spans: &[(TimeUs, TimeUs)],
    kept: &[bool],
) -> (EventChunk, Vec<Vec<u64>>) {
    let (w, h) = (m.sensor.width as usize, m.sensor.height as usize);
    let mut hot_index = vec![u32::MAX; w * h];
    for (k, &(x, y)) in m.hot.iter().enumerate() {
        hot_index[y as usize * w + x as usize] = k as u32;
    }
    let mut clean = EventChunk::with_capacity(m.events.len());
    let mut hot_events = vec![Vec::new(); spans.len()];
    for (b, span) in spans.iter().enumerate() {
        let mut counts = vec![0u64; m.hot.len()];
        let from = m.events.t.partition_point(|&t| t < span.0);
        let to = m.events.t.partition_point(|&t| t < span.1);
        for i in from..to {
            let p = m.events.y[i] as usize * w + m.events.x[i] as usize;
            if hot_index[p] != u32::MAX {
                counts[hot_index[p] as usize] += 1;
            } else if kept[p] {
                clean.push(m.events.t[i], m.events.x[i], m.events.y[i], m.events.on[i]);
            }
        }
        hot_events[b] = counts;
    }
    (clean, hot_events)
}

/// Each block's length, kept pixel-seconds, hot pixels' events and event rate (its clean
/// events are `ranges`), the rest to measure.
fn sized_blocks(
    spans: &[(TimeUs, TimeUs)],
    hot_events: Vec<Vec<u64>>,
    ranges: &[std::ops::Range<usize>],
    kept_pixels: usize,
) -> Vec<BlockMeasure> {
    spans
        .iter()
        .zip(hot_events)
        .zip(ranges)
        .map(|((&span, hot_events), range)| {
            let seconds = (span.1 - span.0) as f64 * 1e-6;
            BlockMeasure {
                seconds,
                pixel_seconds: kept_pixels as f64 * seconds,
                hot_events,
                pixel_rate_hz: range.len() as f64 / (kept_pixels as f64 * seconds),
                ..BlockMeasure::default()
            }
        })
        .collect()
}

/// The isolated events and supported (ON, OFF) counts of each block ([`isolated`]) under
/// every support window and radius, window-major as [`Isolation::index`], the supports
/// measured in parallel.
fn isolated_under_every_support(
    m: &Measuring,
    clean: &EventChunk,
    spans: &[(TimeUs, TimeUs)],
    kept: &[bool],
) -> Vec<Vec<(Isolated, (u64, u64))>> {
    let nears: Vec<Near> = SUPPORT_WINDOWS_US
        .into_iter()
        .flat_map(|window| {
            SUPPORT_RADII_PX.map(|radius| Near {
                window,
                radius,
                sensor: m.sensor,
            })
        })
        .collect();
    nears
        .par_iter()
        .map(|&near| {
            let support = crate::stats::support::supported_two_sided_within(
                clean,
                m.sensor,
                near.window,
                near.radius,
            );
            spans
                .iter()
                .map(|&span| isolated(clean, &support, span, near, kept))
                .collect()
        })
        .collect()
}

/// The neighbourhood an event's support is looked for in.
#[derive(Clone, Copy)]
struct Near {
    window: TimeUs,
    radius: usize,
    sensor: Sensor,
}

/// Isolated events at quiet pixels of the clean events (hot and masked pixels out) in
/// `span` under `near`, and the supported (ON, OFF) counts. Neighbour events up to a
/// window outside the span cover it too (they support events inside it).
fn isolated(
    clean: &EventChunk,
    support: &[bool],
    span: (TimeUs, TimeUs),
    near: Near,
    kept: &[bool],
) -> (Isolated, (u64, u64)) {
    let (w, h) = (near.sensor.width as usize, near.sensor.height as usize);
    let window = near.window;
    let mut cover = Cover::new(w * h, span.0);
    let mut alone = vec![[0u32; 2]; w * h];
    let mut signal = (0u64, 0u64);
    let from = clean.t.partition_point(|&t| t < span.0 - window);
    let to = clean.t.partition_point(|&t| t < span.1 + window);
    #[allow(clippy::needless_range_loop)] // five columns of one event share the index
    for i in from..to {
        let (t, x, y, on) = (
            clean.t[i],
            clean.x[i] as usize,
            clean.y[i] as usize,
            clean.on[i],
        );
        let p = y * w + x;
        if (span.0..span.1).contains(&t) {
            match (support[i], on) {
                (true, true) => signal.0 += 1,
                (true, false) => signal.1 += 1,
                (false, _) => alone[p][on as usize] += 1,
            }
        }
        let lit = ((t - window).max(span.0), (t + window).min(span.1));
        cover.around((x, y), lit, near.radius, (w, h));
    }
    (quiet_isolated(&cover.covered, &alone, kept, span), signal)
}

/// How long each pixel was covered by its neighbours' events within a span, µs: the union
/// of their ±window spans, counted up to `until`, the end of the cover counted so far.
struct Cover {
    until: Vec<TimeUs>,
    covered: Vec<TimeUs>,
}

impl Cover {
    /// No pixel of `pixels` covered yet, the span starting at `start`.
    fn new(pixels: usize, start: TimeUs) -> Self {
        Self {
            until: vec![start; pixels],
            covered: vec![0 as TimeUs; pixels],
        }
    }

    /// Covers the pixels within `r` of `(x, y)`, itself left out, over `(lo, hi)` (the
    /// part not covered already: events come in time order).
    #[inline]
    fn around(
        &mut self,
        (x, y): (usize, usize),
        (lo, hi): (TimeUs, TimeUs),
        r: usize,
        (w, h): (usize, usize),
    ) {
        let p = y * w + x;
        for ny in y.saturating_sub(r)..(y + r + 1).min(h) {
            for nx in x.saturating_sub(r)..(x + r + 1).min(w) {
                let n = ny * w + nx;
                if n == p {
                    continue;
                }
                let start = lo.max(self.until[n]);
                if hi > start {
                    self.covered[n] += hi - start;
                    self.until[n] = hi;
                }
            }
        }
    }
}

/// The isolated events (`alone`, OFF then ON per pixel) of the kept pixels left uncovered
/// at least [`QUIET_SHARE`] of `span`, and the seconds they were uncovered.
fn quiet_isolated(
    covered: &[TimeUs],
    alone: &[[u32; 2]],
    kept: &[bool],
    span: (TimeUs, TimeUs),
) -> Isolated {
    let span_us = span.1 - span.0;
    let mut out = Isolated::default();
    for p in (0..covered.len()).filter(|&p| kept[p]) {
        let uncovered = span_us - covered[p].min(span_us);
        if uncovered as f64 >= QUIET_SHARE * span_us as f64 {
            out.on += alone[p][1] as u64;
            out.off += alone[p][0] as u64;
            out.pixel_seconds += uncovered as f64 * 1e-6;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// Poisson noise at 2 Hz ON and 1 Hz OFF everywhere, plus a bright square where every
    /// pixel fires every 2 ms (covered all the time): the isolated rate is the noise rate.
    #[test]
    fn isolated_events_over_uncovered_time_is_the_noise_rate() {
        let sensor = Sensor::new(40, 30);
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(5);
        let mut all = Vec::new();
        let seconds = 20.0;
        for y in 0..30u16 {
            for x in 0..40u16 {
                for (rate, on) in [(2.0, true), (1.0, false)] {
                    let mut t = 0.0;
                    loop {
                        t += -(1.0 - rng.random::<f64>()).ln() / rate;
                        if t >= seconds {
                            break;
                        }
                        all.push(((t * 1e6) as TimeUs, x, y, on));
                    }
                }
                if x < 10 && y < 10 {
                    for k in 0..(seconds * 500.0) as i64 {
                        all.push((k * 2000 + 7, x, y, k % 2 == 0));
                    }
                }
            }
        }
        all.sort_unstable();
        let mut events = EventChunk::default();
        for (t, x, y, on) in all {
            events.push(t, x, y, on);
        }
        let excluded = vec![false; sensor.pixels()];
        let blocks = measure(
            &Measuring {
                events: &events,
                sensor,
                excluded: &excluded,
                hot: &[(39, 29)],
            },
            &[(0, 10_000_000), (10_000_000, 20_000_000)],
        );
        let refs: Vec<&BlockMeasure> = blocks.iter().collect();
        let (iso, still_falling) = choose_isolation(&refs);
        assert_eq!((iso, still_falling), (Isolation::default(), None));
        let (on, on_se) = BlockMeasure::isolated_rate(&refs, iso, true).unwrap();
        let (off, off_se) = BlockMeasure::isolated_rate(&refs, iso, false).unwrap();
        // ~1090 quiet pixels x 20 s: 2 Hz +- 0.01, 1 Hz +- 0.007
        assert!((on - 2.0).abs() < 4.0 * on_se, "{on} +- {on_se}");
        assert!((off - 1.0).abs() < 4.0 * off_se, "{off} +- {off_se}");
        assert!(on_se < 0.02);
        // the hot pixel's own events are counted apart
        let hot: u64 = blocks.iter().map(|b| b.hot_events[0]).sum();
        assert!((hot as f64 - 60.0).abs() < 4.0 * 60f64.sqrt(), "{hot}");
        // the square's events are supported: 100 pixels x 500 Hz
        let signal: u64 = blocks.iter().map(|b| b.signal_on + b.signal_off).sum();
        assert!(signal >= 100 * 10_000, "{signal}");
    }

    /// Poisson noise at 0.2 Hz per polarity everywhere, and a scene whose events no 8
    /// neighbours support: a line sweeping across the sensor at 50 px/s fires only the
    /// pixels of even x and y (one event a sweep, ON one way, OFF back), so each has
    /// neighbours 2 px away firing with it. Under the 8-neighbourhood the scene's events read
    /// as 0.2 Hz more noise; the 5 x 5 neighbourhood supports them and reads the noise.
    #[test]
    fn a_wider_neighbourhood_takes_out_scene_events_that_no_eight_neighbours_support() {
        let sensor = Sensor::new(60, 40);
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(8);
        let seconds = 20.0;
        let mut all = Vec::new();
        for y in 0..40u16 {
            for x in 0..60u16 {
                for on in [true, false] {
                    let mut t = 0.0;
                    loop {
                        t += -(1.0 - rng.random::<f64>()).ln() / 0.2;
                        if t >= seconds {
                            break;
                        }
                        all.push(((t * 1e6) as TimeUs, x, y, on));
                    }
                }
            }
        }
        let sweep_us = 1_200_000;
        for k in 0..(seconds * 1e6) as i64 / sweep_us {
            for x in (0..60u16).step_by(2) {
                let along = if k % 2 == 0 { x as i64 } else { 59 - x as i64 };
                for y in (0..40u16).step_by(2) {
                    all.push((k * sweep_us + along * 20_000 + 3, x, y, k % 2 == 0));
                }
            }
        }
        all.sort_unstable();
        let mut events = EventChunk::default();
        for (t, x, y, on) in all {
            events.push(t, x, y, on);
        }
        let excluded = vec![false; sensor.pixels()];
        let spans: Vec<(TimeUs, TimeUs)> = (0..4)
            .map(|b| (b * 5_000_000, (b + 1) * 5_000_000))
            .collect();
        let m = Measuring {
            events: &events,
            sensor,
            excluded: &excluded,
            hot: &[],
        };
        let blocks = measure(&m, &spans);
        let refs: Vec<&BlockMeasure> = blocks.iter().collect();
        let (iso, still_falling) = choose_isolation(&refs);
        assert_eq!((iso.radius_px(), still_falling), (2, None), "{iso:?}");
        let eight = Isolation { radius: 0, ..iso };
        let (narrow, _) = BlockMeasure::isolated_rate(&refs, eight, true).unwrap();
        let (on, on_se) = BlockMeasure::isolated_rate(&refs, iso, true).unwrap();
        let (off, off_se) = BlockMeasure::isolated_rate(&refs, iso, false).unwrap();
        assert!(narrow > 0.3, "{narrow}");
        assert!((on - 0.2).abs() < 4.0 * on_se, "{on} +- {on_se}");
        assert!((off - 0.2).abs() < 4.0 * off_se, "{off} +- {off_se}");
    }

    /// One block of 1,000 pixel-seconds whose isolated events are `rates` (ON + OFF, Hz)
    /// over `quiet` pixel-seconds at each support (window-major, as [`Isolation::index`]).
    fn block(rates: [f64; 12], quiet: [f64; 12]) -> BlockMeasure {
        BlockMeasure {
            seconds: 1.0,
            pixel_seconds: 1000.0,
            isolated: rates
                .iter()
                .zip(quiet)
                .map(|(&r, q)| Isolated {
                    on: (r * q / 2.0).round() as u64,
                    off: (r * q / 2.0).round() as u64,
                    pixel_seconds: q,
                })
                .collect(),
            ..BlockMeasure::default()
        }
    }

    /// A scene that leaves 0.3 % of the pixel time quiet (2 Hz of isolated events there)
    /// and no wider support enough quiet time to check them: an upper bound. The same rates
    /// over half the pixel time are the noise; and over 0.3 % they are too where a longer
    /// window keeps enough quiet time and does not lower them.
    #[test]
    fn isolated_events_that_no_wider_support_checks_in_a_busy_scene_are_an_upper_bound() {
        let rates = [2.0; 12];
        let busy = [3.0, 0.3, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1];
        let (iso, bound) = choose_isolation(&[&block(rates, busy)]);
        assert_eq!(iso, Isolation::default());
        match bound {
            Some(UpperBound::Unconfirmed { quiet_share }) => {
                assert!((quiet_share - 0.003).abs() < 1e-12, "{quiet_share}")
            }
            other => panic!("{other:?}"),
        }
        let calm = busy.map(|q| q * 500.0 / 3.0);
        assert_eq!(
            choose_isolation(&[&block(rates, calm)]),
            (Isolation::default(), None)
        );
        let checked = [3.0, 0.3, 0.1, 1.0, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1];
        assert_eq!(
            choose_isolation(&[&block(rates, checked)]),
            (Isolation::default(), None)
        );
    }
}
