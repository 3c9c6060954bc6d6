//! A display between scene and camera, for on-screen calibration (Stoffregen et al. 2020,
//! method 3): what the camera sees of a monitor is not the stimulus' pixel values.
//!
//! - luminance: `L = black + (1 - black) * (DN / 255)^gamma`, relative to full white (a
//!   gamma-encoded display with a non-zero black level);
//! - camera DN: `white_dn * L` (the exposure puts full white at `white_dn`);
//! - optics: a Gaussian blur of `blur_px` (sigma, pixels), kernel radius `ceil(3 sigma)`,
//!   borders reflected without repeating the edge pixel (OpenCV's BORDER_REFLECT_101);
//! - time: sample and hold at `refresh_hz` (no LCD response time or PWM flicker), see
//!   [`super::source::DisplaySource`].
//!
//! Screen pixels map 1:1 onto sensor pixels, unless a [`super::screen_geometry`] warp puts the
//! screen at an angle.

use super::params::DisplayParams;
#[cfg(target_arch = "x86_64")]
use super::simd::use_avx2;

/// The display transform with its blur kernel precomputed.
#[derive(Clone, Debug)]
pub struct DisplayModel {
    params: DisplayParams,
    kernel: Vec<f32>,
    lut: Vec<f32>,
}

fn reflect_101(i: isize, n: usize) -> usize {
    let n = n as isize;
    if n == 1 {
        return 0;
    }
    let period = 2 * (n - 1);
    let mut i = i.rem_euclid(period);
    if i >= n {
        i = period - i;
    }
    i as usize
}

/// The table index of a screen DN: the DN truncated where it lies in 0..=255, else 0 (NaN
/// too); the DN is whole and in the table exactly when the index converts back to it.
#[inline(always)]
fn table_index(dn: f32) -> u8 {
    let inside = if (0.0..=255.0).contains(&dn) { dn } else { 0.0 };
    inside as u8
}

impl DisplayModel {
    pub fn new(params: &DisplayParams) -> Self {
        let sigma = params.blur_px.unwrap_or(0.0);
        let kernel = if sigma > 0.0 {
            let radius = (3.0 * sigma).ceil() as isize;
            let raw: Vec<f64> = (-radius..=radius)
                .map(|i| (-(i as f64).powi(2) / (2.0 * sigma * sigma)).exp())
                .collect();
            let sum: f64 = raw.iter().sum();
            raw.iter().map(|v| (v / sum) as f32).collect()
        } else {
            vec![1.0]
        };
        let lut = (0..256)
            .map(|dn| {
                let l = params.black_level
                    + (1.0 - params.black_level) * (dn as f64 / 255.0).powf(params.gamma);
                (params.white_dn * l) as f32
            })
            .collect();
        Self {
            params: params.clone(),
            kernel,
            lut,
        }
    }

    pub fn params(&self) -> &DisplayParams {
        &self.params
    }

    /// Camera DN of one screen DN value (before blur).
    pub fn luminance_dn(&self, screen_dn: f32) -> f32 {
        let p = &self.params;
        let l = p.black_level
            + (1.0 - p.black_level) * (screen_dn.clamp(0.0, 255.0) as f64 / 255.0).powf(p.gamma);
        (p.white_dn * l) as f32
    }

    /// Camera DN of one screen DN before blur, as [`Self::lit`] gives it (the same bits):
    /// whole DN from the table, any other value computed.
    #[inline(always)]
    pub fn lit_value(&self, screen_dn: f32) -> f32 {
        let index = table_index(screen_dn);
        if index as f32 == screen_dn {
            self.lut[index as usize]
        } else {
            self.luminance_dn(screen_dn)
        }
    }

    /// Camera DN of a screen frame (W x H), blurred.
    pub fn camera_dn(&self, screen: &[f32], width: usize, height: usize) -> Vec<f32> {
        self.blur(self.lit(screen), width, height)
    }

    /// Camera DN of each screen pixel, before the optics (for a screen seen at an angle,
    /// [`super::screen_geometry`] resamples these onto the sensor before [`Self::blur`]).
    pub fn lit(&self, screen: &[f32]) -> Vec<f32> {
        #[cfg(target_arch = "x86_64")]
        if use_avx2() {
            // SAFETY: use_avx2() is true only when the CPU has AVX2.
            return unsafe { self.lit_avx2(screen) };
        }
        self.lit_portable(screen)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn lit_avx2(&self, screen: &[f32]) -> Vec<f32> {
        self.lit_portable(screen)
    }

    /// Whole screen DN (every 8-bit stimulus) are read from the table in a loop without
    /// branches or calls, which the compiler vectorises (each simulation through the
    /// display lights every stimulus frame: a tenth of `estimate screen` when the loop
    /// branched per pixel); any other value is computed after, as [`Self::luminance_dn`].
    #[inline(always)]
    fn lit_portable(&self, screen: &[f32]) -> Vec<f32> {
        let lut: &[f32; 256] = self.lut[..].try_into().expect("256 entries");
        let mut out = vec![0f32; screen.len()];
        let mut all_whole = true;
        for (o, &dn) in out.iter_mut().zip(screen) {
            let index = table_index(dn);
            *o = lut[index as usize];
            all_whole &= index as f32 == dn;
        }
        if !all_whole {
            for (o, &dn) in out.iter_mut().zip(screen) {
                if table_index(dn) as f32 != dn {
                    *o = self.luminance_dn(dn);
                }
            }
        }
        out
    }

    /// The optical blur of a camera-DN image (W x H).
    pub fn blur(&self, lit: Vec<f32>, width: usize, height: usize) -> Vec<f32> {
        if self.kernel.len() == 1 {
            return lit;
        }
        #[cfg(target_arch = "x86_64")]
        if use_avx2() {
            // SAFETY: use_avx2() is true only when the CPU has AVX2.
            return unsafe { self.blur_avx2(&lit, width, height) };
        }
        self.blur_portable(&lit, width, height)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn blur_avx2(&self, lit: &[f32], width: usize, height: usize) -> Vec<f32> {
        self.blur_portable(lit, width, height)
    }

    /// Separable: along rows, then across rows; both passes run over contiguous rows (and
    /// are inlined into the AVX2 copy: [`super::simd`]).
    #[inline(always)]
    fn blur_portable(&self, lit: &[f32], width: usize, height: usize) -> Vec<f32> {
        self.blur_columns(&self.blur_rows(lit, width, height), width, height)
    }

    /// The blur along each row (interior samples read directly, only the border reflects).
    /// The interior is summed tap by tap over whole row slices (which the compiler
    /// vectorises); each sample's terms are added in the kernel's order, as at the border.
    #[inline(always)]
    fn blur_rows(&self, input: &[f32], width: usize, height: usize) -> Vec<f32> {
        let radius = self.kernel.len() / 2;
        let mut out = vec![0f32; input.len()];
        // the samples whose whole kernel lies inside the row (none on a row narrower than it)
        let interior = radius..width.saturating_sub(radius).max(radius);
        for y in 0..height {
            let row = &input[y * width..(y + 1) * width];
            let target = &mut out[y * width..(y + 1) * width];
            for (k, &w) in self
                .kernel
                .iter()
                .enumerate()
                .filter(|_| !interior.is_empty())
            {
                let source = &row[interior.start - radius + k..interior.end - radius + k];
                for (o, &v) in target[interior.clone()].iter_mut().zip(source) {
                    *o += w * v;
                }
            }
            for i in (0..width).filter(|i| !interior.contains(i)) {
                let mut acc = 0.0;
                for (k, w) in self.kernel.iter().enumerate() {
                    acc += w * row[reflect_101(i as isize + k as isize - radius as isize, width)];
                }
                target[i] = acc;
            }
        }
        out
    }

    /// The blur across rows: each output row is the weighted sum of whole input rows.
    #[inline(always)]
    fn blur_columns(&self, input: &[f32], width: usize, height: usize) -> Vec<f32> {
        let radius = self.kernel.len() / 2;
        let mut out = vec![0f32; input.len()];
        for y in 0..height {
            let target = &mut out[y * width..(y + 1) * width];
            for (k, &w) in self.kernel.iter().enumerate() {
                let source = reflect_101(y as isize + k as isize - radius as isize, height);
                let row = &input[source * width..(source + 1) * width];
                for (o, &v) in target.iter_mut().zip(row) {
                    *o += w * v;
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The oracle's display (calib/screens/lcd_75hz_gamma2.toml).
    fn params() -> DisplayParams {
        DisplayParams::from_toml(
            include_str!("../../../../calib/screens/lcd_75hz_gamma2.toml"),
            "lcd_75hz_gamma2.toml",
        )
        .unwrap()
    }

    /// Whole DN from the table, anything else computed: the values the per-pixel branch
    /// gave, on whole, fractional, negative, too large and NaN screen DN.
    #[test]
    fn lit_reads_whole_dn_from_the_table_and_computes_the_rest() {
        let d = DisplayModel::new(&params());
        let screen = [
            0.0,
            -0.0,
            1.0,
            128.0,
            254.0,
            255.0,
            0.5,
            127.25,
            -0.5,
            -3.0,
            255.5,
            256.0,
            1e9,
            f32::NAN,
        ];
        let expected: Vec<f32> = screen
            .iter()
            .map(|&dn| {
                let index = dn as usize;
                if index < 256 && index as f32 == dn {
                    d.lut[index]
                } else {
                    d.luminance_dn(dn)
                }
            })
            .collect();
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&d.lit(&screen)), bits(&expected));
        assert_eq!(bits(&d.lit_portable(&screen)), bits(&expected));
        let whole: Vec<f32> = (0..256).map(|v| v as f32).collect();
        assert_eq!(bits(&d.lit(&whole)), bits(&d.lut));
    }

    #[test]
    fn luminance_follows_gamma_and_black_level() {
        let d = DisplayModel::new(&params());
        assert!((d.luminance_dn(0.0) - 1.0).abs() < 1e-6); // 200 * 0.005
        assert!((d.luminance_dn(255.0) - 200.0).abs() < 1e-4);
        let half = 200.0 * (0.005 + 0.995 * (128.0f64 / 255.0).powi(2));
        assert!((d.luminance_dn(128.0) as f64 - half).abs() < 1e-4);
    }

    /// The row pass sums each sample's taps in the kernel's order, interior and border
    /// alike: the same floats as a sample-by-sample sum, on rows wider and narrower than the
    /// kernel (7 taps).
    #[test]
    fn the_row_blur_is_the_sample_by_sample_sum() {
        let d = DisplayModel::new(&params());
        let radius = d.kernel.len() / 2;
        for width in [1usize, 3, 6, 7, 8, 40] {
            let input: Vec<f32> = (0..width * 2)
                .map(|i| ((i * 37) % 101) as f32 * 0.7)
                .collect();
            let rows = d.blur_rows(&input, width, 2);
            for y in 0..2 {
                for i in 0..width {
                    let mut acc = 0.0f32;
                    for (k, w) in d.kernel.iter().enumerate() {
                        let x = reflect_101(i as isize + k as isize - radius as isize, width);
                        acc += w * input[y * width + x];
                    }
                    assert_eq!(
                        rows[y * width + i].to_bits(),
                        acc.to_bits(),
                        "{width} {y} {i}"
                    );
                }
            }
        }
    }

    #[test]
    fn blur_kernel_matches_opencv_for_sigma_0_8() {
        let d = DisplayModel::new(&params());
        let expected = [0.000_440_743, 0.021_910_314, 0.228_310_716, 0.498_676_452];
        assert_eq!(d.kernel.len(), 7);
        for (k, e) in expected.iter().enumerate() {
            assert!((d.kernel[k] - *e as f32).abs() < 1e-7);
            assert!((d.kernel[6 - k] - *e as f32).abs() < 1e-7);
        }
    }

    #[test]
    fn blur_of_a_point_is_the_kernel_in_both_directions() {
        let d = DisplayModel::new(&params());
        // a single lit pixel at (5, 4) of a 11x9 black screen, after subtracting black
        let mut screen = vec![0.0f32; 11 * 9];
        screen[4 * 11 + 5] = 255.0;
        let camera = d.camera_dn(&screen, 11, 9);
        let black = d.luminance_dn(0.0);
        let peak = d.luminance_dn(255.0) - black;
        for (dy, wy) in d.kernel.iter().enumerate() {
            for (dx, wx) in d.kernel.iter().enumerate() {
                let (x, y) = (5 + dx - 3, 4 + dy - 3);
                let expected = black + peak * wx * wy;
                assert!((camera[y * 11 + x] - expected).abs() < 1e-4, "({x}, {y})");
            }
        }
    }

    #[test]
    fn blur_preserves_a_flat_field_and_reflects_at_borders() {
        let d = DisplayModel::new(&params());
        let out = d.camera_dn(&[255.0; 12], 4, 3);
        assert!(out.iter().all(|&v| (v - 200.0).abs() < 1e-3));
        assert_eq!(reflect_101(-1, 5), 1);
        assert_eq!(reflect_101(5, 5), 3);
        assert_eq!(reflect_101(0, 1), 0);
    }
}
