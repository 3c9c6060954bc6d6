//! `ctcal._ctcal`: the Python extension of ctcal. Each function calls the library with the
//! GIL released and hands back plain values: NumPy arrays for events and frames, and for
//! results the JSON of the library's result structs (the CLI's keys), which the Python skin
//! (`ctcal/__init__.py`) turns into dicts. Every error is a `CtcalError` (a `ValueError`)
//! carrying the library's message.

use ctcal_core::Sensor;
use ctcal_core::estimate::aps::ApsOptions;
use ctcal_core::sim::PixelParams;
use ctcal_core::stats::{StatsAccumulator, StatsOptions};
use ctcal_io::window::{Loaded, SelectionSpec, Window};
use ctcal_io::{OpenOptions, Recording};
use ctcal_pipeline::{self as pipeline, Input, Options};
use ctcal_report::grouping::Origin;
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use std::path::{Path, PathBuf};

pyo3::create_exception!(
    _ctcal,
    CtcalError,
    pyo3::exceptions::PyValueError,
    "An error of ctcal: bad input (with the fix) or a failure, with the CLI's message."
);

/// Any library error as a `CtcalError` with its message.
fn err(e: impl std::fmt::Display) -> PyErr {
    CtcalError::new_err(e.to_string())
}

/// A result stamped with the version of ctcal that made it, as the CLI writes it.
#[derive(serde::Serialize)]
struct Stamped<'a, T: serde::Serialize> {
    ctcal_version: &'static str,
    #[serde(flatten)]
    value: &'a T,
}

/// The JSON of a result, as `ctcal ... --json` writes it.
fn json(value: &impl serde::Serialize) -> PyResult<String> {
    serde_json::to_string(&Stamped {
        ctcal_version: env!("CARGO_PKG_VERSION"),
        value,
    })
    .map_err(err)
}

/// How to open a recording: the format (detected when `None`) and the sensor size.
fn open_options(format: Option<&str>, sensor: Option<&str>) -> PyResult<OpenOptions> {
    Ok(OpenOptions {
        format: format
            .map(|f| f.parse())
            .transpose()
            .map_err(|e: String| err(e))?,
        sensor: sensor
            .map(|s| {
                Sensor::parse(s).ok_or_else(|| err(format!("`{s}` is not WxH (e.g. 346x260)")))
            })
            .transpose()?,
        ..OpenOptions::default()
    })
}

/// Events as Python receives them: t (int64 us), x, y (uint16), p (uint8, 1 = ON).
type EventArrays<'py> = (
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<u16>>,
    Bound<'py, PyArray1<u16>>,
    Bound<'py, PyArray1<u8>>,
);

/// Events gathered column by column, for [`EventArrays`].
#[derive(Default)]
struct EventColumns {
    t: Vec<i64>,
    x: Vec<u16>,
    y: Vec<u16>,
    p: Vec<u8>,
}

impl EventColumns {
    fn extend(&mut self, chunk: &ctcal_core::EventChunk, range: std::ops::Range<usize>) {
        self.t.extend_from_slice(&chunk.t[range.clone()]);
        self.x.extend_from_slice(&chunk.x[range.clone()]);
        self.y.extend_from_slice(&chunk.y[range.clone()]);
        self.p.extend(chunk.on[range].iter().map(|&on| on as u8));
    }

    fn into_numpy(self, py: Python<'_>) -> EventArrays<'_> {
        (
            PyArray1::from_vec(py, self.t),
            PyArray1::from_vec(py, self.x),
            PyArray1::from_vec(py, self.y),
            PyArray1::from_vec(py, self.p),
        )
    }
}

/// A statistics window as `ctcal stats` takes it: an end equal to the start selects one
/// instant (whose rates are then null, with their reasons); an end before it is an error.
fn check_stats_window(start: Option<f64>, end: Option<f64>) -> Result<(), String> {
    let instant = matches!((start, end), (Some(s), Some(e)) if s == e);
    ctcal_io::window::check_window(start, if instant { None } else { end })
        .map_err(|e| e.to_string())
}

/// The events of `path` (between `start` and `end` seconds after the first event) as
/// four arrays: t (int64 us), x, y (uint16), p (uint8, 1 = ON).
#[pyfunction]
#[pyo3(signature = (path, start=None, end=None, format=None, sensor=None))]
fn read<'py>(
    py: Python<'py>,
    path: PathBuf,
    start: Option<f64>,
    end: Option<f64>,
    format: Option<&str>,
    sensor: Option<&str>,
) -> PyResult<EventArrays<'py>> {
    let open = open_options(format, sensor)?;
    let columns = py
        .detach(|| -> Result<_, String> {
            ctcal_io::window::check_window(start, end).map_err(|e| e.to_string())?;
            let recording = Recording::open(&path, &open).map_err(|e| e.to_string())?;
            let first = recording.first_event_time().map_err(|e| e.to_string())?;
            let to_us = |s: f64| first + (s * 1e6).round() as i64;
            let (from, to) = (start.map_or(i64::MIN, to_us), end.map_or(i64::MAX, to_us));
            let mut stream = recording
                .events_between(from, to)
                .map_err(|e| e.to_string())?;
            let mut columns = EventColumns::default();
            while let Some(chunk) = stream.next_chunk().map_err(|e| e.to_string())? {
                let lo = chunk.t.partition_point(|&v| v < from);
                let hi = chunk.t.partition_point(|&v| v <= to).max(lo);
                columns.extend(chunk, lo..hi);
                if chunk.t.last().is_some_and(|&v| v > to) {
                    break;
                }
            }
            Ok(columns)
        })
        .map_err(err)?;
    Ok(columns.into_numpy(py))
}

/// The grey frames of `path`: their times (int64 us), every frame's pixels one after the
/// other (uint8, row-major), and the frame height and width.
#[pyfunction]
#[pyo3(signature = (path, format=None, sensor=None))]
#[allow(clippy::type_complexity)]
fn read_frames<'py>(
    py: Python<'py>,
    path: PathBuf,
    format: Option<&str>,
    sensor: Option<&str>,
) -> PyResult<(
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<u8>>,
    usize,
    usize,
)> {
    let open = open_options(format, sensor)?;
    let (times, pixels, h, w) = py
        .detach(|| -> Result<_, ctcal_io::InputError> {
            let recording = Recording::open(&path, &open)?;
            let frames = recording.frames_where(|_, _| true)?;
            let (w, h) = frames
                .first()
                .map_or((0, 0), |f| (f.width as usize, f.height as usize));
            let mut pixels = Vec::with_capacity(frames.len() * w * h);
            let mut times = Vec::with_capacity(frames.len());
            for f in &frames {
                times.push(f.t);
                pixels.extend_from_slice(&f.pixels);
            }
            Ok((times, pixels, h, w))
        })
        .map_err(err)?;
    Ok((
        PyArray1::from_vec(py, times),
        PyArray1::from_vec(py, pixels),
        h,
        w,
    ))
}

/// `ctcal info` of `path`, as JSON.
#[pyfunction]
#[pyo3(signature = (path, format=None, sensor=None))]
fn info(
    py: Python<'_>,
    path: PathBuf,
    format: Option<&str>,
    sensor: Option<&str>,
) -> PyResult<String> {
    let open = open_options(format, sensor)?;
    let info = py
        .detach(|| -> Result<_, ctcal_io::InputError> {
            let recording = Recording::open(&path, &open)?;
            let stream = recording.events()?;
            Ok(ctcal_io::info::info(&recording, stream, &|_, _| {})?.0)
        })
        .map_err(err)?;
    json(&info)
}

/// The window of a recording the estimators and the fit take.
#[allow(clippy::too_many_arguments)]
fn load(
    path: &Path,
    open: &OpenOptions,
    start: Option<f64>,
    end: Option<f64>,
    max_frames: usize,
    events_between_frames: bool,
    roi: Option<&str>,
    mask: Option<PathBuf>,
) -> Result<Loaded, String> {
    let roi = roi
        .map(ctcal_core::selection::Roi::parse)
        .transpose()
        .map_err(|e| e.to_string())?;
    ctcal_io::window::load(
        path,
        open,
        &Window {
            start_s: start,
            end_s: end,
            frames: Some(max_frames),
            events_between_frames,
        },
        &SelectionSpec { roi, mask },
        false,
        &ctcal_io::window::Silent,
    )
    .map_err(|e| e.to_string())
}

/// A threshold estimate of `path` (`aps`, `eppps` or `screen`), as the JSON of
/// `ctcal estimate METHOD --json`.
#[pyfunction]
#[pyo3(signature = (path, method, start=None, end=None, max_frames=120, max_pixels=ctcal_io::fit_region::FIT_PIXELS, max_events=ctcal_io::fit_region::FIT_EVENTS, seed=2020, roi=None, mask=None, format=None, sensor=None, stimulus=None))]
#[allow(clippy::too_many_arguments)]
fn estimate(
    py: Python<'_>,
    path: PathBuf,
    method: &str,
    start: Option<f64>,
    end: Option<f64>,
    max_frames: usize,
    max_pixels: usize,
    max_events: usize,
    seed: u64,
    roi: Option<&str>,
    mask: Option<PathBuf>,
    format: Option<&str>,
    sensor: Option<&str>,
    stimulus: Option<PathBuf>,
) -> PyResult<String> {
    let open = open_options(format, sensor)?;
    let method = method.to_string();
    let estimate = py
        .detach(|| -> Result<_, String> {
            let aps_method = method == "aps";
            let loaded = load(&path, &open, start, end, max_frames, aps_method, roi, mask)?;
            let mut estimate = match method.as_str() {
                "aps" => {
                    let budget = ctcal_io::fit_region::FitBudget {
                        max_pixels,
                        max_events,
                    };
                    aps_estimate(&path, &loaded, budget)?
                }
                "eppps" => eppps_estimate(&path, &loaded, seed)?,
                "screen" => screen_estimate(&path, &loaded, stimulus.as_deref())?,
                other => {
                    return Err(format!(
                        "unknown method `{other}`\n  fix: aps, eppps or screen"
                    ));
                }
            };
            if let Some(b) = loaded.recording.biases() {
                estimate.extra.insert(
                    "biases".into(),
                    serde_json::to_value(b).map_err(|e| e.to_string())?,
                );
            }
            Ok(estimate)
        })
        .map_err(err)?;
    json(&estimate)
}

/// An estimate's error as its message, after the recording's `path`.
fn named(path: &Path) -> impl Fn(ctcal_core::estimate::EstimateError) -> String + '_ {
    move |e| format!("{}: {e}", path.display())
}

/// `estimate aps` of the recording at `path` within `budget`; refused without two frames.
fn aps_estimate(
    path: &Path,
    loaded: &Loaded,
    budget: ctcal_io::fit_region::FitBudget,
) -> Result<ctcal_core::estimate::CtEstimate, String> {
    if loaded.frames.len() < 2 {
        return Err(format!(
            "{}: `estimate aps` needs grey frames; the recording has {}\n  fix: use the eppps method, which needs no frames",
            path.display(),
            if loaded.frames.len() == 1 {
                "only one"
            } else {
                "none"
            }
        ));
    }
    Ok(
        ctcal_io::aps_region::aps(loaded, &ApsOptions::default(), budget, &|_, _| {})
            .map_err(named(path))?
            .estimate,
    )
}

/// `estimate eppps` of the recording at `path`, its scenes simulated with `seed`.
fn eppps_estimate(
    path: &Path,
    loaded: &Loaded,
    seed: u64,
) -> Result<ctcal_core::estimate::CtEstimate, String> {
    ctcal_io::window::eppps_of(
        loaded,
        &ApsOptions::default(),
        ctcal_core::estimate::eppps::EpppsOptions {
            seed,
            ..Default::default()
        },
        &|_, _| {},
    )
    .map_err(named(path))
}

/// `estimate screen` of the recording at `path` against the `stimulus` folder's frames,
/// else the recording's own stimulus; refused where there is none.
fn screen_estimate(
    path: &Path,
    loaded: &Loaded,
    stimulus: Option<&Path>,
) -> Result<ctcal_core::estimate::CtEstimate, String> {
    let list = match stimulus {
        Some(dir) => Some(ctcal_io::FrameList::read(dir).map_err(|e| e.to_string())?),
        None => loaded.recording.stimulus().map_err(|e| e.to_string())?,
    };
    let Some(list) = list else {
        return Err(format!(
            "{}: no stimulus.txt beside the recording\n  fix: give the stimulus folder (stimulus=...)",
            path.display()
        ));
    };
    let frames = list.load_all().map_err(|e| e.to_string())?;
    ctcal_io::window::screen_of(loaded, &frames, (None, None), None, &|_, _| {})
        .map_err(named(path))
}

/// `ctcal fit` of `path` with the default options, as JSON.
#[pyfunction]
#[pyo3(signature = (path, start=None, end=None, max_frames=120, max_pixels=ctcal_io::fit_region::FIT_PIXELS, max_events=ctcal_io::fit_region::FIT_EVENTS, seed=2020, roi=None, mask=None, format=None, sensor=None))]
#[allow(clippy::too_many_arguments)]
fn fit(
    py: Python<'_>,
    path: PathBuf,
    start: Option<f64>,
    end: Option<f64>,
    max_frames: usize,
    max_pixels: usize,
    max_events: usize,
    seed: u64,
    roi: Option<&str>,
    mask: Option<PathBuf>,
    format: Option<&str>,
    sensor: Option<&str>,
) -> PyResult<String> {
    let open = open_options(format, sensor)?;
    let result = py
        .detach(|| -> Result<_, String> {
            let loaded = load(&path, &open, start, end, max_frames, true, roi, mask)?;
            ctcal_io::fit_region::fit(
                &loaded,
                &ctcal_core::fit::FitOptions {
                    seed,
                    ..Default::default()
                },
                ctcal_io::fit_region::FitBudget {
                    max_pixels,
                    max_events,
                },
                &|_: &str, _: f64| {},
            )
            .map_err(|e| format!("{}: {e}", path.display()))
        })
        .map_err(err)?;
    json(&result)
}

/// The pipeline's options from the skin's JSON (`start`, `end`, `max_frames`, `max_pixels`, `max_events`, `seed`,
/// `fit`, `screen` (a TOML file), `roi`, `mask`, `force`).
fn report_options(text: &str) -> PyResult<Options> {
    let v: serde_json::Value = serde_json::from_str(text).map_err(err)?;
    let mut o = Options {
        start_s: v["start"].as_f64(),
        end_s: v["end"].as_f64(),
        ..Options::default()
    };
    if let Some(n) = v["max_frames"].as_u64() {
        o.max_frames = n as usize;
    }
    if let Some(n) = v["max_pixels"].as_u64() {
        o.fit_budget.max_pixels = n as usize;
    }
    if let Some(n) = v["max_events"].as_u64() {
        o.fit_budget.max_events = n as usize;
    }
    if let Some(s) = v["seed"].as_u64() {
        o.seed = s;
    }
    if v["fit"].as_bool() == Some(false) {
        o.fit_left_out = Some("left out (fit=False)".into());
    }
    if let Some(path) = v["screen"].as_str() {
        let path = Path::new(path);
        let text = ctcal_core::files::read_small_text(path, 1 << 20)
            .map_err(|e| err(ctcal_io::InputError::not_a_file(path, e)))?;
        o.screen = Some(
            ctcal_core::sim::DisplayParams::from_toml(&text, &path.display().to_string())
                .map_err(err)?,
        );
    }
    o.selection = SelectionSpec {
        roi: v["roi"]
            .as_str()
            .map(ctcal_core::selection::Roi::parse)
            .transpose()
            .map_err(err)?,
        mask: v["mask"].as_str().map(PathBuf::from),
    };
    o.force = v["force"].as_bool() == Some(true);
    o.check().map_err(err)?;
    Ok(o)
}

/// One input as the skin passes it: (path, name, dataset or `None` for its folder's).
type InputTuple = (PathBuf, String, Option<String>, String);

fn to_tuple(i: &Input) -> InputTuple {
    match &i.origin {
        Origin::Named(n) => (
            i.path.clone(),
            i.name.clone(),
            Some(n.clone()),
            String::new(),
        ),
        Origin::Folder(f) => (i.path.clone(), i.name.clone(), None, f.clone()),
    }
}

fn from_tuple((path, name, named, folder): InputTuple) -> Input {
    Input {
        path,
        name,
        origin: match named {
            Some(n) => Origin::Named(n),
            None => Origin::Folder(folder),
        },
    }
}

/// The recordings of a report's inputs: paths (recordings or folders of them) and named
/// datasets `(name, path)`, each as (path, name, dataset, folder).
#[pyfunction]
fn report_inputs(
    paths: Vec<PathBuf>,
    datasets: Vec<(String, PathBuf)>,
) -> PyResult<Vec<InputTuple>> {
    let inputs = pipeline::inputs::inputs(&paths, &datasets).map_err(err)?;
    Ok(inputs.iter().map(to_tuple).collect())
}

/// What [`report_sequence`] hands back: done or not, the sequence's JSON or the error's
/// message, and the files (path in the report, bytes).
type SequenceOutcome<'py> = (bool, String, Vec<(String, Bound<'py, PyBytes>)>);

/// A [`SequenceOutcome`] as it comes back to the merge.
type Outcome = (bool, String, Vec<(String, Vec<u8>)>);

/// One recording of a report, as one task of a cluster runs it: `(True, sequence JSON,
/// files)` or `(False, error message, [])`; files are (path in the report, bytes).
#[pyfunction]
fn report_sequence<'py>(
    py: Python<'py>,
    input: InputTuple,
    options: &str,
) -> PyResult<SequenceOutcome<'py>> {
    let options = report_options(options)?;
    let input = from_tuple(input);
    let outcome =
        py.detach(|| pipeline::process(&input, &options, &|_, _| {}).map_err(|e| e.to_string()));
    match outcome {
        Ok(processed) => Ok((
            true,
            json(&processed.report)?,
            processed
                .files
                .iter()
                .map(|f| (f.path.clone(), PyBytes::new(py, &f.bytes)))
                .collect(),
        )),
        Err(message) => Ok((false, message, Vec::new())),
    }
}

/// Writes a report into `out`: each input's outcome from [`report_sequence`] merged by the
/// library's merge, every file written and the folder committed whole. Returns the
/// report's JSON (`results.json`).
#[pyfunction]
#[pyo3(signature = (out, inputs, outcomes, options, command_line, protected))]
fn report_merge(
    py: Python<'_>,
    out: PathBuf,
    inputs: Vec<InputTuple>,
    outcomes: Vec<Outcome>,
    options: &str,
    command_line: Vec<String>,
    protected: Vec<PathBuf>,
) -> PyResult<String> {
    let options = report_options(options)?;
    let inputs: Vec<Input> = inputs.into_iter().map(from_tuple).collect();
    py.detach(|| -> Result<String, String> {
        let policy = output_policy(options.force, &protected, &inputs);
        policy.check_folder(&out).map_err(|e| e.to_string())?;
        let mut merged = Vec::new();
        let mut files = Vec::new();
        let mut first_error = None;
        for (input, (ok, payload, sequence_files)) in inputs.iter().zip(outcomes) {
            if ok {
                let value: serde_json::Value =
                    serde_json::from_str(&payload).map_err(|e| e.to_string())?;
                let s = pipeline::decode::sequence(&value).map_err(|e| e.to_string())?;
                files.extend(sequence_files);
                merged.push((input.clone(), Ok(s)));
            } else {
                first_error.get_or_insert_with(|| payload.clone());
                merged.push((input.clone(), Err(payload)));
            }
        }
        if merged.iter().all(|(_, o)| o.is_err())
            && let Some(e) = first_error
        {
            return Err(e);
        }
        let presets = ctcal_report::presets::simulate(options.seed).map_err(|e| e.to_string())?;
        let report = pipeline::merge(merged, presets, options.seed, command_line);
        let staged = policy.folder(&out).map_err(|e| e.to_string())?;
        for (path, bytes) in &files {
            staged.write(path, bytes).map_err(|e| e.to_string())?;
        }
        for f in ctcal_report::render_summary(&report) {
            staged.write(&f.path, &f.bytes).map_err(|e| e.to_string())?;
        }
        staged.commit().map_err(|e| e.to_string())?;
        serde_json::to_string(&report).map_err(|e| e.to_string())
    })
    .map_err(err)
}

/// Where a report may write: never over the inputs or the paths the caller protects.
fn output_policy(
    force: bool,
    protected: &[PathBuf],
    inputs: &[Input],
) -> ctcal_io::write::OutputPolicy {
    ctcal_io::write::OutputPolicy::new(force).protect_all(
        protected
            .iter()
            .map(PathBuf::as_path)
            .chain(inputs.iter().map(|i| i.path.as_path())),
    )
}

/// A report made on this machine's threads, as `ctcal report` makes it. Returns the
/// report's JSON.
#[pyfunction]
fn report_local(
    py: Python<'_>,
    out: PathBuf,
    inputs: Vec<InputTuple>,
    options: &str,
    command_line: Vec<String>,
    protected: Vec<PathBuf>,
) -> PyResult<String> {
    let options = report_options(options)?;
    let inputs: Vec<Input> = inputs.into_iter().map(from_tuple).collect();
    py.detach(|| -> Result<String, String> {
        let policy = output_policy(options.force, &protected, &inputs);
        policy.check_folder(&out).map_err(|e| e.to_string())?;
        let staged = policy.folder(&out).map_err(|e| e.to_string())?;
        let outcomes = pipeline::run(&inputs, &options, &|_, _| {}, &|f| {
            staged.write(&f.path, &f.bytes)
        })
        .map_err(|e| e.to_string())?;
        let mut merged = Vec::new();
        let mut first_error = None;
        for (input, outcome) in inputs.iter().zip(outcomes.sequences) {
            let outcome = outcome.map_err(|e| e.to_string());
            if let Err(e) = &outcome {
                first_error.get_or_insert_with(|| e.clone());
            }
            merged.push((input.clone(), outcome));
        }
        if merged.iter().all(|(_, o)| o.is_err())
            && let Some(e) = first_error
        {
            return Err(e);
        }
        let presets = outcomes.presets.map_err(|e| e.to_string())?;
        let report = pipeline::merge(merged, presets, options.seed, command_line);
        for f in ctcal_report::render_summary(&report) {
            staged.write(&f.path, &f.bytes).map_err(|e| e.to_string())?;
        }
        staged.commit().map_err(|e| e.to_string())?;
        serde_json::to_string(&report).map_err(|e| e.to_string())
    })
    .map_err(err)
}

/// `ctcal stats --json` of `path` (between `start` and `end` seconds after the first event;
/// `window_s`: the rate timeline's window, `support_window_s`: the background rate's).
#[pyfunction]
#[pyo3(signature = (path, start=None, end=None, window_s=0.01, support_window_s=0.01, format=None, sensor=None))]
#[allow(clippy::too_many_arguments)]
fn stats(
    py: Python<'_>,
    path: PathBuf,
    start: Option<f64>,
    end: Option<f64>,
    window_s: f64,
    support_window_s: f64,
    format: Option<&str>,
    sensor: Option<&str>,
) -> PyResult<String> {
    let open = open_options(format, sensor)?;
    let stats = py
        .detach(|| -> Result<_, String> {
            check_seconds(window_s, support_window_s)?;
            check_stats_window(start, end)?;
            let recording = Recording::open(&path, &open).map_err(|e| e.to_string())?;
            let windowed = start.is_some() || end.is_some();
            let origin = if windowed {
                Some(recording.first_event_time().map_err(|e| e.to_string())?)
            } else {
                None
            };
            let mut accumulator = StatsAccumulator::new(
                StatsOptions {
                    start_s: start,
                    end_s: end,
                    window_s,
                    support_window_s,
                    origin_us: origin,
                    max_pixels: Some(ctcal_core::stats::PIXEL_BUDGET),
                    ..StatsOptions::default()
                },
                recording.sensor,
            );
            let window = origin.map(|origin| (origin, start, end));
            let max_coordinates = accumulate(&recording, &mut accumulator, window)?;
            finished_stats(&recording, accumulator, max_coordinates)
        })
        .map_err(err)?;
    json(&stats)
}

/// Reads the recording's events into `accumulator` (only those from `start` to `end`
/// seconds after `origin`, the first event's time, where `window` gives them); refused
/// where the events reach beyond the per-pixel budget. Returns the largest coordinates.
fn accumulate(
    recording: &Recording,
    accumulator: &mut StatsAccumulator,
    window: Option<(ctcal_core::TimeUs, Option<f64>, Option<f64>)>,
) -> Result<Option<(u16, u16)>, String> {
    let mut stream = match window {
        Some((origin, start, end)) => {
            let at = |s: Option<f64>, default| {
                s.map_or(default, |s| origin.saturating_add((s * 1e6).round() as i64))
            };
            recording.events_between(at(start, i64::MIN), at(end, i64::MAX))
        }
        None => recording.events(),
    }
    .map_err(|e| e.to_string())?;
    let read_ahead = rayon_threads() > 1;
    ctcal_io::read_ahead::for_each_chunk(&mut stream, read_ahead, |chunk, _| {
        accumulator.add(chunk)
    })
    .map_err(|e| e.to_string())?;
    if let Some(over) = accumulator.over_budget() {
        return Err(format!(
            "{}: the events reach x = {}, y = {}: statistics of that area keep {} pixels of state, more than the budget of {} pixels\n  fix: give the camera's real sensor size (sensor=\"WxH\")",
            recording.path.display(),
            over.max_x,
            over.max_y,
            over.pixels,
            ctcal_core::stats::PIXEL_BUDGET
        ));
    }
    Ok(stream.max_coordinates())
}

/// The statistics `accumulator` gathered, on the sensor resolved from the recording and
/// `max_coordinates`, with the frame times and the biases; an error where it holds none.
fn finished_stats(
    recording: &Recording,
    accumulator: StatsAccumulator,
    max_coordinates: Option<(u16, u16)>,
) -> Result<ctcal_core::stats::SequenceStats, String> {
    let resolved = recording.resolve_sensor(max_coordinates);
    let frame_times = recording.frame_times().map_err(|e| e.to_string())?;
    let mut stats = accumulator
        .finish(resolved.sensor, &resolved.source, &frame_times)
        .ok_or_else(|| {
            format!(
                "{}: no events in the selected time window",
                recording.path.display()
            )
        })?;
    stats.biases = recording.biases();
    Ok(stats)
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

fn check_seconds(window_s: f64, support_window_s: f64) -> Result<(), String> {
    for (name, value) in [
        ("window_s", window_s),
        ("support_window_s", support_window_s),
    ] {
        if !(value.is_finite() && value > 0.0 && value <= 1e12) {
            return Err(format!(
                "{name} {value} must be a positive number of seconds up to 1e12"
            ));
        }
    }
    Ok(())
}

/// `ctcal stats` of events in memory (`sensor` "WxH", else the events' extent).
#[pyfunction]
#[pyo3(signature = (t, x, y, p, sensor=None, window_s=0.01, support_window_s=0.01))]
#[allow(clippy::too_many_arguments)]
fn stats_events(
    py: Python<'_>,
    t: PyReadonlyArray1<'_, i64>,
    x: PyReadonlyArray1<'_, u16>,
    y: PyReadonlyArray1<'_, u16>,
    p: PyReadonlyArray1<'_, u8>,
    sensor: Option<&str>,
    window_s: f64,
    support_window_s: f64,
) -> PyResult<String> {
    let sensor = sensor
        .map(|s| Sensor::parse(s).ok_or_else(|| err(format!("`{s}` is not WxH (e.g. 346x260)"))))
        .transpose()?;
    let (t, x, y, p) = (t.as_slice()?, x.as_slice()?, y.as_slice()?, p.as_slice()?);
    if x.len() != t.len() || y.len() != t.len() || p.len() != t.len() {
        return Err(err("t, x, y and p must have one value per event"));
    }
    let mut events = ctcal_core::EventChunk::default();
    for i in 0..t.len() {
        events.push(t[i], x[i], y[i], p[i] != 0);
    }
    let stats = py
        .detach(|| -> Result<_, String> {
            check_seconds(window_s, support_window_s)?;
            if events.t.windows(2).any(|w| w[1] < w[0]) {
                return Err("the events are not in time order\n  fix: sort them by t".into());
            }
            let (sensor, source) = match sensor {
                Some(s) => (s, "given".to_string()),
                None => {
                    let (mx, my) = events.max_coordinates().ok_or("no events")?;
                    (
                        Sensor {
                            width: mx + 1,
                            height: my + 1,
                        },
                        "the events' extent".to_string(),
                    )
                }
            };
            let mut accumulator = StatsAccumulator::new(
                StatsOptions {
                    window_s,
                    support_window_s,
                    max_pixels: Some(ctcal_core::stats::PIXEL_BUDGET),
                    ..StatsOptions::default()
                },
                Some(sensor),
            );
            accumulator.add(&events);
            accumulator
                .finish(sensor, &source, &[])
                .ok_or_else(|| "no events".to_string())
        })
        .map_err(err)?;
    json(&stats)
}

/// PARAMS.toml text, or the JSON of a params dict.
fn params_of(text: &str) -> Result<PixelParams, String> {
    if text.trim_start().starts_with('{') {
        let value: serde_json::Value = serde_json::from_str(text).map_err(|e| e.to_string())?;
        let toml = toml_of(&value)?;
        PixelParams::from_toml(&toml, "params").map_err(|e| e.to_string())
    } else {
        PixelParams::from_toml(text, "params").map_err(|e| e.to_string())
    }
}

/// A params dict as PARAMS.toml text (the nested `display` table included).
fn toml_of(value: &serde_json::Value) -> Result<String, String> {
    let Some(map) = value.as_object() else {
        return Err("params must be a dict of PARAMS.toml keys".into());
    };
    let scalar = |v: &serde_json::Value| -> Result<String, String> {
        match v {
            serde_json::Value::String(s) => {
                Ok(serde_json::to_string(s).map_err(|e| e.to_string())?)
            }
            serde_json::Value::Number(n) => Ok(n.to_string()),
            serde_json::Value::Bool(b) => Ok(b.to_string()),
            other => Err(format!("{other} is not a PARAMS.toml value")),
        }
    };
    let mut top = String::new();
    let mut tables = String::new();
    for (k, v) in map {
        match v {
            serde_json::Value::Null => {}
            serde_json::Value::Object(inner) => {
                tables.push_str(&format!("[{k}]\n"));
                for (ik, iv) in inner {
                    if !iv.is_null() {
                        tables.push_str(&format!("{ik} = {}\n", scalar(iv)?));
                    }
                }
            }
            _ => top.push_str(&format!("{k} = {}\n", scalar(v)?)),
        }
    }
    Ok(top + &tables)
}

/// Events of frames (uint8, `n` frames of `h` x `w`, at `times` us) through the pixel model
/// `params` (PARAMS.toml text or a params dict's JSON): t, x, y, p arrays.
#[pyfunction]
fn simulate<'py>(
    py: Python<'py>,
    pixels: PyReadonlyArray1<'py, u8>,
    n: usize,
    h: usize,
    w: usize,
    times: PyReadonlyArray1<'py, i64>,
    params: &str,
) -> PyResult<EventArrays<'py>> {
    let pixels = pixels.as_slice()?;
    let times = times.as_slice()?;
    if times.len() != n || pixels.len() != n * h * w {
        return Err(err(format!(
            "{} times for {n} frames of {w}x{h}: give one time per frame",
            times.len()
        )));
    }
    if n < 2 {
        return Err(err("needs at least two frames to simulate events"));
    }
    if times.windows(2).any(|p| p[1] <= p[0]) {
        return Err(err("the frame times must increase"));
    }
    let frames: Vec<ctcal_core::Frame> = (0..n)
        .map(|i| ctcal_core::Frame {
            t: times[i],
            width: w as u32,
            height: h as u32,
            pixels: pixels[i * h * w..(i + 1) * h * w].to_vec(),
            exposure_us: None,
        })
        .collect();
    let params = params_of(params).map_err(err)?;
    let columns = py
        .detach(|| -> Result<_, ctcal_core::sim::SimError> {
            // as `ctcal simulate --frames` replays its frames
            let mut source =
                ctcal_core::sim::source::LoadedFrames::new(frames.len(), (w, h), |i| {
                    Ok(frames[i].clone())
                });
            let mut columns = EventColumns::default();
            ctcal_core::sim::run::<ctcal_core::sim::SimError>(
                &mut source,
                &params,
                ctcal_core::sim::PixelMaps::default(),
                |chunk| {
                    columns.extend(chunk, 0..chunk.t.len());
                    Ok(())
                },
                |_| {},
            )?;
            Ok(columns)
        })
        .map_err(err)?;
    Ok(columns.into_numpy(py))
}

/// `ctcal config --format FORMAT` of a fit's JSON or a report's `results.json` text.
#[pyfunction]
fn config(text: &str, format: &str) -> PyResult<String> {
    use ctcal_report::configs::{self, ConfigFormat};
    let format = ConfigFormat::parse(format).ok_or_else(|| {
        err(format!(
            "unknown format `{format}`\n  fix: esim, esim-generator, v2e or ctcal"
        ))
    })?;
    let json: serde_json::Value = serde_json::from_str(text).map_err(err)?;
    let mut fits = configs::source::FitSet::default();
    fits.add("the fit JSON", &json).map_err(err)?;
    let setup = fits.setup("the fit JSON", None).map_err(err)?;
    configs::render(format, &fits.params, &setup).ok_or_else(|| err("no fits given"))
}

#[pymodule]
fn _ctcal(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("CtcalError", m.py().get_type::<CtcalError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("FIT_PIXELS", ctcal_io::fit_region::FIT_PIXELS)?;
    m.add("FIT_EVENTS", ctcal_io::fit_region::FIT_EVENTS)?;
    m.add_function(wrap_pyfunction!(read, m)?)?;
    m.add_function(wrap_pyfunction!(read_frames, m)?)?;
    m.add_function(wrap_pyfunction!(info, m)?)?;
    m.add_function(wrap_pyfunction!(estimate, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(stats, m)?)?;
    m.add_function(wrap_pyfunction!(stats_events, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(config, m)?)?;
    m.add_function(wrap_pyfunction!(report_inputs, m)?)?;
    m.add_function(wrap_pyfunction!(report_sequence, m)?)?;
    m.add_function(wrap_pyfunction!(report_merge, m)?)?;
    m.add_function(wrap_pyfunction!(report_local, m)?)?;
    Ok(())
}
