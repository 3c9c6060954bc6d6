//! A whole esim_config_generator configuration (Stoffregen et al. 2020's scene generator):
//! its scene sections with example motion ranges and placeholder image folders to adapt,
//! and `camera_params` covering every given fit with margin for training: ON and OFF
//! thresholds are drawn as `C`, `C * N(1, ct_diff_sigma)`.

use super::{Setup, combine, unmeasured_notes};
use crate::sim::PixelParams;
use serde::Serialize;
use serde_json::json;

/// esim_config_generator's `camera_params`, covering `fits`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EsimGeneratorCamera {
    pub contrast_threshold_mean: f64,
    pub ct_diff_sigma: f64,
    #[serde(rename = "min_C")]
    pub min_c: f64,
    #[serde(rename = "max_C")]
    pub max_c: f64,
    pub hard_c_t_sigmas: f64,
    pub refractory_period_ns: i64,
    pub sim_framerate: u32,
}

#[derive(Serialize)]
struct Sensor {
    width: u32,
    height: u32,
}

/// The whole file, `ctcal_version` first (how ctcal knows a file it may replace).
#[derive(Serialize)]
struct EsimGenerator {
    ctcal_version: &'static str,
    name: &'static str,
    foreground_params: serde_json::Value,
    background_params: serde_json::Value,
    foreground_images: serde_json::Value,
    background_images: serde_json::Value,
    camera_params: EsimGeneratorCamera,
    #[serde(skip_serializing_if = "Option::is_none")]
    ctcal_sensor: Option<Sensor>,
    ctcal_notes: Vec<String>,
}

/// The camera covering `fits`: the mean threshold, a spread of ON against OFF that covers
/// every fit's ratio (at least the paper's 0.1), bounds 20 % beyond the lowest and highest
/// fitted thresholds, the median fitted mismatch and refractory period.
fn camera(fits: &[PixelParams]) -> Option<(EsimGeneratorCamera, String)> {
    let thresholds: Vec<f64> = fits.iter().flat_map(|p| [p.ct_on, p.ct_off]).collect();
    let mean = thresholds.iter().sum::<f64>() / thresholds.len() as f64;
    let ratio_spread = fits
        .iter()
        .map(|p| (p.ct_off / p.ct_on).ln().abs())
        .fold(0.0, f64::max);
    let lo = thresholds.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = thresholds.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let combined = combine(fits)?;
    let note = format!(
        "from {} fit(s): thresholds {lo:.3} to {hi:.3}; ON and OFF differ by up to {:.0} %",
        fits.len(),
        100.0 * (ratio_spread.exp() - 1.0)
    );
    let camera = EsimGeneratorCamera {
        contrast_threshold_mean: mean,
        ct_diff_sigma: ratio_spread.max(0.1),
        min_c: (lo / 1.2 * 1e4).round() / 1e4,
        max_c: (hi * 1.2 * 1e4).round() / 1e4,
        hard_c_t_sigmas: combined.ct_sigma.unwrap_or(1e-4),
        refractory_period_ns: (combined.refractory_s.unwrap_or(0.0) * 1e9).round() as i64,
        sim_framerate: 100,
    };
    Some((camera, note))
}

/// The esim_config_generator JSON for `fits`.
pub fn esim_generator(fits: &[PixelParams], setup: &Setup) -> Option<String> {
    if fits.is_empty() {
        return None;
    }
    let (camera, from) = camera(fits)?;
    let mut notes = vec![
        from,
        "hard_c_t_sigmas is ESIM's per-event threshold noise; ctcal fitted a frozen per-pixel mismatch of that size".into(),
        "sim_framerate is the generator's default; raise it for fast motion".into(),
        "foreground_params, background_params and the image folders are examples: set the folders to your 4-channel PNG foregrounds and JPEG backgrounds, and the motions to your scenes".into(),
    ];
    if let Some((w, h)) = setup.sensor {
        notes.push(format!(
            "the fitted sensor is {w}x{h}: give the generator and ESIM that image size"
        ));
    }
    notes.extend(unmeasured_notes(setup));
    let config = EsimGenerator {
        ctcal_version: env!("CARGO_PKG_VERSION"),
        name: "ctcal_fitted_camera",
        foreground_params: json!({
            "fg_min_ang_velocity_deg": 0.0, "fg_max_ang_velocity_deg": 5.0,
            "fg_min_velocity": 0.5, "fg_max_velocity": 30.0,
            "fg_growthmin": 0.3, "fg_growthmax": 0.9
        }),
        background_params: json!({
            "bg_min_ang_velocity_deg": 0.0, "bg_max_ang_velocity_deg": 5.0,
            "bg_min_velocity": 0.5, "bg_max_velocity": 10.0,
            "bg_growthmin": 1.0, "bg_growthmax": 1.5
        }),
        foreground_images: json!({
            "png_dataset": { "path": "/path/to/foreground_pngs", "proportion": 1.0 },
            "min_num": 5, "max_num": 10
        }),
        background_images: json!({ "jpg_dataset": { "path": "/path/to/background_jpgs" } }),
        camera_params: camera,
        ctcal_sensor: setup.sensor.map(|(width, height)| Sensor { width, height }),
        ctcal_notes: notes,
    };
    serde_json::to_string_pretty(&config).ok().map(|s| s + "\n")
}
