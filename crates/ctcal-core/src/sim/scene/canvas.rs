//! Procedural textures: periodic log-normal canvases with a power-law spectrum, the texture
//! model of the oracle scenes (and of natural images, whose amplitude spectra fall roughly
//! as 1/f: Field, JOSA A 1987). White Gaussian noise is filtered in the Fourier domain by
//! `A(f) = f^-beta * exp(-2 (pi * blur * f)^2)` (`A(0) = 0`), normalised to zero mean and unit
//! standard deviation, and mapped to intensity `exp(clip(ln(mean) + log_std * z, ln(min),
//! ln(max)))`. The canvas tiles seamlessly, so it can be sampled anywhere with wrap-around.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;
use serde::{Deserialize, Serialize};

/// A square, periodic intensity image (camera DN).
#[derive(Clone, Debug)]
pub struct Canvas {
    pub size: usize,
    pub pixels: Vec<f32>,
}

/// How to make a texture.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TextureParams {
    #[serde(default = "default_canvas_px")]
    pub canvas_px: usize,
    #[serde(default = "default_mean")]
    pub mean_dn: f64,
    #[serde(default = "default_log_std")]
    pub log_std: f64,
    #[serde(default = "default_min")]
    pub min_dn: f64,
    #[serde(default = "default_max")]
    pub max_dn: f64,
    #[serde(default = "default_beta")]
    pub spectrum_beta: f64,
    #[serde(default = "default_blur")]
    pub blur_px: f64,
}

fn default_canvas_px() -> usize {
    512
}
fn default_mean() -> f64 {
    90.0
}
fn default_log_std() -> f64 {
    0.45
}
fn default_min() -> f64 {
    25.0
}
fn default_max() -> f64 {
    235.0
}
fn default_beta() -> f64 {
    1.0
}
fn default_blur() -> f64 {
    1.5
}

impl Default for TextureParams {
    fn default() -> Self {
        Self {
            canvas_px: default_canvas_px(),
            mean_dn: default_mean(),
            log_std: default_log_std(),
            min_dn: default_min(),
            max_dn: default_max(),
            spectrum_beta: default_beta(),
            blur_px: default_blur(),
        }
    }
}

/// 2-D FFT in place (rows, then columns).
fn fft2(data: &mut [Complex<f64>], n: usize, inverse: bool) {
    let mut planner = FftPlanner::<f64>::new();
    let fft = if inverse {
        planner.plan_fft_inverse(n)
    } else {
        planner.plan_fft_forward(n)
    };
    for row in data.chunks_exact_mut(n) {
        fft.process(row);
    }
    let mut column = vec![Complex::new(0.0, 0.0); n];
    for x in 0..n {
        for y in 0..n {
            column[y] = data[y * n + x];
        }
        fft.process(&mut column);
        for y in 0..n {
            data[y * n + x] = column[y];
        }
    }
}

/// Signed FFT frequency of index `k` of `n` (cycles per pixel), as numpy's `fftfreq`.
fn frequency(k: usize, n: usize) -> f64 {
    let k = if k < n.div_ceil(2) {
        k as f64
    } else {
        k as f64 - n as f64
    };
    k / n as f64
}

impl Canvas {
    /// Synthesises a texture.
    pub fn generate(params: &TextureParams, rng: &mut impl Rng) -> Self {
        let n = params.canvas_px.max(8);
        let mut data: Vec<Complex<f64>> = (0..n * n)
            .map(|_| Complex::new(StandardNormal.sample(rng), 0.0))
            .collect();
        fft2(&mut data, n, false);
        for y in 0..n {
            for x in 0..n {
                let f = frequency(x, n).hypot(frequency(y, n));
                let amplitude = if f == 0.0 {
                    0.0
                } else {
                    f.powf(-params.spectrum_beta)
                        * (-2.0 * (std::f64::consts::PI * params.blur_px * f).powi(2)).exp()
                };
                data[y * n + x] *= amplitude;
            }
        }
        fft2(&mut data, n, true);
        let real: Vec<f64> = data.iter().map(|c| c.re).collect();
        let mean = real.iter().sum::<f64>() / real.len() as f64;
        let sd = (real.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / real.len() as f64)
            .sqrt()
            .max(1e-300);
        let (lo, hi) = (params.min_dn.ln(), params.max_dn.ln());
        let pixels = real
            .iter()
            .map(|v| {
                let z = (v - mean) / sd;
                (params.mean_dn.ln() + params.log_std * z)
                    .clamp(lo, hi)
                    .exp() as f32
            })
            .collect();
        Self { size: n, pixels }
    }

    /// A canvas from a grey image (tiled periodically when sampled).
    pub fn from_image(width: usize, height: usize, pixels: &[u8]) -> Self {
        // resample to a square by nearest neighbour so wrap-around stays simple
        let size = width.max(height);
        let mut out = vec![0f32; size * size];
        for y in 0..size {
            for x in 0..size {
                let sx = x * width / size;
                let sy = y * height / size;
                out[y * size + x] = pixels[sy * width + sx] as f32;
            }
        }
        Self { size, pixels: out }
    }

    /// Multiplies every pixel so that the mean is `mean_dn` (an illumination change; a
    /// black canvas stays black).
    pub fn scale_mean(&mut self, mean_dn: f64) {
        let mean = self.pixels.iter().map(|&p| p as f64).sum::<f64>() / self.pixels.len() as f64;
        if mean > 0.0 {
            let gain = (mean_dn / mean) as f32;
            self.pixels.iter_mut().for_each(|p| *p *= gain);
        }
    }

    /// Bilinear sample at (column `x`, row `y`) with periodic wrap.
    ///
    /// The hot loop of rendering a scene (two thirds of `simulate --scene` time when it
    /// called libm's `fmod` and `floor` and divided twice per coordinate). The same value
    /// to the bit is now had without them: see [`wrap`] and [`Self::sample_reference`].
    #[inline]
    pub fn sample(&self, x: f64, y: f64) -> f32 {
        let n = self.size as f64;
        let (x, y) = (wrap(x, n, self.size), wrap(y, n, self.size));
        // x, y in [0, n]: the floor is the truncation; n itself (a rounding of a tiny
        // negative coordinate up to n) wraps to 0
        let (i0, j0) = (x as usize, y as usize);
        let (fx, fy) = ((x - i0 as f64) as f32, (y - j0 as f64) as f32);
        let next = |i: usize| {
            if i + 1 >= self.size {
                i + 1 - self.size
            } else {
                i + 1
            }
        };
        let (i0, j0) = (
            if i0 >= self.size { i0 - self.size } else { i0 },
            if j0 >= self.size { j0 - self.size } else { j0 },
        );
        let (i1, j1) = (next(i0), next(j0));
        let p = |i: usize, j: usize| self.pixels[j * self.size + i];
        let top = p(i0, j0) + (p(i1, j0) - p(i0, j0)) * fx;
        let bottom = p(i0, j1) + (p(i1, j1) - p(i0, j1)) * fx;
        top + (bottom - top) * fy
    }

    /// `out[k] = self.sample(xs[k], ys[k])` for every `k`, to the bit: the hot loop of
    /// rendering a scene, a row at a time. With an AVX2 CPU the wrap and split of the
    /// coordinates into cell and fraction run vectorised over blocks of [`BLOCK`] points
    /// ([`cells`]), then the four neighbours are read and blended; without AVX2 (or on a
    /// canvas over 2^15 px a side) each point is [`Self::sample`]d.
    pub fn sample_many(&self, xs: &[f64], ys: &[f64], out: &mut [f32]) {
        assert!(xs.len() == out.len() && ys.len() == out.len());
        // a NaN or a coordinate past 4e15 (see `wrap`) fails the comparison
        let in_range = |c: &[f64]| c.iter().fold(true, |ok, v| ok & (v.abs() < 4.0e15));
        // offsets into the canvas are u32: up to 2^15 a side
        let vectorised = self.size <= 1 << 15 && use_avx2();
        if !(vectorised && in_range(xs) && in_range(ys)) {
            for ((o, &x), &y) in out.iter_mut().zip(xs).zip(ys) {
                *o = self.sample(x, y);
            }
            return;
        }
        let (mut column, mut row) = (Cells::new(), Cells::new());
        for ((xs, ys), out) in xs
            .chunks(BLOCK)
            .zip(ys.chunks(BLOCK))
            .zip(out.chunks_mut(BLOCK))
        {
            // SAFETY: use_avx2() is true, so the CPU has AVX2; the canvas is up to 2^15 px a
            // side and every coordinate is finite and within 4e15 (checked above).
            // The cells are then within the canvas for blend.
            unsafe {
                cells(xs, self.size, 1, &mut column);
                cells(ys, self.size, self.size, &mut row);
                self.blend(&column, &row, out);
            }
        }
    }

    /// The bilinear blend of [`Self::sample`] at points already split into cells.
    ///
    /// # Safety
    /// The first `out.len()` cells of `column` and `row` are [`cells`] of this canvas (with
    /// strides 1 and `size`): every offset is then within the canvas (a column below
    /// `size` plus a row below `size` times `size`), so the reads are not checked.
    #[inline]
    unsafe fn blend(&self, column: &Cells, row: &Cells, out: &mut [f32]) {
        let p = &self.pixels;
        debug_assert!(out.len() <= BLOCK);
        // SAFETY: the offsets are within the canvas (the contract above)
        let at = |offset: u32| unsafe { *p.get_unchecked(offset as usize) };
        for (k, o) in out.iter_mut().enumerate() {
            let (i0, i1, fx) = (column.c0[k], column.c1[k], column.f[k]);
            let (j0, j1, fy) = (row.c0[k], row.c1[k], row.f[k]);
            debug_assert!(j1.max(j0) as usize + (i1.max(i0) as usize) < p.len());
            let (p00, p10) = (at(j0 + i0), at(j0 + i1));
            let (p01, p11) = (at(j1 + i0), at(j1 + i1));
            let top = p00 + (p10 - p00) * fx;
            let bottom = p01 + (p11 - p01) * fx;
            *o = top + (bottom - top) * fy;
        }
    }

    /// [`Self::sample`] as first written (`rem_euclid`, `floor`, `%`): the reference its
    /// tests compare with.
    #[cfg(test)]
    pub fn sample_reference(&self, x: f64, y: f64) -> f32 {
        let n = self.size as f64;
        let (x, y) = (x.rem_euclid(n), y.rem_euclid(n));
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let (i0, j0) = (x0 as usize % self.size, y0 as usize % self.size);
        let (i1, j1) = ((i0 + 1) % self.size, (j0 + 1) % self.size);
        let p = |i: usize, j: usize| self.pixels[j * self.size + i];
        let top = p(i0, j0) + (p(i1, j0) - p(i0, j0)) * fx;
        let bottom = p(i0, j1) + (p(i1, j1) - p(i0, j1)) * fx;
        top + (bottom - top) * fy
    }
}

/// `x.rem_euclid(n)` to the bit, without libm's `fmod` where `n` (= `size`) is a power of
/// two: `x / n` is then exact, so `k = floor(x / n)` is the exact quotient, and
/// `x - n k` is exact too (Sterbenz: for `k >= 1`, `x / 2 <= n k <= x`; for `k <= -2` every
/// value involved is a multiple of `x`'s unit in the last place and below `2 |x|`), which is
/// what `fmod` followed by `+ n` gives; for `k = -1` both compute the same rounded `x + n`.
/// The floor of a value within `i64` is its truncation, less one where that rounded up.
#[inline]
fn wrap(x: f64, n: f64, size: usize) -> f64 {
    // NaN and values past 4e15 (where the cast could saturate) take the reference path
    if !size.is_power_of_two() || x.is_nan() || x.abs() >= 4.0e15 {
        return x.rem_euclid(n);
    }
    let q = x / n;
    let t = q as i64 as f64;
    let k = if t > q { t - 1.0 } else { t };
    x - n * k
}

/// Points of [`Canvas::sample_many`] taken at a time (small enough to stay in L1 beside the
/// canvas rows they read).
const BLOCK: usize = 64;

/// Coordinates of up to [`BLOCK`] points split into cells: the offsets of the two
/// neighbouring columns (or rows) in the canvas and the fraction between them.
struct Cells {
    c0: [u32; BLOCK],
    c1: [u32; BLOCK],
    f: [f32; BLOCK],
}

impl Cells {
    fn new() -> Self {
        Self {
            c0: [0; BLOCK],
            c1: [0; BLOCK],
            f: [0.0; BLOCK],
        }
    }
}

/// The cells of `coords` on a canvas of `size`, offsets scaled by `stride`: the wrap and
/// split of [`Canvas::sample`] on four lanes, without libm's `fmod`.
///
/// The wrap is `r = x - n k` with `k = floor(x / n)` (`+ 0`, so never `-0`, as in [`wrap`]),
/// then `r + n` where `r < 0`. For a power of two it is [`wrap`] (`x / n` exact, `r >= 0`).
/// For any `n` up to 2^15 and `|x| < 2^52` it is `x.rem_euclid(n)` (up to the sign of a
/// zero, which the blend cannot see): with `F = floor(x / n)` exactly, the rounded
/// quotient's floor `k` is `F` or `F + 1` (rounding is monotone and `F` representable), `n k`
/// is an exact integer, and `x - n F` (`x >= 0`, the remainder) and `x - n (F + 1)` (`x`'s
/// `fmod` when `x < 0`, or minus the remainder's complement) are exact; `x - n F` for `x < 0`
/// is the rounded `fmod + n` of `rem_euclid` itself, and `fmod + n` from `k = F + 1` is the
/// same operation.
///
/// # Safety
/// The CPU must have AVX2; `size` must be at most 2^15 and every coordinate finite and
/// smaller than 4e15 in magnitude (so the wrapped value is in `[0, size]`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn cells(coords: &[f64], size: usize, stride: usize, out: &mut Cells) {
    // SAFETY: the caller's contract
    if size.is_power_of_two() {
        unsafe { cells_with::<true>(coords, size, stride, out) }
    } else {
        unsafe { cells_with::<false>(coords, size, stride, out) }
    }
}

/// [`cells`]; with `POW2` (`size` a power of two) `x / n` is taken as `x * (1 / n)`: `1 / n`
/// is exact, so both are the rounding of the same real number, the same bits, without a
/// division per point.
///
/// With `POW2` three more steps are shorter, with the same results (about a fifth of the
/// time of a sample). The wrapped `r = x - n k` is never below 0 (exact for `k != -1`, and
/// for `k = -1` the rounded `x + n` of `x` in `[-n, 0)`, at least 0; see [`wrap`]), so the
/// `+ n` below zero is left out. The cell `i` is in `[0, n]`, and `i & (n - 1)` is `i`
/// below `n` and 0 at `n`, which is `if i >= n { i - n }`; likewise `(i + 1) & (n - 1)` for
/// the next cell of an `i` below `n`. The stride is 1 or `n`, a power of two, so the
/// product is a shift by its trailing zeros.
///
/// # Safety
/// As [`cells`].
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn cells_with<const POW2: bool>(
    coords: &[f64],
    size: usize,
    stride: usize,
    out: &mut Cells,
) {
    let n = size as f64;
    let inverse = 1.0 / n;
    let (size, stride) = (size as u32, stride as u32);
    let (mask, shift) = (size.wrapping_sub(1), stride.trailing_zeros());
    let lanes = out.c0.iter_mut().zip(&mut out.c1).zip(&mut out.f);
    for (((c0, c1), f), &x) in lanes.zip(coords) {
        let quotient = if POW2 { x * inverse } else { x / n };
        let x = x - n * (quotient.floor() + 0.0);
        let x = if !POW2 && x < 0.0 { x + n } else { x };
        // SAFETY: x is in [0, n], n <= 2^15 (the caller's contract)
        let i = unsafe { x.to_int_unchecked::<i32>() } as u32;
        *f = (x - i as f64) as f32;
        if POW2 {
            (*c0, *c1) = ((i & mask) << shift, ((i + 1) & mask) << shift);
        } else {
            let i = if i >= size { i - size } else { i };
            let next = if i + 1 >= size { i + 1 - size } else { i + 1 };
            (*c0, *c1) = (i * stride, next * stride);
        }
    }
}

#[cfg(not(target_arch = "x86_64"))]
unsafe fn cells(_: &[f64], _: usize, _: usize, _: &mut Cells) {
    unreachable!("sample_many takes this path only with AVX2")
}

/// Whether [`Canvas::sample_many`] takes its vectorised path: when the CPU has AVX2, unless
/// `CTCAL_SIMD=scalar` asks for the portable path (as the simulator's pixel pass does).
pub(super) use crate::sim::simd::use_avx2;

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn texture_has_the_requested_log_statistics_and_range() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(1);
        let params = TextureParams {
            canvas_px: 128,
            ..Default::default()
        };
        let c = Canvas::generate(&params, &mut rng);
        let logs: Vec<f64> = c.pixels.iter().map(|&p| (p as f64).ln()).collect();
        let mean = logs.iter().sum::<f64>() / logs.len() as f64;
        let sd = (logs.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / logs.len() as f64).sqrt();
        assert!((mean - 90f64.ln()).abs() < 0.05, "{mean}");
        assert!((sd - 0.45).abs() < 0.05, "{sd}");
        assert!(c.pixels.iter().all(|&p| (24.99..=235.01).contains(&p)));
    }

    #[test]
    fn scaling_the_mean_is_an_illumination_change() {
        let mut c = Canvas::from_image(2, 2, &[10, 20, 30, 40]);
        c.scale_mean(50.0);
        assert_eq!(c.pixels, vec![20.0, 40.0, 60.0, 80.0]);
    }

    /// A random canvas of `size` and 20,000 random points on it, with its edges: multiples
    /// of the size, just below and above them, tiny negatives, -0.
    fn canvas_and_points(size: usize, seed: u64) -> (Canvas, Vec<(f64, f64)>) {
        use rand::RngExt;
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
        let c = Canvas {
            size,
            pixels: (0..size * size)
                .map(|_| rng.random_range(0.0..255.0))
                .collect(),
        };
        let n = size as f64;
        let mut points: Vec<(f64, f64)> = (0..20_000)
            .map(|_| {
                (
                    rng.random_range(-5e4..5e4),
                    rng.random_range(-3.0 * n..3.0 * n),
                )
            })
            .collect();
        for k in -3..=3 {
            let e = k as f64 * n;
            for d in [0.0, 1e-300, -1e-300, 1e-17, -1e-17, 1e-9, -1e-9, 0.5, -0.5] {
                points.push((e + d, -(e + d)));
                points.push((f64::from_bits((e + d).to_bits() + 1), e - d));
            }
        }
        points.push((-0.0, -0.0));
        points.push((-1e-20, 3.0 * n - 1e-13));
        // far from the origin, up to the fast wrap's limit (4e15), then past it
        for _ in 0..2_000 {
            let far = rng.random_range(-3.99e15..3.99e15);
            points.push((far, -far / 3.0));
        }
        points.extend([(4.1e15, 1.0), (1.0, -4.1e15), (-1e300, 1e300)]);
        (c, points)
    }

    #[test]
    fn sampling_is_the_reference_to_the_bit() {
        for size in [8usize, 64, 100, 256] {
            let (c, points) = canvas_and_points(size, 3 + size as u64);
            for (x, y) in points {
                let (a, b) = (c.sample(x, y), c.sample_reference(x, y));
                assert_eq!(a.to_bits(), b.to_bits(), "size {size} at ({x:e}, {y:e})");
            }
        }
    }

    #[test]
    fn sampling_many_is_the_reference_to_the_bit() {
        for size in [8usize, 64, 100, 128, 256, 384, 512] {
            let (c, points) = canvas_and_points(size, 5 + size as u64);
            let (xs, ys): (Vec<f64>, Vec<f64>) = points.iter().copied().unzip();
            let mut out = vec![0f32; points.len()];
            // whole, and in odd-length pieces (blocks that do not fill)
            c.sample_many(&xs, &ys, &mut out);
            let mut pieces = vec![0f32; points.len()];
            for ((x, y), o) in xs.chunks(77).zip(ys.chunks(77)).zip(pieces.chunks_mut(77)) {
                c.sample_many(x, y, o);
            }
            for (k, (x, y)) in points.into_iter().enumerate() {
                let b = c.sample_reference(x, y).to_bits();
                assert_eq!(out[k].to_bits(), b, "size {size} at ({x:e}, {y:e})");
                assert_eq!(pieces[k].to_bits(), b, "size {size} at ({x:e}, {y:e})");
            }
        }
    }

    /// The shortcuts of `cells_with::<true>` (no `+ n` below zero, a mask for the wrap, a
    /// shift for the stride) against the general path `cells_with::<false>` (which takes
    /// `x / n` as a division, the same bits on a power of two): the same cells and
    /// fractions to the bit on random, edge and far coordinates.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn cells_of_a_power_of_two_are_the_general_cells_to_the_bit() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        for size in [8usize, 64, 128, 256, 512, 1 << 15] {
            let (_, points) = canvas_and_points(size.min(512), 11 + size as u64);
            let n = size as f64;
            let mut coords: Vec<f64> = points.iter().flat_map(|&(x, y)| [x, y]).collect();
            // past 4e15 is not the fast path's: the edges of a canvas of this size instead
            coords.retain(|c| c.abs() < 4.0e15);
            for k in -4..=4 {
                let e = k as f64 * n;
                for d in [
                    0.0, -0.0, 1e-300, -1e-300, 1e-13, -1e-13, 0.5, -0.5, 1.0, -1.0,
                ] {
                    coords.push(e + d);
                }
                coords.push(f64::from_bits((e - 1.0).to_bits() + 1));
            }
            for stride in [1, size] {
                let (mut fast, mut general) = (Cells::new(), Cells::new());
                for block in coords.chunks(BLOCK) {
                    // SAFETY: AVX2 (checked above), a canvas up to 2^15, every coordinate
                    // finite and within 4e15
                    unsafe {
                        cells_with::<true>(block, size, stride, &mut fast);
                        cells_with::<false>(block, size, stride, &mut general);
                    }
                    for (k, x) in block.iter().enumerate() {
                        let at = format!("size {size} stride {stride} at {x:e}");
                        assert_eq!(fast.c0[k], general.c0[k], "{at}");
                        assert_eq!(fast.c1[k], general.c1[k], "{at}");
                        assert_eq!(fast.f[k].to_bits(), general.f[k].to_bits(), "{at}");
                    }
                }
            }
        }
    }

    #[test]
    fn sampling_wraps_and_interpolates() {
        let c = Canvas {
            size: 2,
            pixels: vec![0.0, 10.0, 20.0, 30.0],
        };
        assert_eq!(c.sample(0.0, 0.0), 0.0);
        assert_eq!(c.sample(0.5, 0.0), 5.0);
        assert_eq!(c.sample(0.5, 0.5), 15.0);
        assert_eq!(c.sample(2.0, 2.0), 0.0);
        assert_eq!(c.sample(-1.0, 0.0), 10.0);
        assert_eq!(c.sample(1.5, 0.0), 5.0);
    }
}
