//! Simulator throughput: input frames per second and events per second at DAVIS240 and
//! DAVIS346 sizes, ideal and with every effect, on one thread and on all threads.
//! Frames are rendered before timing (a texture translating at 65 px/s, 1 kHz).
//!
//! cargo run --release --example simulator_throughput [SECONDS]

use ctcal::sim::scene::SceneSpec;
use ctcal::sim::{PixelMaps, PixelParams, Simulator, Transition};
use std::time::Instant;

fn frames(width: usize, height: usize, seconds: f64, rate: f64) -> Vec<(i64, Vec<f32>)> {
    let scene = SceneSpec::moving_texture(width, height, seconds, rate)
        .realise()
        .expect("scene");
    let n = (seconds * rate).round() as usize;
    (0..=n)
        .map(|k| {
            let t = k as f64 / rate;
            let mut dn = vec![0f32; width * height];
            scene.render_parallel(width, height, t, &mut dn);
            ((t * 1e6).round() as i64, dn)
        })
        .collect()
}

fn all_effects() -> PixelParams {
    PixelParams::from_toml(
        include_str!("../calib/params/all_effects.toml"),
        "all_effects.toml",
    )
    .expect("valid")
}

fn main() {
    let seconds: f64 = std::env::args()
        .nth(1)
        .map(|s| s.parse().expect("seconds"))
        .unwrap_or(1.0);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!("| sensor | model | threads | frames/s | events/s | events |");
    println!("|---|---|---|---|---|---|");
    let sizes: Vec<(usize, usize)> = match std::env::var("SIZES").ok().as_deref() {
        Some("small") => vec![(120, 90), (60, 45)],
        _ => vec![(240, 180), (346, 260)],
    };
    for (width, height) in sizes {
        let input = frames(width, height, seconds, 1000.0);
        let only = std::env::var("ONLY").unwrap_or_default();
        for (model, params) in [
            ("ideal", PixelParams::ideal(0.3, 0.3)),
            ("all effects", all_effects()),
        ] {
            if !only.is_empty() && only != model {
                continue;
            }
            let thread_counts = if std::env::var_os("ONE_THREAD").is_some() {
                vec![1]
            } else {
                vec![1, cores]
            };
            for threads in thread_counts {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("pool");
                // best of five runs: the machine's other load only ever slows a run down
                let repeats = std::env::var("REPEATS")
                    .ok()
                    .and_then(|r| r.parse().ok())
                    .unwrap_or(5);
                let (elapsed, events) = (0..repeats)
                    .map(|_| {
                        pool.install(|| {
                            let mut sim =
                                Simulator::new(&params, width, height, PixelMaps::default());
                            sim.start(input[0].0, &input[0].1);
                            let started = Instant::now();
                            let mut events = 0usize;
                            for (t, dn) in &input[1..] {
                                events += sim.step(*t, dn, Transition::Linear).len();
                            }
                            events += sim.finish().len();
                            (started.elapsed().as_secs_f64(), events)
                        })
                    })
                    .fold(
                        (f64::INFINITY, 0),
                        |best, run| if run.0 < best.0 { run } else { best },
                    );
                let steps = (input.len() - 1) as f64;
                println!(
                    "| {width}x{height} | {model} | {threads} | {:.0} | {:.2e} | {events} |",
                    steps / elapsed,
                    events as f64 / elapsed
                );
            }
        }
    }
}
