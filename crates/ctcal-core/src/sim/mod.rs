//! The event simulator: a DVS pixel model with every effect switchable ([`PixelParams`]),
//! driven by intensity frames from a folder, a procedural scene or a display.
//!
//! It is the instrument of every calibration method in ctcal, so it is deterministic for a
//! seed whatever the thread count, documents each effect's equation and source in
//! [`effects`], and is validated against the v2e oracle cases (`../shared/data/oracle`).

pub mod ahead;
mod batch;
pub mod budget;
pub mod display;
pub mod effects;
pub mod fast_math;
pub mod footprints;
pub mod log_response;
pub mod params;
pub mod peers;
pub mod pixel;
pub mod rng;
mod row;
pub mod scene;
pub mod screen_geometry;
pub mod simd;
pub mod simulator;
pub mod source;

pub use params::{DisplayParams, LogResponse, ParamsError, PixelParams};
pub use pixel::Transition;
pub use simulator::{PixelMaps, Simulator};
pub use source::{FrameSource, Sample};

use crate::events::{EventChunk, TimeUs};
use crate::hint::Text;
use std::path::{Path, PathBuf};

/// What can go wrong in a simulation. Every variant is something the user can fix (a
/// parameter, a scene, an input file), and says how.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A file the simulator reads itself (parameters, scene, texture).
    #[error("{}: {problem}\n  fix: {fix}", path.display())]
    File {
        path: PathBuf,
        problem: String,
        fix: String,
    },
    #[error(transparent)]
    Params(#[from] ParamsError),
    #[error("{0}")]
    Invalid(String),
    /// Work beyond a budget ([`budget`]); the fix names the option that allows it.
    #[error("{}", over_budget(problem, fix))]
    OverBudget { problem: String, fix: Text },
    /// An error of the frame source or event sink the caller supplied (a reader, a writer).
    #[error("{0}")]
    Source(Box<dyn std::error::Error + Send + Sync>),
}

impl SimError {
    pub fn file(path: &Path, problem: impl Into<String>, fix: impl Into<String>) -> Self {
        SimError::File {
            path: path.to_path_buf(),
            problem: problem.into(),
            fix: fix.into(),
        }
    }

    /// A file that cannot be read (missing, a folder, a FIFO, ...).
    pub fn not_a_file(path: &Path, problem: crate::files::NotAFile) -> Self {
        Self::file(path, problem.problem(), problem.fix())
    }

    /// An error from the caller's frame source or event sink.
    pub fn source(error: impl std::error::Error + Send + Sync + 'static) -> Self {
        SimError::Source(Box::new(error))
    }

    /// The message, its fix naming options as hints.
    pub fn message(&self) -> Text {
        match self {
            SimError::OverBudget { problem, fix } => over_budget(problem, fix),
            other => other.to_string().into(),
        }
    }
}

fn over_budget(problem: &str, fix: &Text) -> Text {
    Text::from(problem).fixed_by(fix)
}

/// Counts of a finished simulation.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct SimSummary {
    pub samples: u64,
    pub events: u64,
    pub on_events: u64,
    pub t_first_sample_us: TimeUs,
    pub t_last_sample_us: TimeUs,
}

/// Runs `params` over every sample of `source`, passing each batch of time-sorted events
/// to `sink` (whose own errors pass through). The first sample only sets the pixels'
/// reference levels.
pub fn run<E: From<SimError>>(
    source: &mut dyn FrameSource,
    params: &PixelParams,
    maps: PixelMaps,
    sink: impl FnMut(&EventChunk) -> Result<(), E>,
    progress: impl FnMut(u64),
) -> Result<SimSummary, E> {
    run_noise_stream(source, params, maps, 0, sink, progress)
}

/// [`run`] with the `noise_stream`-th draw of the pixels' random updates (see
/// [`Simulator::noise_stream`]): the runs of one recording each take their own.
pub fn run_noise_stream<E: From<SimError>>(
    source: &mut dyn FrameSource,
    params: &PixelParams,
    maps: PixelMaps,
    noise_stream: u64,
    mut sink: impl FnMut(&EventChunk) -> Result<(), E>,
    mut progress: impl FnMut(u64),
) -> Result<SimSummary, E> {
    let (width, height) = source.size();
    let mut simulator = Simulator::new(params, width, height, maps).noise_stream(noise_stream);
    let mut summary = SimSummary::default();
    let count = |chunk: &EventChunk, summary: &mut SimSummary| {
        summary.events += chunk.len() as u64;
        summary.on_events += chunk.on.iter().filter(|&&p| p).count() as u64;
    };
    let Some(first) = source.next_frame()? else {
        return Err(SimError::Invalid("the input has no frames".into()).into());
    };
    simulator.start(first.t, &first.dn);
    summary.samples = 1;
    summary.t_first_sample_us = first.t;
    summary.t_last_sample_us = first.t;
    while let Some(sample) = source.next_frame()? {
        if sample.t < summary.t_last_sample_us {
            return Err(SimError::Invalid(format!(
                "input sample times go backwards ({} us after {} us)",
                sample.t, summary.t_last_sample_us
            ))
            .into());
        }
        let events = simulator.step(sample.t, &sample.dn, sample.transition);
        count(events, &mut summary);
        sink(events)?;
        summary.samples += 1;
        summary.t_last_sample_us = sample.t;
        progress(summary.samples);
    }
    let rest = simulator.finish();
    count(rest, &mut summary);
    sink(rest)?;
    Ok(summary)
}
