//! `ctcal simulate`: events from a frame folder or a scene through the pixel model.

use super::{BadInput, Global, JsonTarget, emit_json, output, progress_bar};
use clap::{Args, ValueEnum};
use ctcal::io::write::{H5Writer, IjrrWriter};
use ctcal::io::{FrameList, npy};
use ctcal::sim::display::DisplayModel;
use ctcal::sim::scene::{SceneSource, SceneSpec, aps};
use ctcal::sim::source::{DisplaySource, FolderSource};
use ctcal::sim::{FrameSource, PixelMaps, PixelParams, SimError};
use ctcal::{EventChunk, Frame, Sensor};
use serde::Serialize;
use std::path::{Path, PathBuf};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SimOutput {
    Ijrr,
    H5,
}

#[derive(Args, Debug)]
#[command(group = clap::ArgGroup::new("input").required(true).args(["frames", "scene"]))]
pub struct SimulateArgs {
    /// Pixel parameters (PARAMS.toml).
    #[arg(long, value_name = "PARAMS.toml")]
    pub params: PathBuf,
    /// A folder with images.txt (or stimulus.txt) and its images; the first frame only sets
    /// each pixel's reference level.
    #[arg(long, value_name = "DIR")]
    pub frames: Option<PathBuf>,
    /// A scene file (see calib/scenes/).
    #[arg(long, value_name = "SCENE.toml")]
    pub scene: Option<PathBuf>,
    /// Output folder (IJRR) or HDF5 file.
    #[arg(long, value_name = "PATH")]
    pub out: PathBuf,
    /// Output layout (default: h5 when --out ends in .h5, else ijrr).
    #[arg(long, value_enum)]
    pub to: Option<SimOutput>,
    /// Per-pixel ON thresholds, an (H, W) .npy array (instead of drawing them).
    #[arg(long, value_name = "FILE.npy")]
    pub ct_on_map: Option<PathBuf>,
    /// Per-pixel OFF thresholds, an (H, W) .npy array.
    #[arg(long, value_name = "FILE.npy")]
    pub ct_off_map: Option<PathBuf>,
    /// Per-pixel leak-rate factors, an (H, W) .npy array.
    #[arg(long, value_name = "FILE.npy")]
    pub leak_factor_map: Option<PathBuf>,
    /// Write a summary (counts, rates, timing) as JSON to PATH (`-` for stdout).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
}

/// What was simulated and what came out (`simulation.json` in an IJRR output folder).
#[derive(Serialize)]
struct Provenance {
    ctcal_version: &'static str,
    width: usize,
    height: usize,
    input_samples: u64,
    events: u64,
    on_events: u64,
    t_first_sample_us: i64,
    t_last_sample_us: i64,
    duration_s: f64,
    events_per_pixel_per_second: f64,
    aps_frames: usize,
    render_hz: Option<f64>,
    params: PixelParams,
    #[serde(skip_serializing_if = "Option::is_none")]
    scene: Option<SceneSpec>,
    #[serde(skip_serializing_if = "Option::is_none")]
    frames: Option<PathBuf>,
}

/// The `--json` summary: the provenance plus timing.
#[derive(Serialize)]
struct Summary<'a> {
    #[serde(flatten)]
    provenance: &'a Provenance,
    wall_s: f64,
    samples_per_second: f64,
}

enum Writer {
    Ijrr(IjrrWriter),
    H5(H5Writer),
}

impl Writer {
    fn events(&mut self, chunk: &EventChunk) -> Result<(), SimError> {
        match self {
            Writer::Ijrr(w) => w.write_events(chunk)?,
            Writer::H5(w) => w.write_events(chunk)?,
        }
        Ok(())
    }

    fn frame(&mut self, frame: &Frame) -> Result<(), SimError> {
        match self {
            Writer::Ijrr(w) => w.write_frame(frame)?,
            Writer::H5(w) => w.write_frame(frame)?,
        }
        Ok(())
    }
}

/// The frame index of a `--frames` folder: images.txt, else stimulus.txt.
fn frame_index(dir: &Path) -> Result<PathBuf, BadInput> {
    if dir.is_file() {
        return Ok(dir.to_path_buf());
    }
    for name in ["images.txt", "stimulus.txt"] {
        if dir.join(name).is_file() {
            return Ok(dir.join(name));
        }
    }
    Err(BadInput(format!(
        "{}: holds neither images.txt nor stimulus.txt\n  fix: point --frames at a folder listing its frames (`t images/frame_XXXXXXXX.png` lines)",
        dir.display()
    )))
}

fn load_maps(args: &SimulateArgs, sensor: Sensor) -> Result<PixelMaps, SimError> {
    let read = |path: &Option<PathBuf>| {
        path.as_deref()
            .map(|p| npy::read_pixel_map(p, sensor))
            .transpose()
    };
    Ok(PixelMaps {
        ct_on: read(&args.ct_on_map)?,
        ct_off: read(&args.ct_off_map)?,
        leak_factor: read(&args.leak_factor_map)?,
    })
}

pub fn run(args: &SimulateArgs, global: &Global) -> anyhow::Result<()> {
    let params = PixelParams::from_file(&args.params)?;
    let started = std::time::Instant::now();
    let (mut source, scene_spec, render_hz, aps_frames): (
        Box<dyn FrameSource>,
        Option<SceneSpec>,
        Option<f64>,
        Vec<Frame>,
    ) = match (&args.frames, &args.scene) {
        (Some(dir), _) => {
            let list = FrameList::read(&frame_index(dir)?)?;
            if list.len() < 2 {
                return Err(BadInput(format!(
                    "{}: needs at least two frames to simulate events",
                    list.index_path.display()
                ))
                .into());
            }
            (Box::new(FolderSource::new(list)?), None, None, Vec::new())
        }
        (None, Some(path)) => {
            let spec = SceneSpec::from_file(path)?;
            let scene = spec.realise()?;
            let source = SceneSource::new(&spec, scene.clone());
            let hz = source.render_hz();
            let frames = match &spec.aps {
                Some(a) => aps::render(&scene, spec.width, spec.height, spec.duration_s, hz, a),
                None => Vec::new(),
            };
            (Box::new(source), Some(spec), Some(hz), frames)
        }
        (None, None) => unreachable!("clap requires --frames or --scene"),
    };
    if let Some(display) = &params.display {
        source = Box::new(DisplaySource::new(source, DisplayModel::new(display)));
    }
    let (width, height) = source.size();
    let sensor = Sensor::new(width as u16, height as u16);
    let maps = load_maps(args, sensor)?;
    let to = args.to.unwrap_or(
        if args
            .out
            .extension()
            .is_some_and(|e| e == "h5" || e == "hdf5")
        {
            SimOutput::H5
        } else {
            SimOutput::Ijrr
        },
    );
    let mut writer = match to {
        SimOutput::Ijrr => Writer::Ijrr(IjrrWriter::create(&args.out, sensor)?),
        SimOutput::H5 => Writer::H5(H5Writer::create(&args.out, sensor)?),
    };
    let bar = progress_bar(global, source.len_hint().unwrap_or(0), "simulating");
    let summary = ctcal::sim::run(
        source.as_mut(),
        &params,
        maps,
        |events| writer.events(events),
        |n| bar.set_position(n),
    )?;
    bar.finish_and_clear();
    for frame in &aps_frames {
        writer.frame(frame)?;
    }
    let wall_s = started.elapsed().as_secs_f64();
    let duration_s = (summary.t_last_sample_us - summary.t_first_sample_us) as f64 * 1e-6;
    let result = Provenance {
        ctcal_version: env!("CARGO_PKG_VERSION"),
        width,
        height,
        input_samples: summary.samples,
        events: summary.events,
        on_events: summary.on_events,
        t_first_sample_us: summary.t_first_sample_us,
        t_last_sample_us: summary.t_last_sample_us,
        duration_s,
        events_per_pixel_per_second: if duration_s > 0.0 {
            summary.events as f64 / ((width * height) as f64 * duration_s)
        } else {
            0.0
        },
        aps_frames: aps_frames.len(),
        render_hz,
        params,
        scene: scene_spec,
        frames: args.frames.clone(),
    };
    match writer {
        Writer::Ijrr(mut w) => {
            w.add_file(
                "simulation.json",
                serde_json::to_string_pretty(&result)?.as_bytes(),
            )?;
            w.finish()?
        }
        Writer::H5(w) => w.finish()?,
    }
    let samples_per_second = summary.samples as f64 / wall_s;
    let target = args.json.as_deref().map(JsonTarget::parse);
    if let Some(target) = &target {
        emit_json(
            &Summary {
                provenance: &result,
                wall_s,
                samples_per_second,
            },
            target,
        )?;
    }
    if !matches!(target, Some(JsonTarget::Stdout)) && !global.quiet {
        output::print_table(&[
            ("sensor".into(), format!("{width}x{height}")),
            ("input samples".into(), result.input_samples.to_string()),
            (
                "events".into(),
                format!("{} ({} ON)", result.events, result.on_events),
            ),
            ("duration".into(), output::seconds(duration_s)),
            (
                "events/pixel/s".into(),
                format!("{:.4}", result.events_per_pixel_per_second),
            ),
            ("APS frames".into(), result.aps_frames.to_string()),
            (
                "wall time".into(),
                format!(
                    "{} ({:.0} samples/s)",
                    output::seconds(wall_s),
                    samples_per_second
                ),
            ),
            ("written".into(), args.out.display().to_string()),
        ]);
    }
    Ok(())
}
