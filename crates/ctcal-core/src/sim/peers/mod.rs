//! Other simulators' pixel models, re-implemented so that ctcal's estimators can be tested
//! on recordings made by conventions other than its own (v2e's): ESIM ([`esim`]),
//! DVS-Voltmeter ([`voltmeter`]) and IEBCS ([`iebcs`]). Each follows its peer's published
//! code (cited in its module, with the commit read), including its time discretisation, and
//! takes ctcal [`Sample`](super::Sample)s (camera DN with times in microseconds).
//!
//! | | compares | threshold noise | refractory | leak | bandwidth, latency | noise |
//! |---|---|---|---|---|---|---|
//! | ESIM | `ln(DN/255 + 1e-3)` | redrawn per pixel per frame interval | drops events, reference moves | none | none | none |
//! | DVS-Voltmeter | `k1 ln(DN + k2)` in volts, threshold 1 | none (diffusion) | none | `k4 + k5 DN` | none | diffusion `k3 sqrt(DN)/(DN+k2) + k6` |
//! | IEBCS | `ln(DN/255 * 1e4 + 1)` | redrawn after every event | drops changes, reference reset at its end | none | low-pass `tau (1 klux / E)`, latency + jitter | fixed-rate or measured ON/OFF |
//!
//! A display's refreshes reach every peer as steps ([`held`]).
//!
//! [`write_case_with`] renders a scene through one of them into an IJRR folder with the truth
//! in ctcal's terms (`params.json`, [`CaseTruth`]), through a [`CaseWriter`] the caller
//! creates (the IO crate's `peers::write_case` gives it its IJRR writer).

pub mod esim;
mod held;
pub mod iebcs;
pub mod voltmeter;

use super::scene::{SceneSource, SceneSpec, aps};
use super::{FrameSource, SimError};
use crate::events::{EventChunk, Frame, Sensor};
use serde::{Deserialize, Serialize};

/// A peer simulator with its own parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "simulator", content = "params", rename_all = "snake_case")]
pub enum Peer {
    Esim(esim::Params),
    Voltmeter(voltmeter::Params),
    Iebcs(iebcs::Params),
}

impl Peer {
    /// The peer's name and the source its emulator follows.
    pub fn source(&self) -> (&'static str, &'static str) {
        match self {
            Peer::Esim(_) => (
                "ESIM",
                "uzh-rpg/rpg_esim@4cf0b8952e9f58f674c3098f1b027a4b6db53427",
            ),
            Peer::Voltmeter(_) => (
                "DVS-Voltmeter",
                "Lynn0306/DVS-Voltmeter@9d86353ecfaaa1af82b9eb66b162f0bf80cd4861",
            ),
            Peer::Iebcs(_) => (
                "IEBCS",
                "neuromorphicsystems/IEBCS@8fdab5c3d078435d091fa8a94ad657e1fedf0c59",
            ),
        }
    }

    /// Runs the peer over `source`: the time-sorted events (deterministic for a seed). A
    /// held sample (a display's refresh) reaches the peer as a step at its time
    /// ([`held::HeldAsSteps`]).
    pub fn simulate(
        &self,
        source: &mut dyn FrameSource,
        seed: u64,
    ) -> Result<EventChunk, SimError> {
        let source = &mut held::HeldAsSteps::new(source);
        match self {
            Peer::Esim(p) => esim::simulate(source, p, seed),
            Peer::Voltmeter(p) => voltmeter::simulate(source, p, seed),
            Peer::Iebcs(p) => iebcs::simulate(source, p, seed),
        }
    }

    /// The peer's parameters in ctcal's terms (reading IEBCS's measured noise
    /// distributions, if it is given them, for their mean rates).
    pub fn truth(&self) -> Result<Truth, SimError> {
        Ok(match self {
            Peer::Esim(p) => esim_truth(p),
            Peer::Voltmeter(p) => voltmeter_truth(p),
            Peer::Iebcs(p) => iebcs_truth(p)?,
        })
    }
}

/// ESIM's parameters in ctcal's terms: its threshold spread redrawn per interval, its
/// `ln(I + eps)` as an offset, its refractory period dropping changes.
fn esim_truth(p: &esim::Params) -> Truth {
    Truth {
        ct_on: p.contrast_threshold_pos,
        ct_off: p.contrast_threshold_neg,
        ct_sigma: p.contrast_threshold_sigma_pos,
        ct_sigma_off: p.contrast_threshold_sigma_neg,
        ct_sigma_kind: "per_interval",
        log_offset_dn: p.use_log_image.then_some(255.0 * p.log_eps),
        refractory: Refractory {
            period_s: p.refractory_period_ns as f64 * 1e-9,
            semantics: "drop",
        },
        ..Truth::ideal()
    }
}

/// DVS-Voltmeter's parameters in ctcal's terms: thresholds `1/k1`, the log offset `k2`,
/// its leak (`k4`, and `k5` per DN) and Brownian noise.
fn voltmeter_truth(p: &voltmeter::Params) -> Truth {
    let [k1, k2, k3, k4, k5, k6] = p.k;
    Truth {
        ct_on: 1.0 / k1,
        ct_off: 1.0 / k1,
        log_offset_dn: Some(k2),
        leak: Leak {
            on_rate_hz: k4 * 1e6,
            on_rate_hz_per_dn: k5 * 1e6,
        },
        noise: Noise {
            model: format!(
                "Brownian diffusion sigma(DN) = {k3} sqrt(DN) / (DN + {k2}) + {k6} \
                 per sqrt(us), thresholds at +-1"
            ),
            ..Noise::none()
        },
        ..Truth::ideal()
    }
}

/// IEBCS's parameters in ctcal's terms: thresholds redrawn per event, the log offset of
/// `ln(lux + 1)`, refractory period, noise rates (its measured distributions read for
/// their means), the photoreceptor's cutoff and latency.
fn iebcs_truth(p: &iebcs::Params) -> Result<Truth, SimError> {
    let offset = 255.0 / p.lux_at_255;
    let [on_rate_hz, off_rate_hz] = p.noise_rates()?;
    let model = match &p.noise_distributions {
        None => "fixed period per pixel, random phase; resets the pixel".into(),
        Some([on, off]) => format!(
            "measured distributions {} and {}, a random row per pixel; resets the pixel",
            on.display(),
            off.display()
        ),
    };
    Ok(Truth {
        ct_on: p.th_pos,
        ct_off: p.th_neg,
        ct_sigma: p.th_noise,
        ct_sigma_off: p.th_noise,
        ct_sigma_kind: "per_event",
        log_offset_dn: Some(offset),
        refractory: Refractory {
            period_s: p.ref_us as f64 * 1e-6,
            semantics: "drop",
        },
        noise: Noise {
            on_rate_hz,
            off_rate_hz,
            model,
        },
        cutoff: Some(Cutoff {
            hz_at_255: (p.lux_at_255 + 1.0) * 1e3 / (std::f64::consts::TAU * p.tau_us),
            dn_offset: offset,
        }),
        latency: Latency {
            mean_s: p.lat_us * 1e-6,
            jitter_s: p.jit_us * 1e-6,
        },
        ..Truth::ideal()
    })
}

/// A peer's parameters in ctcal's terms. Thresholds are in natural-log units of what the
/// pixel compares: `ln(DN + log_offset_dn)` of the frames' DN when `log_offset_dn` is given.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Truth {
    pub ct_on: f64,
    pub ct_off: f64,
    /// Threshold spread of ON events (OFF in `ct_sigma_off`).
    pub ct_sigma: f64,
    pub ct_sigma_off: f64,
    /// "none", "per_interval" (redrawn per pixel and frame interval) or "per_event".
    pub ct_sigma_kind: &'static str,
    pub log_offset_dn: Option<f64>,
    pub refractory: Refractory,
    pub leak: Leak,
    pub noise: Noise,
    /// The photoreceptor low-pass, if any.
    pub cutoff: Option<Cutoff>,
    pub latency: Latency,
}

impl Truth {
    fn ideal() -> Self {
        Self {
            ct_on: 0.0,
            ct_off: 0.0,
            ct_sigma: 0.0,
            ct_sigma_off: 0.0,
            ct_sigma_kind: "none",
            log_offset_dn: None,
            refractory: Refractory {
                period_s: 0.0,
                semantics: "none",
            },
            leak: Leak {
                on_rate_hz: 0.0,
                on_rate_hz_per_dn: 0.0,
            },
            noise: Noise::none(),
            cutoff: None,
            latency: Latency {
                mean_s: 0.0,
                jitter_s: 0.0,
            },
        }
    }
}

/// The refractory period; `semantics` "drop": a change within it is lost (v2e and ctcal
/// delay it instead).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Refractory {
    pub period_s: f64,
    pub semantics: &'static str,
}

/// Leak ON events per second in a static scene: `on_rate_hz + on_rate_hz_per_dn * DN`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Leak {
    pub on_rate_hz: f64,
    pub on_rate_hz_per_dn: f64,
}

/// Background noise: event rates per pixel and the model's description.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Noise {
    pub on_rate_hz: f64,
    pub off_rate_hz: f64,
    pub model: String,
}

impl Noise {
    fn none() -> Self {
        Self {
            on_rate_hz: 0.0,
            off_rate_hz: 0.0,
            model: "none".into(),
        }
    }
}

/// A first-order low-pass whose cutoff is `hz_at_255 (DN + dn_offset) / (255 + dn_offset)`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Cutoff {
    pub hz_at_255: f64,
    pub dn_offset: f64,
}

/// Event latency after the crossing: mean and Gaussian jitter.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Latency {
    pub mean_s: f64,
    pub jitter_s: f64,
}

/// What [`write_case`] wrote (`params.json`): the truth, the peer's own parameters, the
/// scene and the counts.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CaseTruth {
    pub ctcal_version: &'static str,
    /// The peer's name and the repository@commit its emulator follows.
    pub simulator: &'static str,
    pub source: &'static str,
    #[serde(flatten)]
    pub truth: Truth,
    pub peer: Peer,
    pub seed: u64,
    pub scene: SceneSpec,
    pub render_hz: f64,
    pub width: usize,
    pub height: usize,
    pub events: u64,
    pub on_events: u64,
    pub aps_frames: usize,
}

/// Where [`write_case_with`] writes a case: an IJRR folder (the IO crate's IJRR writer).
pub trait CaseWriter {
    fn write_events(&mut self, events: &EventChunk) -> Result<(), SimError>;
    fn write_frame(&mut self, frame: &Frame) -> Result<(), SimError>;
    fn add_file(&mut self, name: &str, bytes: &[u8]) -> Result<(), SimError>;
    fn finish(self) -> Result<(), SimError>;
}

/// Simulates `scene` through `peer` with `seed` and writes an IJRR folder through the
/// writer `create` makes for the case's sensor (`events.txt`; `images.txt` and `images/`
/// from the scene's APS frames, if it has any; `params.json`, the [`CaseTruth`] it
/// returns).
pub fn write_case_with<W: CaseWriter>(
    create: impl FnOnce(Sensor) -> Result<W, SimError>,
    scene: &SceneSpec,
    peer: &Peer,
    seed: u64,
) -> Result<CaseTruth, SimError> {
    let realised = scene.realise()?;
    let mut source = SceneSource::new(scene, realised.clone());
    let render_hz = source.render_hz();
    scene.work(render_hz).check(
        "the peer case's scene",
        "lower render_hz, duration_s, the APS rate or the sensor size",
        false,
    )?;
    let events = peer.simulate(&mut source, seed)?;
    let (width, height) = (scene.width, scene.height);
    let frames = match &scene.aps {
        Some(a) => aps::render(&realised, width, height, scene.duration_s, render_hz, a),
        None => Vec::new(),
    };
    let sensor = Sensor::new(width as u16, height as u16);
    let mut writer = create(sensor)?;
    writer.write_events(&events)?;
    for frame in &frames {
        writer.write_frame(frame)?;
    }
    let (simulator, source_ref) = peer.source();
    let case = CaseTruth {
        ctcal_version: env!("CARGO_PKG_VERSION"),
        simulator,
        source: source_ref,
        truth: peer.truth()?,
        peer: peer.clone(),
        seed,
        scene: scene.clone(),
        render_hz,
        width,
        height,
        events: events.len() as u64,
        on_events: events.on_count() as u64,
        aps_frames: frames.len(),
    };
    let json = serde_json::to_string_pretty(&case).map_err(SimError::source)?;
    writer.add_file("params.json", json.as_bytes())?;
    writer.finish()?;
    Ok(case)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn truths_are_in_log_units_of_the_compared_quantity() {
        let esim = Peer::Esim(esim::Params::default()).truth().unwrap();
        assert_eq!((esim.ct_on, esim.ct_sigma), (1.0, 0.021));
        assert!((esim.log_offset_dn.unwrap() - 0.255).abs() < 1e-12);
        let volt = Peer::Voltmeter(voltmeter::Params::dvs346())
            .truth()
            .unwrap();
        assert!((volt.ct_on - 1.0 / 5.265).abs() < 1e-12);
        assert_eq!(volt.log_offset_dn, Some(20.0));
        assert!((volt.leak.on_rate_hz - 0.1).abs() < 1e-12);
        assert!((volt.leak.on_rate_hz_per_dn - 0.005).abs() < 1e-12);
        let iebcs = Peer::Iebcs(iebcs::Params::default()).truth().unwrap();
        assert_eq!(iebcs.ct_on, 0.4);
        assert!((iebcs.refractory.period_s - 1e-4).abs() < 1e-15);
        assert!((iebcs.log_offset_dn.unwrap() - 0.0255).abs() < 1e-12);
        // tau_p = 40 us * 1e3 / 10001 at 255 DN: a 39.8 kHz cutoff
        let cutoff = iebcs.cutoff.unwrap();
        assert!((cutoff.hz_at_255 - 1.0 / (std::f64::consts::TAU * 4e-6 / 1.0001)).abs() < 1.0);
    }

    #[test]
    fn peers_serialise_with_their_name_and_parameters() {
        let peer = Peer::Iebcs(iebcs::Params::default());
        let json = serde_json::to_value(&peer).unwrap();
        assert_eq!(json["simulator"], "iebcs");
        assert_eq!(json["params"]["th_pos"], 0.4);
        let back: Peer = serde_json::from_value(json).unwrap();
        assert_eq!(back, peer);
    }
}
