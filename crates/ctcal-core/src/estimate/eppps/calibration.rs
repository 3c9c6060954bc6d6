//! The calibration side of `estimate eppps`: line scans ([`super::scans`]) laid out like the
//! recording's pixels. Without frames they run in 8 x 8 blocks (a tile of the sensor)
//! through the prior's natural images ([`super::prior`]), with the recording's own
//! distribution of travel and flow direction;
//! with frames they are the recording's own pixels, each following its path along the
//! frames' flow through every used interval (the scene's contrast measured, not assumed).

use super::recording::RecordingRates;
use super::scans::{BURN_IN_PX, Block, LogImage, Profile, STEP_PX, Scan, TILE_PX};
use crate::estimate::frames::PreparedFrames;
use crate::sim::effects::bandwidth;
use crate::sim::log_response::LogMap;
use crate::sim::params::LogResponse;
use rand::{RngExt, SeedableRng};

/// Blocks of scans per prior image.
pub const BLOCKS_PER_IMAGE: usize = 100;
/// The longest counted stretch of a scan, pixels: a longer travel is scanned this far (its
/// events per pixel of travel are those of the long-travel regime already).
pub const MAX_SCAN_PX: f64 = 100.0;

/// Blocks of scans through `image` with the recording's travel and directions (sampled
/// together, per counted tile), placed so that burn-in and counted part stay inside.
pub fn prior_blocks(image: &LogImage, rates: &RecordingRates, seed: u64) -> Vec<Block> {
    let seconds_per_px = 1.0 / rates.speed_median_px_s.max(1e-3);
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
    let n = rates.travels.len();
    let side = TILE_PX as f64;
    (0..BLOCKS_PER_IMAGE)
        .map(|_| {
            let k = rng.random_range(0..n);
            let (dx, dy) = rates.directions.get(k).copied().unwrap_or((1.0, 0.0));
            let (dx, dy) = (dx as f64, dy as f64);
            let length = (rates.travels[k] as f64)
                .min(MAX_SCAN_PX)
                .min(fitting_length(image, dx, dy));
            let span = |d: f64, size: usize| {
                let (a, b) = (-BURN_IN_PX * d, length * d);
                (1.0 - a.min(b), (size as f64 - 2.0 - side) - a.max(b))
            };
            let (x_lo, x_hi) = span(dx, image.width);
            let (y_lo, y_hi) = span(dy, image.height);
            let mut pick = |lo: f64, hi: f64| {
                if hi > lo {
                    rng.random_range(lo..hi)
                } else {
                    0.5 * (lo + hi)
                }
            };
            let (x, y) = (pick(x_lo, x_hi), pick(y_lo, y_hi));
            Block {
                corner: Scan {
                    x,
                    y,
                    dx,
                    dy,
                    length,
                    seconds_per_px,
                },
            }
        })
        .collect()
}

/// The longest counted stretch whose burn-in, scan and tile fit inside `image` along
/// direction `(dx, dy)` (at least a pixel): never binding on the prior's photographs (256
/// px wide, at least 150 high: room for 123 px where [`MAX_SCAN_PX`] is 100), it keeps
/// scans through a small sensor's own frames from running off the frame into the clamped
/// border, where they would find no contrast.
fn fitting_length(image: &LogImage, dx: f64, dy: f64) -> f64 {
    let room = |d: f64, size: usize| {
        if d.abs() < 1e-9 {
            f64::INFINITY
        } else {
            (size as f64 - 3.0 - TILE_PX as f64) / d.abs() - BURN_IN_PX
        }
    };
    room(dx, image.width).min(room(dy, image.height)).max(1.0)
}

/// A log response the frames are read through: a map and the DN added before it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Response {
    pub map: LogMap,
    pub offset_dn: f32,
}

impl Response {
    /// The frames' own (measured or given) response.
    pub fn of(frames: &PreparedFrames) -> Self {
        Response {
            map: frames.log_map,
            offset_dn: frames.offset,
        }
    }

    /// The two ends of what sensors and simulators use where a recording does not measure
    /// it: v2e's lin-log (linear below 20 DN, as an offset of about 20 DN would be;
    /// DVS-Voltmeter fits `ln(DN + k2)` with k2 = 20-23 DN on a DAVIS346 and a DVS240) and a
    /// pure log (ESIM's `ln(I + 0.001)`, 0.26 DN).
    pub fn ends() -> [(Self, &'static str); 2] {
        [
            (
                Response {
                    map: LogMap::new(LogResponse::V2e, 0.001),
                    offset_dn: 0.0,
                },
                "v2e's lin-log",
            ),
            (
                Response {
                    map: LogMap::new(LogResponse::Eps, 0.001),
                    offset_dn: 0.0,
                },
                "a pure log ln(DN/255 + 0.001)",
            ),
        ]
    }

    #[inline]
    fn log(&self, dn: f32) -> f32 {
        self.map.apply(dn + self.offset_dn)
    }
}

/// Every second pixel (in x and y) of the frames, each along its path through every run of
/// consecutive used intervals where it is reliable: log intensity interpolated along the
/// flow, sampled every quarter pixel of travel; burn-in along the first interval's flow
/// backwards from the run's first frame. With `photoreceptor_hz` (a cutoff at white), each
/// profile is what a photoreceptor that slow passes of it ([`low_pass`]).
pub fn frame_profiles(
    frames: &PreparedFrames,
    excluded: &[bool],
    response: &Response,
    photoreceptor_hz: Option<f64>,
) -> Vec<Profile> {
    let (w, h) = (frames.width, frames.height);
    let mut out = Vec::new();
    for y in (0..h).step_by(2) {
        for x in (0..w).step_by(2) {
            let pixel = y * w + x;
            if excluded[pixel] {
                continue;
            }
            let mut run: Option<Building> = None;
            for k in 0..frames.flows.len() {
                let usable = frames.flows[k].is_some() && frames.reliable(k, pixel);
                if !usable {
                    out.extend(run.take().map(|b| b.finish(photoreceptor_hz)));
                    continue;
                }
                let building = run.get_or_insert_with(|| {
                    burn_in(frames, response, k, x, y, photoreceptor_hz.is_some())
                });
                building.extend(frames, response, k, x, y);
            }
            out.extend(run.map(|b| b.finish(photoreceptor_hz)));
        }
    }
    out.retain(|p| p.length > 0.0);
    out
}

/// A pixel's profile while it is built, with each sample's frame DN (the intensity that
/// sets a photoreceptor's cutoff) where it is to be low-passed.
struct Building {
    profile: Profile,
    dn: Option<Vec<f32>>,
}

impl Building {
    /// Appends the pixel's samples over interval `k` (at most a quarter pixel apart).
    fn extend(
        &mut self,
        frames: &PreparedFrames,
        response: &Response,
        k: usize,
        x: usize,
        y: usize,
    ) {
        let (profile, dn) = (&mut self.profile, &mut self.dn);
        let travel = path_samples(frames, k, x, y, |t, v| {
            profile.values.push(response.log(v));
            profile.times_s.push(t as f64 * 1e-6);
            if let Some(dn) = dn {
                dn.push(v);
            }
            true
        });
        profile.length += travel;
    }

    /// The profile, low-passed where a photoreceptor cutoff is given.
    fn finish(mut self, photoreceptor_hz: Option<f64>) -> Profile {
        if let (Some(cutoff_hz), Some(dn)) = (photoreceptor_hz, &self.dn) {
            low_pass(&mut self.profile, dn, cutoff_hz);
        }
        self.profile
    }
}

/// `profile`'s log intensity as a photoreceptor whose cutoff at white is `cutoff_hz`
/// passes it: the simulator's first-order low-pass ([`bandwidth`], v2e's law), its cutoff
/// at each step's mean frame DN (`dn`), exact for an input linear between samples. It
/// starts settled at the mean of the burn-in (a slow pixel holds an average of what passed
/// it, and the burn-in is all the scan knows of that); at the first sample without one.
pub fn low_pass(profile: &mut Profile, dn: &[f32], cutoff_hz: f64) {
    let (values, times_s) = (&mut profile.values, &profile.times_s);
    let Some(&first) = values.first() else {
        return;
    };
    let burn = profile.burn.min(values.len());
    let settled = if burn > 0 {
        values[..burn].iter().sum::<f32>() / burn as f32
    } else {
        first
    };
    values[0] = settled;
    let (mut filtered, mut input_before) = (settled, first);
    for i in 1..values.len() {
        let input = values[i];
        let h_us = ((times_s[i] - times_s[i - 1]) * 1e6) as f32;
        let tau_us = bandwidth::tau_us(0.5 * (dn[i - 1] + dn[i]), cutoff_hz as f32);
        filtered = bandwidth::advance(filtered, input_before, input, h_us, tau_us);
        input_before = input;
        values[i] = filtered;
    }
}

/// A profile holding only the burn-in before frame `k` at (x, y), and its DN where
/// `keep_dn` (a low-pass to come).
fn burn_in(
    frames: &PreparedFrames,
    response: &Response,
    k: usize,
    x: usize,
    y: usize,
    keep_dn: bool,
) -> Building {
    let (u, v) = frames.flows[k].as_ref().map_or((0.0, 0.0), |f| f.at(x, y));
    let norm = u.hypot(v).max(1e-6) as f64;
    let (dx, dy) = (u as f64 / norm, v as f64 / norm);
    let burn = (BURN_IN_PX / STEP_PX).round() as usize;
    let frame = &frames.dn[k];
    // the burn-in passes at the first interval's speed
    let steps = ((u.hypot(v) as f64 / STEP_PX).ceil()).clamp(1.0, 4000.0);
    let (t0, t1) = (
        frames.times[k] as f64 * 1e-6,
        frames.times[k + 1] as f64 * 1e-6,
    );
    let dt = (t1 - t0) / steps;
    let times_s = (0..burn).map(|i| t0 - (burn - i) as f64 * dt).collect();
    // the content that passed the pixel before the frame: at fraction a < 0 of the
    // interval it saw the frame at (x, y) - a (u, v), downstream along the flow
    let dn: Vec<f32> = (0..burn)
        .map(|i| {
            let s = (burn - i) as f64 * STEP_PX;
            let dn = frame.sample_cubic((x as f64 + s * dx) as f32, (y as f64 + s * dy) as f32);
            dn.max(0.0)
        })
        .collect();
    let values = dn.iter().map(|&v| response.log(v)).collect();
    Building {
        profile: Profile {
            values,
            times_s,
            burn,
            length: 0.0,
        },
        dn: keep_dn.then_some(dn),
    }
}

/// Visits pixel (x, y)'s frame values (DN, without the offset) along its path over
/// interval `k`, every [`STEP_PX`] of travel at most (interpolated along the flow, where the
/// pixel is reliable), until `visit(t, dn)` returns `false`; returns the interval's travel.
pub(super) fn path_samples(
    frames: &PreparedFrames,
    k: usize,
    x: usize,
    y: usize,
    mut visit: impl FnMut(crate::events::TimeUs, f32) -> bool,
) -> f64 {
    let (u, v) = frames.flows[k].as_ref().map_or((0.0, 0.0), |f| f.at(x, y));
    let travel = u.hypot(v) as f64;
    let steps = ((travel / STEP_PX).ceil() as usize).clamp(1, 4000);
    let (t0, t1) = (frames.times[k], frames.times[k + 1]);
    for j in 0..=steps {
        let t = t0 + ((t1 - t0) as f64 * j as f64 / steps as f64) as crate::events::TimeUs;
        let t = t.min(t1 - 1);
        if let Some(dn) = frames.dn_at(x as u16, y as u16, t)
            && !visit(t, dn)
        {
            break;
        }
    }
    travel
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A step of 1 in log intensity through a photoreceptor of 10 Hz at white: at 255 DN
    /// its time constant is 1 / (2 pi 10 Hz) = 15.915 ms, so 16 ms after the step it has
    /// risen 1 - exp(-16 / 15.915) = 0.6340; at 35 DN the cutoff is 10 (35 + 20) / 275 =
    /// 2 Hz, 79.58 ms, and it has risen 1 - exp(-16 / 79.58) = 0.1822. Before the step it
    /// holds the first sample.
    #[test]
    fn a_slow_photoreceptor_lags_a_step_by_its_time_constant_at_the_pixel_s_brightness() {
        let risen = |dn: f32| {
            let mut times_s = vec![0.0, 0.001];
            times_s.extend((0..=16).map(|k| 0.001 + 1e-6 + k as f64 * 1e-3));
            let mut values = vec![0.0f32; 2];
            values.extend(std::iter::repeat_n(1.0f32, 17));
            let dn = vec![dn; values.len()];
            let mut profile = Profile {
                values,
                times_s,
                burn: 0,
                length: 1.0,
            };
            low_pass(&mut profile, &dn, 10.0);
            (profile.values[1], profile.values[18] as f64)
        };
        let (before, bright) = risen(255.0);
        assert_eq!(before, 0.0);
        assert!((bright - 0.6340).abs() < 1e-3, "{bright}");
        let (_, dim) = risen(35.0);
        assert!((dim - 0.1822).abs() < 1e-3, "{dim}");
    }

    /// The two ends of the response prior agree on a bright scene and part in a dim one: a
    /// factor 2 in light is ln 2 = 0.693 through both at 100 -> 200 DN, but 15 -> 30 DN
    /// crosses the lin-log's knee at 20 DN, 0.15 * 15 = 2.247 -> ln 30 = 3.401 (1.154),
    /// against ln((30/255 + 0.001) / (15/255 + 0.001)) = 0.685 through the pure log.
    #[test]
    fn the_response_ends_agree_in_bright_light_and_part_in_the_dark() {
        let [(lin_log, _), (pure, _)] = Response::ends();
        let step = |r: &Response, a: f32, b: f32| (r.log(b) - r.log(a)) as f64;
        assert!((step(&lin_log, 100.0, 200.0) - 2f64.ln()).abs() < 2e-3);
        assert!((step(&pure, 100.0, 200.0) - 0.6919).abs() < 2e-3);
        assert!((step(&lin_log, 15.0, 30.0) - 1.154).abs() < 2e-3);
        assert!((step(&pure, 15.0, 30.0) - 0.6848).abs() < 2e-3);
    }
}
