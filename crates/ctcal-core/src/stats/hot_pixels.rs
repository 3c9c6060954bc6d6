//! Hot pixels: pixels that fire far more than their neighbourhood, whatever the scene.
//!
//! A scene makes event density vary over the sensor, but along structures: a busy region, an
//! edge or a thin line always has a busy neighbour next to each busy pixel. A hot pixel is a
//! lone outlier. So each pixel's count `c` is compared with the largest count `m` among its
//! 8 neighbours; the residual `r = c - m` is turned into a robust z-score `z = r / s`, with
//! `s = 1.4826 * MAD(r)` over the active pixels (the median absolute deviation, scaled to a
//! Gaussian standard deviation) and never below the Poisson spread `sqrt(m + 1)` of the
//! neighbour's count. A pixel is hot when `z > Z_THRESHOLD` and it fired at least
//! `MIN_EVENTS` events. Two hot pixels side by side hide each other; in real sensors that is
//! rare. (Robust z-scores: Iglewicz & Hoaglin, "How to Detect and Handle Outliers", 1993.)

use serde::Serialize;

/// z-score above which a pixel is hot.
pub const Z_THRESHOLD: f64 = 10.0;
/// A hot pixel fired at least this many events.
pub const MIN_EVENTS: u32 = 10;

/// The method, as reported in statistics output.
pub const METHOD: &str = "robust z-score of each pixel's event count against the busiest of its 8 neighbours: z = (count - neighbour_max) / max(1.4826 * MAD, sqrt(neighbour_max + 1)), hot if z > 10 and count >= 10";

/// One hot pixel.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HotPixel {
    pub x: u16,
    pub y: u16,
    pub events: u64,
    pub rate_hz: f64,
    /// The robust z-score.
    pub z: f64,
}

/// The largest count among the 8 neighbours of pixel (x, y).
fn neighbour_max(counts: &[u32], width: usize, height: usize, x: usize, y: usize) -> f64 {
    let mut max = 0;
    for ny in y.saturating_sub(1)..(y + 2).min(height) {
        for nx in x.saturating_sub(1)..(x + 2).min(width) {
            if (nx, ny) != (x, y) {
                max = max.max(counts[ny * width + nx]);
            }
        }
    }
    max as f64
}

/// Finds hot pixels in a `width x height` map of per-pixel event counts over `duration_s`.
pub fn find_hot_pixels(
    counts: &[u32],
    width: usize,
    height: usize,
    duration_s: f64,
) -> Vec<HotPixel> {
    // residuals of active pixels (a pixel with an active neighbourhood counts too)
    let mut candidates = Vec::new();
    let mut absolute_residuals = Vec::new();
    for y in 0..height {
        for x in 0..width {
            let c = counts[y * width + x];
            if c == 0 {
                continue;
            }
            let m = neighbour_max(counts, width, height, x, y);
            let r = c as f64 - m;
            absolute_residuals.push(r.abs());
            if c >= MIN_EVENTS && r > 0.0 {
                candidates.push((x, y, c, m, r));
            }
        }
    }
    if absolute_residuals.is_empty() {
        return Vec::new();
    }
    let mid = absolute_residuals.len() / 2;
    let (_, mad, _) = absolute_residuals.select_nth_unstable_by(mid, f64::total_cmp);
    let scale = 1.4826 * *mad;
    let mut hot: Vec<HotPixel> = candidates
        .into_iter()
        .filter_map(|(x, y, c, m, r)| {
            let z = r / scale.max((m + 1.0).sqrt());
            (z > Z_THRESHOLD).then(|| HotPixel {
                x: x as u16,
                y: y as u16,
                events: c as u64,
                rate_hz: if duration_s > 0.0 {
                    c as f64 / duration_s
                } else {
                    0.0
                },
                z,
            })
        })
        .collect();
    hot.sort_by(|a, b| {
        b.events
            .cmp(&a.events)
            .then(a.y.cmp(&b.y))
            .then(a.x.cmp(&b.x))
    });
    hot
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lone_busy_pixel_is_hot_and_a_busy_region_is_not() {
        let (w, h) = (40, 30);
        let mut counts = vec![3u32; w * h];
        // a bright textured region: 20 events per pixel over a 10x10 block
        for y in 5..15 {
            for x in 5..15 {
                counts[y * w + x] = 20 + ((x * 7 + y * 3) % 5) as u32;
            }
        }
        counts[25 * w + 30] = 60; // hot
        let hot = find_hot_pixels(&counts, w, h, 2.0);
        assert_eq!(hot.len(), 1, "{hot:?}");
        assert_eq!((hot[0].x, hot[0].y, hot[0].events), (30, 25, 60));
        assert_eq!(hot[0].rate_hz, 30.0);
    }

    #[test]
    fn a_thin_busy_line_is_not_hot() {
        let (w, h) = (30, 20);
        let mut counts = vec![1u32; w * h];
        for x in 0..w {
            counts[10 * w + x] = 50 + (x % 3) as u32;
        }
        assert!(find_hot_pixels(&counts, w, h, 1.0).is_empty());
    }
}
