//! The calibration scans of `estimate eppps`, its hot loop without frames (issue 19): one
//! prior image's curve over blocks of 8 x 8 parallel line scans at the 31 thresholds of
//! the grid (profile sampling and the play operator), and the play operator alone on one
//! profile at every threshold.
//!
//! Input: the first natural image of the prior (`calib/priors/natural`), unblurred, under
//! the middle floor; 20 blocks scanning 40 px at 200 px/s in four directions.
//!
//! Also the support filter: two-sided (`stats::support::supported_two_sided`), which eppps
//! and the screen's lag run, and causal in stretches on the pool (`stats::support::supported`),
//! which the fit's observation of every simulation, the re-simulation and the event timing
//! run: 1 M events on 240 x 180, four to a microsecond (as EVT3 packs them).

use criterion::{Criterion, criterion_group, criterion_main};
use ctcal::estimate::eppps::prior;
use ctcal::estimate::eppps::scans::{self, Block, Scan, ScanPixel};
use ctcal::{EventChunk, Sensor};
use rand::{RngExt, SeedableRng};

fn blocks() -> Vec<Block> {
    (0..20)
        .map(|k| {
            let angle = (k % 4) as f64 * std::f64::consts::FRAC_PI_4;
            Block {
                corner: Scan {
                    x: 70.0 + 5.0 * k as f64,
                    y: 60.0 + 3.0 * k as f64,
                    dx: angle.cos(),
                    dy: angle.sin(),
                    length: 40.0,
                    seconds_per_px: 1.0 / 200.0,
                },
            }
        })
        .collect()
}

fn calibration_scans(c: &mut Criterion) {
    let images = prior::images(1);
    let image = images
        .iter()
        .find(|i| i.blur_px == 0.0 && i.floor_of_mean == prior::FLOORS_OF_MEAN[1])
        .expect("the unblurred middle floor");
    let grid = scans::threshold_grid();
    let blocks = blocks();
    c.bench_function(
        "eppps block_curve (20 blocks x 64 scans x 31 thresholds)",
        |b| b.iter(|| scans::block_curve(&image.log, &blocks, &grid, ScanPixel::SYMMETRIC)),
    );
    let profile = scans::profile(&image.log, &blocks[0].corner);
    c.bench_function("eppps count (one 40 px profile, 31 thresholds)", |b| {
        b.iter(|| {
            grid.iter()
                .map(|&ct| scans::count(&profile, ct as f32, ct as f32).on)
                .sum::<u32>()
        })
    });
}

/// 1 M events on 240 x 180 at pixels drawn with a fixed seed, four per microsecond.
fn events() -> EventChunk {
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(2020);
    let mut chunk = EventChunk::default();
    for i in 0..1_000_000i64 {
        let (x, y) = (rng.random_range(0..240), rng.random_range(0..180));
        chunk.push(i / 4, x, y, rng.random_bool(0.5));
    }
    chunk
}

fn support_filter(c: &mut Criterion) {
    let events = events();
    let sensor = Sensor::new(240, 180);
    c.bench_function("support filter, two-sided (1 M events, 240x180)", |b| {
        b.iter(|| ctcal::stats::support::supported_two_sided(&events, sensor, 10_000))
    });
    c.bench_function("support filter, causal (1 M events, 240x180)", |b| {
        b.iter(|| ctcal::stats::support::supported(&events, sensor, 10_000))
    });
}

criterion_group!(benches, calibration_scans, support_filter);
criterion_main!(benches);
