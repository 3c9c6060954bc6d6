//! How fast a recording's scene changes: what the events-per-pixel-per-second method needs
//! to build calibration scenes that resemble it (Stoffregen et al. 2020 chose their
//! simulated scenes "with similar motion" by hand; here it is measured).
//!
//! - From frames: the speed of the optical flow, and the total variation rate of the log
//!   intensity, `R = mean over pixels of sum |L(s+1) - L(s)| / T` over the frames upsampled
//!   along the flow. An ideal pixel of threshold `C` fires about `R / C` events per second,
//!   so `R` is the quantity events per pixel per second is to be compared against.
//! - From events alone: the speed of moving edges, by fitting a plane to the times of the
//!   latest events around each event (the surface of active events; Benosman et al.,
//!   "Event-based visual flow", IEEE TNNLS 2014); the normal speed is `1 / |grad t|`. Its
//!   median is a statistic of the motion that is measured the same way on the simulated
//!   calibration scenes, so that their motion can be matched to it.

use super::flow::FlowField;
use super::frames::PreparedFrames;
use crate::events::{EventChunk, Sensor, TimeUs};
use rayon::prelude::*;
use serde::Serialize;

/// Below this total-variation rate of the log intensity (per pixel per second) the frames
/// show a static scene: nothing there crosses a threshold, so thresholds cannot be measured
/// from it (its events are noise).
pub const STATIC_CHANGE_RATE: f64 = 0.02;

/// Dynamics measured from frames.
#[derive(Clone, Debug, Serialize)]
pub struct FrameDynamics {
    /// Median and 90th percentile of the flow speed over textured pixels, px/s.
    pub speed_median_px_s: f64,
    pub speed_p90_px_s: f64,
    /// Total variation rate of the log intensity per pixel, log units per second.
    pub log_change_rate: f64,
}

/// Measures `frames` (upsampled along their flow, `max_step_px` apart).
pub fn from_frames(frames: &PreparedFrames, max_step_px: f64) -> Option<FrameDynamics> {
    // each frame's speeds on the pool, kept in frame order
    let per_frame: Vec<Vec<f64>> = frames
        .flows
        .par_iter()
        .enumerate()
        .map(|(k, flow)| {
            flow.as_ref()
                .map_or_else(Vec::new, |f| textured_speeds(frames, k, f))
        })
        .collect();
    let mut speeds = per_frame.concat();
    if speeds.is_empty() {
        return None;
    }
    speeds.sort_by(f64::total_cmp);
    let quantile = |q: f64| speeds[((speeds.len() - 1) as f64 * q) as usize];
    let mut variation = 0.0f64;
    let mut duration = 0.0f64;
    let pixels = frames.width * frames.height;
    let log = |v: f32| frames.log(v);
    for run in frames.upsample_runs(max_step_px, 512 << 20) {
        // each pair's sum on the pool, added in order (the same total as one by one)
        let sums: Vec<f64> = run
            .par_windows(2)
            .map(|pair| {
                pair[0]
                    .dn
                    .iter()
                    .zip(&pair[1].dn)
                    .map(|(&a, &b)| (log(b - frames.offset) - log(a - frames.offset)).abs() as f64)
                    .sum::<f64>()
            })
            .collect();
        for (pair, sum) in run.windows(2).zip(sums) {
            variation += sum;
            duration += (pair[1].t - pair[0].t) as f64 * 1e-6;
        }
    }
    (duration > 0.0).then(|| FrameDynamics {
        speed_median_px_s: quantile(0.5),
        speed_p90_px_s: quantile(0.9),
        log_change_rate: variation / (pixels as f64 * duration),
    })
}

/// The flow speeds (px/s) of frame `k`'s textured pixels (gradient at or above the
/// median): where events come from.
fn textured_speeds(frames: &PreparedFrames, k: usize, flow: &FlowField) -> Vec<f64> {
    let dt = (frames.times[k + 1] - frames.times[k]) as f64 * 1e-6;
    let (gx, gy) = frames.dn[k].gradients();
    let energies: Vec<f32> = gx
        .data
        .iter()
        .zip(&gy.data)
        .map(|(a, b)| a.hypot(*b))
        .collect();
    let mut ranked = energies.clone();
    let middle = ranked.len() / 2;
    let threshold = *ranked.select_nth_unstable_by(middle, f32::total_cmp).1;
    energies
        .iter()
        .enumerate()
        .filter(|(_, e)| **e >= threshold)
        .map(|(i, _)| flow.u[i].hypot(flow.v[i]) as f64 / dt)
        .collect()
}

/// The median normal speed of moving edges, px/s, from plane fits to the surface of
/// active events (at most `max_fits` fits, spread over the recording). `None` with too few
/// good fits.
pub fn edge_speed(events: &EventChunk, sensor: Sensor, max_fits: usize) -> Option<f64> {
    let w = sensor.width as i32;
    // latest event time per pixel and polarity
    let mut latest = vec![[TimeUs::MIN; 2]; sensor.pixels()];
    let stride = (events.len() / max_fits.max(1)).max(1);
    let mut speeds = Vec::new();
    for i in 0..events.len() {
        let (x, y, t) = (events.x[i] as i32, events.y[i] as i32, events.t[i]);
        let p = events.on[i] as usize;
        latest[(y * w + x) as usize][p] = t;
        if i % stride != 0 {
            continue;
        }
        let sums = PlaneSums::around(&latest, sensor, (x, y, t), p);
        if let Some(speed) = sums.normal_speed() {
            speeds.push(speed);
        }
    }
    if speeds.len() < 100 {
        return None;
    }
    let mid = speeds.len() / 2;
    Some(*speeds.select_nth_unstable_by(mid, f64::total_cmp).1)
}

/// The sums of a least-squares plane `t_n - t = a dx + b dy + c` over an event's recent
/// same-polarity neighbours (the surface of active events around it).
#[derive(Clone, Copy, Default)]
struct PlaneSums {
    sxx: f64,
    sxy: f64,
    syy: f64,
    sx: f64,
    sy: f64,
    sxt: f64,
    syt: f64,
    st: f64,
    n: f64,
}

impl PlaneSums {
    /// Neighbours within this many pixels of the event are fitted.
    const RADIUS: i32 = 2;
    /// Neighbours whose latest event of the polarity is older than this are left out.
    const WINDOW_US: TimeUs = 100_000;

    /// The sums over the neighbours of the event at `(x, y, t)` of polarity `p`, from each
    /// pixel's `latest` event time per polarity.
    fn around(
        latest: &[[TimeUs; 2]],
        sensor: Sensor,
        (x, y, t): (i32, i32, TimeUs),
        p: usize,
    ) -> Self {
        let (w, h) = (sensor.width as i32, sensor.height as i32);
        let mut s = PlaneSums::default();
        for dy in -Self::RADIUS..=Self::RADIUS {
            for dx in -Self::RADIUS..=Self::RADIUS {
                let (nx, ny) = (x + dx, y + dy);
                if nx < 0 || ny < 0 || nx >= w || ny >= h {
                    continue;
                }
                let tn = latest[(ny * w + nx) as usize][p];
                if tn == TimeUs::MIN || t - tn > Self::WINDOW_US {
                    continue;
                }
                let (fx, fy, ft) = (dx as f64, dy as f64, (tn - t) as f64 * 1e-6);
                s.sxx += fx * fx;
                s.sxy += fx * fy;
                s.syy += fy * fy;
                s.sx += fx;
                s.sy += fy;
                s.sxt += fx * ft;
                s.syt += fy * ft;
                s.st += ft;
                s.n += 1.0;
            }
        }
        s
    }

    /// The plane's normal speed `1 / |grad t|`, px/s; `None` with fewer than 6 neighbours,
    /// a degenerate plane, or a speed of 10,000 px/s or more.
    fn normal_speed(&self) -> Option<f64> {
        let PlaneSums {
            sxx,
            sxy,
            syy,
            sx,
            sy,
            sxt,
            syt,
            st,
            n,
        } = *self;
        if n < 6.0 {
            return None;
        }
        // centre, then solve the 2x2 system for (a, b)
        let (cxx, cxy, cyy) = (sxx - sx * sx / n, sxy - sx * sy / n, syy - sy * sy / n);
        let (cxt, cyt) = (sxt - sx * st / n, syt - sy * st / n);
        let det = cxx * cyy - cxy * cxy;
        if det <= 1e-9 {
            return None;
        }
        let a = (cyy * cxt - cxy * cyt) / det;
        let b = (cxx * cyt - cxy * cxt) / det;
        let gradient = a.hypot(b);
        (gradient > 1e-5)
            .then(|| 1.0 / gradient)
            .filter(|&speed| speed < 1e4)
    }
}
