//! Time-order checking shared by every decoder: counts the places where a timestamp goes
//! backwards and remembers the first, so that an unsorted file is refused with the count and
//! the place (or accepted with `--sort`); and remembers the first time beyond
//! [`TIME_LIMIT_US`], which the event stream refuses at once.

use crate::events::{TIME_LIMIT_US, TimeUs};

/// Running check that timestamps never decrease.
#[derive(Clone, Debug)]
pub struct OrderCheck {
    last: TimeUs,
    /// Number of events whose time is earlier than the event before them.
    pub backwards: u64,
    /// The first such place: (where, previous time, this time).
    pub first: Option<(String, TimeUs, TimeUs)>,
    /// The first time beyond [`TIME_LIMIT_US`]: (where, time).
    pub out_of_range: Option<(String, TimeUs)>,
}

impl Default for OrderCheck {
    fn default() -> Self {
        Self {
            last: TimeUs::MIN,
            backwards: 0,
            first: None,
            out_of_range: None,
        }
    }
}

impl OrderCheck {
    /// Checks the next event's time; `place` is only evaluated at the first violation.
    #[inline(always)]
    pub fn check(&mut self, t: TimeUs, place: impl Fn() -> String) {
        // one branch for both checks in the per-event path; the cold path tells them apart
        if t < self.last || t.unsigned_abs() > TIME_LIMIT_US as u64 {
            self.record_either(t, &place);
        }
        self.last = t;
    }

    /// The time of the last event checked.
    #[inline]
    pub fn last(&self) -> TimeUs {
        self.last
    }

    /// Continues after a run of events that a decoder checked itself and found in order and
    /// within [`TIME_LIMIT_US`], the last at `t` (no earlier than [`Self::last`]).
    #[inline]
    pub fn skip_checked(&mut self, t: TimeUs) {
        debug_assert!(t >= self.last && t.unsigned_abs() <= TIME_LIMIT_US as u64);
        self.last = t;
    }

    #[cold]
    #[inline(never)]
    fn record_either(&mut self, t: TimeUs, place: &impl Fn() -> String) {
        if t < self.last {
            self.record(t, place);
        }
        if t.unsigned_abs() > TIME_LIMIT_US as u64 {
            self.record_out_of_range(t, place);
        }
    }

    /// Checks a run of times; `place(i)` names the `i`-th and is only evaluated at a
    /// violation. Runs that are in order and in range (the usual case) take one pass.
    pub fn check_all(&mut self, times: &[TimeUs], place: impl Fn(usize) -> String) {
        let Some(&first) = times.first() else {
            return;
        };
        let sorted = first >= self.last && times.windows(2).all(|w| w[0] <= w[1]);
        let in_range = times
            .iter()
            .all(|t| t.unsigned_abs() <= TIME_LIMIT_US as u64);
        if sorted && in_range {
            self.last = times[times.len() - 1];
            return;
        }
        for (i, &t) in times.iter().enumerate() {
            self.check(t, || place(i));
        }
    }

    /// Records `count` events that go backwards, found by a decoder that checks order its
    /// own way (the first at `place`, `t` after `previous`).
    pub fn record_backwards(
        &mut self,
        count: u64,
        place: impl FnOnce() -> String,
        previous: TimeUs,
        t: TimeUs,
    ) {
        if count == 0 {
            return;
        }
        self.backwards += count;
        if self.first.is_none() {
            self.first = Some((place(), previous, t));
        }
    }

    /// Checks only that `times` lie within [`TIME_LIMIT_US`] (for a decoder that checks
    /// their order its own way).
    pub fn check_range(&mut self, times: &[TimeUs], place: impl Fn(usize) -> String) {
        if let Some(i) = times
            .iter()
            .position(|t| t.unsigned_abs() > TIME_LIMIT_US as u64)
        {
            self.record_out_of_range(times[i], &|| place(i));
        }
    }

    #[cold]
    #[inline(never)]
    fn record(&mut self, t: TimeUs, place: &impl Fn() -> String) {
        self.backwards += 1;
        if self.first.is_none() {
            self.first = Some((place(), self.last, t));
        }
    }

    #[cold]
    #[inline(never)]
    fn record_out_of_range(&mut self, t: TimeUs, place: &impl Fn() -> String) {
        if self.out_of_range.is_none() {
            self.out_of_range = Some((place(), t));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_each_decrease_and_keeps_the_first_place() {
        let mut check = OrderCheck::default();
        for (i, t) in [1, 2, 2, 1, 5, 3, 4].into_iter().enumerate() {
            check.check(t, || format!("event {i}"));
        }
        assert_eq!(check.backwards, 2);
        assert_eq!(check.first, Some(("event 3".to_string(), 2, 1)));
        // the same through the run check, across two runs
        let mut runs = OrderCheck::default();
        runs.check_all(&[1, 2, 2], |i| format!("event {i}"));
        runs.check_all(&[1, 5, 3, 4], |i| format!("event {}", i + 3));
        assert_eq!(
            (runs.backwards, &runs.first),
            (check.backwards, &check.first)
        );
        runs.check_all(&[TIME_LIMIT_US + 1], |_| "far".into());
        assert_eq!(
            runs.out_of_range,
            Some(("far".to_string(), TIME_LIMIT_US + 1))
        );
    }
}
