//! What `estimate eppps` measures of the recording: events per pixel of scene travel, per
//! polarity, with the sensor's noise taken out. Dividing by travel removes the
//! speed of the motion; counting only 8 x 8 tiles that hold signal, not the whole view,
//! removes how much of the view is blank or static (the two mismatches that made raw events per pixel per
//! second read a sensor as having high thresholds when its view barely moved).
//!
//! Travel comes from the optical flow: of the frames where there are frames (each pixel's
//! path over every used interval), else of the events themselves by contrast maximisation
//! ([`crate::estimate::event_flow`]), per patch (32 px, larger for a sparse recording) and
//! time window. A window too sparse for a flow is left out, its events with it; one whose
//! flow is not trusted takes the recording's median speed.
//!
//! Noise: events count when a neighbour fired within a few pixel-crossings before or after
//! them (a two-sided support filter: an edge's first event, or an event at the start of a
//! short recording, is not noise for want of a past). The filter still drops some isolated
//! signal events (a few per cent of an ideal pixel's over a sparse texture), which no scan
//! drops, and keeps the rare noise event that lands next to signal; so the unsupported
//! events of the pixels that have signal are split down the middle: the rate is the
//! geometric mean of "none of them are signal" and "all of them are", and half that range
//! (as a uniform spread) is a systematic of the interval.

use crate::estimate::event_flow::{EventFlowOptions, PatchFlow, patch_flows};
use crate::estimate::frames::PreparedFrames;
use crate::events::{EventChunk, Sensor, TimeUs};
use crate::stats::support::supported_two_sided as supported;
use rand::{RngExt, SeedableRng};

/// The recording's side of the comparison.
#[derive(Clone, Debug)]
pub struct RecordingRates {
    /// Supported ON and OFF events per pixel of travel, over the pixels that count.
    pub on_per_px: f64,
    pub off_per_px: f64,
    /// Standard errors of the logarithms of the two (bootstrap over 32 px patches).
    pub ln_se_on: f64,
    pub ln_se_off: f64,
    /// Relative error of the travel (the flow's precision), a systematic of both.
    pub travel_relative_error: f64,
    /// Relative systematic of the counts: half the log range between supported and all
    /// events of the pixels with signal, as a uniform spread.
    pub noise_relative_error: f64,
    /// Share of the counted events without support.
    pub unsupported_share: f64,
    /// Units that count (8 x 8 tiles with signal, without frames; every reliable pixel,
    /// with frames) and all pixels kept.
    pub counted_units: usize,
    pub kept_pixels: usize,
    /// Total travel of the counted pixels, pixels; and the time it took, seconds.
    pub counted_travel_px: f64,
    pub duration_s: f64,
    /// Supported events per kept pixel per second (the raw rate of the paper's method).
    pub events_per_pixel_per_second: f64,
    /// Median flow speed, px/s, and its source.
    pub speed_median_px_s: f64,
    pub flow_source: String,
    /// Travel (px, per pixel) and flow direction (unit vector) of the counted units, for
    /// the scans.
    pub travels: Vec<f32>,
    pub directions: Vec<(f32, f32)>,
    pub support_window_us: TimeUs,
    /// How the recording's events follow each other at a pixel (without frames: how sharp
    /// its scene is, to read the prior at).
    pub bursts: Option<BurstShare>,
}

/// Of a recording's consecutive supported events of one polarity at a pixel, how many
/// (`pairs`) and how many within [`super::scans::BURST_PX`] of travel at their window's
/// flow (`bursts`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BurstShare {
    pub pairs: usize,
    pub bursts: usize,
}

impl BurstShare {
    pub fn fraction(self) -> f64 {
        self.bursts as f64 / self.pairs.max(1) as f64
    }

    /// Counts the consecutive events of `events` (time-sorted) at each pixel and polarity
    /// among those that count: supported, not excluded, and in a window whose flow
    /// `speed_px_s(i, pixel)` gives (`None`: not counted).
    fn measure(
        events: &EventChunk,
        sensor: Sensor,
        excluded: &[bool],
        support: &[bool],
        speed_px_s: impl Fn(usize, usize) -> Option<f64>,
    ) -> Self {
        let w = sensor.width as usize;
        let mut last = vec![TimeUs::MIN; 2 * sensor.pixels()];
        let mut share = BurstShare::default();
        for (i, &supported) in support.iter().enumerate().take(events.len()) {
            let pixel = events.y[i] as usize * w + events.x[i] as usize;
            if !supported || excluded[pixel] {
                continue;
            }
            let Some(speed) = speed_px_s(i, pixel) else {
                continue;
            };
            let slot = &mut last[2 * pixel + events.on[i] as usize];
            if *slot != TimeUs::MIN {
                share.pairs += 1;
                let travel = (events.t[i] - *slot) as f64 * 1e-6 * speed;
                share.bursts += (travel < super::scans::BURST_PX) as usize;
            }
            *slot = events.t[i];
        }
        share
    }
}

/// Per 32-px patch sums, for the bootstrap: ON, OFF, travel.
type Groups = Vec<[f64; 3]>;

/// Side of the bootstrap patches, pixels.
const PATCH_PX: usize = 32;

/// Log standard errors of the ON and OFF rates by a bootstrap over patches.
fn bootstrap(groups: &Groups) -> (f64, f64) {
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(31);
    let n = groups.len();
    if n < 2 {
        return (f64::NAN, f64::NAN);
    }
    let (mut on, mut off) = (Vec::with_capacity(200), Vec::with_capacity(200));
    for _ in 0..200 {
        let mut s = [0.0; 3];
        for _ in 0..n {
            let g = groups[rng.random_range(0..n)];
            s = [s[0] + g[0], s[1] + g[1], s[2] + g[2]];
        }
        if s[0] > 0.0 && s[1] > 0.0 && s[2] > 0.0 {
            on.push((s[0] / s[2]).ln());
            off.push((s[1] / s[2]).ln());
        }
    }
    (std_dev(&on), std_dev(&off))
}

fn std_dev(v: &[f64]) -> f64 {
    crate::stats::robust::sample_std_dev(v).unwrap_or(f64::NAN)
}

/// The support window: three pixel-crossings of the typical motion, 10-100 ms.
fn support_window(speed: f64) -> TimeUs {
    ((3.0 / speed.max(1e-3)) * 1e6).clamp(10_000.0, 100_000.0) as TimeUs
}

fn duration_s(events: &EventChunk) -> f64 {
    (events.t[events.len() - 1] - events.t[0]) as f64 * 1e-6
}

/// Events per pixel of the part that is compared: all, and those with support.
struct Tally {
    all: Vec<[f64; 2]>,
    supported: Vec<[f64; 2]>,
}

impl Tally {
    /// Tallies `events`; `counted(i, pixel)` says whether event `i` is in a counted cell.
    fn new(
        events: &EventChunk,
        sensor: Sensor,
        excluded: &[bool],
        support: &[bool],
        counted: impl Fn(usize, usize) -> bool,
    ) -> Self {
        let pixels = sensor.pixels();
        let w = sensor.width as usize;
        let mut t = Tally {
            all: vec![[0.0; 2]; pixels],
            supported: vec![[0.0; 2]; pixels],
        };
        for (i, &supported) in support.iter().enumerate().take(events.len()) {
            let pixel = events.y[i] as usize * w + events.x[i] as usize;
            if excluded[pixel] || !counted(i, pixel) {
                continue;
            }
            let pol = if events.on[i] { 0 } else { 1 };
            t.all[pixel][pol] += 1.0;
            if supported {
                t.supported[pixel][pol] += 1.0;
            }
        }
        t
    }
}

/// What turns a tally into rates besides the travel.
struct Finish {
    kept: usize,
    duration: f64,
    supported_total: f64,
    speed: f64,
    source: String,
    travel_error: f64,
    window: TimeUs,
    bursts: Option<BurstShare>,
}

/// Per-pixel travel (px) and flow direction; travel 0: not counted.
struct Paths {
    travel: Vec<f64>,
    direction: Vec<(f32, f32)>,
    /// The units pixels are counted in: 8 x 8 tiles of which only those with signal count
    /// (without frames), or single pixels that all count (with frames).
    tile_px: Option<usize>,
}

/// One counting unit's sums: ON and OFF events (all, and supported), travel (px), pixels,
/// direction.
#[derive(Clone, Copy, Default)]
struct Unit {
    all: [f64; 2],
    supported: [f64; 2],
    travel: f64,
    pixels: usize,
    direction: (f32, f32),
}

/// The counting units of a tally: tiles or pixels.
fn units(tally: &Tally, paths: &Paths, excluded: &[bool], w: usize) -> Vec<(usize, Unit)> {
    let side = paths.tile_px.unwrap_or(1);
    let tiles_x = w.div_ceil(side);
    let mut out = vec![Unit::default(); tiles_x * (excluded.len() / w).div_ceil(side)];
    for pixel in 0..excluded.len() {
        if excluded[pixel] || paths.travel[pixel] <= 0.0 {
            continue;
        }
        let u = &mut out[(pixel / w / side) * tiles_x + (pixel % w) / side];
        for k in 0..2 {
            u.all[k] += tally.all[pixel][k];
            u.supported[k] += tally.supported[pixel][k];
        }
        u.travel += paths.travel[pixel];
        u.pixels += 1;
        u.direction = paths.direction[pixel];
    }
    // the unit's first pixel, for the bootstrap patch it falls in
    out.into_iter()
        .enumerate()
        .map(|(k, u)| (((k / tiles_x) * side) * w + (k % tiles_x) * side, u))
        .filter(|(_, u)| u.pixels > 0)
        .collect()
}

/// Rates from a tally and the pixels' paths: per unit with signal (a supported event), the
/// geometric mean of its supported and of all its events (see the module docs).
fn finish(
    tally: &Tally,
    paths: &Paths,
    excluded: &[bool],
    w: usize,
    f: Finish,
) -> Option<RecordingRates> {
    let tiles_x = w.div_ceil(PATCH_PX);
    let mut groups: Groups = vec![[0.0; 3]; tiles_x * (excluded.len() / w).div_ceil(PATCH_PX)];
    let (mut travels, mut directions) = (Vec::new(), Vec::new());
    let (mut all_total, mut supported_total) = (0.0, 0.0);
    for (first, u) in units(tally, paths, excluded, w) {
        let signal = u.supported[0] + u.supported[1] > 0.0;
        if paths.tile_px.is_some() && !signal {
            continue;
        }
        // unsupported events count only where there is signal
        let all = if signal { u.all } else { u.supported };
        all_total += all[0] + all[1];
        supported_total += u.supported[0] + u.supported[1];
        let g = &mut groups[(first / w / PATCH_PX) * tiles_x + (first % w) / PATCH_PX];
        *g = [g[0] + all[0], g[1] + all[1], g[2] + u.travel];
        travels.push((u.travel / u.pixels as f64) as f32);
        directions.push(u.direction);
    }
    let total = groups
        .iter()
        .fold([0.0; 3], |s, g| [s[0] + g[0], s[1] + g[1], s[2] + g[2]]);
    if total[2] <= 0.0 || travels.is_empty() || supported_total <= 0.0 {
        return None;
    }
    let groups: Groups = groups.into_iter().filter(|g| g[2] > 0.0).collect();
    let (ln_se_on, ln_se_off) = bootstrap(&groups);
    // the middle of the bracket [supported, all]: the all-event rates scaled down by half
    // the log range
    let half_range = 0.5 * (all_total / supported_total).ln();
    let middle = (-half_range).exp();
    Some(RecordingRates {
        on_per_px: middle * total[0] / total[2],
        off_per_px: middle * total[1] / total[2],
        ln_se_on,
        ln_se_off,
        travel_relative_error: f.travel_error,
        noise_relative_error: half_range / 3f64.sqrt(),
        unsupported_share: 1.0 - supported_total / all_total.max(1.0),
        counted_units: travels.len(),
        kept_pixels: f.kept,
        counted_travel_px: total[2],
        duration_s: f.duration,
        events_per_pixel_per_second: f.supported_total
            / (f.kept.max(1) as f64 * f.duration.max(1e-9)),
        speed_median_px_s: f.speed,
        flow_source: f.source,
        travels,
        directions,
        support_window_us: f.window,
        bursts: f.bursts,
    })
}

/// The recording's rates with travel from the events' own flow.
pub fn from_events(
    events: &EventChunk,
    sensor: Sensor,
    excluded: &[bool],
) -> Option<RecordingRates> {
    let options = EventFlowOptions::default();
    let flows = patch_flows(events, sensor, excluded, &options);
    let mut trusted: Vec<f64> = flows
        .iter()
        .filter(|f| f.trusted())
        .map(PatchFlow::speed)
        .collect();
    if trusted.is_empty() {
        return None;
    }
    trusted.sort_by(f64::total_cmp);
    let median = trusted[trusted.len() / 2];
    let window = support_window(median);
    let support = supported(events, sensor, window);
    // the patch side the flow settled on (larger than asked for a sparse recording)
    let p = flows.first().map_or(options.patch_px, |f| f.size);
    let (w, tiles_x) = (sensor.width as usize, (sensor.width as usize).div_ceil(p));
    let tiles = tiles_x * (sensor.height as usize).div_ceil(p);
    let mut by_patch: Vec<Vec<&PatchFlow>> = vec![Vec::new(); tiles];
    for f in &flows {
        by_patch[(f.y0 / p) * tiles_x + f.x0 / p].push(f);
    }
    let patch_of = |pixel: usize| (pixel / w / p) * tiles_x + (pixel % w) / p;
    let tally = Tally::new(events, sensor, excluded, &support, |i, pixel| {
        let t = events.t[i];
        by_patch[patch_of(pixel)]
            .iter()
            .any(|f| f.t_start <= t && t <= f.t_end)
    });
    let bursts = BurstShare::measure(events, sensor, excluded, &support, |i, pixel| {
        let t = events.t[i];
        by_patch[patch_of(pixel)]
            .iter()
            .find(|f| f.t_start <= t && t <= f.t_end)
            .map(|f| if f.trusted() { f.speed() } else { median })
    });
    let (patches, travel_error) = patch_paths(&by_patch, median);
    let pixels = sensor.pixels();
    let paths = Paths {
        travel: (0..pixels).map(|q| patches[patch_of(q)].0).collect(),
        direction: (0..pixels).map(|q| patches[patch_of(q)].1).collect(),
        tile_px: Some(super::scans::TILE_PX),
    };
    let finish_with = Finish {
        kept: excluded.iter().filter(|&&e| !e).count(),
        duration: duration_s(events),
        supported_total: support.iter().filter(|&&s| s).count() as f64,
        speed: median,
        source: format!("the events (contrast maximisation per {p} px patch)"),
        travel_error,
        window,
        bursts: Some(bursts),
    };
    finish(&tally, &paths, excluded, w, finish_with)
}

/// Each patch's travel (px) and the direction of its longest trusted window, and the
/// event-weighted relative precision of the travel: its windows at their own speed, or the
/// median speed when not trusted.
/// A patch's travel (px) and direction.
type PatchPath = (f64, (f32, f32));

fn patch_paths(by_patch: &[Vec<&PatchFlow>], median: f64) -> (Vec<PatchPath>, f64) {
    let (mut weighted, mut weight) = (0.0, 0.0);
    let paths = by_patch
        .iter()
        .map(|windows| {
            let (mut travel, mut longest) = (0.0, 0.0);
            let mut direction = (1.0f32, 0.0f32);
            for f in windows {
                let span = (f.t_end - f.t_start) as f64 * 1e-6;
                let speed = if f.trusted() { f.speed() } else { median };
                let d = speed * span;
                travel += d;
                // the flow's resolution: half a pixel of displacement, or the split-half
                // spread where larger
                let relative = (0.5 / d.max(0.5)).max(f.speed_standard_error / speed.max(1e-9));
                weighted += relative * f.events as f64;
                weight += f.events as f64;
                if d > longest && f.trusted() {
                    longest = d;
                    let s = f.speed().max(1e-9);
                    direction = ((f.vx / s) as f32, (f.vy / s) as f32);
                }
            }
            (travel, direction)
        })
        .collect();
    (paths, weighted / weight.max(1.0))
}

/// The recording's rates with travel from the frames' flow: every reliable pixel of every
/// used interval counts (the scans follow the same paths, so nothing needs to have fired).
pub fn from_frames(
    events: &EventChunk,
    frames: &PreparedFrames,
    sensor: Sensor,
    excluded: &[bool],
) -> Option<RecordingRates> {
    let (w, pixels) = (frames.width, frames.width * frames.height);
    let mut speeds = Vec::new();
    let mut paths = Paths {
        travel: vec![0.0; pixels],
        direction: vec![(1.0, 0.0); pixels],
        tile_px: None,
    };
    for (k, flow) in frames.flows.iter().enumerate() {
        let Some(flow) = flow else { continue };
        let dt = (frames.times[k + 1] - frames.times[k]) as f64 * 1e-6;
        for (pixel, m) in flow.magnitudes().iter().enumerate() {
            speeds.push(*m as f64 / dt);
            if frames.reliable(k, pixel) {
                paths.travel[pixel] += *m as f64;
            }
        }
    }
    if speeds.is_empty() {
        return None;
    }
    speeds.sort_by(f64::total_cmp);
    let median = speeds[speeds.len() / 2];
    let window = support_window(median);
    let support = supported(events, sensor, window);
    let tally = Tally::new(events, sensor, excluded, &support, |i, pixel| {
        frames
            .interval_of(events.t[i])
            .is_some_and(|k| frames.reliable(k, pixel))
    });
    let finish_with = Finish {
        kept: excluded.iter().filter(|&&e| !e).count(),
        duration: duration_s(events),
        supported_total: support.iter().filter(|&&s| s).count() as f64,
        speed: median,
        source: "the frames (pyramidal Lucas-Kanade)".into(),
        travel_error: 0.0,
        window,
        // the frames measure the scene's contrast: no prior to read at its sharpness
        bursts: None,
    };
    finish(&tally, &paths, excluded, w, finish_with)
}
