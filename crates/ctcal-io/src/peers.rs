//! The cases of the peer simulators (`ctcal_core::sim::peers`) written as IJRR folders:
//! the simulation is core's ([`write_case_with`]), the folder this crate's [`IjrrWriter`].

use crate::sim::SimError;
use crate::sim::peers::{CaseTruth, CaseWriter, Peer, write_case_with};
use crate::sim::scene::SceneSpec;
use crate::write::{IjrrWriter, OutputPolicy};
use ctcal_core::{EventChunk, Frame};
use std::path::Path;

impl CaseWriter for IjrrWriter {
    fn write_events(&mut self, events: &EventChunk) -> Result<(), SimError> {
        IjrrWriter::write_events(self, events).map_err(SimError::source)
    }
    fn write_frame(&mut self, frame: &Frame) -> Result<(), SimError> {
        IjrrWriter::write_frame(self, frame).map_err(SimError::source)
    }
    fn add_file(&mut self, name: &str, bytes: &[u8]) -> Result<(), SimError> {
        IjrrWriter::add_file(self, name, bytes).map_err(SimError::source)
    }
    fn finish(self) -> Result<(), SimError> {
        IjrrWriter::finish(self).map_err(SimError::source)
    }
}

/// Simulates `scene` through `peer` with `seed` and writes an IJRR folder at `dir`
/// (`events.txt`; `images.txt` and `images/` from the scene's APS frames, if it has any;
/// `params.json`, the [`CaseTruth`] it returns).
pub fn write_case(
    dir: &Path,
    scene: &SceneSpec,
    peer: &Peer,
    seed: u64,
) -> Result<CaseTruth, SimError> {
    write_case_with(
        |sensor| {
            IjrrWriter::create(dir, sensor, &OutputPolicy::default()).map_err(SimError::source)
        },
        scene,
        peer,
        seed,
    )
}
