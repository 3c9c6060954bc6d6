//! The noise model simulated back onto held-out blocks and measured like the recording.
//!
//! Without grey frames the scene cannot be re-simulated, but the pixel's own additions can
//! be: the blocks' supported events (the scene, as recorded) are kept, their isolated
//! events and the named hot pixels' events taken out, and the model's noise is drawn on
//! top — Poisson shot noise per polarity at every kept pixel (leak as its ON excess, at
//! its rate: v2e's leak is a drift with a random phase per pixel, whose events at a
//! quiet pixel are evenly spread), each named hot pixel a Poisson train at the model's
//! rate and ON share, and a refractory period that drops a drawn event closer than the
//! period to its pixel's last event. The result goes through the very measurement the
//! recording went through ([`super::measure::measure`]): support windows, uncovered
//! time, the quiet-pixel rule. So the check closes the loop on what the analytic
//! comparison takes for granted — that isolated events over uncovered time give the rate
//! whatever the scene hides, that hot pixels' neighbours are measured alike, that the
//! refractory period costs the noise little.
//!
//! The same-pixel intervals and the ON/OFF balance belong to the scene's events, which
//! are the recording's own here: for those two components the model's prediction
//! ([`super::model::Prediction::of`]) stands.

use super::measure::{BlockMeasure, Isolation, Measuring, SUPPORT_WINDOWS_US, measure};
use super::model::{NoiseModel, Prediction};
use crate::events::{EventChunk, Sensor, TimeUs};
use crate::fit::effects::hot_pixels::{self, HotTrain};
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Poisson};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Drawn events beyond this many times the recording's own (plus a million) are not drawn: a
/// rate measured on little quiet time spread over every pixel would cost more than the
/// recording. The analytic comparison then stands alone.
const MAX_DRAWN_PER_EVENT: f64 = 4.0;

/// What the model is simulated onto.
pub struct Replaying<'a> {
    pub measuring: &'a Measuring<'a>,
    /// The held-out blocks, in time order.
    pub spans: &'a [(TimeUs, TimeUs)],
    /// The support the noise is measured under.
    pub isolation: Isolation,
    /// The named hot pixels' trains (positions and ON shares; rates from the model).
    pub trains: &'a [HotTrain],
    /// The refractory period the model applies, µs.
    pub edge_us: Option<f64>,
    pub seed: u64,
}

/// The model simulated onto the blocks and measured, or why it was not.
pub fn simulated(r: &Replaying, model: &NoiseModel) -> Result<Prediction, String> {
    let ranges = padded(r.spans, r.measuring.events);
    let scene = scene(r, &ranges);
    let noise = noise(r, model, &ranges)?;
    let refractory = r.edge_us.filter(|_| model.refractory);
    let events = overlay(&scene, &noise, r.measuring.sensor, refractory);
    let blocks = measure(
        &Measuring {
            events: &events,
            ..*r.measuring
        },
        r.spans,
    );
    let blocks: Vec<&BlockMeasure> = blocks.iter().collect();
    let rate = |on| BlockMeasure::isolated_rate(&blocks, r.isolation, on).map_or(0.0, |v| v.0);
    let seconds: f64 = blocks.iter().map(|b| b.seconds).sum();
    let hot_rates = (0..r.trains.len())
        .map(|k| blocks.iter().map(|b| b.hot_events[k]).sum::<u64>() as f64 / seconds)
        .collect();
    let analytic = Prediction::of(model);
    Ok(Prediction {
        on_hz: rate(true),
        off_hz: rate(false),
        hot_rates_hz: (!r.trains.is_empty()).then_some(hot_rates),
        ..analytic
    })
}

/// The blocks widened by the longest support window each side (neighbours' events there
/// cover the blocks' time), within the recording, overlapping ones joined.
fn padded(spans: &[(TimeUs, TimeUs)], events: &EventChunk) -> Vec<(TimeUs, TimeUs)> {
    let pad = SUPPORT_WINDOWS_US[SUPPORT_WINDOWS_US.len() - 1];
    let (first, end) = (events.t[0], events.t[events.len() - 1] + 1);
    let mut out: Vec<(TimeUs, TimeUs)> = Vec::new();
    for &(a, b) in spans {
        let (a, b) = ((a - pad).max(first), (b + pad).min(end));
        match out.last_mut() {
            Some(last) if a <= last.1 => last.1 = last.1.max(b),
            _ => out.push((a, b)),
        }
    }
    out
}

/// The recording's supported events at kept pixels over `ranges`: the scene as recorded,
/// its isolated events (noise, leak) and the hot pixels' events out.
fn scene(r: &Replaying, ranges: &[(TimeUs, TimeUs)]) -> EventChunk {
    let m = r.measuring;
    let w = m.sensor.width as usize;
    let kept = m.kept_pixels();
    let mut all = EventChunk::default();
    for &(a, b) in ranges {
        let from = m.events.t.partition_point(|&t| t < a);
        let to = m.events.t.partition_point(|&t| t < b);
        for i in from..to {
            if kept[m.events.y[i] as usize * w + m.events.x[i] as usize] {
                all.push(m.events.t[i], m.events.x[i], m.events.y[i], m.events.on[i]);
            }
        }
    }
    let support = crate::stats::support::supported_two_sided_within(
        &all,
        m.sensor,
        r.isolation.window_us(),
        r.isolation.radius_px(),
    );
    let mut out = EventChunk::with_capacity(all.len());
    for (i, _) in support.iter().enumerate().filter(|(_, s)| **s) {
        out.push(all.t[i], all.x[i], all.y[i], all.on[i]);
    }
    out
}

/// The model's own events over `ranges`, time-sorted: shot noise and leak at every kept
/// pixel (and at the named hot pixels when the model does not know them as hot), the
/// named hot pixels' trains at the model's rates.
fn noise(
    r: &Replaying,
    model: &NoiseModel,
    ranges: &[(TimeUs, TimeUs)],
) -> Result<EventChunk, String> {
    let pixels = noisy_pixels(r, model);
    let pixel_seconds: f64 = pixels.len() as f64
        * ranges
            .iter()
            .map(|r| (r.1 - r.0) as f64 * 1e-6)
            .sum::<f64>();
    let expected = (model.noise_on_hz + model.noise_off_hz) * pixel_seconds;
    let bound = MAX_DRAWN_PER_EVENT * r.measuring.events.len() as f64 + 1e6;
    if expected > bound {
        return Err(format!(
            "the model's noise would draw {expected:.0} events on the held-out blocks, over {bound:.0} (four times the recording's events plus a million): not simulated back"
        ));
    }
    let mut out = drawn_noise(r, model, ranges, &pixels, expected);
    if let Some(rates) = &model.hot_rates_hz {
        let trains: Vec<HotTrain> = r
            .trains
            .iter()
            .zip(rates)
            .map(|(t, &rate_hz)| HotTrain { rate_hz, ..*t })
            .collect();
        for &range in ranges {
            out = EventChunk::merged(&out, &hot_pixels::events(&trains, range, r.seed));
        }
    }
    Ok(out)
}

/// The pixels (y * W + x) the noise is drawn at: the kept ones, and the named hot pixels
/// when the model does not know them as hot.
fn noisy_pixels(r: &Replaying, model: &NoiseModel) -> Vec<usize> {
    let m = r.measuring;
    let w = m.sensor.width as usize;
    let mut pixels: Vec<usize> = m
        .kept_pixels()
        .iter()
        .enumerate()
        .filter(|(_, k)| **k)
        .map(|(p, _)| p)
        .collect();
    if model.hot_rates_hz.is_none() {
        pixels.extend(m.hot.iter().map(|&(x, y)| y as usize * w + x as usize));
    }
    pixels
}

/// The model's shot noise and leak over `ranges`, time-sorted: per range and polarity a
/// Poisson number of events (about `expected` in all), each at a uniform time and one of
/// `pixels` drawn uniformly.
fn drawn_noise(
    r: &Replaying,
    model: &NoiseModel,
    ranges: &[(TimeUs, TimeUs)],
    pixels: &[usize],
    expected: f64,
) -> EventChunk {
    let w = r.measuring.sensor.width as usize;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(r.seed);
    let mut drawn: Vec<(TimeUs, u32, bool)> = Vec::with_capacity(expected as usize + 16);
    for &(a, b) in ranges {
        let seconds = (b - a) as f64 * 1e-6;
        for (rate, on) in [(model.noise_on_hz, true), (model.noise_off_hz, false)] {
            let mean = rate * pixels.len() as f64 * seconds;
            if mean.is_nan() || mean <= 0.0 {
                continue;
            }
            let n = Poisson::new(mean).map_or(0.0, |d| d.sample(&mut rng)) as u64;
            for _ in 0..n {
                let p = pixels[rng.random_range(0..pixels.len())];
                drawn.push((rng.random_range(a..b), p as u32, on));
            }
        }
    }
    drawn.sort_unstable();
    let mut out = EventChunk::with_capacity(drawn.len());
    for (t, p, on) in drawn {
        out.push(t, (p as usize % w) as u16, (p as usize / w) as u16, on);
    }
    out
}

/// The scene's events with the drawn ones laid over them, in time order. Under a
/// refractory period a drawn event closer than the period to its pixel's last event (of
/// either kind) is dropped; the scene's events are the recording's and stay.
fn overlay(
    scene: &EventChunk,
    drawn: &EventChunk,
    sensor: Sensor,
    refractory_us: Option<f64>,
) -> EventChunk {
    let width = sensor.width as usize;
    let mut out = EventChunk::with_capacity(scene.len() + drawn.len());
    let mut last = vec![TimeUs::MIN; sensor.pixels()];
    let (mut i, mut j) = (0, 0);
    while i < scene.len() || j < drawn.len() {
        let from_scene = j == drawn.len() || (i < scene.len() && scene.t[i] <= drawn.t[j]);
        let (c, k) = if from_scene { (scene, i) } else { (drawn, j) };
        let (t, x, y) = (c.t[k], c.x[k], c.y[k]);
        let p = y as usize * width + x as usize;
        let blocked = !from_scene
            && last[p] != TimeUs::MIN
            && refractory_us.is_some_and(|e| ((t - last[p]) as f64) < e);
        if !blocked {
            out.push(t, x, y, c.on[k]);
            last[p] = t;
        }
        if from_scene {
            i += 1;
        } else {
            j += 1;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chunk(events: &[(TimeUs, u16, u16, bool)]) -> EventChunk {
        let mut c = EventChunk::default();
        for &(t, x, y, on) in events {
            c.push(t, x, y, on);
        }
        c
    }

    #[test]
    fn a_drawn_event_inside_the_refractory_period_is_dropped_and_the_scene_stays() {
        let scene = chunk(&[(1_000, 2, 0, true), (1_300, 2, 0, true)]);
        let drawn = chunk(&[
            (1_200, 2, 0, false),
            (1_900, 2, 0, false),
            (1_950, 3, 0, true),
        ]);
        let out = overlay(&scene, &drawn, Sensor::new(8, 1), Some(500.0));
        // 1200 is 200 us after the scene's 1000; 1900 is 600 us after 1300; pixel 3 is new
        assert_eq!(out.t, vec![1_000, 1_300, 1_900, 1_950]);
        let all = overlay(&scene, &drawn, Sensor::new(8, 1), None);
        assert_eq!(all.len(), 5);
    }

    /// A static scene with 0.5 Hz ON and 0.2 Hz OFF noise: the model with the measured
    /// rates, simulated back, measures what the recording measures; twice the rates
    /// measure twice as much.
    #[test]
    fn the_measured_rates_simulated_back_are_measured_again() {
        let sensor = Sensor::new(60, 40);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        let mut all = Vec::new();
        for y in 0..40u16 {
            for x in 0..60u16 {
                for (rate, on) in [(0.5, true), (0.2, false)] {
                    let mut t = 0.0;
                    loop {
                        t += -(1.0 - rng.random::<f64>()).ln() / rate;
                        if t >= 20.0 {
                            break;
                        }
                        all.push(((t * 1e6) as TimeUs, x, y, on));
                    }
                }
            }
        }
        all.sort_unstable();
        let events = chunk(&all);
        let excluded = vec![false; sensor.pixels()];
        let measuring = Measuring {
            events: &events,
            sensor,
            excluded: &excluded,
            hot: &[],
        };
        let spans = [(10_000_000, 20_000_000)];
        let real = measure(&measuring, &spans);
        let real: Vec<&BlockMeasure> = real.iter().collect();
        let (on, _) = BlockMeasure::isolated_rate(&real, Isolation::default(), true).unwrap();
        let (off, _) = BlockMeasure::isolated_rate(&real, Isolation::default(), false).unwrap();
        let replaying = Replaying {
            measuring: &measuring,
            spans: &spans,
            isolation: Isolation::default(),
            trains: &[],
            edge_us: None,
            seed: 3,
        };
        let model = NoiseModel {
            noise_on_hz: on,
            noise_off_hz: off,
            ..NoiseModel::ideal()
        };
        let back = simulated(&replaying, &model).unwrap();
        // 2400 pixels x 10 s: ON 12000 +- 110 events, OFF 4800 +- 70
        assert!(
            (back.on_hz / on - 1.0).abs() < 0.04,
            "{} for {on}",
            back.on_hz
        );
        assert!(
            (back.off_hz / off - 1.0).abs() < 0.06,
            "{} for {off}",
            back.off_hz
        );
        let doubled = NoiseModel {
            noise_on_hz: 2.0 * on,
            noise_off_hz: 2.0 * off,
            ..model.clone()
        };
        let back2 = simulated(&replaying, &doubled).unwrap();
        assert!((back2.on_hz / on - 2.0).abs() < 0.1, "{}", back2.on_hz);
        // the ideal pixel adds nothing to a scene without supported events
        let none = simulated(&replaying, &NoiseModel::ideal()).unwrap();
        assert_eq!((none.on_hz, none.off_hz), (0.0, 0.0));
    }
}
