//! Time blocks of a recording without frames: the events' span cut into equal spans, the
//! first ones fit, then selection, then test ([`crate::fit::observe::roles`], the same split
//! as the frame-based fit), each a contiguous slice of the time-sorted events.

use crate::events::{EventChunk, TimeUs};
use crate::fit::observe::{Role, roles};

/// The blocks of a recording and what each is for.
#[derive(Clone, Debug)]
pub struct Blocks {
    /// `[start, end)` of each block, µs.
    pub spans: Vec<(TimeUs, TimeUs)>,
    pub role: Vec<Role>,
}

impl Blocks {
    /// `count` equal blocks over the span of `events` (non-empty), the first
    /// `(1 - holdout) * count` (at least one) fitting.
    pub fn split(events: &EventChunk, count: usize, holdout: f64) -> Self {
        let first = events.t[0];
        let end = events.t[events.len() - 1] + 1;
        let count = count.max(1);
        let length = (end - first) as f64 / count as f64;
        let edge = |k: usize| first + (length * k as f64).round() as TimeUs;
        let spans: Vec<(TimeUs, TimeUs)> = (0..count)
            .map(|k| (edge(k), if k + 1 == count { end } else { edge(k + 1) }))
            .collect();
        let fitting = ((1.0 - holdout) * count as f64).round() as usize;
        Self {
            spans,
            role: roles(fitting, count),
        }
    }

    pub fn count(&self) -> usize {
        self.spans.len()
    }

    /// The blocks of one role.
    pub fn of(&self, role: Role) -> Vec<usize> {
        (0..self.count())
            .filter(|&b| self.role[b] == role)
            .collect()
    }

    /// Seconds of `blocks`.
    pub fn seconds(&self, blocks: &[usize]) -> f64 {
        blocks
            .iter()
            .map(|&b| (self.spans[b].1 - self.spans[b].0) as f64 * 1e-6)
            .sum()
    }

    /// The end of the fit run (the start of the first held-out block).
    pub fn fit_end(&self) -> TimeUs {
        self.spans
            .iter()
            .zip(&self.role)
            .find(|(_, r)| **r != Role::Fit)
            .map_or(TimeUs::MAX, |(s, _)| s.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_cover_the_span_in_order_with_fit_first() {
        let mut e = EventChunk::default();
        for t in [100, 250, 400, 1099] {
            e.push(t, 0, 0, true);
        }
        let b = Blocks::split(&e, 10, 0.4);
        assert_eq!(b.spans[0], (100, 200));
        assert_eq!(b.spans[9], (1000, 1100));
        assert_eq!(b.of(Role::Fit), vec![0, 1, 2, 3, 4, 5]);
        assert_eq!(b.of(Role::Selection), vec![6, 7]);
        assert_eq!(b.of(Role::Test), vec![8, 9]);
        assert_eq!(b.fit_end(), 700);
        assert!((b.seconds(&[0, 1]) - 200e-6).abs() < 1e-12);
    }
}
