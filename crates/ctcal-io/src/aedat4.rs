//! AEDAT 4.0 (iniVation DV): `#!AER-DAT4.0\r\n`, a u32 length and an `IOHeader` FlatBuffer
//! (compression, position of the file data table, and an XML description naming each
//! stream: `typeIdentifier` EVTS / FRME / IMUS / TRIG and `sizeX`/`sizeY`), then packets:
//! i32 stream id, i32 byte size, and a (LZ4-frame or Zstandard compressed) size-prefixed
//! FlatBuffer. Event packets hold a vector of 16-byte structs `{t: i64, x: i16, y: i16,
//! on: bool}`; frame packets a `Frame` table. IMU and trigger packets are skipped unread.
//!
//! Schemas: iniVation dv-processing (`events.fbs`, `frame.fbs`, `io_header.fbs`). The tables
//! are read with the maintained `flatbuffers` crate (every buffer verified before use); the
//! three accessors below stand in for `flatc` output because ctcal reads only a few fields.

use super::error::{FIX_TRUNCATED, InputError};
use super::order::OrderCheck;
use super::{EventDecoder, Progress};
use crate::events::{CHUNK_EVENTS, EventChunk, Frame, Sensor, TimeUs};
use flatbuffers::{Follow, ForwardsUOffset, Table, Vector, Verifiable, Verifier};
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

const MAGIC: &[u8] = b"#!AER-DAT4.0\r\n";

/// Whether `head` starts like an AEDAT4 file.
pub fn has_magic(head: &[u8]) -> bool {
    head.starts_with(MAGIC)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Compression {
    None,
    Lz4,
    Zstd,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum StreamKind {
    Events,
    Frames,
    Other,
}

#[derive(Clone, Debug)]
struct Stream {
    id: i32,
    kind: StreamKind,
    /// `sizeX`/`sizeY`: `None` where not stated, else the sensor or why they give none.
    size: Option<Result<Sensor, String>>,
}

/// What the header of an AEDAT4 file says.
#[derive(Clone, Debug)]
pub struct Aedat4Header {
    compression: Compression,
    data_start: u64,
    data_end: Option<u64>,
    streams: Vec<Stream>,
    /// The camera named in the description (`source`), if any.
    pub source: Option<String>,
}

impl Aedat4Header {
    /// The event stream's sensor size.
    pub fn event_sensor(&self) -> Option<Sensor> {
        self.event_size()?.clone().ok()
    }

    /// What the event stream's `sizeX`/`sizeY` state where they give no sensor size, and
    /// why.
    pub fn unusable_event_size(&self) -> Option<String> {
        self.event_size()?.clone().err()
    }

    fn event_size(&self) -> Option<&Result<Sensor, String>> {
        self.streams
            .iter()
            .find(|s| s.kind == StreamKind::Events)
            .and_then(|s| s.size.as_ref())
    }

    fn event_stream(&self) -> Option<i32> {
        self.streams
            .iter()
            .find(|s| s.kind == StreamKind::Events)
            .map(|s| s.id)
    }

    fn frame_stream(&self) -> Option<i32> {
        self.streams
            .iter()
            .find(|s| s.kind == StreamKind::Frames)
            .map(|s| s.id)
    }

    /// Reads and checks the header of `path`.
    pub fn read(path: &Path) -> Result<Self, InputError> {
        let buffer = read_io_header_bytes(path)?;
        let length = buffer.len();
        let header = flatbuffers::root::<IoHeader>(&buffer).map_err(|e| {
            InputError::corrupt(
                path,
                "byte offset 18 (IOHeader)",
                format!(
                    "the IOHeader is no valid FlatBuffer table ({})",
                    first_line(&e)
                ),
                FIX_TRUNCATED,
            )
        })?;
        let compression = compression_of(path, header.compression())?;
        let description = header.description().unwrap_or_default();
        let (streams, source) = parse_description(description).map_err(|problem| {
            InputError::corrupt(
                path,
                "the XML stream description in the header",
                problem,
                FIX_TRUNCATED,
            )
        })?;
        let data_end = u64::try_from(header.data_table_position()).ok();
        Ok(Self {
            compression,
            data_start: 18 + length as u64,
            data_end,
            streams,
            source,
        })
    }
}

/// The IOHeader's bytes, after checking the magic line and that the file holds them.
fn read_io_header_bytes(path: &Path) -> Result<Vec<u8>, InputError> {
    let mut file = std::fs::File::open(path).map_err(|e| InputError::io(path, e))?;
    let mut magic = [0u8; 14];
    read_exact(&mut file, &mut magic, path, 0, "the AEDAT4 magic line")?;
    if magic != MAGIC {
        return Err(InputError::corrupt(
            path,
            "byte offset 0",
            "the file does not start with #!AER-DAT4.0",
            "this is not an AEDAT 4.0 file; AEDAT 2/3 files must be converted with DV first",
        ));
    }
    let mut length = [0u8; 4];
    read_exact(&mut file, &mut length, path, 14, "the header length")?;
    let length = u32::from_le_bytes(length) as usize;
    let file_size = file.metadata().map_err(|e| InputError::io(path, e))?.len();
    if 18 + length as u64 > file_size {
        return Err(InputError::corrupt(
            path,
            "byte offset 14",
            format!("the header claims {length} bytes, more than the {file_size}-byte file holds"),
            FIX_TRUNCATED,
        ));
    }
    let mut buffer = vec![0u8; length];
    read_exact(&mut file, &mut buffer, path, 18, "the IOHeader")?;
    Ok(buffer)
}

/// The packets' compression from the IOHeader's code (an error for an unknown code).
fn compression_of(path: &Path, code: i32) -> Result<Compression, InputError> {
    match code {
        0 => Ok(Compression::None),
        1 | 2 => Ok(Compression::Lz4),
        3 | 4 => Ok(Compression::Zstd),
        other => Err(InputError::corrupt(
            path,
            "byte offset 18 (IOHeader)",
            format!("unknown compression code {other}"),
            "re-export the recording from DV with LZ4, Zstd or no compression",
        )),
    }
}

fn read_exact(
    file: &mut impl Read,
    buffer: &mut [u8],
    path: &Path,
    offset: u64,
    what: &str,
) -> Result<(), InputError> {
    file.read_exact(buffer).map_err(|e| {
        if e.kind() == std::io::ErrorKind::UnexpectedEof {
            InputError::corrupt(
                path,
                format!("byte offset {offset}"),
                format!("the file ends inside {what}"),
                FIX_TRUNCATED,
            )
        } else {
            InputError::io(path, e)
        }
    })
}

/// Streams (id, kind, size) and the camera name from the DV XML description.
fn parse_description(xml: &str) -> Result<(Vec<Stream>, Option<String>), String> {
    let document = roxmltree::Document::parse(xml).map_err(|e| format!("unreadable XML: {e}"))?;
    let out_info = document
        .descendants()
        .find(|n| n.has_tag_name("node") && n.attribute("name") == Some("outInfo"))
        .ok_or("no outInfo node")?;
    let attr = |node: roxmltree::Node, key: &str| -> Option<String> {
        node.children()
            .find(|c| c.has_tag_name("attr") && c.attribute("key") == Some(key))
            .and_then(|c| c.text())
            .map(|t| t.trim().to_string())
    };
    let mut streams = Vec::new();
    let mut source = None;
    for node in out_info.children().filter(|n| n.has_tag_name("node")) {
        let Some(id) = node.attribute("name").and_then(|n| n.parse::<i32>().ok()) else {
            continue;
        };
        let kind = match attr(node, "typeIdentifier").as_deref() {
            Some("EVTS") => StreamKind::Events,
            Some("FRME") => StreamKind::Frames,
            _ => StreamKind::Other,
        };
        let info = node
            .children()
            .find(|c| c.has_tag_name("node") && c.attribute("name") == Some("info"));
        let size = info.and_then(|info| stated_size(attr(info, "sizeX")?, attr(info, "sizeY")?));
        if source.is_none() {
            source = info.and_then(|info| attr(info, "source"));
        }
        streams.push(Stream { id, kind, size });
    }
    if !streams.iter().any(|s| s.kind == StreamKind::Events) {
        return Err("the description names no event (EVTS) stream".into());
    }
    Ok((streams, source))
}

/// A stream's `sizeX`/`sizeY` as a sensor, or what they state and why it is none.
fn stated_size(x: String, y: String) -> Option<Result<Sensor, String>> {
    let side = super::prophesee::side;
    Some(match (side(&x), side(&y)) {
        (Ok(w), Ok(h)) => Ok(Sensor::new(w, h)),
        (Err(why), _) | (_, Err(why)) => Err(format!(
            "sizeX/sizeY of the event stream in the AEDAT4 header state {x}x{y}, which is no sensor size ({why})"
        )),
    })
}

/// The most bytes one packet may decompress to (DV writes packets of a few MB at most).
const MAX_PACKET_BYTES: u64 = 256 << 20;

/// Decompresses `raw` onto `decoded`, stopping one byte beyond [`MAX_PACKET_BYTES`].
fn decompress(compression: Compression, raw: &[u8], decoded: &mut Vec<u8>) -> std::io::Result<()> {
    let limit = MAX_PACKET_BYTES + 1;
    match compression {
        Compression::None => {
            decoded.extend_from_slice(raw);
            Ok(())
        }
        Compression::Lz4 => lz4_flex::frame::FrameDecoder::new(raw)
            .take(limit)
            .read_to_end(decoded)
            .map(|_| ()),
        Compression::Zstd => zstd::stream::read::Decoder::new(raw)
            .and_then(|d| d.take(limit).read_to_end(decoded))
            .map(|_| ()),
    }
}

/// Reads packets one at a time, decompressing those of one stream.
struct PacketReader {
    path: PathBuf,
    file: BufReader<std::fs::File>,
    position: u64,
    end: u64,
    compression: Compression,
    raw: Vec<u8>,
    decoded: Vec<u8>,
    /// Packets passed so far (every stream's).
    count: u64,
    /// The packet in `decoded`: its index among the file's packets, byte offset and stream.
    current: (u64, u64, i32),
}

impl PacketReader {
    fn open(path: &Path, header: &Aedat4Header) -> Result<Self, InputError> {
        let mut file = std::fs::File::open(path).map_err(|e| InputError::io(path, e))?;
        let length = file.metadata().map_err(|e| InputError::io(path, e))?.len();
        file.seek(SeekFrom::Start(header.data_start))
            .map_err(|e| InputError::io(path, e))?;
        Ok(Self {
            path: path.to_path_buf(),
            file: BufReader::with_capacity(1 << 20, file),
            position: header.data_start,
            end: header.data_end.unwrap_or(length).min(length),
            compression: header.compression,
            raw: Vec::new(),
            decoded: Vec::new(),
            count: 0,
            current: (0, 0, 0),
        })
    }

    /// Advances to the next packet of stream `wanted`; returns its offset, its decoded bytes
    /// are then in `self.decoded`. `None` at the end of the packets.
    fn next(&mut self, wanted: i32) -> Result<Option<u64>, InputError> {
        loop {
            let Some((offset, stream, size)) = self.next_packet_header()? else {
                return Ok(None);
            };
            if stream != wanted {
                self.file
                    .seek_relative(size as i64)
                    .map_err(|e| InputError::io(&self.path, e))?;
                continue;
            }
            self.current = (self.count - 1, offset, stream);
            self.read_packet_data(offset, size)?;
            return Ok(Some(offset));
        }
    }

    /// Reads the next packet header and passes it: (offset, stream, byte size); `None` at the end.
    fn next_packet_header(&mut self) -> Result<Option<(u64, i32, i32)>, InputError> {
        if self.position + 8 > self.end {
            if self.position < self.end {
                return Err(InputError::corrupt(
                    &self.path,
                    format!("byte offset {}", self.position),
                    "the file ends inside a packet header",
                    FIX_TRUNCATED,
                ));
            }
            return Ok(None);
        }
        let offset = self.position;
        let mut head = [0u8; 8];
        read_exact(
            &mut self.file,
            &mut head,
            &self.path,
            offset,
            "a packet header",
        )?;
        let stream = i32::from_le_bytes([head[0], head[1], head[2], head[3]]);
        let size = i32::from_le_bytes([head[4], head[5], head[6], head[7]]);
        if size < 0 || offset + 8 + size as u64 > self.end {
            return Err(InputError::corrupt(
                &self.path,
                format!("byte offset {offset}"),
                format!("packet of stream {stream} claims {size} bytes, more than the file holds"),
                FIX_TRUNCATED,
            ));
        }
        self.position = offset + 8 + size as u64;
        self.count += 1;
        Ok(Some((offset, stream, size)))
    }

    /// Reads the `size` bytes of the packet at `offset` and decompresses them into `decoded`.
    fn read_packet_data(&mut self, offset: u64, size: i32) -> Result<(), InputError> {
        self.raw.resize(size as usize, 0);
        read_exact(
            &mut self.file,
            &mut self.raw,
            &self.path,
            offset + 8,
            "a packet",
        )?;
        self.decoded.clear();
        // a packet decompresses to at most MAX_PACKET_BYTES: more is a decompression
        // bomb or damage, never an event packet
        let result = decompress(self.compression, &self.raw, &mut self.decoded);
        if self.decoded.len() as u64 > MAX_PACKET_BYTES {
            return Err(InputError::corrupt(
                &self.path,
                self.place(""),
                format!(
                    "the packet decompresses to more than {} MB",
                    MAX_PACKET_BYTES >> 20
                ),
                FIX_DAMAGED_PACKET,
            ));
        }
        result.map_err(|e| {
            InputError::corrupt(
                &self.path,
                self.place(""),
                format!("cannot decompress the packet: {e}"),
                FIX_DAMAGED_PACKET,
            )
        })
    }

    /// The packet in `decoded`, of a `what` (event, frame) stream, whose contents are
    /// damaged: `problem`.
    fn damaged(&self, what: &str, problem: impl std::fmt::Display) -> InputError {
        InputError::corrupt(
            &self.path,
            self.place(&format!("{what} ")),
            problem.to_string(),
            FIX_DAMAGED_PACKET,
        )
    }

    /// The packet in `decoded`: its index among the file's packets, offset and stream (of
    /// `kind`: "event ", "frame ", or "" where not known).
    fn place(&self, kind: &str) -> String {
        let (index, offset, stream) = self.current;
        format!("packet {index} at byte offset {offset} ({kind}stream {stream})")
    }

    /// The packet in `decoded` is no valid `what` packet, by the FlatBuffer verifier.
    fn invalid(&self, what: &str, error: &flatbuffers::InvalidFlatbuffer) -> InputError {
        self.damaged(
            what,
            format!(
                "the packet ({} bytes after decompression) is no valid {what} packet ({})",
                self.decoded.len(),
                first_line(error)
            ),
        )
    }
}

/// The fix for a packet whose contents are damaged.
const FIX_DAMAGED_PACKET: &str =
    "the file is damaged at this packet: copy it again from the source recording";

/// The first line of a FlatBuffer verifier error, without its full stop: the lines below it
/// trace the verifier's path through the buffer (and end in blank lines).
fn first_line(error: &flatbuffers::InvalidFlatbuffer) -> String {
    let text = error.to_string();
    let line = text.lines().next().unwrap_or_default().trim_end();
    line.strip_suffix('.').unwrap_or(line).to_string()
}

/// Streaming decoder of the event stream.
pub struct Aedat4Decoder {
    packets: PacketReader,
    stream: i32,
    sensor: Option<Sensor>,
    order: OrderCheck,
    pending: Vec<u8>,
    pending_at: usize,
    packet_offset: u64,
}

impl Aedat4Decoder {
    pub fn open(
        path: &Path,
        header: &Aedat4Header,
        sensor: Option<Sensor>,
    ) -> Result<Self, InputError> {
        let stream = header
            .event_stream()
            .expect("checked by Aedat4Header::read");
        Ok(Self {
            packets: PacketReader::open(path, header)?,
            stream,
            sensor,
            order: OrderCheck::default(),
            pending: Vec::new(),
            pending_at: 0,
            packet_offset: 0,
        })
    }

    /// Loads the next event packet's raw 16-byte structs into `pending`.
    fn load_packet(&mut self) -> Result<bool, InputError> {
        let Some(offset) = self.packets.next(self.stream)? else {
            return Ok(false);
        };
        let packet = flatbuffers::size_prefixed_root::<EventPacket>(&self.packets.decoded)
            .map_err(|e| self.packets.invalid("event", &e))?;
        self.pending.clear();
        if let Some(elements) = packet.elements() {
            self.pending.extend_from_slice(elements.bytes());
        }
        self.pending_at = 0;
        self.packet_offset = offset;
        Ok(true)
    }
}

impl EventDecoder for Aedat4Decoder {
    fn read_chunk(&mut self, out: &mut EventChunk) -> Result<(), InputError> {
        while out.len() < CHUNK_EVENTS {
            if self.pending_at >= self.pending.len() && !self.load_packet()? {
                break;
            }
            let room = CHUNK_EVENTS - out.len();
            let end = (self.pending_at + 16 * room).min(self.pending.len());
            for (i, e) in self.pending[self.pending_at..end]
                .chunks_exact(16)
                .enumerate()
            {
                let t = i64::from_le_bytes(e[0..8].try_into().expect("8 bytes"));
                let x = i16::from_le_bytes([e[8], e[9]]);
                let y = i16::from_le_bytes([e[10], e[11]]);
                let index = (self.pending_at / 16) + i;
                let inside = x >= 0 && y >= 0 && super::within(self.sensor, x as u32, y as u32);
                if !inside {
                    return Err(super::outside_sensor(
                        &self.packets.path,
                        format!(
                            "packet at byte offset {}, event {index}",
                            self.packet_offset
                        ),
                        x as i64,
                        y as i64,
                        self.sensor,
                    ));
                }
                let packet_offset = self.packet_offset;
                self.order.check(t, || {
                    format!("packet at byte offset {packet_offset}, event {index}")
                });
                out.push(t, x as u16, y as u16, e[12] != 0);
            }
            self.pending_at = end;
        }
        Ok(())
    }

    fn order(&self) -> &OrderCheck {
        &self.order
    }

    fn progress(&self) -> Progress {
        Progress {
            done: self.packets.position,
            total: self.packets.end,
        }
    }
}

/// Decodes every frame of the file's first frame stream (grey; colour is converted with
/// ITU-R BT.601 weights). Frame time: the exposure midpoint where the packet gives the
/// exposure, else the frame's own timestamp. Frames must share one size and come in time
/// order (as IJRR frame lists must).
pub fn read_frames(path: &Path, header: &Aedat4Header) -> Result<Vec<Frame>, InputError> {
    read_frames_where(path, header, |_, _| true)
}

/// The frames whose index and time `keep` accepts.
pub fn read_frames_where(
    path: &Path,
    header: &Aedat4Header,
    keep: impl Fn(usize, TimeUs) -> bool,
) -> Result<Vec<Frame>, InputError> {
    let mut frames = Vec::new();
    let mut index = 0;
    for_each_frame(path, header, true, |frame| {
        if keep(index, frame.t) {
            frames.push(frame);
        }
        index += 1;
    })?;
    Ok(frames)
}

/// The frames' timestamps (each packet is decompressed and checked, its pixels dropped).
pub fn read_frame_times(path: &Path, header: &Aedat4Header) -> Result<Vec<TimeUs>, InputError> {
    let mut times = Vec::new();
    for_each_frame(path, header, false, |frame| times.push(frame.t))?;
    Ok(times)
}

/// Calls `f` with every frame of the first frame stream, in file order, each checked
/// ([`frame_layout`], [`frame_time`], [`check_frame_sequence`]); with `keep_pixels` false
/// the frames carry no pixels.
fn for_each_frame(
    path: &Path,
    header: &Aedat4Header,
    keep_pixels: bool,
    mut f: impl FnMut(Frame),
) -> Result<(), InputError> {
    let Some(stream) = header.frame_stream() else {
        return Ok(());
    };
    let mut packets = PacketReader::open(path, header)?;
    let mut previous: Option<(TimeUs, u32, u32)> = None;
    while let Some(offset) = packets.next(stream)? {
        let frame = flatbuffers::size_prefixed_root::<FramePacket>(&packets.decoded)
            .map_err(|e| packets.invalid("frame", &e))?;
        let layout = frame_layout(&packets, &frame)?;
        let (w, h) = (layout.width, layout.height);
        let (t, exposure_us) = frame_time(&packets, offset, &frame)?;
        check_frame_sequence(&packets, offset, previous, (t, w, h))?;
        previous = Some((t, w, h));
        let pixels = if keep_pixels {
            grey_pixels(layout.data, layout.channels)
        } else {
            Vec::new()
        };
        f(Frame {
            t,
            width: w,
            height: h,
            pixels,
            exposure_us,
        });
    }
    Ok(())
}

/// A frame packet's size and pixel bytes, checked by [`frame_layout`].
struct FrameLayout<'a> {
    width: u32,
    height: u32,
    /// Bytes per pixel: 1 (grey), 3 (BGR) or 4 (BGRA).
    channels: usize,
    /// The pixels, row by row, `channels` bytes each.
    data: &'a [u8],
}

/// The size and pixel bytes of the frame in packet `frame`, checked. AEDAT4 (dv-processing
/// `frame.fbs`): `sizeX`/`sizeY` must lie in 1..=`MAX_SENSOR_SIDE`, `format` is an OpenCV
/// pixel type (0 grey `CV_8UC1`, 16 BGR `CV_8UC3`, 24 BGRA `CV_8UC4`), and `pixels` must
/// hold exactly width x height x channels bytes.
fn frame_layout<'a>(
    packets: &PacketReader,
    frame: &FramePacket<'a>,
) -> Result<FrameLayout<'a>, InputError> {
    let (w, h) = (frame.width(), frame.height());
    let limit = crate::events::MAX_SENSOR_SIDE as i16;
    if w <= 0 || h <= 0 || w > limit || h > limit {
        return Err(packets.damaged(
            "frame",
            format!("frame size {w}x{h} (1..={limit} pixels a side expected)"),
        ));
    }
    let (w, h) = (w as u32, h as u32);
    let data = frame.pixels().map(|p| p.bytes()).unwrap_or_default();
    let channels = match frame.format() {
        0 => 1,
        16 => 3,
        24 => 4,
        other => {
            return Err(packets.damaged("frame", format!("unknown pixel format {other}")));
        }
    };
    if data.len() != (w * h) as usize * channels {
        return Err(packets.damaged(
            "frame",
            format!(
                "{} pixel bytes for a {w}x{h} frame with {channels} channels",
                data.len()
            ),
        ));
    }
    Ok(FrameLayout {
        width: w,
        height: h,
        channels,
        data,
    })
}

/// The time of the frame in packet `frame` (at byte `offset`) and its exposure, us. AEDAT4
/// (dv-processing `frame.fbs`): the midpoint of `timestampStartOfExposure` ..
/// `timestampEndOfExposure` where the packet gives a positive exposure, else the frame's
/// `timestamp`; a time beyond `TIME_LIMIT_US` of zero is damage.
fn frame_time(
    packets: &PacketReader,
    offset: u64,
    frame: &FramePacket,
) -> Result<(TimeUs, Option<i64>), InputError> {
    let (start, end) = (frame.exposure_start_t(), frame.exposure_end_t());
    let (t, exposure_us) = if end > start && start > 0 {
        (start + (end - start) / 2, Some(end - start))
    } else {
        (frame.t(), None)
    };
    if t.unsigned_abs() > crate::events::TIME_LIMIT_US as u64 {
        return Err(InputError::corrupt(
            &packets.path,
            format!("byte offset {offset} (frame packet)"),
            format!(
                "frame time {t} us lies beyond +-{} us (about 73,000 years) of zero",
                crate::events::TIME_LIMIT_US
            ),
            "the file is damaged at this place; cut the recording before it or copy it again from the source",
        ));
    }
    Ok((t, exposure_us))
}

/// Checks frame `(t, w, h)` (in the packet at byte `offset`) against the frame before it,
/// `previous`: frames must share one size and come in time order.
fn check_frame_sequence(
    packets: &PacketReader,
    offset: u64,
    previous: Option<(TimeUs, u32, u32)>,
    (t, w, h): (TimeUs, u32, u32),
) -> Result<(), InputError> {
    if let Some((t0, w0, h0)) = previous {
        if (w, h) != (w0, h0) {
            return Err(packets.damaged(
                "frame",
                format!("the frame is {w}x{h}, the first frame {w0}x{h0}"),
            ));
        }
        if t < t0 {
            return Err(InputError::corrupt(
                &packets.path,
                format!("byte offset {offset} (frame packet)"),
                format!("frame time {t} us is earlier than the frame before ({t0} us)"),
                "the file is damaged; frames must come in time order",
            ));
        }
    }
    Ok(())
}

/// The grey levels of a frame's pixel bytes `data` of `channels` bytes a pixel: grey
/// frames as they are, BGR(A) ones by ITU-R BT.601 weights (0.299 R + 0.587 G + 0.114 B,
/// rounded).
fn grey_pixels(data: &[u8], channels: usize) -> Vec<u8> {
    if channels == 1 {
        data.to_vec()
    } else {
        data.chunks_exact(channels)
            .map(|p| {
                let (b, g, r) = (p[0] as f32, p[1] as f32, p[2] as f32);
                (0.299 * r + 0.587 * g + 0.114 * b).round() as u8
            })
            .collect()
    }
}

// --- FlatBuffer accessors (field slots from the dv-processing schemas) ---

/// Little-endian scalars read without an alignment requirement: DV writes some tables whose
/// 8-byte fields are not 8-aligned within the buffer, which the stock scalar verifier
/// rejects; bounds are still checked.
macro_rules! unaligned_scalar {
    ($name:ident, $t:ty, $n:expr) => {
        struct $name;
        impl<'a> Follow<'a> for $name {
            type Inner = $t;
            unsafe fn follow(buf: &'a [u8], loc: usize) -> $t {
                let mut bytes = [0u8; $n];
                bytes.copy_from_slice(&buf[loc..loc + $n]);
                <$t>::from_le_bytes(bytes)
            }
        }
        impl Verifiable for $name {
            fn run_verifier(
                v: &mut Verifier,
                pos: usize,
            ) -> Result<(), flatbuffers::InvalidFlatbuffer> {
                v.range_in_buffer(pos, $n)
            }
        }
    };
}
unaligned_scalar!(LeI64, i64, 8);
unaligned_scalar!(LeI32, i32, 4);
unaligned_scalar!(LeI16, i16, 2);
unaligned_scalar!(LeI8, i8, 1);

struct IoHeader<'a>(Table<'a>);

impl<'a> Follow<'a> for IoHeader<'a> {
    type Inner = IoHeader<'a>;
    unsafe fn follow(buf: &'a [u8], loc: usize) -> Self::Inner {
        // SAFETY: forwarded from the caller's contract (a verified table at `loc`).
        IoHeader(unsafe { Table::new(buf, loc) })
    }
}

impl Verifiable for IoHeader<'_> {
    fn run_verifier(v: &mut Verifier, pos: usize) -> Result<(), flatbuffers::InvalidFlatbuffer> {
        v.visit_table(pos)?
            .visit_field::<LeI32>("compression", 4, false)?
            .visit_field::<LeI64>("dataTablePosition", 6, false)?
            .visit_field::<ForwardsUOffset<&str>>("infoNode", 8, false)?
            .finish();
        Ok(())
    }
}

impl<'a> IoHeader<'a> {
    fn compression(&self) -> i32 {
        // SAFETY: the buffer was verified (`flatbuffers::root`) before this accessor runs.
        unsafe { self.0.get::<LeI32>(4, Some(0)) }.unwrap_or(0)
    }
    fn data_table_position(&self) -> i64 {
        // SAFETY: as above.
        unsafe { self.0.get::<LeI64>(6, Some(-1)) }.unwrap_or(-1)
    }
    fn description(&self) -> Option<&'a str> {
        // SAFETY: as above.
        unsafe { self.0.get::<ForwardsUOffset<&str>>(8, None) }
    }
}

/// One 16-byte event struct `{t: i64, x: i16, y: i16, on: bool, 3 bytes padding}`.
#[repr(transparent)]
struct RawEvent([u8; 16]);

impl flatbuffers::SimpleToVerifyInSlice for RawEvent {}

impl<'a> Follow<'a> for RawEvent {
    type Inner = &'a [u8];
    unsafe fn follow(buf: &'a [u8], loc: usize) -> Self::Inner {
        &buf[loc..loc + 16]
    }
}

struct EventPacket<'a>(Table<'a>);

impl<'a> Follow<'a> for EventPacket<'a> {
    type Inner = EventPacket<'a>;
    unsafe fn follow(buf: &'a [u8], loc: usize) -> Self::Inner {
        // SAFETY: forwarded from the caller's contract (a verified table at `loc`).
        EventPacket(unsafe { Table::new(buf, loc) })
    }
}

impl Verifiable for EventPacket<'_> {
    fn run_verifier(v: &mut Verifier, pos: usize) -> Result<(), flatbuffers::InvalidFlatbuffer> {
        v.visit_table(pos)?
            .visit_field::<ForwardsUOffset<Vector<'_, RawEvent>>>("elements", 4, false)?
            .finish();
        Ok(())
    }
}

impl<'a> EventPacket<'a> {
    fn elements(&self) -> Option<Vector<'a, RawEvent>> {
        // SAFETY: the buffer was verified (`size_prefixed_root`) before this accessor runs.
        unsafe { self.0.get::<ForwardsUOffset<Vector<'a, RawEvent>>>(4, None) }
    }
}

struct FramePacket<'a>(Table<'a>);

impl<'a> Follow<'a> for FramePacket<'a> {
    type Inner = FramePacket<'a>;
    unsafe fn follow(buf: &'a [u8], loc: usize) -> Self::Inner {
        // SAFETY: forwarded from the caller's contract (a verified table at `loc`).
        FramePacket(unsafe { Table::new(buf, loc) })
    }
}

impl Verifiable for FramePacket<'_> {
    fn run_verifier(v: &mut Verifier, pos: usize) -> Result<(), flatbuffers::InvalidFlatbuffer> {
        v.visit_table(pos)?
            .visit_field::<LeI64>("timestamp", 4, false)?
            .visit_field::<LeI64>("timestampStartOfFrame", 6, false)?
            .visit_field::<LeI64>("timestampEndOfFrame", 8, false)?
            .visit_field::<LeI64>("timestampStartOfExposure", 10, false)?
            .visit_field::<LeI64>("timestampEndOfExposure", 12, false)?
            .visit_field::<LeI8>("format", 14, false)?
            .visit_field::<LeI16>("sizeX", 16, false)?
            .visit_field::<LeI16>("sizeY", 18, false)?
            .visit_field::<ForwardsUOffset<Vector<'_, u8>>>("pixels", 24, false)?
            .finish();
        Ok(())
    }
}

impl<'a> FramePacket<'a> {
    // SAFETY (all accessors): the buffer was verified before any accessor runs.
    fn t(&self) -> i64 {
        unsafe { self.0.get::<LeI64>(4, Some(0)) }.unwrap_or(0)
    }
    fn exposure_start_t(&self) -> i64 {
        unsafe { self.0.get::<LeI64>(10, Some(0)) }.unwrap_or(0)
    }
    fn exposure_end_t(&self) -> i64 {
        unsafe { self.0.get::<LeI64>(12, Some(0)) }.unwrap_or(0)
    }
    fn format(&self) -> i8 {
        unsafe { self.0.get::<LeI8>(14, Some(0)) }.unwrap_or(0)
    }
    fn width(&self) -> i16 {
        unsafe { self.0.get::<LeI16>(16, Some(0)) }.unwrap_or(0)
    }
    fn height(&self) -> i16 {
        unsafe { self.0.get::<LeI16>(18, Some(0)) }.unwrap_or(0)
    }
    fn pixels(&self) -> Option<Vector<'a, u8>> {
        unsafe { self.0.get::<ForwardsUOffset<Vector<'a, u8>>>(24, None) }
    }
}
