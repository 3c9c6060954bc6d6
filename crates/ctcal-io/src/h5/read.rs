//! Reading the HDF5 layouts of [`super`] through `hdf5-metno` (libhdf5), in chunks of
//! `CHUNK_EVENTS` rows; compressed 1-D columns by direct chunk access on all cores
//! ([`super::direct`]).

use super::direct::{DirectColumn, DirectError, ElementKind};
use super::frame_pixels::frame_pixels;
use super::{H5Info, Layout, Side};
use crate::error::InputError;
use crate::events::{CHUNK_EVENTS, EventChunk, Frame, MAX_SENSOR_SIDE, Sensor, TimeUs};
use crate::hint::{Hint, Text};
use crate::order::OrderCheck;
use crate::{EventDecoder, Progress};
use hdf5::types::TypeDescriptor;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
impl Side {
    /// The MVSEC group of this camera.
    fn group(self) -> String {
        format!("davis/{}", self.name())
    }
}

pub(super) fn h5_error(path: &Path, what: &str, e: hdf5::Error) -> InputError {
    InputError::hdf5(
        path,
        format!("{what}: {e}"),
        "check that the file is a complete event_utils, v2e, MVSEC or DSEC HDF5 file (h5ls -r shows its layout)",
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
        "ctcal reads the event_utils layout (events/ts, events/xs, events/ys, events/ps), the v2e layout (events: N x 4 [t_us, x, y, p]), MVSEC (davis/left/events: N x 4 [x, y, t, p]) and DSEC (events/x, events/y, events/t, events/p)",
    )
}

fn layout_of(path: &Path, file: &hdf5::File, side: Side) -> Result<Layout, InputError> {
    if let Ok(group) = file.group("events") {
        return columns_layout(path, &group);
    }
    if let Ok(davis) = file.group("davis") {
        return mvsec_layout(path, file, &davis, side);
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
        "group `events` (event_utils, DSEC), dataset `events` (v2e) or group `davis` (MVSEC)",
    ))
}

/// The layout of a file whose group `events` holds one column per field: event_utils
/// (`ts`, `xs`, `ys`, `ps`) or DSEC (`t`, `x`, `y`, `p`), every column present.
fn columns_layout(path: &Path, group: &hdf5::Group) -> Result<Layout, InputError> {
    // event_utils names its columns ts/xs/ys/ps, DSEC t/x/y/p
    for (names, layout) in [
        (["ts", "xs", "ys", "ps"], Layout::EventUtils),
        (["t", "x", "y", "p"], Layout::Dsec),
    ] {
        if group.link_exists(names[0]) {
            for name in names {
                if !group.link_exists(name) {
                    return Err(missing(path, &format!("dataset events/{name}")));
                }
            }
            return Ok(layout);
        }
    }
    Err(missing(
        path,
        "events/ts (event_utils) or events/t (DSEC) in group `events`",
    ))
}

/// The MVSEC layout of the camera `side`, where the file's group `davis` holds its events;
/// otherwise an error naming the cameras that have events.
fn mvsec_layout(
    path: &Path,
    file: &hdf5::File,
    davis: &hdf5::Group,
    side: Side,
) -> Result<Layout, InputError> {
    let wanted = side.group();
    if file.link_exists(&format!("{wanted}/events")) {
        return Ok(Layout::Mvsec(side));
    }
    let others: Vec<String> = davis
        .member_names()
        .unwrap_or_default()
        .into_iter()
        .filter(|n| file.link_exists(&format!("davis/{n}/events")))
        .collect();
    Err(InputError::hdf5(
        path,
        format!(
            "an MVSEC file without {wanted}/events (cameras with events: {})",
            if others.is_empty() {
                "none".to_string()
            } else {
                others.join(", ")
            }
        ),
        match others.first() {
            Some(other) => Text::default().act(Hint::Side(other.clone())),
            None => {
                "the file holds no MVSEC events (davis/left/events or davis/right/events)".into()
            }
        },
    ))
}

/// One 1-D column of an event_utils file: read by direct chunk access and parallel
/// inflation where the layout allows ([`super::direct`]), through libhdf5 otherwise.
/// Results go into caller buffers, which are reused from chunk to chunk.
struct Column {
    name: String,
    dataset: hdf5::Dataset,
    direct: Option<(DirectColumn, ElementKind)>,
}

impl Column {
    fn open(path: &Path, file: &hdf5::File, name: &str) -> hdf5::Result<Self> {
        let dataset = file.dataset(name)?;
        let kind = dataset.dtype().ok().and_then(|d| ElementKind::of(&d));
        let direct = DirectColumn::new(path, &dataset).zip(kind);
        Ok(Self {
            name: name.to_string(),
            dataset,
            direct,
        })
    }

    /// The values of `range` into `out` by the direct path, when it can read them (`false`:
    /// read through the library); a chunk that does not decode is an error naming it.
    fn direct<T: Copy + Default + Send>(
        &self,
        range: &std::ops::Range<usize>,
        out: &mut Vec<T>,
        integer: impl Fn(i64) -> T + Sync,
        float: impl Fn(f64) -> T + Sync,
    ) -> hdf5::Result<bool> {
        let Some((column, kind)) = self.direct.as_ref() else {
            return Ok(false);
        };
        // the callers pass empty buffers (reused from chunk to chunk)
        debug_assert!(out.is_empty());
        match column.read_decoded(range.clone(), out, |bytes, piece| {
            kind.decode_into(bytes, piece, &integer, &float)
        }) {
            Ok(()) => Ok(true),
            Err(DirectError::Unsupported) => Ok(false),
            Err(DirectError::Damaged { chunk, problem }) => {
                let n = column.chunk_len();
                Err(hdf5::Error::from(format!(
                    "{}: the chunk of elements {}..{} {problem}",
                    self.name,
                    chunk * n,
                    (chunk + 1) * n
                )))
            }
        }
    }

    /// Appends the values of `range` as i64, whatever the stored type: integers as they are,
    /// floats that hold an integer converted, any other float (NaN, infinite, fractional)
    /// as [`NOT_AN_INTEGER`].
    fn ints(&self, range: std::ops::Range<usize>, out: &mut Vec<i64>) -> hdf5::Result<()> {
        if self.direct(&range, out, |v| v, float_to_int)? {
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
    fn floats(&self, range: std::ops::Range<usize>, out: &mut Vec<f64>) -> hdf5::Result<()> {
        if !self.direct(&range, out, |v| v as f64, |f| f)? {
            out.extend(self.dataset.read_slice_1d::<f64, _>(range)?.iter());
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

/// The four columns of a DSEC file and its time offset.
struct DsecColumns {
    t_offset: TimeUs,
    t: Column,
    x: Column,
    y: Column,
    p: Column,
}

/// The four event columns of an event_utils or DSEC file, or the N x 4 table of a v2e or
/// MVSEC file.
enum EventTable {
    EventUtils(Box<EventColumns>),
    V2e(hdf5::Dataset),
    Mvsec(hdf5::Dataset, Side),
    Dsec(Box<DsecColumns>),
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
            EventTable::Mvsec(_, Side::Left) => FieldNames {
                t: "davis/left/events[:, 2]",
                x: "davis/left/events[:, 0]",
                y: "davis/left/events[:, 1]",
                p: "davis/left/events[:, 3]",
            },
            EventTable::Mvsec(_, Side::Right) => FieldNames {
                t: "davis/right/events[:, 2]",
                x: "davis/right/events[:, 0]",
                y: "davis/right/events[:, 1]",
                p: "davis/right/events[:, 3]",
            },
            EventTable::Dsec(_) => FieldNames {
                t: "events/t (+ t_offset)",
                x: "events/x",
                y: "events/y",
                p: "events/p",
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
            Layout::Mvsec(side) => {
                EventTable::Mvsec(file.dataset(&format!("{}/events", side.group()))?, side)
            }
            Layout::Dsec => EventTable::Dsec(Box::new(DsecColumns {
                t_offset: dsec_t_offset(file)?,
                t: Column::open(path, file, "events/t")?,
                x: Column::open(path, file, "events/x")?,
                y: Column::open(path, file, "events/y")?,
                p: Column::open(path, file, "events/p")?,
            })),
        })
    }

    /// Replaces `columns.x` and `columns.y` with the coordinates of `range`.
    fn coordinates(
        &self,
        range: std::ops::Range<usize>,
        columns: &mut Columns,
    ) -> hdf5::Result<()> {
        columns.x.clear();
        columns.y.clear();
        match self {
            EventTable::EventUtils(c) => {
                c.xs.ints(range.clone(), &mut columns.x)?;
                c.ys.ints(range, &mut columns.y)?;
            }
            EventTable::V2e(ds) => {
                let rows = ds.read_slice_2d::<i64, _>(ndarray::s![range, 1..3])?;
                columns.x.extend(rows.column(0).iter());
                columns.y.extend(rows.column(1).iter());
            }
            EventTable::Mvsec(ds, _) => {
                let rows = ds.read_slice_2d::<f64, _>(ndarray::s![range, 0..2])?;
                columns
                    .x
                    .extend(rows.column(0).iter().map(|&v| float_to_int(v)));
                columns
                    .y
                    .extend(rows.column(1).iter().map(|&v| float_to_int(v)));
            }
            EventTable::Dsec(c) => {
                c.x.ints(range.clone(), &mut columns.x)?;
                c.y.ints(range, &mut columns.y)?;
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
            EventTable::EventUtils(c) => c.read(range, &mut buffers.seconds, columns),
            EventTable::V2e(ds) => read_v2e_rows(ds, range, columns),
            EventTable::Mvsec(ds, _) => read_mvsec_rows(ds, range, columns),
            EventTable::Dsec(c) => c.read(range, columns),
        }
    }
}

impl EventColumns {
    /// Replaces `columns.x`, `y` and `p` with the events of `range` and appends their times
    /// to the emptied `columns.t`. event_utils: `events/ts` in seconds (floats, read via
    /// `seconds`, a reused buffer) or, as integers, in microseconds; `xs`, `ys`, `ps` as
    /// integers.
    fn read(
        &self,
        range: std::ops::Range<usize>,
        seconds: &mut Vec<f64>,
        columns: &mut Columns,
    ) -> hdf5::Result<()> {
        let Columns { t, x, y, p } = columns;
        x.clear();
        y.clear();
        seconds.clear();
        // the four columns at once (see DsecColumns::read)
        let ((rt, rx), (ry, rp)) = rayon::join(
            || {
                rayon::join(
                    || {
                        if self.integer_times {
                            // integer timestamps are microseconds (seconds as
                            // integers make no sense)
                            self.ts.ints(range.clone(), t)
                        } else {
                            self.ts.floats(range.clone(), seconds)
                        }
                    },
                    || self.xs.ints(range.clone(), x),
                )
            },
            || {
                rayon::join(
                    || self.ys.ints(range.clone(), y),
                    || self.ps.ints(range.clone(), p),
                )
            },
        );
        rt.and(rx).and(ry).and(rp)?;
        if !self.integer_times {
            // a non-finite time becomes i64::MIN and is reported by read_chunk
            t.extend(seconds.iter().map(|&s| {
                if s.is_finite() {
                    crate::events::s_to_us(s)
                } else {
                    TimeUs::MIN
                }
            }));
        }
        Ok(())
    }
}

/// Appends the events of rows `range` of v2e's N x 4 table `events` (`[t_us, x, y, p]`,
/// read as integers) to the emptied `columns.t` and `p`, replacing `columns.x` and `y`.
fn read_v2e_rows(
    ds: &hdf5::Dataset,
    range: std::ops::Range<usize>,
    columns: &mut Columns,
) -> hdf5::Result<()> {
    let rows = ds.read_slice_2d::<i64, _>(ndarray::s![range, ..])?;
    columns.t.extend(rows.column(0).iter());
    columns.x.clear();
    columns.y.clear();
    columns.x.extend(rows.column(1).iter());
    columns.y.extend(rows.column(2).iter());
    columns.p.extend(rows.column(3).iter());
    Ok(())
}

/// Appends the events of rows `range` of MVSEC's N x 4 float64 table
/// `davis/{side}/events` (`[x, y, t, p]`, t in seconds since the epoch) to the emptied
/// `columns.t` and `p`, replacing `columns.x` and `y`; a value that is no integer (or no
/// finite time) is marked for read_chunk to report.
fn read_mvsec_rows(
    ds: &hdf5::Dataset,
    range: std::ops::Range<usize>,
    columns: &mut Columns,
) -> hdf5::Result<()> {
    let rows = ds.read_slice_2d::<f64, _>(ndarray::s![range, ..])?;
    columns.x.clear();
    columns.y.clear();
    columns
        .x
        .extend(rows.column(0).iter().map(|&v| float_to_int(v)));
    columns
        .y
        .extend(rows.column(1).iter().map(|&v| float_to_int(v)));
    // seconds since the epoch, to the nearest microsecond (float64 resolves
    // 0.24 us there)
    columns.t.extend(rows.column(2).iter().map(|&s| {
        if s.is_finite() && s.abs() < 1e12 {
            crate::events::s_to_us(s)
        } else {
            TimeUs::MIN
        }
    }));
    columns
        .p
        .extend(rows.column(3).iter().map(|&v| float_to_int(v)));
    Ok(())
}

impl DsecColumns {
    /// Replaces `columns.x`, `y` and `p` with the events of `range` and appends their times
    /// to the emptied `columns.t`. DSEC: `events/t` (microseconds, to which the file's
    /// `t_offset` is added), `x`, `y`, `p` as integers.
    fn read(&self, range: std::ops::Range<usize>, columns: &mut Columns) -> hdf5::Result<()> {
        let Columns { t, x, y, p } = columns;
        x.clear();
        y.clear();
        // the four columns at once: each column's chunks are read under libhdf5's
        // lock one after another, but decompress while the next column is read
        let ((rt, rx), (ry, rp)) = rayon::join(
            || {
                rayon::join(
                    || self.t.ints(range.clone(), t),
                    || self.x.ints(range.clone(), x),
                )
            },
            || {
                rayon::join(
                    || self.y.ints(range.clone(), y),
                    || self.p.ints(range.clone(), p),
                )
            },
        );
        rt.and(rx).and(ry).and(rp)?;
        let offset = self.t_offset;
        for t in t.iter_mut() {
            // an offset that overflows is damage: reported like a non-finite time
            *t = if *t == NOT_AN_INTEGER {
                TimeUs::MIN
            } else {
                t.checked_add(offset).unwrap_or(TimeUs::MIN)
            };
        }
        Ok(())
    }
}

/// DSEC's `t_offset` (microseconds added to every `events/t`; 0 when absent).
fn dsec_t_offset(file: &hdf5::File) -> hdf5::Result<TimeUs> {
    if !file.link_exists("t_offset") {
        return Ok(0);
    }
    let ds = file.dataset("t_offset")?;
    if !ds.shape().is_empty() {
        return Err(hdf5::Error::from(format!(
            "t_offset has shape {:?}; DSEC stores it as a scalar (microseconds)",
            ds.shape()
        )));
    }
    ds.read_scalar::<i64>()
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
    let mut columns = Columns::default();
    let mut max_x = -1i64;
    let mut max_y = -1i64;
    let mut start = 0;
    while start < n {
        let end = (start + CHUNK_EVENTS).min(n);
        table
            .coordinates(start..end, &mut columns)
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
    check_shape(path, name, &shape, rank)?;
    check_filters(path, name, &ds)?;
    let element = ds.dtype().map(|d| d.size()).unwrap_or(1) as f64;
    check_chunk_size(path, name, &ds, element)?;
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

/// Checks the shape of dataset `name`: `rank` dimensions, and grey frames, not colour
/// images, where it holds frames.
fn check_shape(path: &Path, name: &str, shape: &[usize], rank: usize) -> Result<(), InputError> {
    let frames = name.starts_with("images/") || name == "frame" || name.ends_with("image_raw");
    if frames && shape.len() == rank + 1 && matches!(shape[rank], 3 | 4) {
        return Err(InputError::hdf5(
            path,
            format!(
                "{name} has shape {shape:?}: a colour image ({} channels), where ctcal reads grey frames",
                shape[rank]
            ),
            "write the frames as grey images, (H, W) per frame in 8 bits (e.g. in NumPy: 0.299 R + 0.587 G + 0.114 B), as event cameras' APS frames are",
        ));
    }
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
    Ok(())
}

/// Checks that libhdf5 can undo every filter of dataset `name`.
fn check_filters(path: &Path, name: &str, ds: &hdf5::Dataset) -> Result<(), InputError> {
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
    Ok(())
}

/// Checks that a chunk of dataset `name` (of `element` bytes per value) is at most
/// [`MAX_CHUNK_BYTES`].
fn check_chunk_size(
    path: &Path,
    name: &str,
    ds: &hdf5::Dataset,
    element: f64,
) -> Result<(), InputError> {
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
    Ok(())
}

/// Inspects an HDF5 event file and checks its sensor claim against the coordinates.
pub fn probe(path: &Path, side: Side) -> Result<H5Info, InputError> {
    let file = open_file(path)?;
    let layout = layout_of(path, &file, side)?;
    let events = event_count(path, &file, layout)?;
    let notes = time_precision(path, &file, layout, events)?
        .into_iter()
        .collect::<Vec<_>>();
    let frames = frame_index(path, &file, layout)?;
    let claimed = match layout {
        // MVSEC states no resolution; its frames show the whole sensor
        Layout::Mvsec(side) if !frames.times.is_empty() => {
            let (w, h) = frames.size;
            return Ok(H5Info {
                layout,
                events,
                sensor: Some(Sensor::new(w as u16, h as u16)),
                sensor_note: Some(format!("the size of {}/image_raw", side.group())),
                frame_count: frames.times.len(),
                notes,
            });
        }
        _ => claimed_resolution(&file),
    };
    let (sensor, sensor_note) = match claimed {
        None => (None, None),
        Some((h, w)) => checked_resolution(path, &file, layout, events, h, w)?,
    };
    Ok(H5Info {
        layout,
        events,
        sensor,
        sensor_note,
        frame_count: frames.times.len(),
        notes,
    })
}

/// The number of events of `layout`, after [`check_dataset`] on every event dataset (HDF5:
/// rank, filters, chunk and stored sizes): the four 1-D columns of event_utils
/// (`events/ts`, `xs`, `ys`, `ps`) and DSEC (`events/t`, `x`, `y`, `p`) must have one
/// length; the v2e table `events` is 2-D (its 4 columns checked by [`layout_of`]) and
/// MVSEC's `davis/{side}/events` N x 4.
fn event_count(path: &Path, file: &hdf5::File, layout: Layout) -> Result<usize, InputError> {
    Ok(match layout {
        Layout::EventUtils => column_length(
            path,
            file,
            "events/ts",
            ["events/xs", "events/ys", "events/ps"],
        )?,
        Layout::V2e => check_dataset(path, file, "events", 2)?[0],
        Layout::Mvsec(side) => {
            let name = format!("{}/events", side.group());
            let shape = check_dataset(path, file, &name, 2)?;
            if shape[1] != 4 {
                return Err(InputError::hdf5(
                    path,
                    format!("{name} has shape {shape:?}, expected N x 4"),
                    "MVSEC files store events as N rows of [x, y, t, p]",
                ));
            }
            shape[0]
        }
        Layout::Dsec => {
            column_length(path, file, "events/t", ["events/x", "events/y", "events/p"])?
        }
    })
}

/// The length of the 1-D column `first`, after checking each column (`first` and the
/// `others`, [`check_dataset`]) and that the `others` have the same length.
fn column_length(
    path: &Path,
    file: &hdf5::File,
    first: &str,
    others: [&str; 3],
) -> Result<usize, InputError> {
    let n = check_dataset(path, file, first, 1)?[0];
    for name in others {
        let len = check_dataset(path, file, name, 1)?[0];
        if len != n {
            return Err(InputError::hdf5(
                path,
                format!("{name} has {len} entries but {first} has {n}"),
                "the file is damaged or was written incompletely; rewrite it",
            ));
        }
    }
    Ok(n)
}

/// The sensor and how it is known, from the `sensor_resolution` the file claims, (`h`, `w`)
/// as event_utils writes it, checked against the largest coordinates over the whole file:
/// read as (H, W) where the events fit, else as (W, H) where they fit that, else the events
/// lie outside the sensor and the file is refused.
fn checked_resolution(
    path: &Path,
    file: &hdf5::File,
    layout: Layout,
    events: usize,
    h: u16,
    w: u16,
) -> Result<(Option<Sensor>, Option<String>), InputError> {
    let (max_x, max_y) = coordinate_extent(path, file, layout, events)?;
    let fits = |w: u16, h: u16| max_x < w as i64 && max_y < h as i64;
    if fits(w, h) {
        Ok((
            Some(Sensor::new(w, h)),
            Some(format!("sensor_resolution ({h}, {w}) read as (H, W)")),
        ))
    } else if fits(h, w) {
        Ok((
            Some(Sensor::new(h, w)),
            Some(format!(
                "sensor_resolution is stored as ({h}, {w}); the coordinates (x up to {max_x}, y up to {max_y}) only fit {h}x{w}, so it was read as (W, H)"
            )),
        ))
    } else {
        Err(InputError::OutsideSensor {
            path: path.to_path_buf(),
            place: "root attribute sensor_resolution".into(),
            x: max_x,
            y: max_y,
            width: w,
            height: h,
            claimed: format!(" the file claims (sensor_resolution = ({h}, {w}), in either order)"),
            fix: Text::default()
                .act(Hint::Sensor(None))
                .words(" with the real sensor size"),
        })
    }
}

/// The coarsest spacing of stored times ctcal accepts, seconds: events less than this
/// apart would share a time (rates per window, the support window and same-pixel intervals
/// lose their meaning).
pub const MAX_TIME_RESOLUTION_S: f64 = 1e-3;

/// The spacing of float32 values near `t`.
fn float32_spacing(t: f64) -> f64 {
    let t = (t.abs() as f32).max(f32::MIN_POSITIVE);
    (f32::from_bits(t.to_bits() + 1) - t) as f64
}

/// Checks that float times in seconds keep their precision: float32 resolves only 1 us
/// below 16.8 s and 128 s at the epoch times MVSEC stores, where a whole recording
/// collapses to one time. Refused when the spacing of stored values at the file's times
/// is coarser than [`MAX_TIME_RESOLUTION_S`]; a note when coarser than a microsecond.
fn time_precision(
    path: &Path,
    file: &hdf5::File,
    layout: Layout,
    n: usize,
) -> Result<Option<String>, InputError> {
    let Some(times) = FloatTimes::float32(path, file, layout)? else {
        return Ok(None);
    };
    if n == 0 {
        return Ok(None);
    }
    let (first, last) = (times.at(path, file, 0)?, times.at(path, file, n - 1)?);
    if !first.is_finite() || !last.is_finite() {
        // reported with its index by the reader
        return Ok(None);
    }
    precision_of(path, &times.field(), (first, last), n)
}

/// A layout's times stored as float seconds: the dataset's name, the column of a table
/// (`None`: a column of its own) and the dataset.
struct FloatTimes {
    name: String,
    column: Option<usize>,
    ds: hdf5::Dataset,
}

impl FloatTimes {
    /// The times of `layout` where they are float32 seconds (event_utils' `events/ts`, the
    /// third column of MVSEC's events); `None` for other layouts and types.
    fn float32(path: &Path, file: &hdf5::File, layout: Layout) -> Result<Option<Self>, InputError> {
        let (name, column) = match layout {
            Layout::EventUtils => ("events/ts".to_string(), None),
            Layout::Mvsec(side) => (format!("{}/events", side.group()), Some(2)),
            _ => return Ok(None),
        };
        let ds = file.dataset(&name).map_err(|e| h5_error(path, &name, e))?;
        let is_float32 = matches!(
            ds.dtype().and_then(|d| d.to_descriptor()),
            Ok(TypeDescriptor::Float(hdf5::types::FloatSize::U4))
        );
        Ok(is_float32.then_some(Self { name, column, ds }))
    }

    /// The time stored at `row`, seconds.
    fn at(&self, path: &Path, file: &hdf5::File, row: usize) -> Result<f64, InputError> {
        let v = match self.column {
            None => element::<f64>(file, &self.name, row),
            Some(c) => self
                .ds
                .read_slice_2d::<f64, _>(ndarray::s![row..row + 1, c..c + 1])
                .map(|a| a.iter().next().copied().unwrap_or(0.0)),
        };
        v.map_err(|e| h5_error(path, &self.name, e))
    }

    /// The times' name in messages: the dataset, with the column of a table.
    fn field(&self) -> String {
        match self.column {
            None => self.name.clone(),
            Some(c) => format!("{}[:, {c}]", self.name),
        }
    }
}

/// Whether the `n` float32 times from `first` to `last` of `field` keep their precision:
/// refused where the spacing of float32 values at the larger is coarser than
/// [`MAX_TIME_RESOLUTION_S`], a note where coarser than a microsecond, else `None`.
fn precision_of(
    path: &Path,
    field: &str,
    (first, last): (f64, f64),
    n: usize,
) -> Result<Option<String>, InputError> {
    let t = first.abs().max(last.abs());
    let spacing = float32_spacing(t);
    let problem = format!(
        "{field} stores times as float32 seconds, which near {t:.6e} s only take values {spacing:.3e} s apart: events closer than that share one time (the {} events from {first} s to {last} s)",
        n
    );
    if spacing > MAX_TIME_RESOLUTION_S {
        return Err(InputError::hdf5(
            path,
            problem,
            "the times lost their precision when the file was written: write them again from the source recording as float64 seconds (or int64 microseconds)",
        ));
    }
    Ok((spacing > 1e-6).then(|| {
        format!(
            "{}: {problem}; times are kept only to {:.0} us",
            path.display(),
            spacing * 1e6
        )
    }))
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
    let mut index = FrameIndex {
        times: Vec::new(),
        datasets: Vec::new(),
        size: (0, 0),
    };
    match layout {
        Layout::EventUtils => event_utils_frames(path, file, &mut index)?,
        Layout::V2e => v2e_frames(path, file, &mut index)?,
        Layout::Mvsec(side) => mvsec_frames(path, file, side, &mut index)?,
        Layout::Dsec => {}
    }
    Ok(index)
}

/// A frame time in seconds as microseconds; a value that is not a time (NaN, infinite,
/// beyond 1e12 s) is refused with `problem`.
fn frame_seconds(
    path: &Path,
    t: f64,
    problem: impl FnOnce() -> String,
) -> Result<TimeUs, InputError> {
    if !t.is_finite() || t.abs() > 1e12 {
        return Err(InputError::hdf5(
            path,
            problem(),
            "frame timestamps are seconds; the file is damaged",
        ));
    }
    Ok(crate::events::s_to_us(t))
}

/// event_utils: one dataset per frame under `images/`, its time (seconds) an attribute.
fn event_utils_frames(
    path: &Path,
    file: &hdf5::File,
    index: &mut FrameIndex,
) -> Result<(), InputError> {
    let err = |what: &str, e: hdf5::Error| h5_error(path, what, e);
    for name in image_names(file) {
        let full = format!("images/{name}");
        let shape = check_dataset(path, file, &full, 2)?;
        let size = frame_size(path, &full, shape[0], shape[1])?;
        let ds = file.dataset(&full).map_err(|e| err(&full, e))?;
        let t: f64 = ds
            .attr("timestamp")
            .and_then(|a| a.read_scalar::<f64>())
            .map_err(|e| err(&format!("{full} attribute `timestamp`"), e))?;
        let t = frame_seconds(path, t, || format!("{full} has timestamp {t}"))?;
        index.push(path, &full, t, size, Some(full.clone()))?;
    }
    Ok(())
}

/// v2e: the frames as rows of `frame` (N, H, W), their times in `frame_ts` (microseconds,
/// integers or floats).
fn v2e_frames(path: &Path, file: &hdf5::File, index: &mut FrameIndex) -> Result<(), InputError> {
    let err = |what: &str, e: hdf5::Error| h5_error(path, what, e);
    if file.dataset("frame").is_err() {
        return Ok(());
    }
    let shape = check_dataset(path, file, "frame", 3)?;
    let size = frame_size(path, "frame", shape[1], shape[2])?;
    // microseconds, as integers (v2e) or floats: a float NaN or infinity must not
    // become a time by integer conversion
    let stamps = file.dataset("frame_ts").map_err(|e| err("frame_ts", e))?;
    let float = matches!(
        stamps.dtype().and_then(|d| d.to_descriptor()),
        Ok(TypeDescriptor::Float(_))
    );
    let times: Vec<i64> = if float {
        let values: Vec<f64> = stamps.read_raw().map_err(|e| err("frame_ts", e))?;
        let mut times = Vec::with_capacity(values.len());
        for (i, &t) in values.iter().enumerate() {
            if !(t.is_finite() && t.abs() <= crate::events::TIME_LIMIT_US as f64) {
                return Err(InputError::hdf5(
                    path,
                    format!("frame_ts[{i}] is {t}, not a time in microseconds"),
                    "frame timestamps are microseconds; the file is damaged",
                ));
            }
            times.push(t.round() as i64);
        }
        times
    } else {
        stamps.read_raw::<i64>().map_err(|e| err("frame_ts", e))?
    };
    check_frame_count(
        path,
        ("frame", shape[0]),
        ("frame_ts", times.len()),
        "v2e frames are (N, H, W) with N timestamps (microseconds) in frame_ts",
    )?;
    for (i, &t) in times.iter().enumerate() {
        index.push(path, &format!("frame_ts[{i}]"), t, size, None)?;
    }
    Ok(())
}

/// A frame stack `(name, frames)` and its timestamps `(name, count)` must agree in number.
fn check_frame_count(
    path: &Path,
    (stack, frames): (&str, usize),
    (stamps, count): (&str, usize),
    fix: &str,
) -> Result<(), InputError> {
    if count == frames {
        return Ok(());
    }
    Err(InputError::hdf5(
        path,
        format!("{stack} holds {frames} frames but {stamps} {count} timestamps"),
        fix,
    ))
}

/// MVSEC: the frames of one side as rows of `image_raw` (M, H, W), their times in
/// `image_raw_ts` (seconds).
fn mvsec_frames(
    path: &Path,
    file: &hdf5::File,
    side: Side,
    index: &mut FrameIndex,
) -> Result<(), InputError> {
    let err = |what: &str, e: hdf5::Error| h5_error(path, what, e);
    let stack = format!("{}/image_raw", side.group());
    if !file.link_exists(&stack) {
        return Ok(());
    }
    let shape = check_dataset(path, file, &stack, 3)?;
    let size = frame_size(path, &stack, shape[1], shape[2])?;
    let stamps = format!("{stack}_ts");
    let times: Vec<f64> = file
        .dataset(&stamps)
        .and_then(|d| d.read_raw::<f64>())
        .map_err(|e| err(&stamps, e))?;
    check_frame_count(
        path,
        (&stack, shape[0]),
        (&stamps, times.len()),
        "MVSEC frames are (M, H, W) with M timestamps (seconds) in image_raw_ts",
    )?;
    for (i, &t) in times.iter().enumerate() {
        let t = frame_seconds(path, t, || format!("{stamps}[{i}] is {t}"))?;
        index.push(path, &format!("{stamps}[{i}]"), t, size, None)?;
    }
    Ok(())
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
        if t.unsigned_abs() > crate::events::TIME_LIMIT_US as u64 {
            return Err(InputError::corrupt(
                path,
                place,
                format!(
                    "frame time {t} us lies beyond +-{} us (about 73,000 years) of zero",
                    crate::events::TIME_LIMIT_US
                ),
                "the file is damaged at this place; frame times are in the file's clock",
            ));
        }
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
    let stack_name = match info.layout {
        Layout::V2e => "frame".to_string(),
        Layout::Mvsec(side) => format!("{}/image_raw", side.group()),
        _ => String::new(),
    };
    let stack = match info.layout {
        Layout::V2e | Layout::Mvsec(_) if !index.times.is_empty() => {
            Some(file.dataset(&stack_name).map_err(|e| err(&stack_name, e))?)
        }
        _ => None,
    };
    let mut frames = Vec::with_capacity(index.times.len());
    for (i, (&t, dataset)) in index.times.iter().zip(&index.datasets).enumerate() {
        let pixels = match (dataset, &stack) {
            (Some(name), _) => {
                let ds = file.dataset(name).map_err(|e| err(name, e))?;
                frame_pixels(path, &ds, None, &format!("{name} (frame {i})"), width)?
            }
            (None, Some(stack)) => {
                frame_pixels(path, stack, Some(i), &format!("{stack_name}[{i}]"), width)?
            }
            (None, None) => unreachable!("v2e and MVSEC frames have the stack"),
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
        Self::open_rows(path, info, sensor, 0..info.events)
    }

    /// A decoder of the event rows `rows` only (after a seek, [`index_window`]).
    pub fn open_rows(
        path: &Path,
        info: &H5Info,
        sensor: Option<Sensor>,
        rows: std::ops::Range<usize>,
    ) -> Result<Self, InputError> {
        let file = open_file(path)?;
        let table = EventTable::open(path, &file, info.layout)
            .map_err(|e| h5_error(path, "opening the event datasets", e))?;
        Ok(Self {
            path: path.to_path_buf(),
            _file: file,
            table,
            buffers: Buffers::default(),
            columns: Columns::default(),
            position: rows.start.min(info.events),
            events: rows.end.min(info.events),
            sensor,
            order: OrderCheck::default(),
        })
    }
}

/// One element of a 1-D dataset.
fn element<T: hdf5::H5Type + Copy>(file: &hdf5::File, name: &str, index: usize) -> hdf5::Result<T> {
    let values = file
        .dataset(name)?
        .read_slice_1d::<T, _>(index..index + 1)?;
    values
        .first()
        .copied()
        .ok_or_else(|| hdf5::Error::from(format!("{name}[{index}] is missing")))
}

/// The time of the first event (in the file's clock), read without decoding the rest; `None`
/// for layouts without an index to seek with.
pub fn first_time(path: &Path, info: &H5Info) -> Result<Option<TimeUs>, InputError> {
    if info.events == 0 {
        return Ok(None);
    }
    let file = open_file(path)?;
    let err = |e| h5_error(path, "reading the first event's time", e);
    Ok(match info.layout {
        Layout::Dsec => {
            let t: i64 = element::<u64>(&file, "events/t", 0)
                .map(|t| t as i64)
                .or_else(|_| element::<i64>(&file, "events/t", 0))
                .map_err(err)?;
            t.checked_add(dsec_t_offset(&file).map_err(err)?)
        }
        Layout::Mvsec(side) => {
            let row = file
                .dataset(&format!("{}/events", side.group()))
                .and_then(|d| d.read_slice_2d::<f64, _>(ndarray::s![0..1, 2..3]))
                .map_err(err)?;
            row.iter()
                .next()
                .filter(|s| s.is_finite() && s.abs() < 1e12)
                .map(|&s| crate::events::s_to_us(s))
        }
        _ => None,
    })
}

/// The first row whose time is at least `t`, searched from the row `near` (galloping away
/// from it, then bisecting), in rows sorted by time `0..n`.
fn first_row_at_or_after(
    near: usize,
    n: usize,
    t: TimeUs,
    time_at: &impl Fn(usize) -> Result<TimeUs, InputError>,
) -> Result<usize, InputError> {
    let at_or_after =
        |row: usize| -> Result<bool, InputError> { Ok(row >= n || time_at(row)? >= t) };
    // a bracket lo < answer <= hi, lo = usize::MAX meaning "before row 0"
    let (mut lo, mut hi) = if at_or_after(near)? {
        let mut step = 1;
        let mut hi = near;
        loop {
            if hi == 0 {
                break (None, 0);
            }
            let probe = hi.saturating_sub(step);
            if at_or_after(probe)? {
                hi = probe;
                step *= 2;
            } else {
                break (Some(probe), hi);
            }
        }
    } else {
        let mut step = 1;
        let mut lo = near;
        loop {
            let probe = (lo + step).min(n);
            if at_or_after(probe)? {
                break (Some(lo), probe);
            }
            lo = probe;
            step *= 2;
        }
    };
    while let Some(l) = lo {
        if hi - l <= 1 {
            break;
        }
        let mid = l + (hi - l) / 2;
        if at_or_after(mid)? {
            hi = mid;
        } else {
            lo = Some(mid);
        }
    }
    if lo.is_none() {
        // every row from 0 to hi is at or after t
        hi = 0;
    }
    Ok(hi)
}

/// Event rows found with a file's index, and a note when the index had to be corrected.
pub type IndexedRows = (std::ops::Range<usize>, Option<String>);

/// The rows that hold the events of times `from..=to`, found with the file's own index
/// (DSEC `ms_to_idx`: the first event of each millisecond; MVSEC `image_raw_event_inds`: the
/// event nearest each frame), from which the exact ends are found on the event times, so
/// that a window is read without scanning what lies before it. An index that contradicts
/// the times (a DSEC millisecond that does not start at its row) costs a longer search, not
/// events: the rows are found on the times, and the note says where the index is wrong.
/// `None` when the layout has no usable index.
pub fn index_window(
    path: &Path,
    info: &H5Info,
    from: TimeUs,
    to: TimeUs,
) -> Result<Option<IndexedRows>, InputError> {
    let file = open_file(path)?;
    let n = info.events;
    match info.layout {
        Layout::Dsec if file.link_exists("ms_to_idx") => dsec_window(path, &file, n, from, to),
        Layout::Mvsec(side) => mvsec_window(path, &file, side, n, from, to),
        _ => Ok(None),
    }
}

/// [`index_window`] through DSEC's `ms_to_idx`, each row it gives checked against the
/// event times (a contradiction noted, the rows then found on the times).
fn dsec_window(
    path: &Path,
    file: &hdf5::File,
    n: usize,
    from: TimeUs,
    to: TimeUs,
) -> Result<Option<IndexedRows>, InputError> {
    let offset = dsec_t_offset(file).map_err(|e| h5_error(path, "t_offset", e))?;
    let ms = check_dataset(path, file, "ms_to_idx", 1)?[0];
    if ms == 0 || n == 0 {
        return Ok(None);
    }
    let index = DsecIndex {
        path,
        file,
        n,
        offset,
    };
    let millisecond = |t: TimeUs| (t.saturating_sub(offset)).div_euclid(1000);
    let mut notes = Vec::new();
    let first = millisecond(from).clamp(0, ms as i64 - 1) as usize;
    let last = millisecond(to).saturating_add(1);
    let near_start = if from <= offset {
        0
    } else {
        index.checked(first, &mut notes)?
    };
    let near_end = if last < 0 {
        0
    } else if (last as u64) < ms as u64 {
        index.checked(last as usize, &mut notes)?
    } else {
        n
    };
    // the exact ends, on the times (the index's rows are where the search starts)
    let rows = rows_on_times((near_start, near_end), n, (from, to), &|row| {
        index.time_at(row)
    })?;
    Ok(Some((rows, notes.into_iter().next())))
}

/// A DSEC file's `ms_to_idx` and event times (`n` events, `t_offset` `offset`), read a row
/// at a time.
struct DsecIndex<'a> {
    path: &'a Path,
    file: &'a hdf5::File,
    n: usize,
    offset: TimeUs,
}

impl DsecIndex<'_> {
    /// The time of event `row` in the file's clock (`t_offset` added); `TimeUs::MAX` past
    /// the last event.
    fn time_at(&self, row: usize) -> Result<TimeUs, InputError> {
        if row >= self.n {
            return Ok(TimeUs::MAX);
        }
        let t = element::<u64>(self.file, "events/t", row)
            .map(|t| t as i64)
            .or_else(|_| element::<i64>(self.file, "events/t", row))
            .map_err(|e| h5_error(self.path, "events/t", e))?;
        Ok(t.saturating_add(self.offset))
    }

    /// The row `ms_to_idx` gives for millisecond `k`, checked against the times: the first
    /// row at or after the millisecond's start (a contradiction is noted in `notes`).
    fn checked(&self, k: usize, notes: &mut Vec<String>) -> Result<usize, InputError> {
        let (path, n) = (self.path, self.n);
        let v: u64 =
            element(self.file, "ms_to_idx", k).map_err(|e| h5_error(path, "ms_to_idx", e))?;
        let row = (v as usize).min(n);
        let begins = self.offset.saturating_add(k as i64 * 1000);
        let before_ok = row == 0 || self.time_at(row - 1)? < begins;
        let at_ok = row >= n || self.time_at(row)? >= begins;
        if !(before_ok && at_ok) {
            let actual = first_row_at_or_after(row, n, begins, &|row| self.time_at(row))?;
            notes.push(format!(
                "{}: ms_to_idx[{k}] = {row} contradicts events/t: the first event of millisecond {k} is row {actual}; the window was found on the event times instead (the index is damaged: rewrite it)",
                path.display()
            ));
        }
        Ok(row)
    }
}

/// The rows of the events of times `from..=to` of `n` rows sorted by time (`time_at`),
/// found on the times from rows an index gives near the window's start and end.
fn rows_on_times(
    (near_start, near_end): (usize, usize),
    n: usize,
    (from, to): (TimeUs, TimeUs),
    time_at: &impl Fn(usize) -> Result<TimeUs, InputError>,
) -> Result<std::ops::Range<usize>, InputError> {
    let start = first_row_at_or_after(near_start.min(n), n, from, time_at)?;
    let end = first_row_at_or_after(near_end.min(n), n, to.saturating_add(1), time_at)?;
    Ok(start..end.max(start))
}

/// [`index_window`] through MVSEC's `image_raw_event_inds` (the event nearest each frame),
/// where it is usable (as long as the frame stamps, non-decreasing, within the events).
fn mvsec_window(
    path: &Path,
    file: &hdf5::File,
    side: Side,
    n: usize,
    from: TimeUs,
    to: TimeUs,
) -> Result<Option<IndexedRows>, InputError> {
    let Some((us, indices)) = mvsec_frame_index(path, file, side, n)? else {
        return Ok(None);
    };
    // the frames around the window give rows near its ends (the event nearest each
    // frame); the exact ends are then found on the event times themselves
    let events = file
        .dataset(&format!("{}/events", side.group()))
        .map_err(|e| h5_error(path, "events", e))?;
    let before = us.partition_point(|&t| t <= from);
    let near_start = if before >= 1 {
        indices[before - 1] as usize
    } else {
        0
    };
    let after = us.partition_point(|&t| t < to);
    let near_end = if after < indices.len() {
        indices[after] as usize
    } else {
        n
    };
    let rows = rows_on_times((near_start, near_end), n, (from, to), &|row| {
        mvsec_event_time(path, &events, row)
    })?;
    Ok(Some((rows, None)))
}

/// Each frame's time (microseconds) and the row of the event nearest it.
type FrameRows = (Vec<TimeUs>, Vec<i64>);

/// MVSEC's frame index where it is usable: each frame's time (microseconds) and the row of
/// the event nearest it, the rows non-decreasing within the `n` events; `None` where the
/// file has no index or it is not usable.
fn mvsec_frame_index(
    path: &Path,
    file: &hdf5::File,
    side: Side,
    n: usize,
) -> Result<Option<FrameRows>, InputError> {
    let inds = format!("{}/image_raw_event_inds", side.group());
    let stamps = format!("{}/image_raw_ts", side.group());
    if !file.link_exists(&inds) || !file.link_exists(&stamps) {
        return Ok(None);
    }
    let err = |e| h5_error(path, &inds, e);
    let times: Vec<f64> = file
        .dataset(&stamps)
        .and_then(|d| d.read_raw())
        .map_err(err)?;
    let indices: Vec<i64> = file
        .dataset(&inds)
        .and_then(|d| d.read_raw())
        .map_err(err)?;
    let usable = times.len() == indices.len()
        && indices.windows(2).all(|w| w[0] <= w[1])
        && indices.iter().all(|&i| i >= 0 && i as usize <= n)
        && times.iter().all(|t| t.is_finite());
    if !usable || times.is_empty() {
        return Ok(None);
    }
    let us: Vec<TimeUs> = times.iter().map(|&t| crate::events::s_to_us(t)).collect();
    Ok(Some((us, indices)))
}

/// The time of event `row` of an MVSEC `events` table (its third column, in seconds);
/// `TimeUs::MAX` where it is not a plausible time or past the last event.
fn mvsec_event_time(path: &Path, events: &hdf5::Dataset, row: usize) -> Result<TimeUs, InputError> {
    let v = events
        .read_slice_2d::<f64, _>(ndarray::s![row..row + 1, 2..3])
        .map_err(|e| h5_error(path, "events", e))?;
    Ok(v.iter().next().map_or(TimeUs::MAX, |&s| {
        if s.is_finite() && s.abs() < 1e12 {
            crate::events::s_to_us(s)
        } else {
            TimeUs::MAX
        }
    }))
}

/// The columns appended to `out` (one fused pass split over the cores, converting while
/// tracking each column's extremes), and the extremes of x, y, p and t.
fn convert(columns: &Columns, out: &mut EventChunk) -> ([i64; 4], [i64; 4]) {
    let Columns {
        t,
        x: xs,
        y: ys,
        p: ps,
    } = columns;
    let start = out.len();
    let n = t.len();
    out.t.extend_from_slice(t);
    out.x.resize(start + n, 0);
    out.y.resize(start + n, 0);
    out.on.resize(start + n, false);
    const PIECE: usize = 1 << 14;
    let (lo, hi) = out.x[start..]
        .par_chunks_mut(PIECE)
        .zip(out.y[start..].par_chunks_mut(PIECE))
        .zip(out.on[start..].par_chunks_mut(PIECE))
        .enumerate()
        .map(|(k, ((x_out, y_out), on_out))| {
            let base = k * PIECE;
            let (mut lo, mut hi) = ([i64::MAX; 4], [i64::MIN; 4]);
            for j in 0..x_out.len() {
                let i = base + j;
                let values = [xs[i], ys[i], ps[i], t[i]];
                for v in 0..4 {
                    lo[v] = lo[v].min(values[v]);
                    hi[v] = hi[v].max(values[v]);
                }
                x_out[j] = xs[i] as u16;
                y_out[j] = ys[i] as u16;
                on_out[j] = ps[i] == 1;
            }
            (lo, hi)
        })
        .reduce(
            || ([i64::MAX; 4], [i64::MIN; 4]),
            |(a_lo, a_hi), (b_lo, b_hi)| {
                (
                    std::array::from_fn(|v| a_lo[v].min(b_lo[v])),
                    std::array::from_fn(|v| a_hi[v].max(b_hi[v])),
                )
            },
        );
    (lo, hi)
}

impl H5Decoder {
    /// The chunk's events appended one by one, the first out of range named with its
    /// index and the fix.
    fn checked_one_by_one(&mut self, out: &mut EventChunk) -> Result<(), InputError> {
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
            check_coordinates(&self.path, &names, index, (x, y), self.sensor)?;
            if t[i] == TimeUs::MIN {
                return Err(InputError::corrupt(
                    &self.path,
                    format!("{}[{index}]", names.t),
                    "the timestamp is not a finite number",
                    "the file is damaged; rewrite it from the source recording",
                ));
            }
            let on = checked_polarity(&self.path, names.p, index, ps[i])?;
            self.order.check(t[i], || format!("{}[{index}]", names.t));
            out.push(t[i], x as u16, y as u16, on);
        }
        Ok(())
    }
}

/// Checks the coordinates of event `index`: whole numbers (stored in the datasets `names`
/// gives), on `sensor` (within [`MAX_SENSOR_SIDE`] where it is not known).
fn check_coordinates(
    path: &Path,
    names: &FieldNames,
    index: usize,
    (x, y): (i64, i64),
    sensor: Option<Sensor>,
) -> Result<(), InputError> {
    if x == NOT_AN_INTEGER || y == NOT_AN_INTEGER {
        let (name, value) = if x == NOT_AN_INTEGER {
            (names.x, x)
        } else {
            (names.y, y)
        };
        return Err(InputError::corrupt(
            path,
            format!("{name}[{index}]"),
            format!("the coordinate is {}", shown(value)),
            "coordinates must be whole pixel numbers; the file is damaged or was written from floating-point data: rewrite it with integer x and y",
        ));
    }
    if !(x >= 0 && y >= 0 && crate::within(sensor, x as u32, y as u32))
        || x > u32::MAX as i64
        || y > u32::MAX as i64
    {
        return Err(crate::outside_sensor(
            path,
            format!("event index {index} ({}, {})", names.x, names.y),
            x,
            y,
            sensor,
        ));
    }
    Ok(())
}

/// Whether the polarity `p` of event `index` (in dataset `name`) is ON: 1 is ON, 0 and -1
/// are OFF, anything else an error.
fn checked_polarity(path: &Path, name: &str, index: usize, p: i64) -> Result<bool, InputError> {
    match p {
        1 => Ok(true),
        0 | -1 => Ok(false),
        other => Err(InputError::corrupt(
            path,
            format!("{name}[{index}]"),
            format!("the polarity is {}", shown(other)),
            "polarities are 1 (ON) and 0 or -1 (OFF); the file is damaged or uses another convention",
        )),
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
        // fast path: every value in range (four vectorisable min/max passes), then the
        // columns moved over in bulk; anything out of range is found and named below
        let (width, height) = self
            .sensor
            .map_or((MAX_SENSOR_SIDE as i64, MAX_SENSOR_SIDE as i64), |s| {
                (s.width as i64, s.height as i64)
            });
        let start = out.len();
        let (lo, hi) = convert(&self.columns, out);
        let all_valid = lo[0] >= 0
            && hi[0] < width
            && lo[1] >= 0
            && hi[1] < height
            && lo[2] >= -1
            && hi[2] <= 1
            && lo[3] != TimeUs::MIN;
        if all_valid {
            let (position, names) = (self.position, self.table.names());
            self.order.check_all(&self.columns.t, |i| {
                format!("{}[{}]", names.t, position + i)
            });
        } else {
            // something is out of range: undo, and find and name it event by event
            out.t.truncate(start);
            out.x.truncate(start);
            out.y.truncate(start);
            out.on.truncate(start);
            self.checked_one_by_one(out)?;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_row_of_a_time_is_found_from_any_starting_row() {
        // times with repeats and gaps
        let times: Vec<TimeUs> = [0, 0, 3, 5, 5, 5, 9, 12, 12, 20, 21, 30]
            .into_iter()
            .collect();
        let n = times.len();
        let time_at = |row: usize| -> Result<TimeUs, InputError> { Ok(times[row]) };
        for t in -1..=32 {
            let expected = times.partition_point(|&v| v < t);
            for near in 0..=n {
                assert_eq!(
                    first_row_at_or_after(near, n, t, &time_at).unwrap(),
                    expected,
                    "t {t} from row {near}"
                );
            }
        }
    }
}
