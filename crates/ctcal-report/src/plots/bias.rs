//! Thresholds and background rate against each bias that differs between recordings of one
//! sensor ([`crate::bias_sweep`]): measured pairs joined in order of the bias value, one
//! series per polarity and sensor. No curve is fitted between them (no bias model).

use super::lines::{Lines, Pair};
use crate::bias_sweep::SweepPoint;
use std::collections::BTreeSet;

/// The two panels of one bias's sweep: thresholds (left), background rate (right).
pub(super) fn sweep(bias: &str, points: &[SweepPoint]) -> Pair {
    let sensors: BTreeSet<&str> = points.iter().map(|p| p.sensor.as_str()).collect();
    let label = |what: &str, sensor: &str| {
        if sensors.len() > 1 {
            format!("{what} {sensor}")
        } else {
            what.to_string()
        }
    };
    let (mut thresholds, mut rates) = (Vec::new(), Vec::new());
    for sensor in &sensors {
        let of_sensor: Vec<&SweepPoint> = points.iter().filter(|p| p.sensor == *sensor).collect();
        let series = |pick: fn(&(f64, f64, &'static str)) -> f64| -> Vec<(f64, f64)> {
            of_sensor
                .iter()
                .filter_map(|p| Some((p.value as f64, pick(p.thresholds.as_ref()?))))
                .collect()
        };
        thresholds.push((label("ON", sensor), series(|t| t.0)));
        thresholds.push((label("OFF", sensor), series(|t| t.1)));
        rates.push((
            label("background", sensor),
            of_sensor
                .iter()
                .filter_map(|p| Some((p.value as f64, p.background_rate_hz?)))
                .collect(),
        ));
    }
    let x_label = format!("{bias} (the recording's bias value)");
    Pair(
        Lines {
            title: "best contrast thresholds".into(),
            x_label: x_label.clone(),
            y_label: "threshold (ln units)".into(),
            log_x: false,
            series: thresholds,
            zero: true,
        },
        Lines {
            title: "background rate".into(),
            x_label,
            y_label: "events / pixel / s".into(),
            log_x: false,
            series: rates,
            zero: true,
        },
    )
}
