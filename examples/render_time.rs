//! Render-only timing of a scene: whole frames of `Scene::render` on the calling thread
//! (no simulation, no output), at the first FRAMES times of the scene's render rate; the
//! best of RUNS passes, in ms per frame. For the rendering share of `simulate --scene`
//! (benches/README.md), where perf's shares are noisy on a loaded machine.
//!
//! cargo run --release --example render_time SCENE.toml [FRAMES] [RUNS]

use ctcal::sim::scene::SceneSpec;
use std::time::Instant;

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .expect("usage: render_time SCENE.toml [FRAMES] [RUNS]");
    let frames: usize = args.next().map_or(300, |s| s.parse().expect("frames"));
    let runs: usize = args.next().map_or(5, |s| s.parse().expect("runs"));
    let spec = SceneSpec::from_file(path.as_ref()).expect("scene");
    let scene = spec.realise().expect("realised");
    let rate = spec.render_hz(&scene);
    let (width, height) = (spec.width, spec.height);
    let mut out = vec![0f32; width * height];
    let mut best = f64::INFINITY;
    let mut checksum = 0.0;
    for _ in 0..runs {
        let start = Instant::now();
        for k in 0..frames {
            scene.render(width, height, k as f64 / rate, &mut out);
            checksum += f64::from(out[k % out.len()]);
        }
        best = best.min(start.elapsed().as_secs_f64());
    }
    println!(
        "{path}: {:.4} ms/frame (best of {runs} x {frames} frames at {rate:.0} Hz; checksum {checksum:.6e})",
        best * 1e3 / frames as f64,
    );
}
