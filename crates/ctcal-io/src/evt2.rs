//! Prophesee RAW EVT 2.0: little-endian 32-bit words, the event type in the top 4 bits.
//!
//! `CD_OFF` (0x0) / `CD_ON` (0x1): bits 27..22 the 6 low time bits, 21..11 x, 10..0 y.
//! `EVT_TIME_HIGH` (0x8): bits 27..0 the time above those 6 bits (a 34-bit microsecond clock,
//! unwrapped here when it loops). `EXT_TRIGGER` (0xA), `OTHERS` (0xE) and `CONTINUED` (0xF)
//! carry no polarity events and are skipped. CD events before the first time-high word have
//! no defined time and are skipped. Reference: Prophesee, "EVT 2.0 format" (Metavision SDK
//! documentation); the decoder is written here because no maintained Rust crate decodes EVT2.

use super::blocks::BlockReader;
use super::error::InputError;
use super::order::OrderCheck;
use super::{EventDecoder, Progress};
use crate::events::{CHUNK_EVENTS, EventChunk, Sensor};
use std::path::{Path, PathBuf};

const TIME_HIGH_RANGE: u64 = 1 << 28;

/// Streaming EVT2 decoder.
pub struct Evt2Decoder {
    reader: BlockReader,
    state: State,
}

struct State {
    path: PathBuf,
    sensor: Option<Sensor>,
    order: OrderCheck,
    time_high: Option<u64>,
    last_raw_high: u64,
    loops: u64,
}

impl Evt2Decoder {
    /// Opens `path` with its data starting at `data_offset` (after the header).
    pub fn open(path: &Path, data_offset: u64, sensor: Option<Sensor>) -> Result<Self, InputError> {
        Ok(Self {
            reader: BlockReader::open(path, data_offset)?,
            state: State {
                path: path.to_path_buf(),
                sensor,
                order: OrderCheck::default(),
                time_high: None,
                last_raw_high: 0,
                loops: 0,
            },
        })
    }
}

impl State {
    #[inline]
    fn decode(&mut self, word: u32, offset: u64, out: &mut EventChunk) -> Result<(), InputError> {
        match word >> 28 {
            kind @ (0x0 | 0x1) => {
                let Some(high) = self.time_high else {
                    return Ok(());
                };
                let t = (high << 6 | ((word >> 22) & 0x3f) as u64) as i64;
                let x = ((word >> 11) & 0x7ff) as u16;
                let y = (word & 0x7ff) as u16;
                if !super::within(self.sensor, x as u32, y as u32) {
                    return Err(super::outside_sensor(
                        &self.path,
                        format!("byte offset {offset}"),
                        x as i64,
                        y as i64,
                        self.sensor,
                    ));
                }
                self.order.check(t, || format!("byte offset {offset}"));
                out.push(t, x, y, kind == 0x1);
            }
            0x8 => {
                let raw = (word & 0x0fff_ffff) as u64;
                if self.time_high.is_some()
                    && raw < self.last_raw_high
                    && self.last_raw_high - raw > TIME_HIGH_RANGE / 2
                {
                    self.loops += 1;
                }
                self.last_raw_high = raw;
                self.time_high = Some(raw + self.loops * TIME_HIGH_RANGE);
            }
            _ => {}
        }
        Ok(())
    }
}

impl EventDecoder for Evt2Decoder {
    fn read_chunk(&mut self, out: &mut EventChunk) -> Result<(), InputError> {
        loop {
            // a word emits at most one event
            let (words, base) = self
                .reader
                .records(4, CHUNK_EVENTS.saturating_sub(out.len()));
            for (i, bytes) in words.chunks_exact(4).enumerate() {
                let word = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
                self.state.decode(word, base + 4 * i as u64, out)?;
            }
            let consumed = words.len();
            self.reader.consume(consumed);
            if out.len() >= CHUNK_EVENTS {
                return Ok(());
            }
            if !self.reader.refill_units(4, "a 4-byte EVT2 word")? {
                return Ok(());
            }
        }
    }

    fn order(&self) -> &OrderCheck {
        &self.state.order
    }

    fn progress(&self) -> Progress {
        self.reader.progress()
    }
}
