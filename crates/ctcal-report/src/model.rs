//! The report model: everything `ctcal report` computed, in one value that every exporter
//! renders (HTML, Markdown, tables, plots, configs) and that is written whole as
//! `results.json`.

use crate::estimate::CtEstimate;
use crate::fit::FitResult;
use crate::stats::SequenceStats;
use serde::Serialize;
use std::collections::BTreeMap;

/// A whole report.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub ctcal_version: &'static str,
    /// The command line that made it.
    pub command_line: Vec<String>,
    /// The seed of every simulation.
    pub seed: u64,
    pub sequences: Vec<SequenceReport>,
    pub datasets: Vec<DatasetReport>,
    /// Events per pixel per second of the calibration scene at the paper's fixed presets.
    pub presets: Vec<PresetLevel>,
    /// How the presets were simulated.
    pub presets_scene: String,
    /// Recordings that could not be reported, with the error.
    pub failed: Vec<FailedSequence>,
}

/// A recording the report could not be made of.
#[derive(Clone, Debug, Serialize)]
pub struct FailedSequence {
    pub name: String,
    pub path: String,
    pub error: String,
}

/// An input file: where, how big and its content hash.
#[derive(Clone, Debug, Serialize)]
pub struct InputFile {
    pub path: String,
    pub bytes: u64,
    pub sha256: String,
}

/// One contrast-threshold method's result for a sequence.
#[derive(Clone, Debug, Serialize)]
pub struct MethodResult {
    pub method: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimate: Option<CtEstimate>,
    /// Why the method could not be applied (its message).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_applied: Option<String>,
}

/// The parameters a recording was made with, where it says (a simulation's
/// `simulation.json`, an oracle's `params.json`).
#[derive(Clone, Debug, Serialize)]
pub struct Truth {
    pub source: String,
    /// PARAMS.toml keys and values.
    pub params: BTreeMap<String, f64>,
}

/// The per-pixel data of one recording, kept only until its plots and masks are rendered.
#[derive(Clone, Debug, Default)]
pub struct PixelData {
    /// Events per pixel (kept pixels), for the count and hot-pixel maps.
    pub counts: Vec<u32>,
    pub maps: Option<PixelMaps>,
}

/// Per-pixel thresholds from event timing (`estimate aps`), NaN where a pixel has too
/// little evidence.
#[derive(Clone, Debug)]
pub struct PixelMaps {
    pub width: usize,
    pub height: usize,
    pub ct_on: Vec<f32>,
    pub ct_off: Vec<f32>,
}

/// One recording.
#[derive(Clone, Debug, Serialize)]
pub struct SequenceReport {
    /// A short unique name (file or folder name).
    pub name: String,
    pub dataset: String,
    pub format: String,
    pub inputs: Vec<InputFile>,
    pub stats: SequenceStats,
    pub methods: Vec<MethodResult>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fit: Option<FitResult>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fit_not_applied: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth: Option<Truth>,
    /// What reading the recording warned of (sensor size guessed, frames thinned, ...).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// The files rendered of it (filled in by [`super::render_sequence`]).
    pub outputs: SequenceOutputs,
    /// Seconds spent on each stage.
    pub seconds: BTreeMap<String, f64>,
}

/// The files of one sequence inside the report folder.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SequenceOutputs {
    pub plots: Vec<PlotEntry>,
    pub configs: Vec<String>,
    pub masks: Vec<String>,
    /// Plots that could not be drawn, with the error.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub plots_not_drawn: Vec<String>,
}

/// A plot of the report: its file stem under `plots/` and its title.
#[derive(Clone, Debug, Serialize)]
pub struct PlotEntry {
    pub name: String,
    pub title: String,
}

impl SequenceReport {
    /// The estimate of `method`, if it was applied.
    pub fn estimate(&self, method: &str) -> Option<&CtEstimate> {
        self.methods
            .iter()
            .find(|m| m.method == method)
            .and_then(|m| m.estimate.as_ref())
    }

    /// The sensor as `WxH`.
    pub fn sensor(&self) -> String {
        format!("{}x{}", self.stats.width, self.stats.height)
    }

    /// The fit's thresholds, where the recording identifies them.
    pub fn fitted_thresholds(&self) -> Option<(f64, f64)> {
        let f = self.fit.as_ref()?;
        let known = |k: &str| !f.params.not_identified.contains_key(k);
        (known("ct_on") && known("ct_off")).then_some((f.params.ct_on, f.params.ct_off))
    }

    /// The best threshold estimate available (fit, then aps, screen, eppps): (ON, OFF,
    /// method).
    pub fn best_thresholds(&self) -> Option<(f64, f64, &'static str)> {
        if let Some((on, off)) = self.fitted_thresholds() {
            return Some((on, off, "fit"));
        }
        ["aps", "screen", "eppps"].into_iter().find_map(|m| {
            let e = self.estimate(m)?;
            let (on, off) = e.thresholds()?;
            Some((on, off, e.method))
        })
    }
}

/// A dataset: the sequences grouped under one name, and their aggregates.
#[derive(Clone, Debug, Serialize)]
pub struct DatasetReport {
    pub name: String,
    pub sequences: Vec<String>,
    /// Events per pixel per second: mean and the range over sequences.
    pub events_per_pixel_per_second: Summary,
    /// Per method, the thresholds (mean of ON and OFF) over sequences.
    pub ct: BTreeMap<String, Summary>,
    /// Per fitted parameter, its value over sequences.
    pub fitted: BTreeMap<String, Summary>,
    /// Effects added in how many of the fitted sequences.
    pub effects: BTreeMap<String, usize>,
    /// The sensors (`WxH`) of its sequences.
    pub sensors: Vec<String>,
    /// What a reader of its aggregates must know (e.g. that it mixes sensors).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// Mean, standard deviation (of two or more values), minimum and maximum of some values.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    pub n: usize,
    pub mean: f64,
    pub sd: Option<f64>,
    pub min: f64,
    pub max: f64,
}

impl Summary {
    pub fn of(values: &[f64]) -> Option<Self> {
        let values: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
        if values.is_empty() {
            return None;
        }
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let sd = (values.len() > 1)
            .then(|| (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt());
        Some(Self {
            n: values.len(),
            mean,
            sd,
            min: values.iter().copied().fold(f64::INFINITY, f64::min),
            max: values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        })
    }
}

/// A preset of the paper's Fig. 2.
#[derive(Clone, Debug, Serialize)]
pub struct PresetLevel {
    pub ct: f64,
    pub events_per_pixel_per_second: f64,
}

/// The identified numeric parameters of a fit, as (PARAMS.toml key, value): the ones the
/// recording does not identify are left out.
pub fn identified_params(f: &FitResult) -> Vec<(String, f64)> {
    crate::configs::numeric_params(&f.params)
        .into_iter()
        .filter(|(k, _)| !f.params.not_identified.contains_key(k))
        .collect()
}

/// The sensors of some sequences (`WxH`), each once, with how many sequences have it.
pub fn sensors(sequences: &[&SequenceReport]) -> Vec<(String, usize)> {
    let mut out: Vec<(String, usize)> = Vec::new();
    for s in sequences {
        let sensor = s.sensor();
        match out.iter_mut().find(|(k, _)| *k == sensor) {
            Some(entry) => entry.1 += 1,
            None => out.push((sensor, 1)),
        }
    }
    out
}

/// The warning for a dataset whose sequences come from sensors of different sizes.
fn mixed_sensors_warning(sensors: &[(String, usize)]) -> Option<String> {
    (sensors.len() > 1).then(|| {
        format!(
            "this dataset mixes sensors ({}): its means and spreads pool different cameras, and no simulator configuration is combined across them; name one dataset per sensor",
            sensors
                .iter()
                .map(|(s, n)| format!("{s}: {n} sequence{}", if *n == 1 { "" } else { "s" }))
                .collect::<Vec<_>>()
                .join(", ")
        )
    })
}

/// The aggregates of one dataset's sequences.
fn dataset(name: String, members: &[&SequenceReport]) -> DatasetReport {
    let rates: Vec<f64> = members
        .iter()
        .filter_map(|s| s.stats.events_per_pixel_per_second)
        .collect();
    let mut ct = BTreeMap::new();
    for method in ["aps", "eppps", "screen"] {
        let values: Vec<f64> = members
            .iter()
            .filter_map(|s| s.estimate(method).and_then(|e| e.ct))
            .collect();
        if let Some(summary) = Summary::of(&values) {
            ct.insert(method.to_string(), summary);
        }
    }
    let fitted_ct: Vec<f64> = members
        .iter()
        .filter_map(|s| s.fitted_thresholds().map(|(on, off)| 0.5 * (on + off)))
        .collect();
    if let Some(summary) = Summary::of(&fitted_ct) {
        ct.insert("fit".to_string(), summary);
    }
    let mut fitted = BTreeMap::new();
    let mut effects = BTreeMap::new();
    for f in members.iter().filter_map(|s| s.fit.as_ref()) {
        for (key, value) in identified_params(f) {
            fitted.entry(key).or_insert_with(Vec::new).push(value);
        }
        for e in &f.effects_added {
            *effects.entry(e.effect.name().to_string()).or_insert(0) += 1;
        }
    }
    let sensors = sensors(members);
    DatasetReport {
        sequences: members.iter().map(|s| s.name.clone()).collect(),
        events_per_pixel_per_second: Summary::of(&rates).unwrap_or(Summary {
            n: 0,
            mean: f64::NAN,
            sd: None,
            min: f64::NAN,
            max: f64::NAN,
        }),
        ct,
        fitted: fitted
            .into_iter()
            .filter_map(|(k, v)| Summary::of(&v).map(|s| (k, s)))
            .collect(),
        effects,
        warnings: mixed_sensors_warning(&sensors).into_iter().collect(),
        sensors: sensors.into_iter().map(|(s, _)| s).collect(),
        name,
    }
}

/// The aggregates of the sequences of each dataset (in the order datasets first appear).
pub fn datasets(sequences: &[SequenceReport]) -> Vec<DatasetReport> {
    let mut names: Vec<String> = Vec::new();
    for s in sequences {
        if !names.contains(&s.dataset) {
            names.push(s.dataset.clone());
        }
    }
    names
        .into_iter()
        .map(|name| {
            let members: Vec<&SequenceReport> =
                sequences.iter().filter(|s| s.dataset == name).collect();
            dataset(name, &members)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summaries_of_values() {
        let s = Summary::of(&[1.0, 2.0, 3.0, f64::NAN]).unwrap();
        assert_eq!((s.n, s.mean, s.min, s.max), (3, 2.0, 1.0, 3.0));
        assert!((s.sd.unwrap() - 1.0).abs() < 1e-12);
        assert!(Summary::of(&[]).is_none());
    }
}
