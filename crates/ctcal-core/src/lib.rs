//! # ctcal-core: the event-camera model and the analyses, with no file formats
//!
//! The events and their sensor ([`events`]), the pixel simulator ([`sim`]), the dataset
//! statistics ([`stats`]), the contrast-threshold estimators ([`estimate`]) and the fit of
//! every simulator parameter ([`fit`]), with what they share (pixel selections, sensor
//! sizes, synthetic recordings, option hints, file checks, and the [`format::Format`] and
//! [`biases::Biases`] types the readers fill in).
//!
//! Arrows point down: this crate depends on no other ctcal crate. The readers and writers
//! (`ctcal-io`), the report (`ctcal-report`) and the `ctcal` binary build on it; nothing
//! here imports them, parses a command line or reads a recording.

pub mod biases;
pub mod estimate;
pub mod events;
pub mod files;
pub mod fit;
pub mod format;
pub mod hint;
pub mod region;
pub mod selection;
pub mod sensors;

pub use events::{CHUNK_EVENTS, Event, EventChunk, Frame, Sensor, TimeUs};

/// The seed of the fit's and eppps's simulations unless one is given (the year of
/// Stoffregen et al.'s paper), the same in `fit`, `estimate eppps` and `report`, so that
/// each reproduces the others' numbers. (aps's re-simulation keeps its own fixed seed,
/// `estimate::aps::ApsOptions::default`.)
pub const DEFAULT_SEED: u64 = 2020;
pub mod sim;
pub mod stats;
pub mod synthetic;
