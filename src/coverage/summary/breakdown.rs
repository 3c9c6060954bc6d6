//! Coverage broken down by what a case was (scene family, generator, each effect present,
//! brightness, speed, threshold size, frame count), so that a miss can be traced to what
//! causes it.

use super::score::{Score, score};
use crate::coverage::method::Method;
use crate::coverage::record::RunRecord;
use serde::Serialize;

/// A group of cases: its label and who belongs to it.
pub struct Group {
    pub label: String,
    pub contains: Box<dyn Fn(&RunRecord) -> bool>,
}

fn group(label: impl Into<String>, contains: impl Fn(&RunRecord) -> bool + 'static) -> Group {
    Group {
        label: label.into(),
        contains: Box::new(contains),
    }
}

fn mean_dn(r: &RunRecord) -> f64 {
    r.truth.as_ref().map_or(r.case.brightness_dn, |t| t.mean_dn)
}

fn thresholds(r: &RunRecord) -> (f64, f64) {
    (r.case.params.ct_on, r.case.params.ct_off)
}

/// Every group the records have members in.
pub fn groups(records: &[RunRecord]) -> Vec<Group> {
    let mut all = Vec::new();
    for family in crate::coverage::SceneFamily::ALL {
        all.push(group(format!("family {}", family.name()), move |r| {
            r.case.family == family
        }));
    }
    for generator in crate::coverage::Generator::ALL {
        all.push(group(format!("generator {}", generator.name()), move |r| {
            r.case.generator == generator
        }));
    }
    let mut effects: Vec<String> = records
        .iter()
        .flat_map(|r| crate::coverage::truth::effects_present(&r.case.params))
        .filter(|e| e != "mismatch" && e != "display")
        .collect();
    effects.sort();
    effects.dedup();
    for effect in effects {
        all.push(group(format!("with {effect}"), move |r| {
            crate::coverage::truth::effects_present(&r.case.params).contains(&effect)
        }));
    }
    all.push(group("no effect but mismatch (and display)", |r| {
        crate::coverage::truth::effects_present(&r.case.params)
            .iter()
            .all(|e| e == "mismatch" || e == "display")
    }));
    all.push(group("dim (mean < 30 DN)", |r| mean_dn(r) < 30.0));
    all.push(group("mid (30-100 DN)", |r| {
        (30.0..=100.0).contains(&mean_dn(r))
    }));
    all.push(group("bright (> 100 DN)", |r| mean_dn(r) > 100.0));
    all.push(group("slow (< 60 px/s)", |r| r.case.speed_px_s < 60.0));
    all.push(group("medium (60-200 px/s)", |r| {
        (60.0..=200.0).contains(&r.case.speed_px_s)
    }));
    all.push(group("fast (> 200 px/s)", |r| r.case.speed_px_s > 200.0));
    all.push(group("small CT (min < 0.25)", |r| {
        let (p, n) = thresholds(r);
        p.min(n) < 0.25
    }));
    all.push(group("large CT (max > 0.6)", |r| {
        let (p, n) = thresholds(r);
        p.max(n) > 0.6
    }));
    all.push(group("asymmetric (|Cp - Cn| > 0.3)", |r| {
        let (p, n) = thresholds(r);
        (p - n).abs() > 0.3
    }));
    all.push(group("few APS frames (< 20)", |r| {
        r.truth
            .as_ref()
            .is_some_and(|t| !r.case.is_screen() && t.aps_frames < 20)
    }));
    all.retain(|g| records.iter().any(|r| (g.contains)(r)));
    all
}

/// One cell: covered of determinable, of cases.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Cell {
    pub cases: usize,
    pub determinable: usize,
    pub covered: usize,
}

/// One line of a method's breakdown.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BreakdownRow {
    pub method: Method,
    pub group: String,
    /// One cell per parameter of [`Breakdown::parameters`].
    pub cells: Vec<Cell>,
}

/// A method's breakdown over its threshold parameters.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Breakdown {
    pub method: Method,
    pub parameters: Vec<String>,
    pub rows: Vec<BreakdownRow>,
}

fn cell(records: &[&RunRecord], parameter: &str) -> Cell {
    let mut cell = Cell::default();
    for score in records.iter().filter_map(|r| score(r, parameter)) {
        cell.cases += 1;
        if let Score::Value { covered, .. } = score {
            cell.determinable += 1;
            cell.covered += covered as usize;
        }
    }
    cell
}

impl Breakdown {
    pub fn tabulate(records: &[RunRecord], method: Method, parameters: Vec<String>) -> Self {
        let runs: Vec<&RunRecord> = records.iter().filter(|r| r.method == method).collect();
        let rows = groups(records)
            .into_iter()
            .filter_map(|g| {
                let members: Vec<&RunRecord> =
                    runs.iter().copied().filter(|r| (g.contains)(r)).collect();
                (!members.is_empty()).then(|| BreakdownRow {
                    method,
                    group: g.label,
                    cells: parameters.iter().map(|p| cell(&members, p)).collect(),
                })
            })
            .collect();
        Breakdown {
            method,
            parameters,
            rows,
        }
    }
}
