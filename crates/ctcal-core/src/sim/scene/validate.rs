//! Checks of a scene file's numbers ([`SceneSpec::from_toml_file`]): each out-of-range
//! value is refused with its key and what to give instead, before any frame is rendered.

use super::canvas::TextureParams;
use super::checkerboard::CheckerboardScene;
use super::multi_object::{self, MultiObjectScene};
use super::texture::TextureScene;
use super::{SceneKind, SceneSpec, scene_error};
use crate::sim::SimError;
use std::path::Path;

/// The largest speed, offset or modulation a scene may give (a finite value).
const SPEED: f64 = 1e6;

/// The file whose values are checked, named in every error.
struct Checks<'a> {
    path: &'a Path,
}

impl Checks<'_> {
    /// `value` within `lo..=hi`.
    fn within(&self, key: &str, value: f64, lo: f64, hi: f64, fix: &str) -> Result<(), SimError> {
        if value.is_finite() && value >= lo && value <= hi {
            Ok(())
        } else {
            Err(scene_error(
                self.path,
                format!("`{key}` = {value} is outside {lo}..={hi}"),
                fix,
            ))
        }
    }

    /// `[lo, hi]` an ordered range within `min..=max`.
    fn range(&self, key: &str, [lo, hi]: [f64; 2], min: f64, max: f64) -> Result<(), SimError> {
        if lo.is_finite() && hi.is_finite() && min <= lo && lo <= hi && hi <= max {
            Ok(())
        } else {
            Err(scene_error(
                self.path,
                format!("`{key}` = [{lo}, {hi}] is not a range within {min}..={max}"),
                "give [low, high] with low <= high",
            ))
        }
    }

    /// Every `(key, value)` finite (within +-[`SPEED`]).
    fn finite(&self, values: &[(&str, f64)]) -> Result<(), SimError> {
        for &(key, v) in values {
            self.within(key, v, -SPEED, SPEED, "give a finite value")?;
        }
        Ok(())
    }

    /// A procedural texture's parameters, its keys under `prefix`.
    fn texture(&self, prefix: &str, t: &TextureParams) -> Result<(), SimError> {
        let dn = "give intensities in camera DN";
        for (key, value, lo, hi, fix) in [
            (
                "canvas_px",
                t.canvas_px as f64,
                8.0,
                8192.0,
                "give the texture canvas side in pixels",
            ),
            ("min_dn", t.min_dn, 1e-3, 1e6, dn),
            (
                "max_dn",
                t.max_dn,
                t.min_dn,
                1e6,
                "max_dn must be at least min_dn",
            ),
            ("mean_dn", t.mean_dn, 1e-3, 1e6, dn),
            (
                "log_std",
                t.log_std,
                0.0,
                10.0,
                "give the log-intensity spread",
            ),
            (
                "spectrum_beta",
                t.spectrum_beta,
                -10.0,
                10.0,
                "give the spectral exponent (1 for natural images)",
            ),
            (
                "blur_px",
                t.blur_px,
                0.0,
                1e3,
                "give the texture blur in pixels",
            ),
        ] {
            self.within(&format!("{prefix}{key}"), value, lo, hi, fix)?;
        }
        Ok(())
    }
}

impl SceneSpec {
    /// Refuses a scene whose size, timing or scene table holds a value out of range, or
    /// whose kind has no table.
    pub(super) fn validate(&self, path: &Path) -> Result<(), SimError> {
        let c = Checks { path };
        self.validate_size(path)?;
        self.validate_timing(&c)?;
        match self.kind {
            SceneKind::Texture => self.texture.as_ref().map_or(Ok(()), |t| t.validate(&c)),
            SceneKind::Checkerboard => self
                .checkerboard
                .as_ref()
                .map_or(Ok(()), |s| s.validate(&c)),
            SceneKind::MultiObject => self
                .multi_object
                .as_ref()
                .map_or(Ok(()), |m| m.validate(&c)),
        }?;
        self.validate_table(path)
    }

    fn validate_size(&self, path: &Path) -> Result<(), SimError> {
        use super::super::budget::MAX_SIDE;
        if self.width == 0 || self.height == 0 || self.width > MAX_SIDE || self.height > MAX_SIDE {
            return Err(scene_error(
                path,
                format!(
                    "size {}x{} is not a sensor size (1..={MAX_SIDE} pixels a side)",
                    self.width, self.height
                ),
                "give width and height in pixels",
            ));
        }
        Ok(())
    }

    /// The length, the render rate and the APS frames.
    fn validate_timing(&self, c: &Checks) -> Result<(), SimError> {
        let length = "give the scene length in seconds";
        if self.duration_s.is_nan() || self.duration_s <= 0.0 {
            return Err(scene_error(c.path, "`duration_s` must be positive", length));
        }
        c.within("duration_s", self.duration_s, 0.0, 86_400.0, length)?;
        if let Some(r) = self.render_hz {
            c.within("render_hz", r, 1e-3, 1e6, "remove it to let ctcal choose")?;
        }
        if let Some(aps) = &self.aps {
            c.within(
                "aps.rate_hz",
                aps.rate_hz,
                1e-3,
                1e4,
                "give the APS frame rate in Hz",
            )?;
            if !(aps.exposure_s >= 0.0 && aps.exposure_s <= 1.0 / aps.rate_hz) {
                return Err(scene_error(
                    c.path,
                    "aps needs 0 <= exposure_s <= 1/rate_hz",
                    "fix the [aps] table",
                ));
            }
        }
        Ok(())
    }

    /// The table the kind names is there.
    fn validate_table(&self, path: &Path) -> Result<(), SimError> {
        let table = match self.kind {
            SceneKind::Texture => self.texture.is_some(),
            SceneKind::Checkerboard => self.checkerboard.is_some(),
            SceneKind::MultiObject => self.multi_object.is_some(),
        };
        if table {
            return Ok(());
        }
        let name = serde_json::to_value(self.kind)
            .ok()
            .and_then(|v| v.as_str().map(String::from))
            .unwrap_or_default();
        Err(scene_error(
            path,
            format!("kind = \"{name}\" needs a [{name}] table"),
            "add the table (see calib/scenes/)",
        ))
    }
}

impl TextureScene {
    fn validate(&self, c: &Checks) -> Result<(), SimError> {
        c.texture("texture.", &self.texture)?;
        c.finite(&[
            ("texture.vx_px_s", self.vx_px_s),
            ("texture.vy_px_s", self.vy_px_s),
            ("texture.omega_deg_s", self.omega_deg_s),
            ("texture.offset_px[0]", self.offset_px[0]),
            ("texture.offset_px[1]", self.offset_px[1]),
            ("texture.mod_amp_ln", self.mod_amp_ln),
            ("texture.mod_hz", self.mod_hz),
        ])?;
        if let Some(mean) = self.image_mean_dn {
            c.within(
                "texture.image_mean_dn",
                mean,
                1e-3,
                1e6,
                "give the image's mean intensity in camera DN",
            )?;
        }
        Ok(())
    }
}

impl CheckerboardScene {
    fn validate(&self, c: &Checks) -> Result<(), SimError> {
        let dn = "give intensities in camera DN";
        c.within(
            "checkerboard.square_px",
            self.square_px,
            0.5,
            1e5,
            "give the square side in pixels",
        )?;
        c.within("checkerboard.lo_dn", self.lo_dn, 0.0, 1e6, dn)?;
        c.within("checkerboard.hi_dn", self.hi_dn, 0.0, 1e6, dn)?;
        c.finite(&[
            ("checkerboard.vx_px_s", self.vx_px_s),
            ("checkerboard.vy_px_s", self.vy_px_s),
            ("checkerboard.origin_px[0]", self.origin_px[0]),
            ("checkerboard.origin_px[1]", self.origin_px[1]),
        ])
    }
}

impl MultiObjectScene {
    fn validate(&self, c: &Checks) -> Result<(), SimError> {
        if self.objects[0] > self.objects[1] || self.objects[1] > multi_object::MAX_OBJECTS {
            return Err(scene_error(
                c.path,
                format!(
                    "`multi_object.objects` = [{}, {}] is not a range within 0..={}",
                    self.objects[0],
                    self.objects[1],
                    multi_object::MAX_OBJECTS
                ),
                "give [fewest, most] objects",
            ));
        }
        for (key, range, min, max) in [
            (
                "background_velocity_px_s",
                self.background_velocity_px_s,
                0.0,
                SPEED,
            ),
            (
                "background_angular_velocity_deg_s",
                self.background_angular_velocity_deg_s,
                0.0,
                SPEED,
            ),
            ("background_scale", self.background_scale, 1e-3, 1e3),
            (
                "object_velocity_px_s",
                self.object_velocity_px_s,
                0.0,
                SPEED,
            ),
            (
                "object_angular_velocity_deg_s",
                self.object_angular_velocity_deg_s,
                0.0,
                SPEED,
            ),
            ("object_scale", self.object_scale, 1e-3, 1e3),
            ("object_size_px", self.object_size_px, 0.5, 1e4),
        ] {
            c.range(&format!("multi_object.{key}"), range, min, max)?;
        }
        c.texture("multi_object.background_texture.", &self.background_texture)
    }
}
