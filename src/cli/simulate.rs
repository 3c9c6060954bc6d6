//! `ctcal simulate`: events from a frame folder or a scene through the pixel model.

use super::{BadInput, Global, JsonTarget, check_json, emit_json, output, progress_bar};
use clap::{Args, ValueEnum};
use ctcal::io::write::{H5Writer, IjrrWriter};
use ctcal::io::{FrameList, npy};
use ctcal::sim::budget::{EffectWork, MAX_SIDE, Work};
use ctcal::sim::display::DisplayModel;
use ctcal::sim::scene::{SceneSource, SceneSpec};
use ctcal::sim::source::{DisplaySource, LoadedFrames};
use ctcal::sim::{FrameSource, PixelMaps, PixelParams, SimError, SimSummary};
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
    /// Output layout (default from --out: .h5/.hdf5 -> h5, no extension -> an ijrr folder).
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

/// What was simulated and what came out (`simulation.json` in an IJRR output folder,
/// stamped with ctcal's version as every JSON output).
#[derive(Serialize)]
struct Provenance {
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
    fn events(&mut self, chunk: &EventChunk) -> anyhow::Result<()> {
        match self {
            Writer::Ijrr(w) => w.write_events(chunk)?,
            Writer::H5(w) => w.write_events(chunk)?,
        }
        Ok(())
    }

    fn frame(&mut self, frame: &Frame) -> anyhow::Result<()> {
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

fn load_maps(args: &SimulateArgs, sensor: Sensor) -> anyhow::Result<PixelMaps> {
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

/// The output layout `--out`'s extension asks for, when `--to` is not given.
fn layout_from_extension(out: &Path) -> Result<SimOutput, BadInput> {
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "" => Ok(SimOutput::Ijrr),
        "h5" | "hdf5" => Ok(SimOutput::H5),
        other => Err(BadInput(format!(
            "{}: ctcal simulate cannot write .{other} files\n  fix: pass --to ijrr (a folder) or --to h5, or end --out in .h5 or no extension",
            out.display()
        ))),
    }
}

/// What is simulated: the frame source, the scene it came from (if any), and the work.
struct SimInput {
    source: Box<dyn FrameSource>,
    scene_spec: Option<SceneSpec>,
    render_hz: Option<f64>,
    aps_frames: Vec<Frame>,
    work: Work,
    /// The input's time span, seconds.
    span_s: f64,
}

/// Opens `--frames` or `--scene` (checking the scene's work against the budget).
fn open_input(args: &SimulateArgs, global: &Global) -> anyhow::Result<SimInput> {
    Ok(match (&args.frames, &args.scene) {
        (Some(dir), _) => {
            let list = FrameList::read(&frame_index(dir)?)?;
            if list.len() < 2 {
                return Err(BadInput(format!(
                    "{}: needs at least two frames to simulate events",
                    list.index_path.display()
                ))
                .into());
            }
            let (w, h) = list.image_size()?.expect("two frames listed");
            let (w, h) = (w as usize, h as usize);
            if w > MAX_SIDE || h > MAX_SIDE {
                return Err(BadInput(format!(
                    "{}: the frames are {w}x{h}, larger than the {MAX_SIDE}x{MAX_SIDE} ctcal simulates\n  fix: downscale the frames",
                    list.index_path.display()
                ))
                .into());
            }
            let work = Work::new(list.len() as f64, w, h);
            let span_s = (list.entries[list.len() - 1].t - list.entries[0].t) as f64 * 1e-6;
            let source = LoadedFrames::new(list.len(), (w, h), move |i| {
                list.load(i).map_err(SimError::source)
            });
            SimInput {
                source: Box::new(source),
                scene_spec: None,
                render_hz: None,
                aps_frames: Vec::new(),
                work,
                span_s,
            }
        }
        (None, Some(path)) => {
            let spec = SceneSpec::from_file(path)?;
            let scene = spec.realise()?;
            let source = SceneSource::new(&spec, scene.clone());
            let hz = source.render_hz();
            let work = spec.work(hz);
            work.check(
                &path.display().to_string(),
                "lower render_hz, duration_s, the APS rate or the sensor size",
                global.force,
            )?;
            let frames = spec.aps_frames(&scene, hz);
            SimInput {
                source: Box::new(source),
                span_s: spec.duration_s,
                scene_spec: Some(spec),
                render_hz: Some(hz),
                aps_frames: frames,
                work,
            }
        }
        (None, None) => unreachable!("clap requires --frames or --scene"),
    })
}

pub fn run(args: &SimulateArgs, global: &Global) -> anyhow::Result<()> {
    let to = match args.to {
        Some(to) => to,
        None => layout_from_extension(&args.out)?,
    };
    let params = PixelParams::from_file(&args.params)?;
    let policy = global.outputs(input_paths(args));
    check_json(args.json.as_deref(), &policy)?;
    let started = std::time::Instant::now();
    let SimInput {
        source,
        scene_spec,
        render_hz,
        aps_frames,
        work,
        span_s,
    } = open_input(args, global)?;
    let mut source = checked_source(args, global, &params, source, work, span_s)?;
    let (width, height) = source.size();
    let sensor = Sensor::new(width as u16, height as u16);
    let maps = load_maps(args, sensor)?;
    let mut writer = create_writer(to, &args.out, sensor, &policy)?;
    let summary = simulate_into(source.as_mut(), &params, maps, &mut writer, global)?;
    for frame in &aps_frames {
        writer.frame(frame)?;
    }
    write_stimulus(args, &mut writer)?;
    let wall_s = started.elapsed().as_secs_f64();
    let (duration_s, rate) = duration_and_rate(&summary, (width, height));
    let result = Provenance {
        width,
        height,
        input_samples: summary.samples,
        events: summary.events,
        on_events: summary.on_events,
        t_first_sample_us: summary.t_first_sample_us,
        t_last_sample_us: summary.t_last_sample_us,
        duration_s,
        events_per_pixel_per_second: rate,
        aps_frames: aps_frames.len(),
        render_hz,
        params,
        scene: scene_spec,
        frames: args.frames.clone(),
    };
    finish_output(writer, &result)?;
    let summary = Summary {
        provenance: &result,
        wall_s,
        samples_per_second: summary.samples as f64 / wall_s,
    };
    present(args, global, &policy, &summary)
}

/// Creates the output: an IJRR folder or an event_utils HDF5 file at `out`.
fn create_writer(
    to: SimOutput,
    out: &Path,
    sensor: Sensor,
    policy: &super::OutputPolicy,
) -> anyhow::Result<Writer> {
    Ok(match to {
        SimOutput::Ijrr => Writer::Ijrr(IjrrWriter::create(out, sensor, policy)?),
        SimOutput::H5 => Writer::H5(H5Writer::create(out, sensor, policy)?),
    })
}

/// Runs the pixel model `params` (with the per-pixel `maps`) over every sample of
/// `source`, each batch of events written as it comes, with a progress bar of the samples.
fn simulate_into(
    source: &mut dyn FrameSource,
    params: &PixelParams,
    maps: PixelMaps,
    writer: &mut Writer,
    global: &Global,
) -> anyhow::Result<SimSummary> {
    let bar = progress_bar(global, source.len_hint().unwrap_or(0), "simulating");
    let summary = ctcal::sim::run::<anyhow::Error>(
        source,
        params,
        maps,
        |events| writer.events(events),
        |n| bar.set_position(n),
    )?;
    bar.finish_and_clear();
    Ok(summary)
}

/// The simulated span, seconds (first to last input sample), and the events per pixel per
/// second over it, `events / (width * height * duration_s)` (the rate Stoffregen et al.
/// 2020 match between real and simulated data; 0 over no time).
fn duration_and_rate(summary: &SimSummary, (width, height): (usize, usize)) -> (f64, f64) {
    let duration_s = (summary.t_last_sample_us - summary.t_first_sample_us) as f64 * 1e-6;
    let rate = if duration_s > 0.0 {
        summary.events as f64 / ((width * height) as f64 * duration_s)
    } else {
        0.0
    };
    (duration_s, rate)
}

/// Finishes the output: an IJRR folder also gets `simulation.json` (the provenance).
fn finish_output(writer: Writer, result: &Provenance) -> anyhow::Result<()> {
    match writer {
        Writer::Ijrr(mut w) => {
            w.add_file("simulation.json", output::json_text(result)?.as_bytes())?;
            w.finish()?
        }
        Writer::H5(w) => w.finish()?,
    }
    Ok(())
}

/// The files the simulation reads (never written over).
fn input_paths(args: &SimulateArgs) -> Vec<&Path> {
    let mut inputs: Vec<&Path> = vec![args.params.as_path()];
    inputs.extend(args.frames.as_deref());
    inputs.extend(args.scene.as_deref());
    for map in [&args.ct_on_map, &args.ct_off_map, &args.leak_factor_map] {
        inputs.extend(map.as_deref());
    }
    inputs
}

/// The input behind the display where the parameters have one, its work (images, display
/// refreshes, and the events and blur the effects add) checked against the budget before
/// the output is created.
fn checked_source(
    args: &SimulateArgs,
    global: &Global,
    params: &PixelParams,
    mut source: Box<dyn FrameSource>,
    mut work: Work,
    span_s: f64,
) -> anyhow::Result<Box<dyn FrameSource>> {
    // the images of the input (a display blurs each once)
    let images = work.samples;
    if let Some(display) = &params.display {
        // the display adds a sample at every refresh
        work.samples += span_s * display.refresh_hz;
        source = Box::new(DisplaySource::new(source, DisplayModel::new(display)));
    }
    let what = args
        .frames
        .as_deref()
        .or(args.scene.as_deref())
        .map(|p| p.display().to_string())
        .unwrap_or_default();
    work.check(
        &what,
        "simulate fewer frames, a shorter scene or a smaller sensor",
        global.force,
    )?;
    EffectWork::new(params, &work, span_s, images)
        .check(&args.params.display().to_string(), global.force)?;
    Ok(source)
}

/// A simulated recording of an on-screen stimulus carries the stimulus, so that `estimate
/// screen` finds it beside the events.
fn write_stimulus(args: &SimulateArgs, writer: &mut Writer) -> anyhow::Result<()> {
    if let (Some(dir), Writer::Ijrr(w)) = (&args.frames, writer) {
        let index = frame_index(dir)?;
        if index.file_name().is_some_and(|n| n == "stimulus.txt") {
            let list = FrameList::read(&index)?;
            for i in 0..list.len() {
                w.write_stimulus_frame(&list.load(i)?)?;
            }
        }
    }
    Ok(())
}

/// The summary as JSON (`--json`) and as a table.
fn present(
    args: &SimulateArgs,
    global: &Global,
    policy: &super::OutputPolicy,
    summary: &Summary,
) -> anyhow::Result<()> {
    let result = summary.provenance;
    let target = args.json.as_deref().map(JsonTarget::parse);
    if let Some(target) = &target {
        emit_json(summary, target, policy)?;
    }
    if !matches!(target, Some(JsonTarget::Stdout)) && !global.quiet {
        output::print_table(&[
            (
                "sensor".into(),
                format!("{}x{}", result.width, result.height),
            ),
            ("input samples".into(), result.input_samples.to_string()),
            (
                "events".into(),
                format!("{} ({} ON)", result.events, result.on_events),
            ),
            ("duration".into(), output::seconds(result.duration_s)),
            (
                "events/pixel/s".into(),
                format!("{:.4}", result.events_per_pixel_per_second),
            ),
            ("APS frames".into(), result.aps_frames.to_string()),
            (
                "wall time".into(),
                format!(
                    "{} ({:.0} samples/s)",
                    output::seconds(summary.wall_s),
                    summary.samples_per_second
                ),
            ),
            ("written".into(), args.out.display().to_string()),
        ])?;
    }
    Ok(())
}
