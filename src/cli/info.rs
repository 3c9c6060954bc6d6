//! `ctcal info`: what a recording is (format, sensor, events, time span, frames).

use super::{Global, InputArgs, JsonTarget, emit_json, output, progress_bar, warn};
use clap::Args;
use ctcal::Recording;
use serde::Serialize;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct InfoArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Write the result as JSON to PATH (`-` for stdout).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
}

#[derive(Serialize)]
struct Info {
    format: ctcal::Format,
    /// HDF5: which layout.
    #[serde(skip_serializing_if = "Option::is_none")]
    layout: Option<&'static str>,
    /// ROS bags: every topic with its message type and count.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    topics: Vec<ctcal::io::bag::Topic>,
    width: u16,
    height: u16,
    sensor_source: String,
    events: u64,
    on_events: u64,
    t_first_us: i64,
    t_last_us: i64,
    /// Places where a timestamp is earlier than the one before.
    timestamps_backwards: u64,
    frames: usize,
    file_bytes: u64,
    /// Sensor biases saved in or beside the recording.
    #[serde(skip_serializing_if = "Option::is_none")]
    biases: Option<ctcal::io::Biases>,
}

pub fn run(args: &InfoArgs, global: &Global) -> anyhow::Result<()> {
    let recording = Recording::open(&args.input.input, &args.input.open_options())?;
    for note in &recording.notes {
        warn(global, note);
    }
    let mut stream = match recording.events() {
        Ok(stream) => stream,
        Err(error) => {
            // a bag whose events topic must be chosen: show what it holds first
            if !recording.topics().is_empty() && !global.quiet {
                print_topics(recording.topics())?;
            }
            return Err(error.into());
        }
    };
    stream.allow_unsorted = true;
    let bar = progress_bar(global, stream.progress().total, "reading");
    let (mut first, mut last, mut on) = (i64::MAX, i64::MIN, 0u64);
    while let Some(chunk) = stream.next_chunk()? {
        first = first.min(*chunk.t.iter().min().expect("non-empty"));
        last = last.max(*chunk.t.iter().max().expect("non-empty"));
        on += chunk.on.iter().filter(|&&p| p).count() as u64;
        bar.set_position(stream.progress().done);
    }
    bar.finish_and_clear();
    let resolved = recording.resolve_sensor(stream.max_coordinates());
    if let Some(w) = &resolved.warning {
        warn(global, w);
    }
    let info = Info {
        format: recording.format,
        layout: recording.layout(),
        topics: recording.topics().to_vec(),
        width: resolved.sensor.width,
        height: resolved.sensor.height,
        sensor_source: resolved.source.clone(),
        events: stream.events_read(),
        on_events: on,
        t_first_us: first,
        t_last_us: last,
        timestamps_backwards: stream.unsorted_count(),
        frames: recording.frame_times()?.len(),
        file_bytes: std::fs::metadata(recording.event_file())
            .map(|m| m.len())
            .unwrap_or(0),
        biases: recording.biases(),
    };
    let target = args.json.as_deref().map(JsonTarget::parse);
    if let Some(target) = &target {
        emit_json(&info, target, &global.outputs([args.input.input.as_path()]))?;
    }
    if !matches!(target, Some(JsonTarget::Stdout)) {
        let mut format = info.format.to_string();
        if let Some(layout) = info.layout {
            format.push_str(&format!(" ({layout} layout)"));
        }
        output::print_table(&[
            ("format".into(), format),
            (
                "sensor".into(),
                format!("{}x{} ({})", info.width, info.height, info.sensor_source),
            ),
            (
                "events".into(),
                format!("{} ({} ON)", info.events, info.on_events),
            ),
            (
                "time".into(),
                format!("{} .. {} us", info.t_first_us, info.t_last_us),
            ),
            (
                "duration".into(),
                output::seconds((info.t_last_us - info.t_first_us) as f64 * 1e-6),
            ),
            (
                "timestamps backwards".into(),
                info.timestamps_backwards.to_string(),
            ),
            ("frames".into(), info.frames.to_string()),
            output::biases_row(info.biases.as_ref()),
        ])?;
        if !info.topics.is_empty() {
            print_topics(&info.topics)?;
        }
    }
    Ok(())
}

/// A bag's topics, one row each.
fn print_topics(topics: &[ctcal::io::bag::Topic]) -> anyhow::Result<()> {
    let rows: Vec<(String, String)> = topics
        .iter()
        .map(|t| {
            (
                format!("topic {}", t.name),
                format!("{} ({} messages)", t.message_type, t.messages),
            )
        })
        .collect();
    output::print_table(&rows)?;
    Ok(())
}
