//! A region of a large sensor to measure on, and a recording's events, frames and pixel
//! selection cut to it.
//!
//! The fit re-simulates the recording's frames hundreds of times ([`crate::fit`]); its cost
//! grows with the pixels simulated. Thresholds, their mismatch and the noise rates are
//! properties of a pixel, which a sample of ~90,000 pixels (a DAVIS346's, which the fit
//! measures whole) measures too; more pixels would narrow only the statistical part of the
//! intervals, not the frames' systematics (frame rate, exposure, the blocks' spread). So a
//! larger sensor is measured on one rectangle of that size: the one where its events are
//! densest, which carries the most of the scene's motion and texture. What a
//! region cannot see is said in `assumptions` by the caller: a variation of the thresholds
//! across the sensor beyond the per-pixel mismatch (e.g. from the readout's column
//! circuits), and hot pixels outside it.

use crate::events::{EventChunk, Frame, Sensor};
use crate::selection::{PixelSelection, Roi};

/// Where a region is searched: every this many pixels across and down (a finer step moves
/// a region of hundreds of pixels by under 1 % of its events).
const POSITION_STEP: u16 = 4;

/// The share of the pixels with events whose count a pixel's is capped at when the
/// regions are compared (so that a few hot pixels, firing thousands of times the scene's
/// rate, do not choose the region).
const COUNT_CAP_QUANTILE: f64 = 0.99;

/// The size of a region of at most `max_pixels` of `sensor`, with the sensor's aspect
/// ratio; `None` where the sensor has no more pixels than that.
pub fn region_size(sensor: Sensor, max_pixels: usize) -> Option<(u16, u16)> {
    let (w, h) = (sensor.width as usize, sensor.height as usize);
    if w * h <= max_pixels || max_pixels == 0 {
        return None;
    }
    let scale = (max_pixels as f64 / (w * h) as f64).sqrt();
    let (mut rw, mut rh) = (
        ((w as f64 * scale).floor() as usize).max(1),
        ((h as f64 * scale).floor() as usize).max(1),
    );
    while rw * rh > max_pixels {
        if rw >= rh { rw -= 1 } else { rh -= 1 }
    }
    Some((rw as u16, rh as u16))
}

/// The region of [`region_size`] whose kept pixels (`excluded` false) hold the most events,
/// each pixel's count capped at the [`COUNT_CAP_QUANTILE`] of the counts of the pixels with
/// events and at twice its busiest neighbour's; of equal regions, the one nearest the sensor's centre. `None` where the sensor
/// has no more than `max_pixels` pixels.
pub fn busiest_region(
    events: &EventChunk,
    sensor: Sensor,
    excluded: &[bool],
    max_pixels: usize,
) -> Option<Roi> {
    let (rw, rh) = region_size(sensor, max_pixels)?;
    let (w, h) = (sensor.width as usize, sensor.height as usize);
    let mut counts = vec![0u64; w * h];
    for (&x, &y) in events.x.iter().zip(&events.y) {
        if (x as usize) < w && (y as usize) < h {
            counts[y as usize * w + x as usize] += 1;
        }
    }
    for (c, &e) in counts.iter_mut().zip(excluded) {
        if e {
            *c = 0;
        }
    }
    let cap = cap_of(&counts);
    let counts = neighbour_capped(&counts, w, h);
    let table = SummedArea::new(&counts, w, h, cap);
    let centre = ((w - rw as usize) / 2, (h - rh as usize) / 2);
    // every POSITION_STEP-th position, the last and the centred one
    let positions = |side: usize, size: u16, centred: usize| {
        let last = side - size as usize;
        (0..=last)
            .step_by(POSITION_STEP as usize)
            .chain([last, centred])
    };
    let mut best: Option<(u64, f64, usize, usize)> = None;
    for y0 in positions(h, rh, centre.1) {
        for x0 in positions(w, rw, centre.0) {
            let sum = table.sum(x0, y0, rw as usize, rh as usize);
            let off = (x0 as f64 - centre.0 as f64).powi(2) + (y0 as f64 - centre.1 as f64).powi(2);
            let better = best.is_none_or(|(s, d, _, _)| sum > s || (sum == s && off < d));
            if better {
                best = Some((sum, off, x0, y0));
            }
        }
    }
    let (_, _, x0, y0) = best?;
    Some(Roi {
        x0: x0 as u16,
        y0: y0 as u16,
        x1: x0 as u16 + rw,
        y1: y0 as u16 + rh,
    })
}

/// The [`COUNT_CAP_QUANTILE`] of the non-zero counts (`u64::MAX` where none).
fn cap_of(counts: &[u64]) -> u64 {
    let mut busy: Vec<u64> = counts.iter().copied().filter(|&c| c > 0).collect();
    if busy.is_empty() {
        return u64::MAX;
    }
    let k = ((busy.len() - 1) as f64 * COUNT_CAP_QUANTILE).round() as usize;
    *busy.select_nth_unstable(k).1
}

/// Each count capped at twice the busiest of its 8 neighbours' (at least 1): the scene's
/// events come from edges spanning neighbouring pixels, a hot pixel fires alone. The
/// quantile cap alone misses hot pixels where under 1 % of the pixels have events.
fn neighbour_capped(counts: &[u64], w: usize, h: usize) -> Vec<u64> {
    let at = |x: usize, y: usize| counts[y * w + x];
    let mut out = Vec::with_capacity(counts.len());
    for y in 0..h {
        for x in 0..w {
            let mut busiest = 0;
            for ny in y.saturating_sub(1)..(y + 2).min(h) {
                for nx in x.saturating_sub(1)..(x + 2).min(w) {
                    if (nx, ny) != (x, y) {
                        busiest = busiest.max(at(nx, ny));
                    }
                }
            }
            out.push(at(x, y).min((2 * busiest).max(1)));
        }
    }
    out
}

/// A summed-area table of capped counts: any rectangle's sum in four reads.
struct SummedArea {
    width: usize,
    table: Vec<u64>,
}

impl SummedArea {
    fn new(counts: &[u64], w: usize, h: usize, cap: u64) -> Self {
        let width = w + 1;
        let mut table = vec![0u64; width * (h + 1)];
        for y in 0..h {
            let mut row = 0u64;
            for x in 0..w {
                row += counts[y * w + x].min(cap);
                table[(y + 1) * width + x + 1] = table[y * width + x + 1] + row;
            }
        }
        Self { width, table }
    }

    fn sum(&self, x0: usize, y0: usize, rw: usize, rh: usize) -> u64 {
        let at = |x: usize, y: usize| self.table[y * self.width + x];
        at(x0 + rw, y0 + rh) + at(x0, y0) - at(x0, y0 + rh) - at(x0 + rw, y0)
    }
}

impl Roi {
    pub fn width(&self) -> u16 {
        self.x1 - self.x0
    }

    pub fn height(&self) -> u16 {
        self.y1 - self.y0
    }

    /// The region as a sensor of its own size.
    pub fn as_sensor(&self) -> Sensor {
        Sensor::new(self.width(), self.height())
    }

    /// Whether pixel `(x, y)` lies inside the region.
    pub fn holds(&self, x: u16, y: u16) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&y)
    }
}

/// The values of a row-major image of `width` columns inside `roi`, row-major.
fn cut<T: Copy>(values: &[T], width: usize, roi: Roi) -> Vec<T> {
    (roi.y0 as usize..roi.y1 as usize)
        .flat_map(|y| &values[y * width + roi.x0 as usize..y * width + roi.x1 as usize])
        .copied()
        .collect()
}

impl EventChunk {
    /// The events inside `roi`, in the region's coordinates (its corner at 0, 0).
    pub fn within(&self, roi: Roi) -> EventChunk {
        let mut out = EventChunk::default();
        for i in 0..self.len() {
            let (x, y) = (self.x[i], self.y[i]);
            if roi.holds(x, y) {
                out.push(self.t[i], x - roi.x0, y - roi.y0, self.on[i]);
            }
        }
        out
    }
}

impl Frame {
    /// The frame's pixels inside `roi` (which must lie on the frame).
    pub fn within(&self, roi: Roi) -> Frame {
        Frame {
            pixels: cut(&self.pixels, self.width as usize, roi),
            width: roi.width() as u32,
            height: roi.height() as u32,
            ..*self
        }
    }
}

impl PixelSelection {
    /// The selection of the pixels inside `roi`, as a selection of a sensor of the region's
    /// size (what was applied is kept, the region added).
    pub fn within(&self, roi: Roi) -> PixelSelection {
        let keep = cut(self.kept_mask(), self.sensor().width as usize, roi);
        self.cut(
            roi.as_sensor(),
            keep,
            format!("measured on the region {roi}"),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_region_keeps_the_aspect_and_the_pixel_limit() {
        // 1280 x 720 at 346 x 260's pixels: 0.3124 of each side
        assert_eq!(
            region_size(Sensor::new(1280, 720), 346 * 260),
            Some((399, 224))
        );
        assert_eq!(region_size(Sensor::new(346, 260), 346 * 260), None);
        assert_eq!(region_size(Sensor::new(100, 10), 250), Some((50, 5)));
    }

    /// A 40 x 20 sensor with a busy 10 x 8 patch at x 24..34, y 8..16 (3 events a pixel)
    /// and one hot pixel at (2, 2) with 10,000 events: the 200-pixel region (20 x 10) holds
    /// the patch, not the hot pixel; with no events, the centred region is chosen.
    #[test]
    fn the_busiest_region_holds_the_scene_not_a_hot_pixel() {
        let sensor = Sensor::new(40, 20);
        let mut events = EventChunk::default();
        for y in 8..16 {
            for x in 24..34 {
                for t in 0..3 {
                    events.push(t, x, y, true);
                }
            }
        }
        for t in 0..10_000 {
            events.push(t, 2, 2, true);
        }
        let excluded = vec![false; 800];
        let roi = busiest_region(&events, sensor, &excluded, 200).unwrap();
        assert_eq!((roi.width(), roi.height()), (20, 10));
        assert!(
            roi.x0 <= 24 && roi.x1 >= 34 && roi.y0 <= 8 && roi.y1 >= 16,
            "{roi}"
        );
        // of the positions that hold the whole patch (x0 16 or 20 on the 4 px grid, y0 8),
        // the one nearest the centred (10, 5)
        assert_eq!((roi.x0, roi.y0), (16, 8));
        let quiet = EventChunk::default();
        let centred = busiest_region(&quiet, sensor, &excluded, 200).unwrap();
        assert_eq!((centred.x0, centred.y0), (10, 5));
    }

    /// A 200 x 100 sensor where 0.72 % of the pixels see the scene (a 12 x 12 patch at
    /// x 20..32, y 40..52, 3 events a pixel) and five hot pixels of 10,000 events sit
    /// apart in the far corner: 149 active pixels, the 99th percentile a hot pixel's count,
    /// so the quantile cap alone lets them choose; capped by their silent neighbours, the
    /// 400-pixel region holds the patch.
    #[test]
    fn hot_pixels_do_not_choose_the_region_of_a_sparse_scene() {
        let sensor = Sensor::new(200, 100);
        let mut events = EventChunk::default();
        for y in 40..52 {
            for x in 20..32 {
                for t in 0..3 {
                    events.push(t, x, y, false);
                }
            }
        }
        for (x, y) in [(180, 85), (184, 88), (188, 91), (192, 86), (186, 94)] {
            for t in 0..10_000 {
                events.push(t, x, y, true);
            }
        }
        let excluded = vec![false; 20_000];
        let roi = busiest_region(&events, sensor, &excluded, 400).unwrap();
        assert!(
            roi.x0 <= 20 && roi.x1 >= 32 && roi.y0 <= 40 && roi.y1 >= 52,
            "{roi}"
        );
    }

    #[test]
    fn events_frames_and_selections_are_cut_to_the_region() {
        let roi = Roi::parse("1,1,3,3").unwrap();
        let mut events = EventChunk::default();
        events.push(5, 0, 0, true);
        events.push(6, 2, 1, false);
        events.push(7, 3, 2, true);
        let cut = events.within(roi);
        assert_eq!(
            (cut.t, cut.x, cut.y, cut.on),
            (vec![6], vec![1], vec![0], vec![false])
        );
        let frame = Frame {
            t: 9,
            width: 4,
            height: 3,
            pixels: (0..12).collect(),
            exposure_us: Some(3),
        };
        let f = frame.within(roi);
        assert_eq!(
            (f.width, f.height, f.pixels, f.t),
            (2, 2, vec![5, 6, 9, 10], 9)
        );
        let s = PixelSelection::all(Sensor::new(4, 3)).without([(2, 2)], "hot pixels");
        let c = s.within(roi);
        assert_eq!(c.sensor(), Sensor::new(2, 2));
        assert_eq!(c.kept_mask(), [true, true, true, false]);
        assert!(
            c.description().contains("region 1,1,3,3"),
            "{}",
            c.description()
        );
    }
}
