//! One HDF5 frame's grey levels, checked before they are used.
//!
//! ctcal's frames are 8-bit grey levels (the DAVIS APS readout as event_utils, v2e and MVSEC
//! store it). Datasets of other types are read as numbers and refused when they cannot be
//! grey levels, instead of letting libhdf5's type conversion decide: it turns NaN into 0,
//! saturates 12-bit values at 255 and truncates a frame normalised to [0, 1] to black and
//! white, and each of those reads as a scene without a word.
//!
//! Why refuse a normalised frame instead of scaling it: the log response ln(DN + b) is fitted
//! in grey levels, and a guessed scale would move the fitted offset b with it.

use super::read::h5_error;
use crate::error::InputError;
use hdf5::types::{IntSize, TypeDescriptor};
use std::path::Path;

/// A frame's values, where they came from and the frame's width (to name pixels).
struct FrameValues<'a> {
    path: &'a Path,
    place: &'a str,
    width: u32,
    values: Vec<f64>,
}

/// One frame's grey levels: a whole dataset (`row` `None`) or row `row` of a stack, at
/// `place`. 8-bit datasets are read as they are; others as numbers, which must be finite
/// grey levels 0-255 (rounded to the nearest level).
pub(super) fn frame_pixels(
    path: &Path,
    ds: &hdf5::Dataset,
    row: Option<usize>,
    place: &str,
    width: u32,
) -> Result<Vec<u8>, InputError> {
    let descriptor = ds.dtype().and_then(|d| d.to_descriptor());
    let eight_bit = matches!(
        descriptor,
        Ok(TypeDescriptor::Unsigned(IntSize::U1) | TypeDescriptor::Boolean)
    );
    if eight_bit || descriptor.is_err() {
        return frame_values::<u8>(ds, row).map_err(|e| h5_error(path, place, e));
    }
    let frame = FrameValues {
        path,
        place,
        width,
        values: frame_values::<f64>(ds, row).map_err(|e| h5_error(path, place, e))?,
    };
    frame.check_finite()?;
    frame.check_grey_levels()?;
    Ok(frame.values.iter().map(|&v| v.round() as u8).collect())
}

fn frame_values<T: hdf5::H5Type + Copy>(
    ds: &hdf5::Dataset,
    row: Option<usize>,
) -> hdf5::Result<Vec<T>> {
    match row {
        None => ds.read_raw::<T>(),
        Some(i) => Ok(ds
            .read_slice_2d::<T, _>(ndarray::s![i, .., ..])?
            .iter()
            .copied()
            .collect()),
    }
}

impl FrameValues<'_> {
    /// Refuses a frame with NaN or infinite pixels, naming how many and the first.
    fn check_finite(&self) -> Result<(), InputError> {
        self.refuse_pixels(
            |v| !v.is_finite(),
            "NaN or infinite",
            "the frame is damaged: write it again from its source (grey levels are finite numbers), or leave it out of the file",
        )
    }

    /// Refuses a frame whose values are not 8-bit grey levels: outside 0-255 (a 10- or
    /// 12-bit readout, signed data), or all within [0, 1] with fractions (normalised).
    fn check_grey_levels(&self) -> Result<(), InputError> {
        self.refuse_pixels(
            |v| !(-0.5..255.5).contains(&v),
            "outside the grey levels 0-255",
            "write the frames as 8-bit grey levels (uint8): scale a 10- or 12-bit readout to 0-255 (e.g. value >> 4 for 12 bits)",
        )?;
        let max = self.values.iter().copied().fold(f64::MIN, f64::max);
        let fractional = self.values.iter().any(|v| v.fract() != 0.0);
        if max <= 1.0 && fractional {
            return Err(InputError::corrupt(
                self.path,
                self.place,
                format!(
                    "the frame's values all lie in [0, 1] with fractions (largest {max}): a normalised frame, while ctcal reads grey levels 0-255 (the log response ln(DN + b) is fitted in grey levels, so ctcal does not guess a scale)"
                ),
                "write the frames as 8-bit grey levels: round(255 x value) as uint8, if 1.0 was white",
            ));
        }
        Ok(())
    }

    /// Refuses the frame when any pixel is `bad`, naming how many and the first.
    fn refuse_pixels(
        &self,
        bad: impl Fn(f64) -> bool,
        what: &str,
        fix: &'static str,
    ) -> Result<(), InputError> {
        let Some(first) = self.values.iter().position(|&v| bad(v)) else {
            return Ok(());
        };
        let count = self.values.iter().filter(|&&v| bad(v)).count();
        let verb = if count == 1 { "is" } else { "are" };
        let width = self.width.max(1) as usize;
        let (x, y) = (first % width, first / width);
        Err(InputError::corrupt(
            self.path,
            self.place,
            format!(
                "{count} of the frame's {} pixels {verb} {what} (the first at x = {x}, y = {y}: {})",
                self.values.len(),
                self.values[first]
            ),
            fix,
        ))
    }
}
