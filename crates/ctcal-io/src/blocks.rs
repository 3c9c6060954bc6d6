//! Block-wise file reading with a carried-over tail: decoders see whole lines or words even
//! when a read ends in the middle of one, and memory stays at one block whatever the file
//! size (a memory map would count the whole file as resident).

use super::Progress;
use super::error::{FIX_TRUNCATED, InputError};
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// Bytes read from disk per refill.
pub const BLOCK_BYTES: usize = 4 << 20;

/// A file read in blocks, exposing the not-yet-consumed bytes.
pub struct BlockReader {
    path: PathBuf,
    file: std::fs::File,
    buffer: Vec<u8>,
    start: usize,
    end: usize,
    /// File offset of `buffer[0]`.
    buffer_offset: u64,
    eof: bool,
    total: u64,
}

impl BlockReader {
    /// Opens `path` and positions it at byte `skip` (e.g. after a text header).
    pub fn open(path: &Path, skip: u64) -> Result<Self, InputError> {
        let mut file = std::fs::File::open(path).map_err(|e| InputError::io(path, e))?;
        let total = file.metadata().map_err(|e| InputError::io(path, e))?.len();
        file.seek(SeekFrom::Start(skip))
            .map_err(|e| InputError::io(path, e))?;
        Ok(Self {
            path: path.to_path_buf(),
            file,
            buffer: vec![0; BLOCK_BYTES],
            start: 0,
            end: 0,
            buffer_offset: skip,
            eof: false,
            total,
        })
    }

    /// The unconsumed bytes currently in memory.
    #[inline]
    pub fn available(&self) -> &[u8] {
        &self.buffer[self.start..self.end]
    }

    /// Marks `n` bytes of [`Self::available`] as consumed.
    #[inline]
    pub fn consume(&mut self, n: usize) {
        debug_assert!(self.start + n <= self.end);
        self.start += n;
    }

    /// Moves the unconsumed tail to the front and reads more. Returns `false` when nothing
    /// more could be read (end of file).
    pub fn refill(&mut self) -> Result<bool, InputError> {
        if self.eof {
            return Ok(false);
        }
        let tail = self.end - self.start;
        if self.start > 0 {
            self.buffer.copy_within(self.start..self.end, 0);
            self.buffer_offset += self.start as u64;
            self.start = 0;
            self.end = tail;
        }
        if self.end == self.buffer.len() {
            // a single unit longer than a block (a very long line): grow
            self.buffer.resize(self.buffer.len() * 2, 0);
        }
        let mut read_any = false;
        while self.end < self.buffer.len() {
            let n = self
                .file
                .read(&mut self.buffer[self.end..])
                .map_err(|e| InputError::io(&self.path, e))?;
            if n == 0 {
                self.eof = true;
                break;
            }
            self.end += n;
            read_any = true;
        }
        Ok(read_any)
    }

    /// File offset of the first unconsumed byte.
    #[inline]
    pub fn offset(&self) -> u64 {
        self.buffer_offset + self.start as u64
    }

    /// Bytes consumed of the file.
    pub fn progress(&self) -> Progress {
        Progress {
            done: self.offset(),
            total: self.total,
        }
    }

    /// The whole records of `unit` bytes in memory, at most `max` of them, and the file
    /// offset of the first.
    #[inline]
    pub fn records(&self, unit: usize, max: usize) -> (&[u8], u64) {
        let available = self.available();
        let count = (available.len() / unit).min(max);
        (&available[..count * unit], self.offset())
    }

    /// For fixed-size binary records: reads more when fewer than `unit` bytes are left.
    /// `Ok(true)`: read on; `Ok(false)`: the file ended cleanly; an error when it ends inside
    /// a record (`what` names the record, e.g. "a 4-byte EVT2 word").
    pub fn refill_units(&mut self, unit: usize, what: &str) -> Result<bool, InputError> {
        if self.available().len() >= unit || self.refill()? {
            return Ok(true);
        }
        let left = self.available().len();
        if left > 0 {
            return Err(InputError::corrupt(
                &self.path,
                format!("byte offset {}", self.offset()),
                format!("the file ends inside {what} ({left} of {unit} bytes)"),
                FIX_TRUNCATED,
            ));
        }
        Ok(false)
    }
}
