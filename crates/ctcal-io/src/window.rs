//! A time window of a recording in memory, as the estimators, the fit and the report take
//! it: the events of the window, its grey frames (at most a given number, evenly spread),
//! the sensor and the pixels a region or mask keeps. Warnings and reading progress go to
//! the caller's callbacks; errors are typed ([`LoadError`]) and name no command-line flag,
//! so that the `ctcal` binary and the Python package each word the fix in their own terms.

use crate::estimate::aps::{self, ApsOptions};
use crate::estimate::{CtEstimate, EstimateError, eppps, screen};
use crate::events::{EventChunk, Frame, Sensor, TimeUs, us_to_s};
use crate::frame_blocks;
use crate::hint::{Hint, Text};
use crate::selection::{PixelSelection, Roi};
use crate::sim::DisplayParams;
use crate::sim::log_response::LogMap;
use crate::{InputError, OpenOptions, Recording};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The most events a window holds in memory (about 1.3 GB).
pub const MAX_EVENTS: usize = 100_000_000;

/// A time window of a recording, in memory.
pub struct Loaded {
    pub recording: Recording,
    pub sensor: Sensor,
    pub sensor_source: String,
    pub events: EventChunk,
    pub frames: Vec<Frame>,
    /// Frames in the window before thinning to the frame limit.
    pub frames_available: usize,
    /// The frame limit the window was read with, scaled to the frames' size
    /// ([`frame_blocks::scaled_limit`]); 0 when no frames were asked for.
    pub frame_limit: usize,
    /// Spans between the blocks of frames read (see [`frame_blocks`]) whose events were not
    /// read: a pixel's change across one is unknown. Empty when the window was read whole.
    pub unread: Vec<(TimeUs, TimeUs)>,
    /// The pixels the region / mask keep.
    pub selection: PixelSelection,
    /// One flag per pixel: left out by the region / mask (what the estimators take).
    pub excluded: Vec<bool>,
    /// What `assumptions` says of the window: its frames and pixels, and
    /// [`Self::recording_notes`].
    pub notes: Vec<String>,
    /// What `assumptions` says of the recording's sensor and events whatever frames a
    /// window takes (a stated sensor given way to the events' reach, same-microsecond
    /// repeats), carried into its blocks ([`load_blocks`]).
    pub recording_notes: Vec<String>,
}

/// What to read.
#[derive(Clone, Debug, Default)]
pub struct Window {
    /// Seconds after the first event.
    pub start_s: Option<f64>,
    pub end_s: Option<f64>,
    /// Read frames at all, and at most how many (of a sensor up to
    /// [`frame_blocks::LIMIT_PIXELS`]; proportionally fewer of larger frames).
    pub frames: Option<usize>,
    /// Keep only the events between the first and last frame kept.
    pub events_between_frames: bool,
}

/// Which pixels to keep: a region and a mask file (hot pixels are left out by the caller,
/// who finds them).
#[derive(Clone, Debug, Default)]
pub struct SelectionSpec {
    pub roi: Option<Roi>,
    /// A PNG or `.npy` array of the sensor's size (H x W), non-zero = keep.
    pub mask: Option<PathBuf>,
}

/// Why a window could not be read.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error(transparent)]
    Input(#[from] InputError),
    /// A start or end that is not a time of the recording.
    #[error("{0}")]
    Window(String),
    #[error("{}: more than {max} events in the selected time window\n  fix: select a shorter part of the recording (start/end, seconds from the first event)", path.display())]
    TooManyEvents { path: PathBuf, max: usize },
    #[error("{}: the frames are {}x{} but the sensor is {sensor}\n  fix: give the sensor size {}x{} if the frames show the whole sensor", path.display(), frames.0, frames.1, frames.0, frames.1)]
    FrameSize {
        path: PathBuf,
        frames: (usize, usize),
        sensor: Sensor,
    },
    #[error("{}: the {sensor} sensor has {} pixels; the estimators keep several maps of one value per pixel, more than the budget of {} pixels\n  fix: give the camera's real sensor size (the events reach x = {}, y = {}), or force to use the memory anyway", path.display(), sensor.pixels(), crate::stats::PIXEL_BUDGET, reach.0, reach.1)]
    OverBudget {
        path: PathBuf,
        sensor: Sensor,
        /// The largest x and y of the events.
        reach: (u16, u16),
    },
    #[error("{}: a pixel selection of the {sensor} sensor keeps one flag per pixel ({} pixels), more than the budget of {} pixels\n  fix: give the camera's real sensor size, or force to use the memory anyway", path.display(), sensor.pixels(), crate::stats::PIXEL_BUDGET)]
    SelectionOverBudget { path: PathBuf, sensor: Sensor },
    #[error("{}: {problem}\n  fix: {fix}", path.display())]
    Selection {
        path: PathBuf,
        problem: Text,
        fix: Text,
    },
}

/// Checks a window's start and end (seconds from the first event).
pub fn check_window(start: Option<f64>, end: Option<f64>) -> Result<(), LoadError> {
    for (name, value) in [("start", start), ("end", end)] {
        if let Some(v) = value
            && !(v.is_finite() && (0.0..=1e12).contains(&v))
        {
            return Err(LoadError::Window(format!(
                "{name} {v} must be a number of seconds from the first event, between 0 and 1e12"
            )));
        }
    }
    if let (Some(s), Some(e)) = (start, end)
        && e <= s
    {
        return Err(LoadError::Window(format!("end {e} is not after start {s}")));
    }
    Ok(())
}

impl SelectionSpec {
    /// The region and mask for `sensor`; `input` names the recording in errors. A
    /// selection holds a flag per pixel: a sensor over the pixel budget is refused unless
    /// `force`. A selection that keeps no pixel is an error naming what emptied it.
    pub fn build(
        &self,
        sensor: Sensor,
        input: &Path,
        force: bool,
    ) -> Result<PixelSelection, LoadError> {
        if sensor.pixels() > crate::stats::PIXEL_BUDGET && !force {
            return Err(LoadError::SelectionOverBudget {
                path: input.to_path_buf(),
                sensor,
            });
        }
        let fail = |e: crate::selection::SelectionError| LoadError::Selection {
            path: input.to_path_buf(),
            problem: e.problem,
            fix: e.fix,
        };
        let mut selection = PixelSelection::all(sensor);
        if let Some(roi) = self.roi {
            selection = selection.roi(roi).map_err(fail)?;
        }
        if let Some(path) = &self.mask {
            let mask = crate::mask::read_mask(path, sensor)?;
            selection = selection
                .mask(&mask, &path.display().to_string())
                .map_err(fail)?;
        }
        Ok(selection)
    }
}

/// Refuses a pixel selection that holds none of the window's events: every estimate would
/// otherwise fail on it for a reason that is not the one (no motion, too few frames' worth
/// of events), and name a fix that does not help.
fn check_selection_has_events(
    path: &Path,
    events: &EventChunk,
    kept: &PixelSelection,
    window: &Window,
) -> Result<(), LoadError> {
    let sensor = kept.sensor();
    let inside = |x: u16, y: u16| x < sensor.width && y < sensor.height && kept.keeps(x, y);
    if kept.is_all() || events.x.iter().zip(&events.y).any(|(&x, &y)| inside(x, y)) {
        return Ok(());
    }
    let windowed = window.start_s.is_some() || window.end_s.is_some();
    Err(empty_selection(path, &kept.description(), windowed))
}

/// The error for a pixel selection (`what`: the region, the mask, ...) that holds none of
/// the events (of the time window, where `windowed`); `stats`, which streams rather than
/// loads, gives the same.
pub fn empty_selection(path: &Path, what: &str, windowed: bool) -> LoadError {
    LoadError::Selection {
        path: path.to_path_buf(),
        problem: format!(
            "no event {}lies in the selected pixels ({what})",
            if windowed { "of the time window " } else { "" },
        )
        .into(),
        fix: "select pixels where the recording has events, or leave the selection out".into(),
    }
}

/// Where a load reports what it warns of and how far it has read.
pub trait LoadObserver {
    /// A warning about the recording (sensor size guessed, an index rebuilt, ...), which
    /// may name options.
    fn warn(&self, _message: &Text) {}
    /// `done` of `total` units of the event stream read.
    fn reading(&self, _done: u64, _total: u64) {}
}

/// Passes on reading progress, not warnings.
struct ProgressOnly<'a>(&'a dyn LoadObserver);
impl LoadObserver for ProgressOnly<'_> {
    fn reading(&self, done: u64, total: u64) {
        self.0.reading(done, total);
    }
}

/// An observer that ignores everything.
pub struct Silent;
impl LoadObserver for Silent {}

/// Reads the window of the recording at `path`, and the pixels `selection` keeps. More
/// than [`MAX_EVENTS`] events, or a sensor over the pixel budget, is refused unless `force`
/// (the pixel budget only).
pub fn load(
    path: &Path,
    open: &OpenOptions,
    window: &Window,
    selection: &SelectionSpec,
    force: bool,
    observer: &dyn LoadObserver,
) -> Result<Loaded, LoadError> {
    check_window(window.start_s, window.end_s)?;
    let recording = Recording::open(path, open)?;
    for note in &recording.notes {
        observer.warn(&note.as_str().into());
    }
    let read = read_window(&recording, Source::Decode, window, observer)?;
    let (resolved, area_note) = window_sensor(&recording, &read, selection, observer);
    let sensor = resolved.sensor;
    check_sensor_fits(&recording, &read, sensor, force)?;
    let kept = selection.build(sensor, &recording.path, force)?;
    check_selection_has_events(&recording.path, &read.events, &kept, window)?;
    let mut recording_notes: Vec<String> = area_note.into_iter().collect();
    if let Some(note) = repeats_note(&read.events, sensor) {
        observer.warn(&Text::from(format!("{}: {note}", recording.path.display())));
        recording_notes.push(note);
    }
    let mut notes = notes(&read.chosen, &kept);
    notes.extend(recording_notes.iter().cloned());
    Ok(Loaded {
        excluded: kept.excluded(),
        selection: kept,
        sensor: resolved.sensor,
        sensor_source: resolved.source,
        recording,
        events: read.events,
        frames: read.chosen.frames,
        frames_available: read.chosen.available,
        frame_limit: read.chosen.limit,
        unread: read.unread,
        notes,
        recording_notes,
    })
}

/// The sensor of a window's recording, resolved from the reach of its events (and the
/// region's), with the warnings that come of it, and the note where the events' area
/// replaces the recording's sensor.
fn window_sensor(
    recording: &Recording,
    read: &WindowRead,
    selection: &SelectionSpec,
    observer: &dyn LoadObserver,
) -> (crate::recording::ResolvedSensor, Option<String>) {
    let reach = read.events.max_coordinates();
    let mut resolved = recording.resolve_sensor(reach);
    let mut area_note = None;
    if let Some((area, note)) = crate::events_area::reach_instead(
        &resolved,
        reach_with_region(reach, selection.roi),
        !read.chosen.frames.is_empty() || selection.mask.is_some(),
        &recording.path,
    ) {
        (resolved, area_note) = (area, Some(note));
    }
    if let Some(w) = &resolved.warning {
        observer.warn(w);
    }
    if let Some(w) = frames_larger_than_events(&resolved, reach, &recording.path) {
        observer.warn(&w);
    }
    (resolved, area_note)
}

/// Refuses a window whose frames are not the size of `sensor`, or whose `sensor` is over
/// the pixel budget (unless `force`).
fn check_sensor_fits(
    recording: &Recording,
    read: &WindowRead,
    sensor: Sensor,
    force: bool,
) -> Result<(), LoadError> {
    if let Some(f) = read.chosen.frames.first()
        && (f.width as u16, f.height as u16) != (sensor.width, sensor.height)
    {
        return Err(LoadError::FrameSize {
            path: recording.path.clone(),
            frames: (f.width as usize, f.height as usize),
            sensor,
        });
    }
    // the estimators keep several maps of one value per pixel
    if sensor.pixels() > crate::stats::PIXEL_BUDGET && !force {
        return Err(LoadError::OverBudget {
            path: recording.path.clone(),
            sensor,
            reach: read.events.max_coordinates().unwrap_or((0, 0)),
        });
    }
    Ok(())
}

/// The share of a window's events at which [`repeats_note`] speaks: the shared real
/// recordings have none or a few in ten thousand (the Gen3 EVT2 sample: 345 of 521,252).
const REPEATS_SHARE: f64 = 0.01;

/// What `assumptions` says where over [`REPEATS_SHARE`] of the events repeat their pixel's
/// previous event in the same microsecond.
fn repeats_note(events: &EventChunk, sensor: Sensor) -> Option<String> {
    let repeats = events.same_microsecond_repeats(sensor);
    (repeats as f64 > REPEATS_SHARE * events.len() as f64).then(|| {
        format!(
            "events: {repeats} of {} ({:.1} %) repeat their pixel's previous event in the same microsecond, and every estimate counts them as events; a camera's pixel fires at most once in its refractory period, so they come from a simulator that gives all crossings of a step one time, or from a file whose events were duplicated (then remove the copies: each is counted twice)",
            events.len(),
            100.0 * repeats as f64 / events.len() as f64
        )
    })
}

/// The largest x and y of the events, or of the region where it reaches further (the
/// region's pixels must lie on the sensor the window works on).
fn reach_with_region(events: Option<(u16, u16)>, roi: Option<Roi>) -> Option<(u16, u16)> {
    let Some(roi) = roi else { return events };
    let (x, y) = events.unwrap_or((0, 0));
    Some((x.max(roi.x1 - 1), y.max(roi.y1 - 1)))
}

/// A warning where the sensor's size comes from the grey frames and the events reach under
/// [`EVENTS_REACH`] of it across or down: frames resized (or from another camera) would
/// give every estimate the wrong active area.
fn frames_larger_than_events(
    resolved: &crate::recording::ResolvedSensor,
    reach: Option<(u16, u16)>,
    path: &Path,
) -> Option<Text> {
    let (x, y) = reach?;
    let s = resolved.sensor;
    let short = |reach: u16, side: u16| reach as f64 + 1.0 < EVENTS_REACH * side as f64;
    (resolved.source == crate::recording::FRAMES_SENSOR && (short(x, s.width) || short(y, s.height))).then(|| {
        Text::from(format!(
            "{}: the sensor size {s} comes from the grey frames, but the events reach only x < {}, y < {}: if the frames were resized or are another camera's, the estimates are off; ",
            path.display(),
            x as u32 + 1,
            y as u32 + 1
        ))
        .act(Hint::Sensor(None))
        .words(" with the event camera's size")
    })
}

/// The share of the frames' width or height the events must reach before
/// [`frames_larger_than_events`] warns.
const EVENTS_REACH: f64 = 0.8;

/// The same window as `whole` (read whole by [`load`] with `window`), in blocks of
/// consecutive frames with only the events between them ([`Window::events_between_frames`]),
/// its events taken from `whole` rather than decoded again, and its frames too where `whole`
/// holds every frame of the window (otherwise only the chosen frames are read).
pub fn load_blocks(
    whole: &Loaded,
    window: &Window,
    observer: &dyn LoadObserver,
) -> Result<Loaded, LoadError> {
    let window = Window {
        events_between_frames: true,
        ..window.clone()
    };
    let read = read_window(
        &whole.recording,
        Source::Read {
            events: &whole.events,
            frames: (whole.frames.len() == whole.frames_available).then_some(&whole.frames[..]),
        },
        &window,
        observer,
    )?;
    let mut notes = notes(&read.chosen, &whole.selection);
    notes.extend(whole.recording_notes.iter().cloned());
    Ok(Loaded {
        recording: whole.recording.clone(),
        sensor: whole.sensor,
        sensor_source: whole.sensor_source.clone(),
        events: read.events,
        frames: read.chosen.frames,
        frames_available: read.chosen.available,
        frame_limit: read.chosen.limit,
        unread: read.unread,
        selection: whole.selection.clone(),
        excluded: whole.excluded.clone(),
        notes,
        recording_notes: whole.recording_notes.clone(),
    })
}

/// What a window says in `assumptions`: how its frames were chosen, which pixels it keeps.
fn notes(chosen: &ChosenFrames, selection: &PixelSelection) -> Vec<String> {
    let mut notes: Vec<String> = chosen.note.iter().cloned().collect();
    if !selection.is_all() {
        notes.push(format!("pixels: {}", selection.description()));
    }
    notes
}

/// Where a window's events and frames come from: decoded from the recording, or already
/// read (`frames`: every frame of the window, in the recording's order, where they were all
/// read).
#[derive(Clone, Copy)]
enum Source<'a> {
    Decode,
    Read {
        events: &'a EventChunk,
        frames: Option<&'a [Frame]>,
    },
}

/// A window's frames and events, before the sensor is resolved.
struct WindowRead {
    chosen: ChosenFrames,
    unread: Vec<(TimeUs, TimeUs)>,
    events: EventChunk,
}

/// The frames `window` chooses and the events of its span (outside the spans between
/// frame blocks), from `source`.
fn read_window(
    recording: &Recording,
    source: Source,
    window: &Window,
    observer: &dyn LoadObserver,
) -> Result<WindowRead, LoadError> {
    // the first event fixes the clock of start/end
    let first = recording.first_event_time()?;
    let to_us = |s: f64| first + (s * 1e6).round() as TimeUs;
    let (mut from, mut to) = (
        window.start_s.map_or(TimeUs::MIN, to_us),
        window.end_s.map_or(TimeUs::MAX, to_us),
    );
    let chosen = match window.frames {
        Some(max_frames) => choose_frames(
            recording,
            source,
            window,
            max_frames,
            (from, to),
            first,
            observer,
        )?,
        None => ChosenFrames::default(),
    };
    let between_frames = window.events_between_frames && chosen.frames.len() >= 2;
    if between_frames {
        from = from.max(chosen.frames[0].t);
        to = to.min(chosen.frames[chosen.frames.len() - 1].t);
    }
    let unread: Vec<(TimeUs, TimeUs)> =
        chosen.blocks.windows(2).map(|w| (w[0].1, w[1].0)).collect();
    let events = read_events(recording, source, (from, to), &unread, observer)?;
    if events.is_empty() {
        return Err(no_events_error(
            recording,
            window,
            between_frames,
            (from, to),
            first,
        ));
    }
    Ok(WindowRead {
        chosen,
        unread,
        events,
    })
}

/// Why a window read no event in `[from, to]`: frames and events on different clocks, where
/// no window was asked for and only the frames' span was read; otherwise an empty window.
fn no_events_error(
    recording: &Recording,
    window: &Window,
    between_frames: bool,
    (from, to): (TimeUs, TimeUs),
    first: TimeUs,
) -> LoadError {
    if between_frames && window.start_s.is_none() && window.end_s.is_none() {
        // no window was asked for: the frames' span held none of the events
        return InputError::invalid(
            &recording.path,
            format!(
                "no event lies between the first and the last frame: the frames span {:.6} s .. {:.6} s of the file's clock and the first event is at {:.6} s, so frames and events are not on one clock or in one unit",
                us_to_s(from),
                us_to_s(to),
                us_to_s(first)
            ),
            "check that the frames' and the events' times are seconds of the same clock",
        )
        .into();
    }
    InputError::EmptyWindow {
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
    .into()
}

/// Calls `each` on the chunks of events from `source` that reach into `[from, to]`, in time
/// order (a chunk may hold events outside it), until one passes `to`.
fn each_chunk(
    recording: &Recording,
    source: Source,
    (from, to): (TimeUs, TimeUs),
    observer: &dyn LoadObserver,
    mut each: impl FnMut(&EventChunk) -> Result<(), LoadError>,
) -> Result<(), LoadError> {
    let mut stream = match source {
        Source::Read { events, .. } => return each(events),
        Source::Decode => recording.events_between(from, to)?,
    };
    for note in &stream.notes {
        observer.warn(&note.as_str().into());
    }
    while stream.next_chunk()?.is_some() {
        let chunk = stream.current_chunk();
        each(chunk)?;
        let progress = stream.progress();
        observer.reading(progress.done, progress.total);
        if chunk.t.last().is_some_and(|&t| t > to) {
            // the events read must be in order even where the reading stops early
            stream.check_order()?;
            break;
        }
    }
    Ok(())
}

/// The frames a window reads: all of them, every k-th, or blocks of consecutive frames
/// ([`frame_blocks`]).
#[derive(Default)]
struct ChosenFrames {
    frames: Vec<Frame>,
    /// Frames in the window before the choice.
    available: usize,
    /// The frame limit applied (scaled to the frames' size).
    limit: usize,
    /// First and last frame time of each block (empty unless read in blocks).
    blocks: Vec<(TimeUs, TimeUs)>,
    /// What the choice says in `assumptions`.
    note: Option<String>,
}

/// At most `max_frames` of the frames in `[from, to]` (fewer of frames larger than
/// [`frame_blocks::LIMIT_PIXELS`]: [`frame_blocks::scaled_limit`]), evenly thinned or in
/// blocks (the latter only where the window keeps just the events between its frames).
fn choose_frames(
    recording: &Recording,
    source: Source,
    window: &Window,
    max_frames: usize,
    (from, to): (TimeUs, TimeUs),
    first: TimeUs,
    observer: &dyn LoadObserver,
) -> Result<ChosenFrames, LoadError> {
    let times = recording.frame_times()?;
    let inside: Vec<usize> = (0..times.len())
        .filter(|&i| times[i] >= from && times[i] <= to)
        .collect();
    let inside_times: Vec<TimeUs> = inside.iter().map(|&i| times[i]).collect();
    let mut chosen = ChosenFrames {
        available: inside.len(),
        ..Default::default()
    };
    let (max_frames, scaled_note) = scaled_frame_limit(recording, &inside, max_frames)?;
    chosen.limit = max_frames;
    let keep = kept_frames(
        recording,
        source,
        window,
        (&inside, &inside_times),
        first,
        observer,
        &mut chosen,
    )?;
    chosen.frames = frames_kept(recording, source, (&inside, &inside_times), &keep)?;
    if let (Some(scaled), Some(note)) = (scaled_note, chosen.note.as_mut()) {
        *note = format!("{scaled}: {note}");
    }
    Ok(chosen)
}

/// The frame limit `given`, scaled to the size of the window's frames (`inside`: their
/// indices in the recording) by [`frame_blocks::scaled_limit`], and what `assumptions`
/// says where the scaled limit is lower.
fn scaled_frame_limit(
    recording: &Recording,
    inside: &[usize],
    given: usize,
) -> Result<(usize, Option<String>), LoadError> {
    // a larger sensor's frames count for more (only where the limit could bind)
    let max_frames = match inside.first() {
        Some(&i) if inside.len() > frame_blocks::MIN_SCALED_FRAMES.min(given) => {
            let pixels = recording.frame_pixels(i)?.unwrap_or(0);
            frame_blocks::scaled_limit(given, pixels)
        }
        _ => given,
    };
    let scaled_note = (max_frames < given).then(|| {
        format!(
            "the frame limit of {given} is for sensors up to 346x260 pixels; these frames are larger, so at most {max_frames} of them (the same frame pixels, at least {} frames)",
            frame_blocks::MIN_SCALED_FRAMES.min(given)
        )
    });
    Ok((max_frames, scaled_note))
}

/// The recording's indices of the frames kept of the window's frames (`inside`, at
/// `inside_times`) under the limit `chosen.limit`: all, every k-th, or blocks of
/// consecutive frames (the latter only where the window keeps just the events between its
/// frames); the choice's note (and blocks) go into `chosen`.
fn kept_frames(
    recording: &Recording,
    source: Source,
    window: &Window,
    (inside, inside_times): (&[usize], &[TimeUs]),
    first: TimeUs,
    observer: &dyn LoadObserver,
    chosen: &mut ChosenFrames,
) -> Result<BTreeSet<usize>, LoadError> {
    let max_frames = chosen.limit;
    Ok(match frame_blocks::plan(inside_times, max_frames) {
        frame_blocks::Plan::Blocks { step } if window.events_between_frames => kept_in_blocks(
            recording,
            source,
            (inside, inside_times),
            step,
            first,
            observer,
            chosen,
        )?,
        frame_blocks::Plan::All => inside.iter().copied().collect(),
        frame_blocks::Plan::Stride(_) | frame_blocks::Plan::Blocks { .. } => {
            let stride = inside.len().div_ceil(max_frames.max(2)).max(1);
            chosen.note = Some(format!(
                "every {stride}th of the {} frames used ({} frames; the frame limit is {max_frames})",
                inside.len(),
                inside.len().div_ceil(stride)
            ));
            inside.iter().step_by(stride).copied().collect()
        }
    })
}

/// The recording's indices of the frames kept in blocks of consecutive frames, thinned to
/// every `step`-th and chosen on the events between them ([`frame_blocks::choose`], under
/// the limit `chosen.limit`); the blocks' spans and note go into `chosen`.
fn kept_in_blocks(
    recording: &Recording,
    source: Source,
    (inside, inside_times): (&[usize], &[TimeUs]),
    step: usize,
    first: TimeUs,
    observer: &dyn LoadObserver,
    chosen: &mut ChosenFrames,
) -> Result<BTreeSet<usize>, LoadError> {
    let counts = interval_counts(recording, source, inside_times, observer)?;
    let thinned: Vec<usize> = (0..inside.len()).step_by(step).collect();
    let blocks = frame_blocks::choose(&frame_blocks::thinned_counts(&counts, step), chosen.limit);
    let times_of: Vec<TimeUs> = thinned.iter().map(|&k| inside_times[k]).collect();
    chosen.note = Some(blocks_note(&blocks, &times_of, (step, inside.len()), first));
    chosen.blocks = blocks
        .iter()
        .map(|&(a, b)| (times_of[a], times_of[b]))
        .collect();
    Ok(blocks
        .iter()
        .flat_map(|&(a, b)| thinned[a..=b].iter().map(|&k| inside[k]))
        .collect())
}

/// The frames `keep` of the window's frames (`inside`, at `inside_times`): those `source`
/// already read where they are the window's, in the order of `inside` (checked by their
/// times); read from the recording otherwise.
fn frames_kept(
    recording: &Recording,
    source: Source,
    (inside, inside_times): (&[usize], &[TimeUs]),
    keep: &BTreeSet<usize>,
) -> Result<Vec<Frame>, LoadError> {
    Ok(match source {
        Source::Read {
            frames: Some(read), ..
        } if read.len() == inside.len()
            && read.iter().zip(inside_times).all(|(f, &t)| f.t == t) =>
        {
            inside
                .iter()
                .zip(read)
                .filter(|(i, _)| keep.contains(i))
                .map(|(_, frame)| frame.clone())
                .collect()
        }
        _ => recording.frames_where(|i, _| keep.contains(&i))?,
    })
}

/// The events in `[from, to]` outside the `unread` spans, at most [`MAX_EVENTS`].
fn read_events(
    recording: &Recording,
    source: Source,
    (from, to): (TimeUs, TimeUs),
    unread: &[(TimeUs, TimeUs)],
    observer: &dyn LoadObserver,
) -> Result<EventChunk, LoadError> {
    let mut events = EventChunk::default();
    each_chunk(recording, source, (from, to), observer, |chunk| {
        let lo = chunk.t.partition_point(|&t| t < from);
        let hi = chunk.t.partition_point(|&t| t <= to);
        for i in lo..hi.max(lo) {
            if !in_unread(unread, chunk.t[i]) {
                events.push(chunk.t[i], chunk.x[i], chunk.y[i], chunk.on[i]);
            }
        }
        if events.len() > MAX_EVENTS {
            return Err(LoadError::TooManyEvents {
                path: recording.path.clone(),
                max: MAX_EVENTS,
            });
        }
        Ok(())
    })?;
    Ok(events)
}

/// Whether `t` lies strictly inside one of the `unread` spans (time-sorted).
fn in_unread(unread: &[(TimeUs, TimeUs)], t: TimeUs) -> bool {
    let k = unread.partition_point(|&(_, end)| end <= t);
    unread.get(k).is_some_and(|&(start, _)| t > start)
}

/// The events between each pair of neighbouring `times` (sorted), counted in one pass over
/// the events of their span (none kept).
fn interval_counts(
    recording: &Recording,
    source: Source,
    times: &[TimeUs],
    observer: &dyn LoadObserver,
) -> Result<Vec<u64>, LoadError> {
    let mut counts = vec![0u64; times.len().saturating_sub(1)];
    let (from, to) = (times[0], times[times.len() - 1]);
    let mut k = 0;
    // the window's own read warns of the stream's notes
    let quiet = ProgressOnly(observer);
    each_chunk(recording, source, (from, to), &quiet, |chunk| {
        let lo = chunk.t.partition_point(|&t| t < from);
        for &t in &chunk.t[lo..] {
            if t >= to {
                break;
            }
            while times[k + 1] <= t {
                k += 1;
            }
            counts[k] += 1;
        }
        Ok(())
    })?;
    Ok(counts)
}

/// What the blocks' choice says in `assumptions`: `chosen` ranges of `times` (the frames
/// thinned to every `step`-th of `all`).
fn blocks_note(
    chosen: &[(usize, usize)],
    times: &[TimeUs],
    (step, all): (usize, usize),
    first: TimeUs,
) -> String {
    let used: usize = chosen.iter().map(|&(a, b)| b - a + 1).sum();
    let read: TimeUs = chosen.iter().map(|&(a, b)| times[b] - times[a]).sum();
    let total = times[times.len() - 1] - times[0];
    let spans: Vec<String> = chosen
        .iter()
        .map(|&(a, b)| {
            format!(
                "{:.2}-{:.2} s",
                us_to_s(times[a] - first),
                us_to_s(times[b] - first)
            )
        })
        .collect();
    let thinning = if step > 1 {
        format!(
            ", every {step}th frame (frames at most {} ms apart)",
            frame_blocks::MAX_SPACING_US / 1000
        )
    } else {
        String::new()
    };
    format!(
        "measured on {} blocks of consecutive frames{thinning} ({used} of {all} frames, {:.1} % of the frames' time span: {}): every frame thinned evenly to the frame limit would lie more than {} ms apart, too far for the optical flow; one block in each equal part of the recording, each where its part holds the most events (an interval's events counted up to the 75th percentile of the intervals with events); only these blocks' frames and events were kept, the rest of the recording is not measured",
        chosen.len(),
        100.0 * read as f64 / total.max(1) as f64,
        spans.join(", "),
        frame_blocks::MAX_SPACING_US / 1000
    )
}

/// The `eppps` estimate of a window: its frames, where there are and they prepare as for
/// `aps`, give the scene's dynamics.
pub fn eppps_of(
    loaded: &Loaded,
    options: &ApsOptions,
    eppps_options: eppps::EpppsOptions,
    progress: crate::estimate::Progress,
) -> Result<CtEstimate, EstimateError> {
    let excluded = &loaded.excluded;
    let mut notes = loaded.notes.clone();
    // frames, when there are and they are wanted, prepared as for `aps`
    let prepared = if loaded.frames.len() >= 2 {
        match aps::prepare(&loaded.aps_input(), excluded, options) {
            Ok(p) => {
                notes.extend(p.assumptions.iter().cloned());
                // a response the events could not choose is tried both ways
                let known = !options.choose_response
                    || options.frame_offset_dn.is_some()
                    || (p.offset.is_some() && p.other_response.is_none());
                let fitted = options.frame_offset_dn.is_none()
                    && p.offset.as_ref().is_some_and(|o| o.source == "fitted");
                if known && !fitted && options.frame_offset_dn.is_none() && p.offset.is_some() {
                    notes.push(eppps::OFFSET_NOT_BRACKETED.to_string());
                }
                Some((p.frames, known, fitted))
            }
            Err(e) => {
                notes.push(format!("frames not used for the dynamics: {}", e.problem));
                None
            }
        }
    } else {
        None
    };
    let mut estimate = eppps::estimate(
        &eppps::EpppsInput {
            sensor: loaded.sensor,
            events: &loaded.events,
            frames: prepared.as_ref().map(|(f, _, _)| f),
            response_known: prepared.as_ref().is_some_and(|(_, known, _)| *known),
            offset_fitted: prepared.as_ref().is_some_and(|(_, _, fitted)| *fitted),
            excluded,
            frame_images: &loaded.frames,
        },
        &eppps_options,
        progress,
    )?;
    estimate.assumptions.extend(notes);
    estimate.span_events(&loaded.events);
    Ok(estimate)
}

/// The `screen` estimate of a window recorded while `stimulus` played on `screen` (a
/// measured screen model; `None`: [`default_screen`], with the gamma of displays in use),
/// through the sensor's declared log response (`None`: not declared, both candidates
/// fitted; see [`screen::ResponsePrior`]).
pub fn screen_of(
    loaded: &Loaded,
    stimulus: &[Frame],
    (screen, response): (Option<DisplayParams>, Option<LogMap>),
    refresh_hz: Option<f64>,
    progress: crate::estimate::Progress,
) -> Result<CtEstimate, EstimateError> {
    let mut estimate = screen::estimate(
        &screen::ScreenInput {
            sensor: loaded.sensor,
            events: &loaded.events,
            stimulus,
            gamma_prior: match &screen {
                Some(measured) => screen::GammaPrior::Measured(measured.gamma),
                None => screen::GammaPrior::Displays,
            },
            screen: screen.unwrap_or_else(default_screen),
            response: match response {
                Some(log) => screen::ResponsePrior::Declared(log),
                None => screen::ResponsePrior::Unknown,
            },
            refresh_hz,
            excluded: &loaded.excluded,
        },
        progress,
    )?;
    estimate.assumptions.extend(loaded.notes.iter().cloned());
    estimate.span_events(&loaded.events);
    Ok(estimate)
}

/// The built-in screen model (a typical 60 Hz LCD), for recordings of an on-screen
/// stimulus when no model is given.
pub fn default_screen() -> DisplayParams {
    const DEFAULT_SCREEN: &str = include_str!("../../../calib/screens/lcd_60hz_srgb.toml");
    DisplayParams::from_toml(DEFAULT_SCREEN, "the built-in 60 Hz LCD model")
        .expect("the built-in screen model is valid")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_times_strictly_between_blocks_are_unread() {
        let unread = [(100, 200), (300, 400)];
        let read: Vec<TimeUs> = [0, 100, 150, 200, 250, 300, 399, 400, 500]
            .into_iter()
            .filter(|&t| !in_unread(&unread, t))
            .collect();
        assert_eq!(read, vec![0, 100, 200, 250, 300, 400, 500]);
        assert!(!in_unread(&[], 7));
    }

    /// 75 frames at 25 Hz under a limit of 60: three blocks of consecutive frames; under 100:
    /// all of them. Taken from the events (and frames) of the whole window already read, they
    /// are the blocks a second decoding reads.
    #[test]
    fn blocks_from_the_whole_window_are_the_blocks_decoded_again() {
        use crate::write::{IjrrWriter, OutputPolicy};
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rec");
        let sensor = Sensor::new(16, 12);
        let mut writer = IjrrWriter::create(&path, sensor, &OutputPolicy::default()).unwrap();
        let mut events = EventChunk::default();
        // busier in the middle second, so that the blocks' choice has something to choose
        for k in 0..30_000i64 {
            let t = k * 100 + (k % 7) * 3;
            let busy = (1_000_000..2_000_000).contains(&t) || k % 3 == 0;
            if busy {
                events.push(t, (k % 16) as u16, ((k / 16) % 12) as u16, k % 2 == 0);
            }
        }
        writer.write_events(&events).unwrap();
        for f in 0..75i64 {
            writer
                .write_frame(&Frame {
                    t: 20_000 + f * 40_000,
                    width: 16,
                    height: 12,
                    pixels: vec![(f * 3) as u8; 16 * 12],
                    exposure_us: None,
                })
                .unwrap();
        }
        writer.finish().unwrap();
        // under the limit of 60 the whole window holds every other frame (its frames for the
        // blocks are read from disk); under 100 it holds them all (taken from memory)
        for limit in [60, 100] {
            let window = Window {
                start_s: None,
                end_s: None,
                frames: Some(limit),
                events_between_frames: false,
            };
            let load_with = |between: bool| {
                load(
                    &path,
                    &OpenOptions::default(),
                    &Window {
                        events_between_frames: between,
                        ..window.clone()
                    },
                    &SelectionSpec::default(),
                    false,
                    &Silent,
                )
                .unwrap()
            };
            let decoded = load_with(true);
            let whole = load_with(false);
            assert_eq!(whole.frames.len() == 75, limit == 100);
            let taken = load_blocks(&whole, &window, &Silent).unwrap();
            assert_eq!(
                decoded.unread.is_empty(),
                limit == 100,
                "{:?}",
                decoded.notes
            );
            assert_eq!(taken.unread, decoded.unread);
            assert_eq!(taken.events.t, decoded.events.t);
            assert_eq!(taken.events.x, decoded.events.x);
            assert_eq!(taken.events.on, decoded.events.on);
            let frames = |l: &Loaded| {
                l.frames
                    .iter()
                    .map(|f| (f.t, f.pixels.clone()))
                    .collect::<Vec<_>>()
            };
            assert_eq!(frames(&taken), frames(&decoded));
            assert_eq!(taken.notes, decoded.notes);
            assert_eq!(taken.frames_available, 75);
            assert!(taken.events.len() < whole.events.len());
        }
    }
}
