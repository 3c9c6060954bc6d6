//! Line scans: what one ideal pixel sees while a scene moves past it. For a scene that moves
//! at `v`, a pixel's log intensity over time is the scene's log intensity along a line in
//! the direction of `-v`, read at `|v|` pixels per second; an ideal pixel (Lichtsteiner et
//! al., JSSC 2008) fires an event each time that profile moves one threshold from the level
//! of its last event. Counting events along many such lines through an image, at a grid of
//! thresholds, gives the calibration curve of `estimate eppps`: events per pixel of travel,
//! over pixels that fired, against the threshold.
//!
//! Each scan begins with a burn-in stretch before its counted part, so that the pixel's
//! memorised level at the start is what the scene before it left there (a pixel of a running
//! camera is somewhere between two events, not freshly reset).

use rayon::prelude::*;

/// Distance between samples along a scan, pixels.
pub const STEP_PX: f64 = 0.25;
/// Stretch scanned before counting starts, pixels.
pub const BURN_IN_PX: f64 = 16.0;
/// Side of the tiles a recording without frames is counted in, and of the blocks of
/// parallel scans that stand for them: a tile counts when any of its pixels has signal, so
/// that blank parts of the view do not, while a tile's pixels that stay silent still do
/// (they carry the threshold: the higher it is, the fewer of them fire).
pub const TILE_PX: usize = 8;

/// Thresholds of the calibration curve: 31 log-spaced values from 0.03 to 9.5 (24 steps a
/// factor 100). Real sensors' thresholds lie well inside; the top reaches past the log
/// range of every prior image under every floor (1.7-5.8), so that each curve falls to no
/// events inside the grid and a sparse recording's threshold is bracketed, not cut off at
/// the grid's end. Thresholds above a scan's own range cost nothing ([`Profile::range`]).
pub fn threshold_grid() -> Vec<f64> {
    (0..31)
        .map(|k| (0.03f64.ln() + k as f64 * (100f64.ln() / 24.0)).exp())
        .collect()
}

/// A log-intensity image, row-major.
#[derive(Clone, Debug)]
pub struct LogImage {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl LogImage {
    /// The standard deviation of its log values.
    pub fn std(&self) -> f64 {
        let n = self.data.len().max(1) as f64;
        let mean = self.data.iter().map(|&v| v as f64).sum::<f64>() / n;
        (self
            .data
            .iter()
            .map(|&v| (v as f64 - mean).powi(2))
            .sum::<f64>()
            / n)
            .sqrt()
    }

    /// Bilinear sample at (x, y), clamped to the image.
    pub fn sample(&self, x: f64, y: f64) -> f32 {
        let x = x.clamp(0.0, (self.width - 1) as f64);
        let y = y.clamp(0.0, (self.height - 1) as f64);
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
        let (fx, fy) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
        let at = |x: usize, y: usize| self.data[y * self.width + x];
        (1.0 - fy) * ((1.0 - fx) * at(x0, y0) + fx * at(x1, y0))
            + fy * ((1.0 - fx) * at(x0, y1) + fx * at(x1, y1))
    }
}

/// One scan: a start point, a unit direction and the counted length, pixels.
#[derive(Clone, Copy, Debug)]
pub struct Scan {
    pub x: f64,
    pub y: f64,
    pub dx: f64,
    pub dy: f64,
    pub length: f64,
    /// Time the scene takes to move one pixel past the scan, seconds.
    pub seconds_per_px: f64,
}

/// A scan's log-intensity profile: `burn` samples of burn-in, then the counted part.
pub struct Profile {
    pub values: Vec<f32>,
    /// The time of each sample, seconds (any origin).
    pub times_s: Vec<f64>,
    pub burn: usize,
    /// Counted length, pixels.
    pub length: f64,
}

impl Profile {
    /// The largest change from the first sample: no threshold above it fires (the
    /// memorised level starts at the first sample and moves only with an event).
    pub fn range(&self) -> f32 {
        let first = self.values.first().copied().unwrap_or(0.0);
        self.values
            .iter()
            .fold(0f32, |r, &v| r.max((v - first).abs()))
    }
}

/// The profile of `scan` through `image`.
pub fn profile(image: &LogImage, scan: &Scan) -> Profile {
    let burn = (BURN_IN_PX / STEP_PX).round() as usize;
    let counted = (scan.length / STEP_PX).ceil().max(1.0) as usize;
    let values = (0..=burn + counted)
        .map(|i| {
            let s = (i as f64 - burn as f64) * STEP_PX;
            image.sample(scan.x + s * scan.dx, scan.y + s * scan.dy)
        })
        .collect();
    let times_s = (0..=burn + counted)
        .map(|i| i as f64 * STEP_PX * scan.seconds_per_px)
        .collect();
    Profile {
        values,
        times_s,
        burn,
        length: scan.length,
    }
}

/// The travel within which two consecutive events of one polarity at a pixel count as one
/// burst (an edge passing), pixels: how sharp a scene is, as its events tell it (a sharp
/// edge fires its events within a pixel of travel, a smooth gradient one per threshold's
/// worth of slope).
pub const BURST_PX: f64 = 1.0;

/// What one scan fires at one pair of thresholds: its counted ON and OFF events, and of
/// its consecutive counted events of one polarity (`pairs`) those within [`BURST_PX`] of
/// travel (`bursts`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ScanCount {
    pub on: u32,
    pub off: u32,
    pub pairs: u32,
    pub bursts: u32,
}

impl ScanCount {
    fn add(&mut self, other: ScanCount) {
        self.on += other.on;
        self.off += other.off;
        self.pairs += other.pairs;
        self.bursts += other.bursts;
    }

    /// A counted event of polarity `up` at `travel` pixels along the scan, after the one
    /// before it of that polarity at `last[up]`.
    fn event(&mut self, up: bool, travel: f64, last: &mut [Option<f64>; 2]) {
        if up {
            self.on += 1;
        } else {
            self.off += 1;
        }
        let slot = &mut last[up as usize];
        if let Some(before) = *slot {
            self.pairs += 1;
            self.bursts += (travel - before < BURST_PX) as u32;
        }
        *slot = Some(travel);
    }
}

/// ON and OFF events of an ideal pixel of thresholds `c_on`, `c_off` along `profile`,
/// counted after its burn-in; the memorised level starts at the first sample and moves by
/// one threshold per event. The two thresholds interact: the memorised level is a play
/// operator of width `c_on + c_off` on the profile, so a pixel's ON count depends on its OFF
/// threshold wherever the profile turns. Event positions (for the bursts) are the samples'
/// travel, [`STEP_PX`] apart. (A pass over every sample: most fire nothing and cost a
/// comparison, which measured faster than bisecting the profile's runs as
/// [`count_refractory_over`] does, whose every sample is dearer.)
pub fn count(profile: &Profile, c_on: f32, c_off: f32) -> ScanCount {
    let mut reference = profile.values[0];
    let mut out = ScanCount::default();
    let mut last = [None, None];
    for (i, &level) in profile.values.iter().enumerate() {
        if level - reference < c_on && reference - level < c_off {
            // most samples fire nothing: nothing else to do for them
            continue;
        }
        let counted = i > profile.burn;
        let travel = i as f64 * STEP_PX;
        while level - reference >= c_on {
            reference += c_on;
            if counted {
                out.event(true, travel, &mut last);
            }
        }
        while reference - level >= c_off {
            reference -= c_off;
            if counted {
                out.event(false, travel, &mut last);
            }
        }
    }
    out
}

/// A profile cut where it turns: each run's end (exclusive), its samples after its first
/// each at least (a rising run) or at most (a falling one) the sample before.
pub struct Runs {
    ends: Vec<u32>,
    rising: Vec<bool>,
}

impl Runs {
    pub fn of(profile: &Profile) -> Self {
        let v = &profile.values;
        let (mut ends, mut rising) = (Vec::new(), Vec::new());
        let mut up: Option<bool> = None;
        for i in 1..v.len() {
            let step_up = v[i] > v[i - 1];
            let step_down = v[i] < v[i - 1];
            match up {
                None if step_up || step_down => up = Some(step_up),
                Some(true) if step_down => {
                    ends.push(i as u32);
                    rising.push(true);
                    up = Some(false);
                }
                Some(false) if step_up => {
                    ends.push(i as u32);
                    rising.push(false);
                    up = Some(true);
                }
                _ => {}
            }
        }
        ends.push(v.len() as u32);
        rising.push(up.unwrap_or(true));
        Self { ends, rising }
    }
}

/// The pixel the scans simulate besides its ON threshold: its OFF threshold as a multiple
/// of the ON one, and its refractory period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanPixel {
    /// OFF threshold / ON threshold.
    pub ratio: f64,
    /// Refractory period, seconds (0: none).
    pub refractory_s: f64,
}

impl ScanPixel {
    pub const SYMMETRIC: ScanPixel = ScanPixel {
        ratio: 1.0,
        refractory_s: 0.0,
    };

    /// What `profile`, whose [`Profile::range`] is `range` and whose runs are `runs`
    /// (found where the pixel has a refractory period, [`ScanPixel::runs`]), fires at ON
    /// threshold `c`.
    fn count(&self, profile: &Profile, runs: Option<&Runs>, range: f32, c: f64) -> ScanCount {
        let (c_on, c_off) = (c as f32, (c * self.ratio) as f32);
        if c_on > range && c_off > range {
            return ScanCount::default();
        }
        match runs {
            Some(runs) if self.refractory_s > 0.0 => {
                count_refractory_over(profile, runs, c_on, c_off, self.refractory_s)
            }
            _ if self.refractory_s > 0.0 => {
                count_refractory(profile, c_on, c_off, self.refractory_s)
            }
            _ => count(profile, c_on, c_off),
        }
    }

    /// The runs of `profile` where this pixel's counts use them (a refractory period).
    fn runs(&self, profile: &Profile) -> Option<Runs> {
        (self.refractory_s > 0.0).then(|| Runs::of(profile))
    }
}

/// [`count`] for a pixel with a refractory period (the simulator's and v2e's semantics,
/// [`crate::sim::effects::refractory`]): after an event the pixel cannot fire for
/// `refractory_s`; a crossing inside the period stays pending and fires when it ends if the
/// level is then still a threshold away, one event per period. Between samples the level
/// is interpolated linearly in time, so crossings are timed within a sample.
pub fn count_refractory(profile: &Profile, c_on: f32, c_off: f32, refractory_s: f64) -> ScanCount {
    count_refractory_over(profile, &Runs::of(profile), c_on, c_off, refractory_s)
}

/// [`count_refractory`] over the profile's runs: every stretch between samples processed
/// as a pass over all of them would, except the stretches of a run after one that fired
/// nothing while the pixel was ready, up to the first that may fire, which a bisection
/// finds. Along a rising run, once a ready stretch fires nothing, no later one fires OFF
/// (its start level only rises), and one fires ON only where its start level is a
/// threshold above the memorised level (`v0 - reference >= c_on`) or its end reaches
/// `reference + c_on`: both monotone along the run; a falling run the same with the
/// polarities exchanged. The same events at the same times, at a cost of the events and
/// the turns rather than the samples.
pub fn count_refractory_over(
    profile: &Profile,
    runs: &Runs,
    c_on: f32,
    c_off: f32,
    refractory_s: f64,
) -> ScanCount {
    let Some(mut pixel) = RefractoryPixel::new(profile, c_on, c_off, refractory_s) else {
        return ScanCount::default();
    };
    let n = pixel.samples();
    let mut run = 0;
    let mut i = 1;
    while i < n {
        let fired = pixel.stretch(i);
        // ready through the whole stretch (unchanged where it fired nothing)
        let ready = pixel.t[i - 1] >= pixel.ready;
        while runs.ends[run] as usize <= i {
            run += 1;
        }
        let end = (runs.ends[run] as usize).min(n);
        i += 1;
        // a ready stretch that fired nothing, inside its run: skip to the first that may
        // (times rising, so that a stretch's level at its start is its first sample's)
        if !fired && ready && pixel.px_per_s > 0.0 && i < end {
            i = pixel.first_that_may_fire(i..end, runs.rising[run]);
        }
    }
    pixel.out
}

/// A refractory pixel along a profile ([`count_refractory`]): the memorised level, when it
/// is ready again, and what it fired.
struct RefractoryPixel<'a> {
    v: &'a [f32],
    t: &'a [f64],
    burn: usize,
    c_on: f32,
    c_off: f32,
    refractory_s: f64,
    /// Travel per second (samples are [`STEP_PX`] of travel apart, evenly in time).
    px_per_s: f64,
    reference: f32,
    ready: f64,
    out: ScanCount,
    last: [Option<f64>; 2],
}

impl<'a> RefractoryPixel<'a> {
    /// At the profile's first sample; `None` without one.
    fn new(profile: &'a Profile, c_on: f32, c_off: f32, refractory_s: f64) -> Option<Self> {
        let (v, t) = (&profile.values[..], &profile.times_s[..]);
        Some(Self {
            reference: *v.first()?,
            px_per_s: match t {
                [a, b, ..] if b > a => STEP_PX / (b - a),
                _ => 0.0,
            },
            v,
            t,
            burn: profile.burn,
            c_on,
            c_off,
            refractory_s,
            ready: f64::NEG_INFINITY,
            out: ScanCount::default(),
            last: [None, None],
        })
    }

    fn samples(&self) -> usize {
        self.v.len().min(self.t.len())
    }

    /// The events of the stretch from sample `i - 1` to `i` (the level interpolated
    /// linearly in time between them); whether it fired any.
    fn stretch(&mut self, i: usize) -> bool {
        let (t0, t1, v0, v1) = (self.t[i - 1], self.t[i], self.v[i - 1], self.v[i]);
        let counted = i > self.burn;
        let level_at = |s: f64| {
            if t1 > t0 {
                v0 + (v1 - v0) * ((s - t0) / (t1 - t0)) as f32
            } else {
                v1
            }
        };
        let (c_on, c_off) = (self.c_on, self.c_off);
        let mut from = t0;
        let mut fired_here = false;
        loop {
            let start = from.max(self.ready);
            if start > t1 {
                break;
            }
            let level = level_at(start);
            let reference = self.reference;
            let fired = if level - reference >= c_on {
                Some((start, true))
            } else if reference - level >= c_off {
                Some((start, false))
            } else {
                // the next crossing later in this stretch, if the level gets there
                let up = v1 > level;
                let target = if up {
                    reference + c_on
                } else {
                    reference - c_off
                };
                let reached = if up { v1 >= target } else { v1 <= target };
                (reached && v1 != level && t1 > start).then(|| {
                    let f = f64::from((target - level) / (v1 - level));
                    (start + f * (t1 - start), up)
                })
            };
            let Some((at, up)) = fired else { break };
            fired_here = true;
            self.reference += if up { c_on } else { -c_off };
            if counted {
                let travel = (at - self.t[0]) * self.px_per_s;
                self.out.event(up, travel, &mut self.last);
            }
            self.ready = at + self.refractory_s;
            from = at;
        }
        fired_here
    }

    /// The first stretch of `stretches` (within one run, rising or not, the pixel ready
    /// and nothing fired before them) that may fire, by bisection; the range's end where
    /// none may (see [`count_refractory_over`]).
    fn first_that_may_fire(&self, stretches: std::ops::Range<usize>, rising: bool) -> usize {
        let (v, r, c_on, c_off) = (self.v, self.reference, self.c_on, self.c_off);
        let quiet = |k: usize| {
            let (from_level, to_level) = (v[k - 1], v[k]);
            if rising {
                !(from_level - r >= c_on || to_level >= r + c_on)
            } else {
                !(r - from_level >= c_off || to_level <= r - c_off)
            }
        };
        let (mut lo, mut hi) = (stretches.start, stretches.end);
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            if quiet(mid) {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        lo
    }
}

/// Which polarity a calibration curve is read for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    On,
    Off,
}

impl Side {
    /// 0 for ON, 1 for OFF: the index of per-polarity pairs.
    pub fn index(self) -> usize {
        match self {
            Side::On => 0,
            Side::Off => 1,
        }
    }

    /// Events of this polarity per pixel of travel at a curve point.
    pub fn rate(self, p: &CurvePoint) -> f64 {
        match self {
            Side::On => p.on_per_px,
            Side::Off => p.off_per_px,
        }
    }

    /// This polarity's threshold at a curve point.
    pub fn threshold(self, p: &CurvePoint) -> f64 {
        match self {
            Side::On => p.ct,
            Side::Off => p.ct_off,
        }
    }
}

/// One point of a calibration curve: at ON threshold `ct` and OFF threshold `ct_off`, ON and
/// OFF events per pixel of travel over the scans that fired, and the share of scans that
/// fired.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct CurvePoint {
    pub ct: f64,
    pub ct_off: f64,
    pub on_per_px: f64,
    pub off_per_px: f64,
    pub active_fraction: f64,
    /// Events per scan (ON + OFF), over all scans.
    pub events_per_scan: f64,
    /// Of the counted scans' consecutive events of one polarity, the share within
    /// [`BURST_PX`] of travel (NaN without any).
    pub burst_fraction: f64,
}

impl CurvePoint {
    /// The point of `sum` (the counted scans' events) over `travel` pixels, `scans` scans
    /// in all, `active_fraction` of them (or of their blocks) firing.
    fn new(
        ct: f64,
        pixel: ScanPixel,
        sum: ScanCount,
        travel: f64,
        active_fraction: f64,
        scans: usize,
    ) -> Self {
        let travel = travel.max(1e-9);
        let scans = scans.max(1) as f64;
        CurvePoint {
            ct,
            ct_off: ct * pixel.ratio,
            on_per_px: sum.on as f64 / travel,
            off_per_px: sum.off as f64 / travel,
            active_fraction,
            events_per_scan: (sum.on + sum.off) as f64 / scans,
            burst_fraction: if sum.pairs > 0 {
                sum.bursts as f64 / sum.pairs as f64
            } else {
                f64::NAN
            },
        }
    }
}

/// The burst fraction of `curve` at ON threshold `ct`, interpolated in ln threshold
/// between the grid points around it (NaN outside the curve or where it has none).
pub fn burst_fraction_at(curve: &[CurvePoint], ct: f64) -> f64 {
    curve
        .windows(2)
        .find(|w| w[0].ct <= ct && ct <= w[1].ct)
        .map_or(f64::NAN, |w| {
            let f = (ct.ln() - w[0].ct.ln()) / (w[1].ct.ln() - w[0].ct.ln());
            match (w[0].burst_fraction.is_nan(), w[1].burst_fraction.is_nan()) {
                (false, false) => {
                    w[0].burst_fraction + f * (w[1].burst_fraction - w[0].burst_fraction)
                }
                (false, true) => w[0].burst_fraction,
                (true, false) => w[1].burst_fraction,
                (true, true) => f64::NAN,
            }
        })
}

/// The calibration curve of `profiles` at every ON threshold of `grid` for `pixel`: per
/// pixel of the travel of the scans that fired (`fired_only`, as the recording's pixels are
/// counted without frames) or of all scans.
pub fn curve(
    profiles: &[Profile],
    grid: &[f64],
    fired_only: bool,
    pixel: ScanPixel,
) -> Vec<CurvePoint> {
    let ranges: Vec<f32> = profiles.par_iter().map(Profile::range).collect();
    let runs: Vec<Option<Runs>> = profiles.par_iter().map(|p| pixel.runs(p)).collect();
    grid.par_iter()
        .map(|&ct| {
            let (mut sum, mut travel, mut active) = (ScanCount::default(), 0.0f64, 0usize);
            for ((p, &range), runs) in profiles.iter().zip(&ranges).zip(&runs) {
                let c = pixel.count(p, runs.as_ref(), range, ct);
                let fired = c.on + c.off > 0;
                active += fired as usize;
                if fired || !fired_only {
                    sum.add(c);
                    travel += p.length;
                }
            }
            let scans = profiles.len();
            CurvePoint::new(
                ct,
                pixel,
                sum,
                travel,
                active as f64 / scans.max(1) as f64,
                scans,
            )
        })
        .collect()
}

/// A block of `TILE_PX` x `TILE_PX` parallel scans one pixel apart, moving together: what
/// one tile of the sensor sees.
#[derive(Clone, Copy, Debug)]
pub struct Block {
    /// The corner scan.
    pub corner: Scan,
}

/// What a block's pixels fire at each ON threshold of `grid`.
fn block_counts(image: &LogImage, block: &Block, grid: &[f64], pixel: ScanPixel) -> Vec<ScanCount> {
    let mut out = vec![ScanCount::default(); grid.len()];
    for j in 0..TILE_PX {
        for i in 0..TILE_PX {
            let scan = Scan {
                x: block.corner.x + i as f64,
                y: block.corner.y + j as f64,
                ..block.corner
            };
            let p = profile(image, &scan);
            let (range, runs) = (p.range(), pixel.runs(&p));
            for (slot, &c) in out.iter_mut().zip(grid) {
                slot.add(pixel.count(&p, runs.as_ref(), range, c));
            }
        }
    }
    out
}

/// The calibration curve of `blocks` through `image` for `pixel`: per ON threshold, events
/// per pixel of travel over the blocks where any pixel fired (as the recording's tiles are
/// counted).
pub fn block_curve(
    image: &LogImage,
    blocks: &[Block],
    grid: &[f64],
    pixel: ScanPixel,
) -> Vec<CurvePoint> {
    let counts: Vec<Vec<ScanCount>> = blocks
        .par_iter()
        .map(|b| block_counts(image, b, grid, pixel))
        .collect();
    let pixels = TILE_PX * TILE_PX;
    (0..grid.len())
        .map(|k| {
            let (mut sum, mut travel, mut active) = (ScanCount::default(), 0.0f64, 0usize);
            for (b, c) in blocks.iter().zip(&counts) {
                if c[k].on + c[k].off > 0 {
                    sum.add(c[k]);
                    travel += pixels as f64 * b.corner.length;
                    active += 1;
                }
            }
            let active_fraction = active as f64 / blocks.len().max(1) as f64;
            CurvePoint::new(
                grid[k],
                pixel,
                sum,
                travel,
                active_fraction,
                pixels * blocks.len(),
            )
        })
        .collect()
}

/// Where a target rate falls against a calibration curve (its rate falls with the
/// threshold, though not always strictly: a noisy tail of few firing blocks can rise again).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Inverted {
    /// At this threshold, interpolated in log-log between the two grid points around it.
    At(f64),
    /// Between two grid points: the curve makes more events than the target at the first
    /// and none at the second (the scene's whole log range is crossed by one threshold
    /// there), so the threshold lies in `(lo, hi]`.
    Between(f64, f64),
    /// Fewer events than the curve makes even at its highest threshold: above it.
    Above(f64),
    /// More events than the curve makes even at its lowest threshold: below it.
    Below(f64),
    /// A target that is not a positive rate, or a curve without events.
    Outside,
}

impl Inverted {
    /// The threshold this calibration gives, or the grid bound that stands in for it
    /// (`Between`: the geometric middle of its two points).
    pub fn value(self) -> Option<f64> {
        match self {
            Inverted::At(v) | Inverted::Above(v) | Inverted::Below(v) => Some(v),
            Inverted::Between(lo, hi) => Some((lo * hi).sqrt()),
            Inverted::Outside => None,
        }
    }
}

/// The threshold of `side` at which its rate reaches `target`: the first pair of grid
/// points whose rates bracket it, interpolated in log-log (or bounded, where the second
/// makes no events); else which end of the curve the target lies beyond.
pub fn invert(curve: &[CurvePoint], side: Side, target: f64) -> Inverted {
    if target.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Inverted::Outside;
    }
    for w in curve.windows(2) {
        let (r0, r1) = (side.rate(&w[0]), side.rate(&w[1]));
        let (c0, c1) = (side.threshold(&w[0]), side.threshold(&w[1]));
        if !(r0 >= target && target >= r1) {
            continue;
        }
        if r1 == 0.0 {
            return Inverted::Between(c0, c1);
        }
        if r0 == r1 {
            // a plateau at the target
            return Inverted::At((c0 * c1).sqrt());
        }
        let f = (target.ln() - r0.ln()) / (r1.ln() - r0.ln());
        return Inverted::At((c0.ln() + f * (c1.ln() - c0.ln())).exp());
    }
    match (curve.first(), curve.last()) {
        (Some(first), _) if target > side.rate(first) => Inverted::Below(side.threshold(first)),
        (_, Some(last)) if target < side.rate(last) => Inverted::Above(side.threshold(last)),
        _ => Inverted::Outside,
    }
}

/// The local slope `d ln rate / d ln threshold` of `side` at threshold `ct` (for turning an
/// error of the rate into an error of the threshold); -1 where it cannot be measured.
pub fn log_slope(curve: &[CurvePoint], side: Side, ct: f64) -> f64 {
    curve
        .windows(2)
        .find(|w| side.threshold(&w[0]) <= ct && ct <= side.threshold(&w[1]))
        .and_then(|w| {
            let (r0, r1) = (side.rate(&w[0]), side.rate(&w[1]));
            let (c0, c1) = (side.threshold(&w[0]), side.threshold(&w[1]));
            (r0 > 0.0 && r1 > 0.0).then(|| (r1.ln() - r0.ln()) / (c1.ln() - c0.ln()))
        })
        .filter(|s| s.is_finite() && *s < 0.0)
        .unwrap_or(-1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pass over every stretch that [`count_refractory_over`] must equal.
    fn count_refractory_per_stretch(
        profile: &Profile,
        c_on: f32,
        c_off: f32,
        refractory_s: f64,
    ) -> ScanCount {
        let mut pixel = RefractoryPixel::new(profile, c_on, c_off, refractory_s).unwrap();
        for i in 1..pixel.samples() {
            pixel.stretch(i);
        }
        pixel.out
    }

    #[test]
    fn counting_over_runs_equals_the_pass_over_every_stretch() {
        // random walks with plateaus, steps of every size against the thresholds, and
        // thresholds from far below a step to above the range
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut uniform = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut events = 0;
        for walk in 0..200 {
            let n = 1 + (uniform() * 600.0) as usize;
            let scale = [0.001, 0.05, 0.4][walk % 3];
            let mut level = 0f32;
            let values: Vec<f32> = (0..n)
                .map(|_| {
                    if uniform() > 0.2 {
                        level += ((uniform() - 0.5) * scale) as f32;
                    }
                    level
                })
                .collect();
            let p = Profile {
                times_s: (0..n).map(|i| i as f64).collect(),
                values,
                burn: (uniform() * 64.0) as usize,
                length: n as f64 * STEP_PX,
            };
            let runs = Runs::of(&p);
            for &(c_on, c_off) in &[
                (0.0005f32, 0.0007f32),
                (0.03, 0.03),
                (0.1, 0.3),
                (0.7, 0.2),
                (5.0, 5.0),
            ] {
                for refractory_s in [0.0, 0.3, 1.0, 2.5, 40.0] {
                    let fast = count_refractory_over(&p, &runs, c_on, c_off, refractory_s);
                    assert_eq!(
                        fast,
                        count_refractory_per_stretch(&p, c_on, c_off, refractory_s),
                        "walk {walk} {c_on} {c_off} {refractory_s}"
                    );
                    events += fast.on + fast.off;
                }
            }
        }
        assert!(events > 10_000, "{events}");
    }

    fn ramp_image(slope: f32) -> LogImage {
        LogImage {
            width: 200,
            height: 4,
            data: (0..800).map(|i| slope * (i % 200) as f32).collect(),
        }
    }

    #[test]
    fn a_ramp_fires_one_event_per_threshold_of_change() {
        // log intensity rising 0.05 per pixel, 40 px counted: a change of 2.0 is 6 events of
        // 0.3 (1.8) or 7, depending on where the burn-in left the memorised level
        let image = ramp_image(0.05);
        let scan = Scan {
            x: 20.0,
            y: 1.0,
            dx: 1.0,
            dy: 0.0,
            length: 40.0,
            seconds_per_px: 0.01,
        };
        let p = profile(&image, &scan);
        let ScanCount { on, off, .. } = count(&p, 0.3, 0.3);
        assert_eq!(off, 0);
        assert!(on == 6 || on == 7, "{on}");
        // against the ramp: OFF
        let back = Scan {
            dx: -1.0,
            x: 120.0,
            ..scan
        };
        assert_eq!(count(&profile(&image, &back), 0.3, 0.3).on, 0);
    }

    #[test]
    fn the_curve_of_a_ramp_inverts_to_its_threshold() {
        let image = ramp_image(0.05);
        let profiles: Vec<Profile> = (0..50)
            .map(|k| {
                profile(
                    &image,
                    &Scan {
                        x: 20.0 + k as f64 * 0.37,
                        y: 1.0,
                        dx: 1.0,
                        dy: 0.0,
                        length: 100.0,
                        seconds_per_px: 0.01,
                    },
                )
            })
            .collect();
        let grid = threshold_grid();
        let c = curve(&profiles, &grid, true, ScanPixel::SYMMETRIC);
        // 0.05 per pixel: 0.05 / C events per pixel of travel
        let Inverted::At(ct) = invert(&c, Side::On, 0.05 / 0.25) else {
            panic!("the ramp's rate is on its curve");
        };
        assert!((ct - 0.25).abs() < 0.01, "{ct}");
        let slope = log_slope(&c, Side::On, 0.25);
        // counts are whole events (17 at 0.3 for 16.7), so the slope between grid points is
        // about -1 within that rounding
        assert!((slope + 1.0).abs() < 0.2, "{slope}");
        assert!((grid[0] - 0.03).abs() < 1e-12 && (grid[24] - 3.0).abs() < 1e-9);
    }

    /// A curve with the given ON rates at thresholds 0.1, 0.2, 0.4, ...
    fn rates_curve(rates: &[f64]) -> Vec<CurvePoint> {
        rates
            .iter()
            .enumerate()
            .map(|(k, &r)| CurvePoint {
                ct: 0.1 * 2f64.powi(k as i32),
                ct_off: 0.3 * 2f64.powi(k as i32),
                on_per_px: r,
                off_per_px: r,
                active_fraction: 1.0,
                events_per_scan: r,
                burst_fraction: f64::NAN,
            })
            .collect()
    }

    #[test]
    fn a_target_is_read_off_its_curve_or_bounded_where_the_curve_ends() {
        let curve = rates_curve(&[0.8, 0.4, 0.1, 0.0, 0.0]);
        // on the curve: log-log between 0.2 (0.4) and 0.4 (0.1)
        match invert(&curve, Side::On, 0.2) {
            Inverted::At(v) => assert!((v - 0.2 * 2f64.powf(0.5)).abs() < 1e-12, "{v}"),
            other => panic!("{other:?}"),
        }
        // the OFF side reads its own thresholds
        match invert(&curve, Side::Off, 0.4) {
            Inverted::At(v) => assert!((v - 0.6).abs() < 1e-12, "{v}"),
            other => panic!("{other:?}"),
        }
        // fewer events than at 0.4, none at 0.8: between them
        assert_eq!(invert(&curve, Side::On, 0.05), Inverted::Between(0.4, 0.8));
        assert!((Inverted::Between(0.4, 0.8).value().unwrap() - 0.32f64.sqrt()).abs() < 1e-12);
        // beyond either end
        assert_eq!(invert(&curve, Side::On, 1.0), Inverted::Below(0.1));
        assert_eq!(
            invert(&rates_curve(&[0.8, 0.4, 0.2]), Side::On, 0.1),
            Inverted::Above(0.4)
        );
        // no rate, no curve
        assert_eq!(invert(&curve, Side::On, 0.0), Inverted::Outside);
        assert_eq!(invert(&curve, Side::On, f64::NAN), Inverted::Outside);
        assert_eq!(invert(&[], Side::On, 0.1), Inverted::Outside);
        // a tail that rises again after a zero: the first bracket counts
        assert_eq!(
            invert(&rates_curve(&[0.5, 0.2, 0.0, 0.001, 0.0]), Side::On, 0.1),
            Inverted::Between(0.2, 0.4)
        );
        // a plateau at the target
        assert_eq!(
            invert(&rates_curve(&[0.5, 0.2, 0.2, 0.1]), Side::On, 0.2),
            Inverted::At(0.2)
        );
    }

    #[test]
    fn a_pixel_s_on_count_depends_on_its_off_threshold_where_the_profile_turns() {
        // a triangle wave between 0.05 and 1.1: with thresholds 0.2 / 0.2 the memorised level
        // swings 0.2 <-> 1.0, 4 ON events per rise; with an OFF threshold of 0.6 it falls
        // only to 0.4 (one OFF event of 0.6), so each rise makes 3 ON events (0.6, 0.8, 1.0)
        let values: Vec<f32> = (0..4000)
            .map(|i| {
                let phase = (i % 200) as f32 / 100.0;
                0.05 + 1.05 * if phase < 1.0 { phase } else { 2.0 - phase }
            })
            .collect();
        let p = Profile {
            times_s: (0..values.len()).map(|i| i as f64 * 1e-3).collect(),
            values,
            burn: 400,
            length: 900.0,
        };
        let (sym, wide) = (count(&p, 0.2, 0.2), count(&p, 0.2, 0.6));
        // 18 rises and falls after the burn-in
        assert_eq!((sym.on, sym.off), (72, 72));
        assert_eq!((wide.on, wide.off), (54, 18));
    }

    #[test]
    fn a_sharp_edge_fires_its_events_in_a_burst_and_a_gradient_spreads_them() {
        // a step of 1.2 (four events of 0.3 within a pixel) against a ramp of 1.2 over
        // 40 px (one event every 10 px), each scanned over 60 px at STEP_PX
        let step: Vec<f32> = (0..240).map(|i| if i < 120 { 0.0 } else { 1.2 }).collect();
        let ramp: Vec<f32> = (0..240)
            .map(|i| (i as f32 * 0.25 / 40.0 * 1.2).min(1.2))
            .collect();
        let scan = |values: Vec<f32>| Profile {
            times_s: (0..values.len()).map(|i| i as f64 * 1e-3).collect(),
            values,
            burn: 0,
            length: 60.0,
        };
        let edge = count(&scan(step), 0.3, 0.3);
        assert_eq!((edge.on, edge.pairs, edge.bursts), (4, 3, 3));
        let gradient = count(&scan(ramp), 0.3, 0.3);
        assert_eq!((gradient.on, gradient.pairs, gradient.bursts), (4, 3, 0));
        // the refractory pixel's positions come from its crossing times: the same
        assert_eq!(
            count_refractory(&scan(vec![0.0; 1]), 0.3, 0.3, 1e-3),
            ScanCount::default()
        );
        let slow = count_refractory(
            &scan((0..240).map(|i| (i as f32 * 0.03).min(1.2)).collect()),
            0.3,
            0.3,
            1e-4,
        );
        assert_eq!((slow.on, slow.pairs, slow.bursts), (4, 3, 0));
    }

    #[test]
    fn a_refractory_pixel_fires_at_most_once_per_period_and_keeps_the_change_pending() {
        // a ramp of 0.05 per ms: a 0.1 threshold is crossed every 2 ms
        let values: Vec<f32> = (0..=100).map(|i| 0.05 * i as f32).collect();
        let p = Profile {
            times_s: (0..=100).map(|i| i as f64 * 1e-3).collect(),
            values,
            burn: 0,
            length: 25.0,
        };
        let events = |c: ScanCount| (c.on, c.off);
        let ideal = count(&p, 0.1, 0.1);
        assert_eq!(events(count_refractory(&p, 0.1, 0.1, 0.0)), events(ideal));
        // 1 ms < 2 ms between crossings: nothing lost, nothing delayed past the end
        assert_eq!(events(count_refractory(&p, 0.1, 0.1, 1e-3)), events(ideal));
        // 5 ms: one event per 5 ms over the 100 ms ramp (the first at 2 ms)
        assert_eq!(events(count_refractory(&p, 0.1, 0.1, 5e-3)), (20, 0));
        assert!(ideal.on >= 49, "{ideal:?}");
    }
}
