//! Hot pixels: a few pixels fire far more than their neighbourhood whatever the scene (a
//! leaky or defective pixel; [`crate::sim::effects::hot_pixels`]).
//!
//! Signature: pixels far above the count distribution of their neighbours in the
//! recording but not in the model ([`crate::stats::hot_pixels`], robust z-score against the
//! busiest 8-neighbour), whose excess falls also where the neighbours are quiet
//! ([`independent_of_scene`]: a defect fires whatever the scene, a low threshold only on it;
//! and a defect fires at its rate throughout, a low threshold in bursts while its brightness
//! rises). They are named, and added to the model where they are: each a
//! Poisson train at its own rate and polarity share, measured on the fit blocks ([`events`]),
//! so that model and recording are compared on the same pixels before and after (a
//! simulator places its hot pixels at random: the fraction and the median rate are reported
//! for simulation).

use super::{Context, Effect, Evidence};
use crate::events::{EventChunk, TimeUs};
use crate::stats::hot_pixels::{HotPixel, find_hot_pixels};
use rand::{RngExt, SeedableRng};

mod scene_trace;
mod silence;

pub use scene_trace::SceneTrace;
use silence::{SensorTime, silent_beyond_a_train};

/// The recording's hot pixels (fit blocks) that the model does not have.
pub fn find(c: &Context) -> Vec<HotPixel> {
    let g = c.geometry;
    let (w, h) = (g.sensor.width as usize, g.sensor.height as usize);
    let duration = g.duration_of(c.subset);
    // both on the same pixels: those compared
    let mut real = c.real.pixels_of(c.geometry, c.subset);
    let mut sim = c.sim.pixels_of(c.geometry, c.subset);
    for ((k, r), s) in c.kept.iter().zip(real.iter_mut()).zip(sim.iter_mut()) {
        if !k {
            (*r, *s) = (0, 0);
        }
    }
    let simulated = find_hot_pixels(&sim, w, h, duration);
    find_hot_pixels(&real, w, h, duration)
        .into_iter()
        .filter(|p| !simulated.iter().any(|s| (s.x, s.y) == (p.x, p.y)))
        .collect()
}

pub fn evidence(c: &Context) -> Evidence {
    let hot = find(c);
    if hot.is_empty() {
        return Evidence::none(Effect::HotPixels, "no pixel stands out from its neighbours");
    }
    let strongest = hot.iter().map(|p| p.z).fold(0.0, f64::max);
    Evidence {
        effect: Effect::HotPixels,
        score: strongest,
        relevant: true,
        text: format!(
            "{} pixels fire far above their neighbours (robust z up to {strongest:.0}), e.g. {}",
            hot.len(),
            hot.iter()
                .take(4)
                .map(|p| format!("({}, {}) at {:.1} Hz", p.x, p.y, p.rate_hz))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        other_start: None,
        start: None,
    }
}

/// Neighbour events within this time of a pixel's event support it (the scene's edges
/// cross neighbouring pixels within it at the speeds of the study, > 10 px/s, whatever
/// their direction).
pub const SCENE_WINDOW_US: TimeUs = 30_000;

/// The named pixels whose excess is not the scene's: a defective pixel fires whatever its
/// neighbours do (a Poisson train independent of the scene), so a share of its events
/// falls where no neighbour fires, as large as the share of time its neighbours leave
/// uncovered (within [`SCENE_WINDOW_US`]). A pixel that out-fires its neighbours only
/// while they fire too — a low threshold under mismatch on the scene's own edges — has
/// none there. A pixel is kept unless its excess over the busiest neighbour, spread over
/// its uncovered time, predicts at least 10 events without support and fewer than a
/// quarter of those are seen; where the neighbours cover too much of the time to tell,
/// it is kept. A pixel is also left out when it falls silent for longer than a train at
/// its excess rate allows ([`silent_beyond_a_train`]; the rate at the lower end of the
/// excess count, two Poisson standard deviations): a low threshold fires where its own
/// brightness rises, which its neighbours' thresholds may not see. Where the frames give
/// the pixel's brightness (`scene`), a pixel whose counts its own brightness changes
/// explain with no room for that train is left out too ([`SceneTrace::explains`]).
/// `range`: the events (of `events`) to judge by. Returns the kept pixels and the number
/// left out.
pub fn independent_of_scene(
    hot: &[HotPixel],
    events: &EventChunk,
    range: std::ops::Range<usize>,
    sensor: crate::events::Sensor,
    scene: Option<&SceneTrace>,
) -> (Vec<HotPixel>, usize) {
    if hot.is_empty() || range.is_empty() {
        return (hot.to_vec(), 0);
    }
    let span = (events.t[range.start], events.t[range.end - 1] + 1);
    let around = Around::gathered(hot, events, range.clone(), sensor);
    let seconds = (span.1 - span.0) as f64 * 1e-6;
    let sensor_time = SensorTime::of(&events.t[range.clone()]);
    let mut kept = Vec::new();
    for (k, h) in hot.iter().enumerate() {
        let own = &around.own[k];
        let (uncovered, unsupported) = uncovered_and_alone(own, &around.neighbours[k], span);
        let busiest = around.busiest_neighbour(h, sensor);
        let excess = own.len().saturating_sub(busiest as usize) as f64;
        let excess_hz = excess / seconds;
        // the train the excess would be, at the lower end of its count (two Poisson sigma)
        let train_hz = (excess - 2.0 * (own.len() as f64).sqrt()).max(0.0) / seconds;
        let predicted = excess_hz * uncovered;
        let fires_alone = predicted < 10.0 || unsupported as f64 >= 0.25 * predicted;
        if fires_alone
            && !silent_beyond_a_train(own, train_hz, &sensor_time)
            && !scene.is_some_and(|s| s.explains(own, h.x, h.y, train_hz))
        {
            kept.push(h.clone());
        }
    }
    let left_out = hot.len() - kept.len();
    (kept, left_out)
}

/// The events at and around the named pixels: each one's own event times and its
/// neighbours' (time-sorted), and the event count of every pixel in a neighbourhood.
struct Around {
    own: Vec<Vec<TimeUs>>,
    neighbours: Vec<Vec<TimeUs>>,
    counts: std::collections::HashMap<usize, u64>,
}

impl Around {
    /// The events `range` of `events` at and around each of `hot`.
    fn gathered(
        hot: &[HotPixel],
        events: &EventChunk,
        range: std::ops::Range<usize>,
        sensor: crate::events::Sensor,
    ) -> Self {
        let w = sensor.width as usize;
        // for each pixel, the named pixels whose 3 x 3 neighbourhood it is in (and whether it
        // is their own)
        let mut watchers: std::collections::HashMap<usize, Vec<(usize, bool)>> =
            std::collections::HashMap::new();
        for (k, h) in hot.iter().enumerate() {
            for (p, is_own) in neighbourhood(h, sensor) {
                watchers.entry(p).or_default().push((k, is_own));
            }
        }
        let mut around = Self {
            own: vec![Vec::new(); hot.len()],
            neighbours: vec![Vec::new(); hot.len()],
            counts: std::collections::HashMap::new(),
        };
        for i in range {
            let p = events.y[i] as usize * w + events.x[i] as usize;
            if let Some(list) = watchers.get(&p) {
                *around.counts.entry(p).or_default() += 1;
                for &(k, is_own) in list {
                    if is_own {
                        around.own[k].push(events.t[i]);
                    } else {
                        around.neighbours[k].push(events.t[i]);
                    }
                }
            }
        }
        around
    }

    /// The events of `h`'s busiest 8-neighbour.
    fn busiest_neighbour(&self, h: &HotPixel, sensor: crate::events::Sensor) -> u64 {
        neighbourhood(h, sensor)
            .filter(|&(_, is_own)| !is_own)
            .map(|(p, _)| self.counts.get(&p).copied().unwrap_or(0))
            .max()
            .unwrap_or(0)
    }
}

/// The pixels (y * W + x) of the 3 x 3 neighbourhood of `h` on the sensor, each with
/// whether it is `h` itself ([`crate::stats::hot_pixels::neighbours`] and `h`).
fn neighbourhood(
    h: &HotPixel,
    sensor: crate::events::Sensor,
) -> impl Iterator<Item = (usize, bool)> {
    let (w, hgt) = (sensor.width as usize, sensor.height as usize);
    let (x, y) = (h.x as usize, h.y as usize);
    std::iter::once((y * w + x, true))
        .chain(crate::stats::hot_pixels::neighbours(w, hgt, x, y).map(|p| (p, false)))
}

/// Seconds of `span` no neighbour event covers (within [`SCENE_WINDOW_US`]) and the own
/// events that fall in that time; both lists time-sorted.
fn uncovered_and_alone(
    own: &[TimeUs],
    neighbours: &[TimeUs],
    span: (TimeUs, TimeUs),
) -> (f64, usize) {
    let mut covered: Vec<(TimeUs, TimeUs)> = Vec::new();
    for &t in neighbours {
        let (a, b) = (t - SCENE_WINDOW_US, t + SCENE_WINDOW_US);
        match covered.last_mut() {
            Some(last) if a <= last.1 => last.1 = last.1.max(b),
            _ => covered.push((a, b)),
        }
    }
    let inside: TimeUs = covered
        .iter()
        .map(|&(a, b)| (b.min(span.1) - a.max(span.0)).max(0))
        .sum();
    let alone = own
        .iter()
        .filter(|&&t| {
            let k = covered.partition_point(|&(_, b)| b <= t);
            covered.get(k).is_none_or(|&(a, _)| t < a)
        })
        .count();
    ((span.1 - span.0 - inside) as f64 * 1e-6, alone)
}

/// A named hot pixel as the model simulates it.
#[derive(Clone, Copy, Debug)]
pub struct HotTrain {
    pub x: u16,
    pub y: u16,
    /// Events per second, and the share of them that are ON.
    pub rate_hz: f64,
    pub on_share: f64,
}

/// The hot pixels' own events over `span`: at each pixel a Poisson train at its rate, each
/// event ON with its share (seeded per pixel, so every simulation adds the same events).
pub fn events(trains: &[HotTrain], span: (TimeUs, TimeUs), seed: u64) -> EventChunk {
    let mut all = EventChunk::default();
    for train in trains.iter().filter(|h| h.rate_hz > 0.0) {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(
            seed ^ ((train.y as u64) << 16 | train.x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
        );
        let mut own = EventChunk::default();
        let mut t = span.0 as f64;
        loop {
            t += -(1.0 - rng.random::<f64>()).ln() / train.rate_hz * 1e6;
            if t >= span.1 as f64 {
                break;
            }
            let on = rng.random::<f64>() < train.on_share;
            own.push(t as TimeUs, train.x, train.y, on);
        }
        all = EventChunk::merged(&all, &own);
    }
    all
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pixel firing a Poisson train at 50 Hz beside quiet neighbours is kept; a pixel
    /// that fires three events for each of its neighbour's (a low threshold on the
    /// scene's edges), always within a few ms of it, is left out.
    #[test]
    fn a_pixel_that_fires_only_with_its_neighbours_is_not_hot() {
        let sensor = crate::events::Sensor::new(20, 10);
        let mut all = Vec::new();
        let train = events(
            &[HotTrain {
                x: 3,
                y: 3,
                rate_hz: 50.0,
                on_share: 0.5,
            }],
            (0, 4_000_000),
            1,
        );
        for i in 0..train.len() {
            all.push((train.t[i], 3u16, 3u16, true));
        }
        // the scene: an edge every 200 ms at (12, 5) and its neighbour (13, 5)
        for k in 0..20i64 {
            let t = k * 200_000 + 1_000;
            all.push((t, 13, 5, true));
            for j in 0..3 {
                all.push((t + 2_000 * j, 12, 5, true));
            }
        }
        all.sort_unstable();
        let mut chunk = EventChunk::default();
        for (t, x, y, on) in all {
            chunk.push(t, x, y, on);
        }
        let named = |x: u16, y: u16, rate_hz: f64| HotPixel {
            x,
            y,
            events: (rate_hz * 4.0) as u64,
            rate_hz,
            z: 20.0,
        };
        let (kept, left_out) = independent_of_scene(
            &[named(3, 3, 50.0), named(12, 5, 15.0)],
            &chunk,
            0..chunk.len(),
            sensor,
            None,
        );
        assert_eq!(left_out, 1);
        assert_eq!((kept[0].x, kept[0].y), (3, 3));
    }

    #[test]
    fn trains_fire_at_their_rate_and_share() {
        let trains = [
            HotTrain {
                x: 3,
                y: 4,
                rate_hz: 1000.0,
                on_share: 0.8,
            },
            HotTrain {
                x: 7,
                y: 1,
                rate_hz: 200.0,
                on_share: 0.0,
            },
        ];
        let e = events(&trains, (1_000_000, 3_000_000), 9);
        let n = |x| e.x.iter().filter(|&&v| v == x).count() as f64;
        // Poisson counts: 2000 +- 45 and 400 +- 20
        assert!((n(3) - 2000.0).abs() < 4.0 * 45.0, "{}", n(3));
        assert!((n(7) - 400.0).abs() < 4.0 * 20.0, "{}", n(7));
        let on3 = (0..e.len()).filter(|&i| e.x[i] == 3 && e.on[i]).count() as f64;
        assert!((on3 / n(3) - 0.8).abs() < 0.04, "{}", on3 / n(3));
        assert!((0..e.len()).all(|i| e.x[i] != 7 || !e.on[i]));
        assert!(e.t.windows(2).all(|w| w[0] <= w[1]));
        assert!(e.t.iter().all(|&t| (1_000_000..3_000_000).contains(&t)));
        // the same events every time
        assert_eq!(events(&trains, (1_000_000, 3_000_000), 9), e);
    }

    use crate::fit::effects::EVIDENCE_THRESHOLD;
    use crate::fit::effects::fixture::{Fixture, chunk, poisson_times, rng, static_frames};

    type Events = Vec<(TimeUs, u16, u16, bool)>;

    /// A 16 x 12 static scene for 2 s whose pixels fire at 5 Hz each (about 10 events).
    fn quiet() -> Events {
        let mut rng = rng(71);
        let mut events = Vec::new();
        for y in 0..12u16 {
            for x in 0..16u16 {
                for t in poisson_times(&mut rng, 5.0, 0.0, 2.0) {
                    events.push((t, x, y, rng.random::<bool>()));
                }
            }
        }
        events
    }

    /// Pixel (9, 6) firing at 500 Hz besides.
    fn with_hot_pixel() -> Events {
        let mut rng = rng(72);
        let mut events = quiet();
        for t in poisson_times(&mut rng, 500.0, 0.0, 2.0) {
            events.push((t, 9, 6, rng.random::<bool>()));
        }
        events
    }

    #[test]
    fn one_pixel_at_500_hz_among_quiet_neighbours_is_found_at_its_rate_and_calls_for_hot_pixels() {
        let (model, recording) = (chunk(quiet()), chunk(with_hot_pixel()));
        let f = Fixture::new(&static_frames(16, 12, 2.0, 100.0), &recording, &model);
        let hot = find(&f.context());
        assert_eq!(hot.len(), 1, "{hot:?}");
        assert_eq!((hot[0].x, hot[0].y), (9, 6));
        // about 1000 events in 2 s, Poisson: 500 +- 16 Hz
        assert!((hot[0].rate_hz - 500.0).abs() < 50.0, "{:?}", hot[0]);
        let e = evidence(&f.context());
        assert!(e.calls_for(), "{e:?}");
        assert!(e.score > EVIDENCE_THRESHOLD, "{e:?}");
        assert_eq!(e.score, hot[0].z);
    }

    #[test]
    fn a_hot_pixel_the_model_has_too_does_not_call_for_hot_pixels() {
        let recording = chunk(with_hot_pixel());
        let f = Fixture::new(&static_frames(16, 12, 2.0, 100.0), &recording, &recording);
        assert!(find(&f.context()).is_empty());
        let e = evidence(&f.context());
        assert!(!e.calls_for(), "{e:?}");
    }

    #[test]
    fn a_hot_pixel_that_is_not_kept_is_not_found() {
        let (model, recording) = (chunk(quiet()), chunk(with_hot_pixel()));
        let mut f = Fixture::new(&static_frames(16, 12, 2.0, 100.0), &recording, &model);
        f.kept[6 * 16 + 9] = false;
        assert!(find(&f.context()).is_empty());
        assert!(!evidence(&f.context()).calls_for());
    }
}
