//! The recording's lag behind a simulation of it: for recorded events with support (a real
//! change, not noise), the signed offset `t_recorded - t_simulated` to the nearest
//! simulated event of the same pixel and polarity, kept as a histogram per block, intensity
//! bin of the pixel and polarity, for two pairings ([`Pairing`]): every event (the
//! distance's `lag` component), and the events that start a burst against the simulated
//! burst starts (the bandwidth's evidence, [`delay_of`]).
//!
//! A burst starts at an event whose pixel gave no event of its polarity for
//! [`ONSET_GAP_US`] before it. Pairing every event with its nearest counterpart reads a
//! delay longer than half the pixel's time between events as the next event's early
//! arrival: coverage draw 6006 (a 20 Hz cutoff in a 25 DN scene, time constants of 48 to
//! 85 ms below 25 DN) read its ON events at +5 ms at 14 DN against +48 ms for its sparser
//! OFF events. Burst starts are at least the gap apart in each pixel, recorded and
//! simulated alike, so a delay up to half the gap (100 ms) pairs with its own counterpart
//! (the same bin: ON +34 ms, OFF +50 ms; `benches/coverage/lag-onsets-2026-12-03/`). The
//! distance keeps every event: burst starts are a fraction of them, and in the distance
//! they moved fitted values of draws without a long delay (the same benchmark).
//!
//! A photoreceptor low-pass of time constant `tau` delays a pixel's response to a ramp by
//! `tau` (a first-order filter's lag to a ramp input), and its cutoff is proportional to the
//! photocurrent (Lichtsteiner, Posch & Delbruck, JSSC 2008), so a bandwidth the model lacks
//! puts the recording's events behind the model's, more in the dark. A bandwidth that only
//! delays events, without thinning them, leaves the count cells as they are and shows here
//! alone. The frames' 8-bit quantisation moves simulated events either way, so it leaves
//! the median offset near zero (pilot on coverage draws 6006 and 6017:
//! `benches/coverage/bandwidth-lag-pilot-2026-12-02/`).
//!
//! A delay is the same for both polarities; a level the model puts its thresholds at
//! wrongly is not. A pixel fires at its reference level plus whole thresholds, so a
//! threshold a few per cent off moves the level of the k-th crossing from the reference by
//! k times that, and the event by the level error over the log's rate of change: earlier on
//! a rising ramp (ON) and later on a falling one (OFF) for the same level error. The error
//! grows with the distance from the reference, so it is largest in the intensity bins far
//! from the scene's typical level, and a median over both polarities follows the bin's mix
//! of ON and OFF events (coverage draw 6014, thresholds 3 % and 1 % off: ON +3.9 ms and OFF
//! -5.4 ms at 113 DN against a re-simulation with them; the fit read the pooled median as a
//! lag of +4.0 ms at 113 DN and added a 1437 Hz bandwidth). The ON and OFF thresholds'
//! level errors are separate, and one can be tens of per cent where the other is right
//! (draw 6029, a rotation at 572 px/s whose OFF threshold was fitted 0.466 for 0.678:
//! OFF burst starts +33 to +39 ms against the fitted model, ON ones -5 to +1 ms). The
//! delay of a bin ([`delay_of`]), which the bandwidth's evidence reads, is therefore the
//! delay both polarities show: the smaller of their median offsets where the two have one
//! sign, none where they differ. The distance's `lag` component keeps the pooled median:
//! it measures any difference between model and recording, and a level error is one (it
//! vanishes at the right thresholds).
//!
//! The statistic pairs the recording's events with a simulation's; it is computed for
//! simulations only ([`LagKeys`] holds the recording's side once).

use super::{Geometry, INTENSITY_BINS};
use crate::events::{EventChunk, TimeUs};
use rayon::prelude::*;

/// Offsets of burst starts beyond this (either sign) are not paired: the nearest simulated
/// one is then another change, not this one. The histograms span it.
pub const LAG_WINDOW_US: TimeUs = 200_000;
/// Offsets of every event beyond this are not paired.
pub const EVERY_EVENT_WINDOW_US: TimeUs = 100_000;
/// Width of the offset histogram's bins, microseconds.
pub const LAG_BIN_US: TimeUs = 250;
/// Bins of the offset histogram, from `-LAG_WINDOW_US` to `+LAG_WINDOW_US`.
pub const LAG_BINS: usize = (2 * LAG_WINDOW_US / LAG_BIN_US) as usize;
/// Paired events an intensity bin needs for its median offset to count.
pub const MIN_LAG_EVENTS: u32 = 50;
/// A burst of a pixel's events of one polarity starts after this long without one
/// ([`Pairing::BurstStarts`], see the module docs): twice the largest delay it pairs
/// without ambiguity.
pub const ONSET_GAP_US: TimeUs = LAG_WINDOW_US;

/// Whether each of the time-sorted `events` starts a burst: its pixel gave no event of its
/// polarity in the [`ONSET_GAP_US`] before it.
fn burst_starts(events: &EventChunk, groups: usize, width: usize) -> Vec<bool> {
    let mut last = vec![TimeUs::MIN; groups];
    (0..events.len())
        .map(|i| {
            let g = group_of(events, i, width);
            let starts = last[g] == TimeUs::MIN || events.t[i] - last[g] > ONSET_GAP_US;
            last[g] = events.t[i];
            starts
        })
        .collect()
}

/// Which of a pixel's events are paired.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pairing {
    /// Every supported event, within [`EVERY_EVENT_WINDOW_US`]: the distance's `lag`.
    EveryEvent,
    /// The supported events that start a burst ([`ONSET_GAP_US`]), within
    /// [`LAG_WINDOW_US`]: the bandwidth's evidence.
    BurstStarts,
}

/// One pairing's recorded events, grouped by pixel and polarity (in time order within each
/// group).
struct GroupedEvents {
    /// Start of each `pixel * 2 + polarity` group in `t` and `slot` (one more than groups).
    start: Vec<u32>,
    t: Vec<TimeUs>,
    /// `(block * INTENSITY_BINS + intensity bin) * 2 + polarity` of each event.
    slot: Vec<u32>,
}

/// The recording's supported events in used blocks with a reliable intensity, grouped by
/// pixel and polarity for each [`Pairing`].
pub struct LagKeys {
    every: GroupedEvents,
    starts: GroupedEvents,
}

/// The offset histograms `[block][intensity][polarity][offset bin]` of one simulation, for
/// each [`Pairing`] (empty for the recording itself).
#[derive(Clone, Debug, Default)]
pub struct LagHistograms {
    pub every_event: Vec<u32>,
    pub burst_starts: Vec<u32>,
}

impl LagHistograms {
    /// The histograms of `pairing`.
    pub fn of(&self, pairing: Pairing) -> &[u32] {
        match pairing {
            Pairing::EveryEvent => &self.every_event,
            Pairing::BurstStarts => &self.burst_starts,
        }
    }
}

/// The `(pixel * 2 + polarity)` group of event `i`.
#[inline]
fn group_of(events: &EventChunk, i: usize, width: usize) -> usize {
    (events.y[i] as usize * width + events.x[i] as usize) * 2 + events.on[i] as usize
}

/// Stable counting sort of the selected events by group: each group's start and the
/// selected indices in group order.
fn by_group(
    events: &EventChunk,
    groups: usize,
    width: usize,
    selected: impl Fn(usize) -> bool,
) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; groups + 1];
    for i in (0..events.len()).filter(|&i| selected(i)) {
        start[group_of(events, i, width) + 1] += 1;
    }
    for g in 0..groups {
        start[g + 1] += start[g];
    }
    let mut next = start.clone();
    let mut order = vec![0u32; start[groups] as usize];
    for i in (0..events.len()).filter(|&i| selected(i)) {
        let g = group_of(events, i, width);
        order[next[g] as usize] = i as u32;
        next[g] += 1;
    }
    (start, order)
}

impl LagKeys {
    /// The recording's side: its time-sorted `events` with their `support` flags.
    pub fn new(events: &EventChunk, support: &[bool], g: &Geometry) -> Self {
        let width = g.sensor.width as usize;
        let groups = g.sensor.pixels() * 2;
        let starts = burst_starts(events, groups, width);
        // each event's slot, u32::MAX where it is not paired
        let mut k = 0usize;
        let slots: Vec<u32> = (0..events.len())
            .map(|i| {
                let t = events.t[i];
                while k + 1 < g.times.len() && g.times[k + 1] <= t {
                    k += 1;
                }
                if !support[i] || t < g.times[0] || k + 1 >= g.times.len() {
                    return u32::MAX;
                }
                let p = events.y[i] as usize * width + events.x[i] as usize;
                match (g.interval_block[k], g.intensity[k].get(p)) {
                    (Some(block), Some(&bin)) if bin != u8::MAX && !g.excluded[p] => {
                        ((block * INTENSITY_BINS + bin as usize) * 2 + events.on[i] as usize) as u32
                    }
                    _ => u32::MAX,
                }
            })
            .collect();
        let grouped = |selected: &dyn Fn(usize) -> bool| {
            let (start, order) = by_group(events, groups, width, selected);
            GroupedEvents {
                start,
                t: order.iter().map(|&i| events.t[i as usize]).collect(),
                slot: order.iter().map(|&i| slots[i as usize]).collect(),
            }
        };
        Self {
            every: grouped(&|i| slots[i] != u32::MAX),
            starts: grouped(&|i| slots[i] != u32::MAX && starts[i]),
        }
    }

    /// The offset histograms of the recording against the time-sorted simulated `events`
    /// (their `support` flags), leaving out `masked` pixels; the two pairings side by side
    /// (each groups the events on one thread before pairing them on the pool).
    pub fn histograms(
        &self,
        events: &EventChunk,
        support: &[bool],
        g: &Geometry,
        masked: &[bool],
    ) -> LagHistograms {
        let width = g.sensor.width as usize;
        let (every_event, burst_starts) = rayon::join(
            || {
                self.every
                    .histogram(events, |i| support[i], g, masked, EVERY_EVENT_WINDOW_US)
            },
            || {
                let starts = burst_starts(events, self.every.start.len() - 1, width);
                self.starts.histogram(
                    events,
                    |i| support[i] && starts[i],
                    g,
                    masked,
                    LAG_WINDOW_US,
                )
            },
        );
        LagHistograms {
            every_event,
            burst_starts,
        }
    }
}

impl GroupedEvents {
    /// The offset histogram `[block][intensity][polarity][offset bin]` of these recorded
    /// events against the `selected` time-sorted simulated `events`, offsets within
    /// `window` paired, leaving out `masked` pixels.
    fn histogram(
        &self,
        events: &EventChunk,
        selected: impl Fn(usize) -> bool,
        g: &Geometry,
        masked: &[bool],
        window: TimeUs,
    ) -> Vec<u32> {
        let width = g.sensor.width as usize;
        let groups = self.start.len() - 1;
        let (sim_start, order) = by_group(events, groups, width, selected);
        let sim_t: Vec<TimeUs> = order.iter().map(|&i| events.t[i as usize]).collect();
        let size = g.blocks * INTENSITY_BINS * 2 * LAG_BINS;
        let chunk = groups
            .div_ceil(4 * rayon::current_num_threads().max(1))
            .max(1);
        (0..groups)
            .into_par_iter()
            .with_min_len(chunk)
            .fold(
                || vec![0u32; size],
                |mut hist, group| {
                    if masked[group / 2] {
                        return hist;
                    }
                    let real = self.start[group] as usize..self.start[group + 1] as usize;
                    let sim = &sim_t[sim_start[group] as usize..sim_start[group + 1] as usize];
                    let (t, slot) = (&self.t[real.clone()], &self.slot[real]);
                    pair_group(t, slot, sim, window, &mut hist);
                    hist
                },
            )
            .reduce(
                || vec![0u32; size],
                |mut a, b| {
                    a.iter_mut().zip(&b).for_each(|(a, b)| *a += b);
                    a
                },
            )
    }
}

/// Adds the offsets of one group's recorded events (`real`, sorted, with their slots) from
/// the nearest of its simulated events (`sim`, sorted) to `hist`, where within `window`.
fn pair_group(real: &[TimeUs], slots: &[u32], sim: &[TimeUs], window: TimeUs, hist: &mut [u32]) {
    if sim.is_empty() {
        return;
    }
    let mut j = 0usize;
    for (&t, &slot) in real.iter().zip(slots) {
        while j < sim.len() && sim[j] < t {
            j += 1;
        }
        let after = sim.get(j).map(|&s| t - s);
        let before = j.checked_sub(1).map(|b| t - sim[b]);
        let offset = match (before, after) {
            (Some(b), Some(a)) => {
                if b <= -a {
                    b
                } else {
                    a
                }
            }
            (Some(b), None) => b,
            (None, Some(a)) => a,
            (None, None) => continue,
        };
        if offset.abs() < window {
            let bin = ((offset + LAG_WINDOW_US) / LAG_BIN_US) as usize;
            hist[slot as usize * LAG_BINS + bin] += 1;
        }
    }
}

/// One intensity bin's offsets: their median, its standard error, and how many.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BinLag {
    pub median_s: f64,
    /// The sample median's standard error, `1.2533 sigma / sqrt(n)`, with `sigma` from the
    /// interquartile range (`IQR / 1.349`), at least the histogram's own resolution (a bin
    /// over `sqrt(12)`).
    pub standard_error_s: f64,
    pub events: u32,
}

/// The `q` quantile of an offset histogram, seconds (linear within its bin).
fn quantile_s(hist: &[u32], n: u32, q: f64) -> f64 {
    let target = n as f64 * q;
    let mut below = 0.0;
    for (k, &c) in hist.iter().enumerate() {
        let c = c as f64;
        if below + c >= target && c > 0.0 {
            let within = (target - below) / c;
            return (-(LAG_WINDOW_US as f64) + (k as f64 + within) * LAG_BIN_US as f64) * 1e-6;
        }
        below += c;
    }
    LAG_WINDOW_US as f64 * 1e-6
}

/// The [`BinLag`] of an offset histogram, `None` when it is empty.
pub fn bin_lag(hist: &[u32]) -> Option<BinLag> {
    let n: u32 = hist.iter().sum();
    if n == 0 {
        return None;
    }
    let iqr = quantile_s(hist, n, 0.75) - quantile_s(hist, n, 0.25);
    let sigma = (iqr / 1.349).max(LAG_BIN_US as f64 * 1e-6 / 12f64.sqrt());
    Some(BinLag {
        median_s: quantile_s(hist, n, 0.5),
        standard_error_s: 1.2533 * sigma / (n as f64).sqrt(),
        events: n,
    })
}

/// The delay of one intensity bin from its offset histograms, OFF then ON (`2 *
/// LAG_BINS` counts), with each polarity's median offset: the delay both polarities show
/// (the median offset smaller in size, with its standard error, where the two have one
/// sign; zero, with the larger standard error, where they differ); `None` unless each
/// polarity has [`MIN_LAG_EVENTS`] paired events (a bin of one polarity cannot tell a delay
/// from a level error, see the module docs).
pub fn delay_of(hist: &[u32]) -> Option<BinDelay> {
    let (off, on) = hist.split_at(LAG_BINS);
    let enough = |h: &[u32]| bin_lag(h).filter(|l| l.events >= MIN_LAG_EVENTS);
    let (off, on) = (enough(off)?, enough(on)?);
    let common = if off.median_s * on.median_s <= 0.0 {
        BinLag {
            median_s: 0.0,
            standard_error_s: off.standard_error_s.max(on.standard_error_s),
            events: off.events + on.events,
        }
    } else if off.median_s.abs() < on.median_s.abs() {
        off
    } else {
        on
    };
    Some(BinDelay {
        common,
        off_s: off.median_s,
        on_s: on.median_s,
    })
}

/// One intensity bin's delay ([`delay_of`]): what both polarities show, and each one's
/// median offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BinDelay {
    pub common: BinLag,
    pub off_s: f64,
    pub on_s: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_recorded_event_is_paired_with_the_nearest_simulated_one() {
        // simulated at 10, 20, 40 ms; recorded at 9 (-1 ms from 10), 16 (-4 from 20, the
        // nearer), 31 (-9 from 40, nearer than +11 from 20) and 300 (260 ms after the last:
        // beyond the window, not paired)
        let sim = [10_000, 20_000, 40_000];
        let real = [9_000, 16_000, 31_000, 300_000];
        let mut hist = vec![0u32; 2 * LAG_BINS];
        pair_group(&real, &[0, 0, 1, 1], &sim, LAG_WINDOW_US, &mut hist);
        let bin = |us: TimeUs| ((us + LAG_WINDOW_US) / LAG_BIN_US) as usize;
        assert_eq!(hist[bin(-1_000)], 1);
        assert_eq!(hist[bin(-4_000)], 1);
        assert_eq!(hist[LAG_BINS + bin(-9_000)], 1);
        assert_eq!(hist.iter().sum::<u32>(), 3);
    }

    #[test]
    fn the_median_offset_interpolates_within_its_bin() {
        let mut hist = vec![0u32; LAG_BINS];
        let bin = |us: TimeUs| ((us + LAG_WINDOW_US) / LAG_BIN_US) as usize;
        // 10 events in the bin [+2.0, +2.25) ms, 5 at -3 ms, 5 at +8 ms
        hist[bin(2_000)] = 10;
        hist[bin(-3_000)] = 5;
        hist[bin(8_000)] = 5;
        let lag = bin_lag(&hist).unwrap();
        assert_eq!(lag.events, 20);
        // half (10) reached halfway through the 10 events: 2.0 + 0.125 ms
        assert!((lag.median_s - 2.125e-3).abs() < 1e-9, "{lag:?}");
        // quartiles: 5 of 5 through the -3 ms bin (its top, -2.75 ms) and 10 of 10 through
        // the +2 ms bin (its top, +2.25 ms): sigma 5 / 1.349 ms, over sqrt(20)
        let se = 1.2533 * 5e-3 / 1.349 / 20f64.sqrt();
        assert!((lag.standard_error_s - se).abs() < 1e-9, "{lag:?}");
        assert_eq!(bin_lag(&vec![0; LAG_BINS]), None);
    }

    #[test]
    fn a_delay_shows_in_both_polarities_and_a_level_error_does_not() {
        let bin = |us: TimeUs| ((us + LAG_WINDOW_US) / LAG_BIN_US) as usize;
        // OFF then ON: 60 events each, OFF 5 ms early and ON 3 ms late (a level error):
        // no delay both show, with the larger of their standard errors
        let mut hist = vec![0u32; 2 * LAG_BINS];
        hist[bin(-5_000)] = 60;
        hist[LAG_BINS + bin(3_000)] = 60;
        let delay = delay_of(&hist).unwrap();
        assert_eq!(delay.common.median_s, 0.0);
        assert_eq!(delay.common.events, 120);
        // each median half-way through its 0.25 ms bin; each IQR half a bin (linear within
        // it), sigma 125 us / 1.349, over sqrt(60)
        assert!((delay.off_s + 4.875e-3).abs() < 1e-9, "{delay:?}");
        assert!((delay.on_s - 3.125e-3).abs() < 1e-9, "{delay:?}");
        let each = 1.2533 * 125e-6 / 1.349 / 60f64.sqrt();
        assert!((delay.common.standard_error_s - each).abs() < 1e-12);
        // OFF 5 ms late and ON 3 ms late: both show the 3 ms
        hist[bin(-5_000)] = 0;
        hist[bin(5_000)] = 60;
        let delay = delay_of(&hist).unwrap();
        assert!((delay.common.median_s - 3.125e-3).abs() < 1e-9, "{delay:?}");
        assert_eq!(delay.common.events, 60);
        // too few OFF events: no delay
        hist[bin(5_000)] = MIN_LAG_EVENTS - 1;
        assert_eq!(delay_of(&hist), None);
    }

    #[test]
    fn only_burst_starts_are_paired() {
        // pixel 0 ON at 0, 30, 450 ms (starts: 0 and 450, 420 ms after the last); pixel 0
        // OFF at 40 ms (a start: the other polarity's events do not count); pixel 1 ON at
        // 60 ms
        let events = crate::fit::effects::fixture::chunk(vec![
            (0, 0, 0, true),
            (30_000, 0, 0, true),
            (40_000, 0, 0, false),
            (60_000, 1, 0, true),
            (450_000, 0, 0, true),
        ]);
        assert_eq!(burst_starts(&events, 4, 2), [true, false, true, true, true]);
    }
}
