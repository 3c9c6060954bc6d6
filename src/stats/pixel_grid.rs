//! Per-pixel running state of the statistics pass: count and last event time, together in
//! one 16-byte cell so that each event touches one cache line. The grid grows when the
//! sensor size is not known in advance (it is inferred from the coordinates at the end).

use crate::events::TimeUs;

/// One pixel's running state.
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelCell {
    pub last: TimeUs,
    pub count: u32,
}

/// A row-major grid of [`PixelCell`]s that can grow.
#[derive(Clone, Debug, Default)]
pub struct PixelGrid {
    pub width: usize,
    pub height: usize,
    pub cells: Vec<PixelCell>,
}

impl PixelGrid {
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            cells: vec![PixelCell::default(); width * height],
        }
    }

    /// Makes the grid contain pixel (`max_x`, `max_y`), keeping the cells' contents.
    pub fn ensure(&mut self, max_x: u16, max_y: u16) {
        let (need_w, need_h) = (max_x as usize + 1, max_y as usize + 1);
        if need_w <= self.width && need_h <= self.height {
            return;
        }
        // grow generously so that a stream of slowly rising maxima does not re-layout often
        let width = self.width.max(need_w.next_power_of_two().max(need_w));
        let height = self.height.max(need_h.next_power_of_two().max(need_h));
        let mut cells = vec![PixelCell::default(); width * height];
        for y in 0..self.height {
            cells[y * width..y * width + self.width]
                .copy_from_slice(&self.cells[y * self.width..(y + 1) * self.width]);
        }
        *self = Self {
            width,
            height,
            cells,
        };
    }

    /// Counts as a `width x height` map (pixels outside the grid count zero).
    pub fn counts(&self, width: usize, height: usize) -> Vec<u32> {
        let mut out = vec![0u32; width * height];
        for y in 0..height.min(self.height) {
            for x in 0..width.min(self.width) {
                out[y * width + x] = self.cells[y * self.width + x].count;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn growing_keeps_every_cell_in_place() {
        let mut g = PixelGrid::new(3, 2);
        let (x, y) = (2, 1);
        g.cells[y * 3 + x].count = 7;
        g.ensure(10, 4);
        assert!(g.width >= 11 && g.height >= 5);
        assert_eq!(g.cells[y * g.width + x].count, 7);
        let counts = g.counts(4, 3);
        assert_eq!(counts[y * 4 + x], 7);
        assert_eq!(counts.iter().sum::<u32>(), 7);
    }
}
