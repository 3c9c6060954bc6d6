//! IEBCS's pixel model (ICNS Event Based Camera Simulator; Joubert et al., "Event camera
//! simulator improvements via characterized parameters", Frontiers in Neuroscience 2021),
//! re-implemented from `src/dvs_sensor.py` (`DvsSensor.update`, `get_latency_tau`,
//! `check_noise`) and the parameters of `examples/00_video_2_events/
//! 1_example_video_to_events.py` in neuromorphicsystems/IEBCS, commit
//! 8fdab5c3d078435d091fa8a94ad657e1fedf0c59 (GPL-3.0; no code copied).
//!
//! - Input and log response: the example scales an 8-bit frame to illuminance,
//!   `E = DN / 255 * 1e4` lux, and the pixel works on `ln(E + 1)`, i.e. `ln(DN + 255 / 1e4)`
//!   up to a constant (`log_offset_dn = 0.0255`); a pixel at exactly 0 lux keeps 0.
//! - Photoreceptor: first-order low-pass with `tau_p = tau * 1e3 / (E + 1)` us (`tau` given at
//!   1 klux). A frame is a step at the start of its interval (held, not interpolated):
//!   `v(t) = v_0 + (ln(E + 1) - v_0) (1 - exp(-(t - t_0) / tau_p))`.
//! - Events: at the end of each frame interval the pixel compares `v - v_ref` with its
//!   thresholds (`v_ref`, the voltage at its last reset). An event is stamped at the
//!   low-pass crossing time plus latency: `t = t_0 + N(lat - tau_p ln(1 - A), jit_eff)`,
//!   `A = (v_ref + th - v_0) / (ln(E + 1) - v_0)`,
//!   `jit_eff = sqrt(jit^2 + (th_noise tau_p / (ln(E + 1) - v_0))^2)`, clipped to 0..10 ms
//!   and truncated to the microsecond; times can fall in later frames, so ctcal sorts the
//!   whole output (IEBCS sorts each frame's packet only).
//! - Refractory: after an event the pixel is blind until `t + ref`; at that moment its
//!   reference is reset to the photoreceptor voltage then. Changes during the latency and the
//!   refractory period are dropped, not fired later (unlike v2e, which delays them). One
//!   event per (latency + refractory) at most, however large the step.
//! - Threshold noise: per event. `th_pos ~ N(th, th_noise)` and `th_neg ~ N(-th, th_noise)`
//!   (clipped to 0..1000 and -1000..0) are drawn for every pixel at start and redrawn after
//!   each of its events.
//! - Noise (`NOISE_FREQ`, what `initCamera` sets up): every pixel fires ON noise exactly
//!   every `1e6 / bgnp` us and OFF noise every `1e6 / bgnn` us, with a uniform random phase,
//!   at most one of each per frame interval; a noise event resets `v` and `v_ref` to the
//!   current frame's `ln(E + 1)` and ignores the refractory period. A rate of 0 here means
//!   no noise.
//! - Noise (`NOISE_MEASURE`, `init_bgn_hist`, which the example uses with
//!   `data/noise_{pos,neg}_161lux.npy`): with `noise_distributions` given, each pixel takes a
//!   random row of the measured ON and of the OFF cumulative distributions over 72 frequency
//!   bins (1..9 x 10^-3 .. 10^4 Hz), normalised by its second-to-last bin (an empty row means
//!   0.001 Hz), and each delay to its next noise event is `1e6 / f` us for the first bin
//!   whose cumulative value reaches a uniform draw; the first is that delay times a uniform
//!   draw. Rows are assigned as IEBCS indexes them: a random row for each of the `W H`
//!   indices, pixel (x, y) taking index `x H + y` for its first delay and `y H + x` for the
//!   later ones (wrapped modulo `W H` for a sensor taller than wide, where IEBCS would
//!   fail). So a pixel's first delay comes from another distribution than its later
//!   ones, and since two thirds of the 161 lux ON rows are empty (0.001 Hz), two thirds of
//!   the pixels stay silent for their first (up to 1e9 us) delay: over 2 s (2000 frames)
//!   of a static 64x48 scene the real code makes 382.3 noise events (sd 46, 10 seeds) and
//!   this one 368.8 (sd 24), against 646 at the long-run mean rate (0.105 Hz ON, 0.002 Hz
//!   OFF); on the moving texture below, 2732.4 (sd 10.1) and 2729.9 events. ctcal does not
//!   bundle those data files: give their paths.
//! - No leak.
//!
//! Random draws use ctcal's generators (numpy's cannot be reproduced), so agreement with
//! the Python code is statistical. Side by side with the real code (`DvsSensor.update(E,
//! 1000)` with `initCamera`'s `NOISE_FREQ` noise) on 40 frames (1 kHz) of a 64x48 texture
//! moving at (300, 120) px/s, 20 seeds each (`tests/cli/peers.rs` rechecks the counts):
//!
//! | input, parameters | real: events (sd), ON | ctcal: events (sd), ON | count-map corr. (real vs real) |
//! |---|---|---|---|
//! | 8-bit frames, the example's | 2732.4 (7.9), 1184.7 | 2730.7 (9.7), 1186.7 | 0.940 (0.938) |
//! | frames at 15 %, the example's | 3029.0 (16.1), 1328.2 | 3034.8 (14.0), 1333.2 | 0.906 (0.897) |
//! | 8-bit frames; th_noise 0.05, jit 50, ref 500, bgnp 5, bgnn 2 | 3514.1 (23.9), 1762.5 | 3500.9 (28.1), 1755.5 | 0.555 (0.567) |
//!
//! Events per 1 ms bin correlate at 0.982, 0.986 and 0.927 (real vs real 0.981, 0.988,
//! 0.934).

use super::super::rng::{Stream, generator};
use super::super::{FrameSource, SimError};
use crate::events::{EventChunk, TimeUs};
use rand::{Rng, RngExt};
use rand_distr::{Distribution, Normal, StandardNormal};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// IEBCS's sensor parameters (the arguments of `DvsSensor.initCamera`), with the example's
/// values, plus the illuminance the example maps 255 DN to.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Params {
    /// `th_pos`: mean ON threshold, log change (0.4).
    pub th_pos: f64,
    /// `th_neg`: mean OFF threshold, log change, positive (0.4).
    pub th_neg: f64,
    /// `th_noise`: threshold standard deviation (0.01).
    pub th_noise: f64,
    /// `lat`: latency at infinite contrast, us (100).
    pub lat_us: f64,
    /// `jit`: latency jitter, us (10).
    pub jit_us: f64,
    /// `ref`: refractory period, us (100).
    pub ref_us: u64,
    /// `tau`: photoreceptor time constant at 1 klux, us (40).
    pub tau_us: f64,
    /// `bgnp`: ON noise rate, Hz (0.1).
    pub bgnp_hz: f64,
    /// `bgnn`: OFF noise rate, Hz (0.01).
    pub bgnn_hz: f64,
    /// Illuminance of 255 DN, lux (the example's `/ 255.0 * 1e4`).
    pub lux_at_255: f64,
    /// Measured ON and OFF noise distributions (`.npy`, last axis 72) for the
    /// `NOISE_MEASURE` model, instead of the fixed rates `bgnp_hz` and `bgnn_hz`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise_distributions: Option<[PathBuf; 2]>,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            th_pos: 0.4,
            th_neg: 0.4,
            th_noise: 0.01,
            lat_us: 100.0,
            jit_us: 10.0,
            ref_us: 100,
            tau_us: 40.0,
            bgnp_hz: 0.1,
            bgnn_hz: 0.01,
            lux_at_255: 1e4,
            noise_distributions: None,
        }
    }
}

/// The latest a latency may be, us (`get_latency_tau`'s clip).
const MAX_LATENCY_US: f64 = 10_000.0;
/// "Not refractory" (`np.iinfo(np.uint64).max`).
const NOT_REFRACTORY: u64 = u64::MAX;

impl Params {
    /// Illuminance (lux) of `dn`.
    pub fn lux(&self, dn: f32) -> f64 {
        dn as f64 / 255.0 * self.lux_at_255
    }

    /// The noise period in us (`np.uint64(1e6 / rate)`), `None` for no noise.
    fn noise_period(rate_hz: f64) -> Option<u64> {
        (rate_hz > 0.0).then(|| ((1e6 / rate_hz) as u64).max(1))
    }

    /// The noise model these parameters ask for (reading the distributions, if any).
    fn noise_model(&self) -> Result<NoiseModel, SimError> {
        Ok(match &self.noise_distributions {
            None => NoiseModel::Freq([
                Self::noise_period(self.bgnp_hz),
                Self::noise_period(self.bgnn_hz),
            ]),
            Some([on, off]) => {
                NoiseModel::Measured([Distributions::read(on)?, Distributions::read(off)?])
            }
        })
    }

    /// The mean ON and OFF noise rates of a pixel, Hz.
    pub fn noise_rates(&self) -> Result<[f64; 2], SimError> {
        Ok(match self.noise_model()? {
            NoiseModel::Freq(_) => [self.bgnp_hz, self.bgnn_hz],
            NoiseModel::Measured([on, off]) => [on.mean_rate_hz(), off.mean_rate_hz()],
        })
    }

    pub(super) fn check(&self) -> Result<(), SimError> {
        let finite = [
            self.th_pos,
            self.th_neg,
            self.th_noise,
            self.lat_us,
            self.jit_us,
            self.tau_us,
            self.bgnp_hz,
            self.bgnn_hz,
            self.lux_at_255,
        ]
        .iter()
        .all(|v| v.is_finite() && *v >= 0.0);
        if finite && self.tau_us > 0.0 && self.lux_at_255 > 0.0 {
            Ok(())
        } else {
            Err(SimError::Invalid(
                "IEBCS parameters must be finite and >= 0, with tau_us and lux_at_255 > 0".into(),
            ))
        }
    }
}

/// IEBCS's 72 noise frequency bins (`FREQ`): 1..9 x 10^d Hz for d = -3..4.
pub fn noise_bin_hz(k: usize) -> f64 {
    (k % 9 + 1) as f64 * 10f64.powi(k as i32 / 9 - 3)
}

/// Where noise events come from.
enum NoiseModel {
    /// `NOISE_FREQ`: fixed ON and OFF periods, us.
    Freq([Option<u64>; 2]),
    /// `NOISE_MEASURE`: ON and OFF distributions.
    Measured([Distributions; 2]),
}

/// Normalised cumulative noise distributions, one row per measured pixel.
struct Distributions {
    rows: Vec<[f64; 72]>,
}

impl Distributions {
    /// Reads a `.npy` array whose last axis has IEBCS's 72 bins and normalises each row
    /// as `init_bgn_hist` does.
    fn read(path: &Path) -> Result<Self, SimError> {
        let fix =
            "give IEBCS's data/noise_pos_*.npy and data/noise_neg_*.npy (float64, last axis 72)";
        let array = ndarray_npy::read_npy::<_, ndarray::ArrayD<f64>>(path).map_err(|e| {
            SimError::file(path, format!("cannot read the distributions: {e}"), fix)
        })?;
        if array.shape().last() != Some(&72) || array.is_empty() {
            return Err(SimError::file(
                path,
                format!("shape {:?} does not end in 72 bins", array.shape()),
                fix,
            ));
        }
        let flat: Vec<f64> = array.iter().copied().collect();
        let rows = flat
            .chunks_exact(72)
            .map(|chunk| {
                let mut row: [f64; 72] = chunk.try_into().expect("72 values");
                if row.iter().sum::<f64>() == 0.0 || row[70] <= 0.0 {
                    // empty (or unnormalisable): all mass in the first, 0.001 Hz bin
                    row = [0.0; 72];
                    row[0] = 1.0;
                } else {
                    let total = row[70];
                    row.iter_mut().for_each(|v| *v /= total);
                }
                row
            })
            .collect();
        Ok(Self { rows })
    }

    /// `get_next_noise`: the delay (us) to a pixel's next noise event from row `row`.
    fn next_delay(&self, row: u32, rng: &mut impl Rng) -> u64 {
        let u: f64 = rng.random();
        let cumulative = &self.rows[row as usize];
        let k = cumulative.iter().position(|&c| c >= u).unwrap_or(70);
        (1e6 / noise_bin_hz(k)) as u64
    }

    /// The noise rate of a pixel with a random row: the mean over rows of one over the
    /// mean delay, Hz.
    fn mean_rate_hz(&self) -> f64 {
        let rate = |row: &[f64; 72]| {
            let mut previous = 0.0;
            let mut mean_delay_s = 0.0;
            for (k, &c) in row.iter().enumerate().take(71) {
                mean_delay_s += (c.min(1.0) - previous).max(0.0) / noise_bin_hz(k);
                previous = previous.max(c.min(1.0));
            }
            1.0 / mean_delay_s
        };
        self.rows.iter().map(rate).sum::<f64>() / self.rows.len() as f64
    }
}

/// One IEBCS pixel (the per-pixel arrays of `DvsSensor`).
#[derive(Clone, Copy, Debug)]
struct Pixel {
    /// `last_v`: voltage at the last reset.
    last_v: f64,
    /// `cur_v`: photoreceptor voltage at `time_px`.
    cur_v: f64,
    th_pos: f64,
    /// Negative.
    th_neg: f64,
    /// End of the refractory period, or [`NOT_REFRACTORY`].
    cur_ref: u64,
    time_px: u64,
    tau_p: f64,
    bgn_pos_next: u64,
    bgn_neg_next: u64,
    /// The pixel's rows of the ON and OFF distributions (`NOISE_MEASURE`).
    noise_rows: [u32; 2],
}

/// What the sensor holds besides its pixels.
struct Sensor<'a, R> {
    params: &'a Params,
    rng: R,
    on_threshold: Normal<f64>,
    off_threshold: Normal<f64>,
    noise: NoiseModel,
}

impl<R: Rng> Sensor<'_, R> {
    fn draw_on(&mut self) -> f64 {
        self.on_threshold.sample(&mut self.rng).clamp(0.0, 1000.0)
    }

    fn draw_off(&mut self) -> f64 {
        self.off_threshold.sample(&mut self.rng).clamp(-1000.0, 0.0)
    }

    /// The delay from a noise event of polarity `k` (0 ON, 1 OFF) to the next, `None` for
    /// no noise.
    fn noise_delay(&mut self, k: usize, row: u32) -> Option<u64> {
        match &self.noise {
            NoiseModel::Freq(periods) => periods[k],
            NoiseModel::Measured(d) => Some(d[k].next_delay(row, &mut self.rng)),
        }
    }

    /// `get_latency_tau`: the delay from `time_px` to the event, us.
    fn latency(&mut self, crossing: f64, p: &Pixel, img_l: f64) -> u64 {
        let span = img_l - p.cur_v;
        let amp = (crossing - p.cur_v) / span;
        let jit =
            (self.params.jit_us.powi(2) + (self.params.th_noise * p.tau_p / span).powi(2)).sqrt();
        let z: f64 = StandardNormal.sample(&mut self.rng);
        let t = self.params.lat_us - p.tau_p * (1.0 - amp).ln() + jit * z;
        // NaN (a degenerate crossing) clips to 0, as numpy's uint64 cast of a clipped NaN
        // cannot be relied on
        if t.is_nan() {
            0
        } else {
            t.clamp(0.0, MAX_LATENCY_US) as u64
        }
    }

    /// One pixel over one frame interval `[time, time + dt)` with log input `img_l` (`lit`:
    /// the frame is not 0 lux there). Events go to `emit(t, on)`.
    fn update(
        &mut self,
        p: &mut Pixel,
        (time, dt): (u64, u64),
        (img_l, lit): (f64, bool),
        mut emit: impl FnMut(u64, bool),
    ) {
        let end = time + dt;
        if p.cur_ref < end {
            p.end_refractory(img_l);
        }
        self.background_noise(p, end, img_l, &mut emit);
        let target = if lit { p.settle(img_l, end) } else { 0.0 };
        let dif = target - p.last_v;
        let idle = p.cur_ref == NOT_REFRACTORY;
        self.fire(
            p,
            end,
            img_l,
            (idle && dif > p.th_pos, idle && dif < p.th_neg),
            &mut emit,
        );
        if lit {
            p.cur_v = p.settle(img_l, end);
        }
        p.time_px = end;
    }

    /// `check_noise`, `check_noise_hist`: each polarity's noise event due before `end`,
    /// the next one scheduled, `v` and `v_ref` reset to the frame's `img_l`.
    fn background_noise(
        &mut self,
        p: &mut Pixel,
        end: u64,
        img_l: f64,
        emit: &mut impl FnMut(u64, bool),
    ) {
        for (k, on) in [(0, true), (1, false)] {
            let next = if on { p.bgn_pos_next } else { p.bgn_neg_next };
            if end <= next {
                continue;
            }
            emit(next, on);
            p.time_px = next;
            let after =
                next.saturating_add(self.noise_delay(k, p.noise_rows[k]).unwrap_or(u64::MAX));
            if on {
                p.bgn_pos_next = after;
            } else {
                p.bgn_neg_next = after;
            }
            p.cur_v = img_l;
            p.last_v = img_l;
        }
    }

    /// The events of the interval ending at `end`, starting with the polarities that crossed
    /// (`pos`, `neg`): each at its latency, its threshold redrawn, the pixel blind for the
    /// refractory period; where that ends before `end`, the pixel compares again.
    fn fire(
        &mut self,
        p: &mut Pixel,
        end: u64,
        img_l: f64,
        (mut pos, mut neg): (bool, bool),
        emit: &mut impl FnMut(u64, bool),
    ) {
        while pos || neg {
            for on in [true, false] {
                if !(if on { pos } else { neg }) {
                    continue;
                }
                let th = if on { p.th_pos } else { p.th_neg };
                let delay = self.latency(p.last_v + th, p, img_l);
                emit(p.time_px + delay, on);
                if on {
                    p.th_pos = self.draw_on();
                } else {
                    p.th_neg = self.draw_off();
                }
                p.cur_ref = p.time_px + delay + self.params.ref_us;
            }
            if p.cur_ref < end {
                p.end_refractory(img_l);
                let dif = p.settle(img_l, end) - p.last_v;
                (pos, neg) = (dif > p.th_pos, dif < p.th_neg);
            } else {
                (pos, neg) = (false, false);
            }
        }
    }
}

impl Pixel {
    /// The photoreceptor voltage at time `until`, settling from `cur_v` at `time_px`
    /// towards the log input `img_l` with time constant `tau_p`.
    fn settle(&self, img_l: f64, until: u64) -> f64 {
        self.cur_v
            + (img_l - self.cur_v)
                * (1.0 - (-(until as f64 - self.time_px as f64) / self.tau_p).exp())
    }

    /// The refractory period's end: the reference reset to the voltage then.
    fn end_refractory(&mut self, img_l: f64) {
        self.last_v = self.settle(img_l, self.cur_ref);
        self.time_px = self.cur_ref;
        self.cur_ref = NOT_REFRACTORY;
        self.cur_v = self.last_v;
    }
}

/// Every pixel's first noise times (`init_bgn`, `init_bgn_hist`): a uniform phase within
/// the period, or, for measured distributions, a random row for each of the `W H` indices,
/// pixel (x, y) drawing its first delay (times a uniform fraction) from index `x H + y` and
/// keeping index `y H + x` (modulo `W H`) for the later ones, as IEBCS indexes them.
fn first_noise(pixels: &mut [Pixel], (w, h): (usize, usize), noise: &NoiseModel, seed: u64) {
    let mut rng = generator(seed, Stream::Thresholds, 1);
    match noise {
        NoiseModel::Freq(periods) => {
            for (k, period) in periods.iter().enumerate() {
                for p in pixels.iter_mut() {
                    let phase = period.map_or(u64::MAX, |period| rng.random_range(0..period));
                    *if k == 0 {
                        &mut p.bgn_pos_next
                    } else {
                        &mut p.bgn_neg_next
                    } = phase;
                }
            }
        }
        NoiseModel::Measured(distributions) => {
            let tables: Vec<Vec<u32>> = distributions
                .iter()
                .map(|d| {
                    (0..w * h)
                        .map(|_| rng.random_range(0..d.rows.len() as u32))
                        .collect()
                })
                .collect();
            for (i, p) in pixels.iter_mut().enumerate() {
                let (x, y) = (i % w, i / w);
                for (k, d) in distributions.iter().enumerate() {
                    p.noise_rows[k] = tables[k][(y * h + x) % (w * h)];
                    let delay = d.next_delay(tables[k][x * h + y], &mut rng) as f64;
                    let first = (delay * rng.random::<f64>()) as u64;
                    *if k == 0 {
                        &mut p.bgn_pos_next
                    } else {
                        &mut p.bgn_neg_next
                    } = first;
                }
            }
        }
    }
}

/// Runs IEBCS over `source`: the first sample initialises the sensor (`init_image`), each
/// later one is an `update` over the time since the previous sample.
pub fn simulate(
    source: &mut dyn FrameSource,
    params: &Params,
    seed: u64,
) -> Result<EventChunk, SimError> {
    params.check()?;
    let (width, _) = source.size();
    let Some(first) = source.next_frame()? else {
        return Err(SimError::Invalid("the input has no frames".into()));
    };
    let noise = params.noise_model()?;
    let normal = |mean: f64| Normal::new(mean, params.th_noise).expect("checked finite");
    let mut sensor = Sensor {
        params,
        rng: generator(seed, Stream::Rows, 1),
        on_threshold: normal(params.th_pos),
        off_threshold: normal(-params.th_neg),
        noise,
    };
    let mut pixels = initial_pixels(&first.dn, params);
    first_noise(&mut pixels, source.size(), &sensor.noise, seed);
    for p in &mut pixels {
        p.th_pos = sensor.draw_on();
    }
    for p in &mut pixels {
        p.th_neg = sensor.draw_off();
    }
    let origin = first.t;
    let (mut time, mut last_t) = (0u64, first.t);
    let mut events: Vec<(u64, usize, bool)> = Vec::new();
    while let Some(sample) = source.next_frame()? {
        if sample.t <= last_t {
            return Err(SimError::Invalid(format!(
                "IEBCS needs strictly increasing frame times ({} us after {last_t} us)",
                sample.t
            )));
        }
        let dt = (sample.t - last_t) as u64;
        for (i, (p, &dn)) in pixels.iter_mut().zip(&sample.dn).enumerate() {
            let lux = params.lux(dn);
            let lit = lux > 0.0;
            let img_l = if lit { (lux + 1.0).ln() } else { 0.0 };
            if lit {
                p.tau_p = params.tau_us * 1e3 / (lux + 1.0);
            }
            sensor.update(p, (time, dt), (img_l, lit), |t, on| events.push((t, i, on)));
        }
        time += dt;
        last_t = sample.t;
    }
    Ok(time_ordered(events, origin, width))
}

/// The pixels of IEBCS's `init_image` at the first sample's `dn`: the low-passed and
/// reference log at the sample's, the time constant at its light, no threshold drawn yet.
fn initial_pixels(dn: &[f32], params: &Params) -> Vec<Pixel> {
    dn.iter()
        .map(|&dn| {
            let lux = params.lux(dn);
            let v = (lux + 1.0).ln();
            Pixel {
                last_v: v,
                cur_v: v,
                th_pos: 0.0,
                th_neg: 0.0,
                cur_ref: NOT_REFRACTORY,
                time_px: 0,
                tau_p: params.tau_us * 1e3 / (lux + 1.0),
                bgn_pos_next: u64::MAX,
                bgn_neg_next: u64::MAX,
                noise_rows: [0, 0],
            }
        })
        .collect()
}

/// `events` (time since `origin`, pixel, polarity) sorted by time, then pixel, as a chunk
/// on the recording's clock.
fn time_ordered(mut events: Vec<(u64, usize, bool)>, origin: TimeUs, width: usize) -> EventChunk {
    events.sort_by_key(|&(t, i, _)| (t, i));
    let mut out = EventChunk::with_capacity(events.len());
    for (t, i, on) in events {
        out.push(
            origin + t as i64,
            (i % width) as u16,
            (i / width) as u16,
            on,
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::pixel::Transition;
    use crate::sim::source::{ReplaySamples, Sample};

    /// No noise of any kind, no latency: the deterministic core.
    fn quiet() -> Params {
        Params {
            th_noise: 0.0,
            lat_us: 0.0,
            jit_us: 0.0,
            bgnp_hz: 0.0,
            bgnn_hz: 0.0,
            ..Params::default()
        }
    }

    fn run(params: &Params, times: &[i64], dn: &[f32], seed: u64) -> EventChunk {
        let samples: Vec<Sample> = times
            .iter()
            .zip(dn)
            .map(|(&t, &d)| Sample {
                t,
                dn: vec![d],
                transition: Transition::Linear,
            })
            .collect();
        simulate(&mut ReplaySamples::new(&samples, 1, 1), params, seed).unwrap()
    }

    /// The DN whose IEBCS log value is `ln(E0 + 1) + delta` for `dn0`.
    fn dn_above(p: &Params, dn0: f32, delta: f64) -> f32 {
        let lux = ((p.lux(dn0) + 1.0).ln() + delta).exp() - 1.0;
        (lux * 255.0 / p.lux_at_255) as f32
    }

    #[test]
    fn a_step_fires_at_the_low_pass_crossing_time() {
        // a step of +0.5 in ln(E + 1) with th 0.4: crossing when 1 - e^(-t/tau_p) = 0.8
        let p = quiet();
        let high = dn_above(&p, 100.0, 0.5);
        let events = run(&p, &[0, 1000], &[100.0, high], 1);
        let tau_p = p.tau_us * 1e3 / (p.lux(high) + 1.0);
        assert_eq!(events.len(), 1);
        assert!(events.on[0]);
        assert_eq!(events.t[0], (-tau_p * (0.2f64).ln()) as i64);
    }

    #[test]
    fn a_change_during_the_refractory_period_is_dropped() {
        // the same step of 0.5 then another of 0.5 (total 1.0 = 2.5 thresholds) within the
        // 100 us latency + 800 us refractory period of the first event: v2e would fire the
        // pending change when the period ends; IEBCS resets the reference then, so nothing
        // more fires
        let p = Params {
            ref_us: 800,
            lat_us: 100.0,
            ..quiet()
        };
        let mid = dn_above(&p, 100.0, 0.5);
        let high = dn_above(&p, 100.0, 1.0);
        let events = run(&p, &[0, 200, 400, 3000], &[100.0, mid, high, high], 1);
        assert_eq!(events.len(), 1, "{events:?}");
        // without the refractory period the second step fires once more (0.4 + 0.4 < 1.0),
        // one latency after the first event's reset
        let free = run(
            &Params { ref_us: 0, ..p },
            &[0, 200, 400, 3000],
            &[100.0, mid, high, high],
            1,
        );
        assert_eq!(free.len(), 2, "{free:?}");
    }

    #[test]
    fn background_noise_fires_at_its_fixed_rate() {
        // 10 Hz ON, 5 Hz OFF over 2 s of a static scene: exactly 20 and 10 per pixel
        let p = Params {
            bgnp_hz: 10.0,
            bgnn_hz: 5.0,
            ..quiet()
        };
        let times: Vec<i64> = (0..=2000).map(|k| k * 1000).collect();
        let events = run(&p, &times, &vec![80.0; times.len()], 4);
        let on = events.on_count();
        assert_eq!((on, events.len() - on), (20, 10));
        let gaps: Vec<i64> = events
            .iter()
            .filter(|e| e.on)
            .map(|e| e.t)
            .collect::<Vec<_>>()
            .windows(2)
            .map(|w| w[1] - w[0])
            .collect();
        assert!(gaps.iter().all(|&g| g == 100_000), "{gaps:?}");
    }

    #[test]
    fn latency_jitter_and_threshold_noise_are_deterministic_for_a_seed() {
        let p = Params::default();
        let times: Vec<i64> = (0..=400).map(|k| k * 1000).collect();
        let dn: Vec<f32> = (0..=400)
            .map(|k| 100.0 * (1.0 + 0.8 * (k as f32 * 0.05).sin()))
            .collect();
        let a = run(&p, &times, &dn, 5);
        assert_eq!(a, run(&p, &times, &dn, 5));
        assert!(a.is_time_sorted());
        assert!(a.len() > 10, "{}", a.len());
    }

    #[test]
    fn measured_noise_draws_delays_from_each_pixels_distribution() {
        // ON rows: one all at the 10 Hz bin (k = 36), one empty (0.001 Hz); OFF: empty.
        // Over 2 s of a static 8x8 scene a pixel whose first-delay index (x H + y) and
        // later index (y H + x) both drew the 10 Hz row fires exactly 20 ON events 100 ms
        // apart; with only the first, one; with an empty first row, none (its first delay is
        // a fraction of 1e9 us)
        let dir = tempfile::tempdir().unwrap();
        let mut on = ndarray::Array3::<f64>::zeros((1, 2, 72));
        for k in 36..71 {
            on[[0, 0, k]] = 3.0;
        }
        let off = ndarray::Array3::<f64>::zeros((1, 2, 72));
        let paths = [dir.path().join("pos.npy"), dir.path().join("neg.npy")];
        ndarray_npy::write_npy(&paths[0], &on).unwrap();
        ndarray_npy::write_npy(&paths[1], &off).unwrap();
        assert_eq!(noise_bin_hz(36), 10.0);
        let p = Params {
            noise_distributions: Some(paths),
            ..quiet()
        };
        let rates = p.noise_rates().unwrap();
        assert!((rates[0] - (10.0 + 0.001) / 2.0).abs() < 1e-9, "{rates:?}");
        assert!((rates[1] - 0.001).abs() < 1e-12);
        let times: Vec<i64> = (0..=2000).map(|k| k * 1000).collect();
        let samples: Vec<Sample> = times
            .iter()
            .map(|&t| Sample {
                t,
                dn: vec![80.0; 64],
                transition: Transition::Linear,
            })
            .collect();
        let events = simulate(&mut ReplaySamples::new(&samples, 8, 8), &p, 2).unwrap();
        assert!(events.on.iter().all(|&on| on));
        let mut per_pixel = [0usize; 64];
        for e in events.iter() {
            per_pixel[e.y as usize * 8 + e.x as usize] += 1;
        }
        assert!(
            per_pixel.iter().all(|&n| [0, 1, 20].contains(&n)),
            "{per_pixel:?}"
        );
        // a quarter each of 20 and 1 (binomial sd 3.5); the diagonal uses one index twice
        let with = |count| per_pixel.iter().filter(|&&n| n == count).count();
        assert!(
            (5..=28).contains(&with(20)) && (5..=28).contains(&with(1)),
            "{per_pixel:?}"
        );
        let diagonal_ones = (0..8).filter(|&i| per_pixel[i * 9] == 1).count();
        assert_eq!(diagonal_ones, 0);
    }
}
