//! The coverage tables as Markdown.

use super::{Breakdown, Cell, Row, Summary};
use crate::coverage::method::label;
use std::fmt::Write;

/// A number to three significant digits (scientific outside 0.001-1000).
fn sig(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let magnitude = v.abs().log10().floor();
    if !(-3.0..3.0).contains(&magnitude) {
        return format!("{v:.2e}");
    }
    let decimals = (2.0 - magnitude).max(0.0) as usize;
    format!("{v:.decimals$}")
}

fn percent(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{:.1} %", 100.0 * v))
}

fn side(v: Option<f64>) -> String {
    v.map_or("open".into(), sig)
}

fn coverage(row: &Row) -> String {
    match (row.coverage, row.coverage_ci95) {
        (Some(c), Some((lo, hi))) => {
            format!("{:.1} % [{:.1}, {:.1}]", 100.0 * c, 100.0 * lo, 100.0 * hi)
        }
        _ => "-".into(),
    }
}

fn main_table(s: &Summary, out: &mut String) {
    out.push_str("## Coverage per method and parameter\n\n");
    out.push_str("Coverage = covered / determinable (a value without an interval counts as not covered; an open side reaches infinity), with a 95 % Wilson interval. Relative error = |value - truth| / truth; relative half-width = half the interval / value.\n\n");
    out.push_str("| method | parameter | cases | failed | not reported | not determinable | determinable | open | no interval | covered | coverage [95 % CI] | median rel. error | median rel. half-width |\n");
    out.push_str("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for r in &s.rows {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.method.name(),
            label(&r.parameter),
            r.cases,
            r.failed,
            r.not_reported,
            r.not_determinable,
            r.determinable,
            r.open,
            r.no_interval,
            r.covered,
            coverage(r),
            percent(r.median_relative_error),
            percent(r.median_relative_half_width),
        );
    }
}

fn misses(s: &Summary, out: &mut String) {
    out.push_str("\n## Worst misses\n\nThe five misses farthest from their interval, in half-widths (inf: no interval).\n\n");
    out.push_str("| method | parameter | case | truth | value | interval | half-widths out |\n");
    out.push_str("|---|---|---|---|---|---|---|\n");
    for r in &s.rows {
        for m in &r.worst_misses {
            let interval = if m.lo.is_none() && m.hi.is_none() {
                "none".to_string()
            } else {
                format!("[{}, {}]", side(m.lo), side(m.hi))
            };
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} | {} | {} | {} |",
                r.method.name(),
                label(&r.parameter),
                m.case_id,
                sig(m.truth),
                sig(m.value),
                interval,
                sig(m.half_widths_out),
            );
        }
    }
}

fn cell(c: &Cell) -> String {
    if c.determinable == 0 {
        return format!("-/{}", c.cases);
    }
    format!(
        "{}/{} of {} ({:.0} %)",
        c.covered,
        c.determinable,
        c.cases,
        100.0 * c.covered as f64 / c.determinable as f64
    )
}

fn breakdown(b: &Breakdown, out: &mut String) {
    let _ = writeln!(out, "\n### {}\n", b.method.name());
    let names: Vec<&str> = b.parameters.iter().map(|p| label(p)).collect();
    let _ = writeln!(out, "| cases | {} |", names.join(" | "));
    let _ = writeln!(out, "|---|{}", "---|".repeat(names.len()));
    for row in &b.rows {
        let cells: Vec<String> = row.cells.iter().map(cell).collect();
        let _ = writeln!(out, "| {} | {} |", row.group, cells.join(" | "));
    }
}

fn detection(s: &Summary, out: &mut String) {
    if s.detection.is_empty() {
        return;
    }
    out.push_str("\n## Effect detection by the fit\n\n");
    out.push_str("| method | effect | cases with it | added | cases without it | added anyway | of those, claimed (interval excludes none) |\n");
    out.push_str("|---|---|---|---|---|---|---|\n");
    for d in &s.detection {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} | {} |",
            d.method.name(),
            d.effect,
            d.present,
            d.detected,
            d.absent,
            d.false_alarms,
            d.false_claims
        );
    }
}

fn reasons(s: &Summary, out: &mut String) {
    if s.reasons.is_empty() {
        return;
    }
    out.push_str("\n## Why runs failed or gave no value\n\n");
    out.push_str("| method | outcome | runs | reason (first line) |\n|---|---|---|---|\n");
    for r in &s.reasons {
        let reason = r.reason.replace('|', "\\|");
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} |",
            r.method.name(),
            r.kind,
            r.count,
            reason
        );
    }
}

fn timing(s: &Summary, out: &mut String) {
    out.push_str(
        "\n## Time per method\n\n| method | runs | median s | total s |\n|---|---|---|---|\n",
    );
    for t in &s.timing {
        let _ = writeln!(
            out,
            "| {} | {} | {:.1} | {:.0} |",
            t.method.name(),
            t.runs,
            t.median_seconds,
            t.total_seconds
        );
    }
}

pub(super) fn render(s: &Summary) -> String {
    let mut out = format!("{} cases, {} runs.\n\n", s.cases, s.runs);
    main_table(s, &mut out);
    misses(s, &mut out);
    out.push_str("\n## Coverage by kind of case\n\nEach cell: covered / determinable of the runs in the group (coverage %).\n");
    for b in &s.breakdowns {
        breakdown(b, &mut out);
    }
    detection(s, &mut out);
    reasons(s, &mut out);
    timing(s, &mut out);
    out
}
