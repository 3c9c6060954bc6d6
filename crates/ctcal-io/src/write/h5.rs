//! event_utils HDF5 files (Stoffregen et al. 2020's layout): `events/ts` (float64 seconds),
//! `events/xs`, `events/ys` (int16), `events/ps` (bool), frames as `images/image%09d`.

use super::{OutputPolicy, Staged};
use crate::Format;
use crate::error::InputError;
use crate::events::{EventChunk, Frame, Sensor, TimeUs};
use crate::hint::{Hint, Text};
use std::path::Path;

/// Writes an event_utils HDF5 file: `events/ts|xs|ys|ps`, `images/image%09d` with a
/// `timestamp` attribute, and the root attributes event_utils writes (`sensor_resolution`
/// as (H, W), `num_events`, `num_pos`, `num_neg`, `t0`, `tk`, `duration`, `num_imgs`).
pub struct H5Writer {
    staged: Staged,
    file: hdf5::File,
    sensor: Sensor,
    written: usize,
    on: u64,
    first: Option<TimeUs>,
    last: TimeUs,
    frames: usize,
}

const H5_CHUNK: usize = 1 << 16;

impl H5Writer {
    pub fn create(
        target: &Path,
        sensor: Sensor,
        policy: &OutputPolicy,
    ) -> Result<Self, InputError> {
        let staged = policy.file(target)?;
        if staged.in_place {
            return Err(InputError::invalid(
                target,
                "is a device or pipe; HDF5 needs a regular file it can seek in",
                "give the path of a file (e.g. out.h5)",
            ));
        }
        let err = |e: hdf5::Error| InputError::write(target, std::io::Error::other(e.to_string()));
        let file = hdf5::File::create(&staged.partial).map_err(err)?;
        let events = file.create_group("events").map_err(err)?;
        macro_rules! column {
            ($t:ty, $name:expr) => {
                events
                    .new_dataset::<$t>()
                    .chunk(H5_CHUNK)
                    .deflate(1)
                    .shape(hdf5::Extent::resizable(0))
                    .create($name)
                    .map_err(err)?
            };
        }
        column!(f64, "ts");
        column!(i16, "xs");
        column!(i16, "ys");
        column!(bool, "ps");
        Ok(Self {
            staged,
            file,
            sensor,
            written: 0,
            on: 0,
            first: None,
            last: 0,
            frames: 0,
        })
    }

    fn err(&self, e: hdf5::Error) -> InputError {
        InputError::write(&self.staged.shown, std::io::Error::other(e.to_string()))
    }

    pub fn write_events(&mut self, chunk: &EventChunk) -> Result<(), InputError> {
        if chunk.is_empty() {
            return Ok(());
        }
        if self.sensor.width > i16::MAX as u16 || self.sensor.height > i16::MAX as u16 {
            return Err(InputError::invalid(
                &self.staged.shown,
                format!(
                    "the {} sensor does not fit event_utils' int16 coordinates",
                    self.sensor
                ),
                Text::from("write an IJRR folder instead").aside(Hint::WriteAs(Format::Ijrr)),
            ));
        }
        let start = self.written;
        let end = start + chunk.len();
        let ts: Vec<f64> = chunk.t.iter().map(|&t| t as f64 / 1e6).collect();
        let xs: Vec<i16> = chunk.x.iter().map(|&x| x as i16).collect();
        let ys: Vec<i16> = chunk.y.iter().map(|&y| y as i16).collect();
        let result = (|| -> hdf5::Result<()> {
            let ds = |name: &str| self.file.dataset(&format!("events/{name}"));
            for name in ["ts", "xs", "ys", "ps"] {
                ds(name)?.resize(end)?;
            }
            ds("ts")?.write_slice(&ts, start..end)?;
            ds("xs")?.write_slice(&xs, start..end)?;
            ds("ys")?.write_slice(&ys, start..end)?;
            ds("ps")?.write_slice(&chunk.on, start..end)?;
            Ok(())
        })();
        result.map_err(|e| self.err(e))?;
        self.written = end;
        self.on += chunk.on.iter().filter(|&&p| p).count() as u64;
        self.first.get_or_insert(chunk.t[0]);
        self.last = *chunk.t.last().expect("non-empty");
        Ok(())
    }

    pub fn write_frame(&mut self, frame: &Frame) -> Result<(), InputError> {
        let result = (|| -> hdf5::Result<()> {
            let group = match self.file.group("images") {
                Ok(g) => g,
                Err(_) => self.file.create_group("images")?,
            };
            let array = ndarray::Array2::from_shape_vec(
                (frame.height as usize, frame.width as usize),
                frame.pixels.clone(),
            )
            .map_err(|e| hdf5::Error::from(e.to_string()))?;
            let ds = group
                .new_dataset_builder()
                .with_data(&array)
                .create(format!("image{:09}", self.frames).as_str())?;
            ds.new_attr::<f64>()
                .create("timestamp")?
                .write_scalar(&(frame.t as f64 / 1e6))?;
            ds.new_attr_builder()
                .with_data(&[frame.height as i64, frame.width as i64])
                .create("size")?;
            Ok(())
        })();
        result.map_err(|e| self.err(e))?;
        self.frames += 1;
        Ok(())
    }

    /// Writes the root attributes, closes the file and moves it into place.
    pub fn finish(self) -> Result<(), InputError> {
        let first = self.first.unwrap_or(0);
        let result = (|| -> hdf5::Result<()> {
            let f = &self.file;
            f.new_attr::<hdf5::types::VarLenUnicode>()
                .create("ctcal_version")?
                .write_scalar(
                    &env!("CARGO_PKG_VERSION")
                        .parse::<hdf5::types::VarLenUnicode>()
                        .expect("a version has no NUL"),
                )?;
            f.new_attr_builder()
                .with_data(&[self.sensor.height as i64, self.sensor.width as i64])
                .create("sensor_resolution")?;
            let scalar_i = |name: &str, v: i64| -> hdf5::Result<()> {
                f.new_attr::<i64>().create(name)?.write_scalar(&v)
            };
            let scalar_f = |name: &str, v: f64| -> hdf5::Result<()> {
                f.new_attr::<f64>().create(name)?.write_scalar(&v)
            };
            scalar_i("num_events", self.written as i64)?;
            scalar_i("num_pos", self.on as i64)?;
            scalar_i("num_neg", self.written as i64 - self.on as i64)?;
            scalar_i("num_imgs", self.frames as i64)?;
            scalar_f("t0", first as f64 * 1e-6)?;
            scalar_f("tk", self.last as f64 * 1e-6)?;
            scalar_f("duration", (self.last - first) as f64 * 1e-6)?;
            Ok(())
        })();
        result.map_err(|e| self.err(e))?;
        drop(self.file);
        self.staged.commit()
    }
}
