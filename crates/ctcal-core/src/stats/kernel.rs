//! The per-event kernel of the statistics pass: per-pixel counts, spatio-temporal support,
//! same-pixel intervals and the rate timeline, in one loop over a chunk's events.
//!
//! Written for speed (it runs once per event of every recording): cell indices are computed
//! first in a vectorised pass so that the loop can prefetch an event's neighbourhood a few
//! events ahead (events hop between rows, and overlapping those cache misses is most of the
//! kernel's speed); an event's support is one read of its own cell's newest neighbour, which
//! its neighbours wrote when they fired (events arrive in time order, so the last written is
//! the newest): eight stores a CPU need not wait for, where eight loads and their maximum
//! had been a third of the kernel (the support check cost 4.1 ns an event, 2.5 ns
//! after, `benches/README.md`); running counts live in locals (a count kept in a struct the
//! compiler cannot prove apart from the histogram's bins is stored back every event).

use super::intervals::IntervalHistogram;
use super::pixel_grid::PixelGrid;
use super::support::tell_neighbours;
use super::timeline::SparseTimeline;
use crate::events::TimeUs;

/// The rate timeline being counted: finished windows, and the current one's index, end and
/// count so far.
#[derive(Default)]
pub(super) struct WindowCounter {
    pub timeline: SparseTimeline,
    pub index: u64,
    pub end: TimeUs,
    pub count: u64,
}

impl WindowCounter {
    /// Records the finished window and starts the one holding `t` (skipping empty ones
    /// without storing them).
    #[cold]
    #[inline(never)]
    fn close(&mut self, t: TimeUs, first: TimeUs, window_us: TimeUs) {
        if self.count > 0 {
            self.timeline.add(self.index, self.count);
        }
        self.index = (t.saturating_sub(first) / window_us) as u64;
        self.end = first.saturating_add((self.index as TimeUs + 1).saturating_mul(window_us));
        self.count = 0;
    }
}

/// What the kernel reads besides the events.
pub(super) struct Settings {
    /// Cells per stored row (the grid's width plus its border).
    pub stride: usize,
    /// The first counted event's time (the timeline's origin).
    pub first: TimeUs,
    pub support_us: TimeUs,
    /// The first time an event has a whole support window of history before it (the
    /// first event fed plus the window): earlier events are not judged as unsupported.
    pub judged_from: TimeUs,
    pub window_us: TimeUs,
}

/// Hints the cache to load the memory at `address` (no effect on results; a no-op off
/// x86-64). Takes a pointer rather than a reference so that the caller needs no bounds
/// check to name it: a prefetch never faults, whatever the address.
#[inline(always)]
fn prefetch<T>(address: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: prefetching is a hint and never faults, whatever the address.
    unsafe {
        std::arch::x86_64::_mm_prefetch(address as *const i8, std::arch::x86_64::_MM_HINT_T0);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = address;
}

/// Cell indices of the events (`indices` is scratch, reused between chunks).
pub(super) fn cell_indices(xs: &[u16], ys: &[u16], stride: usize, indices: &mut Vec<u32>) {
    indices.clear();
    indices.extend(
        xs.iter()
            .zip(ys)
            .map(|(&x, &y)| ((y as usize + 1) * stride + x as usize + 1) as u32),
    );
}

/// Adds the events at `ts` with cell `indices` to `grid`, `intervals` and `windows`.
/// With `SELECTED`, intervals and the timeline count only the events `kept` flags (every
/// event still updates its pixel, so that support sees every neighbour).
#[inline(never)]
pub(super) fn accumulate<const SELECTED: bool>(
    ts: &[TimeUs],
    indices: &[u32],
    kept: &[bool],
    settings: &Settings,
    grid: &mut PixelGrid,
    intervals: &mut IntervalHistogram,
    windows: &mut WindowCounter,
) {
    let stride = settings.stride;
    let (first, support_us, window_us) = (settings.first, settings.support_us, settings.window_us);
    let judged_from = settings.judged_from;
    let indices = &indices[..ts.len()];
    let mut window_end = windows.end;
    let mut window_count = windows.count;
    const AHEAD: usize = 16;
    // the addresses to prefetch are computed, not indexed: with six bounds checks an
    // event the kernel took 15-25 % longer
    let PixelGrid {
        cells,
        neighbours_last,
        ..
    } = grid;
    let base = cells.as_ptr();
    let told = neighbours_last.as_ptr();
    for (i, (&t, &k)) in ts.iter().zip(indices).enumerate() {
        if let Some(&ahead) = indices.get(i + AHEAD) {
            let ahead = ahead as usize;
            prefetch(base.wrapping_add(ahead));
            prefetch(told.wrapping_add(ahead - stride - 1));
            prefetch(told.wrapping_add(ahead - stride + 1));
            prefetch(told.wrapping_add(ahead - 1));
            prefetch(told.wrapping_add(ahead + 1));
            prefetch(told.wrapping_add(ahead + stride - 1));
            prefetch(told.wrapping_add(ahead + stride + 1));
        }
        let k = k as usize;
        let newest = neighbours_last[k];
        tell_neighbours(neighbours_last, k, stride, t);
        let cell = &mut cells[k];
        let counted = !SELECTED || kept[i];
        if cell.count > 0 && counted {
            intervals.add(t.wrapping_sub(cell.last) as u64);
        }
        cell.count += 1;
        cell.unsupported += (newest < t.saturating_sub(support_us) && t >= judged_from) as u32;
        cell.last = t;
        if !counted {
            continue;
        }
        if t >= window_end {
            windows.count = window_count;
            windows.close(t, first, window_us);
            window_end = windows.end;
            window_count = 0;
        }
        window_count += 1;
    }
    windows.count = window_count;
}
