//! ROS1 bags (`.bag`, `#ROSBAG V2.0`), as IJRR, MVSEC, HQF and CED are published: events
//! from `dvs_msgs/EventArray` messages and grey frames from `sensor_msgs/Image` messages
//! ([`messages`]), in a container of plain, bz2 or LZ4 chunks ([`records`], [`reader`]).
//!
//! Topics are found by message type; `--topic` / `--image-topic` choose when there are
//! several (a stereo bag has `/davis/left/events` and `/davis/right/events`). The topics and
//! their message counts come from the bag's index; a bag that was never closed has none and
//! is scanned instead.
//!
//! Messages of one topic may overlap in time (a driver publishes by count or by time, and
//! two publishers can interleave), so events are merged into time order as they stream:
//! the events of earlier messages are held until a message starts after them. Memory is one
//! chunk plus the overlap. Time order is checked as every other reader checks it, with that
//! overlap as the only allowance; each of these counts as a timestamp going backwards (an
//! unsorted file, which `--sort` accepts):
//! - an event earlier than the event before it in the same message;
//! - a message that ends before a message before it started (reversed records);
//! - a message that ends earlier than events already read by more than its own span (and
//!   [`OVERLAP_SLACK_US`]): it is not an overlap but an event far ahead of its neighbours
//!   (a damaged stamp) or records out of place;
//! - a message with events earlier than events already handed on.
//!
//! A message of a connection that no connection record before it defines is damage, named
//! with its connection id.

pub mod messages;
pub mod reader;
pub mod records;

use super::error::{FIX_TRUNCATED, InputError};
use super::order::OrderCheck;
use super::{EventDecoder, Progress};
use crate::events::{CHUNK_EVENTS, EventChunk, Frame, MAX_SENSOR_SIDE, Sensor, TimeUs};
use crate::hint::{Hint, Text};
use reader::{Item, MessageReader};
use records::{RecordFile, op};
use serde::Serialize;
use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};

/// How much a message may end before the latest event already read, beyond its own span
/// (delivery jitter between publishers).
pub const OVERLAP_SLACK_US: TimeUs = 1_000;

/// A topic of the bag.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Topic {
    pub name: String,
    pub message_type: String,
    pub messages: u64,
}

/// Which topics to read.
#[derive(Clone, Debug, Default)]
pub struct TopicChoice {
    pub events: Option<String>,
    pub images: Option<String>,
}

/// What a bag holds, and the topics chosen.
#[derive(Clone, Debug)]
pub struct BagInfo {
    pub topics: Vec<Topic>,
    /// The events topic, or why none could be chosen (problem, fix).
    pub events_topic: Result<String, (String, Text)>,
    pub image_topic: Option<String>,
    /// The sensor the first event message states (width, height).
    pub sensor: Option<Sensor>,
    /// Remarks for the user (no index, topic choices).
    pub notes: Vec<String>,
    data_start: u64,
    chunks_end: u64,
}

/// The bag header: where the records start and where the index is.
fn bag_header(path: &Path) -> Result<(u64, u64, u64), InputError> {
    let mut file = match RecordFile::open(path).map_err(|e| InputError::io(path, e))? {
        Ok(f) => f,
        Err(damage) => return Err(reader::damage_error(path, damage)),
    };
    let header = match file
        .next_header(u64::MAX)
        .map_err(|e| InputError::io(path, e))?
    {
        Ok(Some(h)) => h,
        Ok(None) => {
            return Err(InputError::Empty {
                path: path.to_path_buf(),
            });
        }
        Err(damage) => return Err(reader::damage_error(path, damage)),
    };
    let place = "the bag header record (byte offset 13)";
    let fields = records::fields(&header.header)
        .map_err(|p| InputError::corrupt(path, place, p, FIX_TRUNCATED))?;
    if records::op_of(&fields) != Some(op::BAG_HEADER) {
        return Err(InputError::corrupt(
            path,
            place,
            "the first record is not the bag header",
            FIX_TRUNCATED,
        ));
    }
    let index_pos = records::int_field::<8>(&fields, "index_pos").ok_or_else(|| {
        InputError::corrupt(
            path,
            place,
            "the bag header has no 8-byte index_pos",
            FIX_TRUNCATED,
        )
    })?;
    file.skip_data(&header)
        .map_err(|e| InputError::io(path, e))?;
    Ok((file.position, index_pos, file.len))
}

/// The connections of a bag and the message count of each connection id.
type Connections = (Vec<reader::Connection>, BTreeMap<u32, u64>);

/// Connections and message counts from the index section (`None` if it does not read).
fn read_index(path: &Path, index_pos: u64) -> Result<Option<Connections>, InputError> {
    let mut file = match RecordFile::open(path).map_err(|e| InputError::io(path, e))? {
        Ok(f) => f,
        Err(_) => return Ok(None),
    };
    file.seek(index_pos).map_err(|e| InputError::io(path, e))?;
    let mut connections = Vec::new();
    let mut counts: BTreeMap<u32, u64> = BTreeMap::new();
    let mut data = Vec::new();
    loop {
        let header = match file
            .next_header(u64::MAX)
            .map_err(|e| InputError::io(path, e))?
        {
            Ok(Some(h)) => h,
            Ok(None) => break,
            Err(_) => return Ok(None),
        };
        let Ok(fields) = records::fields(&header.header) else {
            return Ok(None);
        };
        match records::op_of(&fields) {
            Some(op::CONNECTION) => {
                file.read_data(&header, &mut data)
                    .map_err(|e| InputError::io(path, e))?;
                match reader::connection(&fields, &data) {
                    Ok(c) => connections.push(c),
                    Err(_) => return Ok(None),
                }
            }
            Some(op::CHUNK_INFO) => {
                file.read_data(&header, &mut data)
                    .map_err(|e| InputError::io(path, e))?;
                for pair in data.chunks_exact(8) {
                    let conn = u32::from_le_bytes(pair[..4].try_into().expect("4"));
                    let count = u32::from_le_bytes(pair[4..].try_into().expect("4"));
                    *counts.entry(conn).or_default() += count as u64;
                }
            }
            _ => file
                .skip_data(&header)
                .map_err(|e| InputError::io(path, e))?,
        }
    }
    Ok((!connections.is_empty()).then_some((connections, counts)))
}

/// The topics of `connections` with their message counts.
fn topics_of(connections: &[reader::Connection], counts: &BTreeMap<u32, u64>) -> Vec<Topic> {
    let mut topics: Vec<Topic> = Vec::new();
    for c in connections {
        let n = counts.get(&c.id).copied().unwrap_or(0);
        match topics.iter_mut().find(|t| t.name == c.topic) {
            Some(t) => t.messages += n,
            None => topics.push(Topic {
                name: c.topic.clone(),
                message_type: c.message_type.clone(),
                messages: n,
            }),
        }
    }
    topics.sort_by(|a, b| a.name.cmp(&b.name));
    topics
}

/// A one-line list of topics for messages.
fn listing(topics: &[Topic]) -> String {
    topics
        .iter()
        .map(|t| format!("{} ({}, {} messages)", t.name, t.message_type, t.messages))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Chooses the topic of `message_type`: the one asked for, else the only one.
fn choose(
    topics: &[Topic],
    message_type: &str,
    wanted: Option<&str>,
    option: Hint,
) -> Result<String, (String, Text)> {
    if let Some(name) = wanted {
        return match topics.iter().find(|t| t.name == name) {
            Some(t) if t.message_type == message_type => Ok(t.name.clone()),
            Some(t) => Err((
                format!(
                    "topic {name} carries {}, not {message_type}",
                    t.message_type
                ),
                Text::from(format!("choose a {message_type} topic"))
                    .aside(option)
                    .words(format!(": {}", listing(topics))),
            )),
            None => Err((
                format!("the bag has no topic {name}"),
                Text::from("choose one of its topics")
                    .aside(option)
                    .words(format!(": {}", listing(topics))),
            )),
        };
    }
    let of_type: Vec<&Topic> = topics
        .iter()
        .filter(|t| t.message_type == message_type)
        .collect();
    match of_type.as_slice() {
        [one] => Ok(one.name.clone()),
        [] => Err((
            format!("the bag has no {message_type} topic (its topics: {})", listing(topics)),
            "ctcal reads events from dvs_msgs/EventArray messages (rpg_dvs_ros); convert other event messages to that type".into(),
        )),
        several => Err((
            format!(
                "the bag has {} {message_type} topics: {}",
                several.len(),
                several.iter().map(|t| t.name.as_str()).collect::<Vec<_>>().join(", ")
            ),
            Text::default().act(option),
        )),
    }
}

/// Inspects a bag: its topics (from the index, or by scanning a bag without one), the
/// topics chosen and the sensor size the first event message states.
pub fn probe(path: &Path, choice: &TopicChoice) -> Result<BagInfo, InputError> {
    let (data_start, index_pos, len) = bag_header(path)?;
    let mut notes = Vec::new();
    let (chunks_end, (connections, counts)) =
        bag_connections(path, data_start, index_pos, len, &mut notes)?;
    let topics = topics_of(&connections, &counts);
    let events_topic = choose(
        &topics,
        messages::EVENT_ARRAY,
        choice.events.as_deref(),
        Hint::Topic,
    );
    let image_topic = chosen_image_topic(path, &topics, &events_topic, choice, &mut notes)?;
    if choice.events.is_some()
        && let Err((problem, fix)) = &events_topic
    {
        return Err(InputError::invalid(path, problem.clone(), fix.clone()));
    }
    let sensor = match &events_topic {
        Ok(topic) => first_event_sensor(path, data_start, chunks_end, topic)?,
        Err(_) => None,
    };
    Ok(BagInfo {
        topics,
        events_topic,
        image_topic,
        sensor,
        notes,
        data_start,
        chunks_end,
    })
}

/// The chunks' end and every connection's message count: from the index, else by a scan (noted).
fn bag_connections(
    path: &Path,
    data_start: u64,
    index_pos: u64,
    len: u64,
    notes: &mut Vec<String>,
) -> Result<(u64, Connections), InputError> {
    if index_pos > len {
        return Err(InputError::corrupt(
            path,
            "the bag header record (byte offset 13)",
            format!(
                "the index lies at byte {index_pos}, beyond the end of the file ({len} bytes): the bag is cut short"
            ),
            "copy the whole bag again from its source (or run `rosbag reindex` on a complete copy)",
        ));
    }
    let indexed = index_pos >= data_start;
    let chunks_end = if indexed { index_pos } else { len };
    let index = if indexed {
        read_index(path, index_pos)?
    } else {
        None
    };
    let connections = match index {
        Some(found) => found,
        None => {
            notes.push(if indexed {
                "the bag's index does not read; topics found by scanning the whole bag".to_string()
            } else {
                "the bag has no index (it was not closed when recorded); topics found by scanning it (`rosbag reindex` adds one)".to_string()
            });
            scan_connections(path, data_start, chunks_end)?
        }
    };
    Ok((chunks_end, connections))
}

/// The image topic: the one asked for, else the only one, else the one beside the events topic.
fn chosen_image_topic(
    path: &Path,
    topics: &[Topic],
    events_topic: &Result<String, (String, Text)>,
    choice: &TopicChoice,
    notes: &mut Vec<String>,
) -> Result<Option<String>, InputError> {
    match choose(
        topics,
        messages::IMAGE,
        choice.images.as_deref(),
        Hint::ImageTopic,
    ) {
        Ok(t) => Ok(Some(t)),
        Err((problem, fix)) if choice.images.is_some() => {
            Err(InputError::invalid(path, problem, fix))
        }
        Err(_) => Ok(image_topic_beside_events(topics, events_topic, notes)),
    }
}

/// The image topic beside the events topic (/davis/left/...), noting several with none beside it.
fn image_topic_beside_events(
    topics: &[Topic],
    events_topic: &Result<String, (String, Text)>,
    notes: &mut Vec<String>,
) -> Option<String> {
    let images: Vec<&Topic> = topics
        .iter()
        .filter(|t| t.message_type == messages::IMAGE)
        .collect();
    let namespace = |name: &str| {
        name.rsplit_once('/')
            .map(|(ns, _)| ns.to_string())
            .unwrap_or_default()
    };
    let beside = events_topic.as_ref().ok().and_then(|e| {
        images
            .iter()
            .find(|t| namespace(&t.name) == namespace(e))
            .map(|t| t.name.clone())
    });
    if beside.is_none() && images.len() > 1 {
        notes.push(format!(
            "{} image topics and none beside the events topic: frames not read (name the image topic to read them)",
            images.len()
        ));
    }
    beside
}

/// Every connection and its message count, by reading every chunk.
fn scan_connections(path: &Path, start: u64, end: u64) -> Result<Connections, InputError> {
    let mut reader = MessageReader::open(path, start, end)?;
    let mut connections: Vec<reader::Connection> = Vec::new();
    let mut counts: BTreeMap<u32, u64> = BTreeMap::new();
    while let Some(item) = reader.next_item()? {
        match item {
            Item::Connection(c) => {
                if !connections.iter().any(|k| k.id == c.id) {
                    connections.push(c);
                }
            }
            Item::Message { connection, .. } => *counts.entry(connection).or_default() += 1,
        }
    }
    Ok((connections, counts))
}

/// The sensor size stated by the first message of `topic`.
fn first_event_sensor(
    path: &Path,
    start: u64,
    end: u64,
    topic: &str,
) -> Result<Option<Sensor>, InputError> {
    let mut reader = MessageReader::open(path, start, end)?;
    let mut ids = HashSet::new();
    let mut scratch = EventChunk::default();
    loop {
        let chunk = reader.place();
        let Some(item) = reader.next_item()? else {
            return Ok(None);
        };
        match item {
            Item::Connection(c) if c.topic == topic => {
                ids.insert(c.id);
            }
            Item::Message { connection, data } if ids.contains(&connection) => {
                let place = format!("topic {topic}, message 1 ({chunk})");
                let (w, h) = messages::event_array(data, &mut scratch)
                    .map_err(|p| InputError::corrupt(path, place, p, FIX_TRUNCATED))?;
                return Ok(match (u16::try_from(w), u16::try_from(h)) {
                    (Ok(w), Ok(h)) if w > 0 && h > 0 => Some(Sensor::new(w, h)),
                    _ => None,
                });
            }
            _ => {}
        }
    }
}

/// The topic's connection ids, kept up to date as connection records stream by.
#[derive(Default)]
struct TopicIds {
    topic: String,
    ids: HashSet<u32>,
}

impl TopicIds {
    fn see(&mut self, c: &reader::Connection) {
        if c.topic == self.topic {
            self.ids.insert(c.id);
        }
    }
}

/// Streaming event reader of a bag (one topic), merging overlapping messages into time
/// order.
pub struct BagDecoder {
    path: PathBuf,
    reader: MessageReader,
    topic: TopicIds,
    sensor: Option<Sensor>,
    order: OrderCheck,
    /// Events of earlier messages not yet handed on (time-sorted).
    pending: EventChunk,
    /// Events ready to hand on, and how many have been.
    ready: EventChunk,
    handed: usize,
    /// Scratch for one message and for merging.
    incoming: EventChunk,
    merged: EventChunk,
    /// The event topic's messages read, and the place of the latest, for messages.
    message: u64,
    place: String,
    finished: bool,
    /// The latest event and the latest message start read so far, and the latest event
    /// handed on (for the order checks).
    latest: TimeUs,
    latest_start: TimeUs,
    handed_max: TimeUs,
    /// The message just read is out of place: everything held is handed on before it.
    out_of_place: bool,
}

impl BagDecoder {
    pub fn open(path: &Path, info: &BagInfo, sensor: Option<Sensor>) -> Result<Self, InputError> {
        let topic = match &info.events_topic {
            Ok(t) => t.clone(),
            Err((problem, fix)) => {
                return Err(InputError::invalid(path, problem.clone(), fix.clone()));
            }
        };
        Ok(Self {
            path: path.to_path_buf(),
            reader: MessageReader::open(path, info.data_start, info.chunks_end)?,
            topic: TopicIds {
                topic,
                ids: HashSet::new(),
            },
            sensor,
            order: OrderCheck::default(),
            pending: EventChunk::default(),
            ready: EventChunk::default(),
            handed: 0,
            incoming: EventChunk::default(),
            merged: EventChunk::default(),
            message: 0,
            place: String::new(),
            finished: false,
            latest: TimeUs::MIN,
            latest_start: TimeUs::MIN,
            handed_max: TimeUs::MIN,
            out_of_place: false,
        })
    }

    /// Reads the next message of the topic into `incoming`; `false` at the end.
    fn next_message(&mut self) -> Result<bool, InputError> {
        loop {
            let place = self.reader.place();
            match self.reader.next_item()? {
                None => return Ok(false),
                Some(Item::Connection(c)) => self.topic.see(&c),
                Some(Item::Message { connection, data })
                    if self.topic.ids.contains(&connection) =>
                {
                    self.message += 1;
                    self.place = format!(
                        "topic {}, message {} ({place})",
                        self.topic.topic, self.message
                    );
                    self.incoming.clear();
                    messages::event_array(data, &mut self.incoming).map_err(|p| {
                        InputError::corrupt(&self.path, &self.place, p, FIX_TRUNCATED)
                    })?;
                    for i in 0..self.incoming.len() {
                        let (x, y) = (self.incoming.x[i], self.incoming.y[i]);
                        if !super::within(self.sensor, x as u32, y as u32) {
                            return Err(super::outside_sensor(
                                &self.path,
                                format!("{}, event {i}", self.place),
                                x as i64,
                                y as i64,
                                self.sensor,
                            ));
                        }
                    }
                    self.check_order();
                    return Ok(true);
                }
                Some(Item::Message { .. }) => {}
            }
        }
    }

    /// Checks the order of the message just read (in `incoming`, in file order) against
    /// itself and the messages before it (see the module notes), then sorts it.
    fn check_order(&mut self) {
        let ts = &self.incoming.t;
        if ts.is_empty() {
            self.out_of_place = false;
            return;
        }
        let place = &self.place;
        self.order
            .check_range(ts, |i| format!("{place}, event {i}"));
        // within the message, in file order
        let within = ts.windows(2).filter(|w| w[1] < w[0]).count() as u64;
        if within > 0 {
            let i = ts.windows(2).position(|w| w[1] < w[0]).expect("counted") + 1;
            self.order
                .record_backwards(within, || format!("{place}, event {i}"), ts[i - 1], ts[i]);
        }
        let last_in_file = ts[ts.len() - 1];
        self.incoming.sort_by_time();
        let ts = &self.incoming.t;
        let (first, last) = (ts[0], ts[ts.len() - 1]);
        let span = last - first;
        let reversed = last < self.latest_start;
        let held_back = self.latest.saturating_sub(last) > span.saturating_add(OVERLAP_SLACK_US);
        self.out_of_place = reversed || held_back;
        // what the message's events must not precede
        let bound = if self.out_of_place {
            self.latest
        } else {
            self.handed_max
        };
        // counted as other readers count: once where the message goes back (its events
        // after that are in order among themselves)
        let goes_back = ts[0] < bound;
        if goes_back {
            let what = if reversed {
                "the message ends before a message before it started"
            } else if held_back {
                "the message ends far before events already read"
            } else {
                "the message holds events earlier than events already read"
            };
            self.order
                .record_backwards(1, || format!("{place}: {what}"), bound, first);
        }
        if within > 0 || goes_back {
            // as other readers do after a step back: go on from here, so that one bad
            // stamp counts once, not against every message after it
            self.latest = last_in_file;
            self.latest_start = first;
        } else {
            self.latest = self.latest.max(last);
            self.latest_start = self.latest_start.max(first);
        }
    }

    /// Moves the pending events earlier than `before` to `ready`.
    fn release(&mut self, before: TimeUs) {
        let n = self.pending.t.partition_point(|&t| t < before);
        if n == 0 {
            return;
        }
        self.handed_max = self.handed_max.max(self.pending.t[n - 1]);
        for i in 0..n {
            self.ready.push(
                self.pending.t[i],
                self.pending.x[i],
                self.pending.y[i],
                self.pending.on[i],
            );
        }
        self.pending.t.drain(..n);
        self.pending.x.drain(..n);
        self.pending.y.drain(..n);
        self.pending.on.drain(..n);
    }

    /// Merges `incoming` into `pending` (both time-sorted).
    fn merge_incoming(&mut self) {
        if self.pending.is_empty() {
            std::mem::swap(&mut self.pending, &mut self.incoming);
            return;
        }
        let (a, b) = (&self.pending, &self.incoming);
        self.merged.clear();
        let (mut i, mut j) = (0, 0);
        while i < a.len() || j < b.len() {
            let take_a = j == b.len() || (i < a.len() && a.t[i] <= b.t[j]);
            let e = if take_a {
                i += 1;
                a.get(i - 1)
            } else {
                j += 1;
                b.get(j - 1)
            };
            self.merged.push_event(e);
        }
        std::mem::swap(&mut self.pending, &mut self.merged);
    }
}

impl EventDecoder for BagDecoder {
    fn read_chunk(&mut self, out: &mut EventChunk) -> Result<(), InputError> {
        loop {
            if self.handed < self.ready.len() {
                let n =
                    (self.ready.len() - self.handed).min(CHUNK_EVENTS.saturating_sub(out.len()));
                let range = self.handed..self.handed + n;
                out.t.extend_from_slice(&self.ready.t[range.clone()]);
                out.x.extend_from_slice(&self.ready.x[range.clone()]);
                out.y.extend_from_slice(&self.ready.y[range.clone()]);
                out.on.extend_from_slice(&self.ready.on[range]);
                self.handed += n;
                if out.len() >= CHUNK_EVENTS {
                    return Ok(());
                }
            }
            if self.finished {
                return Ok(());
            }
            self.ready.clear();
            self.handed = 0;
            if self.next_message()? {
                if self.out_of_place {
                    // already refused (or to be sorted): hold nothing across it, so that
                    // memory stays one message plus the overlap, and go on from here
                    self.release(TimeUs::MAX);
                    self.handed_max = TimeUs::MIN;
                } else if let Some(&first) = self.incoming.t.first() {
                    self.release(first);
                }
                self.merge_incoming();
            } else {
                self.release_all();
                self.finished = true;
            }
        }
    }

    fn order(&self) -> &OrderCheck {
        &self.order
    }

    fn progress(&self) -> Progress {
        let (done, total) = self.reader.progress();
        Progress { done, total }
    }
}

impl BagDecoder {
    /// Moves every pending event to `ready` (at the end of the bag).
    fn release_all(&mut self) {
        self.release(TimeUs::MAX);
    }
}

/// The image topic's messages, one at a time: (index, stamp, data) to `visit`, which says
/// whether to go on.
fn each_image(
    path: &Path,
    info: &BagInfo,
    mut visit: impl FnMut(usize, &str, &[u8]) -> Result<bool, InputError>,
) -> Result<(), InputError> {
    let Some(topic) = &info.image_topic else {
        return Ok(());
    };
    let mut reader = MessageReader::open(path, info.data_start, info.chunks_end)?;
    let mut ids = TopicIds {
        topic: topic.clone(),
        ids: HashSet::new(),
    };
    let mut index = 0;
    loop {
        let place = reader.place();
        match reader.next_item()? {
            None => return Ok(()),
            Some(Item::Connection(c)) => ids.see(&c),
            Some(Item::Message { connection, data }) if ids.ids.contains(&connection) => {
                let place = format!("topic {topic}, message {} ({place})", index + 1);
                if !visit(index, &place, data)? {
                    return Ok(());
                }
                index += 1;
            }
            Some(_) => {}
        }
    }
}

/// Checks frames as IJRR frame lists are checked: one size, times that never decrease.
fn check_frame(
    path: &Path,
    place: &str,
    frames: &[Frame],
    t: TimeUs,
    size: (u32, u32),
) -> Result<(), InputError> {
    if let Some(previous) = frames.last() {
        if (previous.width, previous.height) != size {
            return Err(InputError::corrupt(
                path,
                place,
                format!(
                    "the image is {}x{}, the first {}x{}",
                    size.0, size.1, previous.width, previous.height
                ),
                "give frames of one size",
            ));
        }
        if t < previous.t {
            return Err(InputError::corrupt(
                path,
                place,
                format!(
                    "the image stamp {t} us is earlier than the image before ({} us)",
                    previous.t
                ),
                "images must be in time order",
            ));
        }
    }
    Ok(())
}

/// The frames whose index and stamp `keep` accepts, decoded to grey.
pub fn frames_where(
    path: &Path,
    info: &BagInfo,
    keep: impl Fn(usize, TimeUs) -> bool,
) -> Result<Vec<Frame>, InputError> {
    let mut frames: Vec<Frame> = Vec::new();
    let mut last_stamp = TimeUs::MIN;
    each_image(path, info, |index, place, data| {
        let t = messages::image_stamp(data)
            .map_err(|p| InputError::corrupt(path, place, p, FIX_TRUNCATED))?;
        if t < last_stamp {
            return Err(InputError::corrupt(
                path,
                place,
                format!(
                    "the image stamp {t} us is earlier than the image before ({last_stamp} us)"
                ),
                "images must be in time order",
            ));
        }
        last_stamp = t;
        if !keep(index, t) {
            return Ok(true);
        }
        let image = messages::image(data, MAX_SENSOR_SIDE as u32)
            .map_err(|p| InputError::corrupt(path, place, p, FIX_TRUNCATED))?;
        check_frame(path, place, &frames, image.t, (image.width, image.height))?;
        frames.push(Frame {
            t: image.t,
            width: image.width,
            height: image.height,
            pixels: image.pixels,
            exposure_us: None,
        });
        Ok(true)
    })?;
    Ok(frames)
}

/// The image stamps, without decoding pixels.
pub fn frame_times(path: &Path, info: &BagInfo) -> Result<Vec<TimeUs>, InputError> {
    let mut times: Vec<TimeUs> = Vec::new();
    each_image(path, info, |_, place, data| {
        let t = messages::image_stamp(data)
            .map_err(|p| InputError::corrupt(path, place, p, FIX_TRUNCATED))?;
        if let Some(&previous) = times.last()
            && t < previous
        {
            return Err(InputError::corrupt(
                path,
                place,
                format!("the image stamp {t} us is earlier than the image before ({previous} us)"),
                "images must be in time order",
            ));
        }
        times.push(t);
        Ok(true)
    })?;
    Ok(times)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn topic(name: &str, message_type: &str) -> Topic {
        Topic {
            name: name.into(),
            message_type: message_type.into(),
            messages: 3,
        }
    }

    #[test]
    fn the_event_topic_is_the_only_one_or_the_one_asked_for() {
        let stereo = [
            topic("/davis/left/events", messages::EVENT_ARRAY),
            topic("/davis/left/image_raw", messages::IMAGE),
            topic("/davis/right/events", messages::EVENT_ARRAY),
        ];
        let (problem, fix) = choose(&stereo, messages::EVENT_ARRAY, None, Hint::Topic).unwrap_err();
        assert!(
            problem.contains("2 dvs_msgs/EventArray topics"),
            "{problem}"
        );
        assert!(
            problem.contains("/davis/left/events, /davis/right/events"),
            "{problem}"
        );
        assert_eq!(fix, Text::default().act(Hint::Topic));
        assert_eq!(
            choose(
                &stereo,
                messages::EVENT_ARRAY,
                Some("/davis/right/events"),
                Hint::Topic
            ),
            Ok("/davis/right/events".to_string())
        );
        assert_eq!(
            choose(&stereo[..2], messages::EVENT_ARRAY, None, Hint::Topic),
            Ok("/davis/left/events".to_string())
        );
        let (problem, _) = choose(
            &stereo,
            messages::EVENT_ARRAY,
            Some("/davis/left/image_raw"),
            Hint::Topic,
        )
        .unwrap_err();
        assert!(problem.contains("carries sensor_msgs/Image"), "{problem}");
        let (problem, _) =
            choose(&stereo[1..2], messages::EVENT_ARRAY, None, Hint::Topic).unwrap_err();
        assert!(
            problem.contains("no dvs_msgs/EventArray topic"),
            "{problem}"
        );
    }

    /// A bag whose event messages are exactly `messages`.
    fn bag_of(messages: &[&[TimeUs]]) -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.bag");
        let mut writer = crate::write::BagWriter::create(
            &path,
            Sensor::new(8, 8),
            crate::write::BagCompression::None,
            &crate::write::OutputPolicy::default(),
        )
        .unwrap();
        for ts in messages {
            let events: EventChunk = ts
                .iter()
                .map(|&t| crate::events::Event {
                    t,
                    x: (t % 8) as u16,
                    y: 1,
                    on: true,
                })
                .collect();
            writer.write_message(&events).unwrap();
        }
        writer.finish().unwrap();
        (dir, path)
    }

    fn decode(path: &Path) -> Result<EventChunk, InputError> {
        crate::Recording::open(path, &crate::OpenOptions::default())?.read_all(false)
    }

    #[test]
    fn overlapping_messages_are_merged_into_time_order() {
        let (_dir, path) = bag_of(&[&[10, 30, 50], &[20, 40, 60], &[55, 70], &[70, 71]]);
        let events = decode(&path).unwrap();
        assert_eq!(events.t, vec![10, 20, 30, 40, 50, 55, 60, 70, 70, 71]);
        assert_eq!(events.x[0], 2);
        // a message that starts before events already handed on is real disorder
        let (_dir, path) = bag_of(&[&[10, 30], &[40, 50], &[20]]);
        match decode(&path) {
            Err(InputError::Unsorted { count, .. }) => assert_eq!(count, 1),
            other => panic!("{other:?}"),
        }
    }
}
