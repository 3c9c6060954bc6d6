//! Format detection from content (the extension is only a tie-breaker): AEDAT4 and HDF5 by
//! their signatures, Prophesee files by their `%` header (`evt 2.0` / `evt 3.0`, or DAT's
//! `Width`/`Height`), text by a first data line that parses as numbers.

use super::error::InputError;
use super::prophesee::PropheseeHeader;
use super::{Format, aedat4, h5, text};
use std::io::Read;
use std::path::Path;

/// Detects the format of `path` (a file or an IJRR folder).
pub fn detect(path: &Path) -> Result<Format, InputError> {
    if !path.exists() {
        return Err(InputError::NotFound {
            path: path.to_path_buf(),
        });
    }
    if path.is_dir() {
        if path.join("events.txt").is_file() {
            return Ok(Format::Ijrr);
        }
        return Err(InputError::UnknownFormat {
            path: path.to_path_buf(),
            detail: "a folder without events.txt".into(),
        });
    }
    let mut head = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(1 << 16).read_to_end(&mut head))
        .map_err(|e| InputError::io(path, e))?;
    if head.is_empty() {
        return Err(InputError::Empty {
            path: path.to_path_buf(),
        });
    }
    if aedat4::has_magic(&head) {
        return Ok(Format::Aedat4);
    }
    if [0usize, 512, 1024, 2048]
        .iter()
        .any(|&at| head.get(at..at + 8) == Some(h5::SIGNATURE))
    {
        return Ok(Format::H5);
    }
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    if head[0] == b'%' {
        let header = PropheseeHeader::parse(&head);
        return match header.evt_version() {
            Some(3) => Ok(Format::Evt3),
            Some(2) => Ok(Format::Evt2),
            Some(v) => Err(InputError::UnknownFormat {
                path: path.to_path_buf(),
                detail: format!("Prophesee RAW EVT {v}, which ctcal does not decode"),
            }),
            None if extension == "dat"
                || header.get("Width").is_some()
                || header.get("Version").is_some() =>
            {
                Ok(Format::Dat)
            }
            None => Err(InputError::UnknownFormat {
                path: path.to_path_buf(),
                detail: "a Prophesee header without an `evt` line".into(),
            }),
        };
    }
    if looks_like_event_text(&head) {
        return Ok(Format::Ijrr);
    }
    Err(InputError::UnknownFormat {
        path: path.to_path_buf(),
        detail: format!(
            "first bytes {:02x?} match no known signature",
            &head[..head.len().min(8)]
        ),
    })
}

/// Whether the first non-comment line is `t x y p` (or a `width height` line).
fn looks_like_event_text(head: &[u8]) -> bool {
    for line in head.split(|&b| b == b'\n') {
        let line = line.trim_ascii();
        if line.is_empty() || line[0] == b'#' {
            continue;
        }
        let mut fields = [&b""[..]; 4];
        let n = text::split_fields(line, &mut fields);
        return match n {
            4 => text::seconds_to_us(fields[0]).is_some() && text::parse_u32(fields[1]).is_some(),
            2 => text::parse_u32(fields[0]).is_some() && text::parse_u32(fields[1]).is_some(),
            _ => false,
        };
    }
    false
}
