//! Reading a recording for the estimators and the fit: the events of a time window in
//! memory, and the grey frames of that window (at most `max_frames`, evenly spread).

use super::{BadInput, Global, InputArgs, SelectionArgs, progress_bar, warn};
use ctcal::events::{EventChunk, Frame, Sensor, TimeUs, us_to_s};
use ctcal::{InputError, Recording};

/// The most events an estimate holds in memory (about 1.3 GB).
const MAX_EVENTS: usize = 100_000_000;

/// A time window of a recording, in memory.
pub struct Loaded {
    pub recording: Recording,
    pub sensor: Sensor,
    pub sensor_source: String,
    pub events: EventChunk,
    pub frames: Vec<Frame>,
    /// Frames in the window before thinning to `max_frames`.
    pub frames_available: usize,
    /// The pixels `--roi` / `--mask` keep.
    pub selection: ctcal::selection::PixelSelection,
    /// One flag per pixel: left out by `--roi` / `--mask` (what the estimators take).
    pub excluded: Vec<bool>,
    pub notes: Vec<String>,
}

/// What to read.
pub struct Window {
    /// Seconds after the first event.
    pub start_s: Option<f64>,
    pub end_s: Option<f64>,
    /// Read frames at all, and at most how many.
    pub frames: Option<usize>,
    /// Keep only the events between the first and last frame kept.
    pub events_between_frames: bool,
}

/// Checks `--start`/`--end` as `stats` does.
pub fn check_window(start: Option<f64>, end: Option<f64>) -> Result<(), BadInput> {
    for (name, value) in [("--start", start), ("--end", end)] {
        if let Some(v) = value
            && !(v.is_finite() && (0.0..=1e12).contains(&v))
        {
            return Err(BadInput(format!(
                "{name} {v} must be a number of seconds from the first event, between 0 and 1e12"
            )));
        }
    }
    if let (Some(s), Some(e)) = (start, end)
        && e <= s
    {
        return Err(BadInput(format!("--end {e} is not after --start {s}")));
    }
    Ok(())
}

/// Reads `input` for an estimate, and the pixels `selection` keeps.
pub fn load(
    input: &InputArgs,
    window: &Window,
    selection: &SelectionArgs,
    global: &Global,
) -> anyhow::Result<Loaded> {
    check_window(window.start_s, window.end_s)?;
    let recording = Recording::open(&input.input, &input.open_options())?;
    for note in &recording.notes {
        warn(global, note);
    }
    // the first event fixes the clock of --start/--end
    let first = recording.first_event_time()?;
    let to_us = |s: f64| first + (s * 1e6).round() as TimeUs;
    let (mut from, mut to) = (
        window.start_s.map_or(TimeUs::MIN, to_us),
        window.end_s.map_or(TimeUs::MAX, to_us),
    );
    let mut notes = Vec::new();
    let mut frames = Vec::new();
    let mut frames_available = 0;
    if let Some(max_frames) = window.frames {
        let times = recording.frame_times()?;
        let inside: Vec<usize> = (0..times.len())
            .filter(|&i| times[i] >= from && times[i] <= to)
            .collect();
        frames_available = inside.len();
        let stride = inside.len().div_ceil(max_frames.max(2)).max(1);
        let keep: std::collections::BTreeSet<usize> =
            inside.iter().step_by(stride).copied().collect();
        if stride > 1 {
            notes.push(format!(
                "every {stride}th of the {} frames used ({} frames; --max-frames sets the limit)",
                inside.len(),
                keep.len()
            ));
        }
        frames = recording.frames_where(|i, _| keep.contains(&i))?;
        if window.events_between_frames && frames.len() >= 2 {
            from = from.max(frames[0].t);
            to = to.min(frames[frames.len() - 1].t);
        }
    }
    let mut stream = recording.events_between(from, to)?;
    for note in &stream.notes {
        warn(global, note);
    }
    let bar = progress_bar(global, stream.progress().total, "reading events");
    let mut events = EventChunk::default();
    while stream.next_chunk()?.is_some() {
        let chunk = stream.current_chunk();
        let lo = chunk.t.partition_point(|&t| t < from);
        let hi = chunk.t.partition_point(|&t| t <= to);
        for i in lo..hi.max(lo) {
            events.push(chunk.t[i], chunk.x[i], chunk.y[i], chunk.on[i]);
        }
        let past_window = chunk.t.last().is_some_and(|&t| t > to);
        if events.len() > MAX_EVENTS {
            return Err(BadInput(format!(
                "{}: more than {MAX_EVENTS} events in the selected time window\n  fix: select a shorter part of the recording with --start/--end (seconds from the first event)",
                recording.path.display()
            ))
            .into());
        }
        bar.set_position(stream.progress().done);
        if past_window {
            break;
        }
    }
    bar.finish_and_clear();
    if events.is_empty() {
        return Err(InputError::EmptyWindow {
            path: recording.path.clone(),
            detail: format!(
                "{:.6} s .. {:.6} s",
                us_to_s(from.max(first) - first),
                if to == TimeUs::MAX {
                    f64::INFINITY
                } else {
                    us_to_s(to - first)
                }
            ),
        }
        .into());
    }
    let resolved = recording.resolve_sensor(events.max_coordinates());
    if let Some(w) = &resolved.warning {
        warn(global, w);
    }
    if let Some(f) = frames.first()
        && (f.width as u16, f.height as u16) != (resolved.sensor.width, resolved.sensor.height)
    {
        return Err(BadInput(format!(
            "{}: the frames are {}x{} but the sensor is {}\n  fix: pass --sensor {}x{} if the frames show the whole sensor",
            recording.path.display(),
            f.width,
            f.height,
            resolved.sensor,
            f.width,
            f.height
        ))
        .into());
    }
    // the estimators keep several maps of one value per pixel
    let sensor = resolved.sensor;
    if sensor.pixels() > ctcal::stats::PIXEL_BUDGET && !global.force {
        let (max_x, max_y) = events.max_coordinates().unwrap_or((0, 0));
        return Err(BadInput(format!(
            "{}: the {sensor} sensor has {} pixels; the estimators keep several maps of one value per pixel, more than the budget of {} pixels\n  fix: pass --sensor WxH with the camera's real size (the events reach x = {max_x}, y = {max_y}), or --force to use the memory anyway",
            recording.path.display(),
            sensor.pixels(),
            ctcal::stats::PIXEL_BUDGET,
        ))
        .into());
    }
    let kept = selection.build(sensor, &recording.path, global.force)?;
    if !kept.is_all() {
        notes.push(format!("pixels: {}", kept.description()));
    }
    Ok(Loaded {
        excluded: kept.excluded(),
        selection: kept,
        sensor: resolved.sensor,
        sensor_source: resolved.source,
        recording,
        events,
        frames,
        frames_available,
        notes,
    })
}
