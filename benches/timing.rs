//! The event-timing estimator, the hot loop of `estimate aps` and of the starting thresholds
//! of `fit` (issue 19): a whole estimate with the frames' log offset fitted (pairs read
//! along the flow, the offset's root and interval, the 200 bootstrap draws) on one thread
//! and on all threads, and one bootstrap draw (resampled weights, the weighted least
//! squares, the per-pixel sums of both polarities), and the samples' mode.
//!
//! Input: a 1/f texture translating over a 240x180 sensor for 0.5 s, rendered at 1 kHz
//! and simulated with the ideal pixel (thresholds 0.3), its 25 Hz frames as 8-bit APS
//! frames (everything made before timing).

use criterion::{Criterion, criterion_group, criterion_main};
use ctcal::estimate::frames::{FrameOptions, PreparedFrames};
use ctcal::estimate::timing::{self, TimingOptions, model, pixels, samples};
use ctcal::events::{EventChunk, Frame, Sensor};
use ctcal::sim::log_response::LogMap;
use ctcal::sim::scene::SceneSpec;
use ctcal::sim::{LogResponse, PixelMaps, PixelParams, Simulator, Transition};

const WIDTH: usize = 240;
const HEIGHT: usize = 180;
/// Rendered frames (1 kHz) and the step between the APS frames kept (25 Hz).
const RENDERED: usize = 500;
const APS_STEP: usize = 40;

/// The recording: its events and its 8-bit frames.
fn recording() -> (EventChunk, Vec<Frame>) {
    let spec = SceneSpec::moving_texture(WIDTH, HEIGHT, RENDERED as f64 / 1000.0, 1000.0);
    let scene = spec.realise().unwrap();
    let params = PixelParams::ideal(0.3, 0.3);
    let mut sim = Simulator::new(&params, WIDTH, HEIGHT, PixelMaps::default());
    let mut events = EventChunk::default();
    let mut frames = Vec::new();
    let mut dn = vec![0f32; WIDTH * HEIGHT];
    for k in 0..=RENDERED {
        scene.render(WIDTH, HEIGHT, k as f64 / 1000.0, &mut dn);
        let t = k as i64 * 1000;
        if k == 0 {
            sim.start(t, &dn);
        } else {
            events.extend_from(sim.step(t, &dn, Transition::Linear));
        }
        if k % APS_STEP == 0 {
            frames.push(Frame {
                t,
                width: WIDTH as u32,
                height: HEIGHT as u32,
                pixels: dn
                    .iter()
                    .map(|&v| v.round().clamp(0.0, 255.0) as u8)
                    .collect(),
                exposure_us: None,
            });
        }
    }
    (events, frames)
}

fn timing_estimator(c: &mut Criterion) {
    let (events, frames) = recording();
    let log_map = LogMap::new(LogResponse::V2e, 0.001);
    let prepared =
        PreparedFrames::new(&frames, &events.t, &[], log_map, &FrameOptions::default()).unwrap();
    let sensor = Sensor::new(WIDTH as u16, HEIGHT as u16);
    let excluded = vec![false; sensor.pixels()];
    let options = TimingOptions {
        fit_offset: true,
        choose_response: true,
        ..TimingOptions::default()
    };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut group = c.benchmark_group("timing");
    group.sample_size(10);
    for threads in [1, cores] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        group.bench_function(format!("estimate_fit_offset/{threads}_threads"), |b| {
            b.iter(|| {
                pool.install(|| timing::estimate(&events, &prepared, sensor, &excluded, &options))
                    .expect("an estimate")
            })
        });
    }
    let pairs = samples::collect(&events, &prepared, 0, sensor, &excluded, None);
    let (_, values, weights) =
        model::fit_at(&pairs, &log_map, 0.0, 0.5, sensor.pixels(), true).expect("a fit");
    let slots = pixels::PixelSlots::new(&pairs);
    group.bench_function(format!("bootstrap_draw/{}_pairs", pairs.len()), |b| {
        b.iter(|| {
            let w = model::resampled_weights(&pairs, &weights, sensor.pixels(), 11);
            let c = model::fit(&pairs, &values, &w, true).expect("a fit");
            let on = pixels::pixel_sums(&pairs, &slots, &values, &w, &c, true);
            let off = pixels::pixel_sums(&pairs, &slots, &values, &w, &c, false);
            (on.map(|s| s.0.len()), off.map(|s| s.0.len()))
        })
    });
    // the samples' mode (mean shift from the median and the deciles, over the sorted
    // samples): once per polarity in every fit; 2.5 M samples are a dense recording's
    // (coverage draw 51), this recording's log changes repeated, each copy scaled by 1e-7
    // more (all distinct, as a real recording's)
    let n = values.y.len();
    let many: Vec<f64> = (0..2_500_000)
        .map(|i| values.y[i % n] * (1.0 + 1e-7 * (i / n) as f64))
        .collect();
    group.bench_function(format!("mode/{}_samples", many.len()), |b| {
        b.iter(|| model::mode(&many, 0.5))
    });
    group.finish();
}

criterion_group!(benches, timing_estimator);
criterion_main!(benches);
