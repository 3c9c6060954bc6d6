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
        if t < self.last {
            self.record(t, &place);
        }
        if t.unsigned_abs() > TIME_LIMIT_US as u64 {
            self.record_out_of_range(t, &place);
        }
        self.last = t;
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
    }
}
