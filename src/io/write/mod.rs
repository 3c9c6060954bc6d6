//! Writers: IJRR folders ([`ijrr`]), event_utils HDF5 files ([`h5`]) and Prophesee EVT3
//! ([`evt3`]). Every writer works in a temporary sibling and renames it into place at the end,
//! so a failure never leaves a half-written output under the requested name.

pub mod evt3;
pub mod h5;
pub mod ijrr;

pub use evt3::Evt3Writer;
pub use h5::H5Writer;
pub use ijrr::IjrrWriter;

use super::error::InputError;
use crate::events::{Frame, TimeUs};
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

/// An output being written under a temporary sibling name: moved into place by
/// [`Staged::commit`], deleted when dropped uncommitted (an error or a panic midway).
#[derive(Debug)]
pub struct Staged {
    pub target: PathBuf,
    pub partial: PathBuf,
    committed: bool,
}

impl Staged {
    /// Stages an output for `target` (a stale partial copy of an earlier run is removed).
    pub fn new(target: &Path) -> Result<Self, InputError> {
        let partial = temporary_sibling(target);
        remove_any(&partial).map_err(|e| InputError::write(&partial, e))?;
        Ok(Self {
            target: target.to_path_buf(),
            partial,
            committed: false,
        })
    }

    /// Moves the finished output into place.
    pub fn commit(mut self) -> Result<(), InputError> {
        commit(&self.partial, &self.target)?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.committed {
            // best effort: the error that stopped the writer is the one to report
            let _ = remove_any(&self.partial);
        }
    }
}

fn remove_any(path: &Path) -> std::io::Result<()> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => std::fs::remove_dir_all(path),
        Ok(_) => std::fs::remove_file(path),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(e),
    }
}

/// Writes `bytes` to `path` atomically (temporary sibling, then rename).
pub fn write_file_atomically(path: &Path, bytes: &[u8]) -> Result<(), InputError> {
    let staged = Staged::new(path)?;
    std::fs::write(&staged.partial, bytes).map_err(|e| InputError::write(path, e))?;
    staged.commit()
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
