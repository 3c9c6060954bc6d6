//! Writing a case ([`write_case`]): the scene (or the checkerboard through its display) is
//! rendered by ctcal's scene renderer, turned into events by the case's generator, and
//! written as an IJRR folder (`events.txt`, `images.txt` + `images/`, or `stimulus.txt` +
//! `stimulus/` for an on-screen case) with `case.json` (the spec) and `truth.json`.

use super::case::{CaseSpec, Generator, RecordingSpec};
use super::truth::Truth;
use crate::events::{Frame, Sensor};
use crate::io::write::{IjrrWriter, OutputPolicy};
use crate::sim::display::DisplayModel;
use crate::sim::scene::stimulus::StimulusSpec;
use crate::sim::scene::{SceneSource, SceneSpec};
use crate::sim::source::{DisplaySource, LoadedFrames};
use crate::sim::{FrameSource, PixelMaps, SimError, SimSummary};
use std::path::{Path, PathBuf};

/// What the camera looks at, ready to simulate.
struct CameraInput {
    source: Box<dyn FrameSource>,
    aps_frames: Vec<Frame>,
    stimulus: Vec<Frame>,
    mean_dn: f64,
    sample_hz: f64,
}

/// The ctcal source tree, against which a case's relative image paths are read.
pub fn project_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The scene with its relative image paths anchored at [`project_root`].
fn anchored(scene: &SceneSpec) -> SceneSpec {
    let mut scene = scene.clone();
    let anchor = |path: &mut Option<PathBuf>| {
        if let Some(p) = path.as_mut()
            && p.is_relative()
        {
            *p = project_root().join(&*p);
        }
    };
    if let Some(t) = scene.texture.as_mut() {
        anchor(&mut t.image);
    }
    if let Some(m) = scene.multi_object.as_mut() {
        anchor(&mut m.textures_dir);
    }
    scene
}

fn mean(values: &[f32]) -> f64 {
    values.iter().map(|&v| v as f64).sum::<f64>() / values.len().max(1) as f64
}

/// A scene seen directly, with its APS frames (as `ctcal simulate --scene` renders it).
fn scene_input(spec: &SceneSpec) -> Result<CameraInput, SimError> {
    let spec = anchored(spec);
    let scene = spec.realise()?;
    let source = SceneSource::new(&spec, scene.clone());
    let render_hz = source.render_hz();
    let mut middle = vec![0f32; spec.width * spec.height];
    scene.render(spec.width, spec.height, spec.duration_s / 2.0, &mut middle);
    Ok(CameraInput {
        aps_frames: spec.aps_frames(&scene, render_hz),
        source: Box::new(source),
        stimulus: Vec::new(),
        mean_dn: mean(&middle),
        sample_hz: render_hz,
    })
}

/// The calibration checkerboard played on `display` (as `ctcal simulate --frames` plays a
/// `ctcal calib checkerboard` folder through a `[display]`).
fn screen_input(stimulus: &StimulusSpec, case: &CaseSpec) -> Result<CameraInput, SimError> {
    let display = case.params.display.as_ref().ok_or_else(|| {
        SimError::Invalid(format!("{}: an on-screen case needs a display", case.id))
    })?;
    let frames: Vec<Frame> = (0..stimulus.frame_count())
        .map(|k| stimulus.render(k))
        .collect();
    let model = DisplayModel::new(display);
    let middle = &frames[frames.len() / 2];
    let screen: Vec<f32> = middle.pixels.iter().map(|&p| p as f32).collect();
    let mean_dn = mean(&model.camera_dn(&screen, stimulus.width, stimulus.height));
    let replay = frames.clone();
    let played = LoadedFrames::new(frames.len(), (stimulus.width, stimulus.height), move |i| {
        Ok(replay[i].clone())
    });
    Ok(CameraInput {
        source: Box::new(DisplaySource::new(played, model)),
        aps_frames: Vec::new(),
        stimulus: frames,
        mean_dn,
        sample_hz: display.refresh_hz,
    })
}

/// Events of `input` by the case's generator, written as they come.
fn generate(
    case: &CaseSpec,
    input: &mut CameraInput,
    writer: &mut IjrrWriter,
) -> Result<SimSummary, SimError> {
    match (case.generator, &case.peer) {
        (Generator::Ctcal, _) => crate::sim::run::<SimError>(
            input.source.as_mut(),
            &case.params,
            PixelMaps::default(),
            |events| writer.write_events(events).map_err(SimError::source),
            |_| {},
        ),
        (_, Some(peer)) => {
            let events = peer.simulate(input.source.as_mut(), case.seed)?;
            writer.write_events(&events).map_err(SimError::source)?;
            Ok(SimSummary {
                samples: 0,
                events: events.len() as u64,
                on_events: events.on_count() as u64,
                t_first_sample_us: events.t.first().copied().unwrap_or(0),
                t_last_sample_us: events.t.last().copied().unwrap_or(0),
            })
        }
        (generator, None) => Err(SimError::Invalid(format!(
            "{}: a {} case needs the peer's parameters (`peer`)",
            case.id,
            generator.name()
        ))),
    }
}

/// Writes `case` as an IJRR folder at `dir` (replacing what ctcal wrote there before) and
/// returns its truth (also written as `truth.json`).
pub fn write_case(case: &CaseSpec, dir: &Path) -> Result<Truth, SimError> {
    let mut input = match &case.recording {
        RecordingSpec::Scene { scene } => scene_input(scene)?,
        RecordingSpec::Screen { stimulus } => screen_input(stimulus, case)?,
    };
    let (width, height) = case.size();
    let sensor = Sensor::new(width as u16, height as u16);
    let mut writer =
        IjrrWriter::create(dir, sensor, &OutputPolicy::new(true)).map_err(SimError::source)?;
    let summary = generate(case, &mut input, &mut writer)?;
    for frame in &input.aps_frames {
        writer.write_frame(frame).map_err(SimError::source)?;
    }
    for frame in &input.stimulus {
        writer
            .write_stimulus_frame(frame)
            .map_err(SimError::source)?;
    }
    let truth = Truth {
        mean_dn: input.mean_dn,
        events: summary.events,
        on_events: summary.on_events,
        events_per_pixel_per_second: summary.events as f64
            / ((width * height) as f64 * case.duration_s()),
        aps_frames: input.aps_frames.len(),
        sample_hz: input.sample_hz,
        ..Truth::of(case)
    };
    writer
        .add_file("case.json", pretty(case).as_bytes())
        .and_then(|_| writer.add_file("truth.json", pretty(&truth).as_bytes()))
        .and_then(|_| writer.finish())
        .map_err(SimError::source)?;
    Ok(truth)
}

fn pretty(value: &impl serde::Serialize) -> String {
    serde_json::to_string_pretty(value).expect("case records serialise")
}
