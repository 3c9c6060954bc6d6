//! Output helpers: `--json PATH` (written atomically) or `--json -` (stdout, and nothing else
//! on stdout), and aligned key/value tables for people.

use anyhow::Context;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Where `--json` goes.
#[derive(Clone, Debug)]
pub enum JsonTarget {
    Stdout,
    File(PathBuf),
}

impl JsonTarget {
    pub fn parse(path: &Path) -> Self {
        if path == Path::new("-") {
            JsonTarget::Stdout
        } else {
            JsonTarget::File(path.to_path_buf())
        }
    }
}

/// Writes `value` as pretty JSON to `target`.
pub fn emit_json<T: Serialize>(value: &T, target: &JsonTarget) -> anyhow::Result<()> {
    let mut text = serde_json::to_string_pretty(value).context("serialising JSON")?;
    text.push('\n');
    match target {
        JsonTarget::Stdout => {
            use std::io::Write;
            let mut out = std::io::stdout().lock();
            out.write_all(text.as_bytes())?;
            out.flush()?;
        }
        JsonTarget::File(path) => ctcal::io::write::write_file_atomically(path, text.as_bytes())?,
    }
    Ok(())
}

/// Prints `rows` as an aligned two-column table to stdout.
pub fn print_table(rows: &[(String, String)]) {
    let width = rows.iter().map(|(k, _)| k.len()).max().unwrap_or(0);
    for (key, value) in rows {
        println!("{key:<width$}  {value}");
    }
}

/// Formats seconds with a sensible number of digits.
pub fn seconds(s: f64) -> String {
    if s == 0.0 {
        "0 s".into()
    } else if s.abs() < 1e-3 {
        format!("{:.1} us", s * 1e6)
    } else if s.abs() < 1.0 {
        format!("{:.3} ms", s * 1e3)
    } else {
        format!("{s:.6} s")
    }
}
