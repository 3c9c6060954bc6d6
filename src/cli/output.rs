//! Output helpers: `--json PATH` (written through the output rules of
//! `ctcal::io::write::destination`) or `--json -` (stdout, and nothing else on stdout), and
//! aligned key/value tables for people. Everything on stdout goes through [`stdout`], whose
//! errors (a closed pipe: `ctcal stats ... | head`) end the command quietly.

use anyhow::Context;
use ctcal::io::write::OutputPolicy;
use serde::Serialize;
use std::io::Write;
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

/// A JSON result stamped with the version of ctcal that made it (first key), which is also
/// how ctcal recognises a JSON file it may overwrite.
#[derive(Serialize)]
struct Stamped<'a, T: Serialize> {
    ctcal_version: &'static str,
    #[serde(flatten)]
    value: &'a T,
}

/// The pretty JSON text of `value`, stamped with ctcal's version.
pub fn json_text<T: Serialize>(value: &T) -> anyhow::Result<String> {
    let mut text = serde_json::to_string_pretty(&Stamped {
        ctcal_version: env!("CARGO_PKG_VERSION"),
        value,
    })
    .context("serialising JSON")?;
    text.push('\n');
    Ok(text)
}

/// Checks, before any work, that `--json PATH` may be written (a file ctcal did not write
/// is refused now, not after minutes of fitting); `-` and no `--json` always may.
pub fn check_json(json: Option<&Path>, policy: &OutputPolicy) -> anyhow::Result<()> {
    if let Some(JsonTarget::File(path)) = json.map(JsonTarget::parse) {
        policy.check_file(&path)?;
    }
    Ok(())
}

/// Writes `value` as pretty JSON to `target`.
pub fn emit_json<T: Serialize>(
    value: &T,
    target: &JsonTarget,
    policy: &OutputPolicy,
) -> anyhow::Result<()> {
    let text = json_text(value)?;
    match target {
        JsonTarget::Stdout => stdout(&text)?,
        JsonTarget::File(path) => policy.file(path)?.write_all(text.as_bytes())?,
    }
    Ok(())
}

/// Writes `text` to stdout (the only way the binary writes there).
pub fn stdout(text: &str) -> std::io::Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
    out.flush()
}

/// Prints `rows` as an aligned two-column table to stdout.
pub fn print_table(rows: &[(String, String)]) -> std::io::Result<()> {
    let width = rows.iter().map(|(k, _)| k.len()).max().unwrap_or(0);
    let mut text = String::new();
    for (key, value) in rows {
        text.push_str(&format!("{key:<width$}  {value}\n"));
    }
    stdout(&text)
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

/// The table row of a recording's biases.
pub fn biases_row(biases: Option<&ctcal::io::Biases>) -> (String, String) {
    let text = match biases {
        Some(b) => format!(
            "{} (from {})",
            b.values
                .iter()
                .map(|(name, value)| format!("{name} {value}"))
                .collect::<Vec<_>>()
                .join(", "),
            b.source.display()
        ),
        None => "none found in or beside the recording".into(),
    };
    ("biases".into(), text)
}
