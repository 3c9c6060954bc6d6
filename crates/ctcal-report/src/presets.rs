//! The fixed presets of Stoffregen et al. (2020, Fig. 2): the events per pixel per second
//! that a simulator makes of typical training scenes at contrast thresholds 0.2, 0.5, 0.75,
//! 1.0 and 1.5, against which a dataset's own rate shows which setting resembles it. The
//! scene is the "medium" speed class of their scene generator (`calib/scenes/
//! multi_object_medium.toml`: 5-10 objects at 20-80 px/s over a slow background), seen by
//! an ideal pixel.

use super::model::PresetLevel;
use crate::estimate::eppps::PRESETS;
use crate::sim::scene::{SceneSource, SceneSpec};
use crate::sim::{PixelMaps, PixelParams, SimError};

/// The scene, as shipped in `calib/scenes`.
const SCENE: &str = include_str!("../../../calib/scenes/multi_object_medium.toml");

/// A description of how the presets were made.
pub const DESCRIPTION: &str = "calib/scenes/multi_object_medium.toml (esim_config_generator's medium motions: 5-10 objects at 20-80 px/s, 240x180, 1 s) simulated by an ideal pixel at each threshold";

/// Simulates the preset levels.
pub fn simulate(seed: u64) -> Result<Vec<PresetLevel>, SimError> {
    let mut spec = SceneSpec::from_toml(
        SCENE,
        std::path::Path::new("calib/scenes/multi_object_medium.toml"),
    )?;
    spec.seed = seed;
    spec.aps = None;
    let scene = spec.realise()?;
    // render once, simulate at every threshold
    let mut source = SceneSource::new(&spec, scene);
    let mut samples = Vec::new();
    while let Some(sample) = crate::sim::FrameSource::next_frame(&mut source)? {
        samples.push(sample);
    }
    let pixels = (spec.width * spec.height) as f64;
    PRESETS
        .iter()
        .map(|&ct| {
            let mut replay =
                crate::sim::source::ReplaySamples::new(&samples, spec.width, spec.height);
            let summary = crate::sim::run::<SimError>(
                &mut replay,
                &PixelParams::ideal(ct, ct),
                PixelMaps::default(),
                |_| Ok(()),
                |_| {},
            )?;
            let duration = (summary.t_last_sample_us - summary.t_first_sample_us) as f64 * 1e-6;
            Ok(PresetLevel {
                ct,
                events_per_pixel_per_second: summary.events as f64 / (pixels * duration.max(1e-6)),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_fall_with_the_threshold() {
        let levels = simulate(1).unwrap();
        assert_eq!(levels.len(), 5);
        assert!(
            levels
                .windows(2)
                .all(|w| w[0].events_per_pixel_per_second > w[1].events_per_pixel_per_second)
        );
        // an ideal pixel fires floor(|change| / C) times for a monotone log change: every
        // event at CT 1.0 takes five at CT 0.2, and the changes smaller than 1.0 that
        // still cross 0.2 add more, so the ratio is above 5 (and not wildly so)
        let ratio = levels[0].events_per_pixel_per_second / levels[3].events_per_pixel_per_second;
        assert!(ratio > 5.0 && ratio < 50.0, "{ratio}");
    }
}
