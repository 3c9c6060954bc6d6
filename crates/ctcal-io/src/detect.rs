//! Format detection from content (the extension is only a tie-breaker): AEDAT4 and HDF5 by
//! their signatures, Prophesee files by their `%` header (`evt 2.0` / `evt 3.0`, or DAT's
//! `Width`/`Height`), text by a first data line that parses as numbers.

use super::error::InputError;
use super::prophesee::PropheseeHeader;
use super::{Format, aedat4, bag, h5, text};
use crate::hint::{Hint, Text};
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
        return folder_format(path);
    }
    let head = read_head(path)?;
    if let Some(format) = signature_format(path, &head)? {
        return Ok(format);
    }
    if head[0] == b'%' {
        return prophesee_format(path, &head);
    }
    if looks_like_event_text(&head) {
        return Ok(Format::Ijrr);
    }
    let first: Vec<String> = head.iter().take(8).map(|b| format!("{b:02x}")).collect();
    Err(InputError::unknown(
        path,
        format!("first bytes {} match no known signature", first.join(" ")),
        super::error::fix_unknown_format(),
    ))
}

/// A folder is an IJRR recording when it holds `events.txt`.
fn folder_format(path: &Path) -> Result<Format, InputError> {
    if path.join("events.txt").is_file() {
        return Ok(Format::Ijrr);
    }
    Err(InputError::unknown(
        path,
        "a folder without events.txt",
        "point ctcal at an IJRR folder (events.txt, optional images.txt) or at a recording file",
    ))
}

/// The first 64 KiB of the regular file `path` (all of it when shorter); an empty file is
/// an error.
fn read_head(path: &Path) -> Result<Vec<u8>, InputError> {
    crate::files::check_regular(path).map_err(|e| InputError::not_a_file(path, e))?;
    let mut head = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(1 << 16).read_to_end(&mut head))
        .map_err(|e| InputError::io(path, e))?;
    if head.is_empty() {
        return Err(InputError::Empty {
            path: path.to_path_buf(),
        });
    }
    Ok(head)
}

/// The format a file's signature names, if any, from its first bytes `head`: AEDAT4
/// (`#!AER-DAT4.0\r\n`), a ROS1 bag (rosbag v2.0: `#ROSBAG V2.0\n`) or HDF5 (the 8-byte
/// superblock signature, at byte 0, 512, 1024 or 2048 where a user block precedes it).
/// Other bag versions and image files are errors that say what the file is.
fn signature_format(path: &Path, head: &[u8]) -> Result<Option<Format>, InputError> {
    if aedat4::has_magic(head) {
        return Ok(Some(Format::Aedat4));
    }
    if head.starts_with(bag::records::MAGIC) {
        return Ok(Some(Format::Bag));
    }
    if head.starts_with(b"#ROSBAG V") {
        return Err(InputError::unknown(
            path,
            format!(
                "a ROS bag of version `{}`; ctcal reads ROS1 bags (V2.0)",
                String::from_utf8_lossy(&head[..head.len().min(16)]).trim()
            ),
            "ROS2 bags are folders of .db3/.mcap files: convert them to a ROS1 bag (`rosbags-convert`) first",
        ));
    }
    if let Some(kind) = image_kind(head) {
        return Err(InputError::unknown(
            path,
            format!("a {kind} image, not an event recording"),
            "give the recording: its folder (events.txt, images.txt) or its event file; frames are found through images.txt",
        ));
    }
    if [0usize, 512, 1024, 2048]
        .iter()
        .any(|&at| head.get(at..at + 8) == Some(h5::SIGNATURE))
    {
        return Ok(Some(Format::H5));
    }
    Ok(None)
}

/// The format of a file whose first bytes `head` start with a Prophesee `%` header: the
/// `evt` line's version (3: EVT3, 2: EVT2, any other is refused), else DAT where the
/// extension is `.dat` or the header has DAT's `Width` or `Version` lines.
fn prophesee_format(path: &Path, head: &[u8]) -> Result<Format, InputError> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let header = PropheseeHeader::parse(head);
    match header.evt_version() {
        Some(3) => Ok(Format::Evt3),
        Some(2) => Ok(Format::Evt2),
        Some(v) => Err(InputError::unknown(
            path,
            format!("Prophesee RAW EVT {v}, which ctcal does not decode"),
            "convert it to EVT 3.0 or 2.0 with Metavision (metavision_file_to_raw) or to HDF5",
        )),
        None if extension == "dat"
            || header.get("Width").is_some()
            || header.get("Version").is_some() =>
        {
            Ok(Format::Dat)
        }
        None => Err(InputError::unknown(
            path,
            "a Prophesee header without an `evt` line",
            Text::default()
                .act(Hint::Format(None))
                .words(" evt2, evt3 or dat to say which it is"),
        )),
    }
}

/// The kind of image a file starts like, if any.
fn image_kind(head: &[u8]) -> Option<&'static str> {
    const KINDS: [(&[u8], &str); 5] = [
        (b"\x89PNG\r\n\x1a\n", "PNG"),
        (b"\xff\xd8\xff", "JPEG"),
        (b"II*\x00", "TIFF"),
        (b"MM\x00*", "TIFF"),
        (b"BM", "BMP"),
    ];
    KINDS
        .iter()
        .find(|(magic, _)| head.starts_with(magic))
        .map(|(_, kind)| *kind)
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
