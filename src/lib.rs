//! # ctcal: what an event camera really is
//!
//! An event-camera (DVS) pixel compares its log intensity `L = ln I` with the level it
//! memorised at its last event; when `L` has risen by the ON contrast threshold `Cp` (or
//! fallen by the OFF threshold `Cn`) it emits an event and moves its memorised level by that
//! threshold (Lichtsteiner, Posch & Delbruck, IEEE JSSC 2008). Real pixels deviate: their
//! thresholds vary from pixel to pixel, they are blind for a refractory period after each
//! event, their photoreceptor is a low-pass filter whose bandwidth falls in the dark, junction
//! leakage makes the memorised level drift (ON events in a static scene), shot noise fires
//! events at random, and a few pixels are hot. Networks trained on simulated events
//! generalise badly when the simulator's thresholds and noise do not match the real camera
//! (Stoffregen et al., "Reducing the Sim-to-Real Gap for Event Cameras", ECCV 2020).
//!
//! ctcal reads recordings in every common format ([`io`]), measures their statistics
//! ([`stats`]), simulates pixels with each of these effects switchable ([`sim`]), and uses
//! the simulator to estimate contrast thresholds and fit every simulator parameter.
//!
//! Time is integer microseconds throughout; seconds appear only at the edges (text files,
//! JSON keys ending `_s`). The library never prints: it returns values and errors, and the
//! `ctcal` binary presents them.

pub mod coverage;
pub mod estimate;
pub mod events;
pub mod files;
pub mod fit;
pub mod hint;
pub mod io;
pub mod report;
pub mod selection;
pub mod sensors;

pub use events::{CHUNK_EVENTS, Event, EventChunk, Frame, Sensor, TimeUs};
pub use io::{Format, InputError, OpenOptions, Recording};
pub mod sim;
pub mod stats;
pub mod synthetic;
pub mod window;
