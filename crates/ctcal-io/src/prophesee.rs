//! The text header shared by Prophesee RAW (EVT2, EVT3) and DAT files: lines starting with
//! `%` (`% key value`), ended by `% end` or by the first line that does not start with `%`.
//! The sensor comes from `% geometry WxH`, `% Width`/`% Height`, or the camera plugin name.

use super::error::InputError;
use crate::events::Sensor;
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

    /// The sensor the header states, and how it is known.
    pub fn sensor(&self) -> Option<(Sensor, String)> {
        if let Some(g) = self.get("geometry")
            && let Some(s) = Sensor::parse(g)
        {
            return Some((s, "% geometry in the header".into()));
        }
        if let Some(format) = self.get("format")
            && let Some(s) = sensor_from_format_line(format)
        {
            return Some((s, "% format line of the header".into()));
        }
        if let (Some(w), Some(h)) = (self.get("Width"), self.get("Height"))
            && let (Ok(w), Ok(h)) = (w.parse::<u16>(), h.parse::<u16>())
            && w > 0
            && h > 0
        {
            return Some((Sensor::new(w, h), "% Width/% Height in the header".into()));
        }
        if let Some(plugin) = self.get("plugin_name")
            && let Some(preset) = sensors::from_metadata(plugin)
        {
            return Some((
                preset.sensor(),
                format!("camera plugin `{plugin}` ({})", preset.name),
            ));
        }
        None
    }
}

/// `EVT3;height=720;width=1280` (newer Prophesee headers) -> 1280x720.
fn sensor_from_format_line(format: &str) -> Option<Sensor> {
    let mut width = None;
    let mut height = None;
    for part in format.split(';') {
        match part.split_once('=') {
            Some(("width", v)) => width = v.trim().parse::<u16>().ok(),
            Some(("height", v)) => height = v.trim().parse::<u16>().ok(),
            _ => {}
        }
    }
    Some(Sensor::new(width?, height?)).filter(|s| s.width > 0 && s.height > 0)
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
        assert_eq!(h.sensor().unwrap().0, Sensor::new(1280, 720));
    }

    #[test]
    fn end_line_closes_the_header() {
        let h = PropheseeHeader::parse(b"% format EVT3;height=720;width=1280\n% end\n%\x01\x02");
        assert_eq!(h.length, 42);
        assert_eq!(h.evt_version(), Some(3));
        assert_eq!(h.sensor().unwrap().0, Sensor::new(1280, 720));
    }

    #[test]
    fn plugin_name_names_the_sensor() {
        let h = PropheseeHeader::parse(b"% plugin_name hal_plugin_gen3_fx3\n% evt 2.0\n\x00");
        assert_eq!(h.sensor().unwrap().0, Sensor::new(640, 480));
        assert_eq!(h.evt_version(), Some(2));
    }
}
