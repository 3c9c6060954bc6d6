//! # ctcal-io: reading and writing recordings
//!
//! Reading and writing recordings: every common event-camera file format into one
//! representation ([`EventChunk`]s of integer-microsecond events, plus [`Frame`]s).
//!
//! One decoder module per format (as faery does), each streaming in chunks so memory stays
//! bounded whatever the file size, each checking what the file claims (resolution, time
//! order) against the data and naming the place of any problem. [`Recording`] ties them
//! together: format detection from content, the sensor size, frames and stimulus.
//!
//! [`window`] loads a time window of a recording into memory for the estimators, the fit
//! and the report, and [`peers`] writes the cases of the peer simulators as IJRR folders.
//!
//! Arrows point down: this crate depends on `ctcal-core` only (the events, the pixel
//! selection, the estimators a window feeds), and never on the report or the command line.

pub mod aedat4;
pub mod aps_region;
pub mod bag;
pub mod biases;
mod blocks;
#[cfg(feature = "hdf5")]
pub mod blosc;
pub mod dat;
mod detect;
pub mod error;
pub mod events_area;
pub mod evt2;
pub mod evt3;
pub mod fit_region;
pub mod frame_blocks;
pub mod frame_list;
pub mod h5;
pub mod ijrr;
pub mod info;
pub mod mask;
pub mod npy;
pub mod order;
pub mod peers;
pub mod prophesee;
pub mod read_ahead;
mod recording;
pub mod text;
pub mod window;
pub mod write;

pub use biases::Biases;
pub use ctcal_core::format::Format;
pub use detect::detect;
pub use error::InputError;
pub use frame_list::FrameList;
pub use order::OrderCheck;
pub use recording::{EventStream, OpenOptions, Recording, ResolvedSensor};

// the core modules by their old paths (`crate::events`, ...), as when this was a module of
// one crate
use ctcal_core::{estimate, events, files, hint, selection, sensors, sim, stats};

use crate::events::{EventChunk, MAX_SENSOR_SIDE, Sensor};
use crate::hint::{Hint, Text};
use std::path::Path;

/// How far a decoder has read (bytes, or rows for HDF5).
#[derive(Clone, Copy, Debug, Default)]
pub struct Progress {
    pub done: u64,
    pub total: u64,
}

/// A format decoder: appends events to a chunk, at most [`CHUNK_EVENTS`] per call; a call
/// that appends nothing means the file is exhausted.
pub trait EventDecoder: Send {
    fn read_chunk(&mut self, out: &mut EventChunk) -> Result<(), InputError>;
    fn order(&self) -> &OrderCheck;
    fn progress(&self) -> Progress;
}

/// Whether `(x, y)` may be an event of `sensor`; while the sensor is not known, of a sensor
/// of at most [`MAX_SENSOR_SIDE`] a side.
#[inline(always)]
pub(crate) fn within(sensor: Option<Sensor>, x: u32, y: u32) -> bool {
    let (w, h) = sensor.map_or((MAX_SENSOR_SIDE, MAX_SENSOR_SIDE), |s| (s.width, s.height));
    x < w as u32 && y < h as u32
}

/// The error for an event outside the sensor (or beyond [`MAX_SENSOR_SIDE`] when the sensor
/// is not known).
pub(crate) fn outside_sensor(
    path: &Path,
    place: String,
    x: i64,
    y: i64,
    sensor: Option<Sensor>,
) -> InputError {
    let (width, height) =
        sensor.map_or((MAX_SENSOR_SIDE, MAX_SENSOR_SIDE), |s| (s.width, s.height));
    InputError::OutsideSensor {
        path: path.to_path_buf(),
        place,
        x,
        y,
        width,
        height,
        claimed: String::new(),
        fix: match sensor {
            Some(s) => Text::from(format!(
                "if the sensor is larger than {s} (the size given, or the file's own: x must stay below {}, y below {}), ",
                s.width, s.height
            )),
            None => Text::from(format!("the file does not state its sensor and ctcal infers at most {MAX_SENSOR_SIDE}x{MAX_SENSOR_SIDE}: if the sensor really is that large, ")),
        }
        .act(Hint::Sensor(None))
        .words("; otherwise the file is damaged"),
    }
}
