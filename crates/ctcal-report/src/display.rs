//! Tables as a reader sees them on the page and in `report.md`: column headers in words
//! with their units, and the columns that are empty in every row left out (the exported
//! CSV, Parquet and LaTeX keep every column and its machine name).

use super::tables::{Table, rows};

/// A table ready to show.
pub struct Shown {
    pub headers: Vec<String>,
    /// Whether each column holds numbers (right-aligned).
    pub numeric: Vec<bool>,
    pub rows: Vec<Vec<Option<String>>>,
}

/// The header of a column: its name in words, with the unit.
pub fn header(name: &str) -> String {
    const UNITS: [(&str, &str); 6] = [
        ("_per_pixel_per_second_sd", " sd (events/px/s)"),
        ("_per_pixel_per_second", " (events/px/s)"),
        ("_hz", " (Hz)"),
        ("_s", " (s)"),
        ("_fraction", " (fraction)"),
        ("_sd", " sd (ln)"),
    ];
    let threshold = name.starts_with("ct_") || name.starts_with("true_ct");
    let (stem, unit) = UNITS
        .iter()
        .find(|(suffix, _)| name.ends_with(suffix))
        .map_or((name, ""), |(suffix, unit)| {
            (&name[..name.len() - suffix.len()], *unit)
        });
    let unit = if unit.is_empty() && threshold {
        " (ln)"
    } else {
        unit
    };
    let stem = match (stem, unit.contains("events/px/s")) {
        ("events", true) => "event rate",
        ("on", true) => "ON rate",
        ("off", true) => "OFF rate",
        ("on", false) => "ON",
        ("ci95_lo", _) => "95 % low",
        ("ci95_hi", _) => "95 % high",
        (other, _) => other,
    };
    format!("{}{unit}", stem.replace('_', " "))
}

/// `t` without its empty columns (but an interval's end beside its value), headers in
/// words.
pub fn shown(t: &Table) -> Shown {
    let (names, cells) = rows(t);
    let numeric: Vec<bool> = t
        .frame
        .columns()
        .iter()
        .map(|c| c.dtype().is_primitive_numeric())
        .collect();
    let filled: Vec<bool> = (0..names.len())
        .map(|i| cells.iter().any(|row| row[i].is_some()))
        .collect();
    let has = |name: &str| {
        names
            .iter()
            .position(|n| n == name)
            .is_some_and(|i| filled[i])
    };
    // an interval's end stays beside its value or its other end, empty or not: a column of
    // dashes says the interval is open there (left out, an open side looked like none)
    let interval_end = |name: &str| {
        [("_lo", "_hi"), ("_hi", "_lo")].iter().any(|(end, other)| {
            name.strip_suffix(end)
                .is_some_and(|stem| has(stem) || has(&format!("{stem}{other}")))
        })
    };
    let keep: Vec<usize> = (0..names.len())
        .filter(|&i| filled[i] || interval_end(&names[i]))
        .collect();
    Shown {
        headers: keep.iter().map(|&i| header(&names[i])).collect(),
        numeric: keep.iter().map(|&i| numeric[i]).collect(),
        rows: cells
            .into_iter()
            .map(|row| keep.iter().map(|&i| row[i].clone()).collect())
            .collect(),
    }
}

/// Escapes text for HTML (`&`, `<`, `>`, `"`).
pub fn escape_html(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// An HTML table (numbers right-aligned, nulls as an en dash), scrolling sideways in a
/// narrow window.
pub fn html(t: &Table) -> String {
    let s = shown(t);
    let mut out = String::from("<div class=\"wide\"><table>\n<tr>");
    for h in &s.headers {
        out.push_str(&format!("<th>{}</th>", escape_html(h)));
    }
    out.push_str("</tr>\n");
    for row in &s.rows {
        out.push_str("<tr>");
        for (cell, &numeric) in row.iter().zip(&s.numeric) {
            let text = cell.as_deref().map_or("–".to_string(), escape_html);
            let class = if numeric { " class=\"num\"" } else { "" };
            out.push_str(&format!("<td{class}>{text}</td>"));
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</table></div>\n");
    out
}

/// A Markdown (GitHub) table.
pub fn markdown(t: &Table) -> String {
    let s = shown(t);
    let escape = |s: &str| s.replace('|', "\\|").replace('\n', " ");
    let mut out = format!("| {} |\n|", s.headers.join(" | "));
    for &numeric in &s.numeric {
        out.push_str(if numeric { "---:|" } else { "---|" });
    }
    out.push('\n');
    for row in &s.rows {
        let cells: Vec<String> = row
            .iter()
            .map(|c| c.as_deref().map_or("–".to_string(), escape))
            .collect();
        out.push_str(&format!("| {} |\n", cells.join(" | ")));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headers_carry_their_units() {
        assert_eq!(header("duration_s"), "duration (s)");
        assert_eq!(
            header("events_per_pixel_per_second"),
            "event rate (events/px/s)"
        );
        assert_eq!(header("background_rate_hz"), "background rate (Hz)");
        assert_eq!(header("ct_on"), "ct on (ln)");
        assert_eq!(header("ct_aps_sd"), "ct aps sd (ln)");
        assert_eq!(header("sequence"), "sequence");
        assert_eq!(header("events"), "events");
        assert_eq!(header("on_fraction"), "ON (fraction)");
        assert_eq!(header("ci95_lo"), "95 % low");
    }

    #[test]
    fn empty_columns_are_hidden() {
        let frame = polars::prelude::DataFrame::new_infer_height(vec![
            polars::prelude::Column::new("a".into(), vec![Some(1.5), None]),
            polars::prelude::Column::new("b".into(), vec![None::<f64>, None]),
        ])
        .unwrap();
        let t = Table {
            name: "t",
            caption: "c",
            frame,
        };
        let s = shown(&t);
        assert_eq!(s.headers, ["a"]);
        assert_eq!(s.rows, [[Some("1.500".to_string())], [None]]);
        assert_eq!(markdown(&t), "| a |\n|---:|\n| 1.500 |\n| – |\n");
    }

    /// An interval open below in every row (the Gen3 recording of expelliarmus: eppps read
    /// ON 0.122 [open, 1.55]): its empty `_lo` column stays beside the value, so the page
    /// shows the open side as a dash instead of no lower end at all.
    #[test]
    fn an_interval_end_stays_beside_its_value_when_it_is_open() {
        let column = |name: &str, values: Vec<Option<f64>>| {
            polars::prelude::Column::new(name.into(), values)
        };
        let frame = polars::prelude::DataFrame::new_infer_height(vec![
            column("ct_on", vec![Some(0.122)]),
            column("ct_on_lo", vec![None]),
            column("ct_on_hi", vec![Some(1.553)]),
            column("ci95_lo", vec![None]),
            column("ci95_hi", vec![Some(1.0)]),
            column("other_lo", vec![None]),
        ])
        .unwrap();
        let t = Table {
            name: "t",
            caption: "c",
            frame,
        };
        assert_eq!(
            shown(&t).headers,
            [
                "ct on (ln)",
                "ct on lo (ln)",
                "ct on hi (ln)",
                "95 % low",
                "95 % high"
            ]
        );
    }
}
