//! How often the support filter ([`super::support`]) would pass an event that has nothing
//! to do with its neighbours: for each pixel, the share of the recording's time that lies
//! within the window of one of its 8 neighbours' events. Shot noise and leak fire
//! independently of the scene (a Poisson or steady process at each pixel; Delbruck,
//! "Frame-free dynamic digital vision", 2008; Lichtsteiner et al., IEEE JSSC 2008), so that
//! share is the probability that a noise event finds support by chance. Where the scene
//! moves slowly the window is long and the share near one: supported events then hold
//! nearly all the noise, and only this share says how much of the noise the unsupported
//! events stand for (a noise event goes unsupported with probability one minus it).

use crate::events::{EventChunk, Sensor, TimeUs};

/// For each pixel (row-major), how much of the time it counts lies within `window_us`
/// before or after an event of one of its 8 neighbours, microseconds: the covered union's
/// pieces measured by `counted(pixel, from, to)` (how much of `[from, to)` counts at the
/// pixel). An estimator that counts each pixel only in some windows (of a flow, of
/// reliable frames) measures the chance where it counts: near a recording's ends the
/// filter sees one side only, and the chance there is lower. `events` must be
/// time-sorted.
pub fn covered_time(
    events: &EventChunk,
    sensor: Sensor,
    window_us: TimeUs,
    counted: impl Fn(usize, TimeUs, TimeUs) -> TimeUs,
) -> Vec<TimeUs> {
    let (w, h) = (sensor.width as usize, sensor.height as usize);
    let mut covered = vec![0 as TimeUs; w * h];
    // the end of the union of windows laid on each pixel so far: times grow, so a new
    // window only extends that union from its end
    let mut union_end = vec![TimeUs::MIN; w * h];
    for i in 0..events.len() {
        let (x, y, t) = (events.x[i] as usize, events.y[i] as usize, events.t[i]);
        for ny in y.saturating_sub(1)..(y + 2).min(h) {
            for nx in x.saturating_sub(1)..(x + 2).min(w) {
                if (nx, ny) == (x, y) {
                    continue;
                }
                let q = ny * w + nx;
                let from = (t - window_us).max(union_end[q]);
                let to = t + window_us;
                if to > from {
                    covered[q] += counted(q, from, to);
                    union_end[q] = to;
                }
            }
        }
    }
    covered
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::events::Event;

    /// For each pixel (row-major), the share of `[first event, last event]` within
    /// `window_us` before or after an event of one of its 8 neighbours (its own events
    /// excluded, as in the filter). `events` must be time-sorted. Empty or instantaneous
    /// recordings give zeros.
    fn chance_support(events: &EventChunk, sensor: Sensor, window_us: TimeUs) -> Vec<f64> {
        let (Some(&first), Some(&last)) = (events.t.first(), events.t.last()) else {
            return vec![0.0; sensor.pixels()];
        };
        if last <= first {
            return vec![0.0; sensor.pixels()];
        }
        let span = (last - first) as f64;
        covered_time(events, sensor, window_us, |_, from, to| {
            (to.min(last) - from.max(first)).max(0)
        })
        .into_iter()
        .map(|c| c as f64 / span)
        .collect()
    }

    fn chunk(events: &[(TimeUs, u16, u16)]) -> EventChunk {
        events
            .iter()
            .map(|&(t, x, y)| Event { t, x, y, on: true })
            .collect()
    }

    #[test]
    fn a_neighbours_windows_cover_their_union_of_the_span() {
        // 3 x 1 pixels over 0..100 ms, window 10 ms. Pixel 1's neighbours fire at 0 (pixel
        // 0), 15 and 50 ms (pixel 2): [0, 10] + [5, 25] + [40, 60] = 10 + 15 + 20 = 45 ms
        // of 100. Pixels 0 and 2 see only pixel 1, at 100 ms: [90, 100], 10 %.
        let events = chunk(&[(0, 0, 0), (15_000, 2, 0), (50_000, 2, 0), (100_000, 1, 0)]);
        let share = chance_support(&events, Sensor::new(3, 1), 10_000);
        assert!((share[1] - 0.45).abs() < 1e-12, "{share:?}");
        assert!((share[0] - 0.10).abs() < 1e-12, "{share:?}");
        assert!((share[2] - 0.10).abs() < 1e-12, "{share:?}");
    }

    #[test]
    fn poisson_neighbours_cover_one_minus_exp_of_their_rate_times_the_window() {
        // 8 neighbours firing at random, 20 Hz in all, window 10 ms either side: a time is
        // uncovered when none fired within 20 ms, exp(-20 * 0.02) = 0.670, so the share is
        // 0.330 (the edges of the span aside)
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(3);
        let mut t = 0;
        let mut events = Vec::new();
        while t < 2_000_000_000 {
            t += (-(1.0 - rng.random::<f64>()).ln() / 20.0 * 1e6) as TimeUs;
            let k = rng.random_range(0..8u16);
            let (x, y) = if k < 4 {
                (k % 3, k / 3)
            } else {
                ((k + 1) % 3, (k + 1) / 3)
            };
            events.push((t, x, y));
        }
        let share = chance_support(&chunk(&events), Sensor::new(3, 3), 10_000);
        let expected = 1.0 - (-20.0f64 * 0.02).exp();
        assert!(
            (share[4] - expected).abs() < 0.01,
            "{} vs {expected}",
            share[4]
        );
    }

    #[test]
    fn only_the_counted_time_is_measured() {
        // the first test's pixel 1, counted only in [20, 70) ms: of its covered pieces
        // [0, 25) and [40, 60) ms, 5 + 20 = 25 ms count
        let events = chunk(&[(0, 0, 0), (15_000, 2, 0), (50_000, 2, 0), (100_000, 1, 0)]);
        let counted = |q: usize, from: TimeUs, to: TimeUs| {
            if q == 1 {
                (to.min(70_000) - from.max(20_000)).max(0)
            } else {
                0
            }
        };
        let covered = covered_time(&events, Sensor::new(3, 1), 10_000, counted);
        assert_eq!(covered, vec![0, 25_000, 0]);
    }

    #[test]
    fn no_span_no_share() {
        assert_eq!(
            chance_support(&chunk(&[]), Sensor::new(2, 2), 1_000),
            vec![0.0; 4]
        );
        let one = chance_support(&chunk(&[(5, 0, 0), (5, 1, 0)]), Sensor::new(2, 1), 1_000);
        assert_eq!(one, vec![0.0; 2]);
    }
}
