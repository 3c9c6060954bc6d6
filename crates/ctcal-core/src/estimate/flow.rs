//! Dense optical flow between two frames: pyramidal, iterative Lucas-Kanade with Gaussian
//! windows (Lucas & Kanade, IJCAI 1981; the pyramid and warping of Bouguet, "Pyramidal
//! implementation of the Lucas Kanade feature tracker", Intel 2001), computed at every pixel.
//!
//! For each pixel the displacement `u` with `I1(x + u) = I0(x)` solves, within a Gaussian
//! window of `window_sigma` pixels, the normal equations
//! `(G*[Ix Ix, Ix Iy; Ix Iy, Iy Iy] + lambda I) du = -G*[Ix e, Iy e]`, `e = I1(x + u) - I0(x)`,
//! iterated with warping, coarse to fine over a 2x pyramid so that motions of several pixels
//! per frame are followed. `lambda` (a small fraction of the mean gradient energy) pulls the
//! flow of untextured pixels towards zero, where it cannot be measured and does not matter
//! (such pixels make no events). Frames are compared in the log domain, where a pixel's
//! events live.
//!
//! Written here rather than taken from a crate: the Rust crates with optical flow are
//! sparse feature trackers or pull in OpenCV; ctcal needs a dense field on small frames.

use super::image::Image;

/// Displacement of every pixel from frame 0 to frame 1, pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct FlowField {
    pub width: usize,
    pub height: usize,
    pub u: Vec<f32>,
    pub v: Vec<f32>,
}

impl FlowField {
    pub fn zero(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            u: vec![0.0; width * height],
            v: vec![0.0; width * height],
        }
    }

    /// The displacement at pixel (x, y).
    #[inline]
    pub fn at(&self, x: usize, y: usize) -> (f32, f32) {
        let i = y * self.width + x;
        (self.u[i], self.v[i])
    }

    /// Displacement magnitudes, for statistics.
    pub fn magnitudes(&self) -> Vec<f32> {
        self.u
            .iter()
            .zip(&self.v)
            .map(|(u, v)| u.hypot(*v))
            .collect()
    }

    /// This field at twice the resolution (values doubled), `width x height`.
    fn upsampled(&self, width: usize, height: usize) -> FlowField {
        let u = Image::new(self.width, self.height, self.u.clone());
        let v = Image::new(self.width, self.height, self.v.clone());
        let mut out = FlowField::zero(width, height);
        for y in 0..height {
            for x in 0..width {
                let (sx, sy) = ((x as f32 - 0.5) / 2.0, (y as f32 - 0.5) / 2.0);
                out.u[y * width + x] = 2.0 * u.sample(sx, sy);
                out.v[y * width + x] = 2.0 * v.sample(sx, sy);
            }
        }
        out
    }
}

/// Settings of the flow estimate.
#[derive(Clone, Debug)]
pub struct FlowOptions {
    /// Standard deviation of the Gaussian window, pixels.
    pub window_sigma: f32,
    /// Warping iterations per pyramid level.
    pub iterations: usize,
    /// Coarsest level has at least this many pixels on its short side.
    pub min_level_side: usize,
    /// Regularisation as a fraction of the mean gradient energy.
    pub regularisation: f32,
}

impl Default for FlowOptions {
    fn default() -> Self {
        Self {
            window_sigma: 4.0,
            iterations: 3,
            min_level_side: 20,
            regularisation: 0.01,
        }
    }
}

/// The flow from `i0` to `i1` (images of one size, log domain).
pub fn dense_flow(i0: &Image, i1: &Image, options: &FlowOptions) -> FlowField {
    assert_eq!((i0.width, i0.height), (i1.width, i1.height), "frame sizes");
    let mut pyramid = vec![(i0.clone(), i1.clone())];
    while pyramid.len() < 6 {
        let (a, b) = pyramid.last().expect("non-empty");
        if a.width.min(a.height) / 2 < options.min_level_side {
            break;
        }
        let next = (a.reduced(), b.reduced());
        pyramid.push(next);
    }
    let coarsest = &pyramid.last().expect("non-empty").0;
    let mut flow = FlowField::zero(coarsest.width, coarsest.height);
    for (level, (a, b)) in pyramid.iter().enumerate().rev() {
        if level + 1 < pyramid.len() {
            flow = flow.upsampled(a.width, a.height);
        }
        refine(a, b, &mut flow, options);
    }
    flow
}

/// Lucas-Kanade iterations at one pyramid level: warp `i1` by the current flow, solve the
/// window's normal equations (with `i0`'s gradients, so the matrix is computed once).
fn refine(i0: &Image, i1: &Image, flow: &mut FlowField, options: &FlowOptions) {
    let (w, h) = (i0.width, i0.height);
    let (gx, gy) = i0.gradients();
    let n = w * h;
    let product = |a: &Image, b: &Image| {
        Image::new(
            w,
            h,
            a.data.iter().zip(&b.data).map(|(p, q)| p * q).collect(),
        )
    };
    let sigma = options.window_sigma;
    let axx = product(&gx, &gx).blurred(sigma);
    let axy = product(&gx, &gy).blurred(sigma);
    let ayy = product(&gy, &gy).blurred(sigma);
    let energy = (axx.data.iter().sum::<f32>() + ayy.data.iter().sum::<f32>()) / n as f32;
    let lambda = options.regularisation * energy + 1e-9;
    let (mut ex, mut ey) = (vec![0f32; n], vec![0f32; n]);
    for _ in 0..options.iterations {
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let e = i1.sample(x as f32 + flow.u[i], y as f32 + flow.v[i]) - i0.data[i];
                ex[i] = gx.data[i] * e;
                ey[i] = gy.data[i] * e;
            }
        }
        let bx = Image::new(w, h, ex.clone()).blurred(sigma);
        let by = Image::new(w, h, ey.clone()).blurred(sigma);
        for i in 0..n {
            let (a, b, c) = (axx.data[i] + lambda, axy.data[i], ayy.data[i] + lambda);
            let det = a * c - b * b;
            if det <= 0.0 {
                continue;
            }
            let (rx, ry) = (-bx.data[i], -by.data[i]);
            flow.u[i] += (c * rx - b * ry) / det;
            flow.v[i] += (a * ry - b * rx) / det;
        }
    }
}

/// The frame between `d0` (fraction 0) and `d1` (fraction 1) at `fraction`, moving each
/// pixel's content along `flow`: `(1 - a) d0(x - a u) + a d1(x + (1 - a) u)`, sampled
/// bicubically. Values are camera DN (the blend is done in intensity, as a camera would
/// integrate it). Rows are computed in parallel.
pub fn interpolate(d0: &Image, d1: &Image, flow: &FlowField, fraction: f32, out: &mut Vec<f32>) {
    use rayon::prelude::*;
    let w = d0.width;
    out.clear();
    out.resize(w * d0.height, 0.0);
    let a = fraction;
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, value) in row.iter_mut().enumerate() {
            let (u, v) = flow.at(x, y);
            let (xf, yf) = (x as f32, y as f32);
            let before = d0.sample_cubic(xf - a * u, yf - a * v);
            let after = d1.sample_cubic(xf + (1.0 - a) * u, yf + (1.0 - a) * v);
            *value = (1.0 - a) * before + a * after;
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth periodic texture shifted by (dx, dy).
    fn texture(w: usize, h: usize, dx: f32, dy: f32) -> Image {
        let mut data = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let (xf, yf) = (x as f32 - dx, y as f32 - dy);
                data.push(
                    4.0 + 0.5 * (xf * 0.31).sin() * (yf * 0.23).cos()
                        + 0.3 * ((xf + 2.0 * yf) * 0.17).sin(),
                );
            }
        }
        Image::new(w, h, data)
    }

    #[test]
    fn recovers_a_translation_of_sub_and_several_pixels() {
        for (dx, dy) in [(0.4f32, -0.3f32), (2.6, 1.2), (-5.5, 3.0)] {
            let (i0, i1) = (texture(120, 90, 0.0, 0.0), texture(120, 90, dx, dy));
            let flow = dense_flow(&i0, &i1, &FlowOptions::default());
            // interior pixels (the border sees content that entered the frame)
            let mut errors = Vec::new();
            for y in 15..75 {
                for x in 15..105 {
                    let (u, v) = flow.at(x, y);
                    errors.push((u - dx).hypot(v - dy));
                }
            }
            errors.sort_by(f32::total_cmp);
            let median = errors[errors.len() / 2];
            assert!(median < 0.05, "({dx}, {dy}): median error {median} px");
        }
    }

    #[test]
    fn interpolation_along_the_flow_reproduces_the_middle_frame() {
        let (i0, i1) = (texture(100, 80, 0.0, 0.0), texture(100, 80, 4.0, -2.0));
        let middle = texture(100, 80, 2.0, -1.0);
        let flow = dense_flow(&i0, &i1, &FlowOptions::default());
        let mut out = Vec::new();
        interpolate(&i0, &i1, &flow, 0.5, &mut out);
        let mut worst = 0f32;
        let mut linear_worst = 0f32;
        for y in 10..70 {
            for x in 10..90 {
                let i = y * 100 + x;
                worst = worst.max((out[i] - middle.data[i]).abs());
                linear_worst =
                    linear_worst.max((0.5 * (i0.data[i] + i1.data[i]) - middle.data[i]).abs());
            }
        }
        assert!(worst < 0.02, "{worst}");
        assert!(
            linear_worst > 5.0 * worst,
            "linear {linear_worst} vs flow {worst}"
        );
    }
}
