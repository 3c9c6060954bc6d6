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
//!
//! ## Layout
//!
//! This package is the `ctcal` binary (`src/main.rs`, `src/cli/`) and this facade, which
//! re-exports the workspace's library crates under the paths of the single crate they
//! were split from (`ctcal::sim`, `ctcal::io`, `ctcal::report`, ...), plus the coverage
//! study ([`coverage`]), which runs the binary. Arrows point down:
//!
//! - `ctcal-core`: events, simulator, statistics, estimators, fit (no other ctcal crate);
//! - `ctcal-io`: readers, writers, the loading of a window of a recording (on core);
//! - `ctcal-report`: tables, plots, pages and configurations of what was computed (on
//!   core; it reads no recording);
//! - `ctcal-pipeline`: the report pipeline, each recording read through io, analysed by
//!   core and rendered by report (on all three);
//! - `ctcal` (this package): the command line and the coverage study, on all four.

pub use ctcal_core::*;
pub use ctcal_io as io;
pub use ctcal_io::{Format, InputError, OpenOptions, Recording};
pub use ctcal_io::{aps_region, fit_region, window};

/// The report ([`ctcal_report`]) with its pipeline ([`ctcal_pipeline`]) under the path they
/// had in one crate, `ctcal::report::pipeline`.
pub mod report {
    pub use ctcal_pipeline as pipeline;
    pub use ctcal_report::*;
}

pub mod coverage;

/// The pixel simulator ([`ctcal_core::sim`]), with the writing of a peer simulator's case
/// as an IJRR folder ([`ctcal_io::peers::write_case`]) under its old path.
pub mod sim {
    pub use ctcal_core::sim::*;

    /// Other simulators' pixel models ([`ctcal_core::sim::peers`]), with
    /// [`write_case`] from the IO crate.
    pub mod peers {
        pub use ctcal_core::sim::peers::*;
        pub use ctcal_io::peers::write_case;
    }
}
