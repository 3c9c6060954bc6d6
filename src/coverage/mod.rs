//! A coverage study: do ctcal's 95 % intervals contain the truth 95 % of the time?
//!
//! Every estimator (`estimate aps|eppps|screen`) and the fit report values with 95 %
//! intervals. This module draws random recordings with known parameters ([`CaseSpec::draw`]:
//! scene family, brightness, speed, frame rate, thresholds and every effect at random
//! strengths, or the calibration checkerboard on a random display), writes them as IJRR
//! folders with their truth ([`write_case`]); the runner (`benches/coverage/run.rs`) runs
//! the `ctcal` binary on them; this module reads each parameter's value and interval out of its JSON
//! ([`reported`]) and tabulates the empirical coverage ([`summary`]). The runner is
//! `benches/coverage/` (`cargo run --release --example coverage`); its measurement is
//! `benches/coverage/COVERAGE.md`.

pub mod case;
pub mod draw;
mod draw_peer;
mod draw_scene;
pub mod method;
pub mod record;
pub mod reported;
pub mod summary;
pub mod truth;
pub mod write;

pub use case::{CaseSpec, Generator, RecordingSpec, SceneFamily};
pub use method::Method;
pub use record::{Outcome, RunRecord};
pub use reported::Reported;
pub use truth::Truth;
pub use write::write_case;
