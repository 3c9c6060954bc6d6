//! A textured plane translating and rotating in front of the camera (the oracle's
//! "texture" scenes): frame pixel (x, y) at time t samples the canvas at
//! `X = c0 + offset_x + vx t + cos(th) u - sin(th) v`, `Y = c0 + offset_y + vy t + sin(th) u +
//! cos(th) v`, with `u = x - (W-1)/2`, `v = y - (H-1)/2`, `th = omega t` and `c0` the canvas
//! centre; brightness may be modulated globally by `exp(mod_amp_ln * sin(2 pi mod_hz t))`.
//! The canvas is procedural ([`TextureParams`]) or, with `image`, a grey photograph, scaled
//! by `image_mean_dn` as a brighter or dimmer illumination would scale it.

use super::canvas::{Canvas, TextureParams};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Parameters of the texture scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TextureScene {
    #[serde(flatten)]
    pub texture: TextureParams,
    #[serde(default)]
    pub vx_px_s: f64,
    #[serde(default)]
    pub vy_px_s: f64,
    #[serde(default)]
    pub omega_deg_s: f64,
    #[serde(default)]
    pub offset_px: [f64; 2],
    /// Global brightness modulation amplitude (log units) and frequency.
    #[serde(default)]
    pub mod_amp_ln: f64,
    #[serde(default)]
    pub mod_hz: f64,
    /// A grey PNG to use as the canvas instead of a procedural texture (a relative path is
    /// relative to the scene file); the procedural keys are then ignored.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image: Option<PathBuf>,
    /// With `image`: scale the image so that its mean is this many camera DN (absent: the
    /// image's own 8-bit values).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image_mean_dn: Option<f64>,
}

impl TextureScene {
    /// The canvas: the image (scaled to `image_mean_dn`) or a procedural texture.
    pub fn canvas(&self, rng: &mut impl rand::Rng) -> Result<Canvas, crate::sim::SimError> {
        let Some(path) = &self.image else {
            return Ok(Canvas::generate(&self.texture, rng));
        };
        let mut canvas = super::load_texture(path)?;
        if let Some(mean_dn) = self.image_mean_dn {
            canvas.scale_mean(mean_dn);
        }
        Ok(canvas)
    }

    /// Fastest image motion, px/s (for choosing a render rate).
    pub fn max_speed_px_s(&self, width: usize, height: usize) -> f64 {
        let radius = (width as f64).hypot(height as f64) / 2.0;
        self.vx_px_s.hypot(self.vy_px_s) + self.omega_deg_s.abs().to_radians() * radius
    }

    /// Renders rows `rows` into `out` (those rows only).
    pub fn render(
        &self,
        canvas: &Canvas,
        width: usize,
        height: usize,
        rows: std::ops::Range<usize>,
        t: f64,
        out: &mut [f32],
    ) {
        let th = self.omega_deg_s.to_radians() * t;
        let (s, c) = th.sin_cos();
        let c0 = canvas.size as f64 / 2.0;
        let (ox, oy) = (
            c0 + self.offset_px[0] + self.vx_px_s * t,
            c0 + self.offset_px[1] + self.vy_px_s * t,
        );
        let gain = (self.mod_amp_ln * (std::f64::consts::TAU * self.mod_hz * t).sin()).exp() as f32;
        let (cx, cy) = ((width as f64 - 1.0) / 2.0, (height as f64 - 1.0) / 2.0);
        // a row's coordinates first (the same expressions, so the same bits), then the canvas
        // sampled along it at once
        let (mut xs, mut ys) = (vec![0f64; width], vec![0f64; width]);
        for (y, out) in rows.zip(out.chunks_exact_mut(width)) {
            let v = y as f64 - cy;
            for (x, (px, py)) in xs.iter_mut().zip(&mut ys).enumerate() {
                let u = x as f64 - cx;
                (*px, *py) = (ox + c * u - s * v, oy + s * u + c * v);
            }
            canvas.sample_many(&xs, &ys, out);
            for value in out {
                *value = (*value * gain).clamp(0.0, 255.0);
            }
        }
    }
}
