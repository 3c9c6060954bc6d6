//! Writers: IJRR folders ([`ijrr`]), event_utils HDF5 files (`h5`), Prophesee EVT3
//! ([`evt3`]), ROS1 bags ([`bag`]) and the DSEC HDF5 layout (`dsec`; both HDF5 writers with
//! the feature `hdf5`). Every writer works in a temporary sibling and moves it into place at the end,
//! so a failure never leaves a half-written output under the requested name; where ctcal may
//! write at all is decided by [`destination`].

pub mod bag;
pub mod destination;
#[cfg(feature = "hdf5")]
pub mod dsec;
pub mod evt3;
#[cfg(feature = "hdf5")]
pub mod h5;
pub mod ijrr;

pub use bag::{BagCompression, BagWriter};
pub use destination::{OutputPolicy, Staged, StagedFolder};
pub use evt3::Evt3Writer;
#[cfg(feature = "hdf5")]
pub use h5::H5Writer;
pub use ijrr::IjrrWriter;

use crate::events::{Frame, TimeUs};
use std::path::Path;

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
