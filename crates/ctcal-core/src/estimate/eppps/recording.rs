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
//! short recording, is not noise for want of a past). Where the motion is slow that window
//! is long, and a noise event finds a neighbour by chance: at each pixel with the
//! probability [`crate::stats::chance_support`] measures (the share of time within the
//! window of a neighbour's event). The unsupported events are then only the part of the
//! noise that chance left alone: their count (Garwood's 97.5 % upper end) over the time no
//! neighbour covers, in every unit, is a noise rate, and that rate over the time the
//! counted units count is the noise they hold (noise fires at one rate across the view).
//! The filter also drops some isolated signal events (a few per cent of an ideal pixel's
//! over a sparse texture), so that is the most the noise can be: per polarity the rate
//! lies between "none of the events are noise" and "that much of them is", the estimate is
//! the geometric mean of the two, and half their log range (as a uniform spread) is a
//! systematic of the interval. Where the noise may be every event of a polarity, its
//! threshold is not determinable.

use super::still::StillPixels;
use crate::estimate::event_flow::{EventFlowOptions, PatchFlow, patch_flows};
use crate::estimate::frames::PreparedFrames;
use crate::events::{EventChunk, Sensor, TimeUs};
use crate::stats::chance_support::covered_time;
use crate::stats::support::supported_two_sided as supported;
use rand::{RngExt, SeedableRng};

/// The recording's side of the comparison.
#[derive(Clone, Debug)]
pub struct RecordingRates {
    /// ON and OFF events per pixel of travel over the units that count, with the noise
    /// taken out (the middle of the noise bracket; all events where the noise may be every
    /// event, see `noise`).
    pub on_per_px: f64,
    pub off_per_px: f64,
    /// Standard errors of the logarithms of the two (bootstrap over 32 px patches).
    pub ln_se_on: f64,
    pub ln_se_off: f64,
    /// Relative error of the travel (the flow's precision), a systematic of both.
    pub travel_relative_error: f64,
    /// The ON and OFF noise brackets.
    pub noise: [NoiseBracket; 2],
    /// Share of the counted events without support.
    pub unsupported_share: f64,
    /// The probability that a noise event at a counted pixel finds support by chance
    /// (mean over the counted pixels, weighted by the time each counts).
    pub chance_support: f64,
    /// Units that count (8 x 8 tiles with signal, without frames; every reliable pixel,
    /// with frames), the units that moved (tiles with a kept pixel the flow moves, partial
    /// ones at the view's edges included; reliable pixels that moved) and all pixels kept.
    pub counted_units: usize,
    pub units: usize,
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
    /// The frames' median brightness, DN, over the reliable pixels of the intervals the
    /// travel was measured on (`None` without frames): how dim the scene is, where a
    /// photoreceptor's bandwidth and leak weigh most.
    pub frames_median_dn: Option<f64>,
    /// Whether the recording's own frames stand in for the prior's photographs (frames whose
    /// flow the motion outruns: travel from the events, contrast from the frames).
    pub frame_images: bool,
    /// The pixels whose frames show a still scene, and their events (with frames only),
    /// and per polarity (ON, OFF) whether their rate decided the noise bracket.
    pub still: Option<StillPixels>,
    pub still_decides: [bool; 2],
    /// ON and OFF events of the units that count, and their counted pixel-seconds.
    pub counted_events: [f64; 2],
    pub counted_exposure_s: f64,
}

impl RecordingRates {
    /// These rates with the still pixels' background in the noise brackets where it
    /// exceeds the support filter's bound ([`StillPixels::bracket`]), the scene's own
    /// events at still pixels read at `thresholds` (ON, OFF: as read without them) taken
    /// off first; `None` where nothing changes.
    pub fn with_still_background(&self, thresholds: [f64; 2]) -> Option<RecordingRates> {
        let still = self.still.as_ref()?;
        let mut out = self.clone();
        for (k, &threshold) in thresholds.iter().enumerate() {
            let support = &self.noise[k];
            let Some(b) = still.bracket(
                k,
                support,
                (self.counted_events[k], self.counted_exposure_s),
                threshold,
            ) else {
                continue;
            };
            let rescale = b.middle / support.middle;
            if k == 0 {
                out.on_per_px *= rescale;
            } else {
                out.off_per_px *= rescale;
            }
            (out.noise[k], out.still_decides[k]) = (b, true);
        }
        (out.still_decides != self.still_decides).then_some(out)
    }
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

fn seconds(times: Vec<TimeUs>) -> Vec<f64> {
    times.into_iter().map(|t| t as f64 * 1e-6).collect()
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
    frames_median_dn: Option<f64>,
    still: Option<StillPixels>,
    /// How much of each pixel's counted time lies within the window of a neighbour's
    /// event, seconds: where a noise event would find support by chance.
    covered_s: Vec<f64>,
}

/// Per-pixel travel (px), flow direction and time counted (s); travel 0: not counted.
struct Paths {
    travel: Vec<f64>,
    direction: Vec<(f32, f32)>,
    exposure_s: Vec<f64>,
    /// The units pixels are counted in: 8 x 8 tiles of which only those with signal count
    /// (without frames), or single pixels that all count (with frames).
    tile_px: Option<usize>,
}

/// One counting unit's sums: ON and OFF events (all, and supported), travel (px), pixels,
/// direction, the time its pixels count (s) and that time weighted by the chance that a
/// noise event goes unsupported.
#[derive(Clone, Copy, Default)]
struct Unit {
    all: [f64; 2],
    supported: [f64; 2],
    travel: f64,
    pixels: usize,
    direction: (f32, f32),
    exposure_s: f64,
    unsupported_exposure_s: f64,
}

/// The counting units of a tally: tiles or pixels; `covered_s`: each pixel's counted time
/// within the window of a neighbour's event.
fn units(
    tally: &Tally,
    paths: &Paths,
    covered_s: &[f64],
    excluded: &[bool],
    w: usize,
) -> Vec<(usize, Unit)> {
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
        u.exposure_s += paths.exposure_s[pixel];
        u.unsupported_exposure_s += (paths.exposure_s[pixel] - covered_s[pixel]).max(0.0);
    }
    // the unit's first pixel, for the bootstrap patch it falls in
    out.into_iter()
        .enumerate()
        .map(|(k, u)| (((k / tiles_x) * side) * w + (k % tiles_x) * side, u))
        .filter(|(_, u)| u.pixels > 0)
        .collect()
}

/// The units summed: the patches' sums for the bootstrap, the travel and direction of
/// each unit that counts, the noise tally over every unit, and how many units there are.
struct Counted {
    groups: Groups,
    travels: Vec<f32>,
    directions: Vec<(f32, f32)>,
    noise: NoiseTally,
    unit_count: usize,
}

impl Counted {
    /// Sums the units of `tally` (see [`units`]): every unit into the noise rate, those
    /// that count into their patch's group and the scans' travels.
    fn sum(tally: &Tally, paths: &Paths, covered_s: &[f64], excluded: &[bool], w: usize) -> Self {
        let tiles_x = w.div_ceil(PATCH_PX);
        let mut groups: Groups = vec![[0.0; 3]; tiles_x * (excluded.len() / w).div_ceil(PATCH_PX)];
        let (mut travels, mut directions) = (Vec::new(), Vec::new());
        let mut noise = NoiseTally::default();
        let mut unit_count = 0;
        for (first, u) in units(tally, paths, covered_s, excluded, w) {
            unit_count += 1;
            // a tile counts where it has signal (a supported event: blank parts of the view
            // travel without events); a reliable pixel counts whatever fired there, since
            // choosing pixels by their own support would choose them by their noise too
            let counts = paths.tile_px.is_none() || u.supported[0] + u.supported[1] > 0.0;
            // the noise rate from every unit, its count where the unit counts
            noise.add(&u, counts);
            if !counts {
                continue;
            }
            let all = u.all;
            let g = &mut groups[(first / w / PATCH_PX) * tiles_x + (first % w) / PATCH_PX];
            *g = [g[0] + all[0], g[1] + all[1], g[2] + u.travel];
            travels.push((u.travel / u.pixels as f64) as f32);
            directions.push(u.direction);
        }
        Counted {
            groups,
            travels,
            directions,
            noise,
            unit_count,
        }
    }
}

/// Rates from a tally and the pixels' paths: per polarity, over the units that count
/// (reliable pixels; tiles with a supported event), the geometric mean of all their events
/// and all but the most noise they can hold (see the module docs).
fn finish(
    tally: &Tally,
    paths: &Paths,
    excluded: &[bool],
    w: usize,
    f: Finish,
) -> Option<RecordingRates> {
    let Counted {
        groups,
        travels,
        directions,
        noise,
        unit_count,
    } = Counted::sum(tally, paths, &f.covered_s, excluded, w);
    let total = groups
        .iter()
        .fold([0.0; 3], |s, g| [s[0] + g[0], s[1] + g[1], s[2] + g[2]]);
    let supported_total = noise.supported[0] + noise.supported[1];
    if total[2] <= 0.0 || travels.is_empty() || supported_total <= 0.0 {
        return None;
    }
    let groups: Groups = groups.into_iter().filter(|g| g[2] > 0.0).collect();
    let (ln_se_on, ln_se_off) = bootstrap(&groups);
    let brackets = [0, 1].map(|k| noise.bracket(k, f.window));
    let all_total = noise.all[0] + noise.all[1];
    Some(RecordingRates {
        on_per_px: brackets[0].middle * total[0] / total[2],
        off_per_px: brackets[1].middle * total[1] / total[2],
        ln_se_on,
        ln_se_off,
        travel_relative_error: f.travel_error,
        noise: brackets,
        unsupported_share: 1.0 - supported_total / all_total.max(1.0),
        chance_support: 1.0 - noise.unsupported_exposure_s / noise.exposure_s.max(1e-12),
        counted_units: travels.len(),
        units: unit_count,
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
        frames_median_dn: f.frames_median_dn,
        frame_images: false,
        still: f.still,
        still_decides: [false; 2],
        counted_events: noise.all,
        counted_exposure_s: noise.exposure_s,
    })
}

/// The units, summed for the noise bracket: of every unit, the ON and OFF events without
/// support and the time no neighbour's window covers (the noise rate, from units not
/// chosen by their events); of the units that count, ON and OFF events (all and
/// supported) and the time counted.
#[derive(Default)]
struct NoiseTally {
    unsupported_anywhere: [f64; 2],
    uncovered_anywhere_s: f64,
    all: [f64; 2],
    supported: [f64; 2],
    exposure_s: f64,
    unsupported_exposure_s: f64,
}

/// One polarity's noise bracket: the factor from all its events to the estimate (the
/// geometric mean of the bracket's ends over its upper end), half its log range as a
/// uniform spread, the most of the events that can be noise, and why there is no lower
/// end where the noise may be every event.
#[derive(Clone, Debug)]
pub struct NoiseBracket {
    pub middle: f64,
    /// Relative systematic of the count: half the log range between all events and all
    /// but the most noise they can hold, as a uniform spread.
    pub relative_error: f64,
    /// The most of the counted events that can be noise (a share).
    pub noise_share: f64,
    /// Why the rate has no lower bound: the noise may be every event.
    pub why: Option<String>,
}

impl NoiseBracket {
    /// A polarity without events: nothing to bracket (the comparison says why).
    fn empty() -> Self {
        NoiseBracket {
            middle: 1.0,
            relative_error: 0.0,
            noise_share: 0.0,
            why: None,
        }
    }

    /// Half the log range between all events and all but the most noise (the uniform
    /// spread's half-width, of which `relative_error` is the standard deviation).
    pub fn half_range(&self) -> f64 {
        self.relative_error * 3f64.sqrt()
    }

    /// A polarity whose noise may be every event: its rate is read at all its events (the
    /// upper end, for what needs a rate, such as the prior's sharpness), and its threshold
    /// is not determinable for `why`.
    pub(super) fn undetermined(why: String) -> Self {
        NoiseBracket {
            middle: 1.0,
            relative_error: f64::INFINITY,
            noise_share: 1.0,
            why: Some(why),
        }
    }
}

impl NoiseTally {
    fn add(&mut self, u: &Unit, counts: bool) {
        for k in 0..2 {
            self.unsupported_anywhere[k] += u.all[k] - u.supported[k];
        }
        self.uncovered_anywhere_s += u.unsupported_exposure_s;
        if !counts {
            return;
        }
        for k in 0..2 {
            self.all[k] += u.all[k];
            self.supported[k] += u.supported[k];
        }
        self.exposure_s += u.exposure_s;
        self.unsupported_exposure_s += u.unsupported_exposure_s;
    }

    /// Polarity `k`'s bracket: the rate of unsupported events per second no neighbour
    /// covers (Garwood's 97.5 % upper end of their count: no unsupported event does not
    /// mean no noise where little time is uncovered), times the time the units that count
    /// are counted, is the most noise they can hold.
    fn bracket(&self, k: usize, window: TimeUs) -> NoiseBracket {
        let all = self.all[k];
        if all <= 0.0 {
            return NoiseBracket::empty();
        }
        let polarity = ["ON", "OFF"][k];
        let unsupported = self.unsupported_anywhere[k].round().max(0.0) as usize;
        let ms = window as f64 / 1e3;
        if self.uncovered_anywhere_s <= 0.0 {
            return NoiseBracket::undetermined(format!(
                "no counted time is free of a neighbour's event within {ms:.0} ms, so the support filter cannot tell noise from signal: the noise may be every {polarity} event"
            ));
        }
        let rate = crate::stats::binomial::poisson95(unsupported).1 / self.uncovered_anywhere_s;
        let noise = rate * self.exposure_s;
        let floor = all - noise;
        if floor <= 0.0 || !floor.is_finite() {
            let open = self.unsupported_exposure_s / self.exposure_s.max(1e-12);
            return NoiseBracket::undetermined(format!(
                "the noise may be every {polarity} event: {:.0} of the {all:.0} counted have no neighbour within {ms:.0} ms, and a noise event finds one by chance {:.0} % of the time at these pixels, so up to {noise:.0} may be noise (the motion is too slow for the support filter to tell noise from signal)",
                all - self.supported[k],
                100.0 * (1.0 - open)
            ));
        }
        let half_range = 0.5 * (all / floor).ln();
        NoiseBracket {
            middle: (-half_range).exp(),
            relative_error: half_range / 3f64.sqrt(),
            noise_share: noise / all,
            why: None,
        }
    }
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
    let by_patch = PatchWindows::new(&flows, sensor, p);
    let tally = Tally::new(events, sensor, excluded, &support, |i, pixel| {
        by_patch.at(pixel, events.t[i]).is_some()
    });
    let bursts = BurstShare::measure(events, sensor, excluded, &support, |i, pixel| {
        by_patch
            .at(pixel, events.t[i])
            .map(|f| if f.trusted() { f.speed() } else { median })
    });
    let (paths, travel_error) = by_patch.paths(median, sensor.pixels());
    let w = sensor.width as usize;
    let finish_with = Finish {
        kept: excluded.iter().filter(|&&e| !e).count(),
        duration: duration_s(events),
        supported_total: support.iter().filter(|&&s| s).count() as f64,
        speed: median,
        source: format!("the events (contrast maximisation per {p} px patch)"),
        travel_error,
        window,
        bursts: Some(bursts),
        frames_median_dn: None,
        still: None,
        // a patch's windows are time-sorted and disjoint: only those reaching past `from`
        covered_s: seconds(covered_time(events, sensor, window, |q, from, to| {
            let windows = &by_patch.windows[by_patch.of(q)];
            windows[windows.partition_point(|f| f.t_end <= from)..]
                .iter()
                .take_while(|f| f.t_start < to)
                .map(|f| (to.min(f.t_end) - from.max(f.t_start)).max(0))
                .sum()
        })),
    };
    finish(&tally, &paths, excluded, w, finish_with)
}

/// The events' flow windows grouped by patch (`side` px square, row-major), each patch's
/// time-sorted.
struct PatchWindows<'a> {
    side: usize,
    width: usize,
    tiles_x: usize,
    windows: Vec<Vec<&'a PatchFlow>>,
}

impl<'a> PatchWindows<'a> {
    fn new(flows: &'a [PatchFlow], sensor: Sensor, side: usize) -> Self {
        let (width, tiles_x) = (
            sensor.width as usize,
            (sensor.width as usize).div_ceil(side),
        );
        let tiles = tiles_x * (sensor.height as usize).div_ceil(side);
        let mut windows: Vec<Vec<&PatchFlow>> = vec![Vec::new(); tiles];
        for f in flows {
            windows[(f.y0 / side) * tiles_x + f.x0 / side].push(f);
        }
        for patch in &mut windows {
            patch.sort_by_key(|f| f.t_start);
        }
        PatchWindows {
            side,
            width,
            tiles_x,
            windows,
        }
    }

    /// The patch of `pixel`.
    fn of(&self, pixel: usize) -> usize {
        (pixel / self.width / self.side) * self.tiles_x + (pixel % self.width) / self.side
    }

    /// The window of `pixel`'s patch that holds time `t`.
    fn at(&self, pixel: usize, t: TimeUs) -> Option<&'a PatchFlow> {
        self.windows[self.of(pixel)]
            .iter()
            .find(|f| f.t_start <= t && t <= f.t_end)
            .copied()
    }

    /// Every pixel's path, its patch's (travel, direction, and the time its events count:
    /// the patch's windows with a flow), and the travel's relative precision
    /// ([`patch_paths`]).
    fn paths(&self, median: f64, pixels: usize) -> (Paths, f64) {
        let (patches, travel_error) = patch_paths(&self.windows, median);
        let patch_exposure_s: Vec<f64> = self
            .windows
            .iter()
            .map(|windows| {
                windows
                    .iter()
                    .map(|f| (f.t_end - f.t_start) as f64 * 1e-6)
                    .sum()
            })
            .collect();
        let paths = Paths {
            travel: (0..pixels).map(|q| patches[self.of(q)].0).collect(),
            direction: (0..pixels).map(|q| patches[self.of(q)].1).collect(),
            exposure_s: (0..pixels).map(|q| patch_exposure_s[self.of(q)]).collect(),
            tile_px: Some(super::scans::TILE_PX),
        };
        (paths, travel_error)
    }
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

/// The median DN of the frames over the reliable pixels of the intervals with a flow (both
/// frames of each interval), from a histogram of whole DN; `None` where no pixel is
/// reliable.
fn median_reliable_dn(frames: &PreparedFrames) -> Option<f64> {
    let mut histogram = [0u64; 256];
    for k in (0..frames.flows.len()).filter(|&k| frames.flows[k].is_some()) {
        for pixel in 0..frames.width * frames.height {
            if frames.reliable(k, pixel) {
                for dn in [&frames.dn[k], &frames.dn[k + 1]] {
                    histogram[(dn.data[pixel].round() as usize).min(255)] += 1;
                }
            }
        }
    }
    crate::stats::robust::histogram_median(&histogram).map(|dn| dn as f64)
}

/// Every reliable pixel's path over the intervals with a flow (travel, and the time it
/// counts), and the median speed of every pixel's flow; `None` without a flow.
fn frame_paths(frames: &PreparedFrames) -> Option<(Paths, f64)> {
    let pixels = frames.width * frames.height;
    let mut speeds = Vec::new();
    let mut paths = Paths {
        travel: vec![0.0; pixels],
        direction: vec![(1.0, 0.0); pixels],
        exposure_s: vec![0.0; pixels],
        tile_px: None,
    };
    for (k, flow) in frames.flows.iter().enumerate() {
        let Some(flow) = flow else { continue };
        let dt = (frames.times[k + 1] - frames.times[k]) as f64 * 1e-6;
        for (pixel, m) in flow.magnitudes().iter().enumerate() {
            speeds.push(*m as f64 / dt);
            if frames.reliable(k, pixel) {
                paths.travel[pixel] += *m as f64;
                paths.exposure_s[pixel] += dt;
            }
        }
    }
    if speeds.is_empty() {
        return None;
    }
    speeds.sort_by(f64::total_cmp);
    Some((paths, speeds[speeds.len() / 2]))
}

/// Each pixel's counted time (the intervals with a flow where it is reliable) within
/// `window` of a neighbour's event, seconds.
fn frames_covered_s(
    events: &EventChunk,
    frames: &PreparedFrames,
    sensor: Sensor,
    window: TimeUs,
) -> Vec<f64> {
    seconds(covered_time(events, sensor, window, |q, from, to| {
        let first = frames
            .times
            .partition_point(|&s| s <= from)
            .saturating_sub(1);
        (first..frames.times.len().saturating_sub(1))
            .take_while(|&k| frames.times[k] < to)
            .filter(|&k| frames.flows[k].is_some() && frames.reliable(k, q))
            .map(|k| (to.min(frames.times[k + 1]) - from.max(frames.times[k])).max(0))
            .sum()
    }))
}

/// The recording's rates with travel from the frames' flow: every reliable pixel of every
/// used interval counts (the scans follow the same paths, so nothing needs to have fired).
pub fn from_frames(
    events: &EventChunk,
    frames: &PreparedFrames,
    sensor: Sensor,
    excluded: &[bool],
) -> Option<RecordingRates> {
    let (paths, median) = frame_paths(frames)?;
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
        frames_median_dn: median_reliable_dn(frames),
        still: Some(StillPixels::measure(
            frames,
            &tally.all,
            &paths.exposure_s,
            excluded,
        )),
        covered_s: frames_covered_s(events, frames, sensor, window),
    };
    finish(&tally, &paths, excluded, frames.width, finish_with)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::binomial::poisson95;

    /// 100 pixel-seconds counted in the units that count; `unsupported` ON and OFF events
    /// without support over `uncovered_s` that no neighbour covered, in every unit.
    fn tally(
        all: [f64; 2],
        supported: [f64; 2],
        unsupported: [f64; 2],
        uncovered_s: f64,
    ) -> NoiseTally {
        NoiseTally {
            unsupported_anywhere: unsupported,
            uncovered_anywhere_s: uncovered_s,
            all,
            supported,
            exposure_s: 100.0,
            unsupported_exposure_s: uncovered_s,
        }
    }

    #[test]
    fn the_bracket_runs_from_all_events_to_all_but_the_most_noise() {
        // ON: 10 unsupported in 100 uncovered s, at most 18.39 (Garwood's upper end,
        // chi2(0.975; 22) / 2) per 100 s; 100 s counted: 18.39 of 100 may be noise
        let t = tally([100.0, 500.0], [95.0, 480.0], [10.0, 40.0], 100.0);
        let most = poisson95(10).1;
        assert!((most - 18.39).abs() < 0.01, "{most}");
        let on = t.bracket(0, 50_000);
        assert!((on.middle - (1.0 - most / 100.0).sqrt()).abs() < 1e-12);
        let half = 0.5 * (100.0 / (100.0 - most)).ln();
        assert!((on.relative_error - half / 3f64.sqrt()).abs() < 1e-12);
        assert!((on.noise_share - most / 100.0).abs() < 1e-12 && on.why.is_none());
        // with half the time uncovered the same 10 events stand for twice the noise
        let t = tally([100.0, 500.0], [95.0, 480.0], [10.0, 40.0], 50.0);
        assert!((t.bracket(0, 50_000).noise_share - 2.0 * most / 100.0).abs() < 1e-12);
    }

    #[test]
    fn no_unsupported_event_is_not_no_noise_where_little_time_is_uncovered() {
        // 100 s uncovered and none unsupported: at most 3.69 noise events of 1,000
        let t = tally([1000.0, 1000.0], [1000.0, 1000.0], [0.0, 0.0], 100.0);
        let on = t.bracket(0, 50_000);
        assert!(
            (on.noise_share - 0.00369).abs() < 1e-4,
            "{}",
            on.noise_share
        );
        // 0.1 s uncovered: 3.69 in 0.1 s is 3,689 in 100 s, more than the 1,000 counted
        let t = tally([1000.0, 1000.0], [1000.0, 1000.0], [0.0, 0.0], 0.1);
        assert!(t.bracket(0, 50_000).why.is_some());
        // no time uncovered at all
        let t = tally([1000.0, 1000.0], [1000.0, 1000.0], [0.0, 0.0], 0.0);
        let why = t.bracket(1, 50_000).why.expect("a reason");
        assert!(why.contains("no counted time is free"), "{why}");
    }

    #[test]
    fn noise_that_may_be_every_event_leaves_no_lower_end() {
        // OFF: 40 unsupported over 100 uncovered seconds stand for up to 54.5 noise events
        // where only 50 were counted
        let t = tally([100.0, 50.0], [95.0, 25.0], [10.0, 40.0], 100.0);
        let off = t.bracket(1, 80_000);
        assert!(off.why.is_some() && off.middle == 1.0 && off.noise_share == 1.0);
        let why = off.why.expect("a reason");
        assert!(
            why.contains("every OFF event") && why.contains("80 ms"),
            "{why}"
        );
        // no events at all: nothing to bracket, and the comparison says why
        let none = tally([0.0, 0.0], [0.0, 0.0], [0.0, 0.0], 100.0).bracket(0, 80_000);
        assert_eq!((none.middle, none.why), (1.0, None));
    }
}
