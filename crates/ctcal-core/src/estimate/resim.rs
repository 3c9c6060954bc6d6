//! Contrast thresholds by re-simulating the recording's own frames (Stoffregen et al. 2020,
//! Sec. 3.1, "APS re-simulation"): events are simulated from the frames, upsampled along the
//! optical flow ([`super::frames`]), with candidate thresholds, and the ON and OFF thresholds
//! are those whose simulated counts best match the real ones in every region (16 x 16 pixel
//! tiles) and every frame interval, not only in total.
//!
//! The mismatch is a chi-square distance over the cells, `sum (r - s)^2 / (r + s + 1)`, for
//! ON and OFF counts. With few events per cell that distance is biased (it favours
//! simulations with more events), so cells are made large enough to hold about 20 real
//! events on average: consecutive intervals are grouped, and tiles grow when even the whole
//! recording is too sparse. The distance is it is minimised with argmin's Brent search for each polarity in turn
//! (ON counts depend on `Cp` and barely on `Cn`, and the other way round). The simulator is
//! deterministic for a seed, so the objective is the same function at every evaluation
//! (common random numbers). Both the real and the simulated events go through the same
//! spatio-temporal support filter, so that the noise of a real sensor (which the ideal
//! model does not make) does not count, and isolated signal events are dropped on both sides
//! alike.

use super::EstimateError;
use super::frames::PreparedFrames;
use super::root::{Crossing, Search, threshold_root};
use crate::events::{EventChunk, Sensor, TimeUs};
use crate::hint::{Analysis, Hint, Text};
use crate::sim::log_response::LogMap;
use crate::sim::{PixelMaps, PixelParams, Sample, Simulator};
use crate::stats::support::supported;
use argmin::core::{CostFunction, Error as ArgminError};
use rayon::prelude::*;
use serde::Serialize;

/// Side of the count tiles, pixels (before they grow for sparse recordings).
pub const TILE_PX: usize = 16;

/// Real events a cell should hold on average.
const EVENTS_PER_CELL: f64 = 20.0;

/// ON and OFF counts per (interval, tile).
#[derive(Clone, Debug, PartialEq)]
pub struct Counts {
    pub on: Vec<u32>,
    pub off: Vec<u32>,
}

impl Counts {
    /// Adds `other`'s counts cell by cell.
    fn add(&mut self, other: &Counts) {
        for (a, b) in self.on.iter_mut().zip(&other.on) {
            *a += b;
        }
        for (a, b) in self.off.iter_mut().zip(&other.off) {
            *a += b;
        }
    }
}

/// Events counted together on one thread by [`Cells::count`].
const COUNT_STRETCH: usize = 1 << 14;

/// The cells of a recording: tiles of the sensor times the used intervals.
#[derive(Clone, Debug)]
pub struct Cells {
    tile_px: usize,
    tiles_x: usize,
    tiles: usize,
    /// Per interval of the frames: its cell row, or `None` when unused.
    interval_row: Vec<Option<usize>>,
    /// Per interval of the frames: its position among the used ones.
    used_index: Vec<Option<usize>>,
    rows: usize,
    times: Vec<TimeUs>,
    excluded: Vec<bool>,
    /// Per used interval (in order), the pixels without a reliable intensity (empty: all
    /// reliable).
    unreliable: Vec<Vec<bool>>,
    width: usize,
    support_us: TimeUs,
    sensor: Sensor,
}

/// The intervals cells are made of: boundary times, and per interval whether it is used
/// and which pixels have no reliable intensity in it (an empty mask: all have).
#[derive(Clone, Debug)]
pub struct Intervals {
    pub times: Vec<TimeUs>,
    pub masks: Vec<Option<Vec<bool>>>,
}

impl Intervals {
    /// The used intervals of `frames` and their unreliable pixels.
    pub fn of_frames(frames: &PreparedFrames, sensor: Sensor) -> Self {
        Self {
            times: frames.times.clone(),
            masks: (0..frames.flows.len())
                .map(|k| {
                    frames.flows[k].as_ref().map(|_| {
                        (0..sensor.pixels())
                            .map(|p| !frames.reliable(k, p))
                            .collect()
                    })
                })
                .collect(),
        }
    }

    /// Every interval between consecutive `times`, all pixels reliable.
    pub fn all(times: Vec<TimeUs>) -> Self {
        let n = times.len().saturating_sub(1);
        Self {
            times,
            masks: vec![Some(Vec::new()); n],
        }
    }
}

impl Cells {
    /// Cells for `intervals`, sized so that the `events` (the real recording) fill each
    /// with about 20 events on average.
    pub fn new(
        intervals: Intervals,
        sensor: Sensor,
        excluded: &[bool],
        support_us: TimeUs,
        events: &EventChunk,
    ) -> Self {
        let used = intervals
            .masks
            .iter()
            .filter(|m| m.is_some())
            .count()
            .max(1);
        let total = {
            let c = Self::with_layout(intervals.clone(), sensor, excluded, support_us, TILE_PX, 1)
                .count(events);
            c.on.iter().chain(&c.off).map(|&v| v as f64).sum::<f64>()
        };
        let mut tile_px = TILE_PX;
        loop {
            let tiles = (sensor.width as usize).div_ceil(tile_px)
                * (sensor.height as usize).div_ceil(tile_px);
            // intervals per group so that a cell holds EVENTS_PER_CELL on average
            let group = ((EVENTS_PER_CELL * (tiles * used) as f64) / (2.0 * total.max(1.0)))
                .ceil()
                .max(1.0) as usize;
            if group <= used || tile_px >= sensor.width.max(sensor.height) as usize {
                return Self::with_layout(
                    intervals,
                    sensor,
                    excluded,
                    support_us,
                    tile_px,
                    group.min(used),
                );
            }
            tile_px *= 2;
        }
    }

    /// Cells of `tile_px` pixels over `group` consecutive intervals each.
    pub fn with_layout(
        intervals: Intervals,
        sensor: Sensor,
        excluded: &[bool],
        support_us: TimeUs,
        tile_px: usize,
        group: usize,
    ) -> Self {
        let tiles_x = (sensor.width as usize).div_ceil(tile_px);
        let tiles_y = (sensor.height as usize).div_ceil(tile_px);
        let mut used = 0;
        let used_index: Vec<Option<usize>> = intervals
            .masks
            .iter()
            .map(|m| {
                m.as_ref().map(|_| {
                    used += 1;
                    used - 1
                })
            })
            .collect();
        let interval_row = used_index.iter().map(|u| u.map(|u| u / group)).collect();
        let unreliable = intervals.masks.into_iter().flatten().collect();
        Self {
            tile_px,
            tiles_x,
            tiles: tiles_x * tiles_y,
            rows: used.div_ceil(group),
            unreliable,
            interval_row,
            used_index,
            times: intervals.times,
            excluded: excluded.to_vec(),
            width: sensor.width as usize,
            support_us,
            sensor,
        }
    }

    /// Each cell's mean frame value (DN, without the offset) over its reliable, included
    /// pixels and the two frames of each of its intervals; `None` for a cell without such a
    /// pixel.
    pub fn mean_levels(&self, frames: &PreparedFrames) -> Vec<Option<f64>> {
        let mut sums = vec![(0.0f64, 0usize); self.rows * self.tiles];
        for (k, row) in self.interval_row.iter().enumerate() {
            let (Some(row), Some(used)) = (row, self.used_index[k]) else {
                continue;
            };
            let mask = &self.unreliable[used];
            let (a, b) = (&frames.dn[k].data, &frames.dn[k + 1].data);
            for (pixel, (&v0, &v1)) in a.iter().zip(b).enumerate() {
                if self.excluded[pixel] || (!mask.is_empty() && mask[pixel]) {
                    continue;
                }
                let (x, y) = (pixel % self.width, pixel / self.width);
                let cell = row * self.tiles + (y / self.tile_px) * self.tiles_x + x / self.tile_px;
                sums[cell].0 += 0.5 * (v0 + v1) as f64;
                sums[cell].1 += 1;
            }
        }
        sums.iter()
            .map(|&(sum, n)| (n > 0).then(|| sum / n as f64))
            .collect()
    }

    /// Counts `events` (time-sorted) into the cells; events outside used intervals, of
    /// excluded pixels or without support are not counted. Stretches of
    /// [`COUNT_STRETCH`] events are counted on the pool and their counts added (sums of
    /// integers: the same whatever the order).
    pub fn count(&self, events: &EventChunk) -> Counts {
        let support = supported(events, self.sensor, self.support_us);
        let n = self.rows * self.tiles;
        let zeros = || Counts {
            on: vec![0; n],
            off: vec![0; n],
        };
        (0..events.len().div_ceil(COUNT_STRETCH))
            .into_par_iter()
            .map(|k| {
                let mut counts = zeros();
                let end = ((k + 1) * COUNT_STRETCH).min(events.len());
                self.count_stretch(events, &support, k * COUNT_STRETCH..end, &mut counts);
                counts
            })
            .reduce(zeros, |mut a, b| {
                a.add(&b);
                a
            })
    }

    /// Adds the events of `stretch` to `counts`: the interval of each found by walking
    /// forward from the previous one's (searched afresh where time goes back).
    fn count_stretch(
        &self,
        events: &EventChunk,
        support: &[bool],
        stretch: std::ops::Range<usize>,
        counts: &mut Counts,
    ) {
        let Some(&first) = events.t.get(stretch.start) else {
            return;
        };
        // the number of boundaries at or before the current time
        let mut after = self.times.partition_point(|&s| s <= first);
        for i in stretch {
            let t = events.t[i];
            if after > 0 && self.times[after - 1] > t {
                // out of order: found afresh
                after = self.times.partition_point(|&s| s <= t);
            }
            while after < self.times.len() && self.times[after] <= t {
                after += 1;
            }
            let Some(k) = after.checked_sub(1) else {
                continue;
            };
            let Some(Some(row)) = self.interval_row.get(k) else {
                continue;
            };
            let (x, y) = (events.x[i] as usize, events.y[i] as usize);
            let pixel = y * self.width + x;
            let used = self.used_index[k].expect("a row is a used interval");
            let mask = &self.unreliable[used];
            if !support[i] || self.excluded[pixel] || (!mask.is_empty() && mask[pixel]) {
                continue;
            }
            let cell = row * self.tiles + (y / self.tile_px) * self.tiles_x + x / self.tile_px;
            if events.on[i] {
                counts.on[cell] += 1;
            } else {
                counts.off[cell] += 1;
            }
        }
    }
}

/// The mismatch of simulated counts `s` against real counts `r`: the median over cells
/// holding at least 5 real events of `ln((s + 1/2) / (r + 1/2))`. When `s` and `r` have the
/// same expectation their difference is symmetric, so the median is 0 (a chi-square
/// distance, by contrast, favours simulations with more events when cells are sparse).
/// Positive: the simulation makes too many events (the threshold is too low).
pub fn log_ratio(real: &[u32], simulated: &[u32]) -> f64 {
    let mut ratios: Vec<f64> = real
        .iter()
        .zip(simulated)
        .filter(|(r, _)| **r >= 5)
        .map(|(&r, &s)| ((s as f64 + 0.5) / (r as f64 + 0.5)).ln())
        .collect();
    if ratios.is_empty() {
        // too sparse for cells: the totals
        let (r, s): (f64, f64) = (
            real.iter().map(|&v| v as f64).sum(),
            simulated.iter().map(|&v| v as f64).sum(),
        );
        return ((s + 0.5) / (r + 0.5)).ln();
    }
    let mid = ratios.len() / 2;
    *ratios.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// How far one polarity's per-cell counts lie from the simulation's at the fitted
/// thresholds, over the cells with at least 5 real events.
#[derive(Clone, Copy, Debug)]
pub struct CellSpread {
    /// The median |ln((s + 0.5) / (r + 0.5))|.
    pub median_abs_log_ratio: f64,
    /// The relative standard error of the threshold: the median log ratio moves 1:1 with
    /// ln(threshold), and the standard error of a median is 1.2533 sigma / sqrt(n), with
    /// sigma = 1.4826 x the median absolute ratio (its MAD about the fitted 0).
    pub relative_standard_error: f64,
    pub cells: usize,
}

/// The [`CellSpread`] of `real` against `simulated`; `None` when no cell holds 5 events
/// (the spread cannot be measured).
pub fn cell_spread(real: &[u32], simulated: &[u32]) -> Option<CellSpread> {
    let mut logs: Vec<f64> = real
        .iter()
        .zip(simulated)
        .filter(|(r, _)| **r >= 5)
        .map(|(&r, &s)| ((s as f64 + 0.5) / (r as f64 + 0.5)).ln().abs())
        .collect();
    let cells = logs.len();
    if cells == 0 {
        return None;
    }
    let median_abs_log_ratio = *logs.select_nth_unstable_by(cells / 2, f64::total_cmp).1;
    Some(CellSpread {
        median_abs_log_ratio,
        relative_standard_error: 1.2533 * 1.4826 * median_abs_log_ratio / (cells as f64).sqrt(),
        cells,
    })
}

/// Simulates the upsampled runs with `params`, all events together.
pub fn simulate(
    runs: &[Vec<Sample>],
    width: usize,
    height: usize,
    params: &PixelParams,
) -> Result<EventChunk, EstimateError> {
    let mut all = EventChunk::default();
    // each run an independent stretch of time: its own draw of the noise; each simulated
    // whole, its rows on the pool (`Simulator::run_all`)
    for (k, run) in runs.iter().enumerate() {
        let events = Simulator::new(params, width, height, PixelMaps::default())
            .noise_stream(k as u64)
            .run_all(run)
            .map_err(|e| {
                EstimateError::new(format!("re-simulation failed: {e}"), "report this as a bug")
            })?;
        if all.is_empty() {
            // the first run's events are taken as they are, not copied
            all = events;
        } else {
            all.extend_from(&events);
        }
    }
    all.sort_by_time();
    Ok(all)
}

/// `params` with the frames' log response `log_map`: the simulated pixel reads the
/// upsampled frames (DN + b) as the event timing read them. A simulator's default response
/// in its place (v2e's lin-log, linear below 20 DN) makes another log change of every dark
/// pixel than the one the thresholds were measured in: on an ESIM recording at 13 DN read
/// as a pure ln(DN + b), the re-simulation then matched the counts at no threshold.
pub fn read_as_frames(params: &PixelParams, log_map: LogMap) -> PixelParams {
    PixelParams {
        log_response: Some(log_map.response()),
        log_eps: Some(log_map.eps()),
        ..params.clone()
    }
}

/// The result of the re-simulation fit.
#[derive(Clone, Debug, Serialize)]
pub struct ResimEstimate {
    pub ct_on: f64,
    pub ct_off: f64,
    /// Median absolute log ratio of simulated to real counts over the cells at the
    /// optimum, ON and OFF: how well the model explains each region and interval.
    pub cell_mismatch_on: f64,
    pub cell_mismatch_off: f64,
    /// Standard errors from the spread of the cells' log ratios.
    pub standard_error_on: f64,
    pub standard_error_off: f64,
    pub cells: usize,
    pub simulations: usize,
    /// The simulated counts at the thresholds found.
    #[serde(skip)]
    pub counts: Counts,
}

/// The input of one re-simulation fit.
pub struct Resimulation<'a> {
    pub runs: &'a [Vec<Sample>],
    pub width: usize,
    pub height: usize,
    pub cells: &'a Cells,
    pub real: &'a Counts,
    /// The recording's timestamp grid, applied to simulated events too.
    pub grid: Option<(TimeUs, TimeUs)>,
    /// The frames' log response: every simulation reads the runs through it.
    pub log_map: LogMap,
    pub evaluations: std::cell::Cell<usize>,
}

impl<'a> Resimulation<'a> {
    /// The re-simulation of `runs` (frames of `width` x `height` upsampled along the flow)
    /// against the recording's `real` counts in `cells`, on the timestamp `grid`, the runs
    /// read through the frames' `log_map` ([`read_as_frames`]).
    pub fn new(
        runs: &'a [Vec<Sample>],
        (width, height): (usize, usize),
        cells: &'a Cells,
        real: &'a Counts,
        grid: Option<(TimeUs, TimeUs)>,
        log_map: LogMap,
    ) -> Self {
        Self {
            runs,
            width,
            height,
            cells,
            real,
            grid,
            log_map,
            evaluations: std::cell::Cell::new(0),
        }
    }

    /// The cells' counts of the runs simulated with `params` (on the recording's grid).
    pub fn counts(&self, params: &PixelParams) -> Result<Counts, EstimateError> {
        self.evaluations.set(self.evaluations.get() + 1);
        let params = read_as_frames(params, self.log_map);
        let mut events = simulate(self.runs, self.width, self.height, &params)?;
        if let Some(grid) = self.grid {
            super::quantise(&mut events, grid);
        }
        Ok(self.cells.count(&events))
    }
}

/// The count mismatch of one polarity as a function of its threshold, the other fixed:
/// a root-finding problem for argmin's Brent solver.
struct Mismatch<'a, 'b> {
    resim: &'b Resimulation<'a>,
    base: PixelParams,
    on: bool,
}

impl CostFunction for Mismatch<'_, '_> {
    type Param = f64;
    type Output = f64;
    fn cost(&self, threshold: &f64) -> Result<f64, ArgminError> {
        let mut p = self.base.clone();
        if self.on {
            p.ct_on = *threshold;
        } else {
            p.ct_off = *threshold;
        }
        let simulated = self.resim.counts(&p)?;
        Ok(if self.on {
            log_ratio(&self.resim.real.on, &simulated.on)
        } else {
            log_ratio(&self.resim.real.off, &simulated.off)
        })
    }
}

/// How far the re-simulation's thresholds may move from the start (the timing estimate)
/// before the frames are taken not to explain the events. Wider is not better: on the 11
/// coverage draws where this window finds no crossing, a factor 2.5 either side found
/// thresholds on 5, and 6 of their 10 values missed the truth, by up to a factor 14
/// (`benches/coverage/aps-window-2026-11-29`).
const MAX_CHANGE: f64 = 0.6;

/// Fits `Cp` and `Cn` from `start` (e.g. the timing estimate), with frozen mismatch
/// `sigma` (a fixed seed, so the same pixels at every evaluation). Two rounds of a root
/// search per polarity ([`super::root`]), each walking from the current value, the first in
/// steps from 8 %, the second from 3 %, at most [`MAX_CHANGE`] away.
pub fn fit(
    resim: &Resimulation,
    start: (f64, f64),
    sigma: f64,
) -> Result<ResimEstimate, EstimateError> {
    fit_with(resim, start, sigma, None, 2)
}

/// [`fit`] of a model with the photoreceptor's `cutoff_hz` (at white, as the simulator
/// takes it), in `rounds` rounds of root searches (the first from 8 % steps, later ones
/// from 3 %).
pub fn fit_with(
    resim: &Resimulation,
    start: (f64, f64),
    sigma: f64,
    cutoff_hz: Option<f64>,
    rounds: usize,
) -> Result<ResimEstimate, EstimateError> {
    if !(start.0.is_finite() && start.0 > 0.0 && start.1.is_finite() && start.1 > 0.0) {
        return Err(EstimateError::new(
            format!(
                "the re-simulation has no positive thresholds to start from (ON {:.4}, OFF {:.4})",
                start.0, start.1
            ),
            "the event timing found no threshold: see its reason",
        ));
    }
    let mut base = PixelParams::ideal(start.0, start.1);
    if sigma > 0.0 {
        base.ct_sigma = Some(sigma);
    }
    base.seed = Some(20_200_823);
    base.cutoff_hz = cutoff_hz;
    let mut estimate = [start.0, start.1];
    for round in 0..rounds {
        for (slot, on) in [(0, true), (1, false)] {
            base.ct_on = estimate[0];
            base.ct_off = estimate[1];
            let first_log_step = if round == 0 { 0.08 } else { 0.03 };
            estimate[slot] = polarity_root(resim, &base, on, estimate[slot], first_log_step)?;
        }
    }
    base.ct_on = estimate[0];
    base.ct_off = estimate[1];
    let simulated = resim.counts(&base)?;
    let spread = |r: &[u32], s: &[u32]| {
        cell_spread(r, s).map_or((0.0, 0.0, 0), |c| {
            (c.median_abs_log_ratio, c.relative_standard_error, c.cells)
        })
    };
    let (mismatch_on, se_on, cells) = spread(&resim.real.on, &simulated.on);
    let (mismatch_off, se_off, _) = spread(&resim.real.off, &simulated.off);
    Ok(ResimEstimate {
        ct_on: estimate[0],
        ct_off: estimate[1],
        cell_mismatch_on: mismatch_on,
        cell_mismatch_off: mismatch_off,
        standard_error_on: se_on * estimate[0],
        standard_error_off: se_off * estimate[1],
        cells,
        simulations: resim.evaluations.get(),
        counts: simulated,
    })
}

/// One polarity's threshold (`on`) where the re-simulated counts of `base` cross the real
/// ones, searched from `current` within [`MAX_CHANGE`] of it; an error where they do not
/// cross there.
fn polarity_root(
    resim: &Resimulation,
    base: &PixelParams,
    on: bool,
    current: f64,
    first_log_step: f64,
) -> Result<f64, EstimateError> {
    let problem = Mismatch {
        resim,
        base: base.clone(),
        on,
    };
    let search = Search {
        first_log_step,
        limits: [current * (1.0 - MAX_CHANGE), current * (1.0 + MAX_CHANGE)],
        relative_tolerance: 0.002,
        max_iterations: 20,
    };
    let cost = |c: f64| {
        problem
            .cost(&c)
            .map_err(|e| EstimateError::new(e.to_string(), "report this as a bug"))
    };
    match threshold_root(cost, current, &search)? {
        Crossing::Root(c) => Ok(c),
        Crossing::Beyond { .. } => Err(EstimateError::new(
            format!(
                "the re-simulated {} counts do not cross the real ones for thresholds within {:.0} % of {current:.3}",
                if on { "ON" } else { "OFF" },
                100.0 * MAX_CHANGE
            ),
            Text::from(
                "the frames do not explain the events (check the frame times and exposure, or use ",
            )
            .name(Hint::Analysis(Analysis::Eppps))
            .words(")"),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::{read_as_frames, simulate};
    use crate::sim::log_response::LogMap;
    use crate::sim::{LogResponse, PixelParams, Sample, Transition};

    /// `n` samples 10 ms apart of a 16 x 16 sensor at `dn(k, pixel)`.
    fn run(n: usize, dn: impl Fn(usize, usize) -> f32) -> Vec<Sample> {
        (0..n)
            .map(|k| Sample {
                t: k as i64 * 10_000,
                dn: (0..256).map(|p| dn(k, p)).collect(),
                transition: Transition::Linear,
            })
            .collect()
    }

    type Event = (i64, u16, u16, bool);

    fn events_of(chunk: &crate::events::EventChunk) -> Vec<Event> {
        (0..chunk.len())
            .map(|i| (chunk.t[i], chunk.x[i], chunk.y[i], chunk.on[i]))
            .collect()
    }

    #[test]
    fn runs_of_a_recording_draw_their_own_noise_over_frozen_thresholds() {
        // shot noise on a static scene: two runs of the same length, the second 1 s later
        let mut params = PixelParams::ideal(0.3, 0.3);
        params.shot_noise_rate_hz = Some(20.0);
        params.ct_sigma = Some(0.05);
        let static_run = |offset: i64| {
            let mut r = run(101, |_, _| 80.0);
            r.iter_mut().for_each(|s| s.t += offset);
            r
        };
        let two = simulate(&[static_run(0), static_run(2_000_000)], 16, 16, &params).unwrap();
        let one = simulate(&[static_run(0)], 16, 16, &params).unwrap();
        let all = events_of(&two);
        let (first, second): (Vec<&Event>, Vec<&Event>) = all.iter().partition(|e| e.0 < 2_000_000);
        // the first run is the simulation of that run alone, event for event
        assert_eq!(
            first.into_iter().copied().collect::<Vec<_>>(),
            events_of(&one)
        );
        // the second's noise is not the first's shifted by 2 s
        let shifted: Vec<_> = second
            .iter()
            .map(|e| (e.0 - 2_000_000, e.1, e.2, e.3))
            .collect();
        assert!(shifted.len() > 100, "{} noise events", shifted.len());
        assert_ne!(shifted, events_of(&one));

        // without random updates both runs fire alike: the thresholds are frozen
        params.shot_noise_rate_hz = None;
        let ramp = |offset: i64| {
            let mut r = run(101, |k, p| 40.0 + k as f32 * (1.0 + (p % 7) as f32 * 0.1));
            r.iter_mut().for_each(|s| s.t += offset);
            r
        };
        let two = events_of(&simulate(&[ramp(0), ramp(2_000_000)], 16, 16, &params).unwrap());
        let (first, second): (Vec<&Event>, Vec<&Event>) = two.iter().partition(|e| e.0 < 2_000_000);
        let shifted: Vec<_> = second
            .iter()
            .map(|e| (e.0 - 2_000_000, e.1, e.2, e.3))
            .collect();
        assert!(first.len() > 1000);
        assert_eq!(first.into_iter().copied().collect::<Vec<_>>(), shifted);
    }

    #[test]
    fn a_dark_ramp_is_simulated_through_the_frames_response() {
        // every pixel from 5 to 10 DN: ln(10 / 5) = 0.693 under a pure ln(DN), six
        // crossings of 0.1; v2e's lin-log is linear there, 5 * ln(20) / 20 = 0.749, seven
        let params = PixelParams::ideal(0.1, 0.1);
        let ramp = [run(11, |k, _| 5.0 + 0.5 * k as f32)];
        let per_pixel = |p: &PixelParams| {
            let events = simulate(&ramp, 16, 16, p).unwrap();
            assert!(events.on.iter().all(|&on| on));
            events.len() as f64 / 256.0
        };
        let pure_log = LogMap::new(LogResponse::Eps, 0.0);
        assert_eq!(per_pixel(&read_as_frames(&params, pure_log)), 6.0);
        let lin_log = LogMap::new(LogResponse::V2e, 0.001);
        assert_eq!(per_pixel(&read_as_frames(&params, lin_log)), 7.0);
        // the simulator's own default is the lin-log, which the frames need not be read with
        assert_eq!(per_pixel(&params), 7.0);
    }
}
