//! HDF5 event files in the two layouts researchers meet most:
//!
//! - event_utils / event_cnn_minimal (Stoffregen et al. 2020): `events/ts` (float64 seconds;
//!   integer timestamps, which some writers store, are read as microseconds),
//!   `events/xs`, `events/ys` (integers), `events/ps` (bool or 0/1 or -1/1), frames as
//!   `images/image%09d` with a `timestamp` attribute in seconds, and a root attribute
//!   `sensor_resolution` = (H, W). Writers disagree on that order, so the claim is checked
//!   against the coordinates and swapped when only the swapped reading contains them;
//! - v2e: `events` N x 4 unsigned `[t_us, x, y, p]`, frames in `frame` (N, H, W) with
//!   `frame_ts` in microseconds.
//!
//! Read through `hdf5-metno` (libhdf5) in chunks of `CHUNK_EVENTS` rows.

use super::error::InputError;
use super::h5_direct::{DirectColumn, ElementKind};
use super::order::OrderCheck;
use super::{EventDecoder, Progress};
use crate::events::{CHUNK_EVENTS, EventChunk, Frame, Sensor, TimeUs};
use hdf5::types::TypeDescriptor;
use std::path::{Path, PathBuf};

/// HDF5 signature at the start of a file.
pub const SIGNATURE: &[u8] = b"\x89HDF\r\n\x1a\n";

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    EventUtils,
    V2e,
}

/// What an HDF5 event file holds, checked against its data.
#[derive(Clone, Debug)]
pub struct H5Info {
    pub layout: Layout,
    pub events: usize,
    /// The sensor after checking the file's claim against the coordinates.
    pub sensor: Option<Sensor>,
    /// How the sensor is known (or why the claim was changed).
    pub sensor_note: Option<String>,
    pub frame_count: usize,
}

fn h5_error(path: &Path, what: &str, e: hdf5::Error) -> InputError {
    InputError::hdf5(
        path,
        format!("{what}: {e}"),
        "check that the file is a complete event_utils or v2e HDF5 file (h5ls -r shows its layout)",
    )
}

fn open_file(path: &Path) -> Result<hdf5::File, InputError> {
    if !path.exists() {
        return Err(InputError::NotFound {
            path: path.to_path_buf(),
        });
    }
    hdf5::File::open(path).map_err(|e| h5_error(path, "cannot open", e))
}

fn missing(path: &Path, what: &str) -> InputError {
    InputError::hdf5(
        path,
        format!("no {what}"),
        "ctcal reads the event_utils layout (events/ts, events/xs, events/ys, events/ps) and the v2e layout (events: N x 4 [t_us, x, y, p])",
    )
}

fn layout_of(path: &Path, file: &hdf5::File) -> Result<Layout, InputError> {
    if let Ok(group) = file.group("events") {
        for name in ["ts", "xs", "ys", "ps"] {
            if !group.link_exists(name) {
                return Err(missing(path, &format!("dataset events/{name}")));
            }
        }
        return Ok(Layout::EventUtils);
    }
    if let Ok(ds) = file.dataset("events") {
        let shape = ds.shape();
        if shape.len() == 2 && shape[1] == 4 {
            return Ok(Layout::V2e);
        }
        return Err(InputError::hdf5(
            path,
            format!("dataset `events` has shape {shape:?}, expected N x 4"),
            "v2e files store events as N rows of [t_us, x, y, p]",
        ));
    }
    Err(missing(
        path,
        "group `events` (event_utils) or dataset `events` (v2e)",
    ))
}

/// One 1-D column of an event_utils file: read by direct chunk access and parallel
/// inflation where the layout allows ([`super::h5_direct`]), through libhdf5 otherwise.
/// Results go into caller buffers, which are reused from chunk to chunk.
struct Column {
    dataset: hdf5::Dataset,
    direct: Option<(DirectColumn, ElementKind)>,
}

impl Column {
    fn open(path: &Path, file: &hdf5::File, name: &str) -> hdf5::Result<Self> {
        let dataset = file.dataset(name)?;
        let kind = dataset.dtype().ok().and_then(|d| ElementKind::of(&d));
        let direct = DirectColumn::new(path, &dataset).zip(kind);
        Ok(Self { dataset, direct })
    }

    /// The raw bytes of `range` into `bytes`, when the direct path can read it.
    fn raw(&self, range: &std::ops::Range<usize>, bytes: &mut Vec<u8>) -> Option<ElementKind> {
        let (column, kind) = self.direct.as_ref()?;
        column.read_into(range.clone(), bytes).map(|_| *kind)
    }

    /// Appends the values of `range` as i64, whatever the stored type: integers as they are,
    /// floats that hold an integer converted, any other float (NaN, infinite, fractional)
    /// as [`NOT_AN_INTEGER`].
    fn ints(
        &self,
        range: std::ops::Range<usize>,
        bytes: &mut Vec<u8>,
        out: &mut Vec<i64>,
    ) -> hdf5::Result<()> {
        if let Some(kind) = self.raw(&range, bytes) {
            kind.decode(bytes, out, |v| v, float_to_int);
            return Ok(());
        }
        match self.dataset.dtype()?.to_descriptor()? {
            TypeDescriptor::Boolean => out.extend(
                self.dataset
                    .read_slice_1d::<bool, _>(range)?
                    .iter()
                    .map(|&b| b as i64),
            ),
            TypeDescriptor::Float(_) => out.extend(
                self.dataset
                    .read_slice_1d::<f64, _>(range)?
                    .iter()
                    .map(|&f| float_to_int(f)),
            ),
            _ => out.extend(self.dataset.read_slice_1d::<i64, _>(range)?.iter()),
        }
        Ok(())
    }

    /// Appends the values of `range` as f64.
    fn floats(
        &self,
        range: std::ops::Range<usize>,
        bytes: &mut Vec<u8>,
        out: &mut Vec<f64>,
    ) -> hdf5::Result<()> {
        match self.raw(&range, bytes) {
            Some(kind) => kind.decode(bytes, out, |v| v as f64, |f| f),
            None => out.extend(self.dataset.read_slice_1d::<f64, _>(range)?.iter()),
        }
        Ok(())
    }
}

/// Marks a float coordinate or polarity that is not an integer (NaN, infinite, fractional).
const NOT_AN_INTEGER: i64 = i64::MIN;

fn float_to_int(f: f64) -> i64 {
    if f.is_finite() && f.fract() == 0.0 && f.abs() < 9e18 {
        f as i64
    } else {
        NOT_AN_INTEGER
    }
}

/// A stored value for messages (`NaN or a fraction` for [`NOT_AN_INTEGER`]).
fn shown(v: i64) -> String {
    if v == NOT_AN_INTEGER {
        "NaN, infinite or not an integer".into()
    } else {
        v.to_string()
    }
}

/// Reused buffers of the HDF5 reader.
#[derive(Default)]
struct Buffers {
    bytes: Vec<u8>,
    seconds: Vec<f64>,
}

/// The four columns of an event_utils file.
struct EventColumns {
    /// `events/ts` holds integers: microseconds rather than seconds.
    integer_times: bool,
    ts: Column,
    xs: Column,
    ys: Column,
    ps: Column,
}

/// The four event columns of an event_utils file, or the N x 4 table of a v2e file.
enum EventTable {
    EventUtils(Box<EventColumns>),
    V2e(hdf5::Dataset),
}

/// Where each event field is stored, for messages.
struct FieldNames {
    t: &'static str,
    x: &'static str,
    y: &'static str,
    p: &'static str,
}

impl EventTable {
    fn names(&self) -> FieldNames {
        match self {
            EventTable::EventUtils(_) => FieldNames {
                t: "events/ts",
                x: "events/xs",
                y: "events/ys",
                p: "events/ps",
            },
            EventTable::V2e(_) => FieldNames {
                t: "events[:, 0]",
                x: "events[:, 1]",
                y: "events[:, 2]",
                p: "events[:, 3]",
            },
        }
    }

    fn open(path: &Path, file: &hdf5::File, layout: Layout) -> hdf5::Result<Self> {
        Ok(match layout {
            Layout::EventUtils => EventTable::EventUtils(Box::new(EventColumns {
                integer_times: matches!(
                    file.dataset("events/ts")?.dtype()?.to_descriptor()?,
                    TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_)
                ),
                ts: Column::open(path, file, "events/ts")?,
                xs: Column::open(path, file, "events/xs")?,
                ys: Column::open(path, file, "events/ys")?,
                ps: Column::open(path, file, "events/ps")?,
            })),
            Layout::V2e => EventTable::V2e(file.dataset("events")?),
        })
    }

    /// Replaces `columns.x` and `columns.y` with the coordinates of `range`.
    fn coordinates(
        &self,
        range: std::ops::Range<usize>,
        buffers: &mut Buffers,
        columns: &mut Columns,
    ) -> hdf5::Result<()> {
        columns.x.clear();
        columns.y.clear();
        match self {
            EventTable::EventUtils(c) => {
                c.xs.ints(range.clone(), &mut buffers.bytes, &mut columns.x)?;
                c.ys.ints(range, &mut buffers.bytes, &mut columns.y)?;
            }
            EventTable::V2e(ds) => {
                let rows = ds.read_slice_2d::<i64, _>(ndarray::s![range, 1..3])?;
                columns.x.extend(rows.column(0).iter());
                columns.y.extend(rows.column(1).iter());
            }
        }
        Ok(())
    }

    /// Replaces `columns` with the events of `range`.
    fn read(
        &self,
        range: std::ops::Range<usize>,
        buffers: &mut Buffers,
        columns: &mut Columns,
    ) -> hdf5::Result<()> {
        columns.t.clear();
        columns.p.clear();
        match self {
            EventTable::EventUtils(c) => {
                if c.integer_times {
                    // integer timestamps are microseconds (seconds as integers make no sense)
                    c.ts.ints(range.clone(), &mut buffers.bytes, &mut columns.t)?;
                    c.ps.ints(range.clone(), &mut buffers.bytes, &mut columns.p)?;
                    return self.coordinates(range, buffers, columns);
                }
                buffers.seconds.clear();
                c.ts.floats(range.clone(), &mut buffers.bytes, &mut buffers.seconds)?;
                // a non-finite time becomes i64::MIN and is reported by read_chunk
                columns.t.extend(buffers.seconds.iter().map(|&s| {
                    if s.is_finite() {
                        crate::events::s_to_us(s)
                    } else {
                        TimeUs::MIN
                    }
                }));
                c.ps.ints(range.clone(), &mut buffers.bytes, &mut columns.p)?;
                self.coordinates(range, buffers, columns)
            }
            EventTable::V2e(ds) => {
                let rows = ds.read_slice_2d::<i64, _>(ndarray::s![range, ..])?;
                columns.t.extend(rows.column(0).iter());
                columns.x.clear();
                columns.y.clear();
                columns.x.extend(rows.column(1).iter());
                columns.y.extend(rows.column(2).iter());
                columns.p.extend(rows.column(3).iter());
                Ok(())
            }
        }
    }
}

/// The claimed `sensor_resolution` (H, W), as an attribute or a dataset.
fn claimed_resolution(file: &hdf5::File) -> Option<(u16, u16)> {
    let values: Vec<i64> = file
        .attr("sensor_resolution")
        .ok()
        .and_then(|a| a.read_raw::<i64>().ok())
        .or_else(|| {
            file.dataset("sensor_resolution")
                .ok()
                .and_then(|d| d.read_raw::<i64>().ok())
        })?;
    match values.as_slice() {
        [h, w, ..] if *h > 0 && *w > 0 => Some((u16::try_from(*h).ok()?, u16::try_from(*w).ok()?)),
        _ => None,
    }
}

/// Largest x and y (and whether any coordinate is negative), over the whole file.
fn coordinate_extent(
    path: &Path,
    file: &hdf5::File,
    layout: Layout,
    n: usize,
) -> Result<(i64, i64), InputError> {
    let table = EventTable::open(path, file, layout)
        .map_err(|e| h5_error(path, "opening the event datasets", e))?;
    let (mut buffers, mut columns) = (Buffers::default(), Columns::default());
    let mut max_x = -1i64;
    let mut max_y = -1i64;
    let mut start = 0;
    while start < n {
        let end = (start + CHUNK_EVENTS).min(n);
        table
            .coordinates(start..end, &mut buffers, &mut columns)
            .map_err(|e| h5_error(path, "reading coordinates", e))?;
        let (xs, ys) = (&columns.x, &columns.y);
        for (i, (&x, &y)) in xs.iter().zip(ys).enumerate() {
            if x < 0 || y < 0 || x > u16::MAX as i64 || y > u16::MAX as i64 {
                return Err(InputError::corrupt(
                    path,
                    format!("event index {}", start + i),
                    format!(
                        "coordinate out of range (x = {}, y = {})",
                        shown(x),
                        shown(y)
                    ),
                    "the file is damaged or uses another coordinate convention; rewrite it with whole x, y in 0..W-1, 0..H-1",
                ));
            }
            max_x = max_x.max(x);
            max_y = max_y.max(y);
        }
        start = end;
    }
    Ok((max_x, max_y))
}

/// The filters h5py and PyTables users meet, by HDF5 filter id.
fn filter_name(id: i32) -> String {
    match id {
        32000 => "LZF (h5py's compression=\"lzf\", filter 32000)".into(),
        32001 => "Blosc (filter 32001)".into(),
        32004 => "LZ4 (filter 32004)".into(),
        32008 => "bitshuffle (filter 32008)".into(),
        32015 => "Zstandard (filter 32015)".into(),
        other => format!("filter {other}"),
    }
}

/// The largest chunk ctcal reads (libhdf5 and the direct reader hold one whole chunk).
const MAX_CHUNK_BYTES: f64 = 256e6;

/// Checks a dataset before anything is allocated from what it claims: its rank, that
/// libhdf5 can undo its filters, and that its logical size is plausible for the bytes it
/// stores (deflate cannot compress more than about 1032:1, so a dataset claiming far more
/// than 1100 times its stored bytes is damage, not data). Returns its shape.
fn check_dataset(
    path: &Path,
    file: &hdf5::File,
    name: &str,
    rank: usize,
) -> Result<Vec<usize>, InputError> {
    let ds = file.dataset(name).map_err(|e| h5_error(path, name, e))?;
    let shape = ds.shape();
    if shape.len() != rank {
        let what = if shape.is_empty() {
            "a scalar".to_string()
        } else {
            format!("{}-dimensional (shape {shape:?})", shape.len())
        };
        return Err(InputError::hdf5(
            path,
            format!("{name} is {what}; ctcal expects a {rank}-dimensional dataset"),
            "check that the file is an event_utils or v2e HDF5 file (h5ls -r shows its layout)",
        ));
    }
    for filter in ds.filters() {
        if !filter.decode_enabled() {
            return Err(InputError::hdf5(
                path,
                format!(
                    "{name} is compressed with {}, which this libhdf5 cannot decompress",
                    filter_name(filter.id())
                ),
                "rewrite the file with gzip compression, e.g. `h5repack -f GZIP=4 in.h5 out.h5` (or in h5py: compression=\"gzip\")",
            ));
        }
    }
    let element = ds.dtype().map(|d| d.size()).unwrap_or(1) as f64;
    if let Some(chunk) = ds.chunk() {
        let chunk_bytes = chunk.iter().map(|&n| n as f64).product::<f64>() * element;
        if chunk_bytes > MAX_CHUNK_BYTES {
            return Err(InputError::hdf5(
                path,
                format!(
                    "{name} is stored in chunks of {chunk_bytes:.3e} bytes, more than the {MAX_CHUNK_BYTES:.0e} ctcal reads at once"
                ),
                "the file is damaged, or rewrite it with smaller chunks (h5repack -l CHUNK=65536)",
            ));
        }
    }
    let logical = shape.iter().map(|&n| n as f64).product::<f64>() * element;
    let stored = ds.storage_size() as f64;
    if logical > 1100.0 * stored.max(4096.0) {
        return Err(InputError::hdf5(
            path,
            format!(
                "{name} claims shape {shape:?} ({logical:.3e} bytes) but stores only {stored:.0} bytes"
            ),
            "the file is damaged or was written incompletely; rewrite it from the source",
        ));
    }
    Ok(shape)
}

/// Inspects an HDF5 event file and checks its sensor claim against the coordinates.
pub fn probe(path: &Path) -> Result<H5Info, InputError> {
    let file = open_file(path)?;
    let layout = layout_of(path, &file)?;
    let events = match layout {
        Layout::EventUtils => {
            let n = check_dataset(path, &file, "events/ts", 1)?[0];
            for name in ["events/xs", "events/ys", "events/ps"] {
                let len = check_dataset(path, &file, name, 1)?[0];
                if len != n {
                    return Err(InputError::hdf5(
                        path,
                        format!("{name} has {len} entries but events/ts has {n}"),
                        "the file is damaged or was written incompletely; rewrite it",
                    ));
                }
            }
            n
        }
        Layout::V2e => check_dataset(path, &file, "events", 2)?[0],
    };
    let (sensor, sensor_note) = match claimed_resolution(&file) {
        None => (None, None),
        Some((h, w)) => {
            let (max_x, max_y) = coordinate_extent(path, &file, layout, events)?;
            let fits = |w: u16, h: u16| max_x < w as i64 && max_y < h as i64;
            if fits(w, h) {
                (
                    Some(Sensor::new(w, h)),
                    Some(format!("sensor_resolution ({h}, {w}) read as (H, W)")),
                )
            } else if fits(h, w) {
                (
                    Some(Sensor::new(h, w)),
                    Some(format!(
                        "sensor_resolution is stored as ({h}, {w}); the coordinates (x up to {max_x}, y up to {max_y}) only fit {h}x{w}, so it was read as (W, H)"
                    )),
                )
            } else {
                return Err(InputError::OutsideSensor {
                    path: path.to_path_buf(),
                    place: "root attribute sensor_resolution".into(),
                    x: max_x,
                    y: max_y,
                    width: w,
                    height: h,
                    claimed: format!(
                        " the file claims (sensor_resolution = ({h}, {w}), in either order)"
                    ),
                    fix: "pass --sensor WxH with the real sensor size".into(),
                });
            }
        }
    };
    let frame_count = frame_index(path, &file, layout)?.times.len();
    Ok(H5Info {
        layout,
        events,
        sensor,
        sensor_note,
        frame_count,
    })
}

fn image_names(file: &hdf5::File) -> Vec<String> {
    let mut names: Vec<String> = file
        .group("images")
        .and_then(|g| g.member_names())
        .unwrap_or_default()
        .into_iter()
        .filter(|n| n.starts_with("image"))
        .collect();
    names.sort();
    names
}

/// Checks a frame size read from a file.
fn frame_size(
    path: &Path,
    name: &str,
    height: usize,
    width: usize,
) -> Result<(u32, u32), InputError> {
    let limit = crate::events::MAX_SENSOR_SIDE as usize;
    if width == 0 || height == 0 || width > limit || height > limit {
        return Err(InputError::hdf5(
            path,
            format!(
                "{name} holds {width}x{height} frames; ctcal reads frames of 1..={limit} pixels a side"
            ),
            "the file is damaged, or its frames are not grey (H, W) images",
        ));
    }
    Ok((width as u32, height as u32))
}

/// The frames' times, (H, W) and how to read each, checked as IJRR frame lists are: one
/// size, times that never decrease.
struct FrameIndex {
    times: Vec<TimeUs>,
    /// Dataset of each frame (event_utils) or `None` (v2e: rows of `frame`).
    datasets: Vec<Option<String>>,
    size: (u32, u32),
}

fn frame_index(path: &Path, file: &hdf5::File, layout: Layout) -> Result<FrameIndex, InputError> {
    let err = |what: &str, e: hdf5::Error| h5_error(path, what, e);
    let mut index = FrameIndex {
        times: Vec::new(),
        datasets: Vec::new(),
        size: (0, 0),
    };
    match layout {
        Layout::EventUtils => {
            for name in image_names(file) {
                let full = format!("images/{name}");
                let shape = check_dataset(path, file, &full, 2)?;
                let size = frame_size(path, &full, shape[0], shape[1])?;
                let ds = file.dataset(&full).map_err(|e| err(&full, e))?;
                let t: f64 = ds
                    .attr("timestamp")
                    .and_then(|a| a.read_scalar::<f64>())
                    .map_err(|e| err(&format!("{full} attribute `timestamp`"), e))?;
                if !t.is_finite() || t.abs() > 1e12 {
                    return Err(InputError::hdf5(
                        path,
                        format!("{full} has timestamp {t}"),
                        "frame timestamps are seconds; the file is damaged",
                    ));
                }
                index.push(
                    path,
                    &full,
                    crate::events::s_to_us(t),
                    size,
                    Some(full.clone()),
                )?;
            }
        }
        Layout::V2e => {
            if file.dataset("frame").is_err() {
                return Ok(index);
            }
            let shape = check_dataset(path, file, "frame", 3)?;
            let size = frame_size(path, "frame", shape[1], shape[2])?;
            let times: Vec<i64> = file
                .dataset("frame_ts")
                .and_then(|d| d.read_raw::<i64>())
                .map_err(|e| err("frame_ts", e))?;
            if times.len() != shape[0] {
                return Err(InputError::hdf5(
                    path,
                    format!(
                        "frame holds {} frames but frame_ts {} timestamps",
                        shape[0],
                        times.len()
                    ),
                    "v2e frames are (N, H, W) with N timestamps (microseconds) in frame_ts",
                ));
            }
            for (i, &t) in times.iter().enumerate() {
                index.push(path, &format!("frame_ts[{i}]"), t, size, None)?;
            }
        }
    }
    Ok(index)
}

impl FrameIndex {
    fn push(
        &mut self,
        path: &Path,
        place: &str,
        t: TimeUs,
        size: (u32, u32),
        dataset: Option<String>,
    ) -> Result<(), InputError> {
        if let Some(&previous) = self.times.last() {
            if size != self.size {
                return Err(InputError::corrupt(
                    path,
                    place,
                    format!(
                        "the frame is {}x{}, the first frame {}x{}",
                        size.0, size.1, self.size.0, self.size.1
                    ),
                    "give frames of one size",
                ));
            }
            if t < previous {
                return Err(InputError::corrupt(
                    path,
                    place,
                    format!("frame time {t} us is earlier than the frame before ({previous} us)"),
                    "store frames in time order",
                ));
            }
        }
        self.size = size;
        self.times.push(t);
        self.datasets.push(dataset);
        Ok(())
    }
}

/// Frame timestamps, without reading any image.
pub fn read_frame_times(path: &Path, info: &H5Info) -> Result<Vec<TimeUs>, InputError> {
    let file = open_file(path)?;
    Ok(frame_index(path, &file, info.layout)?.times)
}

/// Reads every frame.
pub fn read_frames(path: &Path, info: &H5Info) -> Result<Vec<Frame>, InputError> {
    let file = open_file(path)?;
    let index = frame_index(path, &file, info.layout)?;
    let err = |what: &str, e: hdf5::Error| h5_error(path, what, e);
    let (width, height) = index.size;
    let stack = match info.layout {
        Layout::V2e if !index.times.is_empty() => {
            Some(file.dataset("frame").map_err(|e| err("frame", e))?)
        }
        _ => None,
    };
    let mut frames = Vec::with_capacity(index.times.len());
    for (i, (&t, dataset)) in index.times.iter().zip(&index.datasets).enumerate() {
        let pixels: Vec<u8> = match (dataset, &stack) {
            (Some(name), _) => file
                .dataset(name)
                .and_then(|ds| ds.read_raw::<u8>())
                .map_err(|e| err(name, e))?,
            (None, Some(stack)) => stack
                .read_slice_2d::<u8, _>(ndarray::s![i, .., ..])
                .map_err(|e| err(&format!("frame[{i}]"), e))?
                .iter()
                .copied()
                .collect(),
            (None, None) => unreachable!("v2e frames have the stack"),
        };
        frames.push(Frame {
            t,
            width,
            height,
            pixels,
            exposure_us: None,
        });
    }
    Ok(frames)
}

/// One slice of the event columns, before validation (coordinates may be out of range,
/// polarities any integer).
#[derive(Default)]
struct Columns {
    t: Vec<TimeUs>,
    x: Vec<i64>,
    y: Vec<i64>,
    p: Vec<i64>,
}

/// Streaming HDF5 event reader.
pub struct H5Decoder {
    path: PathBuf,
    /// Keeps the file open for the datasets of `table`.
    _file: hdf5::File,
    table: EventTable,
    buffers: Buffers,
    columns: Columns,
    position: usize,
    events: usize,
    sensor: Option<Sensor>,
    order: OrderCheck,
}

impl H5Decoder {
    pub fn open(path: &Path, info: &H5Info, sensor: Option<Sensor>) -> Result<Self, InputError> {
        let file = open_file(path)?;
        let table = EventTable::open(path, &file, info.layout)
            .map_err(|e| h5_error(path, "opening the event datasets", e))?;
        Ok(Self {
            path: path.to_path_buf(),
            _file: file,
            table,
            buffers: Buffers::default(),
            columns: Columns::default(),
            position: 0,
            events: info.events,
            sensor,
            order: OrderCheck::default(),
        })
    }
}

impl EventDecoder for H5Decoder {
    fn read_chunk(&mut self, out: &mut EventChunk) -> Result<(), InputError> {
        if self.position >= self.events {
            return Ok(());
        }
        let end = (self.position + CHUNK_EVENTS.saturating_sub(out.len())).min(self.events);
        self.table
            .read(self.position..end, &mut self.buffers, &mut self.columns)
            .map_err(|e| {
                h5_error(
                    &self.path,
                    &format!("reading events {}..{end}", self.position),
                    e,
                )
            })?;
        let Columns {
            t,
            x: xs,
            y: ys,
            p: ps,
        } = &self.columns;
        let names = self.table.names();
        for i in 0..t.len() {
            let (x, y) = (xs[i], ys[i]);
            let index = self.position + i;
            if x == NOT_AN_INTEGER || y == NOT_AN_INTEGER {
                let (name, value) = if x == NOT_AN_INTEGER {
                    (names.x, x)
                } else {
                    (names.y, y)
                };
                return Err(InputError::corrupt(
                    &self.path,
                    format!("{name}[{index}]"),
                    format!("the coordinate is {}", shown(value)),
                    "coordinates must be whole pixel numbers; the file is damaged or was written from floating-point data: rewrite it with integer x and y",
                ));
            }
            if !(x >= 0 && y >= 0 && super::within(self.sensor, x as u32, y as u32))
                || x > u32::MAX as i64
                || y > u32::MAX as i64
            {
                return Err(super::outside_sensor(
                    &self.path,
                    format!("event index {index} ({}, {})", names.x, names.y),
                    x,
                    y,
                    self.sensor,
                ));
            }
            if t[i] == TimeUs::MIN {
                return Err(InputError::corrupt(
                    &self.path,
                    format!("{}[{index}]", names.t),
                    "the timestamp is not a finite number",
                    "the file is damaged; rewrite it from the source recording",
                ));
            }
            let on = match ps[i] {
                1 => true,
                0 | -1 => false,
                other => {
                    return Err(InputError::corrupt(
                        &self.path,
                        format!("{}[{index}]", names.p),
                        format!("the polarity is {}", shown(other)),
                        "polarities are 1 (ON) and 0 or -1 (OFF); the file is damaged or uses another convention",
                    ));
                }
            };
            self.order.check(t[i], || format!("{}[{index}]", names.t));
            out.push(t[i], x as u16, y as u16, on);
        }
        self.position = end;
        Ok(())
    }

    fn order(&self) -> &OrderCheck {
        &self.order
    }

    fn progress(&self) -> Progress {
        Progress {
            done: self.position as u64,
            total: self.events as u64,
        }
    }
}
