//! Per-pixel running state of the statistics pass: last event time, count and the count of
//! events without spatio-temporal support, together in one 16-byte cell so that each event
//! touches one cache line of its own row. The grid has a one-pixel border of cells that
//! never fire, so that the 8 neighbours of any pixel can be read without bounds checks.
//! It grows when the sensor size is not known in advance (it is inferred from the
//! coordinates at the end); readers bound coordinates by `MAX_SENSOR_SIDE`, and so is the
//! grid.

use crate::events::{MAX_SENSOR_SIDE, TimeUs};

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
}

impl PixelGrid {
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            cells: vec![PixelCell::default(); (width + 2) * (height + 2)],
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
        let (need_w, need_h) = (max_x as usize + 1, max_y as usize + 1);
        if need_w <= self.width && need_h <= self.height {
            return;
        }
        // grow generously so that a stream of slowly rising maxima does not re-layout
        // often, but never past the largest sensor
        let limit = MAX_SENSOR_SIDE as usize;
        let grow = |have: usize, need: usize| {
            if need <= have {
                have
            } else {
                need.max(have + have / 2).max(64).min(limit.max(need))
            }
        };
        let width = grow(self.width, need_w);
        let height = grow(self.height, need_h);
        let mut grown = Self::new(width, height);
        for y in 0..self.height {
            let from = (y + 1) * self.stride() + 1;
            let to = (y + 1) * grown.stride() + 1;
            grown.cells[to..to + self.width].copy_from_slice(&self.cells[from..from + self.width]);
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
}
