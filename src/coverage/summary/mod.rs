//! The coverage tables ([`Summary::tabulate`]) and their Markdown (`COVERAGE.md`): per
//! method and parameter the empirical coverage of the 95 % intervals with a binomial
//! interval on it, the errors, the worst misses; a breakdown by what the cases were; the
//! fit's effect detection; and why runs failed or returned no value.

pub mod binomial;
pub mod breakdown;
mod markdown;
pub mod rows;
pub mod score;

pub use breakdown::{Breakdown, BreakdownRow, Cell};
pub use rows::{Miss, Row};

use super::method::{Method, effect_of};
use super::record::RunRecord;
use super::reported::Reported;
use serde::Serialize;
use std::collections::BTreeMap;

/// How often a fit (with frames, or `fit_events` without) added an effect that was there,
/// and one that was not.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Detection {
    pub method: Method,
    pub effect: String,
    /// Successful fits of cases with the effect, and how many added it.
    pub present: usize,
    pub detected: usize,
    /// Successful fits of cases without it, and how many added it anyway.
    pub absent: usize,
    pub false_alarms: usize,
    /// Of the false alarms, how many claimed the effect: its defining parameter
    /// ([`absent_value`]) reported with an interval that excludes the effect's absence (a
    /// false alarm whose interval reaches the absence says "perhaps none", which is true).
    pub false_claims: usize,
}

/// An effect's defining parameter and the value it takes where the effect is absent (a
/// cutoff of infinity: no bandwidth limit).
pub fn absent_value(effect: &str) -> Option<(&'static str, f64)> {
    Some(match effect {
        "bandwidth" => ("cutoff_hz", f64::INFINITY),
        "leak" => ("leak_rate_hz", 0.0),
        "shot_noise" => ("shot_noise_rate_hz", 0.0),
        "refractory" => ("refractory_s", 0.0),
        "hot_pixels" => ("hot_pixel_fraction", 0.0),
        "timestamp_jitter" => ("timestamp_jitter_s", 0.0),
        _ => return None,
    })
}

/// Whether `fit` reports `effect`'s defining parameter with an interval (or a bare value)
/// that excludes the effect's absence; a parameter the data do not determine claims nothing.
fn claims(fit: &RunRecord, effect: &str) -> bool {
    let Some((parameter, absent)) = absent_value(effect) else {
        return false;
    };
    match fit.reported.get(parameter) {
        Some(r @ (Reported::Interval { .. } | Reported::NoInterval { .. })) => !r.covers(absent),
        _ => false,
    }
}

/// A reason (failure message or `why`, numbers as `N`) and how often a method gave it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Reason {
    pub method: Method,
    pub kind: &'static str,
    pub reason: String,
    pub count: usize,
}

/// Runs and time per method.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Timing {
    pub method: Method,
    pub runs: usize,
    pub median_seconds: f64,
    pub total_seconds: f64,
}

/// Every table of the study.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    pub cases: usize,
    pub runs: usize,
    pub rows: Vec<Row>,
    pub breakdowns: Vec<Breakdown>,
    pub detection: Vec<Detection>,
    pub reasons: Vec<Reason>,
    pub timing: Vec<Timing>,
}

/// The fit's effects whose detection is scored.
const DETECTED: [&str; 6] = [
    "bandwidth",
    "leak",
    "shot_noise",
    "refractory",
    "hot_pixels",
    "timestamp_jitter",
];

fn methods(records: &[RunRecord]) -> Vec<Method> {
    Method::ALL
        .into_iter()
        .filter(|m| records.iter().any(|r| r.method == *m))
        .collect()
}

fn detection(records: &[RunRecord]) -> Vec<Detection> {
    [Method::Fit, Method::FitEvents]
        .into_iter()
        .flat_map(|method| detection_of(records, method))
        .collect()
}

fn detection_of(records: &[RunRecord], method: Method) -> Vec<Detection> {
    let fits: Vec<&RunRecord> = records
        .iter()
        .filter(|r| r.method == method && r.failure().is_none() && r.truth.is_some())
        .collect();
    DETECTED
        .iter()
        .map(|&effect| {
            let mut d = Detection {
                method,
                effect: effect.to_string(),
                present: 0,
                detected: 0,
                absent: 0,
                false_alarms: 0,
                false_claims: 0,
            };
            for fit in &fits {
                let added = fit.effects_added.iter().any(|e| e == effect);
                if fit.truth.as_ref().is_some_and(|t| t.has_effect(effect)) {
                    d.present += 1;
                    d.detected += added as usize;
                } else {
                    d.absent += 1;
                    d.false_alarms += added as usize;
                    d.false_claims += (added && claims(fit, effect)) as usize;
                }
            }
            d
        })
        .filter(|d| d.present + d.absent > 0)
        .collect()
}

/// The first line of a message without the input's path (`error: /path/case-N: `) and
/// with every number as `N`, so that one reason from many cases counts as one; cut to 140
/// characters.
fn headline(message: &str) -> String {
    let mut line = message.lines().next().unwrap_or("").trim();
    line = line.strip_prefix("error: ").unwrap_or(line);
    if line.starts_with('/')
        && let Some(end) = line.find(": ")
    {
        line = &line[end + 2..];
    }
    let (mut out, mut in_number) = (String::new(), false);
    let chars: Vec<char> = line.chars().collect();
    for (i, &c) in chars.iter().enumerate() {
        let decimal_point = c == '.' && chars.get(i + 1).is_some_and(char::is_ascii_digit);
        match c {
            '0'..='9' if !in_number => out.push('N'),
            '0'..='9' => {}
            _ if in_number && decimal_point => {}
            _ => out.push(c),
        }
        in_number = c.is_ascii_digit() || (in_number && decimal_point);
    }
    out.chars().take(140).collect()
}

fn reasons(records: &[RunRecord]) -> Vec<Reason> {
    let mut counts: BTreeMap<(Method, &'static str, String), usize> = BTreeMap::new();
    for r in records {
        if let Some(message) = r.failure() {
            *counts
                .entry((r.method, "failed", headline(message)))
                .or_default() += 1;
        }
        for (key, reported) in &r.reported {
            if let Reported::NotDeterminable { why } = reported {
                let reason = format!("{key}: {}", headline(why));
                *counts
                    .entry((r.method, "not determinable", reason))
                    .or_default() += 1;
            }
        }
    }
    let mut reasons: Vec<Reason> = counts
        .into_iter()
        .map(|((method, kind, reason), count)| Reason {
            method,
            kind,
            reason,
            count,
        })
        .collect();
    reasons.sort_by(|a, b| (a.method, b.count).cmp(&(b.method, a.count)));
    reasons
}

fn timing(records: &[RunRecord], method: Method) -> Timing {
    let seconds: Vec<f64> = records
        .iter()
        .filter(|r| r.method == method)
        .map(|r| r.seconds)
        .collect();
    Timing {
        method,
        runs: seconds.len(),
        total_seconds: seconds.iter().sum(),
        median_seconds: binomial::median(seconds).unwrap_or(0.0),
    }
}

impl Summary {
    /// Every table over `records` (full or compact).
    pub fn tabulate(records: &[RunRecord]) -> Self {
        let mut cases: Vec<&str> = records.iter().map(|r| r.case.id.as_str()).collect();
        cases.sort();
        cases.dedup();
        let mut rows = Vec::new();
        let mut breakdowns = Vec::new();
        for method in methods(records) {
            let shown: Vec<Row> = method
                .parameters()
                .iter()
                .map(|p| Row::tabulate(records, method, p))
                .filter(Row::is_shown)
                .collect();
            let thresholds = shown
                .iter()
                .filter(|r| effect_of(&r.parameter).is_none() || r.parameter == "ct_sigma")
                .map(|r| r.parameter.clone())
                .collect();
            breakdowns.push(Breakdown::tabulate(records, method, thresholds));
            rows.extend(shown);
        }
        Summary {
            cases: cases.len(),
            runs: records.len(),
            rows,
            breakdowns,
            detection: detection(records),
            reasons: reasons(records),
            timing: methods(records)
                .into_iter()
                .map(|m| timing(records, m))
                .collect(),
        }
    }

    /// The row of `parameter` of `method`, if shown.
    pub fn row(&self, method: Method, parameter: &str) -> Option<&Row> {
        self.rows
            .iter()
            .find(|r| r.method == method && r.parameter == parameter)
    }

    /// The tables as Markdown (`COVERAGE.md` without its header).
    pub fn to_markdown(&self) -> String {
        markdown::render(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coverage::record::committed;

    /// Draw 1018 of the fit on seeds 1001-1080 (2026-11-29): no hot pixels, mismatch and a
    /// 109 Hz cutoff; the fit named 2 hot pixels, fraction 4.9e-5 [6.0e-6, 1.8e-4].
    fn draw_1018() -> RunRecord {
        committed(
            "benches/coverage/fit-systematic-2026-11-29/measured-1001-1080/results.compact.jsonl",
            1018,
        )
    }

    #[test]
    fn a_false_alarm_is_a_claim_only_where_its_interval_excludes_the_absence() {
        let mut record = draw_1018();
        let hot = |records: &[RunRecord]| {
            detection(records)
                .into_iter()
                .find(|d| d.effect == "hot_pixels")
                .unwrap()
        };
        let d = hot(std::slice::from_ref(&record));
        assert_eq!((d.absent, d.false_alarms, d.false_claims), (1, 1, 1));
        // the same pixels with an interval reaching none: "perhaps none" is no claim
        record.reported.insert(
            "hot_pixel_fraction".into(),
            Reported::Interval {
                value: 4.9e-5,
                lo: Some(0.0),
                hi: Some(1.8e-4),
            },
        );
        let d = hot(std::slice::from_ref(&record));
        assert_eq!((d.absent, d.false_alarms, d.false_claims), (1, 1, 0));
        // the same run without frames counts in its own rows
        record.method = Method::FitEvents;
        let rows = detection(std::slice::from_ref(&record));
        assert!(rows.iter().all(|d| d.method == Method::FitEvents));
        let d = rows.iter().find(|d| d.effect == "hot_pixels").unwrap();
        assert_eq!((d.absent, d.false_alarms, d.false_claims), (1, 1, 0));
        // a bandwidth limit's absence is an infinite cutoff: only an open upper end covers it
        assert_eq!(
            absent_value("bandwidth"),
            Some(("cutoff_hz", f64::INFINITY))
        );
    }

    #[test]
    fn reasons_drop_the_path_and_the_numbers() {
        assert_eq!(
            headline("error: /runs/case-12: 336 events over 0.579 s are too few.\n  fix: x"),
            "N events over N s are too few."
        );
        assert_eq!(headline("timed out after 400 s"), "timed out after N s");
    }
}
