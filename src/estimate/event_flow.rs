//! Optical flow from events alone, by contrast maximisation (Gallego, Rebecq & Scaramuzza,
//! "A Unifying Contrast Maximization Framework for Event Cameras", CVPR 2018): the events
//! of a patch over a short window, moved back along a candidate flow `v` to one time
//! (`x - v (t - t_ref)`), pile up on the scene's edges when `v` is the true flow; the
//! image of warped events (IWE) is then sharpest, which its variance measures. The flow of
//! each patch and window is the `v` of largest variance, found coarse to fine (IWE cells
//! of 4, 2 and 1 px, displacement steps of one cell), with a small preference for slow
//! flows so that an edge seen through the aperture of a patch gets its normal flow.
//!
//! A patch's flow is trusted when the best variance exceeds the unwarped one by
//! [`MIN_GAIN`] (noise and flicker do not sharpen under any motion); its precision is
//! measured by split halves (the flows of the odd and even events).

use crate::events::{EventChunk, Sensor, TimeUs};
use rayon::prelude::*;
use serde::Serialize;

/// The flow of one patch over one window.
#[derive(Clone, Debug, Serialize)]
pub struct PatchFlow {
    /// The patch's corner and side, pixels.
    pub x0: usize,
    pub y0: usize,
    pub size: usize,
    pub t_start: TimeUs,
    pub t_end: TimeUs,
    /// Flow, pixels per second.
    pub vx: f64,
    pub vy: f64,
    pub events: usize,
    /// IWE variance at the flow over that at zero flow.
    pub gain: f64,
    /// Half the difference of the speeds of the odd and even events, px/s.
    pub speed_standard_error: f64,
}

impl PatchFlow {
    pub fn speed(&self) -> f64 {
        self.vx.hypot(self.vy)
    }

    /// Whether the window sharpened under its flow.
    pub fn trusted(&self) -> bool {
        self.gain >= MIN_GAIN
    }
}

/// Settings of the flow estimate.
#[derive(Clone, Debug)]
pub struct EventFlowOptions {
    /// Side of the patches, pixels.
    pub patch_px: usize,
    /// Events a window needs for a flow.
    pub min_events: usize,
    /// Events per window (a patch's events are cut into windows of this many).
    pub window_events: usize,
}

impl Default for EventFlowOptions {
    fn default() -> Self {
        Self {
            patch_px: 32,
            min_events: 150,
            window_events: 2000,
        }
    }
}

/// The variance gain a trusted flow needs.
pub const MIN_GAIN: f64 = 1.15;

/// The event indices of each patch, in time order.
fn patch_members(events: &EventChunk, sensor: Sensor, excluded: &[bool], p: usize) -> Vec<Vec<u32>> {
    let tiles_x = (sensor.width as usize).div_ceil(p);
    let tiles = tiles_x * (sensor.height as usize).div_ceil(p);
    let width = sensor.width as usize;
    let mut members = vec![Vec::new(); tiles];
    for i in 0..events.len() {
        let (x, y) = (events.x[i] as usize, events.y[i] as usize);
        if !excluded[y * width + x] {
            members[(y / p) * tiles_x + x / p].push(i as u32);
        }
    }
    members
}

/// Flows of every patch and window of `events` (time-sorted).
pub fn patch_flows(
    events: &EventChunk,
    sensor: Sensor,
    excluded: &[bool],
    options: &EventFlowOptions,
) -> Vec<PatchFlow> {
    let p = options.patch_px;
    let tiles_x = (sensor.width as usize).div_ceil(p);
    let members = patch_members(events, sensor, excluded, p);
    members
        .par_iter()
        .enumerate()
        .flat_map_iter(|(tile, indices)| {
            let (x0, y0) = ((tile % tiles_x) * p, (tile / tiles_x) * p);
            let windows = indices.len().div_ceil(options.window_events.max(1)).max(1);
            let per = indices.len().div_ceil(windows).max(1);
            indices
                .chunks(per)
                .filter(|w| w.len() >= options.min_events)
                .map(move |w| window_flow(events, w, (x0, y0), p))
                .collect::<Vec<_>>()
        })
        .collect()
}

/// Events of a window relative to the patch corner and the window's middle time (s).
fn relative(events: &EventChunk, window: &[u32], (x0, y0): (usize, usize)) -> Vec<[f32; 3]> {
    let t0 = events.t[window[0] as usize];
    let t1 = events.t[window[window.len() - 1] as usize];
    let mid = t0 + (t1 - t0) / 2;
    window
        .iter()
        .map(|&i| {
            let i = i as usize;
            [
                events.x[i] as f32 - x0 as f32,
                events.y[i] as f32 - y0 as f32,
                ((events.t[i] - mid) as f64 * 1e-6) as f32,
            ]
        })
        .collect()
}

fn window_flow(events: &EventChunk, window: &[u32], corner: (usize, usize), p: usize) -> PatchFlow {
    let points = relative(events, window, corner);
    let span_s = (events.t[window[window.len() - 1] as usize] - events.t[window[0] as usize]) as f64 * 1e-6;
    let (v, gain) = maximise(&points, p, span_s);
    let halves: Vec<(f64, f64)> = [0usize, 1]
        .iter()
        .map(|&h| {
            let half: Vec<[f32; 3]> = points.iter().skip(h).step_by(2).copied().collect();
            refine(&half, p, span_s, v, 1.0).0
        })
        .collect();
    let speed = |v: (f64, f64)| v.0.hypot(v.1);
    PatchFlow {
        x0: corner.0,
        y0: corner.1,
        size: p,
        t_start: events.t[window[0] as usize],
        t_end: events.t[window[window.len() - 1] as usize],
        vx: v.0,
        vy: v.1,
        events: window.len(),
        gain,
        speed_standard_error: 0.5 * (speed(halves[0]) - speed(halves[1])).abs(),
    }
}

/// The sum of squares of the IWE (its variance up to constants: the number of events and
/// the grid are fixed) of `points` warped by `v` (px/s), on cells of `cell` px, with a
/// border for what moves out of the patch.
fn sharpness(points: &[[f32; 3]], p: usize, v: (f64, f64), cell: f32) -> f64 {
    let border = p as f32;
    let side = ((p as f32 + 2.0 * border) / cell).ceil() as usize + 2;
    let mut grid = vec![0f32; side * side];
    let (vx, vy) = (v.0 as f32, v.1 as f32);
    for &[x, y, t] in points {
        let gx = (x - vx * t + border) / cell;
        let gy = (y - vy * t + border) / cell;
        if gx < 0.0 || gy < 0.0 {
            continue;
        }
        let (ix, iy) = (gx as usize, gy as usize);
        if ix + 1 >= side || iy + 1 >= side {
            continue;
        }
        let (fx, fy) = (gx - ix as f32, gy - iy as f32);
        let k = iy * side + ix;
        grid[k] += (1.0 - fx) * (1.0 - fy);
        grid[k + 1] += fx * (1.0 - fy);
        grid[k + side] += (1.0 - fx) * fy;
        grid[k + side + 1] += fx * fy;
    }
    grid.iter().map(|&g| (g * g) as f64).sum::<f64>() * (cell * cell) as f64
}

/// The objective: sharpness with a slight preference for slow flows (0.1 % per cell of
/// displacement), which picks the normal flow along an aperture's flat valley.
fn objective(points: &[[f32; 3]], p: usize, span_s: f64, v: (f64, f64), cell: f32) -> f64 {
    let displacement = v.0.hypot(v.1) * span_s;
    sharpness(points, p, v, cell) * (1.0 - 1e-3 * displacement / cell as f64)
}

/// Coarse to fine search: displacements over the window up to the patch side, on cells of
/// 4, 2 and 1 px. Returns the flow (px/s) and the sharpness gain over zero flow.
fn maximise(points: &[[f32; 3]], p: usize, span_s: f64) -> ((f64, f64), f64) {
    if span_s <= 0.0 {
        return ((0.0, 0.0), 1.0);
    }
    let reach = p as f64 / span_s;
    let mut best = (0.0, 0.0);
    let mut radius = reach;
    for cell in [4.0f32, 2.0, 1.0] {
        let step = cell as f64 / span_s;
        (best, _) = grid_search(points, p, span_s, best, radius, step, cell);
        radius = 2.0 * step;
    }
    let (v, value) = refine(points, p, span_s, best, 1.0);
    let zero = sharpness(points, p, (0.0, 0.0), 1.0);
    (v, value / zero.max(1e-12))
}

/// The best point of a square grid of `step` around `centre` out to `radius`.
fn grid_search(
    points: &[[f32; 3]],
    p: usize,
    span_s: f64,
    centre: (f64, f64),
    radius: f64,
    step: f64,
    cell: f32,
) -> ((f64, f64), f64) {
    let n = (radius / step).ceil() as i64;
    let mut best = (centre, f64::NEG_INFINITY);
    for j in -n..=n {
        for i in -n..=n {
            let v = (centre.0 + i as f64 * step, centre.1 + j as f64 * step);
            let value = objective(points, p, span_s, v, cell);
            if value > best.1 {
                best = (v, value);
            }
        }
    }
    best
}

/// Sub-cell refinement: a few rounds of a shrinking 3 x 3 search around `start`.
fn refine(
    points: &[[f32; 3]],
    p: usize,
    span_s: f64,
    start: (f64, f64),
    cell: f32,
) -> ((f64, f64), f64) {
    let mut best = (start, objective(points, p, span_s, start, cell));
    let mut step = cell as f64 / span_s.max(1e-9);
    for _ in 0..6 {
        step *= 0.5;
        best = grid_search(points, p, span_s, best.0, step, step, cell);
    }
    (best.0, sharpness(points, p, best.0, cell))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Events of vertical and diagonal edges of a 64 x 64 scene moving at `v` px/s.
    fn moving_edges(v: (f64, f64)) -> EventChunk {
        let mut e = EventChunk::default();
        let edges = [5.0f64, 17.0, 29.0, 41.0];
        for k in 0..400 {
            let t = k as f64 * 50e-6;
            for &e0 in &edges {
                for y in 0..64 {
                    // an edge at x = e0 + 0.3 y, moved by v t
                    let x = e0 + 0.3 * y as f64 + v.0 * t;
                    let yy = y as f64 + v.1 * t;
                    if (0.0..64.0).contains(&x) && (0.0..64.0).contains(&yy) && (k + y) % 7 == 0 {
                        e.push((t * 1e6) as TimeUs, x as u16, yy as u16, true);
                    }
                }
            }
        }
        e.sort_by_time();
        e
    }

    #[test]
    fn the_flow_of_moving_edges_is_found() {
        let events = moving_edges((300.0, 0.0));
        let sensor = Sensor::new(64, 64);
        let flows = patch_flows(
            &events,
            sensor,
            &vec![false; sensor.pixels()],
            &EventFlowOptions::default(),
        );
        assert!(!flows.is_empty());
        let trusted: Vec<&PatchFlow> = flows.iter().filter(|f| f.trusted()).collect();
        assert!(trusted.len() * 2 >= flows.len(), "{flows:?}");
        for f in trusted {
            // slanted edges moving along x: the normal speed is 300 cos(atan 0.3) = 287
            assert!((f.speed() - 287.0).abs() < 30.0, "{f:?}");
        }
    }
}
