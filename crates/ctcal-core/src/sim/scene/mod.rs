//! Procedural, deterministic scenes for the simulator, described by a TOML file
//! (`calib/scenes/`): a moving texture, a moving checkerboard, or multi-object 2D scenes,
//! with optional APS-like frames (frame rate and exposure time, so motion blurs).
//!
//! ```toml
//! kind = "texture"          # texture | checkerboard | multi_object
//! width = 240
//! height = 180
//! duration_s = 1.0
//! seed = 1
//! render_hz = 1000          # optional: default keeps motion under 0.5 px per frame
//! [aps]                     # optional
//! rate_hz = 25.0
//! exposure_s = 0.005
//! [texture]                 # the table named by `kind`
//! vx_px_s = 60.0
//! ```

pub mod aps;
pub mod canvas;
pub mod checkerboard;
pub mod multi_object;
pub mod stimulus;
pub mod texture;
mod validate;

use super::SimError;
use super::pixel::Transition;
use super::rng::{Stream, generator};
use super::source::{FrameSource, Sample};
use crate::events::TimeUs;
use canvas::Canvas;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SceneKind {
    Texture,
    Checkerboard,
    MultiObject,
}

/// APS-like frames: rate and exposure (the frame is the mean intensity over the exposure,
/// stamped at its midpoint).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ApsSpec {
    pub rate_hz: f64,
    #[serde(default)]
    pub exposure_s: f64,
}

/// A scene file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    pub kind: SceneKind,
    pub width: usize,
    pub height: usize,
    pub duration_s: f64,
    #[serde(default)]
    pub seed: u64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub render_hz: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aps: Option<ApsSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texture: Option<texture::TextureScene>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checkerboard: Option<checkerboard::CheckerboardScene>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub multi_object: Option<multi_object::MultiObjectScene>,
}

/// A realised scene that can render its intensity (camera DN) at any time.
#[derive(Clone, Debug)]
pub enum Scene {
    Texture(texture::TextureScene, Canvas),
    Checkerboard(checkerboard::CheckerboardScene),
    MultiObject(multi_object::MultiObjectWorld),
}

fn scene_error(path: &Path, problem: impl Into<String>, fix: impl Into<String>) -> SimError {
    SimError::file(path, problem, fix)
}

impl SceneSpec {
    /// The default texture (`calib/scenes/texture_translation.toml` without APS frames)
    /// translating at (60, 25) px/s for `duration_s`, rendered at `render_hz`.
    pub fn moving_texture(width: usize, height: usize, duration_s: f64, render_hz: f64) -> Self {
        Self {
            kind: SceneKind::Texture,
            width,
            height,
            duration_s,
            seed: 1,
            render_hz: Some(render_hz),
            aps: None,
            texture: Some(texture::TextureScene {
                texture: Default::default(),
                vx_px_s: 60.0,
                vy_px_s: 25.0,
                omega_deg_s: 0.0,
                offset_px: [0.0, 0.0],
                mod_amp_ln: 0.0,
                mod_hz: 0.0,
                image: None,
                image_mean_dn: None,
            }),
            checkerboard: None,
            multi_object: None,
        }
    }

    /// Reads and checks a scene file.
    pub fn from_file(path: &Path) -> Result<Self, SimError> {
        let text = super::params::read_text_file(path)?;
        Self::from_toml(&text, path)
    }

    /// Parses and checks scene text; `path` names it in errors and anchors relative
    /// texture folders.
    pub fn from_toml(text: &str, path: &Path) -> Result<Self, SimError> {
        if let Some(key) = super::params::first_non_finite(text) {
            return Err(scene_error(
                path,
                format!("`{key}` is not a finite number"),
                "give a real number (nan and inf are not scene values)",
            ));
        }
        let mut spec: SceneSpec = toml::from_str(text).map_err(|e| {
            scene_error(
                path,
                format!("cannot read the scene: {}", e.message()),
                "see calib/scenes/*.toml for complete examples",
            )
        })?;
        if let Some(m) = &mut spec.multi_object
            && let Some(dir) = &m.textures_dir
            && dir.is_relative()
        {
            m.textures_dir = Some(path.parent().unwrap_or(Path::new(".")).join(dir));
        }
        if let Some(t) = &mut spec.texture
            && let Some(image) = &t.image
            && image.is_relative()
        {
            t.image = Some(path.parent().unwrap_or(Path::new(".")).join(image));
        }
        spec.validate(path)?;
        Ok(spec)
    }

    /// The work of simulating this scene at `render_hz` (with its APS frames), for
    /// [`super::budget::Work::check`].
    pub fn work(&self, render_hz: f64) -> super::budget::Work {
        let mut samples = self.duration_s * render_hz + 1.0;
        if let Some(aps) = &self.aps {
            let frames = (self.duration_s * aps.rate_hz).floor() + 1.0;
            samples += frames * ((aps.exposure_s * render_hz).ceil() + 2.0);
        }
        super::budget::Work::new(samples, self.width, self.height)
    }

    /// Draws everything random about the scene from its seed.
    pub fn realise(&self) -> Result<Scene, SimError> {
        let mut rng = generator(self.seed, Stream::Scene, 0);
        Ok(match self.kind {
            SceneKind::Texture => {
                let t = self.texture.clone().expect("validated");
                let canvas = t.canvas(&mut rng)?;
                Scene::Texture(t, canvas)
            }
            SceneKind::Checkerboard => {
                Scene::Checkerboard(self.checkerboard.clone().expect("validated"))
            }
            SceneKind::MultiObject => {
                let m = self.multi_object.as_ref().expect("validated");
                let images = match &m.textures_dir {
                    Some(dir) => load_textures(dir)?,
                    None => Vec::new(),
                };
                Scene::MultiObject(m.realise(
                    self.width,
                    self.height,
                    self.duration_s,
                    images,
                    &mut rng,
                ))
            }
        })
    }

    /// The scene's APS frames (none without an `[aps]` table), rendered at `render_hz`.
    pub fn aps_frames(&self, scene: &Scene, render_hz: f64) -> Vec<crate::events::Frame> {
        match &self.aps {
            Some(a) => aps::render(
                scene,
                self.width,
                self.height,
                self.duration_s,
                render_hz,
                a,
            ),
            None => Vec::new(),
        }
    }

    /// The render rate: as given, else fast enough that nothing moves more than half a
    /// pixel between frames (at least 100 Hz, at most 20 kHz), rounded up so that a whole
    /// number of frames spans the duration.
    pub fn render_hz(&self, scene: &Scene) -> f64 {
        self.render_hz.unwrap_or_else(|| {
            let needed =
                (2.0 * scene.max_speed_px_s(self.width, self.height)).clamp(100.0, 20_000.0);
            (self.duration_s * needed).ceil() / self.duration_s
        })
    }
}

/// Grey images (`*.png`) of a folder, as textures.
fn load_textures(dir: &Path) -> Result<Vec<Canvas>, SimError> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| {
            SimError::file(
                dir,
                format!("cannot list textures_dir: {e}"),
                "check the folder's path and permissions",
            )
        })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")))
        .collect();
    paths.sort();
    if paths.is_empty() {
        return Err(scene_error(
            dir,
            "textures_dir holds no .png images",
            "put grey PNG textures there or remove textures_dir",
        ));
    }
    paths.iter().map(|p| load_texture(p)).collect()
}

/// A grey image (PNG) as a texture.
pub(crate) fn load_texture(path: &Path) -> Result<Canvas, SimError> {
    crate::files::check_regular(path).map_err(|e| SimError::not_a_file(path, e))?;
    let image = image::open(path)
        .map_err(|e| {
            scene_error(
                path,
                format!("cannot decode: {e}"),
                "replace it with an intact PNG",
            )
        })?
        .into_luma8();
    let (w, h) = image.dimensions();
    Ok(Canvas::from_image(w as usize, h as usize, image.as_raw()))
}

impl Scene {
    pub fn max_speed_px_s(&self, width: usize, height: usize) -> f64 {
        match self {
            Scene::Texture(t, _) => t.max_speed_px_s(width, height),
            Scene::Checkerboard(c) => c.max_speed_px_s(),
            Scene::MultiObject(m) => m.max_speed_px_s(width, height),
        }
    }

    /// Renders rows `rows` of the intensity (camera DN) at time `t` seconds into `out`
    /// (those rows of a W x H frame).
    pub fn render_rows(
        &self,
        width: usize,
        height: usize,
        rows: std::ops::Range<usize>,
        t: f64,
        out: &mut [f32],
    ) {
        match self {
            Scene::Texture(t_scene, canvas) => t_scene.render(canvas, width, height, rows, t, out),
            Scene::Checkerboard(c) => c.render(width, rows, t, out),
            Scene::MultiObject(m) => m.render(width, rows, t, out),
        }
    }

    /// Renders the whole frame at time `t` seconds into `out` (W x H).
    pub fn render(&self, width: usize, height: usize, t: f64, out: &mut [f32]) {
        self.render_rows(width, height, 0..height, t, out);
    }

    /// Renders the whole frame, bands of rows in parallel.
    pub fn render_parallel(&self, width: usize, height: usize, t: f64, out: &mut [f32]) {
        use rayon::prelude::*;
        const BAND: usize = 8;
        out.par_chunks_mut(width * BAND)
            .enumerate()
            .for_each(|(band, chunk)| {
                let start = band * BAND;
                self.render_rows(width, height, start..(start + BAND).min(height), t, chunk);
            });
    }
}

/// Frames of a scene at its render rate, `t_k = k / render_hz` for `k = 0..=N`.
pub struct SceneSource {
    scene: Scene,
    width: usize,
    height: usize,
    render_hz: f64,
    frames: u64,
    next: u64,
}

impl SceneSource {
    pub fn new(spec: &SceneSpec, scene: Scene) -> Self {
        let render_hz = spec.render_hz(&scene);
        Self {
            frames: (spec.duration_s * render_hz).round() as u64,
            scene,
            width: spec.width,
            height: spec.height,
            render_hz,
            next: 0,
        }
    }

    pub fn render_hz(&self) -> f64 {
        self.render_hz
    }
}

impl FrameSource for SceneSource {
    fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    fn len_hint(&self) -> Option<u64> {
        Some(self.frames + 1)
    }

    fn next_frame(&mut self) -> Result<Option<Sample>, SimError> {
        if self.next > self.frames {
            return Ok(None);
        }
        let t = self.next as f64 / self.render_hz;
        let mut dn = vec![0f32; self.width * self.height];
        self.scene
            .render_parallel(self.width, self.height, t, &mut dn);
        self.next += 1;
        Ok(Some(Sample {
            t: (t * 1e6).round() as TimeUs,
            dn,
            transition: Transition::Linear,
        }))
    }
}
