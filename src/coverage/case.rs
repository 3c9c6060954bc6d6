//! One coverage case: what was drawn (scene or on-screen stimulus, pixel parameters, which
//! simulator made it). A case is serialisable, so its JSON reproduces the recording:
//! `write_case(&serde_json::from_str(json)?, dir)`.

use crate::sim::PixelParams;
use crate::sim::peers::Peer;
use crate::sim::scene::SceneSpec;
use crate::sim::scene::stimulus::StimulusSpec;
use serde::{Deserialize, Serialize};

/// A drawn recording and its true parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CaseSpec {
    /// `case-SEED`.
    pub id: String,
    pub seed: u64,
    pub generator: Generator,
    pub family: SceneFamily,
    /// The true pixel parameters (with `display` for an on-screen case).
    pub params: PixelParams,
    /// The drawn image speed, px/s (nominal: objects and rotation vary around it).
    pub speed_px_s: f64,
    /// The drawn mean brightness, camera DN (nominal for multi-object scenes).
    pub brightness_dn: f64,
    pub recording: RecordingSpec,
    /// The peer simulator's own parameters when `generator` is a peer (ESIM, DVS-Voltmeter,
    /// IEBCS); `params` then holds only the thresholds in ctcal's terms (and the display).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peer: Option<Peer>,
}

/// Which simulator turns the scene into events: ctcal's own, or a re-implementation of
/// another simulator's pixel (`ctcal::sim::peers`), so that a method is checked across
/// generators and not only against the conventions of the simulator it was built with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Generator {
    /// ctcal's own pixel model (`ctcal::sim`, v2e's conventions).
    Ctcal,
    /// ESIM (Rebecq et al. 2018): `ln(DN/255 + eps)`, thresholds redrawn per interval.
    Esim,
    /// DVS-Voltmeter (Lin et al. 2022): Brownian motion with drift, diffusion noise, leak.
    Voltmeter,
    /// IEBCS (Joubert et al. 2021): low-pass, latency and jitter, per-event threshold noise.
    Iebcs,
}

impl Generator {
    pub const ALL: [Generator; 4] = [
        Generator::Ctcal,
        Generator::Esim,
        Generator::Voltmeter,
        Generator::Iebcs,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Generator::Ctcal => "ctcal",
            Generator::Esim => "esim",
            Generator::Voltmeter => "voltmeter",
            Generator::Iebcs => "iebcs",
        }
    }

    /// The generator of `name` (as [`Generator::name`] spells it).
    pub fn named(name: &str) -> Option<Generator> {
        Self::ALL.into_iter().find(|g| g.name() == name)
    }
}

/// The kind of scene, for drawing and for the coverage breakdown.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SceneFamily {
    /// A procedural 1/f^beta texture translating.
    Texture,
    /// A procedural texture rotating (and translating).
    Rotation,
    /// A natural photograph translating, sometimes rotating.
    NaturalImage,
    /// A moving two-level checkerboard.
    Checkerboard,
    /// Textured objects moving over a textured background.
    MultiObject,
    /// Multi-object with natural photographs as textures.
    MultiObjectNatural,
    /// The calibration checkerboard shown on a display (for `estimate screen`).
    Screen,
}

impl SceneFamily {
    pub const ALL: [SceneFamily; 7] = [
        SceneFamily::Texture,
        SceneFamily::Rotation,
        SceneFamily::NaturalImage,
        SceneFamily::Checkerboard,
        SceneFamily::MultiObject,
        SceneFamily::MultiObjectNatural,
        SceneFamily::Screen,
    ];

    pub fn name(self) -> &'static str {
        match self {
            SceneFamily::Texture => "texture",
            SceneFamily::Rotation => "rotation",
            SceneFamily::NaturalImage => "natural_image",
            SceneFamily::Checkerboard => "checkerboard",
            SceneFamily::MultiObject => "multi_object",
            SceneFamily::MultiObjectNatural => "multi_object_natural",
            SceneFamily::Screen => "screen",
        }
    }
}

/// What the camera looks at.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum RecordingSpec {
    /// A scene seen directly, with APS frames. Relative image paths in it are relative to
    /// the ctcal source tree (`calib/scenes/textures/natural/...`).
    Scene { scene: Box<SceneSpec> },
    /// The calibration checkerboard played on the display of `params.display`.
    Screen { stimulus: StimulusSpec },
}

impl CaseSpec {
    pub fn is_screen(&self) -> bool {
        matches!(self.recording, RecordingSpec::Screen { .. })
    }

    /// Sensor size (W, H).
    pub fn size(&self) -> (usize, usize) {
        match &self.recording {
            RecordingSpec::Scene { scene } => (scene.width, scene.height),
            RecordingSpec::Screen { stimulus } => (stimulus.width, stimulus.height),
        }
    }

    pub fn duration_s(&self) -> f64 {
        match &self.recording {
            RecordingSpec::Scene { scene } => scene.duration_s,
            RecordingSpec::Screen { stimulus } => stimulus.duration_s,
        }
    }
}
