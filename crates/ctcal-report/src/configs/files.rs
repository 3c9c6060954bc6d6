//! Which configuration files a report writes: every format for each fitted sequence, and
//! combined ones only over sequences of one sensor (a dataset of one sensor; the
//! esim_config_generator file per sensor), never across sensors.

use super::{ConfigFormat, Setup, render};
use crate::model::{Report, SequenceReport};
use crate::sim::PixelParams;
use std::collections::BTreeMap;

/// The formats a report writes for each fit.
const FORMATS: [ConfigFormat; 5] = ConfigFormat::ALL;

/// The setup of one sequence's fit.
fn setup_of(s: &SequenceReport, seed: u64) -> Option<Setup> {
    let f = s.fit.as_ref()?;
    Some(Setup {
        exposure_ms: f.frame_exposure_us.map(|e| e as f64 / 1e3),
        seed,
        sensor: Some((s.stats.width as u32, s.stats.height as u32)),
        not_identified: f.params.not_identified.clone(),
        not_detected: f.not_detected.clone(),
    })
}

/// (path, text) of each configuration of a fitted sequence.
pub fn of_sequence(s: &SequenceReport, seed: u64) -> Vec<(String, String)> {
    let (Some(f), Some(setup)) = (&s.fit, setup_of(s, seed)) else {
        return Vec::new();
    };
    let fits = std::slice::from_ref(&f.params.model);
    FORMATS
        .into_iter()
        .filter_map(|format| {
            render(format, fits, &setup)
                .map(|text| (format!("configs/{}/{}", s.name, format.file_name()), text))
        })
        .collect()
}

/// One setup for several fitted sequences of one sensor: their exposure where all agree,
/// every parameter any of them does not identify.
fn combined_setup(members: &[&SequenceReport], seed: u64) -> Option<Setup> {
    let setups: Vec<Setup> = members.iter().filter_map(|s| setup_of(s, seed)).collect();
    let first = setups.first()?;
    let mut not_identified = BTreeMap::new();
    let named = members
        .iter()
        .filter(|s| s.fit.is_some())
        .map(|s| s.name.clone());
    let mut per_fit = Vec::new();
    for (s, name) in setups.iter().zip(named) {
        not_identified.extend(s.not_identified.clone());
        per_fit.push((name, s.not_detected.clone()));
    }
    let not_detected = super::merged_reasons(&per_fit);
    Some(Setup {
        exposure_ms: setups
            .iter()
            .all(|s| s.exposure_ms == first.exposure_ms)
            .then_some(first.exposure_ms)
            .flatten(),
        seed,
        sensor: first.sensor,
        not_identified,
        not_detected,
    })
}

fn models(members: &[&SequenceReport]) -> Vec<PixelParams> {
    members
        .iter()
        .filter_map(|s| s.fit.as_ref().map(|f| f.params.model.clone()))
        .collect()
}

/// (path, text) of the combined configurations: every format for each dataset of one
/// sensor with two or more fits, and an esim_config_generator file covering the fits of
/// each sensor (`configs/esim_config_generator.json` when there is one sensor).
pub fn combined(report: &Report) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for d in report.datasets.iter().filter(|d| d.sensors.len() == 1) {
        let members: Vec<&SequenceReport> = report
            .sequences
            .iter()
            .filter(|s| s.dataset == d.name && s.fit.is_some())
            .collect();
        let (fits, Some(setup)) = (models(&members), combined_setup(&members, report.seed)) else {
            continue;
        };
        if fits.len() > 1 {
            for format in FORMATS {
                if let Some(text) = render(format, &fits, &setup) {
                    out.push((
                        format!("configs/datasets/{}/{}", d.name, format.file_name()),
                        text,
                    ));
                }
            }
        }
    }
    let fitted: Vec<&SequenceReport> = report
        .sequences
        .iter()
        .filter(|s| s.fit.is_some())
        .collect();
    let sensors = crate::model::sensors(&fitted);
    for (sensor, _) in &sensors {
        let members: Vec<&SequenceReport> = fitted
            .iter()
            .copied()
            .filter(|s| s.sensor() == *sensor)
            .collect();
        let Some(setup) = combined_setup(&members, report.seed) else {
            continue;
        };
        let path = if sensors.len() == 1 {
            "configs/esim_config_generator.json".to_string()
        } else {
            format!("configs/sensors/{sensor}/esim_config_generator.json")
        };
        if let Some(text) = render(ConfigFormat::EsimGenerator, &models(&members), &setup) {
            out.push((path, text));
        }
    }
    out
}
