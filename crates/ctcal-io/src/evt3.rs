//! Prophesee RAW EVT 3.0: little-endian 16-bit words, the type in the top 4 bits.
//!
//! `EVT_ADDR_Y` (0x0) sets y; `EVT_ADDR_X` (0x2) emits one event at x with polarity bit 11;
//! `VECT_BASE_X` (0x3) sets x and polarity for the vectors; `VECT_12` (0x4) / `VECT_8` (0x5)
//! emit an event per set bit at x + bit, then advance x by 12 / 8; `EVT_TIME_LOW` (0x6) and
//! `EVT_TIME_HIGH` (0x8) carry the low and high 12 bits of a 24-bit microsecond clock, which
//! is unwrapped here when the high part jumps back by more than half its range. Other types
//! (triggers, `OTHERS`, `CONTINUED`) carry no polarity events. Words that straddle two read
//! blocks are carried over by the block reader. Reference: Prophesee, "EVT 3.0 format"
//! (Metavision SDK documentation). Written here because the `evt3` crate decodes only this
//! one format and ctcal needs the same streaming and error conventions for all of them.

use super::blocks::BlockReader;
use super::error::InputError;
use super::order::OrderCheck;
use super::{EventDecoder, Progress};
use crate::events::{CHUNK_EVENTS, EventChunk, Sensor};
use std::path::{Path, PathBuf};

/// Streaming EVT3 decoder.
pub struct Evt3Decoder {
    reader: BlockReader,
    state: State,
}

struct State {
    path: PathBuf,
    sensor: Option<Sensor>,
    order: OrderCheck,
    time_high: u64,
    time_low: u64,
    loops: u64,
    seen_time_high: bool,
    x: u16,
    y: u16,
    on: bool,
}

impl Evt3Decoder {
    /// Opens `path` with its data starting at `data_offset` (after the header).
    pub fn open(path: &Path, data_offset: u64, sensor: Option<Sensor>) -> Result<Self, InputError> {
        Ok(Self {
            reader: BlockReader::open(path, data_offset)?,
            state: State {
                path: path.to_path_buf(),
                sensor,
                order: OrderCheck::default(),
                time_high: 0,
                time_low: 0,
                loops: 0,
                seen_time_high: false,
                x: 0,
                y: 0,
                on: false,
            },
        })
    }
}

impl State {
    #[inline(always)]
    fn time(&self) -> i64 {
        ((self.loops << 24) | (self.time_high << 12) | self.time_low) as i64
    }

    #[inline(always)]
    fn emit(&mut self, x: u16, offset: u64, out: &mut EventChunk) -> Result<(), InputError> {
        if !self.seen_time_high {
            return Ok(());
        }
        if !super::within(self.sensor, x as u32, self.y as u32) {
            return Err(super::outside_sensor(
                &self.path,
                format!("byte offset {offset}"),
                x as i64,
                self.y as i64,
                self.sensor,
            ));
        }
        let t = self.time();
        self.order.check(t, || format!("byte offset {offset}"));
        out.push(t, x, self.y, self.on);
        Ok(())
    }

    #[inline]
    fn decode(&mut self, word: u16, offset: u64, out: &mut EventChunk) -> Result<(), InputError> {
        match word >> 12 {
            0x0 => self.y = word & 0x7ff,
            0x2 => {
                self.on = word & 0x800 != 0;
                self.emit(word & 0x7ff, offset, out)?;
            }
            0x3 => {
                self.x = word & 0x7ff;
                self.on = word & 0x800 != 0;
            }
            kind @ (0x4 | 0x5) => {
                let width = if kind == 0x4 { 12 } else { 8 };
                let mut bits = word & ((1u16 << width) - 1);
                while bits != 0 {
                    let bit = bits.trailing_zeros() as u16;
                    self.emit(self.x + bit, offset, out)?;
                    bits &= bits - 1;
                }
                self.x += width;
            }
            0x6 => self.time_low = (word & 0xfff) as u64,
            0x8 => {
                let high = (word & 0xfff) as u64;
                if self.seen_time_high && high < self.time_high && self.time_high - high > 2048 {
                    self.loops += 1;
                }
                if high != self.time_high || !self.seen_time_high {
                    self.time_low = 0;
                }
                self.time_high = high;
                self.seen_time_high = true;
            }
            _ => {}
        }
        Ok(())
    }
}

impl EventDecoder for Evt3Decoder {
    fn read_chunk(&mut self, out: &mut EventChunk) -> Result<(), InputError> {
        loop {
            // a vector word emits at most 12 events
            let room = (CHUNK_EVENTS.saturating_sub(out.len()) / 12).max(1);
            let (words, base) = self.reader.records(2, room);
            for (i, bytes) in words.chunks_exact(2).enumerate() {
                let word = u16::from_le_bytes([bytes[0], bytes[1]]);
                self.state.decode(word, base + 2 * i as u64, out)?;
            }
            let consumed = words.len();
            self.reader.consume(consumed);
            if out.len() + 12 > CHUNK_EVENTS {
                return Ok(());
            }
            if !self.reader.refill_units(2, "a 2-byte EVT3 word")? {
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
