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
//!
//! **Fast path.** Recordings are mostly `ADDR_Y`, `ADDR_X` and `TIME_LOW` words in an order
//! that follows the scene (a new time before some events, not others), so a `match` per word
//! mispredicts about once an event. A block of words (what `read_chunk` reads at once) is
//! therefore decoded optimistically first (`Position::run`), without checks and without a
//! branch on those words' type: each word writes an event at the chunk's next slot (the
//! time, the raw word as x, y) and only an `ADDR_X` word advances past it; y and the time
//! are selected, not branched on. Vector words and a `TIME_HIGH` that changes the time go
//! out of line (`Rare::word`). One pass then splits x and the polarity, and the block's
//! events are checked at once (`State::all_valid`: the largest x and y inside the sensor,
//! times in order from the previous block's last). Only if a check fails (or the block
//! starts before the first `TIME_HIGH`, the clock nears [`TIME_LIMIT_US`], or a vector
//! reaches beyond x 2047) is the block decoded again from its saved position by the plain
//! decoder (`State::decode`), which checks each event as it is made and so gives the same
//! errors and order records, naming the byte offset of the word. Measured in
//! `benches/README.md` ("EVT3 decoding without a branch per word"): 11.4 -> 6.0 ns/event.

use super::blocks::BlockReader;
use super::error::InputError;
use super::order::OrderCheck;
use super::{EventDecoder, Progress};
use crate::events::{CHUNK_EVENTS, EventChunk, MAX_SENSOR_SIDE, Sensor, TIME_LIMIT_US, TimeUs};
use std::mem::MaybeUninit;
use std::path::{Path, PathBuf};

/// Word types that leave the fast path's branch-free step: `VECT_BASE_X`, `VECT_12`,
/// `VECT_8` (a `TIME_HIGH` leaves it only when it changes the time).
const VECTOR_KINDS: u16 = 1 << 0x3 | 1 << 0x4 | 1 << 0x5;

/// While `loops` stays below this, every time of the clock lies within [`TIME_LIMIT_US`].
const SAFE_LOOPS: u64 = TIME_LIMIT_US as u64 >> 24;

/// Streaming EVT3 decoder.
pub struct Evt3Decoder {
    reader: BlockReader,
    state: State,
}

struct State {
    path: PathBuf,
    sensor: Option<Sensor>,
    order: OrderCheck,
    at: Position,
}

/// What the words decoded so far leave for the next: the clock, the position and the
/// polarity (a copy is kept to decode a block again).
#[derive(Clone, Copy)]
struct Position {
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
            state: State::new(path, sensor),
        })
    }
}

impl State {
    fn new(path: &Path, sensor: Option<Sensor>) -> Self {
        Self {
            path: path.to_path_buf(),
            sensor,
            order: OrderCheck::default(),
            at: Position {
                time_high: 0,
                time_low: 0,
                loops: 0,
                seen_time_high: false,
                x: 0,
                y: 0,
                on: false,
            },
        }
    }
}

impl Position {
    #[inline(always)]
    fn time(&self) -> i64 {
        ((self.loops << 24) | (self.time_high << 12) | self.time_low) as i64
    }

    /// A `TIME_HIGH` word's high 12 bits: counts a loop when they step back by more than
    /// half their range.
    #[inline]
    fn time_high(&mut self, high: u64) {
        if self.seen_time_high && high < self.time_high && self.time_high - high > 2048 {
            self.loops += 1;
        }
        if high != self.time_high || !self.seen_time_high {
            self.time_low = 0;
        }
        self.time_high = high;
        self.seen_time_high = true;
    }

    /// Decodes `words` into `out` without checking the events (the fast path; see the
    /// module documentation): the number of events, or `None` when it had to stop (the
    /// clock neared [`TIME_LIMIT_US`], or a vector reached beyond x 2047; then the block
    /// must be decoded again the plain way).
    fn run(&mut self, words: &[u8], mut out: Sink) -> Option<usize> {
        let (mut t, mut y, mut n) = (self.time(), self.y, 0);
        let mut high_word = 0x8000 | self.time_high as u16;
        let known = (0, self.on);
        let mut rare = Rare {
            at: self,
            words,
            known,
        };
        // the `i`-th word: without a branch on its type for `ADDR_Y`, `ADDR_X`, `TIME_LOW`,
        // an unchanged `TIME_HIGH` and the types without events; `Rare::word` for the rest
        // (a macro, not a closure: the locals must stay in registers)
        macro_rules! step {
            ($word:expr, $i:expr) => {{
                let word: u16 = $word;
                let kind = word >> 12;
                out.write(n, t, word, y);
                if ((VECTOR_KINDS >> kind) & 1 != 0) | ((kind == 0x8) & (word != high_word)) {
                    (t, high_word, n) = rare.word(word, $i, (t, y, n), out.reborrow())?;
                } else {
                    y = if kind == 0x0 { word & 0x7ff } else { y };
                    let t_low = (t & !0xfff) | (word & 0xfff) as TimeUs;
                    t = if kind == 0x6 { t_low } else { t };
                    n += (kind == 0x2) as usize;
                }
            }};
        }
        let quads = words.chunks_exact(8);
        let rest = quads.remainder();
        for (q, bytes) in quads.enumerate() {
            let quad = u64::from_le_bytes(bytes.try_into().expect("8 bytes"));
            for k in 0..4 {
                step!((quad >> (16 * k)) as u16, 4 * q + k);
            }
        }
        let done = words.len() / 2 - rest.len() / 2;
        for (k, bytes) in rest.chunks_exact(2).enumerate() {
            step!(u16::from_le_bytes([bytes[0], bytes[1]]), done + k);
        }
        let (from, before) = rare.known;
        (self.time_low, self.y) = ((t & 0xfff) as u64, y);
        self.on = polarity(&words[from..], before);
        Some(n)
    }

    /// A `VECT_BASE_X`, `VECT_12` or `VECT_8` word on the fast path: its events unchecked
    /// from slot `n` on, each x with its polarity in bit 11 as an `ADDR_X` word has them;
    /// the number of events after them (`None` if an x does not fit in 11 bits).
    fn vector(&mut self, word: u16, mut n: usize, out: &mut Sink) -> Option<usize> {
        let kind = word >> 12;
        if kind == 0x3 {
            self.x = word & 0x7ff;
            self.on = word & 0x800 != 0;
            return Some(n);
        }
        let width = if kind == 0x4 { 12 } else { 8 };
        let mut bits = word & ((1u16 << width) - 1);
        let t = self.time();
        let on = (self.on as u16) << 11;
        while bits != 0 {
            let x = self.x.wrapping_add(bits.trailing_zeros() as u16);
            if x > 0x7ff {
                return None;
            }
            out.write(n, t, x | on, self.y);
            n += 1;
            bits &= bits - 1;
        }
        self.x = self.x.wrapping_add(width);
        Some(n)
    }
}

/// What the fast path's rare words need besides its registers: the decoder's position, the
/// block, and where in it the polarity was last known (bytes up to there, and its value;
/// the fast path does not carry it from word to word).
struct Rare<'a> {
    at: &'a mut Position,
    words: &'a [u8],
    known: (usize, bool),
}

impl Rare<'_> {
    /// The `i`-th word, a vector word or a `TIME_HIGH` that changes the time, given the
    /// fast path's time, y and event count; its new time, `TIME_HIGH` word and count.
    #[inline(never)]
    fn word(
        &mut self,
        word: u16,
        i: usize,
        (t, y, n): (TimeUs, u16, usize),
        mut out: Sink,
    ) -> Option<(TimeUs, u16, usize)> {
        let at = &mut *self.at;
        (at.time_low, at.y) = ((t & 0xfff) as u64, y);
        if word >> 12 == 0x8 {
            at.time_high((word & 0xfff) as u64);
            return (at.loops < SAFE_LOOPS).then_some((at.time(), word, n));
        }
        at.on = polarity(&self.words[self.known.0..2 * i], self.known.1);
        let n = at.vector(word, n, &mut out)?;
        self.known = (2 * i + 2, at.on);
        Some((t, 0x8000 | at.time_high as u16, n))
    }
}

/// The polarity after `words`: that of the last `ADDR_X` or `VECT_BASE_X` word among them,
/// else `before`.
fn polarity(words: &[u8], before: bool) -> bool {
    words
        .chunks_exact(2)
        .rev()
        .find(|bytes| matches!(bytes[1] >> 4, 0x2 | 0x3))
        .map_or(before, |bytes| bytes[1] & 0x08 != 0)
}

/// The chunk's unwritten tail, written by index (all three of one length). x holds the
/// `ADDR_X` word's 12 low bits: x and the polarity in bit 11.
struct Sink<'a> {
    t: &'a mut [MaybeUninit<TimeUs>],
    x: &'a mut [MaybeUninit<u16>],
    y: &'a mut [MaybeUninit<u16>],
}

impl Sink<'_> {
    /// Writes an event at slot `n`.
    #[inline(always)]
    fn write(&mut self, n: usize, t: TimeUs, x_on: u16, y: u16) {
        self.t[n].write(t);
        self.x[n].write(x_on);
        self.y[n].write(y);
    }

    /// The same slices, passed by value (so that the caller's stay in registers).
    fn reborrow(&mut self) -> Sink<'_> {
        Sink {
            t: self.t,
            x: self.x,
            y: self.y,
        }
    }
}

/// Decodes `words` onto the end of `out` with [`Position::run`] (`false` when it stopped),
/// then splits x and the polarity.
fn run_into(at: &mut Position, words: &[u8], out: &mut EventChunk) -> bool {
    // a vector word emits at most 12 events (and the last word's write is at most at slot
    // 12 * (words - 1))
    let most = 12 * (words.len() / 2);
    let len = out.len();
    out.t.reserve(most);
    out.x.reserve(most);
    out.y.reserve(most);
    let sink = Sink {
        t: &mut out.t.spare_capacity_mut()[..most],
        x: &mut out.x.spare_capacity_mut()[..most],
        y: &mut out.y.spare_capacity_mut()[..most],
    };
    let Some(n) = at.run(words, sink) else {
        return false;
    };
    // SAFETY: the fast path wrote slot `n` of the sink before it counted an event there,
    // so the `n` elements after `len` are initialised, and they lie within the capacity
    // reserved.
    unsafe {
        out.t.set_len(len + n);
        out.x.set_len(len + n);
        out.y.set_len(len + n);
    }
    let x_on = &mut out.x[len..];
    out.on.extend(x_on.iter().map(|&x| x & 0x800 != 0));
    x_on.iter_mut().for_each(|x| *x &= 0x7ff);
    true
}

impl State {
    #[inline(always)]
    fn emit(&mut self, x: u16, offset: u64, out: &mut EventChunk) -> Result<(), InputError> {
        if !self.at.seen_time_high {
            return Ok(());
        }
        if !super::within(self.sensor, x as u32, self.at.y as u32) {
            return Err(super::outside_sensor(
                &self.path,
                format!("byte offset {offset}"),
                x as i64,
                self.at.y as i64,
                self.sensor,
            ));
        }
        let t = self.at.time();
        self.order.check(t, || format!("byte offset {offset}"));
        out.push(t, x, self.at.y, self.at.on);
        Ok(())
    }

    /// The plain decoder of one word, checking each event.
    #[inline]
    fn decode(&mut self, word: u16, offset: u64, out: &mut EventChunk) -> Result<(), InputError> {
        match word >> 12 {
            0x0 => self.at.y = word & 0x7ff,
            0x2 => {
                self.at.on = word & 0x800 != 0;
                self.emit(word & 0x7ff, offset, out)?;
            }
            0x3 => {
                self.at.x = word & 0x7ff;
                self.at.on = word & 0x800 != 0;
            }
            kind @ (0x4 | 0x5) => {
                let width = if kind == 0x4 { 12 } else { 8 };
                let mut bits = word & ((1u16 << width) - 1);
                while bits != 0 {
                    let bit = bits.trailing_zeros() as u16;
                    self.emit(self.at.x.wrapping_add(bit), offset, out)?;
                    bits &= bits - 1;
                }
                self.at.x = self.at.x.wrapping_add(width);
            }
            0x6 => self.at.time_low = (word & 0xfff) as u64,
            0x8 => self.at.time_high((word & 0xfff) as u64),
            _ => {}
        }
        Ok(())
    }

    /// Whether the events from `start` on pass every check of [`Self::emit`]: inside the
    /// sensor, and times in order from the last checked one (within [`TIME_LIMIT_US`] as
    /// the fast path ran only below [`SAFE_LOOPS`]).
    fn all_valid(&self, out: &EventChunk, start: usize) -> bool {
        let Some(&first) = out.t.get(start) else {
            return true;
        };
        let (width, height) = self
            .sensor
            .map_or((MAX_SENSOR_SIDE, MAX_SENSOR_SIDE), |s| (s.width, s.height));
        let max_x = out.x[start..].iter().fold(0, |m, &x| m.max(x));
        let max_y = out.y[start..].iter().fold(0, |m, &y| m.max(y));
        let t = &out.t[start..];
        let sorted = t.windows(2).fold(true, |ok, w| ok & (w[0] <= w[1]));
        max_x < width && max_y < height && first >= self.order.last() && sorted
    }

    /// Decodes `words` (read from file offset `base`) onto the end of `out`: the fast path,
    /// and again the plain way if it cannot vouch for the events.
    fn decode_words(
        &mut self,
        words: &[u8],
        base: u64,
        out: &mut EventChunk,
    ) -> Result<(), InputError> {
        let start = out.len();
        if self.at.seen_time_high && self.at.loops < SAFE_LOOPS {
            let saved = self.at;
            if run_into(&mut self.at, words, out) && self.all_valid(out, start) {
                if let Some(&t) = out.t.last().filter(|_| out.len() > start) {
                    self.order.skip_checked(t);
                }
                return Ok(());
            }
            self.at = saved;
            out.t.truncate(start);
            out.x.truncate(start);
            out.y.truncate(start);
            out.on.truncate(start);
        }
        for (i, bytes) in words.chunks_exact(2).enumerate() {
            let word = u16::from_le_bytes([bytes[0], bytes[1]]);
            self.decode(word, base + 2 * i as u64, out)?;
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
            self.state.decode_words(words, base, out)?;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A random stream of every word type (xorshift, seeded): times mostly rising, now and
    /// then stepping back or looping; x and y inside 640x480 but for one word in
    /// `outside_odds` (and vectors far from their base); vectors with and without a base;
    /// the types without events.
    fn random_words(seed: u64, count: usize, outside_odds: u64) -> Vec<u8> {
        let mut state = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
        let mut next = move |below: u64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % below) as u16
        };
        let (mut high, mut low) = (next(4096), 0);
        let mut words = Vec::with_capacity(count);
        if next(8) != 0 {
            words.push(0x8000 | high);
        }
        while words.len() < count {
            let wide = next(outside_odds) == 0;
            let word = match next(100) {
                0..20 => next(if wide { 2048 } else { 480 }),
                20..45 => 0x2000 | next(2) << 11 | next(if wide { 2048 } else { 640 }),
                45..50 => 0x3000 | next(2) << 11 | next(if wide { 2048 } else { 560 }),
                50..55 => 0x4000 | next(4096),
                55..58 => 0x5000 | next(256),
                58..80 => {
                    low = if next(100) == 0 {
                        next(4096)
                    } else {
                        (low + next(3)).min(4095)
                    };
                    0x6000 | low
                }
                80..90 => {
                    high = match next(40) {
                        0 => next(4096),
                        1..8 => (high + 1) % 4096,
                        _ => high,
                    };
                    0x8000 | high
                }
                _ => {
                    [0x1, 0x7, 0x9, 0xa, 0xb, 0xc, 0xd, 0xe, 0xf][next(9) as usize] << 12
                        | next(4096)
                }
            };
            words.push(word);
        }
        words.iter().flat_map(|w| w.to_le_bytes()).collect()
    }

    /// Decodes `bytes` in blocks as `read_chunk` does, each block by `decode_block`; the
    /// events, the order record and the error, if any.
    fn decode_all(
        sensor: Option<Sensor>,
        bytes: &[u8],
        decode_block: impl Fn(&mut State, &[u8], u64, &mut EventChunk) -> Result<(), InputError>,
    ) -> (EventChunk, String, Option<String>) {
        let mut state = State::new(Path::new("random.raw"), sensor);
        let mut out = EventChunk::default();
        let mut error = None;
        for (b, block) in bytes.chunks(1234).enumerate() {
            if let Err(e) = decode_block(&mut state, block, 1234 * b as u64, &mut out) {
                error = Some(format!("{e:?}"));
                break;
            }
        }
        let order = &state.order;
        let record = format!(
            "{:?} {:?} {:?}",
            order.backwards, order.first, order.out_of_range
        );
        (out, record, error)
    }

    #[test]
    fn the_fast_path_decodes_as_the_plain_decoder() {
        let plain = |state: &mut State, block: &[u8], base: u64, out: &mut EventChunk| {
            for (i, bytes) in block.chunks_exact(2).enumerate() {
                let word = u16::from_le_bytes([bytes[0], bytes[1]]);
                state.decode(word, base + 2 * i as u64, out)?;
            }
            Ok(())
        };
        let (mut errors, mut in_order) = (0, 0);
        for seed in 0..300 {
            let bytes = random_words(seed, 20_000, [100, 10_000, 1 << 40][seed as usize % 3]);
            for sensor in [Some(Sensor::new(640, 480)), None] {
                let fast = decode_all(sensor, &bytes, State::decode_words);
                let slow = decode_all(sensor, &bytes, plain);
                assert_eq!(fast.2, slow.2, "error, seed {seed}");
                assert_eq!(fast.1, slow.1, "order record, seed {seed}");
                if fast.2.is_none() {
                    assert_eq!(fast.0, slow.0, "events, seed {seed}");
                }
                errors += fast.2.is_some() as usize;
                in_order += fast.1.starts_with('0') as usize;
            }
        }
        // both outcomes are exercised
        assert!((100..500).contains(&errors), "{errors} of 600 streams fail");
        assert!(
            (50..550).contains(&in_order),
            "{in_order} of 600 streams in order"
        );
    }
}
