//! The report's tables, built as polars DataFrames and exported four ways: CSV and Parquet
//! (polars' writers; Parquet also per sequence, so that DuckDB or Spark can aggregate
//! datasets that outgrow one machine), LaTeX (booktabs, ready for a paper) and Markdown.
//!
//! - `statistics`: one row per sequence;
//! - `thresholds`: one row per sequence and method, with intervals and the truth where the
//!   recording carries it;
//! - `fitted_parameters`: one row per sequence and fitted parameter;
//! - `fit_steps`: one row per step of each fit's loop;
//! - `datasets`: one row per dataset.

use super::model::{Report, SequenceReport};
use polars::prelude::*;

/// A named table.
pub struct Table {
    pub name: &'static str,
    pub caption: &'static str,
    pub frame: DataFrame,
}

/// A column of optional floats.
pub(crate) fn floats(name: &str, values: Vec<Option<f64>>) -> Column {
    Column::new(name.into(), values)
}

/// A column of optional counts.
fn counts(name: &str, values: Vec<Option<u64>>) -> Column {
    Column::new(name.into(), values)
}

pub(crate) fn strings(name: &str, values: Vec<String>) -> Column {
    Column::new(name.into(), values)
}

pub(crate) fn table(name: &'static str, caption: &'static str, columns: Vec<Column>) -> Table {
    let frame = DataFrame::new_infer_height(columns).expect("columns of one length");
    Table {
        name,
        caption,
        frame,
    }
}

/// One row per sequence: its statistics.
pub fn statistics(sequences: &[&SequenceReport]) -> Table {
    let mut columns = naming_columns(sequences);
    columns.extend(rate_columns(sequences));
    columns.extend(pixel_interval_frame_columns(sequences));
    table("statistics", "Event statistics of each sequence", columns)
}

/// A float of each sequence.
fn per_sequence(
    sequences: &[&SequenceReport],
    f: &dyn Fn(&SequenceReport) -> Option<f64>,
) -> Vec<Option<f64>> {
    sequences.iter().map(|q| f(q)).collect()
}

/// The statistics' columns that name each sequence: its name, dataset and sensor.
fn naming_columns(sequences: &[&SequenceReport]) -> Vec<Column> {
    vec![
        strings(
            "sequence",
            sequences.iter().map(|q| q.name.clone()).collect(),
        ),
        strings(
            "dataset",
            sequences.iter().map(|q| q.dataset.clone()).collect(),
        ),
        strings(
            "sensor",
            sequences
                .iter()
                .map(|q| format!("{}x{}", q.stats.width, q.stats.height))
                .collect(),
        ),
    ]
}

/// The statistics' columns of events and their rates: count, duration, rates per pixel
/// (both polarities, ON, OFF), ON fraction, active pixels, background rate.
fn rate_columns(sequences: &[&SequenceReport]) -> Vec<Column> {
    let s = |f: &dyn Fn(&SequenceReport) -> Option<f64>| per_sequence(sequences, f);
    vec![
        counts(
            "events",
            sequences.iter().map(|q| Some(q.stats.events)).collect(),
        ),
        floats("duration_s", s(&|q| Some(q.stats.duration_s))),
        floats(
            "events_per_pixel_per_second",
            s(&|q| q.stats.events_per_pixel_per_second),
        ),
        floats(
            "on_per_pixel_per_second",
            s(&|q| q.stats.on_per_pixel_per_second),
        ),
        floats(
            "off_per_pixel_per_second",
            s(&|q| q.stats.off_per_pixel_per_second),
        ),
        floats("on_fraction", s(&|q| Some(q.stats.on_fraction))),
        floats(
            "active_pixel_fraction",
            s(&|q| Some(q.stats.active_pixel_fraction)),
        ),
        floats("background_rate_hz", s(&|q| q.stats.background_rate_hz)),
    ]
}

/// The statistics' last columns: hot pixels, the same-pixel intervals' 5th percentile and
/// median, frames.
fn pixel_interval_frame_columns(sequences: &[&SequenceReport]) -> Vec<Column> {
    let s = |f: &dyn Fn(&SequenceReport) -> Option<f64>| per_sequence(sequences, f);
    vec![
        counts(
            "hot_pixels",
            sequences
                .iter()
                .map(|q| Some(q.stats.hot_pixels.len() as u64))
                .collect(),
        ),
        floats("interval_p5_s", s(&|q| q.stats.inter_event_interval_s.p5)),
        floats(
            "interval_median_s",
            s(&|q| q.stats.inter_event_interval_s.median),
        ),
        counts(
            "frames",
            sequences
                .iter()
                .map(|q| q.stats.frames.as_ref().map(|f| f.count as u64))
                .collect(),
        ),
    ]
}

/// A row of `thresholds`: sequence, method and [ct_on, its interval's ends, ct_off, its
/// interval's ends, ct_sigma, the true ct_on, the true ct_off].
type ThresholdRow = (String, String, [Option<f64>; 9]);

/// One row per sequence and method: thresholds with their 95 % intervals, and the truth.
pub fn thresholds(sequences: &[&SequenceReport]) -> Table {
    let rows: Vec<ThresholdRow> = sequences.iter().flat_map(|q| threshold_rows(q)).collect();
    let column = |k: usize| -> Vec<Option<f64>> { rows.iter().map(|r| r.2[k]).collect() };
    table(
        "thresholds",
        "Contrast thresholds by method (95 % intervals include each method's systematic error)",
        vec![
            strings("sequence", rows.iter().map(|r| r.0.clone()).collect()),
            strings("method", rows.iter().map(|r| r.1.clone()).collect()),
            floats("ct_on", column(0)),
            floats("ct_on_lo", column(1)),
            floats("ct_on_hi", column(2)),
            floats("ct_off", column(3)),
            floats("ct_off_lo", column(4)),
            floats("ct_off_hi", column(5)),
            floats("ct_sigma", column(6)),
            floats("true_ct_on", column(7)),
            floats("true_ct_off", column(8)),
        ],
    )
}

/// The true value of parameter `key`, where the recording carries its truth.
fn true_param(q: &SequenceReport, key: &str) -> Option<f64> {
    q.truth.as_ref().and_then(|t| t.params.get(key).copied())
}

/// A sequence's rows of `thresholds`: each method's estimate, then the fit's.
fn threshold_rows(q: &SequenceReport) -> Vec<ThresholdRow> {
    let mut rows: Vec<ThresholdRow> = q
        .methods
        .iter()
        .filter_map(|m| {
            let e = m.estimate.as_ref()?;
            Some((
                q.name.clone(),
                m.method.to_string(),
                [
                    e.ct_on,
                    e.ct_on_ci95.and_then(|c| c[0]),
                    e.ct_on_ci95.and_then(|c| c[1]),
                    e.ct_off,
                    e.ct_off_ci95.and_then(|c| c[0]),
                    e.ct_off_ci95.and_then(|c| c[1]),
                    e.ct_sigma,
                    true_param(q, "ct_on"),
                    true_param(q, "ct_off"),
                ],
            ))
        })
        .collect();
    rows.extend(fit_threshold_row(q));
    rows
}

/// The fit's row of `thresholds`, where the sequence has a fit: thresholds the recording
/// does not identify are empty, not start values.
fn fit_threshold_row(q: &SequenceReport) -> Option<ThresholdRow> {
    let f = q.fit.as_ref()?;
    let fitted = q.fitted_thresholds();
    let (on, off) = (fitted.map(|t| t.0), fitted.map(|t| t.1));
    let side = |key: &str, v: Option<f64>, upper: bool| {
        v.and(f.uncertainties.get(key))
            .and_then(|u| u.interval())
            .and_then(|c| c[usize::from(upper)])
    };
    Some((
        q.name.clone(),
        "fit".into(),
        [
            on,
            side("ct_on", on, false),
            side("ct_on", on, true),
            off,
            side("ct_off", off, false),
            side("ct_off", off, true),
            f.params.ct_sigma,
            true_param(q, "ct_on"),
            true_param(q, "ct_off"),
        ],
    ))
}

/// One row per sequence and fitted parameter.
pub fn fitted_parameters(sequences: &[&SequenceReport]) -> Table {
    // (sequence, parameter, [value, standard error, ci95 lo, ci95 hi, truth])
    type Row = (String, String, [Option<f64>; 5]);
    let mut rows: Vec<Row> = Vec::new();
    for q in sequences {
        let Some(f) = &q.fit else { continue };
        for (key, value) in super::configs::numeric_params(&f.params) {
            let uncertain = f.uncertainties.get(&key);
            let se = uncertain.and_then(|u| u.standard_error);
            let ci = uncertain.and_then(|u| u.interval()).unwrap_or([None, None]);
            let truth = q.truth.as_ref().and_then(|t| t.params.get(&key).copied());
            // not identified: no value (the reason is beside the table)
            let value = (!f.params.not_identified.contains_key(&key)).then_some(value);
            let ci = if value.is_some() { ci } else { [None, None] };
            rows.push((q.name.clone(), key, [value, se, ci[0], ci[1], truth]));
        }
    }
    let column = |k: usize| -> Vec<Option<f64>> { rows.iter().map(|r| r.2[k]).collect() };
    table(
        "fitted_parameters",
        "Fitted simulator parameters (PARAMS.toml keys) with standard errors, 95 % intervals (empty side: not bounded by the data) and the truth",
        vec![
            strings("sequence", rows.iter().map(|r| r.0.clone()).collect()),
            strings("parameter", rows.iter().map(|r| r.1.clone()).collect()),
            floats("value", column(0)),
            floats("standard_error", column(1)),
            floats("ci95_lo", column(2)),
            floats("ci95_hi", column(3)),
            floats("truth", column(4)),
        ],
    )
}

/// One row per step of each fit.
pub fn fit_steps(sequences: &[&SequenceReport]) -> Table {
    let mut name = Vec::new();
    let mut effect = Vec::new();
    let mut score = Vec::new();
    let mut before = Vec::new();
    let mut after = Vec::new();
    let mut kept = Vec::new();
    let mut reason = Vec::new();
    for q in sequences {
        let Some(f) = &q.fit else { continue };
        for step in &f.steps {
            name.push(q.name.clone());
            effect.push(step.effect.clone());
            // the starting point and the refits test no effect: no evidence to show
            let tests_an_effect = step.effect != "thresholds" && !step.effect.ends_with("(refit)");
            score.push(tests_an_effect.then_some(step.score));
            before.push(step.error_before);
            after.push(step.error_after);
            kept.push(if step.kept { "yes" } else { "no" }.to_string());
            reason.push(step.reason.clone());
        }
    }
    table(
        "fit_steps",
        "The fit's loop: each effect tried, its evidence (standard errors) and the held-out error before and after",
        vec![
            strings("sequence", name),
            strings("effect", effect),
            floats("evidence", score),
            floats("error_before", before),
            floats("error_after", after),
            strings("kept", kept),
            strings("reason", reason),
        ],
    )
}

/// One row per dataset.
pub fn datasets(report: &Report) -> Table {
    let d = &report.datasets;
    let ct = |method: &str| -> (Vec<Option<f64>>, Vec<Option<f64>>) {
        (
            d.iter().map(|x| x.ct.get(method).map(|s| s.mean)).collect(),
            d.iter()
                .map(|x| x.ct.get(method).and_then(|s| s.sd))
                .collect(),
        )
    };
    let mut columns = vec![
        strings("dataset", d.iter().map(|x| x.name.clone()).collect()),
        counts(
            "sequences",
            d.iter().map(|x| Some(x.sequences.len() as u64)).collect(),
        ),
        floats(
            "events_per_pixel_per_second",
            d.iter()
                .map(|x| Some(x.events_per_pixel_per_second.mean))
                .collect(),
        ),
        floats(
            "events_per_pixel_per_second_sd",
            d.iter().map(|x| x.events_per_pixel_per_second.sd).collect(),
        ),
    ];
    for method in ["aps", "eppps", "screen", "fit"] {
        let (mean, sd) = ct(method);
        columns.push(floats(&format!("ct_{method}"), mean));
        columns.push(floats(&format!("ct_{method}_sd"), sd));
    }
    table(
        "datasets",
        "Datasets: events per pixel per second and thresholds by method (mean and standard deviation over sequences)",
        columns,
    )
}

/// CSV text of a table.
pub fn csv(t: &Table) -> Vec<u8> {
    let mut out = Vec::new();
    let mut frame = t.frame.clone();
    CsvWriter::new(&mut out)
        .finish(&mut frame)
        .expect("writing CSV to memory");
    out
}

/// Parquet bytes of a table.
pub fn parquet(t: &Table) -> Vec<u8> {
    let mut out = Vec::new();
    let mut frame = t.frame.clone();
    ParquetWriter::new(&mut out)
        .finish(&mut frame)
        .expect("writing Parquet to memory");
    out
}

/// A cell as text: numbers to four significant digits, nulls as an en dash.
fn cell(value: &AnyValue) -> Option<String> {
    match value {
        AnyValue::Null => None,
        AnyValue::Float64(v) => Some(number(*v)),
        AnyValue::String(s) => Some(s.to_string()),
        AnyValue::StringOwned(s) => Some(s.to_string()),
        other => Some(other.to_string()),
    }
}

/// A number to four significant digits (integers as they are).
pub fn number(v: f64) -> String {
    if !v.is_finite() {
        return "-".into();
    }
    if v == v.trunc() && v.abs() < 1e9 {
        return format!("{v:.0}");
    }
    let magnitude = v.abs().log10().floor() as i32;
    if !(-3..6).contains(&magnitude) {
        format!("{v:.3e}")
    } else {
        let decimals = (3 - magnitude).max(0) as usize;
        format!("{v:.decimals$}")
    }
}

/// A table's column names and its cells as text (`None` for null).
pub(super) fn rows(t: &Table) -> (Vec<String>, Vec<Vec<Option<String>>>) {
    let columns = t.frame.columns();
    let names = columns.iter().map(|c| c.name().to_string()).collect();
    let rows = (0..t.frame.height())
        .map(|i| {
            columns
                .iter()
                .map(|c| c.get(i).ok().and_then(|v| cell(&v)))
                .collect()
        })
        .collect();
    (names, rows)
}

/// Escapes LaTeX's special characters.
fn latex_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '\\' => out.push_str("\\textbackslash{}"),
            '&' | '%' | '$' | '#' | '_' | '{' | '}' => {
                out.push('\\');
                out.push(c);
            }
            '~' => out.push_str("\\textasciitilde{}"),
            '^' => out.push_str("\\textasciicircum{}"),
            _ => out.push(c),
        }
    }
    out
}

/// Tables wider than this many columns are scaled to the text width.
const LATEX_MAX_UNSCALED_COLUMNS: usize = 7;

/// A booktabs table (needs `\usepackage{booktabs}`; wide ones also `\usepackage{graphicx}`
/// for `\resizebox`).
pub fn latex(t: &Table) -> String {
    let (names, rows) = rows(t);
    let align: String = t
        .frame
        .columns()
        .iter()
        .map(|c| {
            if c.dtype().is_primitive_numeric() {
                'r'
            } else {
                'l'
            }
        })
        .collect();
    let wide = names.len() > LATEX_MAX_UNSCALED_COLUMNS;
    let (packages, open, close) = if wide {
        (
            "\\usepackage{booktabs,graphicx}",
            "\\resizebox{\\linewidth}{!}{%\n",
            "}\n",
        )
    } else {
        ("\\usepackage{booktabs}", "", "")
    };
    let mut out = format!(
        "% ctcal table `{}` (requires {packages})\n\\begin{{table}}[t]\n\\centering\n\\caption{{{}}}\n\\label{{tab:ctcal-{}}}\n{open}\\begin{{tabular}}{{{align}}}\n\\toprule\n",
        t.name,
        latex_escape(t.caption),
        t.name.replace('_', "-")
    );
    out.push_str(
        &names
            .iter()
            .map(|n| latex_escape(n))
            .collect::<Vec<_>>()
            .join(" & "),
    );
    out.push_str(" \\\\\n\\midrule\n");
    for row in rows {
        out.push_str(
            &row.iter()
                .map(|c| c.as_deref().map_or("--".to_string(), latex_escape))
                .collect::<Vec<_>>()
                .join(" & "),
        );
        out.push_str(" \\\\\n");
    }
    out.push_str("\\bottomrule\n\\end{tabular}\n");
    out.push_str(close);
    out.push_str("\\end{table}\n");
    out
}

/// A Markdown (GitHub) table.
pub fn markdown(t: &Table) -> String {
    let (names, rows) = rows(t);
    let escape = |s: &str| s.replace('|', "\\|").replace('\n', " ");
    let mut out = format!("| {} |\n", names.join(" | "));
    out.push_str(&format!(
        "|{}\n",
        t.frame
            .columns()
            .iter()
            .map(|c| if c.dtype().is_primitive_numeric() {
                "---:|"
            } else {
                "---|"
            })
            .collect::<String>()
    ));
    for row in rows {
        out.push_str(&format!(
            "| {} |\n",
            row.iter()
                .map(|c| c.as_deref().map_or("–".to_string(), escape))
                .collect::<Vec<_>>()
                .join(" | ")
        ));
    }
    out
}

/// Every table of a report.
pub fn all(report: &Report) -> Vec<Table> {
    let sequences: Vec<&SequenceReport> = report.sequences.iter().collect();
    let mut out = vec![
        statistics(&sequences),
        thresholds(&sequences),
        fitted_parameters(&sequences),
        fit_steps(&sequences),
        datasets(report),
    ];
    out.extend(super::bias_sweep::bias_sweep(&sequences));
    out
}

/// The per-sequence tables of one sequence (for its Parquet files).
pub fn of_sequence(sequence: &SequenceReport) -> Vec<Table> {
    let one = [sequence];
    vec![
        statistics(&one),
        thresholds(&one),
        fitted_parameters(&one),
        fit_steps(&one),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_keep_four_significant_digits() {
        assert_eq!(number(0.349172), "0.3492");
        assert_eq!(number(12.3456), "12.35");
        assert_eq!(number(42.0), "42");
        assert_eq!(number(1234.56), "1235");
        assert_eq!(number(0.000012346), "1.235e-5");
        assert_eq!(number(f64::NAN), "-");
    }

    #[test]
    fn latex_and_markdown_escape_and_align() {
        let t = table(
            "x",
            "50 % of a_b",
            vec![
                strings("name_of", vec!["a|b".into(), "c&d".into()]),
                floats("value", vec![Some(0.5), None]),
            ],
        );
        let tex = latex(&t);
        assert!(tex.contains("\\caption{50 \\% of a\\_b}"));
        assert!(
            tex.contains("\\begin{tabular}{lr}\n\\toprule\nname\\_of & value \\\\\n\\midrule\n")
        );
        assert!(tex.contains("c\\&d & -- \\\\"));
        let md = markdown(&t);
        assert_eq!(
            md,
            "| name_of | value |\n|---|---:|\n| a\\|b | 0.5000 |\n| c&d | – |\n"
        );
        let csv = String::from_utf8(csv(&t)).unwrap();
        assert_eq!(csv, "name_of,value\na|b,0.5\nc&d,\n");
        assert_eq!(&parquet(&t)[..4], b"PAR1");
    }

    #[test]
    fn wide_tables_are_scaled_to_the_text_width() {
        let columns = (0..9)
            .map(|i| floats(&format!("c{i}"), vec![Some(i as f64 + 0.25)]))
            .collect();
        let t = table("wide_one", "nine columns", columns);
        insta::assert_snapshot!(latex(&t));
        insta::assert_snapshot!(markdown(&t));
    }
}
