//! `ctcal report`: statistics, every applicable threshold estimate and the fit of each
//! recording, grouped into datasets, rendered as a report folder (see `ctcal::report`).
//! Sequences are processed in parallel; each is written as soon as it is done and its
//! per-pixel data dropped. A recording that fails is listed with its error and the others
//! are still reported (exit code 1); when every one fails, nothing is written.
//!
//! The work is the library's report pipeline (`ctcal::report::pipeline`): this module turns
//! the command line into its options, shows its progress, words its errors with the
//! command's flags and writes the folder; `--from-results` merges reports made elsewhere.

mod from_results;
mod inputs;
mod progress;

use super::{BadInput, Global, SelectionArgs, output, warn};
use clap::Args;
use ctcal::report::model::Report;
use ctcal::report::pipeline::{self, Input, SequenceError};
use ctcal::sim::DisplayParams;
use progress::Progress;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// Recordings, or folders of recordings (each recording inside is a sequence of a
    /// dataset named after the folder, split by sensor where the folder mixes sensors).
    #[arg(value_name = "INPUT")]
    pub inputs: Vec<PathBuf>,
    /// Build the report from reports made elsewhere: their folders (or their results.json),
    /// each sequence with its files taken as it is, merged into one report (same seed).
    #[arg(long = "from-results", value_name = "DIR", num_args = 1.., conflicts_with_all = ["inputs", "datasets"])]
    pub from_results: Vec<PathBuf>,
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
    /// Use at most this many frames of a recording for the frame-based estimate and the
    /// fit (of a sensor up to 346x260; fewer of a larger one): one with more is measured on
    /// blocks of consecutive frames (as `fit --max-frames`).
    #[arg(long, value_name = "N", default_value_t = 120)]
    pub max_frames: usize,
    /// The fit simulates at most this many pixels: a larger sensor is fitted on its busiest
    /// region of that size (as `fit --max-pixels`; 0: the whole sensor).
    #[arg(long, value_name = "N", default_value_t = ctcal::fit_region::FIT_PIXELS)]
    pub max_pixels: usize,
    /// The fit re-simulates about this many events at most: a window with more is fitted on
    /// its busiest region holding about that many (as `fit --max-events`; 0: no limit).
    #[arg(long, value_name = "N", default_value_t = ctcal::fit_region::FIT_EVENTS)]
    pub max_events: usize,
    /// The screen model for recordings of an on-screen stimulus (default: a typical 60 Hz
    /// LCD).
    #[arg(long, value_name = "SCREEN.toml")]
    pub screen: Option<PathBuf>,
    /// Seed of every simulation.
    #[arg(long, value_name = "N", default_value_t = ctcal::DEFAULT_SEED)]
    pub seed: u64,
    #[command(flatten)]
    pub selection: SelectionArgs,
}

/// Some recordings could not be reported (the others were), ctcal failing on one: exit
/// code 1.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct SomeFailed(pub String);

/// A recording's error with the fix in the command's flags (its exit code follows it).
fn hinted(error: SequenceError) -> anyhow::Error {
    match error {
        SequenceError::Load(e) => super::load::hinted(e),
        SequenceError::Input(e) => e.into(),
        SequenceError::NoEvents(_) => BadInput(error.to_string()).into(),
        SequenceError::Panic(_) => anyhow::anyhow!("{error}"),
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

/// The measured screen model of `--screen` (`None`: the built-in one, gamma a prior).
fn screen_of(args: &ReportArgs) -> anyhow::Result<Option<DisplayParams>> {
    let Some(path) = &args.screen else {
        return Ok(None);
    };
    let text = ctcal::files::read_small_text(path, 1 << 20)
        .map_err(|e| ctcal::InputError::not_a_file(path, e))?;
    Ok(Some(DisplayParams::from_toml(
        &text,
        &path.display().to_string(),
    )?))
}

/// The pipeline's options of the command line.
fn options(args: &ReportArgs, global: &Global) -> anyhow::Result<pipeline::Options> {
    Ok(pipeline::Options {
        start_s: args.start,
        end_s: args.end,
        max_frames: args.max_frames,
        screen: screen_of(args)?,
        seed: args.seed,
        fit_left_out: args.no_fit.then(|| "left out (--no-fit)".to_string()),
        fit_budget: ctcal::fit_region::FitBudget {
            max_pixels: args.max_pixels,
            max_events: args.max_events,
        },
        selection: args.selection.spec(),
        force: global.force,
    })
}

pub fn run(args: &ReportArgs, global: &Global) -> anyhow::Result<()> {
    if !args.from_results.is_empty() {
        return from_results::run(args, global);
    }
    super::load::check_window(args.start, args.end)?;
    if args.max_frames < 2 {
        return Err(BadInput("--max-frames must be at least 2".into()).into());
    }
    let inputs = inputs::inputs(args)?;
    let policy = global.outputs(protected(args, &inputs));
    // refuse a bad output before the work
    policy.check_folder(&args.out)?;
    let options = options(args, global)?;
    let staged = policy.folder(&args.out)?;
    let progress = Progress::new(global, inputs.len());
    let outcomes = pipeline::run(
        &inputs,
        &options,
        &|name, event| progress.event(name, event),
        &|f| staged.write(&f.path, &f.bytes),
    )?;
    progress.clear();
    let mut merged = Vec::new();
    let mut first_error = None;
    let mut any = false;
    let mut all_bad_input = true;
    for (input, outcome) in inputs.iter().zip(outcomes.sequences) {
        all_bad_input &= !matches!(outcome, Err(SequenceError::Panic(_)));
        let outcome = outcome.map_err(hinted).map_err(|e| {
            let message = super::flags::message(&e);
            first_error.get_or_insert(e);
            message
        });
        any |= outcome.is_ok();
        merged.push((input.clone(), outcome));
    }
    if !any && let Some(e) = first_error {
        // nothing to report: the error as it is (the staged folder is removed)
        return Err(e);
    }
    let report = pipeline::merge(
        merged,
        outcomes.presets?,
        args.seed,
        // the program as `ctcal`, wherever it was run from
        std::iter::once("ctcal".to_string())
            .chain(std::env::args().skip(1))
            .collect(),
    );
    finish(args, global, &report, staged, all_bad_input)
}

/// The summary written beside the sequences, the folder committed, and what was made
/// told. Some recordings failed: exit code 2 when each failed on its input (the message
/// repeats each error with its fix), else 1 (ctcal failed on one).
fn finish(
    args: &ReportArgs,
    global: &Global,
    report: &Report,
    staged: ctcal::io::write::StagedFolder,
    all_bad_input: bool,
) -> anyhow::Result<()> {
    for f in ctcal::report::render_summary(report) {
        staged.write(&f.path, &f.bytes)?;
    }
    staged.commit()?;
    tell(args, global, report)?;
    if report.failed.is_empty() {
        Ok(())
    } else {
        let names: Vec<&str> = report.failed.iter().map(|f| f.name.as_str()).collect();
        let message = format!(
            "{} of {} recordings could not be reported ({}); the report of the others is in {} and lists the errors",
            report.failed.len(),
            report.failed.len() + report.sequences.len(),
            names.join(", "),
            args.out.display()
        );
        if all_bad_input {
            let errors: String = report
                .failed
                .iter()
                .map(|f| format!("\n{}: {}", f.name, f.error))
                .collect();
            return Err(BadInput(format!("{message}:{errors}")).into());
        }
        Err(SomeFailed(message).into())
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
