//! Prophesee DAT (the older Metavision "CD" file): a `%` text header, then one byte event
//! type and one byte event size, then fixed-size events. For CD events (type 0x0C, 8 bytes):
//! a little-endian u32 timestamp in microseconds (unwrapped here if it loops) and a u32 with
//! x in bits 13..0, y in bits 27..14 and polarity in bits 31..28. Written here: the format
//! is a dozen lines and the Rust crates that read it pull in much more.

use super::blocks::BlockReader;
use super::error::{FIX_TRUNCATED, InputError};
use super::order::OrderCheck;
use super::{EventDecoder, Progress};
use crate::events::{CHUNK_EVENTS, EventChunk, Sensor};
use crate::hint::{Hint, Text};
use std::path::{Path, PathBuf};

/// Streaming DAT decoder.
pub struct DatDecoder {
    reader: BlockReader,
    path: PathBuf,
    sensor: Option<Sensor>,
    order: OrderCheck,
    event_size: usize,
    last_raw_t: u64,
    loops: u64,
}

impl DatDecoder {
    /// Opens `path`; `data_offset` is where the header ends (the type/size bytes follow).
    pub fn open(path: &Path, data_offset: u64, sensor: Option<Sensor>) -> Result<Self, InputError> {
        let mut reader = BlockReader::open(path, data_offset)?;
        reader.refill()?;
        let head = reader.available();
        if head.len() < 2 {
            return Err(InputError::corrupt(
                path,
                format!("byte offset {data_offset}"),
                "the file ends before the event type and size bytes",
                FIX_TRUNCATED,
            ));
        }
        let (kind, size) = (head[0], head[1] as usize);
        if size < 8 {
            return Err(InputError::corrupt(
                path,
                format!("byte offset {}", data_offset + 1),
                format!("event size {size} bytes (type 0x{kind:02x}); CD events take 8"),
                Text::from("this is not a Prophesee CD .dat file; ")
                    .act(Hint::Format(None))
                    .words(" to read it as another format"),
            ));
        }
        reader.consume(2);
        Ok(Self {
            reader,
            path: path.to_path_buf(),
            sensor,
            order: OrderCheck::default(),
            event_size: size,
            last_raw_t: 0,
            loops: 0,
        })
    }
}

impl EventDecoder for DatDecoder {
    fn read_chunk(&mut self, out: &mut EventChunk) -> Result<(), InputError> {
        loop {
            let size = self.event_size;
            let (records, base) = self
                .reader
                .records(size, CHUNK_EVENTS.saturating_sub(out.len()));
            for (i, bytes) in records.chunks_exact(size).enumerate() {
                let raw_t = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) as u64;
                let data = u32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]);
                if raw_t < self.last_raw_t && self.last_raw_t - raw_t > 1 << 31 {
                    self.loops += 1;
                }
                self.last_raw_t = raw_t;
                let t = (raw_t + (self.loops << 32)) as i64;
                let x = (data & 0x3fff) as u16;
                let y = ((data >> 14) & 0x3fff) as u16;
                let offset = base + (i * size) as u64;
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
                out.push(t, x, y, (data >> 28) & 0xf != 0);
            }
            let consumed = records.len();
            self.reader.consume(consumed);
            if out.len() >= CHUNK_EVENTS {
                return Ok(());
            }
            if !self.reader.refill_units(size, "an event")? {
                return Ok(());
            }
        }
    }

    fn order(&self) -> &OrderCheck {
        &self.order
    }

    fn progress(&self) -> Progress {
        self.reader.progress()
    }
}
