//! Drawing the scene of a non-screen case: one [`SceneSpec`] per family, with APS frames
//! at 10-100 Hz and 0-10 ms exposure, the drawn brightness, contrast and speed.

use super::case::SceneFamily;
use super::draw::uniform;
use crate::sim::scene::canvas::TextureParams;
use crate::sim::scene::checkerboard::CheckerboardScene;
use crate::sim::scene::multi_object::MultiObjectScene;
use crate::sim::scene::texture::TextureScene;
use crate::sim::scene::{ApsSpec, SceneKind, SceneSpec};
use rand::{Rng, RngExt};
use std::path::PathBuf;

/// The natural photographs (`calib/scenes/textures/natural/`, CC0 or public domain).
pub const NATURAL_IMAGES: [&str; 6] = ["camera", "coffee", "chelsea", "brick", "grass", "gravel"];

/// Where the natural photographs are, relative to the ctcal source tree.
pub const NATURAL_DIR: &str = "calib/scenes/textures/natural";

/// What every family shares: sensor, length, speed and brightness.
pub(super) struct Look {
    pub width: usize,
    pub height: usize,
    pub duration_s: f64,
    pub speed_px_s: f64,
    pub brightness_dn: f64,
}

/// A 1/f^beta log-normal texture: spectrum_beta 0.5-2.5, log_std 0.15-0.9.
fn texture_params(rng: &mut impl Rng, mean_dn: f64) -> TextureParams {
    TextureParams {
        canvas_px: 256,
        mean_dn,
        log_std: uniform(rng, 0.15, 0.9),
        min_dn: 0.5,
        max_dn: 255.0,
        spectrum_beta: uniform(rng, 0.5, 2.5),
        blur_px: 1.0,
    }
}

/// A velocity of `speed` in a random direction.
fn velocity(rng: &mut impl Rng, speed: f64) -> [f64; 2] {
    let direction = uniform(rng, 0.0, std::f64::consts::TAU);
    [speed * direction.cos(), speed * direction.sin()]
}

fn aps(rng: &mut impl Rng) -> ApsSpec {
    let rate_hz = uniform(rng, 10.0, 100.0).round();
    let exposure_s = if rng.random::<f64>() < 0.2 {
        0.0
    } else {
        uniform(rng, 0.0, 0.01f64.min(1.0 / rate_hz))
    };
    ApsSpec {
        rate_hz,
        exposure_s: (exposure_s * 1e5).round() / 1e5,
    }
}

/// A texture scene: translation, or rotation at `speed` at the corners plus a slower drift.
fn moving(rng: &mut impl Rng, look: &Look, rotate: bool) -> TextureScene {
    let (speed, mut omega_deg_s) = (look.speed_px_s, 0.0);
    let [vx, vy] = if rotate {
        let radius = (look.width as f64).hypot(look.height as f64) / 2.0;
        let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
        omega_deg_s = sign * (speed / radius).to_degrees();
        let drift = speed * uniform(rng, 0.0, 0.5);
        velocity(rng, drift)
    } else {
        velocity(rng, speed)
    };
    TextureScene {
        texture: TextureParams::default(),
        vx_px_s: vx,
        vy_px_s: vy,
        omega_deg_s,
        offset_px: [uniform(rng, 0.0, 256.0), uniform(rng, 0.0, 256.0)],
        mod_amp_ln: 0.0,
        mod_hz: 0.0,
        image: None,
        image_mean_dn: None,
    }
}

fn checkerboard(rng: &mut impl Rng, look: &Look) -> CheckerboardScene {
    let contrast_ln = uniform(rng, 0.3, 1.8);
    let [vx, vy] = velocity(rng, look.speed_px_s);
    CheckerboardScene {
        square_px: uniform(rng, 6.0, 30.0),
        lo_dn: (look.brightness_dn * (-contrast_ln / 2.0).exp()).max(1.0),
        hi_dn: (look.brightness_dn * (contrast_ln / 2.0).exp()).min(255.0),
        vx_px_s: vx,
        vy_px_s: vy,
        origin_px: [uniform(rng, 0.0, 60.0), uniform(rng, 0.0, 60.0)],
    }
}

fn multi_object(rng: &mut impl Rng, look: &Look, natural: bool) -> MultiObjectScene {
    let s = look.speed_px_s;
    MultiObjectScene {
        objects: [1, rng.random_range(2..=8)],
        background_velocity_px_s: [0.2 * s, 0.5 * s],
        background_angular_velocity_deg_s: [0.0, 20.0],
        background_scale: [0.9, 1.1],
        object_velocity_px_s: [0.5 * s, s],
        object_angular_velocity_deg_s: [0.0, 90.0],
        object_scale: [0.8, 1.2],
        object_size_px: [8.0, 0.25 * look.height as f64],
        textures_dir: natural.then(|| PathBuf::from(NATURAL_DIR)),
        background_texture: texture_params(rng, look.brightness_dn),
    }
}

/// The scene of one family (not [`SceneFamily::Screen`]).
pub(super) fn draw_scene(
    rng: &mut impl Rng,
    family: SceneFamily,
    look: &Look,
    seed: u64,
) -> SceneSpec {
    let mut spec = SceneSpec {
        kind: SceneKind::Texture,
        width: look.width,
        height: look.height,
        duration_s: look.duration_s,
        seed,
        render_hz: None,
        aps: Some(aps(rng)),
        texture: None,
        checkerboard: None,
        multi_object: None,
    };
    match family {
        SceneFamily::Texture | SceneFamily::Rotation => {
            let mut t = moving(rng, look, family == SceneFamily::Rotation);
            t.texture = texture_params(rng, look.brightness_dn);
            spec.texture = Some(t);
        }
        SceneFamily::NaturalImage => {
            let rotate = rng.random::<bool>();
            let mut t = moving(rng, look, rotate);
            let name = NATURAL_IMAGES[rng.random_range(0..NATURAL_IMAGES.len())];
            t.image = Some(PathBuf::from(format!("{NATURAL_DIR}/{name}.png")));
            t.image_mean_dn = Some(look.brightness_dn);
            spec.texture = Some(t);
        }
        SceneFamily::Checkerboard => {
            spec.kind = SceneKind::Checkerboard;
            spec.checkerboard = Some(checkerboard(rng, look));
        }
        SceneFamily::MultiObject | SceneFamily::MultiObjectNatural => {
            spec.kind = SceneKind::MultiObject;
            let natural = family == SceneFamily::MultiObjectNatural;
            spec.multi_object = Some(multi_object(rng, look, natural));
        }
        SceneFamily::Screen => unreachable!("screen cases draw a stimulus, not a scene"),
    }
    spec
}
