//! Spatio-temporal support of each event (the background-activity filter of Delbruck,
//! "Frame-free dynamic digital vision", 2008): an event is supported when one of its 8
//! neighbours fired within the preceding window. Moving edges give their events neighbours
//! within a few pixel-crossing times; shot-noise, leak and hot-pixel events are isolated.
//! The statistics pass counts the unsupported events ([`super::StatsAccumulator`]); the
//! estimators use the flags to keep noise out of their samples. Events with the same
//! timestamp support each other whatever their order in the file (a display refresh makes
//! whole regions fire at one instant).

use crate::events::{EventChunk, Sensor, TimeUs};

/// For each event of the time-sorted `events`, whether a neighbour fired in the `window_us`
/// before it (or at the same time).
pub fn supported(events: &EventChunk, sensor: Sensor, window_us: TimeUs) -> Vec<bool> {
    let stride = sensor.width as usize + 2;
    let mut last = vec![TimeUs::MIN; stride * (sensor.height as usize + 2)];
    let cell = |i: usize| (events.y[i] as usize + 1) * stride + events.x[i] as usize + 1;
    let mut flags = Vec::with_capacity(events.len());
    let mut start = 0;
    while start < events.len() {
        // the events of one timestamp: mark them all first, so they see each other
        let t = events.t[start];
        let end = start + events.t[start..].partition_point(|&u| u == t);
        let mut own = Vec::with_capacity(end - start);
        for i in start..end {
            let k = cell(i);
            own.push(last[k]);
            last[k] = t;
        }
        for (i, &before) in (start..end).zip(&own) {
            let k = cell(i);
            // the pixel's own mark is not a neighbour's: restore it while looking around
            let mark = std::mem::replace(&mut last[k], before);
            let newest = last[k - stride - 1]
                .max(last[k - stride])
                .max(last[k - stride + 1])
                .max(last[k - 1])
                .max(last[k + 1])
                .max(last[k + stride - 1])
                .max(last[k + stride])
                .max(last[k + stride + 1]);
            last[k] = mark;
            flags.push(newest >= t.saturating_sub(window_us));
        }
        start = end;
    }
    flags
}

/// For each event of the time-sorted `events`, whether a neighbour fired within `window_us`
/// before or after it: the causal filter run forwards and on the time-reversed stream. An
/// estimator comparing counts uses it so that an edge's first event, or any event near the
/// start of a short recording, is not taken for noise for want of a past.
pub fn supported_two_sided(events: &EventChunk, sensor: Sensor, window_us: TimeUs) -> Vec<bool> {
    let forward = supported(events, sensor, window_us);
    let mut reversed = EventChunk::default();
    for i in (0..events.len()).rev() {
        reversed.push(-events.t[i], events.x[i], events.y[i], events.on[i]);
    }
    let backward = supported(&reversed, sensor, window_us);
    let n = events.len();
    (0..n).map(|i| forward[i] || backward[n - 1 - i]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::events::Event;

    #[test]
    fn a_neighbour_within_the_window_supports_an_event() {
        let events: EventChunk = [(0, 1, 1), (5_000, 2, 2), (30_000, 0, 0), (31_000, 3, 3)]
            .into_iter()
            .map(|(t, x, y)| Event { t, x, y, on: true })
            .collect();
        let flags = supported(&events, Sensor::new(4, 4), 10_000);
        assert_eq!(flags, vec![false, true, false, false]);
        // two neighbours at one instant support each other in either order; a pixel does
        // not support itself
        let burst: EventChunk = [(0, 1, 1), (0, 2, 1), (0, 3, 3), (5, 3, 3)]
            .into_iter()
            .map(|(t, x, y)| Event { t, x, y, on: true })
            .collect();
        assert_eq!(
            supported(&burst, Sensor::new(4, 4), 10_000),
            vec![true, true, false, false]
        );
        // two-sided: the first event is supported by the one 5 ms after it
        assert_eq!(
            supported_two_sided(&events, Sensor::new(4, 4), 10_000),
            vec![true, true, false, false]
        );
    }
}
