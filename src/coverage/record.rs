//! One line of `results.jsonl`: a (case, method) run with the case spec, its truth, the
//! method's full JSON or its error, and what it reported per parameter. A compact record
//! drops the full JSON and keeps the rest, enough to tabulate again.

use super::case::CaseSpec;
use super::method::Method;
use super::reported::{Reported, extract};
use super::truth::Truth;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;
use std::io::BufRead;
use std::path::Path;

/// How a run ended.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum Outcome {
    /// Exit 0 with JSON on stdout (dropped in a compact record).
    Ok {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        output: Option<Value>,
    },
    /// A non-zero exit, a time-out, or a case that could not be written.
    Failed {
        exit_code: Option<i32>,
        timed_out: bool,
        message: String,
    },
}

/// A (case, method) run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    pub case: CaseSpec,
    /// `None` when the case could not be written.
    pub truth: Option<Truth>,
    pub method: Method,
    pub seconds: f64,
    pub outcome: Outcome,
    pub reported: BTreeMap<String, Reported>,
    /// The effects a fit added, in order (empty for the estimators).
    #[serde(default)]
    pub effects_added: Vec<String>,
    /// A fit's `hot_pixel_detection.probability`: `[rate_hz, share of pixels]` at which its
    /// hot-pixel search names a hot pixel of that rate (what its `hot_pixel_fraction`
    /// counts of hot pixels of each rate).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hot_detection: Option<Vec<[f64; 2]>>,
}

/// The `effect` names of a fit's `effects_added`.
fn effects_added(output: &Value) -> Vec<String> {
    output["effects_added"]
        .as_array()
        .map(|added| {
            added
                .iter()
                .filter_map(|e| e["effect"].as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default()
}

impl RunRecord {
    /// A record whose `reported` is read from the outcome's JSON.
    pub fn new(
        case: CaseSpec,
        truth: Option<Truth>,
        method: Method,
        seconds: f64,
        outcome: Outcome,
    ) -> Self {
        let mut record = Self {
            case,
            truth,
            method,
            seconds,
            outcome,
            reported: BTreeMap::new(),
            effects_added: Vec::new(),
            hot_detection: None,
        };
        record.read_output();
        record
    }

    /// Reads `reported`, `effects_added` and a fit's `hot_detection` from the full JSON,
    /// where it is kept.
    fn read_output(&mut self) {
        if let Outcome::Ok {
            output: Some(output),
        } = &self.outcome
        {
            self.reported = extract(self.method, output);
            self.hot_detection =
                serde_json::from_value(output["hot_pixel_detection"]["probability"].clone()).ok();
            self.effects_added = effects_added(output);
        }
    }

    /// The record without the method's full JSON.
    pub fn compact(&self) -> Self {
        let mut record = self.clone();
        if let Outcome::Ok { output } = &mut record.outcome {
            *output = None;
        }
        record
    }

    /// The failure message, if the run failed.
    pub fn failure(&self) -> Option<&str> {
        match &self.outcome {
            Outcome::Failed { message, .. } => Some(message),
            Outcome::Ok { .. } => None,
        }
    }

    pub fn to_line(&self) -> String {
        serde_json::to_string(self).expect("records serialise")
    }
}

/// Every record of a `results.jsonl` (full or compact); a record with the full JSON is read
/// again, so that a change in [`extract`] applies to old results.
pub fn read_jsonl(path: &Path) -> std::io::Result<Vec<RunRecord>> {
    let file = std::io::BufReader::new(std::fs::File::open(path)?);
    let mut records = Vec::new();
    for (number, line) in file.lines().enumerate() {
        let line = line?;
        if line.trim().is_empty() {
            continue;
        }
        let mut record: RunRecord = serde_json::from_str(&line).map_err(|e| {
            std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!("{}:{}: {e}", path.display(), number + 1),
            )
        })?;
        record.read_output();
        records.push(record);
    }
    Ok(records)
}

/// The record of the draw of `seed` in a committed study's results (`benches/coverage/...`,
/// relative to the crate), for tests that check the tables on real runs.
#[cfg(test)]
pub fn committed(results: &str, seed: u64) -> RunRecord {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(results);
    read_jsonl(&path)
        .unwrap()
        .into_iter()
        .find(|r| r.case.seed == seed)
        .unwrap_or_else(|| panic!("no draw {seed} in {results}"))
}
