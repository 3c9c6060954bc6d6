//! The event simulator: a DVS pixel model with every effect switchable ([`PixelParams`]),
//! driven by intensity frames from a folder, a procedural scene or a display.
//!
//! It is the instrument of every calibration method in ctcal, so it is deterministic for a
//! seed whatever the thread count, documents each effect's equation and source in
//! [`effects`], and is validated against the v2e oracle cases (`../shared/data/oracle`).

pub mod display;
pub mod effects;
pub mod fast_math;
pub mod log_response;
pub mod params;
pub mod pixel;
pub mod rng;
mod row;
pub mod scene;
pub mod simulator;
pub mod source;

pub use params::{DisplayParams, LogResponse, ParamsError, PixelParams};
pub use pixel::Transition;
pub use simulator::{PixelMaps, Simulator};
pub use source::{FrameSource, Sample};

use crate::events::{EventChunk, TimeUs};
use crate::io::InputError;

/// What can go wrong in a simulation.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    #[error(transparent)]
    Input(#[from] InputError),
    #[error(transparent)]
    Params(#[from] ParamsError),
    #[error("{0}")]
    Invalid(String),
}

impl SimError {
    /// Whether the user can fix this by changing the input (exit code 2).
    pub fn is_bad_input(&self) -> bool {
        match self {
            SimError::Input(e) => e.is_bad_input(),
            SimError::Params(_) | SimError::Invalid(_) => true,
        }
    }
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
/// to `sink`. The first sample only sets the pixels' reference levels.
pub fn run(
    source: &mut dyn FrameSource,
    params: &PixelParams,
    maps: PixelMaps,
    mut sink: impl FnMut(&EventChunk) -> Result<(), SimError>,
    mut progress: impl FnMut(u64),
) -> Result<SimSummary, SimError> {
    let (width, height) = source.size();
    let mut simulator = Simulator::new(params, width, height, maps);
    let mut summary = SimSummary::default();
    let count = |chunk: &EventChunk, summary: &mut SimSummary| {
        summary.events += chunk.len() as u64;
        summary.on_events += chunk.on.iter().filter(|&&p| p).count() as u64;
    };
    let Some(first) = source.next_frame()? else {
        return Err(SimError::Invalid("the input has no frames".into()));
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
            )));
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
