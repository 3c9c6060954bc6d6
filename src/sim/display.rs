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
//! Screen pixels map 1:1 onto sensor pixels.

use super::params::DisplayParams;

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

    /// Camera DN of a screen frame (W x H), blurred.
    pub fn camera_dn(&self, screen: &[f32], width: usize, height: usize) -> Vec<f32> {
        let lit: Vec<f32> = screen
            .iter()
            .map(|&dn| {
                if dn.fract() == 0.0 && (0.0..=255.0).contains(&dn) {
                    self.lut[dn as usize]
                } else {
                    self.luminance_dn(dn)
                }
            })
            .collect();
        if self.kernel.len() == 1 {
            return lit;
        }
        let radius = (self.kernel.len() / 2) as isize;
        let mut horizontal = vec![0f32; lit.len()];
        for y in 0..height {
            for x in 0..width {
                let mut acc = 0.0;
                for (k, w) in self.kernel.iter().enumerate() {
                    let sx = reflect_101(x as isize + k as isize - radius, width);
                    acc += w * lit[y * width + sx];
                }
                horizontal[y * width + x] = acc;
            }
        }
        let mut out = vec![0f32; lit.len()];
        for y in 0..height {
            for x in 0..width {
                let mut acc = 0.0;
                for (k, w) in self.kernel.iter().enumerate() {
                    let sy = reflect_101(y as isize + k as isize - radius, height);
                    acc += w * horizontal[sy * width + x];
                }
                out[y * width + x] = acc;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> DisplayParams {
        DisplayParams {
            refresh_hz: 75.0,
            gamma: 2.0,
            black_level: 0.005,
            white_dn: 200.0,
            blur_px: Some(0.8),
            time_offset_s: None,
        }
    }

    #[test]
    fn luminance_follows_gamma_and_black_level() {
        let d = DisplayModel::new(&params());
        assert!((d.luminance_dn(0.0) - 1.0).abs() < 1e-6); // 200 * 0.005
        assert!((d.luminance_dn(255.0) - 200.0).abs() < 1e-4);
        let half = 200.0 * (0.005 + 0.995 * (128.0f64 / 255.0).powi(2));
        assert!((d.luminance_dn(128.0) as f64 - half).abs() < 1e-4);
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
    fn blur_preserves_a_flat_field_and_reflects_at_borders() {
        let d = DisplayModel::new(&params());
        let out = d.camera_dn(&[255.0; 12], 4, 3);
        assert!(out.iter().all(|&v| (v - 200.0).abs() < 1e-3));
        assert_eq!(reflect_101(-1, 5), 1);
        assert_eq!(reflect_101(5, 5), 3);
        assert_eq!(reflect_101(0, 1), 0);
    }
}
