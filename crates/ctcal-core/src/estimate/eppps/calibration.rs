//! The calibration side of `estimate eppps`: line scans ([`super::scans`]) laid out like the
//! recording's pixels. Without frames they run in 8 x 8 blocks (a tile of the sensor)
//! through the prior's natural images ([`super::prior`]), with the recording's own
//! distribution of travel and flow direction;
//! with frames they are the recording's own pixels, each following its path along the
//! frames' flow through every used interval (the scene's contrast measured, not assumed).

use super::recording::RecordingRates;
use super::scans::{BURN_IN_PX, Block, LogImage, Profile, STEP_PX, Scan, TILE_PX};
use crate::estimate::frames::PreparedFrames;
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
            let length = (rates.travels[k] as f64).min(MAX_SCAN_PX);
            let (dx, dy) = rates.directions.get(k).copied().unwrap_or((1.0, 0.0));
            let (dx, dy) = (dx as f64, dy as f64);
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

/// Every second pixel (in x and y) of the frames, each along its path through every run of
/// consecutive used intervals where it is reliable: log intensity interpolated along the
/// flow, sampled every quarter pixel of travel; burn-in along the first interval's flow
/// backwards from the run's first frame.
pub fn frame_profiles(frames: &PreparedFrames, excluded: &[bool]) -> Vec<Profile> {
    let (w, h) = (frames.width, frames.height);
    let mut out = Vec::new();
    for y in (0..h).step_by(2) {
        for x in (0..w).step_by(2) {
            let pixel = y * w + x;
            if excluded[pixel] {
                continue;
            }
            let mut run: Option<Profile> = None;
            for k in 0..frames.flows.len() {
                let usable = frames.flows[k].is_some() && frames.reliable(k, pixel);
                if !usable {
                    out.extend(run.take());
                    continue;
                }
                let profile = run.get_or_insert_with(|| burn_in(frames, k, x, y));
                extend(profile, frames, k, x, y);
            }
            out.extend(run);
        }
    }
    out.retain(|p| p.length > 0.0);
    out
}

/// A profile holding only the burn-in before frame `k` at (x, y).
fn burn_in(frames: &PreparedFrames, k: usize, x: usize, y: usize) -> Profile {
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
    let values = (0..burn)
        .map(|i| {
            let s = (burn - i) as f64 * STEP_PX;
            let dn = frame.sample_cubic((x as f64 + s * dx) as f32, (y as f64 + s * dy) as f32);
            frames.log(dn.max(0.0))
        })
        .collect();
    Profile {
        values,
        times_s,
        burn,
        length: 0.0,
    }
}

/// Appends the pixel's samples over interval `k` (at most a quarter pixel apart).
fn extend(profile: &mut Profile, frames: &PreparedFrames, k: usize, x: usize, y: usize) {
    let (u, v) = frames.flows[k].as_ref().map_or((0.0, 0.0), |f| f.at(x, y));
    let travel = u.hypot(v) as f64;
    let steps = ((travel / STEP_PX).ceil() as usize).clamp(1, 4000);
    let (t0, t1) = (frames.times[k], frames.times[k + 1]);
    for j in 0..=steps {
        let t = t0 + ((t1 - t0) as f64 * j as f64 / steps as f64) as crate::events::TimeUs;
        let t = t.min(t1 - 1);
        if let Some(level) = frames.log_at(x as u16, y as u16, t) {
            profile.values.push(level);
            profile.times_s.push(t as f64 * 1e-6);
        }
    }
    profile.length += travel;
}
