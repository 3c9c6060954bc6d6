//! The messages of a bag's chunk section, one at a time: chunk records are read and
//! decompressed one after another (memory: one chunk), and the connection and message
//! records inside them handed out in file order.

use super::records::{self, BagDamage, FileRecord, InnerRecords, RecordFile, op};
use crate::error::{FIX_TRUNCATED, InputError};
use std::path::Path;

/// A connection record: a topic and its message type.
#[derive(Clone, Debug)]
pub struct Connection {
    pub id: u32,
    pub topic: String,
    pub message_type: String,
}

/// What the reader hands out.
pub enum Item<'a> {
    Connection(Connection),
    Message { connection: u32, data: &'a [u8] },
}

/// A connection record's id, topic and type.
pub fn connection(fields: &[(&str, &[u8])], data: &[u8]) -> Result<Connection, String> {
    let id =
        records::int_field::<4>(fields, "conn").ok_or("the connection has no `conn` id")? as u32;
    let topic = records::field(fields, "topic").ok_or("the connection has no `topic`")?;
    let described = records::fields(data)?;
    let message_type =
        records::field(&described, "type").ok_or("the connection has no message `type`")?;
    Ok(Connection {
        id,
        topic: String::from_utf8_lossy(topic).into_owned(),
        message_type: String::from_utf8_lossy(message_type).into_owned(),
    })
}

/// An inner record, read.
enum Parsed {
    Connection(Connection),
    Message(u32, std::ops::Range<usize>),
    Other,
}

/// Sequential reader of the chunk section.
pub struct MessageReader {
    file: RecordFile,
    /// Where the chunk section ends (the index, or the end of the file).
    end: u64,
    compressed: Vec<u8>,
    chunk: Vec<u8>,
    /// File offset of the chunk being read, and the position inside it.
    chunk_offset: u64,
    inner: usize,
    /// Messages handed out so far.
    pub messages: u64,
    /// The connections defined so far (id, topic): a message must name one of them.
    known: Vec<(u32, String)>,
}

impl MessageReader {
    /// A reader over the records from `start` to `end`.
    pub fn open(path: &Path, start: u64, end: u64) -> Result<Self, InputError> {
        let mut file = match RecordFile::open(path).map_err(|e| InputError::io(path, e))? {
            Ok(f) => f,
            Err(damage) => return Err(damage_error(path, damage)),
        };
        file.seek(start).map_err(|e| InputError::io(path, e))?;
        Ok(Self {
            file,
            end,
            compressed: Vec::new(),
            chunk: Vec::new(),
            chunk_offset: start,
            inner: 0,
            messages: 0,
            known: Vec::new(),
        })
    }

    /// Bytes of the file read so far, and its length.
    pub fn progress(&self) -> (u64, u64) {
        (self.file.position, self.file.len)
    }

    /// Where the current chunk lies, for messages.
    pub fn place(&self) -> String {
        format!("chunk at byte offset {}", self.chunk_offset)
    }

    /// The next connection or message; `None` at the end of the chunk section.
    pub fn next_item(&mut self) -> Result<Option<Item<'_>>, InputError> {
        let path = self.file.path().to_path_buf();
        loop {
            if self.inner < self.chunk.len() {
                let start = self.inner;
                match self.parse_inner(&path, start)? {
                    Parsed::Connection(c) => {
                        self.remember(&c);
                        return Ok(Some(Item::Connection(c)));
                    }
                    Parsed::Message(connection, _) if !self.is_known(connection) => {
                        return Err(self.unknown_connection(&path, start, connection));
                    }
                    Parsed::Message(connection, range) => {
                        self.messages += 1;
                        return Ok(Some(Item::Message {
                            connection,
                            data: &self.chunk[range],
                        }));
                    }
                    Parsed::Other => continue,
                }
            }
            if !self.load_next_chunk(&path)? {
                return Ok(None);
            }
        }
    }

    /// Where the inner record at byte `start` of the current chunk lies, for messages.
    fn record_place(&self, start: usize) -> String {
        format!(
            "chunk at byte offset {}, record at byte {start} of the chunk",
            self.chunk_offset
        )
    }

    /// Reads the inner record at byte `start` of the current chunk and moves past it.
    /// rosbag v2.0: a chunk's records are connections (op 0x07: `conn` id and `topic` in
    /// the header, the message `type` in the data) and messages (op 0x02: `conn` id in the
    /// header, the serialized message as data); any other op is passed over. A message's
    /// data is returned as a range of the chunk, so that the borrow of the chunk ends here
    /// (before the chunk may be refilled).
    fn parse_inner(&mut self, path: &Path, start: usize) -> Result<Parsed, InputError> {
        let mut records = InnerRecords::new(&self.chunk[start..]);
        let record = records.next().expect("bytes remain");
        self.inner += records.consumed();
        let record = record.map_err(|problem| {
            InputError::corrupt(path, self.record_place(start), problem, FIX_TRUNCATED)
        })?;
        let damaged = |problem: String| {
            InputError::corrupt(path, self.record_place(start), problem, FIX_TRUNCATED)
        };
        Ok(match records::op_of(&record.fields) {
            Some(op::CONNECTION) => {
                Parsed::Connection(connection(&record.fields, record.data).map_err(damaged)?)
            }
            Some(op::MESSAGE) => {
                let connection = records::int_field::<4>(&record.fields, "conn")
                    .ok_or_else(|| damaged("the message has no `conn` id".into()))?;
                let data = start + record.data_offset;
                Parsed::Message(connection as u32, data..data + record.data.len())
            }
            _ => Parsed::Other,
        })
    }

    /// Whether a connection record read so far defines connection `id`.
    fn is_known(&self, id: u32) -> bool {
        self.known.iter().any(|(known, _)| *known == id)
    }

    /// Records the id and topic of connection `c` (once per id), so that the messages after
    /// it can be told apart by topic.
    fn remember(&mut self, c: &Connection) {
        if !self.is_known(c.id) {
            self.known.push((c.id, c.topic.clone()));
        }
    }

    /// The error for a message (at byte `start` of the chunk) of a connection id that no
    /// connection record before it defines: its topic cannot be told, so events or frames
    /// would go missing.
    fn unknown_connection(&self, path: &Path, start: usize, connection: u32) -> InputError {
        let defined = if self.known.is_empty() {
            "none".to_string()
        } else {
            self.known
                .iter()
                .map(|(id, topic)| format!("{id} ({topic})"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        InputError::corrupt(
            path,
            self.record_place(start),
            format!(
                "a message of connection id {connection}, which no connection record before it defines (defined: {defined}), so its topic is unknown"
            ),
            FIX_TRUNCATED,
        )
    }

    /// Reads record headers up to the next chunk record and loads that chunk
    /// ([`Self::load_chunk`]); the data of any other record (rosbag v2.0: the index data
    /// records, op 0x04, that follow each chunk) is skipped. `false` at the end of the chunk
    /// section.
    fn load_next_chunk(&mut self, path: &Path) -> Result<bool, InputError> {
        loop {
            let header = match self
                .file
                .next_header(self.end)
                .map_err(|e| InputError::io(path, e))?
            {
                Ok(Some(h)) => h,
                Ok(None) => return Ok(false),
                Err(damage) => return Err(damage_error(path, damage)),
            };
            let place = format!("record at byte offset {}", header.offset);
            let fields = records::fields(&header.header)
                .map_err(|problem| InputError::corrupt(path, &place, problem, FIX_TRUNCATED))?;
            if records::op_of(&fields) != Some(op::CHUNK) {
                self.file
                    .skip_data(&header)
                    .map_err(|e| InputError::io(path, e))?;
                continue;
            }
            self.load_chunk(path, &header, &fields)?;
            return Ok(true);
        }
    }

    /// Reads the data of chunk record `header` and decompresses it into `self.chunk`,
    /// positioned at its first inner record. rosbag v2.0: a chunk (op 0x05) states its
    /// `compression` (`none`, `bz2` or `lz4`) and uncompressed `size` in its header.
    fn load_chunk(
        &mut self,
        path: &Path,
        header: &FileRecord,
        fields: &[(&str, &[u8])],
    ) -> Result<(), InputError> {
        let chunk_damaged = |problem: String| {
            InputError::corrupt(
                path,
                format!("chunk at byte offset {}", header.offset),
                problem,
                FIX_TRUNCATED,
            )
        };
        let (compression, size) = records::chunk_header(fields).map_err(chunk_damaged)?;
        self.file
            .read_data(header, &mut self.compressed)
            .map_err(|e| InputError::io(path, e))?;
        self.chunk_offset = header.offset;
        records::decompress(compression, &self.compressed, size, &mut self.chunk)
            .map_err(chunk_damaged)?;
        self.inner = 0;
        Ok(())
    }
}

/// The error for damage found in the container.
pub fn damage_error(path: &Path, damage: BagDamage) -> InputError {
    InputError::corrupt(path, damage.place, damage.problem, FIX_TRUNCATED)
}
