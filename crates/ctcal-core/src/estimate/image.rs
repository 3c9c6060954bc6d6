//! A small float image: bilinear sampling, separable Gaussian blur, 2x pyramid reduction
//! and central-difference gradients, the pieces optical flow and motion-compensated frame
//! interpolation are built from.

/// A single-channel image of `f32`, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl Image {
    pub fn new(width: usize, height: usize, data: Vec<f32>) -> Self {
        assert_eq!(data.len(), width * height, "image size");
        Self {
            width,
            height,
            data,
        }
    }

    pub fn filled(width: usize, height: usize, value: f32) -> Self {
        Self::new(width, height, vec![value; width * height])
    }

    /// An 8-bit frame's values.
    pub fn from_u8(width: usize, height: usize, pixels: &[u8]) -> Self {
        Self::new(width, height, pixels.iter().map(|&p| p as f32).collect())
    }

    #[inline(always)]
    pub fn at(&self, x: usize, y: usize) -> f32 {
        self.data[y * self.width + x]
    }

    /// Bilinear sample at (x, y), pixel centres at integers; coordinates outside the image
    /// are clamped to its border.
    #[inline]
    pub fn sample(&self, x: f32, y: f32) -> f32 {
        let max_x = (self.width - 1) as f32;
        let max_y = (self.height - 1) as f32;
        let x = x.clamp(0.0, max_x);
        let y = y.clamp(0.0, max_y);
        let (x0, y0) = (floor_non_negative(x), floor_non_negative(y));
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as usize, y0 as usize);
        let x1 = (x0 + 1).min(self.width - 1);
        let y1 = (y0 + 1).min(self.height - 1);
        let top = self.at(x0, y0) + (self.at(x1, y0) - self.at(x0, y0)) * fx;
        let bottom = self.at(x0, y1) + (self.at(x1, y1) - self.at(x0, y1)) * fx;
        top + (bottom - top) * fy
    }

    /// Bicubic (Catmull-Rom) sample at (x, y), borders clamped. Sharper than bilinear
    /// sampling, which at a half-pixel offset averages two pixels and so lowers the
    /// contrast of fine texture (and with it the events a simulation makes from it).
    /// Away from the border the four columns are one slice (no clamping per tap); the sums
    /// run in the same order either way, so the result is the same to the bit.
    #[inline]
    pub fn sample_cubic(&self, x: f32, y: f32) -> f32 {
        let max_x = (self.width - 1) as isize;
        let max_y = (self.height - 1) as isize;
        let x = x.clamp(0.0, max_x as f32);
        let y = y.clamp(0.0, max_y as f32);
        let (x0, y0) = (floor_non_negative(x), floor_non_negative(y));
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as isize, y0 as isize);
        let wx = catmull_rom(fx);
        let wy = catmull_rom(fy);
        let interior = x0 >= 1 && x0 + 2 <= max_x;
        let mut acc = 0.0;
        for (j, wyj) in wy.iter().enumerate() {
            let yy = (y0 + j as isize - 1).clamp(0, max_y) as usize;
            let row = &self.data[yy * self.width..(yy + 1) * self.width];
            let mut line = 0.0;
            if interior {
                let taps: &[f32; 4] = row[(x0 - 1) as usize..(x0 + 3) as usize]
                    .try_into()
                    .expect("four taps");
                for (wxi, v) in wx.iter().zip(taps) {
                    line += wxi * v;
                }
            } else {
                for (i, wxi) in wx.iter().enumerate() {
                    let xx = (x0 + i as isize - 1).clamp(0, max_x) as usize;
                    line += wxi * row[xx];
                }
            }
            acc += wyj * line;
        }
        acc
    }

    /// The image blurred by a Gaussian of standard deviation `sigma` pixels (separable,
    /// kernel radius `ceil(3 sigma)`, borders clamped).
    ///
    /// Each output is `sum_k w_k * v_k` added up in kernel order from 0.0, as a direct loop
    /// would; the loops run over the kernel outside and the pixels inside (on a row padded
    /// with its clamped border), so that the inner loop is a vectorised multiply-add over a
    /// row rather than a clamped gather per tap (a fifth of `estimate aps`).
    pub fn blurred(&self, sigma: f32) -> Image {
        if sigma <= 0.0 || self.data.is_empty() {
            return self.clone();
        }
        let radius = (3.0 * sigma).ceil() as usize;
        let mut kernel: Vec<f32> = (-(radius as isize)..=radius as isize)
            .map(|i| (-(i * i) as f32 / (2.0 * sigma * sigma)).exp())
            .collect();
        let sum: f32 = kernel.iter().sum();
        kernel.iter_mut().for_each(|k| *k /= sum);
        let (w, h) = (self.width, self.height);
        let mut rows = vec![0f32; self.data.len()];
        let mut padded = vec![0f32; w + 2 * radius];
        for (src, dst) in self.data.chunks_exact(w).zip(rows.chunks_exact_mut(w)) {
            for (i, p) in padded.iter_mut().enumerate() {
                *p = src[i.saturating_sub(radius).min(w - 1)];
            }
            for (k, &weight) in kernel.iter().enumerate() {
                for (d, &v) in dst.iter_mut().zip(&padded[k..k + w]) {
                    *d += weight * v;
                }
            }
        }
        let mut out = vec![0f32; self.data.len()];
        for (y, dst) in out.chunks_exact_mut(w).enumerate() {
            for (k, &weight) in kernel.iter().enumerate() {
                let yy = (y + k).saturating_sub(radius).min(h - 1);
                for (d, &v) in dst.iter_mut().zip(&rows[yy * w..(yy + 1) * w]) {
                    *d += weight * v;
                }
            }
        }
        Image::new(self.width, self.height, out)
    }

    /// Half the size: a binomial blur, then every second pixel (one pyramid level).
    pub fn reduced(&self) -> Image {
        let blurred = self.blurred(1.0);
        let (w, h) = (self.width.div_ceil(2), self.height.div_ceil(2));
        let mut data = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                data.push(blurred.at(2 * x, 2 * y));
            }
        }
        Image::new(w, h, data)
    }

    /// Central-difference gradients (one-sided at the border).
    pub fn gradients(&self) -> (Image, Image) {
        let (w, h) = (self.width, self.height);
        let mut gx = vec![0f32; w * h];
        let mut gy = vec![0f32; w * h];
        for y in 0..h {
            for x in 0..w {
                let (xl, xr) = (x.saturating_sub(1), (x + 1).min(w - 1));
                let (yu, yd) = (y.saturating_sub(1), (y + 1).min(h - 1));
                gx[y * w + x] = (self.at(xr, y) - self.at(xl, y)) / (xr - xl).max(1) as f32;
                gy[y * w + x] = (self.at(x, yd) - self.at(x, yu)) / (yd - yu).max(1) as f32;
            }
        }
        (Image::new(w, h, gx), Image::new(w, h, gy))
    }
}

/// `x.floor()` for a coordinate clamped to the image (`0 <= x < 2^24`, or NaN): the
/// truncating cast, an instruction, where `floor` is a call into libm on the baseline
/// x86-64 target (a tenth of the flow upsampling). At -0.0 it gives +0.0, so the fraction
/// `x - floor` is +0.0 instead of -0.0; interpolation weights of +-0.0 add nothing to a sum
/// either way. NaN becomes 0.0, as `floor`'s NaN did after the cast to an index; the
/// fraction stays NaN.
#[inline(always)]
fn floor_non_negative(x: f32) -> f32 {
    (x as i32) as f32
}

/// Catmull-Rom weights of the four samples around a point at fraction `t` past the second.
#[inline(always)]
fn catmull_rom(t: f32) -> [f32; 4] {
    let (t2, t3) = (t * t, t * t * t);
    [
        0.5 * (-t3 + 2.0 * t2 - t),
        0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
        0.5 * (-3.0 * t3 + 4.0 * t2 + t),
        0.5 * (t3 - t2),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_sampling_is_exact_on_a_plane() {
        let img = Image::new(
            4,
            3,
            (0..12)
                .map(|i| (i % 4) as f32 * 2.0 + (i / 4) as f32 * 10.0)
                .collect(),
        );
        assert!((img.sample(1.25, 0.5) - (2.5 + 5.0)).abs() < 1e-5);
        assert_eq!(img.sample(-3.0, 0.0), 0.0);
        assert_eq!(img.sample(9.0, 9.0), 26.0);
        // cubic sampling is exact on planes too (away from the clamped border), and at the
        // pixels themselves
        let plane = Image::new(
            8,
            8,
            (0..64)
                .map(|i| (i % 8) as f32 * 2.0 + (i / 8) as f32 * 10.0)
                .collect(),
        );
        assert!((plane.sample_cubic(3.25, 3.5) - (6.5 + 35.0)).abs() < 1e-4);
        assert_eq!(img.sample_cubic(2.0, 1.0), img.at(2, 1));
    }

    #[test]
    fn blur_keeps_a_flat_image_and_the_mean_of_a_spike() {
        let flat = Image::filled(9, 7, 3.0).blurred(1.5);
        assert!(flat.data.iter().all(|v| (v - 3.0).abs() < 1e-5));
        let mut spike = Image::filled(21, 21, 0.0);
        spike.data[10 * 21 + 10] = 1.0;
        let b = spike.blurred(1.5);
        assert!((b.data.iter().sum::<f32>() - 1.0).abs() < 1e-4);
        assert!(b.at(10, 10) < 0.1 && b.at(10, 10) > b.at(11, 10));
    }

    /// The direct loops `blurred` and `sample_cubic` replaced (one clamped tap at a time).
    fn reference_blur(img: &Image, sigma: f32) -> Vec<f32> {
        let radius = (3.0 * sigma).ceil() as isize;
        let mut kernel: Vec<f32> = (-radius..=radius)
            .map(|i| (-(i * i) as f32 / (2.0 * sigma * sigma)).exp())
            .collect();
        let sum: f32 = kernel.iter().sum();
        kernel.iter_mut().for_each(|k| *k /= sum);
        let (w, h) = (img.width as isize, img.height as isize);
        let pass = |data: &[f32], step: isize| -> Vec<f32> {
            let mut out = vec![0f32; data.len()];
            for y in 0..h {
                for x in 0..w {
                    let mut acc = 0.0;
                    for (k, weight) in kernel.iter().enumerate() {
                        let (xx, yy) = if step == 1 {
                            ((x + k as isize - radius).clamp(0, w - 1), y)
                        } else {
                            (x, (y + k as isize - radius).clamp(0, h - 1))
                        };
                        acc += weight * data[(yy * w + xx) as usize];
                    }
                    out[(y * w + x) as usize] = acc;
                }
            }
            out
        };
        pass(&pass(&img.data, 1), w)
    }

    fn reference_cubic(img: &Image, x: f32, y: f32) -> f32 {
        let (max_x, max_y) = ((img.width - 1) as isize, (img.height - 1) as isize);
        let (x, y) = (x.clamp(0.0, max_x as f32), y.clamp(0.0, max_y as f32));
        let (x0, y0) = (x.floor(), y.floor());
        let (wx, wy) = (catmull_rom(x - x0), catmull_rom(y - y0));
        let (x0, y0) = (x0 as isize, y0 as isize);
        let mut acc = 0.0;
        for (j, wyj) in wy.iter().enumerate() {
            let yy = (y0 + j as isize - 1).clamp(0, max_y) as usize;
            let mut line = 0.0;
            for (i, wxi) in wx.iter().enumerate() {
                let xx = (x0 + i as isize - 1).clamp(0, max_x) as usize;
                line += wxi * img.data[yy * img.width + xx];
            }
            acc += wyj * line;
        }
        acc
    }

    /// Bilinear sampling as it was written with `floor`.
    fn reference_bilinear(img: &Image, x: f32, y: f32) -> f32 {
        let (max_x, max_y) = ((img.width - 1) as f32, (img.height - 1) as f32);
        let (x, y) = (x.clamp(0.0, max_x), y.clamp(0.0, max_y));
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as usize, y0 as usize);
        let x1 = (x0 + 1).min(img.width - 1);
        let y1 = (y0 + 1).min(img.height - 1);
        let top = img.at(x0, y0) + (img.at(x1, y0) - img.at(x0, y0)) * fx;
        let bottom = img.at(x0, y1) + (img.at(x1, y1) - img.at(x0, y1)) * fx;
        top + (bottom - top) * fy
    }

    #[test]
    fn blur_and_cubic_sampling_match_the_direct_loops_to_the_bit() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        for (w, h) in [(1, 1), (3, 2), (17, 11), (64, 48)] {
            let img = Image::new(w, h, (0..w * h).map(|_| next() * 255.0).collect());
            for sigma in [0.5f32, 1.0, 1.7, 4.0] {
                let fast = img.blurred(sigma).data;
                let direct = reference_blur(&img, sigma);
                assert!(
                    fast.iter()
                        .zip(&direct)
                        .all(|(a, b)| a.to_bits() == b.to_bits())
                );
            }
            // random points, and the edge cases of the floor: signed zeros, whole pixels,
            // the last pixel, beyond the border
            let special = [-0.0f32, 0.0, 1.0, (w - 1) as f32, w as f32 + 7.5, -3.25];
            let points = (0..2_000)
                .map(|_| (next() * (w + 4) as f32 - 2.0, next() * (h + 4) as f32 - 2.0))
                .collect::<Vec<_>>()
                .into_iter()
                .chain(
                    special
                        .iter()
                        .flat_map(|&x| special.iter().map(move |&y| (x, y))),
                );
            for (x, y) in points {
                let (fast, direct) = (img.sample_cubic(x, y), reference_cubic(&img, x, y));
                assert_eq!(fast.to_bits(), direct.to_bits(), "{w}x{h} at ({x}, {y})");
                let bilinear = reference_bilinear(&img, x, y);
                assert_eq!(img.sample(x, y).to_bits(), bilinear.to_bits());
            }
        }
    }

    #[test]
    fn gradients_of_a_ramp() {
        let img = Image::new(
            5,
            4,
            (0..20)
                .map(|i| (i % 5) as f32 * 3.0 - (i / 5) as f32)
                .collect(),
        );
        let (gx, gy) = img.gradients();
        assert!(gx.data.iter().all(|&g| (g - 3.0).abs() < 1e-6));
        assert!(gy.data.iter().all(|&g| (g + 1.0).abs() < 1e-6));
        assert_eq!(img.reduced().width, 3);
    }
}
