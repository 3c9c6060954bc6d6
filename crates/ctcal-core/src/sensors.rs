//! Known sensor presets (`calib/sensors.toml`, compiled in so the binary is self-contained).
//!
//! Used to name a sensor when a file does not state its resolution, and to recognise a
//! sensor from a file's metadata (Prophesee `plugin_name`, iniVation `source`).

use crate::events::Sensor;
use serde::Deserialize;
use std::sync::OnceLock;

/// One known sensor.
#[derive(Clone, Debug, Deserialize)]
pub struct SensorPreset {
    pub name: String,
    pub width: u16,
    pub height: u16,
    #[serde(default)]
    pub aliases: Vec<String>,
}

impl SensorPreset {
    pub fn sensor(&self) -> Sensor {
        Sensor::new(self.width, self.height)
    }
}

#[derive(Deserialize)]
struct PresetFile {
    sensor: Vec<SensorPreset>,
}

/// All presets, in file order.
pub fn presets() -> &'static [SensorPreset] {
    static PRESETS: OnceLock<Vec<SensorPreset>> = OnceLock::new();
    PRESETS.get_or_init(|| {
        let text = include_str!("../../../calib/sensors.toml");
        toml::from_str::<PresetFile>(text)
            .expect("calib/sensors.toml is valid (checked by a unit test)")
            .sensor
    })
}

/// The smallest preset (by pixel count) containing pixel `(max_x, max_y)`.
pub fn smallest_containing(max_x: u16, max_y: u16) -> Option<&'static SensorPreset> {
    presets()
        .iter()
        .filter(|p| max_x < p.width && max_y < p.height)
        .min_by_key(|p| p.width as usize * p.height as usize)
}

/// The preset whose alias occurs in `metadata` (case-insensitive), if any.
pub fn from_metadata(metadata: &str) -> Option<&'static SensorPreset> {
    let lower = metadata.to_ascii_lowercase();
    presets().iter().find(|p| {
        p.aliases
            .iter()
            .any(|a| lower.contains(&a.to_ascii_lowercase()))
    })
}

/// The preset with exactly this size, if any (for naming a sensor).
pub fn named(sensor: Sensor) -> Option<&'static SensorPreset> {
    presets().iter().find(|p| p.sensor() == sensor)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_cover_the_common_sensors() {
        let sizes: Vec<_> = presets().iter().map(|p| (p.width, p.height)).collect();
        for s in [
            (128, 128),
            (240, 180),
            (346, 260),
            (320, 240),
            (640, 480),
            (1280, 720),
        ] {
            assert!(sizes.contains(&s), "missing {s:?}");
        }
    }

    #[test]
    fn smallest_containing_picks_the_tightest_sensor() {
        assert_eq!(smallest_containing(239, 179).unwrap().name, "DAVIS240C");
        assert_eq!(smallest_containing(240, 10).unwrap().width, 320);
        assert_eq!(smallest_containing(345, 259).unwrap().name, "DAVIS346");
        assert_eq!(smallest_containing(1279, 719).unwrap().width, 1280);
        assert!(smallest_containing(2000, 10).is_none());
    }

    #[test]
    fn metadata_names_prophesee_plugins() {
        assert_eq!(
            from_metadata("% plugin_name hal_plugin_gen3_fx3")
                .unwrap()
                .sensor(),
            Sensor::new(640, 480)
        );
        assert_eq!(
            from_metadata("hal_plugin_imx636_evk4").unwrap().sensor(),
            Sensor::new(1280, 720)
        );
    }
}
