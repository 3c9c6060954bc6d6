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
//! [`MIN_GAIN`] (noise and flicker do not sharpen under any motion) and its precision,
//! measured by split halves (the flows of the odd and even events), is within 30 %.

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

    /// Whether the window sharpened under its flow, and its odd and even events agree on
    /// the speed within 30 %.
    pub fn trusted(&self) -> bool {
        self.gain >= MIN_GAIN && self.speed_standard_error <= 0.3 * self.speed()
    }
}

/// Settings of the flow estimate.
#[derive(Clone, Debug)]
pub struct EventFlowOptions {
    /// Side of the patches, pixels.
    pub patch_px: usize,
    /// Events a window needs for a flow.
    pub min_events: usize,
    /// Events of a patch used for its first, rough flow.
    pub rough_events: usize,
    /// The displacement a window is cut to, pixels (the first pass's median speed sets
    /// the windows' length): long enough for the warp to beat the pixel grid, short enough
    /// for the flow to be constant.
    pub window_travel_px: f64,
}

impl Default for EventFlowOptions {
    fn default() -> Self {
        Self {
            patch_px: 32,
            min_events: 150,
            rough_events: 6000,
            window_travel_px: 8.0,
        }
    }
}

/// The variance gain a trusted flow needs: short windows of dense texture (a few pixels of
/// travel) sharpen by only a few per cent, noise and flicker by nothing.
pub const MIN_GAIN: f64 = 1.01;

/// The event indices of each patch, in time order.
fn patch_members(
    events: &EventChunk,
    sensor: Sensor,
    excluded: &[bool],
    p: usize,
) -> Vec<Vec<u32>> {
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

/// Flows of every patch and window of `events` (time-sorted): a first pass on the first
/// events of each patch gives the median speed, which sets the windows' length.
///
/// The patch side starts at [`EventFlowOptions::patch_px`] and doubles (up to 128 px)
/// while the first pass at twice the side finds speeds where the smaller found none, or
/// three quarters of its speeds (its lower quartile) above 1.3 times the smaller side's
/// median: in a sparse recording (a high threshold, a smooth scene) a small patch's windows
/// span more travel than its search can follow, and their flows are false and slow, while
/// a larger patch fills its windows in less time. Where speeds differ across the view (the
/// depths of a translating camera) the quartiles of both sides overlap, and the small
/// patch (finer flow) stays.
pub fn patch_flows(
    events: &EventChunk,
    sensor: Sensor,
    excluded: &[bool],
    options: &EventFlowOptions,
) -> Vec<PatchFlow> {
    let largest = (sensor.width.max(sensor.height) as usize)
        .min(128)
        .max(options.patch_px);
    let mut p = options.patch_px;
    let mut current = rough_pass(events, sensor, excluded, p, options);
    while 2 * p <= largest {
        let larger = rough_pass(events, sensor, excluded, 2 * p, options);
        let larger_patches_faster = match (current.quartiles, larger.quartiles) {
            (_, None) => false,
            (None, Some(_)) => true,
            (Some(small), Some(large)) => large[0] > 1.3 * small[1],
        };
        if !larger_patches_faster {
            break;
        }
        p *= 2;
        current = larger;
    }
    let tiles_x = (sensor.width as usize).div_ceil(p);
    let corner = |tile: usize| ((tile % tiles_x) * p, (tile / tiles_x) * p);
    // without a trusted rough flow every patch is one window
    let window_us = current.quartiles.map_or(TimeUs::MAX / 4, |[_, speed, _]| {
        ((options.window_travel_px / speed.max(1e-3)) * 1e6).max(1.0) as TimeUs
    });
    current
        .members
        .par_iter()
        .enumerate()
        .flat_map_iter(|(tile, indices)| {
            windows(events, indices, window_us)
                .into_iter()
                .filter(|w| w.len() >= options.min_events)
                .map(|w| window_flow(events, w, corner(tile), p))
                .collect::<Vec<_>>()
        })
        .collect()
}

/// The first pass at patch side `p`: each patch's events, and the quartiles of the
/// patches' first speeds ([`rough_speed`]), px/s.
struct RoughPass {
    members: Vec<Vec<u32>>,
    quartiles: Option<[f64; 3]>,
}

fn rough_pass(
    events: &EventChunk,
    sensor: Sensor,
    excluded: &[bool],
    p: usize,
    options: &EventFlowOptions,
) -> RoughPass {
    let members = patch_members(events, sensor, excluded, p);
    let tiles_x = (sensor.width as usize).div_ceil(p);
    let mut speeds: Vec<f64> = members
        .par_iter()
        .enumerate()
        .filter(|(_, m)| m.len() >= options.min_events)
        .filter_map(|(tile, m)| {
            rough_speed(
                events,
                m,
                ((tile % tiles_x) * p, (tile / tiles_x) * p),
                p,
                options,
            )
        })
        .collect();
    speeds.sort_by(f64::total_cmp);
    let at = |q: f64| speeds[((speeds.len() - 1) as f64 * q).round() as usize];
    RoughPass {
        quartiles: (!speeds.is_empty()).then(|| [at(0.25), speeds[speeds.len() / 2], at(0.75)]),
        members,
    }
}

/// The speed of a patch from its first events: the flows of its first
/// [`EventFlowOptions::rough_events`] events, of half as many, and so on, until a flow that
/// is trusted, travels at least [`MIN_SHARPENING_TRAVEL_PX`] and less than the search
/// reaches (nine tenths of the patch's side) is confirmed by the next, shorter window
/// (down to half of [`EventFlowOptions::min_events`]): the two agree (their difference
/// within 30 % of the speed), or the shorter window is untrusted and, at that speed,
/// travels less than [`MIN_SHARPENING_TRAVEL_PX`], too little to sharpen (a dense scene's
/// short recording). A window whose true travel lies beyond the search (a dense scene's
/// many events, a sparse one's long window) still has a best flow, a false one, and the
/// next window's differs.
fn rough_speed(
    events: &EventChunk,
    members: &[u32],
    corner: (usize, usize),
    p: usize,
    options: &EventFlowOptions,
) -> Option<f64> {
    let mut n = members.len().min(options.rough_events);
    let mut candidate: Option<PatchFlow> = None;
    while n >= options.min_events || (candidate.is_some() && 2 * n >= options.min_events) {
        let flow = window_flow(events, &members[..n], corner, p);
        let span_s = (flow.t_end - flow.t_start) as f64 * 1e-6;
        let travel = flow.speed() * span_s;
        if let Some(before) = &candidate {
            let agrees = flow.trusted()
                && (flow.vx - before.vx).hypot(flow.vy - before.vy)
                    <= 0.3 * flow.speed().max(before.speed());
            let too_short = !flow.trusted() && before.speed() * span_s < MIN_SHARPENING_TRAVEL_PX;
            if agrees {
                return Some(0.5 * (flow.speed() + before.speed()));
            }
            if too_short {
                return Some(before.speed());
            }
        }
        let usable = n >= options.min_events
            && flow.trusted()
            && (MIN_SHARPENING_TRAVEL_PX..=0.9 * p as f64).contains(&travel);
        candidate = usable.then_some(flow);
        n /= 2;
    }
    None
}

/// The travel below which a window of events cannot sharpen under the right flow (its
/// events sit within a couple of pixels of where they started), pixels.
const MIN_SHARPENING_TRAVEL_PX: f64 = 2.0;

/// `indices` (time-sorted) cut into windows of `window_us`; a last window shorter than half
/// joins the one before.
fn windows<'a>(events: &EventChunk, indices: &'a [u32], window_us: TimeUs) -> Vec<&'a [u32]> {
    let mut out: Vec<&[u32]> = Vec::new();
    let mut start = 0;
    while start < indices.len() {
        let t0 = events.t[indices[start] as usize];
        let end =
            start + indices[start..].partition_point(|&i| events.t[i as usize] < t0 + window_us);
        out.push(&indices[start..end.max(start + 1)]);
        start = end.max(start + 1);
    }
    if out.len() >= 2 {
        let last = out[out.len() - 1];
        let span = events.t[last[last.len() - 1] as usize] - events.t[last[0] as usize];
        if span < window_us / 2 {
            let before = out[out.len() - 2];
            let joined_start = indices.len() - last.len() - before.len();
            out.truncate(out.len() - 2);
            out.push(&indices[joined_start..]);
        }
    }
    out
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
    let span_s =
        (events.t[window[window.len() - 1] as usize] - events.t[window[0] as usize]) as f64 * 1e-6;
    let (v, gain) = maximise(&points, p, span_s);
    let halves: Vec<(f64, f64)> = [0usize, 1]
        .iter()
        .map(|&h| {
            let half: Vec<[f32; 3]> = points.iter().skip(h).step_by(2).copied().collect();
            refine(&half, p, span_s, v).0
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
/// border for what moves out of the patch. The grid is `side` cells square, but only the
/// cells the warped events reach, and the blur's two cells around them, can be other than
/// zero: those are all that is built and summed (the same sums in the same order as over
/// the whole grid, so the same value, at a fraction of the cost for a large sparse patch).
fn sharpness(points: &[[f32; 3]], p: usize, v: (f64, f64), cell: f32) -> f64 {
    let border = p as f32;
    let side = ((p as f32 + 2.0 * border) / cell).ceil() as usize + 2;
    let (vx, vy) = (v.0 as f32, v.1 as f32);
    let mut splats = Vec::with_capacity(points.len());
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
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
        (x0, y0, x1, y1) = (x0.min(ix), y0.min(iy), x1.max(ix + 1), y1.max(iy + 1));
        splats.push((ix, iy, gx - ix as f32, gy - iy as f32));
    }
    if splats.is_empty() {
        return 0.0;
    }
    let window = Window::around(x0, y0, x1, y1, side);
    let mut grid = vec![0f32; window.width * window.height];
    for (ix, iy, fx, fy) in splats {
        let k = window.index(ix, iy);
        grid[k] += (1.0 - fx) * (1.0 - fy);
        grid[k + 1] += fx * (1.0 - fy);
        grid[k + window.width] += (1.0 - fx) * fy;
        grid[k + window.width + 1] += fx * fy;
    }
    window.blurred_sum_of_squares(&grid) * (cell * cell) as f64
}

/// A part of the `side` x `side` IWE grid: the cells `x0..=x1`, `y0..=y1` that events reach,
/// with [`Window::PAD`] cells of zeros around them (the blur reads two beyond the two it
/// writes).
struct Window {
    x0: usize,
    y0: usize,
    x1: usize,
    y1: usize,
    side: usize,
    width: usize,
    height: usize,
}

impl Window {
    const PAD: usize = 4;

    fn around(x0: usize, y0: usize, x1: usize, y1: usize, side: usize) -> Self {
        Window {
            x0,
            y0,
            x1,
            y1,
            side,
            width: x1 - x0 + 1 + 2 * Self::PAD,
            height: y1 - y0 + 1 + 2 * Self::PAD,
        }
    }

    /// The local index of grid cell (`x`, `y`).
    fn index(&self, x: usize, y: usize) -> usize {
        (y + Self::PAD - self.y0) * self.width + (x + Self::PAD - self.x0)
    }

    /// The grid cells (global) where a blurred value can be other than zero along one axis:
    /// two cells around the events, inside the part of the grid the blur writes (2..side-2).
    fn reach(&self, lo: usize, hi: usize) -> std::ops::Range<usize> {
        lo.saturating_sub(2).max(2)..(hi + 3).min(self.side.saturating_sub(2))
    }

    /// The sum of squares of `grid` smoothed by a Gaussian of one cell (a separable 5-tap
    /// kernel): events sit on integer pixels, so without it an unwarped axis keeps them on
    /// whole cells and wins over the true flow, whose warp spreads them over two (Gallego
    /// et al. 2018 smooth likewise).
    fn blurred_sum_of_squares(&self, grid: &[f32]) -> f64 {
        const K: [f32; 5] = [0.054, 0.244, 0.403, 0.244, 0.054];
        let (xs, ys) = (self.reach(self.x0, self.x1), self.reach(self.y0, self.y1));
        let mut rows = vec![0f32; grid.len()];
        for y in self.y0..=self.y1 {
            for x in xs.clone() {
                let k = self.index(x, y);
                rows[k] = (0..5).map(|i| K[i] * grid[k + i - 2]).sum();
            }
        }
        let mut total = 0f64;
        for y in ys {
            for x in xs.clone() {
                let k = self.index(x, y);
                let g: f32 = (0..5)
                    .map(|i| K[i] * rows[k + i * self.width - 2 * self.width])
                    .sum();
                total += (g * g) as f64;
            }
        }
        total
    }
}

/// Coarse to fine search: displacements over the window up to the patch side, on cells of
/// 4, 2 and 1 px, then halving steps; finally the aperture check ([`normal_flow`]).
/// Returns the flow (px/s) and the sharpness gain over zero flow.
fn maximise(points: &[[f32; 3]], p: usize, span_s: f64) -> ((f64, f64), f64) {
    if span_s <= 0.0 {
        return ((0.0, 0.0), 1.0);
    }
    let mut best = (0.0, 0.0);
    let mut radius = p as f64 / span_s;
    for cell in [4.0f32, 2.0, 1.0] {
        let step = cell as f64 / span_s;
        best = grid_search(points, p, best, radius, step, cell).0;
        radius = 2.0 * step;
    }
    let (v, value) = refine(points, p, span_s, best);
    let v = normal_flow(points, p, span_s, v);
    let zero = sharpness(points, p, (0.0, 0.0), 1.0);
    let _ = value;
    (v, sharpness(points, p, v, 1.0) / zero.max(1e-12))
}

/// The best point of a square grid of `step` around `centre` out to `radius`, and its
/// sharpness.
fn grid_search(
    points: &[[f32; 3]],
    p: usize,
    centre: (f64, f64),
    radius: f64,
    step: f64,
    cell: f32,
) -> ((f64, f64), f64) {
    let n = (radius / step).ceil() as i64;
    (-n..=n)
        .flat_map(|j| (-n..=n).map(move |i| (i, j)))
        .map(|(i, j)| {
            let v = (centre.0 + i as f64 * step, centre.1 + j as f64 * step);
            (v, sharpness(points, p, v, cell))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((centre, 0.0))
}

/// Sub-pixel refinement: a few rounds of a shrinking 3 x 3 search around `start`.
fn refine(points: &[[f32; 3]], p: usize, span_s: f64, start: (f64, f64)) -> ((f64, f64), f64) {
    let mut best = (start, sharpness(points, p, start, 1.0));
    let mut step = 1.0 / span_s.max(1e-9);
    for _ in 0..5 {
        step *= 0.5;
        let next = grid_search(points, p, best.0, step, step, 1.0);
        if next.1 > best.1 {
            best = next;
        }
    }
    best
}

/// The aperture problem: a patch that sees edges of one orientation only is as sharp
/// anywhere along a valley of flows. The curvature of the sharpness at the optimum (a
/// quadratic through a 5 x 5 grid of half-pixel displacement steps) tells: where one
/// principal curvature is under a tenth of the other, the flow along the flat direction is
/// unobserved and is dropped, leaving the normal flow.
fn normal_flow(points: &[[f32; 3]], p: usize, span_s: f64, v: (f64, f64)) -> (f64, f64) {
    let h = 0.5 / span_s;
    let f = |i: f64, j: f64| sharpness(points, p, (v.0 + i * h, v.1 + j * h), 1.0);
    let centre = f(0.0, 0.0);
    let (fxx, fyy) = (
        f(1.0, 0.0) + f(-1.0, 0.0) - 2.0 * centre,
        f(0.0, 1.0) + f(0.0, -1.0) - 2.0 * centre,
    );
    let fxy = 0.25 * (f(1.0, 1.0) + f(-1.0, -1.0) - f(1.0, -1.0) - f(-1.0, 1.0));
    // eigen-decomposition of the (negative definite at a maximum) Hessian
    let (a, b, c) = (-fxx, -fxy, -fyy);
    let mean = 0.5 * (a + c);
    let root = (0.25 * (a - c).powi(2) + b * b).sqrt();
    let (stiff, soft) = (mean + root, mean - root);
    if stiff <= 0.0 || soft > 0.02 * stiff {
        return v;
    }
    // the stiff direction: eigenvector of the larger eigenvalue
    let (ex, ey) = if b.abs() > 1e-12 {
        (stiff - c, b)
    } else if a >= c {
        (1.0, 0.0)
    } else {
        (0.0, 1.0)
    };
    let norm = ex.hypot(ey);
    let (nx, ny) = (ex / norm, ey / norm);
    let along = v.0 * nx + v.1 * ny;
    (along * nx, along * ny)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Events of a grid of slanted edges (two orientations) of a 64 x 64 scene moving at
    /// `v` px/s, each crossing firing with probability 1/7 per 50 us step.
    fn moving_edges(v: (f64, f64)) -> EventChunk {
        let mut e = EventChunk::default();
        let lines = [5.0f64, 17.0, 29.0, 41.0, 53.0];
        let hash = |a: usize, b: usize, c: usize| {
            (a * 7919 + b * 104_729 + c * 31).wrapping_mul(2_654_435_761) % 97 < 14
        };
        for k in 0..400 {
            let t = k as f64 * 50e-6;
            for (n, &c) in lines.iter().enumerate() {
                for s in 0..64 {
                    // x = c + 0.3 y and y = c + 0.2 x, moved by v t
                    let a = (c + 0.3 * s as f64 + v.0 * t, s as f64 + v.1 * t);
                    let b = (s as f64 + v.0 * t, c + 0.2 * s as f64 + v.1 * t);
                    for (m, (x, y)) in [a, b].into_iter().enumerate() {
                        if (0.0..64.0).contains(&x)
                            && (0.0..64.0).contains(&y)
                            && hash(k, s, n * 2 + m)
                        {
                            e.push((t * 1e6) as TimeUs, x as u16, y as u16, m == 0);
                        }
                    }
                }
            }
        }
        e.sort_by_time();
        e
    }

    /// Sparse events of 400 short random edges (3 px segments at random places and
    /// orientations) on a 128 x 128 view that wraps, moving at `v` px/s for 2 s, each edge
    /// pixel firing with probability `q` per 5 ms step: few events per patch over much
    /// travel (as a high threshold gives), and no period the flow could alias with.
    fn sparse_moving_edges(v: (f64, f64), q: f64) -> EventChunk {
        let mut e = EventChunk::default();
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut draw = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let features: Vec<(f64, f64, f64)> = (0..400)
            .map(|_| {
                (
                    128.0 * draw(),
                    128.0 * draw(),
                    std::f64::consts::PI * draw(),
                )
            })
            .collect();
        for k in 0..400 {
            let t = k as f64 * 5e-3;
            for &(fx, fy, angle) in &features {
                for s in [-1.0, 0.0, 1.0] {
                    if draw() < q {
                        let x = (fx + s * angle.cos() + v.0 * t)
                            .rem_euclid(128.0)
                            .min(127.0);
                        let y = (fy + s * angle.sin() + v.1 * t)
                            .rem_euclid(128.0)
                            .min(127.0);
                        let at = (t * 1e6) as TimeUs + (draw() * 5e3) as TimeUs;
                        e.push(at, x as u16, y as u16, s >= 0.0);
                    }
                }
            }
        }
        e.sort_by_time();
        e
    }

    #[test]
    fn a_sparse_scene_s_flow_is_found_on_larger_patches() {
        let v = (-60.0, -25.0);
        let events = sparse_moving_edges(v, 0.016);
        let sensor = Sensor::new(128, 128);
        let flows = patch_flows(
            &events,
            sensor,
            &vec![false; sensor.pixels()],
            &EventFlowOptions::default(),
        );
        let trusted: Vec<&PatchFlow> = flows.iter().filter(|f| f.trusted()).collect();
        assert!(!trusted.is_empty(), "{} events, {flows:?}", events.len());
        let mut speeds: Vec<f64> = trusted.iter().map(|f| f.speed()).collect();
        speeds.sort_by(f64::total_cmp);
        let median = speeds[speeds.len() / 2];
        let truth = v.0.hypot(v.1);
        // 32 px patches alone read 3.3 px/s here (their windows span more travel than
        // their search follows)
        assert!(trusted[0].size > 32, "{} px patches", trusted[0].size);
        assert!(
            (median / truth - 1.0).abs() < 0.15,
            "median speed {median} for {truth} on {} px patches ({} events)",
            trusted[0].size,
            events.len()
        );
    }

    #[test]
    fn the_flow_of_moving_edges_is_found() {
        let events = moving_edges((300.0, -200.0));
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
            assert!(
                (f.vx - 300.0).abs() < 25.0 && (f.vy + 200.0).abs() < 25.0,
                "{f:?}"
            );
        }
    }
}
