//! The sensor biases a recording carries or sits beside, as the camera software saved them:
//! the type only, so that the statistics and the fit can report them; the IO crate
//! (`ctcal-io`, `biases`) finds and parses them.

use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Bias values by name, and the file they were read from.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Biases {
    pub source: PathBuf,
    pub values: BTreeMap<String, i64>,
}
