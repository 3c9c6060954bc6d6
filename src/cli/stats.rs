//! `ctcal stats`: event statistics of a recording (see `ctcal::stats`).

use super::{
    BadInput, Global, InputArgs, JsonTarget, SelectionArgs, check_json, emit_json, output,
    progress_bar, warn,
};
use clap::Args;
use ctcal::Recording;
use ctcal::stats::{SequenceStats, StatsAccumulator, StatsOptions};
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct StatsArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Write the statistics as JSON to PATH (`-` for stdout).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
    /// Only events from S seconds after the first event.
    #[arg(long, value_name = "S")]
    pub start: Option<f64>,
    /// Only events up to S seconds after the first event.
    #[arg(long, value_name = "S")]
    pub end: Option<f64>,
    /// Rate-timeline window in seconds.
    #[arg(long, value_name = "S", default_value_t = 0.01)]
    pub window: f64,
    /// Background activity: an event is supported (not noise) when one of its 8 neighbours
    /// fired within this many seconds before it.
    #[arg(long, value_name = "S", default_value_t = 0.01)]
    pub support_window: f64,
    /// Accept timestamps that go backwards and sort the events (in memory).
    #[arg(long)]
    pub sort: bool,
    #[command(flatten)]
    pub selection: SelectionArgs,
}

/// The longest span, in seconds, a time option may give (any recording is shorter; the
/// limit keeps every time in microseconds far from overflow).
const MAX_SECONDS: f64 = 1e12;

pub fn run(args: &StatsArgs, global: &Global) -> anyhow::Result<()> {
    for (name, value) in [
        ("--window", args.window),
        ("--support-window", args.support_window),
    ] {
        if !(value.is_finite() && value > 0.0 && value <= MAX_SECONDS) {
            return Err(BadInput(format!(
                "{name} {value} must be a positive number of seconds up to {MAX_SECONDS:e}"
            ))
            .into());
        }
    }
    for (name, value) in [("--start", args.start), ("--end", args.end)] {
        if let Some(v) = value
            && !(v.is_finite() && (0.0..=MAX_SECONDS).contains(&v))
        {
            return Err(BadInput(format!(
                "{name} {v} must be a number of seconds from the first event, between 0 and {MAX_SECONDS:e}\n  fix: give {name} in seconds from the first event"
            ))
            .into());
        }
    }
    if let (Some(s), Some(e)) = (args.start, args.end)
        && e < s
    {
        return Err(BadInput(format!(
            "--end {e} is before --start {s}\n  fix: give an --end after --start (both in seconds from the first event)"
        ))
        .into());
    }
    let policy = global.outputs([args.input.input.as_path()]);
    check_json(args.json.as_deref(), &policy)?;
    let recording = Recording::open(&args.input.input, &args.input.open_options())?;
    for note in &recording.notes {
        warn(global, note);
    }
    let mut stats = compute(&recording, args, global)?;
    stats.biases = recording.biases();
    if let Some(note) = &stats.rate_window_note {
        warn(
            global,
            &format!(
                "--window {} s: {note} (rate_window_s in the JSON)\n  fix: for finer windows, select a shorter span with --start/--end",
                args.window
            ),
        );
    }
    let target = args.json.as_deref().map(JsonTarget::parse);
    if let Some(target) = &target {
        emit_json(&stats, target, &policy)?;
    }
    if !matches!(target, Some(JsonTarget::Stdout)) {
        print_human(&stats)?;
    }
    Ok(())
}

fn compute(
    recording: &Recording,
    args: &StatsArgs,
    global: &Global,
) -> anyhow::Result<SequenceStats> {
    let mut options = StatsOptions {
        start_s: args.start,
        end_s: args.end,
        window_s: args.window,
        support_window_s: args.support_window,
        // --force: per-pixel state beyond the budget
        max_pixels: (!global.force).then_some(ctcal::stats::PIXEL_BUDGET),
        ..StatsOptions::default()
    };
    if !args.selection.is_set() {
        return pass(recording, options, args, global);
    }
    // a selection needs the sensor first: infer it in a first pass when the file is silent
    let sensor = match recording.sensor {
        Some(sensor) => sensor,
        None => {
            let mut stream = recording.events()?;
            stream.allow_unsorted = args.sort;
            while stream.next_chunk()?.is_some() {}
            let resolved = recording.resolve_sensor(stream.max_coordinates());
            if let Some(w) = &resolved.warning {
                warn(global, &super::flags::render(w));
            }
            resolved.sensor
        }
    };
    let selection = args
        .selection
        .build(sensor, &recording.path, global.force)?;
    options.selection = Some(selection.clone());
    if !args.selection.exclude_hot_pixels {
        return pass(recording, options, args, global);
    }
    // hot pixels: found by a first pass over the selection, then left out
    let first = pass(recording, options.clone(), args, global)?;
    let hot = first.hot_pixels;
    options.selection = Some(selection.without(hot.iter().map(|h| (h.x, h.y)), "hot pixels"));
    let mut stats = pass(recording, options, args, global)?;
    stats.excluded_hot_pixels = hot;
    Ok(stats)
}

/// One statistics pass over the recording.
fn pass(
    recording: &Recording,
    options: StatsOptions,
    args: &StatsArgs,
    global: &Global,
) -> anyhow::Result<SequenceStats> {
    let mut options = options;
    // a time window: seek to it where the file has an index (DSEC, MVSEC)
    let windowed = !args.sort && (args.start.is_some() || args.end.is_some());
    let origin = if windowed {
        Some(recording.first_event_time()?)
    } else {
        None
    };
    options.origin_us = origin;
    let mut accumulator = StatsAccumulator::new(options, recording.sensor);
    let max_coordinates = if args.sort {
        let all = recording.read_all(true)?;
        accumulator.add(&all);
        all.max_coordinates()
    } else {
        stream_into(&mut accumulator, recording, origin, args, global)?
    };
    if let Some(over) = accumulator.over_budget() {
        return Err(BadInput(over_budget_message(recording, over)).into());
    }
    finish(accumulator, recording, max_coordinates, args, global)
}

/// Streams the recording's events (those between `--start` and `--end` where `origin`,
/// the first event's time, is given) into `accumulator`, with a progress bar; returns the
/// largest coordinates read.
fn stream_into(
    accumulator: &mut StatsAccumulator,
    recording: &Recording,
    origin: Option<ctcal::events::TimeUs>,
    args: &StatsArgs,
    global: &Global,
) -> anyhow::Result<Option<(u16, u16)>> {
    let mut stream = match origin {
        Some(origin) => {
            let at = |s: Option<f64>, default| {
                s.map_or(default, |s| origin.saturating_add((s * 1e6).round() as i64))
            };
            recording.events_between(at(args.start, i64::MIN), at(args.end, i64::MAX))?
        }
        None => recording.events()?,
    };
    for note in &stream.notes {
        warn(global, note);
    }
    let bar = progress_bar(global, stream.progress().total, "reading");
    let read_ahead = rayon::current_num_threads() > 1;
    ctcal::io::read_ahead::for_each_chunk(&mut stream, read_ahead, |chunk, progress| {
        accumulator.add(chunk);
        bar.set_position(progress.done);
    })?;
    bar.finish_and_clear();
    Ok(stream.max_coordinates())
}

/// The statistics of what `accumulator` read, on the sensor resolved from the recording
/// and `max_coordinates` (with its frame times); an error where the window held no events.
fn finish(
    accumulator: StatsAccumulator,
    recording: &Recording,
    max_coordinates: Option<(u16, u16)>,
    args: &StatsArgs,
    global: &Global,
) -> anyhow::Result<SequenceStats> {
    let resolved = recording.resolve_sensor(max_coordinates);
    if let Some(w) = &resolved.warning {
        warn(global, &super::flags::render(w));
    }
    let frame_times = recording.frame_times()?;
    let window = |flag: &str, value: Option<f64>| value.map(|v| format!("{flag} {v} s"));
    accumulator
        .finish(resolved.sensor, &resolved.source, &frame_times)
        .ok_or_else(|| {
            if args.start.is_none() && args.end.is_none() && args.selection.is_set() {
                return selection_empty(recording, &args.selection);
            }
            ctcal::InputError::EmptyWindow {
                path: recording.path.clone(),
                detail: [window("--start", args.start), window("--end", args.end)]
                    .into_iter()
                    .flatten()
                    .collect::<Vec<_>>()
                    .join(", "),
            }
            .into()
        })
}

/// The error for a pixel selection that holds none of the recording's events (no time
/// window was asked for, so the window is not what emptied it).
fn selection_empty(recording: &Recording, selection: &super::SelectionArgs) -> anyhow::Error {
    let what = [
        selection.roi.map(|r| format!("--roi {r}")),
        selection
            .mask
            .as_ref()
            .map(|m| format!("--mask {}", m.display())),
        selection
            .exclude_hot_pixels
            .then(|| "--exclude-hot-pixels".to_string()),
    ]
    .into_iter()
    .flatten()
    .collect::<Vec<_>>()
    .join(", ");
    super::load::hinted(ctcal::window::empty_selection(
        &recording.path,
        &what,
        false,
    ))
}

/// The error for events that reach further than the per-pixel budget.
fn over_budget_message(recording: &Recording, over: ctcal::stats::OverBudget) -> String {
    let sensor = recording
        .sensor
        .map(|s| format!(" of the {s} sensor"))
        .unwrap_or_default();
    format!(
        "{}: the events reach x = {}, y = {}{sensor}: statistics of that area keep {} pixels of state (about {:.1} GB), more than the budget of {} pixels ({:.1} GB)\n  fix: if the sensor is smaller (the coordinates or the stated size are damage), pass --sensor WxH with the camera's real size; to use the memory anyway, pass --force",
        recording.path.display(),
        over.max_x,
        over.max_y,
        over.pixels,
        over.bytes() as f64 / 1e9,
        over.budget,
        (over.budget * ctcal::stats::BYTES_PER_PIXEL) as f64 / 1e9,
    )
}

/// Prints a recording's statistics as a table: what was recorded, the rates, the hot
/// pixels, the rate timeline and the frames.
fn print_human(s: &SequenceStats) -> std::io::Result<()> {
    let mut rows = recording_rows(s);
    rows.extend(rate_rows(s));
    push_hot_pixel_rows(s, &mut rows);
    push_timeline_rows(s, &mut rows);
    output::print_table(&rows)
}

/// A value, or why it is not determined (the statistics' `why` under `key`).
fn shown_or_why(s: &SequenceStats, value: Option<String>, key: &str) -> String {
    value.unwrap_or_else(|| {
        let why = s.why.get(key).map_or("", String::as_str);
        format!("not determined: {why}")
    })
}

/// The rows of what was recorded: the sensor, the events, their time span and the pixels
/// kept.
fn recording_rows(s: &SequenceStats) -> Vec<(String, String)> {
    vec![
        (
            "sensor".to_string(),
            format!("{}x{} ({})", s.width, s.height, s.sensor_source),
        ),
        (
            "events".into(),
            format!(
                "{} ({} ON, {} OFF, ON fraction {:.4})",
                s.events, s.on_events, s.off_events, s.on_fraction
            ),
        ),
        (
            "time".into(),
            format!(
                "{} .. {} us ({})",
                s.t_first_us,
                s.t_last_us,
                output::seconds(s.duration_s)
            ),
        ),
        (
            "pixels".into(),
            format!("{} ({})", s.pixels_kept, s.selection),
        ),
    ]
}

/// The rows of the event rates: per pixel, ON and OFF, the active pixels, the background
/// activity, the median pixel rate, the same-pixel interval, the hot-pixel count and the
/// biases.
fn rate_rows(s: &SequenceStats) -> Vec<(String, String)> {
    let rate = |r: Option<f64>| {
        shown_or_why(
            s,
            r.map(|r| format!("{r:.6}")),
            "events_per_pixel_per_second",
        )
    };
    vec![
        ("events/pixel/s".into(), rate(s.events_per_pixel_per_second)),
        (
            "  ON / OFF".into(),
            match (s.on_per_pixel_per_second, s.off_per_pixel_per_second) {
                (Some(on), Some(off)) => format!("{on:.6} / {off:.6}"),
                _ => "not determined (as above)".into(),
            },
        ),
        (
            "active pixels".into(),
            format!("{:.2} %", 100.0 * s.active_pixel_fraction),
        ),
        (
            "background activity".into(),
            shown_or_why(
                s,
                s.background_rate_hz.map(|r| {
                    format!(
                        "{r:.4} Hz per pixel (events with no neighbour event in the {} before, from one such window after the first event; hot pixels excluded)",
                        output::seconds(s.support_window_s)
                    )
                }),
                "background_rate_hz",
            ),
        ),
        (
            "median pixel rate".into(),
            shown_or_why(
                s,
                s.median_pixel_rate_hz.map(|r| format!("{r:.4} Hz")),
                "median_pixel_rate_hz",
            ),
        ),
        (
            "same-pixel interval".into(),
            match (s.inter_event_interval_s.p5, s.inter_event_interval_s.median) {
                (Some(p5), Some(m)) => {
                    format!("p5 {}, median {}", output::seconds(p5), output::seconds(m))
                }
                _ => "none (no pixel fired twice)".into(),
            },
        ),
        ("hot pixels".into(), s.hot_pixels.len().to_string()),
        output::biases_row(s.biases.as_ref()),
    ]
}

/// The rows of events repeated within a microsecond (if any) and of the first ten hot
/// pixels.
fn push_hot_pixel_rows(s: &SequenceStats, rows: &mut Vec<(String, String)>) {
    if let Some(repeated) = s.inter_event_interval_s.zero.filter(|&n| n > 0) {
        rows.push((
            "same-microsecond events".into(),
            format!(
                "{} events come in the same microsecond as their pixel's previous one: a camera's pixel cannot fire twice so fast (its refractory period), so these were made by a simulator that gives a step's events one time, or duplicated by a writer or converter; every count and estimate takes them as real",
                repeated
            ),
        ));
    }
    for h in s.hot_pixels.iter().take(10) {
        rows.push((
            format!("  ({}, {})", h.x, h.y),
            format!("{} events, {:.1} Hz, z {:.1}", h.events, h.rate_hz, h.z),
        ));
    }
    if s.hot_pixels.len() > 10 {
        rows.push((
            "  ...".into(),
            format!("{} more (see --json)", s.hot_pixels.len() - 10),
        ));
    }
}

/// The rows of the rate timeline (its windows and peak) and of the frames.
fn push_timeline_rows(s: &SequenceStats, rows: &mut Vec<(String, String)>) {
    let peak = s
        .rate_timeline
        .iter()
        .filter_map(|w| w.events_per_pixel_per_second)
        .fold(0.0, f64::max);
    rows.push((
        "rate timeline".into(),
        format!(
            "{} windows of {}, peak {peak:.3} e/pix/s",
            s.rate_timeline.len(),
            output::seconds(s.rate_window_s)
        ),
    ));
    rows.push((
        "frames".into(),
        match &s.frames {
            Some(f) => format!(
                "{} (median interval {})",
                f.count,
                f.median_interval_s.map_or("-".into(), output::seconds)
            ),
            None => "none".into(),
        },
    ));
}
