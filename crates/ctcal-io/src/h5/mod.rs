//! HDF5 event files in the layouts researchers meet most:
//!
//! - event_utils / event_cnn_minimal (Stoffregen et al. 2020): `events/ts` (float64 seconds;
//!   integer timestamps, which some writers store, are read as microseconds),
//!   `events/xs`, `events/ys` (integers), `events/ps` (bool or 0/1 or -1/1), frames as
//!   `images/image%09d` with a `timestamp` attribute in seconds, and a root attribute
//!   `sensor_resolution` = (H, W). Writers disagree on that order, so the claim is checked
//!   against the coordinates and swapped when only the swapped reading contains them;
//! - v2e: `events` N x 4 unsigned `[t_us, x, y, p]`, frames in `frame` (N, H, W) with
//!   `frame_ts` in microseconds;
//! - MVSEC (Zhu et al., RA-L 2018): `davis/left/events` (or `davis/right`) N x 4 float64
//!   `[x, y, t, p]` with `t` in seconds since the epoch and `p` -1/1, grey frames in
//!   `davis/left/image_raw` (M, H, W) with `image_raw_ts` in seconds;
//! - DSEC (Gehrig et al., RA-L 2021): `events/x`, `events/y`, `events/t` (microseconds after
//!   the scalar `t_offset`, also microseconds), `events/p` (0/1), compressed with the Blosc
//!   filter (id 32001, zstd inside), which ctcal decodes itself (no HDF5 plugin needed).
//!   Times are reported as `t + t_offset`, the file's own clock.
//!
//! Read through `hdf5-metno` (libhdf5) in chunks of `CHUNK_EVENTS` rows; compressed 1-D
//! columns by direct chunk access on all cores ([`direct`])..
//!
//! The layouts, the MVSEC side and what a file holds ([`H5Info`]) are always compiled, so a
//! build without HDF5 still parses `--side` and names what it cannot read; the reading
//! itself ([`read`]) needs libhdf5 and comes with the crate's default feature `hdf5`.

#[cfg(feature = "hdf5")]
mod direct;
#[cfg(feature = "hdf5")]
mod frame_pixels;
#[cfg(feature = "hdf5")]
mod read;
#[cfg(feature = "hdf5")]
pub use read::*;

use crate::events::Sensor;

/// HDF5 signature at the start of a file.
pub const SIGNATURE: &[u8] = b"\x89HDF\r\n\x1a\n";

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    EventUtils,
    V2e,
    Mvsec(Side),
    Dsec,
}

impl Layout {
    /// The layout's name, for `info`.
    pub fn name(self) -> &'static str {
        match self {
            Layout::EventUtils => "event_utils",
            Layout::V2e => "v2e",
            Layout::Mvsec(_) => "MVSEC",
            Layout::Dsec => "DSEC",
        }
    }
}

/// Which camera of a stereo MVSEC file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Side {
    #[default]
    Left,
    Right,
}

impl Side {
    pub fn name(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }
}

impl std::str::FromStr for Side {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "left" => Ok(Side::Left),
            "right" => Ok(Side::Right),
            _ => Err(format!("`{s}` is not a side (left or right)")),
        }
    }
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
    /// Remarks for the user (e.g. times stored with less than microsecond precision).
    pub notes: Vec<String>,
}

#[cfg(all(test, not(feature = "hdf5")))]
mod tests {
    use crate::{InputError, OpenOptions, Recording};

    /// Without libhdf5 an HDF5 file is recognised by its signature and refused with the
    /// fix, not misread as another format.
    #[test]
    fn an_hdf5_file_is_named_and_refused_without_the_feature() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("events.h5");
        let mut bytes = super::SIGNATURE.to_vec();
        bytes.resize(4096, 0);
        std::fs::write(&path, bytes).unwrap();
        let error = Recording::open(&path, &OpenOptions::default()).unwrap_err();
        assert!(matches!(error, InputError::Hdf5 { .. }), "{error}");
        let shown = error.to_string();
        assert!(shown.contains("events.h5"), "{shown}");
        assert!(shown.contains("feature `hdf5`"), "{shown}");
    }
}
