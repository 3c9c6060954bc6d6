//! The messages of a bag's chunk section, one at a time: chunk records are read and
//! decompressed one after another (memory: one chunk), and the connection and message
//! records inside them handed out in file order.

use super::records::{self, BagDamage, InnerRecords, RecordFile, op};
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
                // what the record is, with the data as a range (the borrow of the chunk
                // ends before the chunk may be refilled)
                let parsed = {
                    let mut records = InnerRecords::new(&self.chunk[start..]);
                    let record = records.next().expect("bytes remain");
                    self.inner += records.consumed();
                    let place = || {
                        format!(
                            "chunk at byte offset {}, record at byte {start} of the chunk",
                            self.chunk_offset
                        )
                    };
                    let record = record.map_err(|problem| {
                        InputError::corrupt(&path, place(), problem, FIX_TRUNCATED)
                    })?;
                    let damaged = |problem: String| {
                        InputError::corrupt(&path, place(), problem, FIX_TRUNCATED)
                    };
                    match records::op_of(&record.fields) {
                        Some(op::CONNECTION) => Parsed::Connection(
                            connection(&record.fields, record.data).map_err(damaged)?,
                        ),
                        Some(op::MESSAGE) => {
                            let connection = records::int_field::<4>(&record.fields, "conn")
                                .ok_or_else(|| damaged("the message has no `conn` id".into()))?;
                            let data = start + record.data_offset;
                            Parsed::Message(connection as u32, data..data + record.data.len())
                        }
                        _ => Parsed::Other,
                    }
                };
                match parsed {
                    Parsed::Connection(c) => {
                        if !self.known.iter().any(|(id, _)| *id == c.id) {
                            self.known.push((c.id, c.topic.clone()));
                        }
                        return Ok(Some(Item::Connection(c)));
                    }
                    Parsed::Message(connection, _)
                        if !self.known.iter().any(|(id, _)| *id == connection) =>
                    {
                        // its topic cannot be told: events or frames would go missing
                        let defined = if self.known.is_empty() {
                            "none".to_string()
                        } else {
                            self.known
                                .iter()
                                .map(|(id, topic)| format!("{id} ({topic})"))
                                .collect::<Vec<_>>()
                                .join(", ")
                        };
                        return Err(InputError::corrupt(
                            &path,
                            format!(
                                "chunk at byte offset {}, record at byte {start} of the chunk",
                                self.chunk_offset
                            ),
                            format!(
                                "a message of connection id {connection}, which no connection record before it defines (defined: {defined}), so its topic is unknown"
                            ),
                            FIX_TRUNCATED,
                        ));
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
            // the next chunk
            let header = match self
                .file
                .next_header(self.end)
                .map_err(|e| InputError::io(&path, e))?
            {
                Ok(Some(h)) => h,
                Ok(None) => return Ok(None),
                Err(damage) => return Err(damage_error(&path, damage)),
            };
            let place = format!("record at byte offset {}", header.offset);
            let fields = records::fields(&header.header)
                .map_err(|problem| InputError::corrupt(&path, &place, problem, FIX_TRUNCATED))?;
            if records::op_of(&fields) != Some(op::CHUNK) {
                self.file
                    .skip_data(&header)
                    .map_err(|e| InputError::io(&path, e))?;
                continue;
            }
            let (compression, size) = records::chunk_header(&fields).map_err(|problem| {
                InputError::corrupt(
                    &path,
                    format!("chunk at byte offset {}", header.offset),
                    problem,
                    FIX_TRUNCATED,
                )
            })?;
            self.file
                .read_data(&header, &mut self.compressed)
                .map_err(|e| InputError::io(&path, e))?;
            self.chunk_offset = header.offset;
            records::decompress(compression, &self.compressed, size, &mut self.chunk).map_err(
                |problem| {
                    InputError::corrupt(
                        &path,
                        format!("chunk at byte offset {}", header.offset),
                        problem,
                        FIX_TRUNCATED,
                    )
                },
            )?;
            self.inner = 0;
        }
    }
}

/// The error for damage found in the container.
pub fn damage_error(path: &Path, damage: BagDamage) -> InputError {
    InputError::corrupt(path, damage.place, damage.problem, FIX_TRUNCATED)
}
