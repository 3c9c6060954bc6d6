//! Spatio-temporal support of each event (the background-activity filter of Delbruck,
//! "Frame-free dynamic digital vision", 2008): an event is supported when one of its 8
//! neighbours fired within the preceding window. Moving edges give their events neighbours
//! within a few pixel-crossing times; shot-noise, leak and hot-pixel events are isolated.
//! The statistics pass counts the unsupported events ([`super::StatsAccumulator`]); the
//! estimators use the flags to keep noise out of their samples.

use crate::events::{EventChunk, Sensor, TimeUs};

/// For each event of the time-sorted `events`, whether a neighbour fired in the `window_us`
/// before it.
pub fn supported(events: &EventChunk, sensor: Sensor, window_us: TimeUs) -> Vec<bool> {
    let stride = sensor.width as usize + 2;
    let mut last = vec![TimeUs::MIN; stride * (sensor.height as usize + 2)];
    let mut flags = Vec::with_capacity(events.len());
    for i in 0..events.len() {
        let t = events.t[i];
        let k = (events.y[i] as usize + 1) * stride + events.x[i] as usize + 1;
        let newest = last[k - stride - 1]
            .max(last[k - stride])
            .max(last[k - stride + 1])
            .max(last[k - 1])
            .max(last[k + 1])
            .max(last[k + stride - 1])
            .max(last[k + stride])
            .max(last[k + stride + 1]);
        flags.push(newest >= t.saturating_sub(window_us));
        last[k] = t;
    }
    flags
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
    }
}
