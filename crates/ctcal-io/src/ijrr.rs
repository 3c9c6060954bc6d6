//! IJRR / rpg text events (Mueggler et al., "The Event-Camera Dataset and Simulator", IJRR
//! 2017): `events.txt` with one event per line `t x y p` (t in seconds, p 0/1 or -1/1), an
//! optional first line `width height` (as rpg_e2vid writes), `#` comment lines; in a folder
//! with optional `images.txt` + `images/` and `stimulus.txt` + `stimulus/`.
//!
//! The file is read in blocks and parsed line by line without allocation; times are rounded
//! to the microsecond from the decimal digits (see [`super::text`]).

use super::blocks::BlockReader;
use super::error::InputError;
use super::frame_list::FrameList;
use super::order::OrderCheck;
use super::text;
use super::{EventDecoder, Progress};
use crate::events::{CHUNK_EVENTS, EventChunk, Sensor};
use crate::hint::{Hint, Text};
use std::path::{Path, PathBuf};

mod split;

/// The files of an IJRR folder (or a lone `events.txt`).
#[derive(Clone, Debug)]
pub struct IjrrFiles {
    pub events: PathBuf,
    pub images: Option<PathBuf>,
    pub stimulus: Option<PathBuf>,
}

impl IjrrFiles {
    /// Locates the files for `path` (a folder holding `events.txt`, or the file itself).
    pub fn locate(path: &Path) -> Result<Self, InputError> {
        let (folder, events) = if path.is_dir() {
            (path.to_path_buf(), path.join("events.txt"))
        } else {
            (
                path.parent().unwrap_or(Path::new(".")).to_path_buf(),
                path.to_path_buf(),
            )
        };
        match crate::files::check_regular(&events) {
            Ok(_) => {}
            Err(crate::files::NotAFile::Missing) => {
                return Err(InputError::invalid(
                    path,
                    "the folder holds no events.txt",
                    "point ctcal at an IJRR folder (events.txt, optional images.txt) or at an event file",
                ));
            }
            Err(e) => return Err(InputError::not_a_file(&events, e)),
        }
        let existing = |name: &str| Some(folder.join(name)).filter(|p| p.is_file());
        Ok(Self {
            events,
            images: existing("images.txt"),
            stimulus: existing("stimulus.txt"),
        })
    }
}

/// What the head of `events.txt` says: an optional `width height` line.
#[derive(Debug, Default)]
pub struct TextHeader {
    pub sensor: Option<Sensor>,
    /// A `width height` line that gives no sensor (`0 0`, a side over 65535): an error
    /// unless the sensor size is given.
    pub unusable: Option<InputError>,
}

/// Reads the optional `width height` first data line.
pub fn read_header(events: &Path) -> Result<TextHeader, InputError> {
    let file = std::fs::File::open(events).map_err(|e| InputError::io(events, e))?;
    let mut reader = std::io::BufReader::new(file);
    let mut line = Vec::new();
    use std::io::BufRead;
    for number in 1.. {
        line.clear();
        let n = reader
            .read_until(b'\n', &mut line)
            .map_err(|e| InputError::io(events, e))?;
        if n == 0 {
            break;
        }
        let trimmed = line.trim_ascii();
        if trimmed.is_empty() || trimmed[0] == b'#' {
            continue;
        }
        let mut fields = [&b""[..]; 3];
        if text::split_fields(trimmed, &mut fields) == 2
            && let (Some(w), Some(h)) = (text::parse_u32(fields[0]), text::parse_u32(fields[1]))
        {
            return Ok(match (u16::try_from(w), u16::try_from(h)) {
                (Ok(w), Ok(h)) if w > 0 && h > 0 => TextHeader {
                    sensor: Some(Sensor::new(w, h)),
                    unusable: None,
                },
                _ => TextHeader {
                    sensor: None,
                    unusable: Some(InputError::corrupt(
                    events,
                    format!("line {number}"),
                    format!(
                        "the `width height` line `{}` gives no sensor (each side 1 to 65535 pixels)",
                        text::excerpt(trimmed)
                    ),
                    Text::from("write the sensor's real size there (e.g. `240 180`), or delete the line and ")
                        .act(Hint::Sensor(None)),
                    )),
                },
            });
        }
        break;
    }
    Ok(TextHeader::default())
}

/// Streaming decoder of `events.txt`.
pub struct IjrrDecoder {
    reader: BlockReader,
    lines: LineParser,
    /// The second half of a block split between two threads (reused).
    second_half: EventChunk,
}

/// Below this many bytes of whole lines a block is parsed on one thread (splitting costs a
/// task hand-over, worth it only for a few thousand lines).
const MIN_SPLIT_BYTES: usize = 256 << 10;

/// Per-line parsing state, kept apart from the reader so both can be borrowed at once.
struct LineParser {
    path: PathBuf,
    line: usize,
    seen_data_line: bool,
    sensor: Option<Sensor>,
    order: OrderCheck,
    /// `false` for the second half of a split block, whose order the first half's parser
    /// checks after both are done (its first event follows the first half's last).
    check_order: bool,
}

impl IjrrDecoder {
    /// Opens `events`; events are checked against `sensor` when it is known.
    pub fn open(events: &Path, sensor: Option<Sensor>) -> Result<Self, InputError> {
        Ok(Self {
            reader: BlockReader::open(events, 0)?,
            lines: LineParser {
                path: events.to_path_buf(),
                line: 0,
                seen_data_line: false,
                sensor,
                order: OrderCheck::default(),
                check_order: true,
            },
            second_half: EventChunk::default(),
        })
    }
}

impl LineParser {
    fn bad_line(&self, raw: &[u8], problem: &str) -> InputError {
        InputError::corrupt(
            &self.path,
            format!("line {}", self.line),
            format!("{problem}: `{}`", text::excerpt(raw)),
            "each event line is `t x y p` (t in seconds, x and y non-negative integers, p 0/1 or -1/1); fix or delete the line",
        )
    }

    /// Parses one line (without its newline), appending an event if it holds one.
    #[inline]
    fn parse(&mut self, raw: &[u8], out: &mut EventChunk) -> Result<(), InputError> {
        self.line += 1;
        if let Some((t, x, y, on)) = text::event_line(raw) {
            self.seen_data_line = true;
            return self.accept((t, x, y, on), out);
        }
        let mut fields = [&b""[..]; 4];
        let count = text::split_fields(raw, &mut fields);
        if count == 0 || fields[0][0] == b'#' {
            return Ok(());
        }
        if count != 4 {
            if count == 2 && !self.seen_data_line {
                // the optional `width height` line
                self.seen_data_line = true;
                if text::parse_u32(fields[0]).is_some() && text::parse_u32(fields[1]).is_some() {
                    return Ok(());
                }
            }
            let problem = format!("expected 4 fields, found {count}");
            return Err(self.bad_line(raw, &problem));
        }
        self.seen_data_line = true;
        let Some(t) = text::seconds_to_us(fields[0]) else {
            return Err(self.bad_line(raw, "the time is not a finite number of seconds"));
        };
        let (Some(x), Some(y)) = (text::parse_u32(fields[1]), text::parse_u32(fields[2])) else {
            return Err(self.bad_line(raw, "x and y must be non-negative integers"));
        };
        let Some(on) = text::parse_polarity(fields[3]) else {
            return Err(self.bad_line(raw, "the polarity must be 0, 1 or -1"));
        };
        self.accept((t, x, y, on), out)
    }

    /// Checks a parsed event against the sensor and the order, and appends it.
    #[inline(always)]
    fn accept(
        &mut self,
        (t, x, y, on): (i64, u32, u32, bool),
        out: &mut EventChunk,
    ) -> Result<(), InputError> {
        if !super::within(self.sensor, x, y) {
            return Err(super::outside_sensor(
                &self.path,
                format!("line {}", self.line),
                x as i64,
                y as i64,
                self.sensor,
            ));
        }
        if self.check_order {
            let line = self.line;
            self.order.check(t, || format!("line {line}"));
        }
        out.push(t, x as u16, y as u16, on);
        Ok(())
    }
}

impl EventDecoder for IjrrDecoder {
    fn read_chunk(&mut self, out: &mut EventChunk) -> Result<(), InputError> {
        loop {
            if self.lines.seen_data_line && rayon::current_num_threads() > 1 {
                let consumed = split::parse_halves(
                    self.reader.available(),
                    &mut self.lines,
                    out,
                    &mut self.second_half,
                )?;
                self.reader.consume(consumed);
            }
            let available = self.reader.available();
            let mut consumed = 0;
            while out.len() < CHUNK_EVENTS {
                let rest = &available[consumed..];
                let Some(end) = memchr::memchr(b'\n', rest) else {
                    break;
                };
                self.lines.parse(&rest[..end], out)?;
                consumed += end + 1;
            }
            self.reader.consume(consumed);
            if out.len() >= CHUNK_EVENTS {
                return Ok(());
            }
            if !self.reader.refill()? {
                // end of file: a last line without a newline
                let rest = self.reader.available();
                if !rest.is_empty() {
                    let n = rest.len();
                    self.lines.parse(rest, out)?;
                    self.reader.consume(n);
                }
                return Ok(());
            }
        }
    }

    fn order(&self) -> &OrderCheck {
        &self.lines.order
    }

    fn progress(&self) -> Progress {
        self.reader.progress()
    }
}

/// The frame list of an IJRR folder, if it has `images.txt`.
pub fn frames(files: &IjrrFiles) -> Result<Option<FrameList>, InputError> {
    files.images.as_deref().map(FrameList::read).transpose()
}
