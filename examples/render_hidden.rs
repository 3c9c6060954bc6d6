//! How much time a scene's rendering adds to its simulation, on the global pool's threads
//! (`RAYON_NUM_THREADS`): `sim::run` (no output written) over the scene's frames rendered
//! beforehand (the simulation alone), rendered in turn before each step, and rendered one
//! ahead on another thread ([`ctcal::sim::ahead`]). The best of RUNS passes of each,
//! interleaved, in seconds, and the rendering's exposed share `1 - alone / with`. For
//! `benches/README.md`: what `simulate --scene` waits for the renderer.
//!
//! cargo run --release --example render_hidden SCENE.toml [PARAMS.toml] [RUNS]

use ctcal::sim::scene::{SceneSource, SceneSpec};
use ctcal::sim::source::{FrameSource, ReplaySamples};
use ctcal::sim::{PixelMaps, PixelParams};
use std::time::Instant;

/// Seconds of one simulation of `source`'s samples.
fn simulate(source: &mut dyn FrameSource, params: &PixelParams) -> f64 {
    let start = Instant::now();
    let sink = |_: &ctcal::events::EventChunk| Ok::<(), ctcal::sim::SimError>(());
    ctcal::sim::run(source, params, PixelMaps::default(), sink, |_| {}).expect("simulated");
    start.elapsed().as_secs_f64()
}

fn main() {
    let mut args = std::env::args().skip(1);
    let usage = "usage: render_hidden SCENE.toml [PARAMS.toml] [RUNS]";
    let spec = SceneSpec::from_file(args.next().expect(usage).as_ref()).expect("scene");
    let params = match args.next() {
        Some(path) => PixelParams::from_file(path.as_ref()).expect("params"),
        None => PixelParams::ideal(0.3, 0.3),
    };
    let runs: usize = args.next().map_or(5, |s| s.parse().expect("runs"));
    let scene = spec.realise().expect("realised");
    let (width, height) = (spec.width, spec.height);
    let mut rendered = SceneSource::new(&spec, scene.clone());
    let samples: Vec<_> = std::iter::from_fn(|| rendered.next_frame().expect("rendered")).collect();
    let mut best = [f64::INFINITY; 3];
    for _ in 0..runs {
        let times = [
            simulate(&mut ReplaySamples::new(&samples, width, height), &params),
            simulate(&mut SceneSource::new(&spec, scene.clone()), &params),
            simulate(
                ctcal::sim::ahead::ahead(SceneSource::new(&spec, scene.clone())).as_mut(),
                &params,
            ),
        ];
        for (b, t) in best.iter_mut().zip(times) {
            *b = b.min(t);
        }
    }
    let [alone, in_turn, ahead] = best;
    println!(
        "{} frames, {} threads: alone {alone:.3} s, in turn {in_turn:.3} s ({:.1} %), ahead {ahead:.3} s ({:.1} %)",
        samples.len(),
        rayon::current_num_threads(),
        100.0 * (1.0 - alone / in_turn),
        100.0 * (1.0 - alone / ahead),
    );
}
