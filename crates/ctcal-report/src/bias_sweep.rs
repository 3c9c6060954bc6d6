//! Thresholds and noise beside the sensor biases that differ between recordings of one
//! sensor: when a report holds several recordings of one camera made at different bias
//! settings, the measured pairs (bias value, threshold; bias value, noise rate) side by
//! side. Measured pairs only: no bias-to-threshold model is fitted or assumed (how a bias
//! current maps to a threshold depends on the pixel circuit and its process; the vendors'
//! bias guides give directions, not numbers).

use super::model::SequenceReport;
use super::tables::{Table, floats, strings, table};
use std::collections::{BTreeMap, BTreeSet};

/// The bias names whose values differ among the recordings of one sensor (`sensor` of each
/// recording, its biases if it carries any): for each sensor with at least two recordings
/// with biases, the names set to more than one value (a name missing from some is not
/// compared).
pub fn differing<'a>(
    recordings: impl IntoIterator<Item = (String, &'a BTreeMap<String, i64>)>,
) -> BTreeSet<String> {
    let mut by_sensor: BTreeMap<String, Vec<&BTreeMap<String, i64>>> = BTreeMap::new();
    for (sensor, biases) in recordings {
        by_sensor.entry(sensor).or_default().push(biases);
    }
    let mut out = BTreeSet::new();
    for sets in by_sensor.values().filter(|s| s.len() >= 2) {
        let names: BTreeSet<&String> = sets.iter().flat_map(|b| b.keys()).collect();
        for name in names {
            let values: BTreeSet<i64> = sets.iter().filter_map(|b| b.get(name).copied()).collect();
            if values.len() > 1 {
                out.insert(name.clone());
            }
        }
    }
    out
}

/// The recordings that carry biases, with their biases.
fn with_biases<'a>(
    sequences: &[&'a SequenceReport],
) -> Vec<(&'a SequenceReport, &'a BTreeMap<String, i64>)> {
    sequences
        .iter()
        .filter_map(|s| Some((*s, &s.stats.biases.as_ref()?.values)))
        .collect()
}

/// One recording in a sweep of one bias.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepPoint {
    pub sequence: String,
    pub sensor: String,
    /// The bias's value in this recording.
    pub value: i64,
    /// The best thresholds (ON, OFF) and the method they come from, where measured.
    pub thresholds: Option<(f64, f64, &'static str)>,
    /// Null where the recording does not determine it (see its statistics' `why`).
    pub background_rate_hz: Option<f64>,
}

/// For each bias that differs between recordings of one sensor, the recordings that set it,
/// by sensor and value.
pub fn sweeps(sequences: &[&SequenceReport]) -> Vec<(String, Vec<SweepPoint>)> {
    let with = with_biases(sequences);
    let names = differing(with.iter().map(|(s, b)| (s.sensor(), *b)));
    names
        .into_iter()
        .map(|name| {
            let mut points: Vec<SweepPoint> = with
                .iter()
                .filter_map(|(s, b)| {
                    Some(SweepPoint {
                        sequence: s.name.clone(),
                        sensor: s.sensor(),
                        value: *b.get(&name)?,
                        thresholds: s.best_thresholds(),
                        background_rate_hz: s.stats.background_rate_hz,
                    })
                })
                .collect();
            points.sort_by(|a, b| (&a.sensor, a.value).cmp(&(&b.sensor, b.value)));
            (name, points)
        })
        .collect()
}

/// The bias sweep table: one row per recording that carries biases, with each differing
/// bias, the best thresholds (and the method they come from) and the background rate;
/// `None` when no bias differs between recordings of one sensor.
pub fn bias_sweep(sequences: &[&SequenceReport]) -> Option<Table> {
    let with = with_biases(sequences);
    let names = differing(with.iter().map(|(s, b)| (s.sensor(), *b)));
    if names.is_empty() {
        return None;
    }
    let best: Vec<Option<(f64, f64, &'static str)>> =
        with.iter().map(|(s, _)| s.best_thresholds()).collect();
    let mut columns = vec![
        strings(
            "sequence",
            with.iter().map(|(s, _)| s.name.clone()).collect(),
        ),
        strings("sensor", with.iter().map(|(s, _)| s.sensor()).collect()),
    ];
    for name in &names {
        let column = if name.starts_with("bias") {
            name.clone()
        } else {
            format!("bias_{name}")
        };
        columns.push(floats(
            &column,
            with.iter()
                .map(|(_, b)| b.get(name).map(|&v| v as f64))
                .collect(),
        ));
    }
    columns.extend([
        floats("ct_on", best.iter().map(|b| b.map(|t| t.0)).collect()),
        floats("ct_off", best.iter().map(|b| b.map(|t| t.1)).collect()),
        strings(
            "method",
            best.iter()
                .map(|b| b.map_or("", |t| t.2).to_string())
                .collect(),
        ),
        floats(
            "background_rate_hz",
            with.iter()
                .map(|(s, _)| s.stats.background_rate_hz)
                .collect(),
        ),
    ]);
    Some(table(
        "bias_sweep",
        "Thresholds and background rate beside the biases that differ between recordings of one sensor (measured pairs; no bias model)",
        columns,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn biases(pairs: &[(&str, i64)]) -> BTreeMap<String, i64> {
        pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect()
    }

    #[test]
    fn only_biases_that_differ_within_one_sensor_are_swept() {
        let a = biases(&[("bias_diff_on", 10), ("bias_fo", 55), ("bias_hpf", 0)]);
        let b = biases(&[("bias_diff_on", 25), ("bias_fo", 55), ("bias_hpf", 0)]);
        // another sensor whose bias_hpf differs from the first pair's is not compared
        let c = biases(&[("bias_diff_on", 10), ("bias_hpf", 40)]);
        let names = differing([
            ("1280x720".to_string(), &a),
            ("1280x720".to_string(), &b),
            ("640x480".to_string(), &c),
        ]);
        assert_eq!(names, BTreeSet::from(["bias_diff_on".to_string()]));
        // one recording per sensor: nothing to sweep
        assert!(differing([("1280x720".to_string(), &a), ("640x480".to_string(), &c)]).is_empty());
        // the same settings twice: nothing differs
        assert!(differing([("1280x720".to_string(), &a), ("1280x720".to_string(), &a)]).is_empty());
    }
}
