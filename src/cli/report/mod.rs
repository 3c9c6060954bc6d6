//! `ctcal report`: statistics, every applicable threshold estimate and the fit of each
//! recording, grouped into datasets, rendered as a report folder (see `ctcal::report`).
//! Sequences are processed in parallel; each is written as soon as it is done and its
//! per-pixel data dropped. A recording that fails is listed with its error and the others
//! are still reported (exit code 1); when every one fails, nothing is written.

mod inputs;
mod progress;
mod sequence;

use super::estimate::default_screen;
use super::{BadInput, Global, SelectionArgs, output, warn};
use clap::Args;
use ctcal::report::grouping::{Origin, dataset_names, file_stem};
use ctcal::report::model::{FailedSequence, Report, SequenceReport};
use ctcal::sim::DisplayParams;
use inputs::Input;
use progress::Progress;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// Recordings, or folders of recordings (each recording inside is a sequence of a
    /// dataset named after the folder, split by sensor where the folder mixes sensors).
    #[arg(value_name = "INPUT")]
    pub inputs: Vec<PathBuf>,
    /// Recordings of a named dataset: NAME=INPUT (repeatable; INPUT may be a folder of
    /// recordings).
    #[arg(long = "dataset", value_name = "NAME=INPUT")]
    pub datasets: Vec<String>,
    /// The report folder.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Leave the fit out (faster; no fitted model, residuals or configs).
    #[arg(long)]
    pub no_fit: bool,
    /// Only the part of each recording from S seconds after its first event.
    #[arg(long, value_name = "S")]
    pub start: Option<f64>,
    /// Only the part up to S seconds after the first event.
    #[arg(long, value_name = "S")]
    pub end: Option<f64>,
    /// Use at most this many frames of a recording.
    #[arg(long, value_name = "N", default_value_t = 120)]
    pub max_frames: usize,
    /// The screen model for recordings of an on-screen stimulus (default: a typical 60 Hz
    /// LCD).
    #[arg(long, value_name = "SCREEN.toml")]
    pub screen: Option<PathBuf>,
    /// Seed of every simulation.
    #[arg(long, value_name = "N", default_value_t = 2020)]
    pub seed: u64,
    #[command(flatten)]
    pub selection: SelectionArgs,
}

/// Some recordings could not be reported (the others were): exit code 1.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct SomeFailed(pub String);

/// The message of a panic.
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".into())
}

/// One recording computed, rendered and written (its per-pixel data dropped after): the
/// sequence, or the error that stopped it. Only a failure to write ends the report.
fn one(
    input: &Input,
    args: &ReportArgs,
    screen: &DisplayParams,
    global: &Global,
    progress: &Progress,
    staged: &ctcal::io::write::StagedFolder,
) -> anyhow::Result<Result<SequenceReport, anyhow::Error>> {
    let computed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        sequence::sequence(input, args, screen, global, progress)
    }));
    let (mut s, pixels) = match computed {
        Ok(Ok(done)) => done,
        Ok(Err(e)) => {
            progress.finished(&input.name, "failed");
            return Ok(Err(e));
        }
        Err(payload) => {
            progress.finished(&input.name, "failed");
            return Ok(Err(anyhow::anyhow!(
                "ctcal failed on it (a bug; please report it with this recording): {}",
                panic_message(payload.as_ref())
            )));
        }
    };
    let files = ctcal::report::render_sequence(&mut s, &pixels, args.seed);
    drop(pixels);
    for f in files {
        staged.write(&f.path, &f.bytes)?;
    }
    progress.finished(&input.name, "written");
    Ok(Ok(s))
}

/// Names each sequence's dataset: the user's name, else its folder's, split by sensor.
fn name_datasets(sequences: &mut [SequenceReport], origins: &[Origin]) {
    let keyed: Vec<(Origin, String)> = origins
        .iter()
        .cloned()
        .zip(sequences.iter().map(|s| s.sensor()))
        .collect();
    for (s, name) in sequences.iter_mut().zip(dataset_names(&keyed)) {
        s.dataset = file_stem(&name);
    }
}

/// The paths a report must not be written into: its recordings and the folders given.
fn protected<'a>(args: &'a ReportArgs, inputs: &'a [Input]) -> Vec<&'a Path> {
    let mut protected: Vec<&Path> = inputs.iter().map(|i| i.path.as_path()).collect();
    protected.extend(args.inputs.iter().map(PathBuf::as_path));
    protected.extend(
        args.datasets
            .iter()
            .filter_map(|d| d.split_once('=').map(|(_, path)| Path::new(path))),
    );
    protected.extend(args.screen.as_deref());
    protected
}

fn screen_of(args: &ReportArgs) -> anyhow::Result<DisplayParams> {
    Ok(match &args.screen {
        Some(path) => {
            let text = ctcal::files::read_small_text(path, 1 << 20)
                .map_err(|e| ctcal::InputError::not_a_file(path, e))?;
            DisplayParams::from_toml(&text, &path.display().to_string())?
        }
        None => default_screen(),
    })
}

pub fn run(args: &ReportArgs, global: &Global) -> anyhow::Result<()> {
    super::load::check_window(args.start, args.end)?;
    if args.max_frames < 2 {
        return Err(BadInput("--max-frames must be at least 2".into()).into());
    }
    let inputs = inputs::inputs(args)?;
    let policy = global.outputs(protected(args, &inputs));
    // refuse a bad output before the work
    policy.check_folder(&args.out)?;
    let screen = screen_of(args)?;
    let staged = policy.folder(&args.out)?;
    let progress = Progress::new(global, inputs.len());
    let (presets, outcomes) = rayon::join(
        || ctcal::report::presets::simulate(args.seed),
        || {
            inputs
                .par_iter()
                .map(|input| one(input, args, &screen, global, &progress, &staged))
                .collect::<anyhow::Result<Vec<_>>>()
        },
    );
    progress.clear();
    let mut sequences = Vec::new();
    let mut origins = Vec::new();
    let mut failed = Vec::new();
    let mut first_error = None;
    for (input, outcome) in inputs.iter().zip(outcomes?) {
        match outcome {
            Ok(s) => {
                sequences.push(s);
                origins.push(input.origin.clone());
            }
            Err(e) => {
                failed.push(FailedSequence {
                    name: input.name.clone(),
                    path: input.path.display().to_string(),
                    error: format!("{e:#}"),
                });
                first_error.get_or_insert(e);
            }
        }
    }
    if sequences.is_empty()
        && let Some(e) = first_error
    {
        // nothing to report: the error as it is (the staged folder is removed)
        return Err(e);
    }
    name_datasets(&mut sequences, &origins);
    let report = Report {
        ctcal_version: env!("CARGO_PKG_VERSION"),
        // the program as `ctcal`, wherever it was run from
        command_line: std::iter::once("ctcal".to_string())
            .chain(std::env::args().skip(1))
            .collect(),
        seed: args.seed,
        datasets: ctcal::report::model::datasets(&sequences),
        sequences,
        presets: presets?,
        presets_scene: ctcal::report::presets::DESCRIPTION.into(),
        failed,
    };
    for f in ctcal::report::render_summary(&report) {
        staged.write(&f.path, &f.bytes)?;
    }
    staged.commit()?;
    tell(args, global, &report)?;
    if report.failed.is_empty() {
        Ok(())
    } else {
        let names: Vec<&str> = report.failed.iter().map(|f| f.name.as_str()).collect();
        Err(SomeFailed(format!(
            "{} of {} recordings could not be reported ({}); the report of the others is in {} and lists the errors",
            report.failed.len(),
            report.failed.len() + report.sequences.len(),
            names.join(", "),
            args.out.display()
        ))
        .into())
    }
}

/// The summary on stdout, and the warnings on stderr.
fn tell(args: &ReportArgs, global: &Global, report: &Report) -> anyhow::Result<()> {
    if !global.quiet {
        let mut rows = vec![(
            "report".to_string(),
            args.out.join("index.html").display().to_string(),
        )];
        for s in &report.sequences {
            let thresholds = s
                .best_thresholds()
                .map_or("-".to_string(), |(on, off, method)| {
                    format!("ON {on:.3}, OFF {off:.3} ({method})")
                });
            rows.push((format!("{} ({})", s.name, s.dataset), thresholds));
        }
        for f in &report.failed {
            rows.push((f.name.clone(), "failed (see the report)".into()));
        }
        output::print_table(&rows)?;
    }
    for d in &report.datasets {
        for w in &d.warnings {
            warn(global, &format!("dataset {}: {w}", d.name));
        }
    }
    for f in &report.failed {
        warn(
            global,
            &format!("{}: {}", f.name, f.error.lines().next().unwrap_or("")),
        );
    }
    for s in &report.sequences {
        for m in &s.methods {
            if let Some(why) = &m.not_applied
                && m.method != "screen"
                && m.method != "aps"
            {
                warn(
                    global,
                    &format!(
                        "{}: estimate {}: {}",
                        s.name,
                        m.method,
                        why.lines().next().unwrap_or("")
                    ),
                );
            }
        }
    }
    Ok(())
}
