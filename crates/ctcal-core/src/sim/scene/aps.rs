//! APS-like frames of a scene: frame `i` integrates the intensity over
//! `[i / rate, i / rate + exposure]` (motion blur), by the trapezoid rule on renders spaced
//! at most a render interval apart, is rounded to 8 bits and is stamped at the exposure
//! midpoint (the convention of the oracle's APS frames and of DAVIS timestamps).

use super::{ApsSpec, Scene};
use crate::events::Frame;

/// Renders every APS frame whose exposure ends within `duration_s`.
pub fn render(
    scene: &Scene,
    width: usize,
    height: usize,
    duration_s: f64,
    render_hz: f64,
    aps: &ApsSpec,
) -> Vec<Frame> {
    let count = ((duration_s - aps.exposure_s) * aps.rate_hz + 1e-9)
        .floor()
        .max(0.0) as usize
        + 1;
    let samples = ((aps.exposure_s * render_hz).ceil() as usize).max(1) + 1;
    let mut sum = vec![0f64; width * height];
    let mut buffer = vec![0f32; width * height];
    (0..count)
        .map(|i| {
            let start = i as f64 / aps.rate_hz;
            sum.iter_mut().for_each(|s| *s = 0.0);
            let n = if aps.exposure_s > 0.0 { samples } else { 1 };
            for k in 0..n {
                let t = if n == 1 {
                    start
                } else {
                    start + aps.exposure_s * k as f64 / (n - 1) as f64
                };
                let weight = if n == 1 || (k > 0 && k + 1 < n) {
                    1.0
                } else {
                    0.5
                };
                scene.render_parallel(width, height, t, &mut buffer);
                for (s, &b) in sum.iter_mut().zip(&buffer) {
                    *s += weight * b as f64;
                }
            }
            let total_weight = if n == 1 { 1.0 } else { (n - 1) as f64 };
            Frame {
                t: ((start + aps.exposure_s / 2.0) * 1e6).round() as i64,
                width: width as u32,
                height: height as u32,
                pixels: sum
                    .iter()
                    .map(|s| (s / total_weight).round().clamp(0.0, 255.0) as u8)
                    .collect(),
                exposure_us: Some((aps.exposure_s * 1e6).round() as i64),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::scene::checkerboard::CheckerboardScene;

    #[test]
    fn exposure_blurs_a_moving_edge_and_stamps_the_midpoint() {
        // an edge moving 100 px/s for a 20 ms exposure smears over 2 px
        let scene = Scene::Checkerboard(CheckerboardScene {
            square_px: 20.0,
            lo_dn: 0.0,
            hi_dn: 200.0,
            vx_px_s: 100.0,
            vy_px_s: 0.0,
            origin_px: [0.0, 0.0],
        });
        let aps = ApsSpec {
            rate_hz: 10.0,
            exposure_s: 0.02,
        };
        let frames = render(&scene, 40, 4, 0.5, 1000.0, &aps);
        assert_eq!(frames.len(), 5);
        assert_eq!(frames[0].t, 10_000);
        assert_eq!(frames[0].exposure_us, Some(20_000));
        // row 2 lies inside the first square row (row 0 straddles the edge at y = 0)
        let row: Vec<u8> = frames[0].pixels[80..120].to_vec();
        assert_eq!(row[10], 200);
        assert_eq!(row[30], 0);
        // the edge at x = 20..22 over the exposure: intermediate values
        assert!(row[20] > 0 && row[20] < 200, "{row:?}");
    }
}
