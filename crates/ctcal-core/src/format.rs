//! The file formats ctcal reads: named here, below the readers, so that the messages of
//! every crate (a [`Hint`](crate::hint::Hint) to give the format) can name one; the readers
//! are in the IO crate (`ctcal-io`), which re-exports this type.

use serde::Serialize;

/// The file formats ctcal reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    Ijrr,
    H5,
    Aedat4,
    Evt2,
    Evt3,
    Dat,
    Bag,
}

impl Format {
    pub const ALL: [Format; 7] = [
        Format::Ijrr,
        Format::H5,
        Format::Aedat4,
        Format::Evt2,
        Format::Evt3,
        Format::Dat,
        Format::Bag,
    ];

    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Format::Ijrr => "ijrr",
            Format::H5 => "h5",
            Format::Aedat4 => "aedat4",
            Format::Evt2 => "evt2",
            Format::Evt3 => "evt3",
            Format::Dat => "dat",
            Format::Bag => "bag",
        }
    }
}

impl std::str::FromStr for Format {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Format::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| {
                format!("unknown format `{s}` (one of ijrr, h5, aedat4, evt2, evt3, dat, bag)")
            })
    }
}

impl std::fmt::Display for Format {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
