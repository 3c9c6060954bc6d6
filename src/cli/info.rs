//! `ctcal info`: what a recording is (format, sensor, events, time span, frames).

use super::{Global, InputArgs, JsonTarget, emit_json, output, progress_bar, warn};
use clap::Args;
use ctcal::Recording;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct InfoArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Write the result as JSON to PATH (`-` for stdout).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
}

pub fn run(args: &InfoArgs, global: &Global) -> anyhow::Result<()> {
    let recording = Recording::open(&args.input.input, &args.input.open_options())?;
    for note in &recording.notes {
        warn(global, note);
    }
    let stream = match recording.events() {
        Ok(stream) => stream,
        Err(error) => {
            // a bag whose events topic must be chosen: show what it holds first
            if !recording.topics().is_empty() && !global.quiet {
                print_topics(recording.topics())?;
            }
            return Err(error.into());
        }
    };
    let bar = progress_bar(global, stream.progress().total, "reading");
    let (info, warning) =
        ctcal::io::info::info(&recording, stream, &|done, _| bar.set_position(done))?;
    bar.finish_and_clear();
    if let Some(w) = &warning {
        warn(global, &super::flags::render(w));
    }
    let target = args.json.as_deref().map(JsonTarget::parse);
    if let Some(target) = &target {
        emit_json(&info, target, &global.outputs([args.input.input.as_path()]))?;
    }
    if !matches!(target, Some(JsonTarget::Stdout)) {
        print_info(&info)?;
    }
    Ok(())
}

/// The recording's summary as a table, then a bag's topics.
fn print_info(info: &ctcal::io::info::Info) -> anyhow::Result<()> {
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
