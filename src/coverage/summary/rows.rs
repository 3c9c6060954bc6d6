//! One row of the coverage table: a (method, parameter) over every run in its population —
//! counts by outcome, coverage with its binomial interval, median errors and the worst
//! misses.

use super::binomial::{median, wilson95};
use super::score::{Score, score};
use crate::coverage::method::Method;
use crate::coverage::record::RunRecord;
use crate::coverage::reported::Reported;
use serde::Serialize;

/// How many misses a row lists.
pub const WORST_MISSES: usize = 5;

/// A case whose interval missed the truth.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Miss {
    pub case_id: String,
    pub truth: f64,
    pub value: f64,
    pub lo: Option<f64>,
    pub hi: Option<f64>,
    /// Distance from the interval to the truth in half-widths (infinite without one).
    pub half_widths_out: f64,
}

/// Coverage of one parameter of one method.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Row {
    pub method: Method,
    pub parameter: String,
    /// Runs in the population (for a fitted effect parameter: cases with the effect).
    pub cases: usize,
    pub failed: usize,
    pub not_reported: usize,
    pub not_determinable: usize,
    /// Runs that reported a value (with or without an interval).
    pub determinable: usize,
    /// Values with an open interval side.
    pub open: usize,
    /// Values with no interval (never covered).
    pub no_interval: usize,
    pub covered: usize,
    /// covered / determinable.
    pub coverage: Option<f64>,
    pub coverage_ci95: Option<(f64, f64)>,
    /// Median of |value - truth| / |truth| (truth != 0).
    pub median_relative_error: Option<f64>,
    /// Median of half-width / |value| over closed intervals.
    pub median_relative_half_width: Option<f64>,
    pub worst_misses: Vec<Miss>,
}

fn miss(case_id: &str, value: f64, truth: f64, reported: &Reported) -> Miss {
    let (lo, hi) = match *reported {
        Reported::Interval { lo, hi, .. } => (lo, hi),
        _ => (None, None),
    };
    let outside = match (lo, hi) {
        (Some(lo), _) if truth < lo => lo - truth,
        (_, Some(hi)) if truth > hi => truth - hi,
        _ => (value - truth).abs(),
    };
    let half = reported
        .half_width()
        .or_else(|| lo.or(hi).map(|side| (value - side).abs()))
        .filter(|&h| h > 0.0);
    Miss {
        case_id: case_id.to_string(),
        truth,
        value,
        lo,
        hi,
        half_widths_out: half.map_or(f64::INFINITY, |h| outside / h),
    }
}

impl Row {
    fn empty(method: Method, parameter: &str) -> Self {
        Row {
            method,
            parameter: parameter.to_string(),
            cases: 0,
            failed: 0,
            not_reported: 0,
            not_determinable: 0,
            determinable: 0,
            open: 0,
            no_interval: 0,
            covered: 0,
            coverage: None,
            coverage_ci95: None,
            median_relative_error: None,
            median_relative_half_width: None,
            worst_misses: Vec::new(),
        }
    }

    /// The row of `parameter` over the runs of `method` in `records`.
    pub fn tabulate(records: &[RunRecord], method: Method, parameter: &str) -> Self {
        let mut row = Row::empty(method, parameter);
        let (mut errors, mut widths, mut misses) = (Vec::new(), Vec::new(), Vec::new());
        for record in records.iter().filter(|r| r.method == method) {
            let Some(score) = score(record, parameter) else {
                continue;
            };
            row.cases += 1;
            let Score::Value {
                value,
                truth,
                reported,
                covered,
            } = score
            else {
                match score {
                    Score::Failed => row.failed += 1,
                    Score::NotReported => row.not_reported += 1,
                    _ => row.not_determinable += 1,
                }
                continue;
            };
            row.determinable += 1;
            row.open += reported.is_open() as usize;
            row.no_interval += matches!(reported, Reported::NoInterval { .. }) as usize;
            if truth != 0.0 {
                errors.push((value - truth).abs() / truth.abs());
            }
            if let Some(half) = reported.half_width().filter(|_| value != 0.0) {
                widths.push(half / value.abs());
            }
            if covered {
                row.covered += 1;
            } else {
                misses.push(miss(&record.case.id, value, truth, reported));
            }
        }
        misses.sort_by(|a, b| b.half_widths_out.total_cmp(&a.half_widths_out));
        misses.truncate(WORST_MISSES);
        row.worst_misses = misses;
        row.coverage = (row.determinable > 0).then(|| row.covered as f64 / row.determinable as f64);
        row.coverage_ci95 = wilson95(row.covered, row.determinable);
        row.median_relative_error = median(errors);
        row.median_relative_half_width = median(widths);
        row
    }

    /// A row worth showing: thresholds always, other parameters once anything reported them.
    pub fn is_shown(&self) -> bool {
        self.cases > 0
            && (matches!(self.parameter.as_str(), "ct_on" | "ct_off")
                || self.not_reported + self.failed < self.cases)
    }
}
