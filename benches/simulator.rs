//! Simulator throughput (input frames per second) at DAVIS240 and DAVIS346 sizes, ideal and
//! with every effect, on one thread and on all threads, stepped one sample at a time and
//! run whole from memory (`Simulator::run_all`). `examples/simulator_throughput.rs`
//! prints the same matrix with events per second as a table. The `render` group guards the
//! scene renderers (one frame of every scene family of `calib/scenes`, on one thread), the
//! hot loop of `simulate --scene`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use ctcal::sim::scene::SceneSpec;
use ctcal::sim::{PixelMaps, PixelParams, Sample, Simulator, Transition};

fn frames(width: usize, height: usize, count: usize) -> Vec<(i64, Vec<f32>)> {
    let spec = SceneSpec::moving_texture(width, height, count as f64 / 1000.0, 1000.0);
    let scene = spec.realise().unwrap();
    (0..=count)
        .map(|k| {
            let mut dn = vec![0f32; width * height];
            scene.render(width, height, k as f64 / 1000.0, &mut dn);
            (k as i64 * 1000, dn)
        })
        .collect()
}

fn all_effects() -> PixelParams {
    PixelParams::from_toml(
        include_str!("../calib/params/all_effects.toml"),
        "all_effects.toml",
    )
    .unwrap()
}

fn simulator(c: &mut Criterion) {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut group = c.benchmark_group("simulate");
    group.sample_size(10);
    for (width, height) in [(240, 180), (346, 260)] {
        let input = frames(width, height, 200);
        let samples: Vec<Sample> = input
            .iter()
            .map(|(t, dn)| Sample {
                t: *t,
                dn: dn.clone(),
                transition: Transition::Linear,
            })
            .collect();
        group.throughput(Throughput::Elements((input.len() - 1) as u64));
        for (model, params) in [
            ("ideal", PixelParams::ideal(0.3, 0.3)),
            ("all_effects", all_effects()),
        ] {
            for threads in [1, cores] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let name = format!("{width}x{height}/{model}/{threads}_threads");
                group.bench_function(name, |b| {
                    b.iter(|| {
                        pool.install(|| {
                            let mut sim =
                                Simulator::new(&params, width, height, PixelMaps::default());
                            sim.start(input[0].0, &input[0].1);
                            let mut events = 0;
                            for (t, dn) in &input[1..] {
                                events += sim.step(*t, dn, Transition::Linear).len();
                            }
                            events
                        })
                    })
                });
                // the same frames held in memory, each row through 32 samples a task
                // (`Simulator::run_all`, the re-simulation's path)
                group.bench_function(
                    format!("{width}x{height}/{model}/{threads}_threads/run_all"),
                    |b| {
                        b.iter(|| {
                            pool.install(|| {
                                Simulator::new(&params, width, height, PixelMaps::default())
                                    .run_all(&samples)
                                    .unwrap()
                                    .len()
                            })
                        })
                    },
                );
            }
        }
    }
    group.finish();
}

/// One frame of each scene family, rendered on the calling thread (frames per second).
fn render(c: &mut Criterion) {
    let mut group = c.benchmark_group("render");
    group.throughput(Throughput::Elements(1));
    for name in [
        "texture_translation",
        "texture_rotation_davis346",
        "natural_image_rotation",
        "checkerboard",
        "multi_object_fast",
        "multi_object_variety",
    ] {
        let path = std::path::PathBuf::from(format!("calib/scenes/{name}.toml"));
        let spec = SceneSpec::from_file(&path).unwrap();
        let scene = spec.realise().unwrap();
        let hz = spec.render_hz(&scene);
        let mut out = vec![0f32; spec.width * spec.height];
        let mut k = 0u64;
        group.bench_function(name, |b| {
            b.iter(|| {
                // a new time every frame, over the scene's length
                let t = (k % (spec.duration_s * hz) as u64) as f64 / hz;
                k += 1;
                scene.render(spec.width, spec.height, t, &mut out);
                out[0]
            })
        });
    }
    group.finish();
}

criterion_group!(benches, simulator, render);
criterion_main!(benches);
