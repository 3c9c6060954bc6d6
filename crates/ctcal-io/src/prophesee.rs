//! The text header shared by Prophesee RAW (EVT2, EVT3) and DAT files: lines starting with
//! `%` (`% key value`), ended by `% end` or by the first line that does not start with `%`.
//! The sensor comes from `% geometry WxH`, `% Width`/`% Height`, or the camera plugin name.

use super::error::InputError;
use crate::events::{MAX_SENSOR_SIDE, Sensor};
use crate::hint::{Hint, Text};
use crate::sensors;
use std::io::Read;
use std::path::Path;

/// A parsed Prophesee header.
#[derive(Clone, Debug, Default)]
pub struct PropheseeHeader {
    /// Header length in bytes: the binary data start here.
    pub length: u64,
    /// `(key, value)` pairs in file order.
    pub fields: Vec<(String, String)>,
}

impl PropheseeHeader {
    /// Reads the header of `path`.
    pub fn read(path: &Path) -> Result<Self, InputError> {
        let mut file = std::fs::File::open(path).map_err(|e| InputError::io(path, e))?;
        let mut head = Vec::new();
        (&mut file)
            .take(1 << 16)
            .read_to_end(&mut head)
            .map_err(|e| InputError::io(path, e))?;
        Ok(Self::parse(&head))
    }

    /// Parses a header from the first bytes of a file.
    pub fn parse(head: &[u8]) -> Self {
        let mut position = 0usize;
        let mut fields = Vec::new();
        while position < head.len() && head[position] == b'%' {
            let Some(end) = memchr::memchr(b'\n', &head[position..]) else {
                break;
            };
            let line = String::from_utf8_lossy(&head[position + 1..position + end]);
            position += end + 1;
            let line = line.trim();
            if line == "end" {
                break;
            }
            let (key, value) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
            fields.push((key.to_string(), value.trim().to_string()));
        }
        Self {
            length: position as u64,
            fields,
        }
    }

    /// The value of the first field named `key` (case-insensitive).
    pub fn get(&self, key: &str) -> Option<&str> {
        self.fields
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(key))
            .map(|(_, v)| v.as_str())
    }

    /// The event format the header names: `evt 3.0` or `format EVT3` -> 3, `evt 2.0` -> 2.
    pub fn evt_version(&self) -> Option<u8> {
        if let Some(v) = self.get("evt") {
            return v
                .trim()
                .chars()
                .next()
                .and_then(|c| c.to_digit(10))
                .map(|d| d as u8);
        }
        let format = self.get("format")?.to_ascii_uppercase();
        if format.starts_with("EVT3") {
            Some(3)
        } else if format.starts_with("EVT2") {
            Some(2)
        } else {
            None
        }
    }

    /// The sensor the header states, and how it is known; a stated size that is no sensor
    /// (`% geometry 0x0`, `axb`, a side over 65535) is returned as such, never passed over
    /// for the next source.
    pub fn sensor(&self) -> Result<Option<(Sensor, String)>, UnusableSize> {
        if let Some(line) = self.line_of("geometry") {
            let s = self.usable(line, parse_wxh(&self.fields[line].1))?;
            let origin = format!("% geometry on header line {}", line + 1);
            return Ok(Some((s, origin)));
        }
        if let Some(line) = self.line_of("format")
            && let Some(sides) = sides_of_format_line(&self.fields[line].1)
        {
            let s = self.usable(line, sides)?;
            let origin = format!("% format on header line {}", line + 1);
            return Ok(Some((s, origin)));
        }
        if let (Some(w), Some(h)) = (self.line_of("Width"), self.line_of("Height")) {
            let width = side(&self.fields[w].1).map_err(|why| self.unusable(w, why))?;
            let height = side(&self.fields[h].1).map_err(|why| self.unusable(h, why))?;
            let origin = format!(
                "% Width on header line {} and % Height on line {}",
                w + 1,
                h + 1
            );
            return Ok(Some((Sensor::new(width, height), origin)));
        }
        Ok(self.plugin_sensor())
    }

    /// The sensor of the camera plugin the header names (`plugin_name`), if known.
    fn plugin_sensor(&self) -> Option<(Sensor, String)> {
        let plugin = self.get("plugin_name")?;
        let preset = sensors::from_metadata(plugin)?;
        Some((
            preset.sensor(),
            format!("camera plugin `{plugin}` ({})", preset.name),
        ))
    }

    /// The index of the first field named `key` (case-insensitive): its header line - 1.
    fn line_of(&self, key: &str) -> Option<usize> {
        self.fields
            .iter()
            .position(|(k, _)| k.eq_ignore_ascii_case(key))
    }

    fn usable(&self, line: usize, size: Result<Sensor, String>) -> Result<Sensor, UnusableSize> {
        size.map_err(|why| self.unusable(line, why))
    }

    fn unusable(&self, line: usize, why: String) -> UnusableSize {
        let (key, value) = &self.fields[line];
        UnusableSize {
            line: line + 1,
            text: format!("% {key} {value}").trim_end().to_string(),
            why,
            plugin: self.plugin_sensor(),
        }
    }
}

/// A size the header states that is no sensor.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnusableSize {
    /// The header line (1-based: every header line is one field).
    pub line: usize,
    /// The line as written.
    pub text: String,
    /// Why it gives no sensor.
    pub why: String,
    /// The camera plugin's sensor, which ctcal used to take instead.
    plugin: Option<(Sensor, String)>,
}

impl UnusableSize {
    /// What is wrong, for an error or a note.
    pub fn problem(&self) -> String {
        format!(
            "`{}` states no usable sensor size ({})",
            self.text, self.why
        )
    }

    /// The error: the header line and the fixes (the line, or the size given; the plugin's
    /// size where the header names a camera plugin).
    pub fn error(&self, path: &Path) -> InputError {
        let mut fix = Text::from(
            "write the camera's real size on that line (e.g. `% geometry 1280x720`), or ",
        )
        .act(Hint::Sensor(None));
        if let Some((sensor, origin)) = &self.plugin {
            fix = fix
                .words(format!("; the header's {origin} is {sensor}: "))
                .act(Hint::Sensor(Some(*sensor)))
                .words(" if that is the camera");
        }
        InputError::corrupt(
            path,
            format!("header line {}", self.line),
            self.problem(),
            fix,
        )
    }
}

/// One side of a stated size: a whole number of 1 to 65535 pixels; else why not.
pub(crate) fn side(text: &str) -> Result<u16, String> {
    let text = text.trim();
    let n: u64 = text
        .parse()
        .map_err(|_| format!("`{text}` is not a whole number of pixels"))?;
    match u16::try_from(n) {
        Ok(0) => Err("a side of 0 pixels".into()),
        Ok(n) => Ok(n),
        Err(_) => Err(format!(
            "a side of {n} pixels; a side is at most 65535 and no sensor sold exceeds {MAX_SENSOR_SIDE}"
        )),
    }
}

/// `WxH` (e.g. `1280x720`).
fn parse_wxh(text: &str) -> Result<Sensor, String> {
    let (w, h) = text
        .trim()
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("`{text}` is not WxH"))?;
    Ok(Sensor::new(side(w)?, side(h)?))
}

/// `EVT3;height=720;width=1280` (newer Prophesee headers) -> 1280x720; `None` where the
/// line states no size.
fn sides_of_format_line(format: &str) -> Option<Result<Sensor, String>> {
    let mut width = None;
    let mut height = None;
    for part in format.split(';') {
        match part.split_once('=') {
            Some(("width", v)) => width = Some(v),
            Some(("height", v)) => height = Some(v),
            _ => {}
        }
    }
    let (width, height) = (width?, height?);
    Some(side(width).and_then(|w| Ok(Sensor::new(w, side(height)?))))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_ends_at_the_first_binary_byte() {
        let mut bytes = b"% evt 3.0\n% geometry 1280x720\n".to_vec();
        bytes.extend_from_slice(&[0xae, 0x8a, 0x25, 0x00]);
        let h = PropheseeHeader::parse(&bytes);
        assert_eq!(h.length, 30);
        assert_eq!(h.evt_version(), Some(3));
        assert_eq!(h.sensor().unwrap().unwrap().0, Sensor::new(1280, 720));
    }

    #[test]
    fn end_line_closes_the_header() {
        let h = PropheseeHeader::parse(b"% format EVT3;height=720;width=1280\n% end\n%\x01\x02");
        assert_eq!(h.length, 42);
        assert_eq!(h.evt_version(), Some(3));
        assert_eq!(h.sensor().unwrap().unwrap().0, Sensor::new(1280, 720));
    }

    #[test]
    fn a_stated_size_that_is_no_sensor_is_not_passed_over_for_the_plugin() {
        let h = PropheseeHeader::parse(
            b"% plugin_name hal_plugin_gen3_fx3\n% Width 640\n% Height 0\n\x00",
        );
        let unusable = h.sensor().unwrap_err();
        assert_eq!((unusable.line, unusable.text.as_str()), (3, "% Height 0"));
        assert!(unusable.problem().contains("a side of 0 pixels"));
    }

    #[test]
    fn plugin_name_names_the_sensor() {
        let h = PropheseeHeader::parse(b"% plugin_name hal_plugin_gen3_fx3\n% evt 2.0\n\x00");
        assert_eq!(h.sensor().unwrap().unwrap().0, Sensor::new(640, 480));
        assert_eq!(h.evt_version(), Some(2));
    }
}
