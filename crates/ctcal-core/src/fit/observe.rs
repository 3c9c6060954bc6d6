//! The statistics the fit compares between a recording and a simulation of it, computed
//! the same way for both ([`Observed`]) on a common [`Geometry`]:
//!
//! - counts of events with spatio-temporal support (an 8-neighbour event in the preceding
//!   10 ms: the background-activity filter of Delbruck 2008) per cell of scene intensity
//!   (six bins of the frames' DN) x local rate of log-intensity change (seven bins, from the
//!   frames, over as many intervals as the frames' grey levels need: [`change`]) x
//!   polarity: large cells, so that systematic residuals dominate the Poisson
//!   noise of the counts, along the two axes the pixel's dynamics depend on;
//! - the same events per sensor region (a 4 x 3 grid) and polarity (for the residuals);
//! - events without support per intensity bin and polarity: where noise (shot noise,
//!   leak) shows;
//! - the histogram of same-pixel inter-event intervals (log bins, 10 us to 10 s), per
//!   intensity bin of the later event's pixel: refractory periods and timestamp jitter
//!   shape it alike at every brightness, the photoreceptor's bandwidth more in the dark;
//! - per-pixel counts: dispersion within tiles (threshold mismatch), hot pixels;
//! - the event-rate timeline in 1 ms bins (its spectrum shows a display's refresh).
//!
//! Everything is kept per time block: the used frame intervals are grouped into blocks, and
//! some blocks are held out of the fit ([`Subset`]) to judge each added effect on data the
//! fit has not seen.

use crate::estimate::frames::PreparedFrames;
use crate::events::{Sensor, TimeUs};

mod change;
mod count;
pub mod lag;

/// Upper edges of the intensity bins (frame DN; the last bin holds the rest).
pub const INTENSITY_EDGES: [f32; 5] = [10.0, 20.0, 40.0, 80.0, 160.0];
/// Number of intensity bins.
pub const INTENSITY_BINS: usize = INTENSITY_EDGES.len() + 1;
/// Upper edges of the bins of log-intensity change rate (log units per second).
pub const CHANGE_EDGES: [f32; 6] = [0.25, 0.5, 1.0, 2.0, 4.0, 8.0];
pub const CHANGE_BINS: usize = CHANGE_EDGES.len() + 1;
/// Sensor regions for the count cells: a grid of this many columns and rows.
pub const REGIONS_X: usize = 4;
pub const REGIONS_Y: usize = 3;
pub const REGIONS: usize = REGIONS_X * REGIONS_Y;
/// Same-pixel interval histogram: log bins from 10 us, this many per decade, 6 decades.
pub const INTERVAL_FIRST_S: f64 = 1e-5;
pub const INTERVAL_BINS_PER_DECADE: usize = 8;
pub const INTERVAL_BINS: usize = 6 * INTERVAL_BINS_PER_DECADE + 2;
/// The interval histograms kept per block: one per intensity bin, and one for the events
/// of pixels without a reliable intensity (or outside the frames).
pub const INTERVAL_CLASSES: usize = INTENSITY_BINS + 1;
/// Support window of the background counts, microseconds.
pub const SUPPORT_US: TimeUs = 10_000;
/// Side of the tiles of the dispersion statistic, pixels.
pub const TILE_PX: usize = 16;
/// Width of the timeline bins, microseconds.
pub const TIMELINE_BIN_US: TimeUs = 1000;

/// Count cells per block: intensity x change x polarity.
pub const CELLS: usize = INTENSITY_BINS * CHANGE_BINS * 2;

/// The index of a count cell.
#[inline]
pub fn cell_index(intensity: usize, change: usize, polarity: usize) -> usize {
    (intensity * CHANGE_BINS + change) * 2 + polarity
}

/// The (intensity, change, polarity) of a count cell index.
#[inline]
pub fn cell_of(index: usize) -> (usize, usize, usize) {
    (
        index / (2 * CHANGE_BINS),
        (index / 2) % CHANGE_BINS,
        index % 2,
    )
}

/// Which blocks a statistic is taken over.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Subset {
    /// The blocks the fit uses.
    Fit,
    /// The blocks that judge whether an effect is kept (never fitted on).
    Selection,
    /// The blocks that measure the final error (never fitted on, never used to choose).
    Test,
    /// Every block.
    All,
    /// One block (for the spread of a statistic over blocks).
    Block(usize),
}

/// What a block of time is for: fitting, choosing effects, or the final error.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    Fit,
    Selection,
    Test,
}

/// The bin of an interval of `seconds`.
pub fn interval_bin(seconds: f64) -> usize {
    if seconds < INTERVAL_FIRST_S {
        return 0;
    }
    let k = ((seconds / INTERVAL_FIRST_S).log10() * INTERVAL_BINS_PER_DECADE as f64) as usize + 1;
    k.min(INTERVAL_BINS - 1)
}

/// The lower edge of interval bin `k`, seconds.
pub fn interval_bin_start(k: usize) -> f64 {
    if k == 0 {
        0.0
    } else {
        INTERVAL_FIRST_S * 10f64.powf((k - 1) as f64 / INTERVAL_BINS_PER_DECADE as f64)
    }
}

fn bin_of(edges: &[f32], value: f32) -> u8 {
    edges.iter().take_while(|&&e| value >= e).count() as u8
}

/// What the statistics of a recording and of its simulations share: the frame intervals and
/// their blocks, each pixel's intensity and change bins per interval, the regions, the
/// pixels left out, and the pixel-time of each intensity bin.
pub struct Geometry {
    pub sensor: Sensor,
    times: Vec<TimeUs>,
    /// Block of each frame interval (`None`: the interval is not used).
    interval_block: Vec<Option<usize>>,
    pub blocks: usize,
    /// What each block is for.
    pub role: Vec<Role>,
    /// Seconds of frame intervals left out between blocks of different roles (so that a
    /// pixel's state does not carry one role's events into the next).
    pub guard_seconds: f64,
    region: Vec<u8>,
    /// Pixels left out by the user (region of interest, mask).
    excluded: Vec<bool>,
    /// Per frame interval: each pixel's intensity bin (`u8::MAX`: no reliable intensity),
    /// and change bin (empty for unused intervals).
    intensity: Vec<Vec<u8>>,
    change: Vec<Vec<u8>>,
    /// Pixel-seconds per block and intensity bin (reliable, kept pixels).
    pub exposure: Vec<[f64; INTENSITY_BINS]>,
    /// Pixel-seconds per block of still pixels (reliable, kept, in the slowest change bin:
    /// the frames show less than [`CHANGE_EDGES`]`[0]` log units per second), where leak's
    /// ON drift shows without the scene ([`crate::fit::effects::leak::StillBalance`]).
    pub still_exposure: Vec<f64>,
    /// First and last time of the used intervals.
    pub span: (TimeUs, TimeUs),
    /// Median duration of the used frame intervals, seconds: the unit of the recording's
    /// lag behind a simulation ([`lag`]; the frames resolve a change's time to about it).
    pub frame_interval_s: f64,
    /// Spans between blocks of frames read whose events were not read.
    unread: Vec<(TimeUs, TimeUs)>,
    /// Representative DN of each intensity bin (geometric middle).
    pub intensity_centres: [f64; INTENSITY_BINS],
    /// Representative change rate of each change bin (log units per second).
    pub change_centres: [f64; CHANGE_BINS],
}

impl Geometry {
    /// The geometry of `frames` (prepared by the estimators), with about `blocks` time
    /// blocks: those that end by `fit_end` fit, the later ones held out in two contiguous
    /// runs, selection then test ([`roles`]), with one frame interval of guard at each
    /// change of role.
    pub fn new(frames: &PreparedFrames, excluded: &[bool], blocks: usize, fit_end: TimeUs) -> Self {
        let sensor = Sensor::new(frames.width as u16, frames.height as u16);
        let assigned = Blocks::assign(frames, blocks, fit_end);
        let change = interval_change_bins(frames, &assigned.interval_block);
        let measured = Exposure::measure(frames, &assigned, &change, excluded);
        let span = assigned.span(frames);
        let Blocks {
            interval_block,
            blocks,
            role,
            guard_seconds,
            frame_interval_s,
            ..
        } = assigned;
        Self {
            change_centres: change_centres(),
            sensor,
            times: frames.times.clone(),
            unread: frames.unread.clone(),
            interval_block,
            blocks,
            role,
            guard_seconds,
            region: pixel_regions(frames.width, frames.height),
            excluded: excluded.to_vec(),
            intensity: measured.intensity,
            change,
            exposure: measured.per_bin,
            still_exposure: measured.still,
            span,
            frame_interval_s,
            intensity_centres: intensity_centres(),
        }
    }

    /// Whether block `b` belongs to `subset`.
    #[inline]
    pub fn in_subset(&self, b: usize, subset: Subset) -> bool {
        match subset {
            Subset::All => true,
            Subset::Fit => self.role[b] == Role::Fit,
            Subset::Selection => self.role[b] == Role::Selection,
            Subset::Test => self.role[b] == Role::Test,
            Subset::Block(k) => b == k,
        }
    }

    /// The first and last time of `subset`'s frame intervals (`None`: it has none). Each
    /// role's blocks are contiguous in time, so this is where its events fall.
    pub fn time_range_of(&self, subset: Subset) -> Option<(TimeUs, TimeUs)> {
        (0..self.interval_block.len())
            .filter(|&k| self.interval_block[k].is_some_and(|b| self.in_subset(b, subset)))
            .map(|k| (self.times[k], self.times[k + 1]))
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }

    /// Pixel-seconds of intensity bin `bin` over `subset`.
    pub fn exposure_of(&self, bin: usize, subset: Subset) -> f64 {
        (0..self.blocks)
            .filter(|&b| self.in_subset(b, subset))
            .map(|b| self.exposure[b][bin])
            .sum()
    }

    /// Seconds of `subset`.
    pub fn duration_of(&self, subset: Subset) -> f64 {
        (0..self.times.len().saturating_sub(1))
            .filter(|&k| self.interval_block[k].is_some_and(|b| self.in_subset(b, subset)))
            .map(|k| (self.times[k + 1] - self.times[k]) as f64 * 1e-6)
            .sum()
    }

    /// Pixels not left out by the user.
    pub fn kept_pixels(&self) -> usize {
        self.excluded.iter().filter(|&&e| !e).count()
    }

    /// The blocks of `role`.
    pub fn blocks_of(&self, role: Role) -> Vec<usize> {
        (0..self.blocks).filter(|&b| self.role[b] == role).collect()
    }

    /// The subset that judges effects: the selection blocks, or the fit blocks when there
    /// are none (too short a recording, or `holdout` 0).
    pub fn judging(&self) -> Subset {
        if self.role.contains(&Role::Selection) {
            Subset::Selection
        } else {
            Subset::Fit
        }
    }

    /// The subset that measures the final error: the test blocks, else the judging ones.
    pub fn testing(&self) -> Subset {
        if self.role.contains(&Role::Test) {
            Subset::Test
        } else {
            self.judging()
        }
    }
}

/// The roles of `blocks` blocks in time order: the first `fitting` (at least one) fit,
/// then the held-out rest split evenly into selection then test (test gets the odd one).
/// Contiguous runs, so that the starting thresholds can be measured on the fit run alone and
/// held-out data are a later stretch of the recording (blocked evaluation of time series:
/// Bergmeir & Benitez, "On the use of cross-validation for time series predictor
/// evaluation", Information Sciences 2012).
pub fn roles(fitting: usize, blocks: usize) -> Vec<Role> {
    let fit = fitting.clamp(1, blocks.max(1));
    let held = blocks.saturating_sub(fit);
    let test = held.div_ceil(2);
    let mut role = vec![Role::Fit; fit];
    role.extend(std::iter::repeat_n(Role::Selection, held - test));
    role.extend(std::iter::repeat_n(Role::Test, test));
    role
}

/// Leaves out the first used interval of every block whose role differs from the previous
/// block's (when the block has another to keep); returns the seconds left out.
fn guard_intervals(
    interval_block: &mut [Option<usize>],
    role: &[Role],
    durations: &[f64],
    used: &[usize],
) -> f64 {
    let mut guarded = 0.0;
    let assigned = interval_block.to_vec();
    for (i, &k) in used.iter().enumerate() {
        let Some(b) = assigned[k] else { continue };
        let first_of_block = i == 0 || assigned[used[i - 1]] != Some(b);
        let role_changes = b > 0 && role[b - 1] != role[b];
        let more_in_block = used
            .get(i + 1)
            .is_some_and(|&next| assigned[next] == Some(b));
        if first_of_block && role_changes && more_in_block {
            interval_block[k] = None;
            guarded += durations[i] * 1e-6;
        }
    }
    guarded
}

/// The used frame intervals grouped into blocks: each interval's block, each block's role,
/// and the guard intervals left out between roles.
struct Blocks {
    /// The frame intervals with a flow, in time order.
    used: Vec<usize>,
    /// Block of each frame interval (`None`: not used, or a guard).
    interval_block: Vec<Option<usize>>,
    blocks: usize,
    role: Vec<Role>,
    guard_seconds: f64,
    /// Median duration of the used intervals, seconds.
    frame_interval_s: f64,
}

impl Blocks {
    /// Groups the used intervals of `frames` into about `blocks` blocks of equal duration,
    /// gives the blocks their roles by `fit_end` ([`roles`]) and leaves out the guards.
    fn assign(frames: &PreparedFrames, blocks: usize, fit_end: TimeUs) -> Self {
        let used: Vec<usize> = (0..frames.flows.len())
            .filter(|&k| frames.flows[k].is_some())
            .collect();
        let blocks = blocks.clamp(1, used.len().max(1));
        // blocks of about equal duration over the used intervals
        let durations: Vec<f64> = used
            .iter()
            .map(|&k| (frames.times[k + 1] - frames.times[k]) as f64)
            .collect();
        let frame_interval_s = {
            let mut sorted = durations.clone();
            sorted.sort_by(f64::total_cmp);
            sorted.get(sorted.len() / 2).map_or(0.0, |d| d * 1e-6)
        };
        let mut interval_block =
            equal_duration_blocks(frames.flows.len(), &used, &durations, blocks);
        let fitting = fitting_blocks(frames, &used, &interval_block, blocks, fit_end);
        let role = roles(fitting, blocks);
        let guard_seconds = guard_intervals(&mut interval_block, &role, &durations, &used);
        Self {
            used,
            interval_block,
            blocks,
            role,
            guard_seconds,
            frame_interval_s,
        }
    }

    /// The first and last time of the used intervals (`(0, 0)` where there are none).
    fn span(&self, frames: &PreparedFrames) -> (TimeUs, TimeUs) {
        match (self.used.first(), self.used.last()) {
            (Some(&a), Some(&b)) => (frames.times[a], frames.times[b + 1]),
            _ => (0, 0),
        }
    }
}

/// The block of each of `intervals` frame intervals: the `used` ones by where their middle
/// falls in `blocks` equal shares of their total duration, the others `None`.
fn equal_duration_blocks(
    intervals: usize,
    used: &[usize],
    durations: &[f64],
    blocks: usize,
) -> Vec<Option<usize>> {
    let total: f64 = durations.iter().sum();
    let mut interval_block = vec![None; intervals];
    let mut elapsed = 0.0;
    for (i, &k) in used.iter().enumerate() {
        let middle = elapsed + durations[i] / 2.0;
        interval_block[k] = Some(((middle / total * blocks as f64) as usize).min(blocks - 1));
        elapsed += durations[i];
    }
    interval_block
}

/// How many of the `blocks` blocks end by `fit_end` (the blocks that fit).
fn fitting_blocks(
    frames: &PreparedFrames,
    used: &[usize],
    interval_block: &[Option<usize>],
    blocks: usize,
    fit_end: TimeUs,
) -> usize {
    let mut block_end = vec![TimeUs::MIN; blocks];
    for &k in used {
        let b = interval_block[k].expect("assigned");
        block_end[b] = block_end[b].max(frames.times[k + 1]);
    }
    block_end.iter().filter(|&&end| end <= fit_end).count()
}

/// The region of each pixel of a `w` x `h` sensor ([`REGIONS_X`] x [`REGIONS_Y`] grid).
fn pixel_regions(w: usize, h: usize) -> Vec<u8> {
    (0..w * h)
        .map(|p| {
            let (x, y) = (p % w, p / w);
            ((y * REGIONS_Y / h) * REGIONS_X + x * REGIONS_X / w) as u8
        })
        .collect()
}

/// Each frame interval's change bins per pixel (empty for intervals without a block).
fn interval_change_bins(frames: &PreparedFrames, interval_block: &[Option<usize>]) -> Vec<Vec<u8>> {
    let mut change = vec![Vec::new(); frames.flows.len()];
    for (first, end) in frames.runs() {
        let bins = change::run_change_bins(frames, first, end);
        for (k, bins) in (first..end).zip(bins) {
            // guard intervals have no block
            if interval_block[k].is_some() {
                change[k] = bins;
            }
        }
    }
    change
}

/// Each blocked interval's intensity bins per pixel, and the pixel-seconds per block of
/// each intensity bin and of still pixels (reliable, kept pixels).
struct Exposure {
    /// Per frame interval, each pixel's intensity bin (empty for unused intervals).
    intensity: Vec<Vec<u8>>,
    /// Pixel-seconds per block and intensity bin.
    per_bin: Vec<[f64; INTENSITY_BINS]>,
    /// Pixel-seconds per block of still pixels.
    still: Vec<f64>,
}

impl Exposure {
    /// Bins each pixel's intensity in every blocked interval of `frames` and sums the
    /// pixel-seconds of the pixels not `excluded`.
    fn measure(
        frames: &PreparedFrames,
        assigned: &Blocks,
        change: &[Vec<u8>],
        excluded: &[bool],
    ) -> Self {
        let pixels = frames.width * frames.height;
        let mut intensity = vec![Vec::new(); frames.flows.len()];
        let mut per_bin = vec![[0.0; INTENSITY_BINS]; assigned.blocks];
        let mut still = vec![0.0; assigned.blocks];
        for &k in &assigned.used {
            // guard intervals have no block
            let Some(block) = assigned.interval_block[k] else {
                continue;
            };
            let dt = (frames.times[k + 1] - frames.times[k]) as f64 * 1e-6;
            let (a, b) = (&frames.dn[k].data, &frames.dn[k + 1].data);
            let mut bins = vec![u8::MAX; pixels];
            for p in 0..pixels {
                if frames.reliable(k, p) {
                    let bin = bin_of(&INTENSITY_EDGES, 0.5 * (a[p] + b[p]));
                    bins[p] = bin;
                    if !excluded[p] {
                        per_bin[block][bin as usize] += dt;
                        if change[k].get(p) == Some(&0) {
                            still[block] += dt;
                        }
                    }
                }
            }
            intensity[k] = bins;
        }
        Self {
            intensity,
            per_bin,
            still,
        }
    }
}

/// The representative DN of each intensity bin: the geometric middle of its edges (from
/// 3 DN, the last bin to 255).
fn intensity_centres() -> [f64; INTENSITY_BINS] {
    let mut centres = [0.0; INTENSITY_BINS];
    let mut lower = 3.0f64;
    for (i, centre) in centres.iter_mut().enumerate() {
        let upper = INTENSITY_EDGES.get(i).map_or(255.0, |&e| e as f64);
        *centre = (lower * upper).sqrt();
        lower = upper;
    }
    centres
}

/// The representative rate of each change bin (log units per second): the geometric
/// middle of its edges (from 0.1, the last bin to twice its lower edge).
fn change_centres() -> [f64; CHANGE_BINS] {
    let mut centres = [0.0; CHANGE_BINS];
    let mut lower = 0.1f64;
    for (i, centre) in centres.iter_mut().enumerate() {
        let upper = CHANGE_EDGES
            .get(i)
            .map_or(2.0 * lower.max(8.0), |&e| e as f64);
        *centre = (lower * upper).sqrt();
        lower = upper;
    }
    centres
}

/// The statistics of one event set on a [`Geometry`].
#[derive(Clone, Debug)]
pub struct Observed {
    blocks: usize,
    /// Supported events `[block][intensity][change][polarity]`.
    pub cells: Vec<u32>,
    /// Unsupported events `[block][intensity][polarity]`.
    pub background: Vec<u32>,
    /// Supported events `[block][region][polarity]`.
    pub by_region: Vec<u32>,
    /// `[block][intensity class][interval bin]` (class: the later event's intensity bin,
    /// [`INTENSITY_BINS`] where it has none).
    pub intervals: Vec<u32>,
    /// Events per pixel, `[block][pixel]`.
    pub pixel_counts: Vec<u32>,
    /// `[block][polarity]`.
    pub polarity: Vec<[u64; 2]>,
    /// Events at still pixels (the slowest change bin, reliable intensity), supported or
    /// not, `[block][polarity]`.
    pub still: Vec<[u64; 2]>,
    /// Events per 1 ms bin from the start of the used span.
    pub timeline: Vec<u32>,
    /// A simulation's only: the recording's offsets from it, `[block][intensity][polarity]
    /// [offset bin]` for each pairing ([`lag`]); empty for the recording itself.
    pub lag: lag::LagHistograms,
}

impl Observed {
    /// Count cells (see [`cell_index`]) summed over `subset`.
    pub fn cells_of(&self, g: &Geometry, subset: Subset) -> Vec<u32> {
        sum_blocks(&self.cells, CELLS, self.blocks, |b| g.in_subset(b, subset))
    }

    /// Supported events `[region][polarity]` over `subset`.
    pub fn regions_of(&self, g: &Geometry, subset: Subset) -> Vec<u32> {
        sum_blocks(&self.by_region, REGIONS * 2, self.blocks, |b| {
            g.in_subset(b, subset)
        })
    }

    /// Unsupported events `[intensity][polarity]` over `subset`.
    pub fn background_of(&self, g: &Geometry, subset: Subset) -> Vec<u32> {
        sum_blocks(&self.background, INTENSITY_BINS * 2, self.blocks, |b| {
            g.in_subset(b, subset)
        })
    }

    /// The same-pixel interval histogram over `subset`.
    pub fn intervals_of(&self, g: &Geometry, subset: Subset) -> Vec<u32> {
        let by_class = self.intervals_by_intensity_of(g, subset);
        (0..INTERVAL_BINS)
            .map(|k| by_class.iter().map(|h| h[k]).sum())
            .collect()
    }

    /// The same-pixel interval histogram over `subset` per intensity class (the intensity
    /// bins, then the events without one).
    pub fn intervals_by_intensity_of(&self, g: &Geometry, subset: Subset) -> Vec<Vec<u32>> {
        let all = sum_blocks(
            &self.intervals,
            INTERVAL_CLASSES * INTERVAL_BINS,
            self.blocks,
            |b| g.in_subset(b, subset),
        );
        all.chunks(INTERVAL_BINS).map(<[u32]>::to_vec).collect()
    }

    /// The event-rate timeline over `subset`'s time range ([`Geometry::time_range_of`]).
    pub fn timeline_of(&self, g: &Geometry, subset: Subset) -> &[u32] {
        let Some((a, b)) = g.time_range_of(subset) else {
            return &[];
        };
        let bin = |t: TimeUs| ((t - g.span.0) / TIMELINE_BIN_US).max(0) as usize;
        let to = (bin(b) + 1).min(self.timeline.len());
        &self.timeline[bin(a).min(to)..to]
    }

    /// ON and OFF events over `subset`.
    pub fn polarity_of(&self, g: &Geometry, subset: Subset) -> [u64; 2] {
        sum_polarities(&self.polarity, g, subset)
    }

    /// ON and OFF events at still pixels over `subset` ([`Geometry::still_exposure`]).
    pub fn still_of(&self, g: &Geometry, subset: Subset) -> [u64; 2] {
        sum_polarities(&self.still, g, subset)
    }

    /// Per-pixel counts over `subset`.
    pub fn pixels_of(&self, g: &Geometry, subset: Subset) -> Vec<u32> {
        let pixels = self.pixel_counts.len() / self.blocks;
        sum_blocks(&self.pixel_counts, pixels, self.blocks, |b| {
            g.in_subset(b, subset)
        })
    }

    /// The recording's median offset from this simulation per intensity bin over
    /// `subset`, every supported event paired, both polarities pooled (seconds, and the
    /// paired events), where
    /// [`lag::MIN_LAG_EVENTS`] were paired.
    pub fn lag_of(&self, g: &Geometry, subset: Subset) -> [Option<lag::BinLag>; INTENSITY_BINS] {
        self.per_lag_bin(g, subset, lag::Pairing::EveryEvent, |hist| {
            let (off, on) = hist.split_at(lag::LAG_BINS);
            let pooled: Vec<u32> = off.iter().zip(on).map(|(a, b)| a + b).collect();
            lag::bin_lag(&pooled).filter(|l| l.events >= lag::MIN_LAG_EVENTS)
        })
    }

    /// The recording's delay behind this simulation per intensity bin over `subset`
    /// ([`lag::delay_of`] of the burst starts: the delay both the ON and OFF median offsets
    /// show, seconds),
    /// where each polarity has [`lag::MIN_LAG_EVENTS`] paired events.
    pub fn delay_of(
        &self,
        g: &Geometry,
        subset: Subset,
    ) -> [Option<lag::BinDelay>; INTENSITY_BINS] {
        self.per_lag_bin(g, subset, lag::Pairing::BurstStarts, lag::delay_of)
    }

    /// `read` of each intensity bin's offset histograms (OFF then ON) over `subset`.
    fn per_lag_bin<T: Copy>(
        &self,
        g: &Geometry,
        subset: Subset,
        pairing: lag::Pairing,
        read: impl Fn(&[u32]) -> Option<T>,
    ) -> [Option<T>; INTENSITY_BINS] {
        let mut out = [None; INTENSITY_BINS];
        let histograms = self.lag.of(pairing);
        if histograms.is_empty() {
            return out;
        }
        let all = sum_blocks(
            histograms,
            INTENSITY_BINS * 2 * lag::LAG_BINS,
            self.blocks,
            |b| g.in_subset(b, subset),
        );
        for (bin, hist) in all.chunks(2 * lag::LAG_BINS).enumerate() {
            out[bin] = read(hist);
        }
        out
    }

    /// Events over `subset`.
    pub fn total(&self, g: &Geometry, subset: Subset) -> u64 {
        let [off, on] = self.polarity_of(g, subset);
        on + off
    }
}

/// Per-block `[OFF, ON]` counts summed over `subset`.
fn sum_polarities(per_block: &[[u64; 2]], g: &Geometry, subset: Subset) -> [u64; 2] {
    let mut out = [0; 2];
    for (b, counts) in per_block.iter().enumerate() {
        if g.in_subset(b, subset) {
            out[0] += counts[0];
            out[1] += counts[1];
        }
    }
    out
}

fn sum_blocks(
    values: &[u32],
    size: usize,
    blocks: usize,
    keep: impl Fn(usize) -> bool,
) -> Vec<u32> {
    let mut out = vec![0; size];
    for b in (0..blocks).filter(|&b| keep(b)) {
        for (o, &v) in out.iter_mut().zip(&values[b * size..(b + 1) * size]) {
            *o += v;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interval_bins_are_log_spaced_from_10_us() {
        assert_eq!(interval_bin(5e-6), 0);
        assert_eq!(interval_bin(1e-5), 1);
        assert_eq!(interval_bin(1e-4), 1 + INTERVAL_BINS_PER_DECADE);
        assert_eq!(interval_bin(5e-3), 1 + 2 * 8 + (8.0 * 0.69897f64) as usize);
        assert_eq!(interval_bin(1e3), INTERVAL_BINS - 1);
        assert!((interval_bin_start(1 + 8) - 1e-4).abs() < 1e-12);
    }

    #[test]
    fn roles_are_fit_then_selection_then_test() {
        use Role::*;
        assert_eq!(
            roles(7, 10),
            [Fit, Fit, Fit, Fit, Fit, Fit, Fit, Selection, Test, Test]
        );
        assert_eq!(roles(6, 10)[6..], [Selection, Selection, Test, Test]);
        assert_eq!(roles(2, 3), [Fit, Fit, Test]);
        assert_eq!(roles(0, 1), [Fit]);
        assert_eq!(roles(4, 4), [Fit; 4]);
    }

    #[test]
    fn guards_sit_where_the_role_changes() {
        use Role::*;
        let role = [Fit, Fit, Selection, Test];
        // three intervals per block, the last block with one
        let used: Vec<usize> = (0..10).collect();
        let mut block: Vec<Option<usize>> = [0, 0, 0, 1, 1, 1, 2, 2, 2, 3]
            .into_iter()
            .map(Some)
            .collect();
        let seconds = guard_intervals(&mut block, &role, &[1e6; 10], &used);
        let expected: Vec<Option<usize>> = [
            Some(0),
            Some(0),
            Some(0),
            Some(1),
            Some(1),
            Some(1),
            None,
            Some(2),
            Some(2),
            Some(3),
        ]
        .to_vec();
        assert_eq!(block, expected);
        assert_eq!(seconds, 1.0);
    }
}
