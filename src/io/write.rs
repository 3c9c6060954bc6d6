//! Writers for the two interchange layouts: IJRR folders (`events.txt` with a `width height`
//! first line, then `t x y p` with t in seconds to the microsecond; `images.txt` +
//! `images/frame_XXXXXXXX.png`) and event_utils HDF5 files. Both write into a temporary
//! sibling and rename it into place at the end, so a failure never leaves a half-written
//! output under the requested name.

use super::error::InputError;
use crate::events::{EventChunk, Frame, Sensor, TimeUs};
use std::io::Write;
use std::path::{Path, PathBuf};

/// A temporary sibling path for `target` (same folder, so the final rename is atomic).
pub fn temporary_sibling(target: &Path) -> PathBuf {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    target.with_file_name(format!(".{name}.ctcal-partial-{}", std::process::id()))
}

/// Moves `partial` to `target`, replacing an existing file or folder there.
pub fn commit(partial: &Path, target: &Path) -> Result<(), InputError> {
    if target.is_dir() {
        let old = target.with_file_name(format!(
            ".{}.ctcal-old-{}",
            target.file_name().unwrap_or_default().to_string_lossy(),
            std::process::id()
        ));
        std::fs::rename(target, &old).map_err(|e| InputError::write(target, e))?;
        std::fs::rename(partial, target).map_err(|e| InputError::write(target, e))?;
        std::fs::remove_dir_all(&old).map_err(|e| InputError::write(&old, e))?;
    } else {
        std::fs::rename(partial, target).map_err(|e| InputError::write(target, e))?;
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically (temporary sibling, then rename).
pub fn write_file_atomically(path: &Path, bytes: &[u8]) -> Result<(), InputError> {
    let partial = temporary_sibling(path);
    std::fs::write(&partial, bytes).map_err(|e| InputError::write(path, e))?;
    commit(&partial, path)
}

/// Formats microseconds as seconds with six decimals (`-0.000001`, `12.345678`).
pub fn format_seconds(t: TimeUs, out: &mut Vec<u8>) {
    let mut buffer = itoa::Buffer::new();
    if t < 0 {
        out.push(b'-');
    }
    let magnitude = t.unsigned_abs();
    out.extend_from_slice(buffer.format(magnitude / 1_000_000).as_bytes());
    out.push(b'.');
    let fraction = buffer.format(magnitude % 1_000_000);
    out.extend(std::iter::repeat_n(b'0', 6 - fraction.len()));
    out.extend_from_slice(fraction.as_bytes());
}

/// Writes an IJRR folder.
pub struct IjrrWriter {
    target: PathBuf,
    partial: PathBuf,
    events: std::io::BufWriter<std::fs::File>,
    line: Vec<u8>,
    frames: Vec<u8>,
    frame_count: usize,
}

impl IjrrWriter {
    /// Starts a folder at `target`; `sensor` becomes the `width height` first line.
    pub fn create(target: &Path, sensor: Sensor) -> Result<Self, InputError> {
        let partial = temporary_sibling(target);
        if partial.exists() {
            std::fs::remove_dir_all(&partial).map_err(|e| InputError::write(&partial, e))?;
        }
        std::fs::create_dir_all(&partial).map_err(|e| InputError::write(target, e))?;
        let file = std::fs::File::create(partial.join("events.txt"))
            .map_err(|e| InputError::write(target, e))?;
        let mut events = std::io::BufWriter::with_capacity(1 << 20, file);
        writeln!(events, "{} {}", sensor.width, sensor.height)
            .map_err(|e| InputError::write(target, e))?;
        Ok(Self {
            target: target.to_path_buf(),
            partial,
            events,
            line: Vec::with_capacity(64),
            frames: Vec::new(),
            frame_count: 0,
        })
    }

    pub fn write_events(&mut self, chunk: &EventChunk) -> Result<(), InputError> {
        let mut buffer = itoa::Buffer::new();
        for i in 0..chunk.len() {
            self.line.clear();
            format_seconds(chunk.t[i], &mut self.line);
            self.line.push(b' ');
            self.line
                .extend_from_slice(buffer.format(chunk.x[i]).as_bytes());
            self.line.push(b' ');
            self.line
                .extend_from_slice(buffer.format(chunk.y[i]).as_bytes());
            self.line
                .extend_from_slice(if chunk.on[i] { b" 1\n" } else { b" 0\n" });
            self.events
                .write_all(&self.line)
                .map_err(|e| InputError::write(&self.target, e))?;
        }
        Ok(())
    }

    /// Adds a frame (PNG in `images/`, a line in `images.txt`).
    pub fn write_frame(&mut self, frame: &Frame) -> Result<(), InputError> {
        let folder = self.partial.join("images");
        if self.frame_count == 0 {
            std::fs::create_dir_all(&folder).map_err(|e| InputError::write(&self.target, e))?;
        }
        let name = format!("images/frame_{:08}.png", self.frame_count);
        save_png(&self.partial.join(&name), frame)
            .map_err(|e| InputError::write(&self.target, e))?;
        format_seconds(frame.t, &mut self.frames);
        self.frames
            .extend_from_slice(format!(" {name}\n").as_bytes());
        self.frame_count += 1;
        Ok(())
    }

    /// Flushes and moves the folder into place.
    pub fn finish(mut self) -> Result<(), InputError> {
        self.events
            .flush()
            .map_err(|e| InputError::write(&self.target, e))?;
        if self.frame_count > 0 {
            std::fs::write(self.partial.join("images.txt"), &self.frames)
                .map_err(|e| InputError::write(&self.target, e))?;
        }
        commit(&self.partial, &self.target)
    }
}

/// Saves an 8-bit grey PNG.
pub fn save_png(path: &Path, frame: &Frame) -> std::io::Result<()> {
    image::save_buffer(
        path,
        &frame.pixels,
        frame.width,
        frame.height,
        image::ExtendedColorType::L8,
    )
    .map_err(std::io::Error::other)
}

/// Writes an event_utils HDF5 file: `events/ts|xs|ys|ps`, `images/image%09d` with a
/// `timestamp` attribute, and the root attributes event_utils writes (`sensor_resolution`
/// as (H, W), `num_events`, `num_pos`, `num_neg`, `t0`, `tk`, `duration`, `num_imgs`).
pub struct H5Writer {
    target: PathBuf,
    partial: PathBuf,
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
    pub fn create(target: &Path, sensor: Sensor) -> Result<Self, InputError> {
        let partial = temporary_sibling(target);
        let err = |e: hdf5::Error| InputError::write(target, std::io::Error::other(e.to_string()));
        let file = hdf5::File::create(&partial).map_err(err)?;
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
            target: target.to_path_buf(),
            partial,
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
        InputError::write(&self.target, std::io::Error::other(e.to_string()))
    }

    pub fn write_events(&mut self, chunk: &EventChunk) -> Result<(), InputError> {
        if chunk.is_empty() {
            return Ok(());
        }
        if self.sensor.width > i16::MAX as u16 || self.sensor.height > i16::MAX as u16 {
            return Err(InputError::invalid(
                &self.target,
                format!(
                    "the {} sensor does not fit event_utils' int16 coordinates",
                    self.sensor
                ),
                "write an IJRR folder instead (--to ijrr)",
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
        let (partial, target) = (self.partial.clone(), self.target.clone());
        drop(self.file);
        commit(&partial, &target)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seconds_are_printed_to_the_microsecond() {
        let show = |t| {
            let mut v = Vec::new();
            format_seconds(t, &mut v);
            String::from_utf8(v).unwrap()
        };
        assert_eq!(show(0), "0.000000");
        assert_eq!(show(3_811), "0.003811");
        assert_eq!(show(1_589_163_147_368_868), "1589163147.368868");
        assert_eq!(show(-1), "-0.000001");
    }
}
