//! # ctcal-pipeline: the report pipeline
//!
//! Each recording read, measured, estimated, fitted and rendered on
//! its own ([`process`], a failure or a panic isolated to its recording), then every
//! sequence merged into one [`Report`] ([`merge`]). [`run`] does the whole of it on this
//! machine's threads; a caller that spreads the recordings over other machines calls
//! [`process`] there and [`merge`] where the results meet, with the sequences carried as
//! their `results.json` entries ([`decode`]). Progress and warnings go to the caller's
//! [`Observer`]; the library prints nothing and writes nothing (files are returned, or handed
//! to the caller's writer as soon as a sequence is done).
//!
//! Arrows point down: this crate joins the three below it, `ctcal-io` (each recording's
//! window), `ctcal-core` (statistics, estimators, fit) and `ctcal-report` (rendering), so
//! that none of them needs another's layer: the report renders what it is given and reads
//! no file.

pub mod decode;
pub mod gather;
pub mod inputs;
pub mod sequence;

// the core modules, the window loader and the report's modules by the paths they had when
// this was a module of the report (`crate::sim`, `crate::model`, ...)
use ctcal_core::{biases, estimate, files, fit, hint, sim, stats};
use ctcal_io::{fit_region, window};
use ctcal_report::{OutputFile, configs, grouping, model, presets};

use crate::sim::{DisplayParams, SimError};
use crate::window::{LoadError, SelectionSpec};
use ctcal_io::InputError;
use grouping::{Origin, dataset_names, file_stem};
pub use inputs::{Input, InputsError};
use model::{FailedSequence, PresetLevel, Report, SequenceReport};
use rayon::prelude::*;
use std::path::PathBuf;

/// How every recording of a report is read and analysed.
#[derive(Clone, Debug)]
pub struct Options {
    /// Only the part of each recording from this many seconds after its first event.
    pub start_s: Option<f64>,
    /// Only the part up to this many seconds after the first event.
    pub end_s: Option<f64>,
    /// At most this many grey frames of a recording (evenly spread; at least 2).
    pub max_frames: usize,
    /// The measured screen model for recordings of an on-screen stimulus (`None`: the
    /// built-in one, its gamma a prior; see `ctcal_core::estimate::screen::GammaPrior`).
    pub screen: Option<DisplayParams>,
    /// Seed of every simulation.
    pub seed: u64,
    /// `None`: fit every recording; else leave the fit out, with this reason in the report.
    pub fit_left_out: Option<String>,
    /// The pixels and events the fit simulates and `estimate aps` reads at most: a larger
    /// sensor or a denser window is measured on its busiest region within them
    /// (`ctcal_io::fit_region`, `ctcal_io::aps_region`; 0: no limit).
    pub fit_budget: fit_region::FitBudget,
    /// The pixels to analyse.
    pub selection: SelectionSpec,
    /// Run work beyond the memory budgets.
    pub force: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            start_s: None,
            end_s: None,
            max_frames: 120,
            screen: None,
            seed: ctcal_core::DEFAULT_SEED,
            fit_left_out: None,
            fit_budget: fit_region::FitBudget::default(),
            selection: SelectionSpec::default(),
            force: false,
        }
    }
}

impl Options {
    /// Refuses options no recording can be reported with.
    pub fn check(&self) -> Result<(), LoadError> {
        crate::window::check_window(self.start_s, self.end_s)?;
        if self.max_frames < 2 {
            return Err(LoadError::Window(
                "the frame limit must be at least 2".into(),
            ));
        }
        Ok(())
    }
}

/// The stages of one recording, in order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    Reading,
    Statistics,
    Estimates,
    Fit,
}

impl Stage {
    pub const ALL: [Stage; 4] = [
        Stage::Reading,
        Stage::Statistics,
        Stage::Estimates,
        Stage::Fit,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Stage::Reading => "reading",
            Stage::Statistics => "statistics",
            Stage::Estimates => "estimates",
            Stage::Fit => "fit",
        }
    }
}

/// What a recording's processing tells its observer.
#[derive(Clone, Copy, Debug)]
pub enum Event<'a> {
    /// A stage is done.
    Done(Stage),
    /// Reading the recording warned of this.
    Warning(&'a str),
    /// The recording is done: rendered and handed over (`true`), or failed.
    Finished(bool),
}

/// Hears of each recording's progress: its name and the event.
pub type Observer<'a> = dyn Fn(&str, Event<'_>) + Sync + 'a;

/// Why a recording could not be reported.
#[derive(Debug, thiserror::Error)]
pub enum SequenceError {
    #[error(transparent)]
    Load(#[from] LoadError),
    #[error(transparent)]
    Input(#[from] InputError),
    #[error("{}: no events in the selected pixels", .0.display())]
    NoEvents(PathBuf),
    /// A bug: ctcal panicked on it.
    #[error("ctcal failed on it (a bug; please report it with this recording): {0}")]
    Panic(String),
}

/// A recording computed and rendered: its part of the model and its files (tables,
/// plots, configurations, masks), its per-pixel data already dropped.
pub struct Processed {
    pub report: SequenceReport,
    pub files: Vec<OutputFile>,
}

/// The message of a panic.
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".into())
}

/// One recording computed and rendered (its per-pixel data dropped after), or the error
/// that stopped it; a panic is caught and returned as [`SequenceError::Panic`].
pub fn process(
    input: &Input,
    options: &Options,
    progress: &Observer,
) -> Result<Processed, SequenceError> {
    let computed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        sequence::sequence(input, options, progress)
    }));
    let (mut report, pixels) = match computed {
        Ok(Ok(done)) => done,
        Ok(Err(e)) => return Err(e),
        Err(payload) => return Err(SequenceError::Panic(panic_message(payload.as_ref()))),
    };
    let files = ctcal_report::render_sequence(&mut report, &pixels, options.seed);
    Ok(Processed { report, files })
}

/// What [`run`] computed: each input's sequence or error (in the inputs' order), and the
/// presets' event rates.
pub struct Outcomes {
    pub sequences: Vec<Result<SequenceReport, SequenceError>>,
    pub presets: Result<Vec<PresetLevel>, SimError>,
}

/// Every input processed on this machine's threads (and the presets simulated beside),
/// each sequence's files handed to `write` as soon as it is done. Only an error of `write`
/// ends the run.
pub fn run<E: Send>(
    inputs: &[Input],
    options: &Options,
    progress: &Observer,
    write: &(dyn Fn(&OutputFile) -> Result<(), E> + Sync),
) -> Result<Outcomes, E> {
    let one = |input: &Input| -> Result<Result<SequenceReport, SequenceError>, E> {
        match process(input, options, progress) {
            Ok(processed) => {
                for f in &processed.files {
                    write(f)?;
                }
                progress(&input.name, Event::Finished(true));
                Ok(Ok(processed.report))
            }
            Err(e) => {
                progress(&input.name, Event::Finished(false));
                Ok(Err(e))
            }
        }
    };
    let (presets, sequences) = rayon::join(
        || presets::simulate(options.seed),
        || inputs.par_iter().map(one).collect::<Result<Vec<_>, E>>(),
    );
    Ok(Outcomes {
        sequences: sequences?,
        presets,
    })
}

/// Names each sequence's dataset: the given name, else its folder's, split by sensor.
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

/// The sequences merged into one report: each input's sequence, or the message of the
/// error that stopped it (listed under `failed`), with the presets, the seed and the
/// command line that made it. The summary is rendered of it by [`ctcal_report::render_summary`].
pub fn merge(
    outcomes: Vec<(Input, Result<SequenceReport, String>)>,
    presets: Vec<PresetLevel>,
    seed: u64,
    command_line: Vec<String>,
) -> Report {
    let mut sequences = Vec::new();
    let mut origins = Vec::new();
    let mut failed = Vec::new();
    for (input, outcome) in outcomes {
        match outcome {
            Ok(s) => {
                sequences.push(s);
                origins.push(input.origin);
            }
            Err(error) => failed.push(FailedSequence {
                name: input.name,
                path: input.path.display().to_string(),
                error,
            }),
        }
    }
    name_datasets(&mut sequences, &origins);
    Report {
        ctcal_version: env!("CARGO_PKG_VERSION"),
        command_line,
        seed,
        datasets: model::datasets(&sequences),
        sequences,
        presets,
        presets_scene: presets::DESCRIPTION.into(),
        failed,
    }
}
