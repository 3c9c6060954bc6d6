//! The sensor biases a recording carries or sits beside, as the camera software saved them
//! (values as stored, no conversion; ctcal has no model from biases to thresholds):
//!
//! - a Prophesee bias file beside the events (`NAME.bias` for `NAME.raw`/`NAME.dat`, else
//!   the folder's only `*.bias`): lines `VALUE % NAME` (Metavision's format) or
//!   `NAME VALUE`; `%` or `#` at the start of a line begins a comment;
//! - `% bias NAME VALUE` or `% bias_NAME VALUE` lines in a Prophesee RAW/DAT header;
//! - an XML configuration beside the events (`NAME.xml`): iniVation DV (`attr` elements of
//!   integer type under a node whose path holds `/bias/`, named by the path below it and
//!   the key) or jAER (`entry` elements whose key contains `bias`, integer `value`).
//!
//! The first of these that holds a bias is used.

use super::prophesee::PropheseeHeader;
pub use ctcal_core::biases::Biases;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn integer(text: &str) -> Option<i64> {
    let text = text.trim();
    match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => i64::from_str_radix(hex, 16).ok(),
        None => text.parse().ok(),
    }
}

/// The biases of a bias file's text (lines that are neither comments nor biases are
/// skipped).
pub fn parse_bias_file(text: &str) -> BTreeMap<String, i64> {
    let mut values = BTreeMap::new();
    for line in text.lines().map(str::trim) {
        if line.is_empty() || line.starts_with('%') || line.starts_with('#') {
            continue;
        }
        let pair = match line.split_once('%') {
            Some((value, name)) => name
                .split_whitespace()
                .next()
                .zip(integer(value))
                .map(|(n, v)| (n.to_string(), v)),
            None => {
                let mut parts = line.split(|c: char| c.is_whitespace() || c == '=' || c == ',');
                let name = parts.next();
                let value = parts.find(|p| !p.is_empty()).and_then(integer);
                name.zip(value).map(|(n, v)| (n.to_string(), v))
            }
        };
        if let Some((name, value)) = pair {
            values.insert(name, value);
        }
    }
    values
}

/// The biases in a Prophesee header's fields.
pub fn from_header(header: &PropheseeHeader) -> BTreeMap<String, i64> {
    let mut values = BTreeMap::new();
    for (key, value) in &header.fields {
        let key = key.to_ascii_lowercase();
        let pair = if key == "bias" {
            let mut parts = value.split_whitespace();
            parts
                .next()
                .zip(parts.next().and_then(integer))
                .map(|(n, v)| (n.to_string(), v))
        } else if key.starts_with("bias_") {
            integer(value).map(|v| (key.clone(), v))
        } else {
            None
        };
        if let Some((name, value)) = pair {
            values.insert(name, value);
        }
    }
    values
}

/// The biases of a DV or jAER XML configuration (empty when it is not XML).
pub fn parse_xml(text: &str) -> BTreeMap<String, i64> {
    let mut values = BTreeMap::new();
    let Ok(document) = roxmltree::Document::parse(text) else {
        return values;
    };
    for element in document.descendants().filter(|n| n.is_element()) {
        match element.tag_name().name() {
            "attr" => {
                let integral = matches!(
                    element.attribute("type"),
                    Some("int" | "byte" | "short" | "long")
                );
                let path = element
                    .parent()
                    .and_then(|p| p.attribute("path"))
                    .unwrap_or("");
                let lower = path.to_ascii_lowercase();
                let (Some(at), Some(key)) = (lower.find("/bias/"), element.attribute("key")) else {
                    continue;
                };
                let below = path[at + "/bias/".len()..].trim_matches('/');
                let name = if below.is_empty() {
                    key.to_string()
                } else {
                    format!("{below}.{key}")
                };
                if let Some(v) = element.text().and_then(integer).filter(|_| integral) {
                    values.insert(name, v);
                }
            }
            "entry" => {
                let (Some(key), Some(value)) =
                    (element.attribute("key"), element.attribute("value"))
                else {
                    continue;
                };
                if key.to_ascii_lowercase().contains("bias")
                    && let Some(v) = integer(value)
                {
                    values.insert(key.to_string(), v);
                }
            }
            _ => {}
        }
    }
    values
}

/// The bias file beside `event_file`: same name with `.bias`, else the folder's only one.
fn bias_file(event_file: &Path) -> Option<PathBuf> {
    let same = event_file.with_extension("bias");
    if same.is_file() {
        return Some(same);
    }
    let folder = event_file.parent()?;
    let mut found = std::fs::read_dir(if folder.as_os_str().is_empty() {
        Path::new(".")
    } else {
        folder
    })
    .ok()?
    .flatten()
    .map(|e| e.path())
    .filter(|p| {
        p.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("bias"))
            && p.is_file()
    });
    let first = found.next()?;
    found.next().is_none().then_some(first)
}

/// The biases of the recording whose events are in `event_file` (`prophesee`: whether it
/// is a Prophesee RAW or DAT, whose header is read); `None` when none are found.
pub fn find(event_file: &Path, prophesee: bool) -> Option<Biases> {
    let read = |path: &Path| crate::files::read_small_text(path, 1 << 20).ok();
    let candidates: [Option<(PathBuf, BTreeMap<String, i64>)>; 3] = [
        bias_file(event_file).and_then(|p| Some((p.clone(), parse_bias_file(&read(&p)?)))),
        prophesee
            .then(|| PropheseeHeader::read(event_file).ok())
            .flatten()
            .map(|h| (event_file.to_path_buf(), from_header(&h))),
        Some(event_file.with_extension("xml"))
            .filter(|p| p.is_file())
            .and_then(|p| Some((p.clone(), parse_xml(&read(&p)?)))),
    ];
    candidates
        .into_iter()
        .flatten()
        .find(|(_, values)| !values.is_empty())
        .map(|(source, values)| Biases { source, values })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metavision_bias_files_and_name_value_lines_are_read() {
        let text = "% gen4.1 biases\n299   % bias_diff\n 228 % bias_diff_off\n370 % bias_diff_on\n\nbias_fo 0x4D\nbias_hpf=0\nnot a bias\n";
        let v = parse_bias_file(text);
        assert_eq!(v.len(), 5, "{v:?}");
        assert_eq!(v["bias_diff"], 299);
        assert_eq!(v["bias_diff_off"], 228);
        assert_eq!(v["bias_diff_on"], 370);
        assert_eq!(v["bias_fo"], 77);
        assert_eq!(v["bias_hpf"], 0);
    }

    #[test]
    fn header_bias_lines_are_read() {
        let header = PropheseeHeader::parse(
            b"% evt 3.0\n% bias bias_diff_on 102\n% bias_refr 20\n% geometry 1280x720\n% end\n",
        );
        let v = from_header(&header);
        assert_eq!(v.len(), 2);
        assert_eq!(v["bias_diff_on"], 102);
        assert_eq!(v["bias_refr"], 20);
    }

    #[test]
    fn dv_and_jaer_xml_biases_are_read() {
        let dv = r#"<dv version="2.0"><node name="bias" path="/mainloop/capture/bias/">
            <node name="DiffBn" path="/mainloop/capture/bias/DiffBn/">
              <attr key="coarseValue" type="byte">4</attr>
              <attr key="fineValue" type="short">39</attr>
              <attr key="currentType" type="string">Normal</attr>
            </node>
            <attr key="refractoryBias" type="int">12</attr></node>
            <node name="other" path="/mainloop/capture/"><attr key="fps" type="int">30</attr></node></dv>"#;
        let v = parse_xml(dv);
        assert_eq!(v.len(), 3, "{v:?}");
        assert_eq!(v["DiffBn.coarseValue"], 4);
        assert_eq!(v["DiffBn.fineValue"], 39);
        assert_eq!(v["refractoryBias"], 12);
        let jaer = r#"<map><entry key="DVS128.ipot.DiffBias" value="30153"/><entry key="frameRate" value="30"/></map>"#;
        let v = parse_xml(jaer);
        assert_eq!(v.len(), 1);
        assert_eq!(v["DVS128.ipot.DiffBias"], 30153);
        assert!(parse_xml("299 % bias_diff").is_empty());
    }
}
