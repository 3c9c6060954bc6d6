//! Per-pixel running state of the statistics pass: last event time, count and the count of
//! events without spatio-temporal support, together in one 16-byte cell so that each event
//! touches one cache line of its own row; beside the cells, the newest event among each
//! cell's neighbours (8 bytes a cell), which each event writes into its 8 neighbours so
//! that its own support is one read. The grid has a one-cell border of cells that never
//! fire (they are written, and kept when the grid grows over them), so that the 8
//! neighbours of any pixel are reached without bounds checks.
//! It grows when the sensor size is not known in advance (it is inferred from the
//! coordinates at the end); readers bound coordinates by `MAX_SENSOR_SIDE`, and so is the
//! grid. A sensor given larger than [`PIXEL_BUDGET`] pixels is not allocated up front
//! either: the grid then grows to the area the events reach, and the statistics refuse
//! (unless told to go on) when that area exceeds the budget.

use crate::events::{MAX_SENSOR_SIDE, TimeUs};

/// Pixels of per-pixel state the statistics (and the estimators) keep without being told
/// otherwise: 4096 x 4096, the largest sensor ctcal accepts from a file (more than any
/// sensor sold), about [`BYTES_PER_PIXEL`] bytes each (0.7 GB).
pub const PIXEL_BUDGET: usize = MAX_SENSOR_SIDE as usize * MAX_SENSOR_SIDE as usize;

/// Bytes per pixel of the statistics pass: the 16-byte cell, the neighbours' newest event
/// (8 bytes) and the maps of its final step.
pub const BYTES_PER_PIXEL: usize = 40;

/// One pixel's running state.
#[derive(Clone, Copy, Debug)]
pub struct PixelCell {
    /// Time of the last event (`TimeUs::MIN` before the first).
    pub last: TimeUs,
    pub count: u32,
    /// Events with no event of an 8-neighbour in the preceding support window.
    pub unsupported: u32,
}

impl Default for PixelCell {
    fn default() -> Self {
        Self {
            last: TimeUs::MIN,
            count: 0,
            unsupported: 0,
        }
    }
}

/// A row-major grid of [`PixelCell`]s with a one-cell border, that can grow.
#[derive(Clone, Debug, Default)]
pub struct PixelGrid {
    /// Pixels per row and rows (without the border).
    pub width: usize,
    pub height: usize,
    pub cells: Vec<PixelCell>,
    /// Per cell, the time of the last event of any of its 8 neighbours (`TimeUs::MIN`
    /// before the first): each event writes it into its neighbours, so that an event's
    /// support is read from its own cell (the newest neighbour, events arriving in time
    /// order). Apart from the cells, so that the eight writes touch 8 bytes a cell.
    pub neighbours_last: Vec<TimeUs>,
}

impl PixelGrid {
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            cells: vec![PixelCell::default(); (width + 2) * (height + 2)],
            neighbours_last: vec![TimeUs::MIN; (width + 2) * (height + 2)],
        }
    }

    /// Cells per stored row (the width plus the border).
    #[inline(always)]
    pub fn stride(&self) -> usize {
        self.width + 2
    }

    /// The cell index of pixel (x, y).
    #[inline(always)]
    pub fn index(&self, x: u16, y: u16) -> usize {
        (y as usize + 1) * self.stride() + x as usize + 1
    }

    /// Makes the grid contain pixel (`max_x`, `max_y`), keeping the cells' contents.
    pub fn ensure(&mut self, max_x: u16, max_y: u16) {
        let side = MAX_SENSOR_SIDE as usize;
        self.ensure_within(max_x, max_y, (side, side), usize::MAX);
    }

    /// Makes the grid contain pixel (`max_x`, `max_y`), growing ahead of need up to `limit`
    /// (width, height: the sensor) and `max_pixels`, never beyond what is needed past them.
    pub fn ensure_within(
        &mut self,
        max_x: u16,
        max_y: u16,
        limit: (usize, usize),
        max_pixels: usize,
    ) {
        let (need_w, need_h) = (max_x as usize + 1, max_y as usize + 1);
        if need_w <= self.width && need_h <= self.height {
            return;
        }
        // grow generously so that a stream of slowly rising maxima does not re-layout
        // often, but never past the largest sensor
        let grow = |have: usize, need: usize, limit: usize| {
            if need <= have {
                have
            } else {
                need.max(have + have / 2).max(64).min(limit.max(need))
            }
        };
        let mut width = grow(self.width, need_w, limit.0);
        let mut height = grow(self.height, need_h, limit.1);
        if width.saturating_mul(height) > max_pixels {
            width = need_w.max(self.width);
            height = need_h.max(self.height);
        }
        let mut grown = Self::new(width, height);
        // the border too: a border cell holds the newest event of the pixels beside it,
        // and becomes a pixel of the grown grid
        if !self.cells.is_empty() {
            let stride = self.stride();
            for y in 0..self.height + 2 {
                let (from, to) = (y * stride, y * grown.stride());
                grown.cells[to..to + stride].copy_from_slice(&self.cells[from..from + stride]);
                grown.neighbours_last[to..to + stride]
                    .copy_from_slice(&self.neighbours_last[from..from + stride]);
            }
        }
        *self = grown;
    }

    /// A `width x height` map of one value per pixel (pixels outside the grid give
    /// `PixelCell::default()`'s value).
    pub fn map<T: Copy>(
        &self,
        width: usize,
        height: usize,
        value: impl Fn(&PixelCell) -> T,
    ) -> Vec<T> {
        let empty = value(&PixelCell::default());
        let mut out = vec![empty; width * height];
        for y in 0..height.min(self.height) {
            for x in 0..width.min(self.width) {
                out[y * width + x] = value(&self.cells[self.index(x as u16, y as u16)]);
            }
        }
        out
    }

    /// Event counts as a `width x height` map.
    pub fn counts(&self, width: usize, height: usize) -> Vec<u32> {
        self.map(width, height, |c| c.count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn growing_keeps_every_cell_in_place() {
        let mut g = PixelGrid::new(3, 2);
        let i = g.index(2, 1);
        g.cells[i].count = 7;
        g.ensure(10, 4);
        assert!(g.width >= 11 && g.height >= 5);
        assert_eq!(g.cells[g.index(2, 1)].count, 7);
        let counts = g.counts(4, 3);
        assert_eq!(counts[4 + 2], 7);
        assert_eq!(counts.iter().sum::<u32>(), 7);
        // the border stays untouched
        assert_eq!(g.cells[0].last, TimeUs::MIN);
    }

    #[test]
    fn growth_stops_at_the_largest_sensor() {
        let mut g = PixelGrid::new(3000, 1);
        g.ensure(3500, 0);
        assert_eq!(g.width, MAX_SENSOR_SIDE as usize);
    }

    #[test]
    fn growth_ahead_of_need_stays_within_the_budget() {
        let mut g = PixelGrid::default();
        g.ensure_within(999, 999, (60_000, 60_000), 1_000_000);
        assert_eq!((g.width, g.height), (1000, 1000));
        g.ensure_within(1000, 10, (60_000, 60_000), usize::MAX);
        assert_eq!((g.width, g.height), (1500, 1000));
    }
}
