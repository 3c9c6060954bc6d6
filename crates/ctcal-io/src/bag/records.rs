//! The ROS bag 2.0 container (<http://wiki.ros.org/Bags/Format/2.0>): after the line
//! `#ROSBAG V2.0`, a sequence of records, each `header_len: u32, header, data_len: u32, data`
//! (little-endian), the header a list of `field_len: u32, name=value` fields whose `op`
//! byte says what the record is. Chunks (op 5) hold connection (op 7) and message (op 2)
//! records, stored plainly or compressed with bz2 or LZ4 (the LZ4 frame format, as roslz4
//! writes it); the index section after the chunks repeats the connections and lists each
//! chunk's message counts (op 6).
//!
//! Written here rather than taken from the `rosbag` crate: that crate maps the whole file
//! (a bag read end to end becomes resident memory), slices by the header's `index_pos`
//! without checking it (a bag that was never closed, `index_pos = 0`, panics) and
//! decompresses whatever size a chunk claims; ctcal reads record by record with every
//! length checked against the file, and names the byte offset of any damage.

use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// The first bytes of every ROS1 bag.
pub const MAGIC: &[u8] = b"#ROSBAG V2.0\n";

/// Record kinds (`op` field).
pub mod op {
    pub const MESSAGE: u8 = 0x02;
    pub const BAG_HEADER: u8 = 0x03;
    pub const CHUNK: u8 = 0x05;
    pub const CHUNK_INFO: u8 = 0x06;
    pub const CONNECTION: u8 = 0x07;
}

/// The largest record header ctcal reads (headers are a few hundred bytes).
const MAX_HEADER_BYTES: u32 = 1 << 20;
/// The largest chunk ctcal decompresses at once (ROS writes 768 KB chunks by default).
pub const MAX_CHUNK_BYTES: u32 = 256 << 20;

/// Damage found in a bag: where and what.
#[derive(Debug, Clone, PartialEq)]
pub struct BagDamage {
    pub place: String,
    pub problem: String,
}

impl BagDamage {
    pub fn new(place: impl Into<String>, problem: impl Into<String>) -> Self {
        Self {
            place: place.into(),
            problem: problem.into(),
        }
    }
}

/// The `name=value` fields of a record header, in order.
pub fn fields(header: &[u8]) -> Result<Vec<(&str, &[u8])>, String> {
    let mut out = Vec::new();
    let mut rest = header;
    while !rest.is_empty() {
        let Some(len) = rest.get(..4) else {
            return Err("a header field is cut short".into());
        };
        let len = u32::from_le_bytes(len.try_into().expect("4 bytes")) as usize;
        let Some(field) = rest.get(4..4 + len) else {
            return Err(format!(
                "a header field claims {len} bytes, more than the header holds"
            ));
        };
        let Some(eq) = field.iter().position(|&b| b == b'=') else {
            return Err("a header field has no `=`".into());
        };
        let name = std::str::from_utf8(&field[..eq])
            .map_err(|_| "a header field name is not text".to_string())?;
        out.push((name, &field[eq + 1..]));
        rest = &rest[4 + len..];
    }
    Ok(out)
}

/// The value of field `name`, if present.
pub fn field<'a>(fields: &[(&str, &'a [u8])], name: &str) -> Option<&'a [u8]> {
    fields.iter().find(|(n, _)| *n == name).map(|(_, v)| *v)
}

/// A little-endian integer field of exactly `N` bytes.
pub fn int_field<const N: usize>(fields: &[(&str, &[u8])], name: &str) -> Option<u64> {
    let bytes: [u8; N] = field(fields, name)?.try_into().ok()?;
    let mut wide = [0u8; 8];
    wide[..N].copy_from_slice(&bytes);
    Some(u64::from_le_bytes(wide))
}

/// The `op` of a record header.
pub fn op_of(fields: &[(&str, &[u8])]) -> Option<u8> {
    match field(fields, "op") {
        Some([op]) => Some(*op),
        _ => None,
    }
}

/// One record read from the file: where it starts, its header, and its data (in the
/// reader's buffer, or skipped).
pub struct FileRecord {
    pub offset: u64,
    pub header: Vec<u8>,
    pub data_len: u32,
}

/// Sequential reading of a bag's records, every length checked against the file.
pub struct RecordFile {
    path: PathBuf,
    file: std::io::BufReader<std::fs::File>,
    pub position: u64,
    pub len: u64,
}

impl RecordFile {
    /// Opens `path` (the magic is checked) positioned after the magic line.
    pub fn open(path: &Path) -> std::io::Result<Result<Self, BagDamage>> {
        let file = std::fs::File::open(path)?;
        let len = file.metadata()?.len();
        let mut file = std::io::BufReader::with_capacity(1 << 20, file);
        let mut magic = [0u8; 13];
        let got = read_up_to(&mut file, &mut magic)?;
        if got < MAGIC.len() || magic != MAGIC {
            return Ok(Err(BagDamage::new(
                "byte offset 0",
                "the file does not start with `#ROSBAG V2.0`",
            )));
        }
        Ok(Ok(Self {
            path: path.to_path_buf(),
            file,
            position: MAGIC.len() as u64,
            len,
        }))
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Moves to byte `offset` (a record start).
    pub fn seek(&mut self, offset: u64) -> std::io::Result<()> {
        self.file.seek(SeekFrom::Start(offset))?;
        self.position = offset;
        Ok(())
    }

    /// The next record's header; its data is next in the file ([`Self::read_data`] or
    /// [`Self::skip_data`]). `None` at the end of the file or at `end`.
    pub fn next_header(
        &mut self,
        end: u64,
    ) -> std::io::Result<Result<Option<FileRecord>, BagDamage>> {
        if self.position >= end.min(self.len) {
            return Ok(Ok(None));
        }
        let offset = self.position;
        let place = || format!("record at byte offset {offset}");
        let mut word = [0u8; 4];
        if read_up_to(&mut self.file, &mut word)? < 4 {
            return Ok(Err(BagDamage::new(
                place(),
                "the file ends inside a record",
            )));
        }
        let header_len = u32::from_le_bytes(word);
        if header_len > MAX_HEADER_BYTES || offset + 8 + header_len as u64 > self.len {
            return Ok(Err(BagDamage::new(
                place(),
                format!("the record header claims {header_len} bytes, more than the file holds"),
            )));
        }
        let mut header = vec![0u8; header_len as usize];
        self.file.read_exact(&mut header)?;
        if read_up_to(&mut self.file, &mut word)? < 4 {
            return Ok(Err(BagDamage::new(
                place(),
                "the file ends inside a record",
            )));
        }
        let data_len = u32::from_le_bytes(word);
        let data_start = offset + 8 + header_len as u64;
        if data_start + data_len as u64 > self.len {
            return Ok(Err(BagDamage::new(
                place(),
                format!(
                    "the record claims {data_len} data bytes but the file ends {} bytes later",
                    self.len - data_start
                ),
            )));
        }
        self.position = data_start;
        Ok(Ok(Some(FileRecord {
            offset,
            header,
            data_len,
        })))
    }

    /// Reads the current record's data into `buffer` (replacing its contents).
    pub fn read_data(&mut self, record: &FileRecord, buffer: &mut Vec<u8>) -> std::io::Result<()> {
        buffer.clear();
        buffer.resize(record.data_len as usize, 0);
        self.file.read_exact(buffer)?;
        self.position += record.data_len as u64;
        Ok(())
    }

    /// Skips the current record's data.
    pub fn skip_data(&mut self, record: &FileRecord) -> std::io::Result<()> {
        self.file.seek_relative(record.data_len as i64)?;
        self.position += record.data_len as u64;
        Ok(())
    }
}

/// Reads until `buffer` is full or the file ends; the number of bytes read.
fn read_up_to(reader: &mut impl Read, buffer: &mut [u8]) -> std::io::Result<usize> {
    let mut filled = 0;
    while filled < buffer.len() {
        match reader.read(&mut buffer[filled..]) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(filled)
}

/// How a chunk's records are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression {
    None,
    Bz2,
    Lz4,
}

/// A chunk record's compression and uncompressed size, checked.
pub fn chunk_header(fields: &[(&str, &[u8])]) -> Result<(Compression, u32), String> {
    let compression = match field(fields, "compression") {
        Some(b"none") => Compression::None,
        Some(b"bz2") => Compression::Bz2,
        Some(b"lz4") => Compression::Lz4,
        Some(other) => {
            return Err(format!(
                "the chunk is compressed with `{}`, which ROS bags do not use (none, bz2, lz4)",
                String::from_utf8_lossy(other)
            ));
        }
        None => return Err("the chunk header has no `compression` field".into()),
    };
    let size =
        int_field::<4>(fields, "size").ok_or("the chunk header has no 4-byte `size` field")? as u32;
    if size > MAX_CHUNK_BYTES {
        return Err(format!(
            "the chunk claims {size} bytes uncompressed, more than the {MAX_CHUNK_BYTES} ctcal decompresses at once"
        ));
    }
    Ok((compression, size))
}

/// Decompresses a chunk's `data` into `out` (exactly `size` bytes, else an error).
pub fn decompress(
    compression: Compression,
    data: &[u8],
    size: u32,
    out: &mut Vec<u8>,
) -> Result<(), String> {
    out.clear();
    let size = size as usize;
    match compression {
        Compression::None => out.extend_from_slice(data),
        Compression::Bz2 => {
            out.reserve_exact(size);
            let mut decoder = bzip2::Decompress::new(false);
            // decompress_vec writes at most the reserved capacity: a chunk cannot expand
            // beyond the size it claims
            match decoder.decompress_vec(data, out) {
                Ok(bzip2::Status::StreamEnd) => {}
                Ok(_) if out.len() >= size => {
                    return Err(format!(
                        "the bz2 data expands beyond the {size} bytes the chunk claims"
                    ));
                }
                Ok(_) => return Err("the bz2 data ends early".into()),
                Err(e) => return Err(format!("the bz2 data does not decompress ({e})")),
            }
        }
        Compression::Lz4 => {
            let decoder = lz4_flex::frame::FrameDecoder::new(data);
            decoder
                .take(size as u64 + 1)
                .read_to_end(out)
                .map_err(|e| format!("the LZ4 data does not decompress ({e})"))?;
        }
    }
    if out.len() != size {
        return Err(format!(
            "the chunk decompresses to {} bytes but claims {size}",
            out.len()
        ));
    }
    Ok(())
}

/// One record inside a decompressed chunk.
pub struct InnerRecord<'a> {
    /// Byte offset of the record, and of its data, in the bytes iterated.
    pub offset: usize,
    pub data_offset: usize,
    pub fields: Vec<(&'a str, &'a [u8])>,
    pub data: &'a [u8],
}

/// The records of a decompressed chunk, in order.
pub struct InnerRecords<'a> {
    bytes: &'a [u8],
    position: usize,
}

impl<'a> InnerRecords<'a> {
    pub fn new(bytes: &'a [u8]) -> Self {
        Self { bytes, position: 0 }
    }

    /// Bytes consumed so far.
    pub fn consumed(&self) -> usize {
        self.position
    }
}

impl<'a> Iterator for InnerRecords<'a> {
    type Item = Result<InnerRecord<'a>, String>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.position >= self.bytes.len() {
            return None;
        }
        let offset = self.position;
        let rest = &self.bytes[offset..];
        let result = (|| {
            let header_len =
                u32::from_le_bytes(rest.get(..4).ok_or("cut short")?.try_into().expect("4"))
                    as usize;
            let header = rest.get(4..4 + header_len).ok_or_else(|| {
                format!("the record header claims {header_len} bytes, more than the chunk holds")
            })?;
            let after = 4 + header_len;
            let data_len = u32::from_le_bytes(
                rest.get(after..after + 4)
                    .ok_or("cut short")?
                    .try_into()
                    .expect("4"),
            ) as usize;
            let data = rest.get(after + 4..after + 4 + data_len).ok_or_else(|| {
                format!("the record claims {data_len} data bytes, more than the chunk holds")
            })?;
            Ok::<_, String>((fields(header)?, data, after + 4, after + 4 + data_len))
        })();
        match result {
            Ok((fields, data, data_start, length)) => {
                self.position += length;
                Some(Ok(InnerRecord {
                    offset,
                    data_offset: offset + data_start,
                    fields,
                    data,
                }))
            }
            Err(problem) => {
                self.position = self.bytes.len();
                Some(Err(format!(
                    "record at byte {offset} of the chunk: {problem}"
                )))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field_bytes(name: &str, value: &[u8]) -> Vec<u8> {
        let mut f = Vec::new();
        f.extend_from_slice(&((name.len() + 1 + value.len()) as u32).to_le_bytes());
        f.extend_from_slice(name.as_bytes());
        f.push(b'=');
        f.extend_from_slice(value);
        f
    }

    #[test]
    fn header_fields_are_split_and_checked() {
        let mut header = field_bytes("op", &[5]);
        header.extend(field_bytes("size", &1234u32.to_le_bytes()));
        header.extend(field_bytes("compression", b"bz2"));
        let f = fields(&header).unwrap();
        assert_eq!(op_of(&f), Some(op::CHUNK));
        assert_eq!(chunk_header(&f).unwrap(), (Compression::Bz2, 1234));
        // a field longer than the header, and one without `=`
        let mut bad = header.clone();
        bad.extend_from_slice(&100u32.to_le_bytes());
        assert!(fields(&bad).unwrap_err().contains("more than the header"));
        let mut no_eq = 3u32.to_le_bytes().to_vec();
        no_eq.extend_from_slice(b"abc");
        assert!(fields(&no_eq).unwrap_err().contains("no `=`"));
    }

    #[test]
    fn chunks_decompress_to_exactly_their_size() {
        let plain: Vec<u8> = (0..10_000u32)
            .flat_map(|i| (i % 251).to_le_bytes())
            .collect();
        let mut bz = Vec::new();
        {
            let mut w = bzip2::write::BzEncoder::new(&mut bz, bzip2::Compression::best());
            std::io::Write::write_all(&mut w, &plain).unwrap();
        }
        let mut lz = lz4_flex::frame::FrameEncoder::new(Vec::new());
        std::io::Write::write_all(&mut lz, &plain).unwrap();
        let lz = lz.finish().unwrap();
        let mut out = Vec::new();
        for (c, data) in [
            (Compression::Bz2, &bz),
            (Compression::Lz4, &lz),
            (Compression::None, &plain),
        ] {
            decompress(c, data, plain.len() as u32, &mut out).unwrap();
            assert_eq!(out, plain, "{c:?}");
            // a chunk claiming fewer bytes than it holds, or more
            assert!(
                decompress(c, data, plain.len() as u32 - 1, &mut out).is_err(),
                "{c:?}"
            );
            assert!(
                decompress(c, data, plain.len() as u32 + 1, &mut out).is_err(),
                "{c:?}"
            );
        }
        assert!(
            decompress(
                Compression::Bz2,
                &bz[..bz.len() / 2],
                plain.len() as u32,
                &mut out
            )
            .is_err()
        );
        assert!(decompress(Compression::Lz4, &plain[..100], 100, &mut out).is_err());
    }
}
