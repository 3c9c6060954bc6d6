//! `estimate aps` of a window on the region of the sensor it can afford: a window with more
//! events than the budget ([`crate::fit_region::FIT_EVENTS`] unless told otherwise), or a
//! sensor with more pixels, is measured on the rectangle where its events are densest, by
//! the fit's region rule ([`crate::fit_region`]); the threshold maps are given in the
//! sensor's coordinates (NaN and no samples outside the region) and the region is named in
//! `assumptions`. The `ctcal estimate aps` command, the report and the Python package all
//! measure through here.
//!
//! The events bound it because `estimate aps` times every event against the frames' log
//! change and re-simulates the frames to read the thresholds' counts, both growing with
//! the events: coverage draw 7034 (a 240x180 texture turning fast, 4.2 M events in
//! 1.46 s) took 265 s whole on one thread in the coverage study.

use crate::estimate::{EstimateError, Progress};
use crate::fit_region::{FitBudget, Measured, on_region};
use crate::selection::Roi;
use crate::window::Loaded;
use ctcal_core::estimate::aps::{self, ApsInput, ApsOptions, ApsResult};
use ctcal_core::estimate::timing::ThresholdMaps;

/// `estimate aps` of `loaded` (two frames or more) with `options`, on its busiest region
/// within `budget` where it has more pixels or events than that; the window's notes added.
pub fn aps(
    loaded: &Loaded,
    options: &ApsOptions,
    budget: FitBudget,
    progress: Progress,
) -> Result<ApsResult, EstimateError> {
    let (mut result, placed) = on_region(loaded, budget, (Measured::Aps, true), |input| {
        aps::estimate(&input.aps_input(), options, progress)
    })?;
    if let Some(roi) = placed.roi {
        let (w, h) = (loaded.sensor.width as usize, loaded.sensor.height as usize);
        result.maps = embedded(&result.maps, roi, w, h);
    }
    result.estimate.assumptions.extend(placed.note);
    result
        .estimate
        .assumptions
        .extend(loaded.notes.iter().cloned());
    Ok(result)
}

impl Loaded {
    /// The window as `estimate aps` reads it.
    pub fn aps_input(&self) -> ApsInput<'_> {
        ApsInput {
            sensor: self.sensor,
            events: &self.events,
            frames: &self.frames,
            excluded: &self.excluded,
            unread: &self.unread,
        }
    }
}

/// The maps of a region placed in a `width` x `height` sensor: NaN thresholds and no
/// samples outside it.
fn embedded(maps: &ThresholdMaps, roi: Roi, width: usize, height: usize) -> ThresholdMaps {
    let mut whole = ThresholdMaps {
        width,
        height,
        ct_on: vec![f32::NAN; width * height],
        ct_off: vec![f32::NAN; width * height],
        count: vec![0; width * height],
    };
    let (x0, y0) = (roi.x0 as usize, roi.y0 as usize);
    for y in 0..maps.height {
        let from = y * maps.width..(y + 1) * maps.width;
        let to = (y0 + y) * width + x0..(y0 + y) * width + x0 + maps.width;
        whole.ct_on[to.clone()].copy_from_slice(&maps.ct_on[from.clone()]);
        whole.ct_off[to.clone()].copy_from_slice(&maps.ct_off[from.clone()]);
        whole.count[to].copy_from_slice(&maps.count[from]);
    }
    whole
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_region_s_maps_land_at_its_place_in_the_sensor() {
        // a 2x2 region at x 1..3, y 2..4 of a 4x5 sensor
        let maps = ThresholdMaps {
            width: 2,
            height: 2,
            ct_on: vec![0.1, 0.2, 0.3, 0.4],
            ct_off: vec![0.5, 0.6, 0.7, 0.8],
            count: vec![1, 2, 3, 4],
        };
        let roi = Roi {
            x0: 1,
            y0: 2,
            x1: 3,
            y1: 4,
        };
        let whole = embedded(&maps, roi, 4, 5);
        assert_eq!(
            whole.count,
            [0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 2, 0, 0, 3, 4, 0, 0, 0, 0, 0]
        );
        assert_eq!(whole.ct_on[2 * 4 + 1], 0.1);
        assert_eq!(whole.ct_off[3 * 4 + 2], 0.8);
        let inside = [9, 10, 13, 14];
        for (i, v) in whole.ct_on.iter().enumerate() {
            assert_eq!(v.is_nan(), !inside.contains(&i), "{i}");
        }
    }
}
