//! An opened recording: format detection, the sensor size (user, file metadata, frames, or
//! inferred from the coordinates), as many streaming passes over its events as needed,
//! its frames and its stimulus.

use super::Format;
use super::{
    EventDecoder, FrameList, InputError, Progress, aedat4, bag, dat, detect, evt2, evt3, h5, ijrr,
    prophesee,
};
use crate::events::{
    CHUNK_EVENTS, EventChunk, Frame, MAX_SENSOR_SIDE, Sensor, TIME_LIMIT_US, TimeUs,
};
use crate::hint::{Hint, Text};
use crate::sensors;
use std::path::{Path, PathBuf};

/// The [`Recording::sensor_source`] of a sensor size the caller gave ([`OpenOptions::sensor`]).
pub const GIVEN_SENSOR: &str = "given";
/// The sensor source of an IJRR folder whose size comes from its grey frames.
pub const FRAMES_SENSOR: &str = "the size of the images in images.txt";

/// Options for opening a recording.
#[derive(Clone, Debug, Default)]
pub struct OpenOptions {
    /// Skip content detection and read as this format.
    pub format: Option<Format>,
    /// The sensor size, overriding what the file says.
    pub sensor: Option<Sensor>,
    /// ROS bags: the events topic and the image topic (default: found by message type).
    pub topic: Option<String>,
    pub image_topic: Option<String>,
    /// MVSEC HDF5: which camera (default left).
    pub side: Option<h5::Side>,
}

#[derive(Clone, Debug)]
enum Source {
    Ijrr(ijrr::IjrrFiles),
    #[cfg(feature = "hdf5")]
    H5(h5::H5Info),
    Aedat4(aedat4::Aedat4Header),
    Evt2 {
        data_offset: u64,
    },
    Evt3 {
        data_offset: u64,
    },
    Dat {
        data_offset: u64,
    },
    Bag(bag::BagInfo),
}

/// An opened recording: its format, what it says about the sensor, and access to its events
/// (as many streaming passes as needed), frames and stimulus.
#[derive(Clone, Debug)]
pub struct Recording {
    pub path: PathBuf,
    pub format: Format,
    /// The sensor size known before reading events (given in [`OpenOptions`], from the file's
    /// metadata or its frames); `None` when it must be inferred from the coordinates.
    pub sensor: Option<Sensor>,
    /// Where [`Self::sensor`] comes from.
    pub sensor_source: Option<String>,
    /// Remarks for the user (e.g. a resolution claim that was corrected).
    pub notes: Vec<String>,
    source: Source,
}

/// The sensor used for a recording after its events were read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ResolvedSensor {
    pub sensor: Sensor,
    pub source: String,
    /// Set when the size was guessed from the coordinates.
    pub warning: Option<Text>,
}

/// An IJRR folder's files and the sensor size its first line, frames or stimulus give.
/// A `width height` line that gives no sensor is an error unless the size is `given`.
fn ijrr_source(path: &Path, given: bool) -> Result<(Source, Option<(Sensor, String)>), InputError> {
    let files = ijrr::IjrrFiles::locate(path)?;
    let header = ijrr::read_header(&files.events)?;
    if let Some(e) = header.unusable
        && !given
    {
        return Err(e);
    }
    let mut sensor = header
        .sensor
        .map(|s| (s, "the `width height` first line of events.txt".to_string()));
    // frames (or, for an on-screen recording, the stimulus mapped 1:1 onto the
    // sensor) give the size
    for (index, origin) in [
        (&files.images, FRAMES_SENSOR),
        (
            &files.stimulus,
            "the size of the stimulus in stimulus.txt (screen mapped 1:1)",
        ),
    ] {
        if sensor.is_none()
            && let Some(index) = index
            && let Some((w, h)) = FrameList::read(index)?.image_size()?
        {
            let (w, h) = (
                u16::try_from(w).unwrap_or(u16::MAX),
                u16::try_from(h).unwrap_or(u16::MAX),
            );
            sensor = Some((Sensor::new(w, h), origin.to_string()));
        }
    }
    Ok((Source::Ijrr(files), sensor))
}

/// The sensor a Prophesee header states. A stated size that is no sensor is an error
/// unless the size is `given` (then a note says it is not used).
fn prophesee_sensor(
    path: &Path,
    header: &prophesee::PropheseeHeader,
    given: Option<Sensor>,
    notes: &mut Vec<String>,
) -> Result<Option<(Sensor, String)>, InputError> {
    match (header.sensor(), given) {
        (Ok(sensor), _) => Ok(sensor),
        (Err(unusable), Some(given)) => {
            notes.push(format!(
                "header line {}: {}; the sensor size given ({given}) is used",
                unusable.line,
                unusable.problem()
            ));
            Ok(None)
        }
        (Err(unusable), None) => Err(unusable.error(path)),
    }
}

/// A bag's topics (its notes to `notes`) and the sensor its first event message states.
fn bag_source(
    path: &Path,
    options: &OpenOptions,
    notes: &mut Vec<String>,
) -> Result<(Source, Option<(Sensor, String)>), InputError> {
    let info = bag::probe(
        path,
        &bag::TopicChoice {
            events: options.topic.clone(),
            images: options.image_topic.clone(),
        },
    )?;
    notes.extend(info.notes.iter().cloned());
    let sensor = info.sensor.map(|s| {
        (
            s,
            "width/height of the first dvs_msgs/EventArray message".to_string(),
        )
    });
    Ok((Source::Bag(info), sensor))
}

/// An HDF5 file's layout (its notes to `notes`) and the sensor size it states.
#[cfg(feature = "hdf5")]
fn h5_source(
    path: &Path,
    options: &OpenOptions,
    notes: &mut Vec<String>,
) -> Result<(Source, Option<(Sensor, String)>), InputError> {
    let info = h5::probe(path, options.side.unwrap_or_default())?;
    let sensor = info.sensor.map(|s| {
        (
            s,
            info.sensor_note
                .clone()
                .unwrap_or_else(|| "sensor_resolution".into()),
        )
    });
    if let Some(note) = &info.sensor_note
        && note.contains("(W, H)")
    {
        notes.push(note.clone());
    }
    notes.extend(info.notes.iter().cloned());
    Ok((Source::H5(info), sensor))
}

/// An AEDAT4 header and the event stream's sensor size (an unusable one noted if given).
fn aedat4_source(
    path: &Path,
    options: &OpenOptions,
    notes: &mut Vec<String>,
) -> Result<(Source, Option<(Sensor, String)>), InputError> {
    let header = aedat4::Aedat4Header::read(path)?;
    if let (Some(unusable), Some(given)) = (header.unusable_event_size(), options.sensor) {
        notes.push(format!(
            "{unusable}; the sensor size given ({given}) is used"
        ));
    }
    let sensor = header.event_sensor().map(|s| {
        (
            s,
            "sizeX/sizeY of the event stream in the AEDAT4 header".to_string(),
        )
    });
    Ok((Source::Aedat4(header), sensor))
}

impl Recording {
    /// Opens `path`, detecting its format from content unless `options.format` is set.
    pub fn open(path: &Path, options: &OpenOptions) -> Result<Self, InputError> {
        if !path.exists() {
            return Err(InputError::NotFound {
                path: path.to_path_buf(),
            });
        }
        let format = Self::format_of(path, options)?;
        let mut notes = Vec::new();
        let (source, file_sensor) = Self::probe(path, format, options, &mut notes)?;
        let (sensor, sensor_source) = Self::sensor_of(path, options, file_sensor, &mut notes)?;
        Ok(Self {
            path: path.to_path_buf(),
            format,
            sensor,
            sensor_source,
            notes,
            source,
        })
    }

    /// The format forced by `options` (checked against the content) or detected.
    fn format_of(path: &Path, options: &OpenOptions) -> Result<Format, InputError> {
        Ok(match options.format {
            Some(forced) => {
                // the content may still say what it is: a forced format that does not fit is
                // named as such, rather than reported later as damage
                if !path.is_dir() {
                    crate::files::check_regular(path)
                        .map_err(|e| InputError::not_a_file(path, e))?;
                }
                match detect(path) {
                    Ok(found) if found != forced => {
                        return Err(InputError::invalid(
                            path,
                            Text::default()
                                .name(Hint::Format(Some(forced)))
                                .words(format!(" does not fit: the content is {found}")),
                            Text::from("drop ")
                                .name(Hint::Format(None))
                                .words(" (ctcal detects the format from the content), or give the right one"),
                        ));
                    }
                    _ => forced,
                }
            }
            None => detect(path)?,
        })
    }

    /// The format's reader state and the sensor size the file claims, with where it says
    /// so; what the probe warns of goes to `notes`.
    fn probe(
        path: &Path,
        format: Format,
        options: &OpenOptions,
        notes: &mut Vec<String>,
    ) -> Result<(Source, Option<(Sensor, String)>), InputError> {
        Ok(match format {
            Format::Ijrr => ijrr_source(path, options.sensor.is_some())?,
            Format::Bag => bag_source(path, options, notes)?,
            #[cfg(not(feature = "hdf5"))]
            Format::H5 => {
                return Err(InputError::hdf5(
                    path,
                    "this build of ctcal-io reads no HDF5 (built without its feature `hdf5`)",
                    "build ctcal-io with its default feature `hdf5` (libhdf5-dev installed), or convert the file to another format with a full ctcal build",
                ));
            }
            #[cfg(feature = "hdf5")]
            Format::H5 => h5_source(path, options, notes)?,
            Format::Aedat4 => aedat4_source(path, options, notes)?,
            Format::Evt2 | Format::Evt3 | Format::Dat => {
                let header = prophesee::PropheseeHeader::read(path)?;
                let sensor = prophesee_sensor(path, &header, options.sensor, notes)?;
                let data_offset = header.length;
                let source = match format {
                    Format::Evt2 => Source::Evt2 { data_offset },
                    Format::Evt3 => Source::Evt3 { data_offset },
                    _ => Source::Dat { data_offset },
                };
                (source, sensor)
            }
        })
    }

    /// The sensor size given (over the file's, said in `notes`) or the file's, refused
    /// where the file claims one larger than any sensor.
    fn sensor_of(
        path: &Path,
        options: &OpenOptions,
        file_sensor: Option<(Sensor, String)>,
        notes: &mut Vec<String>,
    ) -> Result<(Option<Sensor>, Option<String>), InputError> {
        Ok(match (options.sensor, file_sensor) {
            (Some(s), Some((claimed, _))) if s != claimed => {
                notes.push(format!(
                    "the sensor size given ({s}) overrides the file's {claimed}"
                ));
                (Some(s), Some(GIVEN_SENSOR.to_string()))
            }
            (Some(s), _) => (Some(s), Some(GIVEN_SENSOR.to_string())),
            (None, Some((s, origin))) => {
                if !s.is_plausible() {
                    return Err(InputError::invalid(
                        path,
                        format!(
                            "{origin} says the sensor is {s}, larger than {MAX_SENSOR_SIDE}x{MAX_SENSOR_SIDE} (more than any sensor sold)"
                        ),
                        Text::from("if the header is damaged, ")
                            .act(Hint::Sensor(None))
                            .words(format!(" with the camera's real size; if the sensor really is {s}, "))
                            .act(Hint::Sensor(Some(s)))
                            .words(" (statistics then keep per-pixel state only for the area the events reach)"),
                    ));
                }
                (Some(s), Some(origin))
            }
            (None, None) => (None, None),
        })
    }

    /// A fresh stream over the events (each call starts at the beginning).
    pub fn events(&self) -> Result<EventStream, InputError> {
        self.stream(None)
    }

    /// The time of the first event (a seek and one value for indexed layouts, the first
    /// chunk otherwise).
    pub fn first_event_time(&self) -> Result<TimeUs, InputError> {
        #[cfg(feature = "hdf5")]
        if let Source::H5(info) = &self.source
            && let Some(t) = h5::first_time(&self.path, info)?
        {
            return Ok(t);
        }
        let mut stream = self.events()?;
        stream.allow_unsorted = true;
        Ok(stream
            .next_chunk()?
            .map(|c| c.t[0])
            .expect("a stream that is not empty"))
    }

    /// A stream that holds at least the events of times `from..=to` (file clock), seeking
    /// with the file's own index where it has one (DSEC, MVSEC), else from the start; the
    /// caller trims to the window. An empty window is not an error here.
    pub fn events_between(&self, from: TimeUs, to: TimeUs) -> Result<EventStream, InputError> {
        let (rows, note) = self.indexed_rows(from, to)?;
        let mut stream = self.stream(rows)?;
        stream.allow_empty = true;
        stream.notes.extend(note);
        Ok(stream)
    }

    /// The rows holding times `from..=to` where the file has an index (DSEC, MVSEC), and
    /// a note on how they were found; none (read from the start) otherwise.
    #[cfg_attr(not(feature = "hdf5"), allow(unused_variables))]
    fn indexed_rows(
        &self,
        from: TimeUs,
        to: TimeUs,
    ) -> Result<(Option<std::ops::Range<usize>>, Option<String>), InputError> {
        #[cfg(feature = "hdf5")]
        if let Source::H5(info) = &self.source
            && let Some((rows, note)) = h5::index_window(&self.path, info, from, to)?
        {
            return Ok((Some(rows), note));
        }
        Ok((None, None))
    }

    #[cfg_attr(not(feature = "hdf5"), allow(unused_variables))]
    fn stream(&self, rows: Option<std::ops::Range<usize>>) -> Result<EventStream, InputError> {
        let decoder: Box<dyn EventDecoder> = match &self.source {
            Source::Ijrr(files) => Box::new(ijrr::IjrrDecoder::open(&files.events, self.sensor)?),
            #[cfg(feature = "hdf5")]
            Source::H5(info) => Box::new(h5::H5Decoder::open_rows(
                &self.path,
                info,
                self.sensor,
                rows.unwrap_or(0..info.events),
            )?),
            Source::Aedat4(header) => Box::new(aedat4::Aedat4Decoder::open(
                &self.path,
                header,
                self.sensor,
            )?),
            Source::Evt2 { data_offset } => Box::new(evt2::Evt2Decoder::open(
                &self.path,
                *data_offset,
                self.sensor,
            )?),
            Source::Evt3 { data_offset } => Box::new(evt3::Evt3Decoder::open(
                &self.path,
                *data_offset,
                self.sensor,
            )?),
            Source::Dat { data_offset } => Box::new(dat::DatDecoder::open(
                &self.path,
                *data_offset,
                self.sensor,
            )?),
            Source::Bag(info) => Box::new(bag::BagDecoder::open(&self.path, info, self.sensor)?),
        };
        Ok(EventStream {
            decoder,
            path: self.event_file().to_path_buf(),
            chunk: EventChunk::with_capacity(CHUNK_EVENTS),
            events: 0,
            max_x: None,
            max_y: 0,
            allow_unsorted: false,
            allow_empty: false,
            notes: Vec::new(),
        })
    }

    /// The sensor biases saved in or beside the recording ([`super::biases`]).
    pub fn biases(&self) -> Option<super::Biases> {
        let prophesee = matches!(self.format, Format::Evt2 | Format::Evt3 | Format::Dat);
        super::biases::find(self.event_file(), prophesee)
    }

    /// The file holding the events (`events.txt` for IJRR folders).
    pub fn event_file(&self) -> &Path {
        match &self.source {
            Source::Ijrr(files) => &files.events,
            _ => &self.path,
        }
    }

    /// Every event in memory, sorted by time when `sort` (stable); an unsorted file is an
    /// error unless `sort`.
    pub fn read_all(&self, sort: bool) -> Result<EventChunk, InputError> {
        let mut stream = self.events()?;
        stream.allow_unsorted = sort;
        let mut all = EventChunk::default();
        while let Some(chunk) = stream.next_chunk()? {
            all.extend_from(chunk);
        }
        if sort {
            all.sort_by_time();
        }
        Ok(all)
    }

    /// The sensor for this recording once its largest coordinates are known: the known
    /// sensor, else the smallest preset that contains every event (with a warning).
    pub fn resolve_sensor(&self, max_coordinates: Option<(u16, u16)>) -> ResolvedSensor {
        if let Some(sensor) = self.sensor {
            return ResolvedSensor {
                sensor,
                source: self.sensor_source.clone().unwrap_or_default(),
                warning: None,
            };
        }
        let (max_x, max_y) = max_coordinates.unwrap_or((0, 0));
        let unstated = self.unstated_size();
        match sensors::smallest_containing(max_x, max_y) {
            Some(preset) => ResolvedSensor {
                sensor: preset.sensor(),
                source: format!("inferred: {} ({})", preset.name, preset.sensor()),
                warning: Some(
                    Text::from(format!(
                        "{}: {unstated}; using {} ({}), the smallest known sensor containing every event (x up to {max_x}, y up to {max_y}); ",
                        self.path.display(),
                        preset.name,
                        preset.sensor()
                    ))
                    .act(Hint::Sensor(None))
                    .words(" if that is wrong"),
                ),
            },
            None => {
                let sensor = Sensor::new(max_x.saturating_add(1), max_y.saturating_add(1));
                ResolvedSensor {
                    sensor,
                    source: format!("inferred: {sensor} from the coordinates"),
                    warning: Some(
                        Text::from(format!(
                            "{}: {unstated} and no known sensor contains x up to {max_x}, y up to {max_y}; using {sensor}; ",
                            self.path.display()
                        ))
                        .act(Hint::Sensor(None)),
                    ),
                }
            }
        }
    }

    /// Why the file gives no sensor size: it states none, or (AEDAT4) one that is no sensor.
    fn unstated_size(&self) -> String {
        match &self.source {
            Source::Aedat4(header) => header
                .unusable_event_size()
                .map(|why| format!("{why}, so it is not used")),
            _ => None,
        }
        .unwrap_or_else(|| "the file does not state the sensor size".into())
    }

    /// Decodes every frame (APS images) of the recording.
    pub fn frames(&self) -> Result<Vec<Frame>, InputError> {
        match &self.source {
            Source::Ijrr(files) => match &files.images {
                Some(images) => FrameList::read(images)?.load_all(),
                None => Ok(Vec::new()),
            },
            #[cfg(feature = "hdf5")]
            Source::H5(info) => h5::read_frames(&self.path, info),
            Source::Aedat4(header) => aedat4::read_frames(&self.path, header),
            Source::Bag(info) => bag::frames_where(&self.path, info, |_, _| true),
            _ => Ok(Vec::new()),
        }
    }

    /// The frames whose index and time `keep` accepts, decoded (the others are not kept in
    /// memory).
    pub fn frames_where(
        &self,
        keep: impl Fn(usize, TimeUs) -> bool,
    ) -> Result<Vec<Frame>, InputError> {
        match &self.source {
            Source::Ijrr(files) => match &files.images {
                Some(images) => {
                    let list = FrameList::read(images)?;
                    let mut frames = Vec::new();
                    for (i, entry) in list.entries.iter().enumerate() {
                        if keep(i, entry.t) {
                            frames.push(list.load(i)?);
                        }
                    }
                    if let Some(first) = frames.first()
                        && let Some(other) = frames
                            .iter()
                            .find(|f| (f.width, f.height) != (first.width, first.height))
                    {
                        return Err(InputError::corrupt(
                            images,
                            format!("frame at {} us", other.t),
                            format!(
                                "the image is {}x{}, the first {}x{}",
                                other.width, other.height, first.width, first.height
                            ),
                            "give frames of one size",
                        ));
                    }
                    Ok(frames)
                }
                None => Ok(Vec::new()),
            },
            #[cfg(feature = "hdf5")]
            Source::H5(info) => Ok(h5::read_frames(&self.path, info)?
                .into_iter()
                .enumerate()
                .filter(|(i, f)| keep(*i, f.t))
                .map(|(_, f)| f)
                .collect()),
            Source::Aedat4(header) => aedat4::read_frames_where(&self.path, header, keep),
            Source::Bag(info) => bag::frames_where(&self.path, info, keep),
            _ => Ok(Vec::new()),
        }
    }

    /// The pixels of the frames, where known without decoding more than one: an IJRR
    /// folder's frame `index` (one image file), else the sensor the file states (which a
    /// window's frames must match to be read at all). `None` where neither is known.
    pub fn frame_pixels(&self, index: usize) -> Result<Option<usize>, InputError> {
        if let Source::Ijrr(files) = &self.source
            && let Some(images) = &files.images
        {
            let list = FrameList::read(images)?;
            if index >= list.entries.len() {
                return Ok(None);
            }
            let frame = list.load(index)?;
            return Ok(Some(frame.width as usize * frame.height as usize));
        }
        Ok(self.sensor.map(|s| s.pixels()))
    }

    /// Frame timestamps (without decoding images where the format allows).
    pub fn frame_times(&self) -> Result<Vec<TimeUs>, InputError> {
        match &self.source {
            Source::Ijrr(files) => match &files.images {
                Some(images) => Ok(FrameList::read(images)?.times()),
                None => Ok(Vec::new()),
            },
            #[cfg(feature = "hdf5")]
            Source::H5(info) => h5::read_frame_times(&self.path, info),
            Source::Aedat4(header) => aedat4::read_frame_times(&self.path, header),
            Source::Bag(info) => bag::frame_times(&self.path, info),
            _ => Ok(Vec::new()),
        }
    }

    /// The HDF5 layout (event_utils, v2e, MVSEC, DSEC), for HDF5 files.
    pub fn layout(&self) -> Option<&'static str> {
        match &self.source {
            #[cfg(feature = "hdf5")]
            Source::H5(info) => Some(info.layout.name()),
            _ => None,
        }
    }

    /// The topics of a ROS bag (empty for other formats).
    pub fn topics(&self) -> &[bag::Topic] {
        match &self.source {
            Source::Bag(info) => &info.topics,
            _ => &[],
        }
    }

    /// The on-screen stimulus of an IJRR folder (`stimulus.txt`), if it has one.
    pub fn stimulus(&self) -> Result<Option<FrameList>, InputError> {
        match &self.source {
            Source::Ijrr(files) => files.stimulus.as_deref().map(FrameList::read).transpose(),
            _ => Ok(None),
        }
    }
}

/// A pass over a recording's events, chunk by chunk, that checks at the end that the file
/// was not empty and (unless allowed) that time never went backwards.
pub struct EventStream {
    decoder: Box<dyn EventDecoder>,
    path: PathBuf,
    chunk: EventChunk,
    events: u64,
    max_x: Option<u16>,
    max_y: u16,
    /// Accept decreasing timestamps (the caller sorts).
    pub allow_unsorted: bool,
    /// A stream without events ends quietly (a window the caller checks) rather than with
    /// [`InputError::Empty`].
    pub allow_empty: bool,
    /// Remarks for the user (e.g. a file index that contradicts the times and was not used).
    pub notes: Vec<String>,
}

impl EventStream {
    /// The next chunk of events; `None` after the last.
    pub fn next_chunk(&mut self) -> Result<Option<&EventChunk>, InputError> {
        self.chunk.clear();
        self.decoder.read_chunk(&mut self.chunk)?;
        if let Some((place, t)) = &self.decoder.order().out_of_range {
            return Err(InputError::corrupt(
                &self.path,
                place.clone(),
                format!(
                    "timestamp {t} us lies beyond +-{TIME_LIMIT_US} us (about 73,000 years) of zero"
                ),
                "the file is damaged at this place; cut the recording before it or copy it again from the source",
            ));
        }
        if self.chunk.is_empty() {
            if self.events == 0 && !self.allow_empty {
                return Err(InputError::Empty {
                    path: self.path.clone(),
                });
            }
            self.check_order()?;
            return Ok(None);
        }
        self.events += self.chunk.len() as u64;
        if let Some((x, y)) = self.chunk.max_coordinates() {
            self.max_x = Some(self.max_x.map_or(x, |m| m.max(x)));
            self.max_y = self.max_y.max(y);
        }
        Ok(Some(&self.chunk))
    }

    /// An error if the events read so far went back in time (unless unsorted events are
    /// allowed): checked at the end of the stream, and by a reader that stops early.
    pub fn check_order(&self) -> Result<(), InputError> {
        let order = self.decoder.order();
        if order.backwards > 0
            && !self.allow_unsorted
            && let Some((place, previous_us, t_us)) = order.first.clone()
        {
            return Err(InputError::Unsorted {
                path: self.path.clone(),
                count: order.backwards,
                place,
                previous_us,
                t_us,
            });
        }
        Ok(())
    }

    /// The chunk the last [`Self::next_chunk`] returned.
    pub fn current_chunk(&self) -> &EventChunk {
        &self.chunk
    }

    /// Like [`Self::next_chunk`] but hands over the filled chunk, keeping `spare` as the
    /// buffer for the next one (for passing chunks to another thread without copying).
    pub fn next_chunk_swapped(
        &mut self,
        spare: EventChunk,
    ) -> Result<Option<EventChunk>, InputError> {
        if self.next_chunk()?.is_none() {
            return Ok(None);
        }
        let mut spare = spare;
        spare.clear();
        Ok(Some(std::mem::replace(&mut self.chunk, spare)))
    }

    /// Events delivered so far.
    pub fn events_read(&self) -> u64 {
        self.events
    }

    /// Largest x and y delivered so far.
    pub fn max_coordinates(&self) -> Option<(u16, u16)> {
        self.max_x.map(|x| (x, self.max_y))
    }

    /// Timestamps that went backwards so far.
    pub fn unsorted_count(&self) -> u64 {
        self.decoder.order().backwards
    }

    pub fn progress(&self) -> Progress {
        self.decoder.progress()
    }
}
