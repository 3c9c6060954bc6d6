//! Prophesee RAW EVT 3.0 encoding (the inverse of [`crate::evt3`]): a `%` header with
//! the geometry, then 16-bit words. Each event costs an `EVT_ADDR_X` word, plus
//! `EVT_ADDR_Y` when the row changes and `EVT_TIME_LOW`/`EVT_TIME_HIGH` when the time does;
//! across long gaps, and from time 0 up to the first event, the high word is repeated every
//! 1024 steps so that a decoder can count the 24-bit clock's loops (a file whose first
//! event lies beyond 51 days is refused). Used to write large test recordings and for `convert --to evt3`.

use super::{OutputPolicy, Staged};
use crate::error::InputError;
use crate::events::{EventChunk, Sensor, TimeUs};
use crate::hint::{Hint, Text};
use std::io::Write;
use std::path::Path;

/// The most steps of 1024 high-word units (4.2 s each) written before the first event: a
/// start up to 51 days after time 0 (2 MB of steps).
const MAX_START_STEPS: u64 = 1 << 20;

/// Writes an EVT3 file.
pub struct Evt3Writer {
    staged: Staged,
    out: std::io::BufWriter<std::fs::File>,
    words: Vec<u8>,
    /// Time in units of 4096 us (the high word including loops) last written.
    high: Option<u64>,
    low: u64,
    y: Option<u16>,
    last_t: TimeUs,
}

impl Evt3Writer {
    pub fn create(
        target: &Path,
        sensor: Sensor,
        policy: &OutputPolicy,
    ) -> Result<Self, InputError> {
        if sensor.width > 2048 || sensor.height > 2048 {
            return Err(InputError::invalid(
                target,
                format!("EVT3 addresses 11 bits; the {sensor} sensor does not fit"),
                "write HDF5 or IJRR instead",
            ));
        }
        let staged = policy.file(target)?;
        let file = std::fs::OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(!staged.in_place)
            .open(&staged.partial)
            .map_err(|e| InputError::write(target, e))?;
        let mut out = std::io::BufWriter::with_capacity(1 << 20, file);
        write!(
            out,
            "% evt 3.0\n% format EVT3;height={h};width={w}\n% geometry {w}x{h}\n% integrator_name ctcal\n% end\n",
            w = sensor.width,
            h = sensor.height
        )
        .map_err(|e| InputError::write(target, e))?;
        Ok(Self {
            staged,
            out,
            words: Vec::with_capacity(1 << 16),
            high: None,
            low: 0,
            y: None,
            last_t: TimeUs::MIN,
        })
    }

    #[inline]
    fn word(&mut self, kind: u16, payload: u16) {
        self.words
            .extend_from_slice(&((kind << 12) | (payload & 0xfff)).to_le_bytes());
    }

    /// Appends time-sorted events with non-negative times.
    pub fn write_events(&mut self, chunk: &EventChunk) -> Result<(), InputError> {
        for i in 0..chunk.len() {
            let t = chunk.t[i];
            if t < 0 || t < self.last_t {
                return Err(InputError::invalid(
                    &self.staged.shown,
                    format!("EVT3 needs non-negative, time-sorted events (event {i} at {t} us)"),
                    Text::from("sort the events first").aside(Hint::Sort),
                ));
            }
            self.last_t = t;
            let (high, low) = ((t as u64) >> 12, (t as u64) & 0xfff);
            if self.high != Some(high) {
                if self.high.is_none() && high / 1024 > MAX_START_STEPS {
                    return Err(InputError::invalid(
                        &self.staged.shown,
                        format!(
                            "the first event is at {t} us ({:.1} days): EVT3 counts time from 0 in loops of its 24-bit clock (16.8 s), and a decoder would need {} words to count up to it",
                            t as f64 / 86_400e6,
                            high / 1024
                        ),
                        "write HDF5 or IJRR, which keep any time, or shift the times to start near 0",
                    ));
                }
                // step through long gaps, and from 0 up to the first event, so a decoder
                // sees every loop of the 12-bit high word (it counts a loop where the word
                // steps back by more than half its range)
                let mut at = self.high.unwrap_or(0);
                while high > at + 1024 {
                    at += 1024;
                    self.word(0x8, (at & 0xfff) as u16);
                }
                self.word(0x8, (high & 0xfff) as u16);
                self.high = Some(high);
                self.word(0x6, low as u16);
                self.low = low;
            } else if self.low != low {
                self.word(0x6, low as u16);
                self.low = low;
            }
            if self.y != Some(chunk.y[i]) {
                self.word(0x0, chunk.y[i]);
                self.y = Some(chunk.y[i]);
            }
            self.word(0x2, ((chunk.on[i] as u16) << 11) | chunk.x[i]);
        }
        self.out
            .write_all(&self.words)
            .map_err(|e| InputError::write(&self.staged.shown, e))?;
        self.words.clear();
        Ok(())
    }

    pub fn finish(mut self) -> Result<(), InputError> {
        self.out
            .flush()
            .map_err(|e| InputError::write(&self.staged.shown, e))?;
        drop(self.out);
        self.staged.commit()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{EventDecoder, evt3::Evt3Decoder, prophesee::PropheseeHeader};

    #[test]
    fn encoding_then_decoding_returns_every_event_across_clock_loops() {
        // 40 s of events with long gaps: the 24-bit clock (16.8 s) loops twice
        let mut events = EventChunk::default();
        let mut t: TimeUs = 5;
        for i in 0..20_000u32 {
            t += match i % 1000 {
                0 => 1_900_000,
                _ => (i % 7) as TimeUs,
            };
            events.push(t, (i * 37 % 1280) as u16, (i / 3 % 720) as u16, i % 3 == 0);
        }
        assert!(t > 2 * (1 << 24));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("synthetic.raw");
        let mut writer =
            Evt3Writer::create(&path, Sensor::new(1280, 720), &OutputPolicy::default()).unwrap();
        writer.write_events(&events).unwrap();
        writer.finish().unwrap();
        let header = PropheseeHeader::read(&path).unwrap();
        assert_eq!(header.sensor().unwrap().unwrap().0, Sensor::new(1280, 720));
        let mut decoder =
            Evt3Decoder::open(&path, header.length, Some(Sensor::new(1280, 720))).unwrap();
        let mut decoded = EventChunk::default();
        loop {
            let before = decoded.len();
            decoder.read_chunk(&mut decoded).unwrap();
            if decoded.len() == before {
                break;
            }
        }
        assert!(decoded == events);
        assert_eq!(decoder.order().backwards, 0);
    }
}
