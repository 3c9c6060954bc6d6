//! Reading and writing recordings: every common event-camera file format into one
//! representation ([`EventChunk`]s of integer-microsecond events, plus [`Frame`]s).
//!
//! One decoder module per format (as faery does), each streaming in chunks so memory stays
//! bounded whatever the file size, each checking what the file claims (resolution, time
//! order) against the data and naming the place of any problem. [`Recording`] ties them
//! together: format detection from content, the sensor size, frames and stimulus.

pub mod aedat4;
pub mod bag;
pub mod biases;
mod blocks;
pub mod blosc;
pub mod dat;
mod detect;
pub mod error;
pub mod evt2;
pub mod evt3;
pub mod frame_list;
pub mod h5;
mod h5_direct;
pub mod ijrr;
pub mod info;
pub mod mask;
pub mod npy;
pub mod order;
pub mod prophesee;
pub mod read_ahead;
mod recording;
pub mod text;
pub mod write;

pub use biases::Biases;
pub use detect::detect;
pub use error::InputError;
pub use frame_list::FrameList;
pub use order::OrderCheck;
pub use recording::{EventStream, OpenOptions, Recording, ResolvedSensor};

use crate::events::{EventChunk, MAX_SENSOR_SIDE, Sensor};
use crate::hint::{Hint, Text};
use serde::Serialize;
use std::path::Path;

/// The file formats ctcal reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    Ijrr,
    H5,
    Aedat4,
    Evt2,
    Evt3,
    Dat,
    Bag,
}

impl Format {
    pub const ALL: [Format; 7] = [
        Format::Ijrr,
        Format::H5,
        Format::Aedat4,
        Format::Evt2,
        Format::Evt3,
        Format::Dat,
        Format::Bag,
    ];

    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Format::Ijrr => "ijrr",
            Format::H5 => "h5",
            Format::Aedat4 => "aedat4",
            Format::Evt2 => "evt2",
            Format::Evt3 => "evt3",
            Format::Dat => "dat",
            Format::Bag => "bag",
        }
    }
}

impl std::str::FromStr for Format {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Format::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| {
                format!("unknown format `{s}` (one of ijrr, h5, aedat4, evt2, evt3, dat, bag)")
            })
    }
}

impl std::fmt::Display for Format {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

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
            Some(_) => Text::from("if the sensor is larger than the file says, "),
            None => Text::from(format!("the file does not state its sensor and ctcal infers at most {MAX_SENSOR_SIDE}x{MAX_SENSOR_SIDE}: if the sensor really is that large, ")),
        }
        .act(Hint::Sensor(None))
        .words("; otherwise the file is damaged"),
    }
}
