//! ROS1 bag writing (the inverse of [`crate::bag`]): events as `dvs_msgs/EventArray`
//! messages on `/dvs/events` (a fixed number of events each, stamped with their last
//! event's time, as rpg_dvs_ros publishes), frames as `mono8` `sensor_msgs/Image` messages
//! on `/dvs/image_raw`, in plain, bz2 or LZ4 chunks of about 768 KB (ROS's default) with the
//! index section ROS tools expect (index data after each chunk, then the connections and
//! chunk infos). Used for `convert --to bag`, bag tests and the decoding benchmark.

use super::{OutputPolicy, Staged};
use crate::error::InputError;
use crate::events::{EventChunk, Frame, Sensor, TimeUs};
use crate::hint::{Hint, Text};
use std::collections::BTreeMap;
use std::io::{Seek, SeekFrom, Write};
use std::path::Path;

const EVENTS_TOPIC: &str = "/dvs/events";
const IMAGE_TOPIC: &str = "/dvs/image_raw";
const EVENT_ARRAY_MD5: &str = "5e8beee5a6c107e504c2e78903c224b8";
const IMAGE_MD5: &str = "060021388200f6f0f447d0fcd9c64743";
const EVENT_ARRAY_DEFINITION: &str = "std_msgs/Header header\nuint32 height\nuint32 width\ndvs_msgs/Event[] events\n================================================================================\nMSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n================================================================================\nMSG: dvs_msgs/Event\nuint16 x\nuint16 y\ntime ts\nbool polarity\n";
const IMAGE_DEFINITION: &str = "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data\n================================================================================\nMSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n";
/// Uncompressed bytes after which a chunk is closed.
const CHUNK_BYTES: usize = 768 * 1024;
/// Size of the bag header record, padded (as ROS writes it, so it can be rewritten).
const BAG_HEADER_BYTES: usize = 4096;

/// How chunks are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BagCompression {
    None,
    Bz2,
    /// The LZ4 frame format (what ROS's roslz4 writes).
    Lz4,
}

/// A message's place in the open chunk, for the index.
struct IndexEntry {
    time: TimeUs,
    offset: u32,
}

/// Writes a ROS1 bag.
pub struct BagWriter {
    staged: Staged,
    out: std::io::BufWriter<std::fs::File>,
    sensor: Sensor,
    compression: BagCompression,
    events_per_message: usize,
    chunk_bytes: usize,
    /// Events not yet in a message.
    pending: EventChunk,
    /// The open chunk's records, and per connection its messages.
    chunk: Vec<u8>,
    index: BTreeMap<u32, Vec<IndexEntry>>,
    /// Connections already declared in some chunk.
    declared: [bool; 2],
    /// Chunk infos: position, start and end time, per-connection counts.
    chunks: Vec<(u64, TimeUs, TimeUs, BTreeMap<u32, u32>)>,
    sequence: [u32; 2],
    last_t: TimeUs,
}

fn field(out: &mut Vec<u8>, name: &str, value: &[u8]) {
    out.extend_from_slice(&((name.len() + 1 + value.len()) as u32).to_le_bytes());
    out.extend_from_slice(name.as_bytes());
    out.push(b'=');
    out.extend_from_slice(value);
}

fn record(out: &mut Vec<u8>, header: &[u8], data: &[u8]) {
    out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    out.extend_from_slice(header);
    out.extend_from_slice(&(data.len() as u32).to_le_bytes());
    out.extend_from_slice(data);
}

fn ros_time(t: TimeUs) -> [u8; 8] {
    let sec = (t / 1_000_000) as u32;
    let nsec = ((t % 1_000_000) * 1000) as u32;
    let mut b = [0u8; 8];
    b[..4].copy_from_slice(&sec.to_le_bytes());
    b[4..].copy_from_slice(&nsec.to_le_bytes());
    b
}

/// A connection record (op 7) for connection `id`.
fn connection_record(out: &mut Vec<u8>, id: u32) {
    let (topic, kind, md5, definition) = if id == 0 {
        (
            EVENTS_TOPIC,
            "dvs_msgs/EventArray",
            EVENT_ARRAY_MD5,
            EVENT_ARRAY_DEFINITION,
        )
    } else {
        (
            IMAGE_TOPIC,
            "sensor_msgs/Image",
            IMAGE_MD5,
            IMAGE_DEFINITION,
        )
    };
    let mut header = Vec::new();
    field(&mut header, "op", &[0x07]);
    field(&mut header, "conn", &id.to_le_bytes());
    field(&mut header, "topic", topic.as_bytes());
    let mut data = Vec::new();
    field(&mut data, "topic", topic.as_bytes());
    field(&mut data, "type", kind.as_bytes());
    field(&mut data, "md5sum", md5.as_bytes());
    field(&mut data, "message_definition", definition.as_bytes());
    field(&mut data, "callerid", b"/ctcal");
    field(&mut data, "latching", b"0");
    record(out, &header, &data);
}

/// The bag header record (op 3), padded to [`BAG_HEADER_BYTES`]; its padding carries
/// ctcal's signature, so that ctcal knows the file as its own.
fn bag_header(index_pos: u64, connections: u32, chunks: u32) -> Vec<u8> {
    let mut header = Vec::new();
    field(&mut header, "op", &[0x03]);
    field(&mut header, "index_pos", &index_pos.to_le_bytes());
    field(&mut header, "conn_count", &connections.to_le_bytes());
    field(&mut header, "chunk_count", &chunks.to_le_bytes());
    let mut padding = b"written by ctcal".to_vec();
    padding.resize(BAG_HEADER_BYTES - 8 - header.len(), b' ');
    let mut out = Vec::new();
    record(&mut out, &header, &padding);
    out
}

impl BagWriter {
    pub fn create(
        target: &Path,
        sensor: Sensor,
        compression: BagCompression,
        policy: &OutputPolicy,
    ) -> Result<Self, InputError> {
        let staged = policy.file(target)?;
        if staged.in_place {
            return Err(InputError::invalid(
                target,
                "a bag's header is rewritten when it is finished, which a device or FIFO cannot do",
                "write the bag to a regular file",
            ));
        }
        let file =
            std::fs::File::create(&staged.partial).map_err(|e| InputError::write(target, e))?;
        let mut out = std::io::BufWriter::with_capacity(1 << 20, file);
        out.write_all(crate::bag::records::MAGIC)
            .and_then(|_| out.write_all(&bag_header(0, 0, 0)))
            .map_err(|e| InputError::write(target, e))?;
        Ok(Self {
            staged,
            out,
            sensor,
            compression,
            events_per_message: 4096,
            chunk_bytes: CHUNK_BYTES,
            pending: EventChunk::default(),
            chunk: Vec::with_capacity(CHUNK_BYTES + (1 << 16)),
            index: BTreeMap::new(),
            declared: [false; 2],
            chunks: Vec::new(),
            sequence: [0; 2],
            last_t: 0,
        })
    }

    /// Sets the number of events per message (default 4096).
    pub fn events_per_message(mut self, n: usize) -> Self {
        self.events_per_message = n.max(1);
        self
    }

    /// Sets the uncompressed bytes after which a chunk is closed (default 768 KB).
    pub fn chunk_bytes(mut self, n: usize) -> Self {
        self.chunk_bytes = n.max(1);
        self
    }

    fn check_time(&mut self, t: TimeUs, what: &str) -> Result<(), InputError> {
        if !(0..(1i64 << 32) * 1_000_000).contains(&t) {
            return Err(InputError::invalid(
                &self.staged.shown,
                format!("{what} at {t} us lies outside the times a ROS bag holds (0 to 2^32 s)"),
                "write HDF5 or IJRR instead",
            ));
        }
        Ok(())
    }

    /// Appends a message record of connection `id` to the open chunk.
    fn message(&mut self, id: u32, time: TimeUs, data: &[u8]) -> Result<(), InputError> {
        if !self.declared[id as usize] {
            connection_record(&mut self.chunk, id);
            self.declared[id as usize] = true;
        }
        let offset = self.chunk.len() as u32;
        let mut header = Vec::new();
        field(&mut header, "op", &[0x02]);
        field(&mut header, "conn", &id.to_le_bytes());
        field(&mut header, "time", &ros_time(time));
        record(&mut self.chunk, &header, data);
        self.index
            .entry(id)
            .or_default()
            .push(IndexEntry { time, offset });
        if self.chunk.len() >= self.chunk_bytes {
            self.close_chunk()?;
        }
        Ok(())
    }

    /// A std_msgs/Header.
    fn header(&mut self, id: usize, stamp: TimeUs, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.sequence[id].to_le_bytes());
        self.sequence[id] += 1;
        out.extend_from_slice(&ros_time(stamp));
        out.extend_from_slice(&0u32.to_le_bytes());
    }

    /// Writes the first `n` pending events as one EventArray message.
    fn flush_events(&mut self, n: usize) -> Result<(), InputError> {
        if n == 0 {
            return Ok(());
        }
        let stamp = self.pending.t[n - 1];
        let mut data = Vec::with_capacity(32 + 13 * n);
        self.header(0, stamp, &mut data);
        data.extend_from_slice(&(self.sensor.height as u32).to_le_bytes());
        data.extend_from_slice(&(self.sensor.width as u32).to_le_bytes());
        data.extend_from_slice(&(n as u32).to_le_bytes());
        for i in 0..n {
            data.extend_from_slice(&self.pending.x[i].to_le_bytes());
            data.extend_from_slice(&self.pending.y[i].to_le_bytes());
            data.extend_from_slice(&ros_time(self.pending.t[i]));
            data.push(self.pending.on[i] as u8);
        }
        self.pending.t.drain(..n);
        self.pending.x.drain(..n);
        self.pending.y.drain(..n);
        self.pending.on.drain(..n);
        self.message(0, stamp, &data)
    }

    /// Appends time-sorted events.
    pub fn write_events(&mut self, chunk: &EventChunk) -> Result<(), InputError> {
        for i in 0..chunk.len() {
            let t = chunk.t[i];
            self.check_time(t, &format!("event {i}"))?;
            if t < self.last_t {
                return Err(InputError::invalid(
                    &self.staged.shown,
                    format!("events must be time-sorted (event {i} at {t} us)"),
                    Text::from("sort the events first").aside(Hint::Sort),
                ));
            }
            self.last_t = t;
            self.pending.push(t, chunk.x[i], chunk.y[i], chunk.on[i]);
            if self.pending.len() == self.events_per_message {
                self.flush_events(self.events_per_message)?;
            }
        }
        Ok(())
    }

    /// Writes `events` as one EventArray message, exactly as given (after the events
    /// written so far): bags may hold messages that overlap in time, and readers must merge
    /// them.
    pub fn write_message(&mut self, events: &EventChunk) -> Result<(), InputError> {
        let n = self.pending.len();
        self.flush_events(n)?;
        for i in 0..events.len() {
            self.check_time(events.t[i], &format!("event {i}"))?;
        }
        self.pending.extend_from(events);
        self.last_t = self.last_t.max(events.t.iter().copied().max().unwrap_or(0));
        self.flush_events(events.len())
    }

    /// Appends a grey frame (pending events up to its time are written first).
    pub fn write_frame(&mut self, frame: &Frame) -> Result<(), InputError> {
        self.check_time(frame.t, "a frame")?;
        let before = self.pending.t.partition_point(|&t| t <= frame.t);
        self.flush_events(before)?;
        let mut data = Vec::with_capacity(64 + frame.pixels.len());
        self.header(1, frame.t, &mut data);
        data.extend_from_slice(&frame.height.to_le_bytes());
        data.extend_from_slice(&frame.width.to_le_bytes());
        data.extend_from_slice(&5u32.to_le_bytes());
        data.extend_from_slice(b"mono8");
        data.push(0);
        data.extend_from_slice(&frame.width.to_le_bytes());
        data.extend_from_slice(&(frame.pixels.len() as u32).to_le_bytes());
        data.extend_from_slice(&frame.pixels);
        self.message(1, frame.t, &data)
    }

    /// Writes the open chunk and its index data.
    fn close_chunk(&mut self) -> Result<(), InputError> {
        if self.chunk.is_empty() {
            return Ok(());
        }
        let position = self
            .out
            .stream_position()
            .map_err(|e| InputError::write(&self.staged.shown, e))?;
        let data = self.compressed_chunk()?;
        let mut out = self.chunk_record(&data);
        let (start, end, counts) = self.append_index_data(&mut out);
        self.out
            .write_all(&out)
            .map_err(|e| InputError::write(&self.staged.shown, e))?;
        self.chunks.push((position, start, end, counts));
        self.chunk.clear();
        self.index.clear();
        Ok(())
    }

    /// The open chunk's records, compressed as set (uncompressed: taken from the chunk).
    fn compressed_chunk(&mut self) -> Result<Vec<u8>, InputError> {
        Ok(match self.compression {
            BagCompression::None => std::mem::take(&mut self.chunk),
            BagCompression::Bz2 => {
                let mut encoder =
                    bzip2::write::BzEncoder::new(Vec::new(), bzip2::Compression::default());
                encoder
                    .write_all(&self.chunk)
                    .and_then(|_| encoder.finish())
                    .map_err(|e| InputError::write(&self.staged.shown, e))?
            }
            BagCompression::Lz4 => {
                let mut encoder = lz4_flex::frame::FrameEncoder::new(Vec::new());
                encoder
                    .write_all(&self.chunk)
                    .map_err(|e| InputError::write(&self.staged.shown, e))?;
                encoder
                    .finish()
                    .map_err(|e| InputError::write(&self.staged.shown, std::io::Error::other(e)))?
            }
        })
    }

    /// The chunk record (op 5) holding `data`, the open chunk's records as compressed.
    fn chunk_record(&self, data: &[u8]) -> Vec<u8> {
        let uncompressed = if self.compression == BagCompression::None {
            data.len()
        } else {
            self.chunk.len()
        };
        let mut header = Vec::new();
        field(&mut header, "op", &[0x05]);
        field(
            &mut header,
            "compression",
            match self.compression {
                BagCompression::None => b"none",
                BagCompression::Bz2 => b"bz2",
                BagCompression::Lz4 => b"lz4",
            },
        );
        field(&mut header, "size", &(uncompressed as u32).to_le_bytes());
        let mut out = Vec::with_capacity(data.len() + 1024);
        record(&mut out, &header, data);
        out
    }

    /// Appends an index data record (op 4) per connection; the chunk's time span and counts.
    fn append_index_data(&self, out: &mut Vec<u8>) -> (TimeUs, TimeUs, BTreeMap<u32, u32>) {
        let (mut start, mut end) = (TimeUs::MAX, TimeUs::MIN);
        let mut counts = BTreeMap::new();
        for (&id, entries) in &self.index {
            let mut header = Vec::new();
            field(&mut header, "op", &[0x04]);
            field(&mut header, "ver", &1u32.to_le_bytes());
            field(&mut header, "conn", &id.to_le_bytes());
            field(&mut header, "count", &(entries.len() as u32).to_le_bytes());
            let mut body = Vec::with_capacity(12 * entries.len());
            for e in entries {
                body.extend_from_slice(&ros_time(e.time));
                body.extend_from_slice(&e.offset.to_le_bytes());
                start = start.min(e.time);
                end = end.max(e.time);
            }
            record(out, &header, &body);
            counts.insert(id, entries.len() as u32);
        }
        (start, end, counts)
    }

    /// Writes the rest, the index section and the final bag header, and moves the bag into
    /// place.
    pub fn finish(mut self) -> Result<(), InputError> {
        let n = self.pending.len();
        self.flush_events(n)?;
        self.close_chunk()?;
        let shown = self.staged.shown.clone();
        let index_pos = self
            .out
            .stream_position()
            .map_err(|e| InputError::write(&shown, e))?;
        let mut out = Vec::new();
        let connections: Vec<u32> = (0..2u32).filter(|&id| self.declared[id as usize]).collect();
        for &id in &connections {
            connection_record(&mut out, id);
        }
        for (position, start, end, counts) in &self.chunks {
            let mut header = Vec::new();
            field(&mut header, "op", &[0x06]);
            field(&mut header, "ver", &1u32.to_le_bytes());
            field(&mut header, "chunk_pos", &position.to_le_bytes());
            field(&mut header, "start_time", &ros_time(*start));
            field(&mut header, "end_time", &ros_time(*end));
            field(&mut header, "count", &(counts.len() as u32).to_le_bytes());
            let mut body = Vec::new();
            for (id, count) in counts {
                body.extend_from_slice(&id.to_le_bytes());
                body.extend_from_slice(&count.to_le_bytes());
            }
            record(&mut out, &header, &body);
        }
        let header = bag_header(
            index_pos,
            connections.len() as u32,
            self.chunks.len() as u32,
        );
        self.out
            .write_all(&out)
            .and_then(|_| {
                self.out
                    .seek(SeekFrom::Start(crate::bag::records::MAGIC.len() as u64))
            })
            .and_then(|_| self.out.write_all(&header))
            .and_then(|_| self.out.flush())
            .map_err(|e| InputError::write(&shown, e))?;
        drop(self.out);
        self.staged.commit()
    }
}
