//! The fit of a window, on the region of the sensor it can afford: a sensor with more
//! pixels than a 346x260 one is fitted on the rectangle of that many pixels where its events
//! are densest ([`ctcal_core::region`]), the hot pixels it names given in the sensor's
//! coordinates and the region named in `assumptions`. The `ctcal fit` command, the report
//! and the Python package all fit through here.

use crate::estimate::{EstimateError, Progress};
use crate::frame_blocks::LIMIT_PIXELS;
use crate::selection::Roi;
use crate::window::Loaded;
use ctcal_core::fit::{FitInput, FitOptions, FitResult};

/// The most pixels a fit simulates unless told otherwise: a 346x260 sensor's (the frame
/// limit's sensor, [`LIMIT_PIXELS`]).
pub const FIT_PIXELS: usize = LIMIT_PIXELS;

impl Loaded {
    /// The same window on the pixels of `roi` only, as a sensor of the region's size.
    pub fn within(&self, roi: Roi) -> Loaded {
        let selection = self.selection.within(roi);
        Loaded {
            recording: self.recording.clone(),
            sensor: roi.as_sensor(),
            sensor_source: self.sensor_source.clone(),
            events: self.events.within(roi),
            frames: self.frames.iter().map(|f| f.within(roi)).collect(),
            frames_available: self.frames_available,
            frame_limit: self.frame_limit,
            unread: self.unread.clone(),
            excluded: selection.excluded(),
            selection,
            notes: self.notes.clone(),
        }
    }
}

/// `ctcal fit` of `loaded` with `options`, on its busiest region of at most `max_pixels`
/// pixels where it has frames and more pixels than that (0: the whole sensor); the window's
/// notes and the recording's biases added.
pub fn fit(
    loaded: &Loaded,
    options: &FitOptions,
    max_pixels: usize,
    progress: Progress,
) -> Result<FitResult, EstimateError> {
    let region = (loaded.frames.len() >= 2)
        .then(|| {
            ctcal_core::region::busiest_region(
                &loaded.events,
                loaded.sensor,
                &loaded.excluded,
                max_pixels,
            )
        })
        .flatten();
    let cut = region.map(|roi| loaded.within(roi));
    let input = cut.as_ref().unwrap_or(loaded);
    let mut result = ctcal_core::fit::fit(
        &FitInput {
            sensor: input.sensor,
            events: &input.events,
            frames: &input.frames,
            excluded: &input.excluded,
            unread: &input.unread,
        },
        options,
        progress,
    )?;
    if let Some(roi) = region {
        for p in &mut result.hot_pixels_masked {
            (p.x, p.y) = (p.x + roi.x0, p.y + roi.y0);
        }
        result
            .assumptions
            .push(region_note(roi, loaded, max_pixels));
    }
    result.assumptions.extend(loaded.notes.iter().cloned());
    result.biases = loaded.recording.biases();
    Ok(result)
}

/// What a fit on a region says in `assumptions`.
fn region_note(roi: Roi, loaded: &Loaded, max_pixels: usize) -> String {
    let (rw, rh) = (roi.width() as usize, roi.height() as usize);
    format!(
        "fitted on the region x {}..{}, y {}..{} of the {} sensor ({} of {} pixels; at most {max_pixels} are simulated, the frames cut to it): the {rw}x{rh} rectangle, of the sensor's aspect, where the events are densest (each pixel counted up to the 99th percentile of the pixels' counts, so that hot pixels do not choose it); thresholds, mismatch and noise rates are per-pixel and measured there; a variation of the thresholds across the sensor beyond the per-pixel mismatch, and hot pixels outside the region, are not seen",
        roi.x0,
        roi.x1,
        roi.y0,
        roi.y1,
        loaded.sensor,
        rw * rh,
        loaded.sensor.pixels()
    )
}
