//! Frame index files of IJRR-style folders: `images.txt` (APS frames) and `stimulus.txt`
//! (what an on-screen calibration played), lines `t path` with `t` in seconds and `path`
//! relative to the folder; frames are 8-bit grey images (other PNG kinds are converted).

use super::error::InputError;
use super::text;
use crate::events::{Frame, TimeUs};
use std::path::{Path, PathBuf};

/// One line of a frame index.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameEntry {
    pub t: TimeUs,
    pub path: PathBuf,
    /// 1-based line in the index file.
    pub line: usize,
}

/// A parsed frame index.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameList {
    pub index_path: PathBuf,
    pub entries: Vec<FrameEntry>,
}

impl FrameList {
    /// Reads an index file; times must not decrease and every named image must exist.
    pub fn read(index_path: &Path) -> Result<Self, InputError> {
        crate::files::check_regular(index_path)
            .map_err(|e| InputError::not_a_file(index_path, e))?;
        let bytes = std::fs::read(index_path).map_err(|e| InputError::io(index_path, e))?;
        let folder = index_path.parent().unwrap_or(Path::new("."));
        let mut entries: Vec<FrameEntry> = Vec::new();
        for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
            let line = i + 1;
            let trimmed = raw.trim_ascii();
            if trimmed.is_empty() || trimmed[0] == b'#' {
                continue;
            }
            let (t, path) = time_and_path_field(index_path, line, raw, trimmed)?;
            let entry = frame_entry(index_path, folder, line, t, path, entries.last())?;
            entries.push(entry);
        }
        Ok(Self {
            index_path: index_path.to_path_buf(),
            entries,
        })
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    pub fn times(&self) -> Vec<TimeUs> {
        self.entries.iter().map(|e| e.t).collect()
    }

    /// Width and height of the first image (read from its header only).
    pub fn image_size(&self) -> Result<Option<(u32, u32)>, InputError> {
        let Some(first) = self.entries.first() else {
            return Ok(None);
        };
        image::image_dimensions(&first.path)
            .map(Some)
            .map_err(|e| self.image_error(first, &e.to_string()))
    }

    /// Decodes frame `i` to 8-bit grey.
    pub fn load(&self, i: usize) -> Result<Frame, InputError> {
        let entry = &self.entries[i];
        let image =
            image::open(&entry.path).map_err(|e| self.image_error(entry, &e.to_string()))?;
        let grey = image.into_luma8();
        let (width, height) = grey.dimensions();
        Ok(Frame {
            t: entry.t,
            width,
            height,
            pixels: grey.into_raw(),
            exposure_us: None,
        })
    }

    /// Decodes every frame, checking that all share one size.
    pub fn load_all(&self) -> Result<Vec<Frame>, InputError> {
        let mut frames: Vec<Frame> = Vec::with_capacity(self.len());
        for i in 0..self.len() {
            let frame = self.load(i)?;
            if let Some(first) = frames.first()
                && (frame.width, frame.height) != (first.width, first.height)
            {
                return Err(self.image_error(
                    &self.entries[i],
                    &format!(
                        "image is {}x{}, the first image is {}x{}",
                        frame.width, frame.height, first.width, first.height
                    ),
                ));
            }
            frames.push(frame);
        }
        Ok(frames)
    }

    fn image_error(&self, entry: &FrameEntry, problem: &str) -> InputError {
        InputError::corrupt(
            &self.index_path,
            format!("line {} ({})", entry.line, entry.path.display()),
            format!("cannot decode the image: {problem}"),
            "replace the image with an intact 8-bit PNG of the sensor's size",
        )
    }
}

/// A `t path` line's time (checked against the limit of event times) and its path field.
fn time_and_path_field<'a>(
    index_path: &Path,
    line: usize,
    raw: &[u8],
    trimmed: &'a [u8],
) -> Result<(TimeUs, &'a [u8]), InputError> {
    let mut fields = [&b""[..]; 2];
    let n = text::split_fields(trimmed, &mut fields);
    let t = (n == 2).then(|| text::seconds_to_us(fields[0])).flatten();
    let Some(t) = t else {
        return Err(InputError::corrupt(
            index_path,
            format!("line {line}"),
            format!(
                "expected `t path` (t in seconds), found `{}`",
                text::excerpt(raw)
            ),
            "each line names a frame: its time in seconds, a space, and the image path relative to this folder",
        ));
    };
    // a time as events have them (not beyond 2^61 us)
    if t.unsigned_abs() > crate::events::TIME_LIMIT_US as u64 {
        return Err(InputError::corrupt(
            index_path,
            format!("line {line}"),
            format!(
                "frame time {} s lies beyond +-{} s (about 73,000 years) of zero",
                text::excerpt(fields[0]),
                crate::events::TIME_LIMIT_US / 1_000_000
            ),
            "the line is damaged: give the frame's time in seconds",
        ));
    }
    Ok((t, fields[1]))
}

/// The entry of a line at `t` naming `path`, which must not precede `previous` and must exist.
fn frame_entry(
    index_path: &Path,
    folder: &Path,
    line: usize,
    t: TimeUs,
    path: &[u8],
    previous: Option<&FrameEntry>,
) -> Result<FrameEntry, InputError> {
    if let Some(previous) = previous
        && t < previous.t
    {
        return Err(InputError::corrupt(
            index_path,
            format!("line {line}"),
            format!(
                "frame time {} s is earlier than the line before ({} s)",
                t as f64 * 1e-6,
                previous.t as f64 * 1e-6
            ),
            "list frames in time order",
        ));
    }
    let path = folder.join(String::from_utf8_lossy(path).as_ref());
    if !path.is_file() {
        return Err(InputError::corrupt(
            index_path,
            format!("line {line}"),
            format!("the image {} does not exist", path.display()),
            "restore the image or remove its line",
        ));
    }
    Ok(FrameEntry { t, path, line })
}
