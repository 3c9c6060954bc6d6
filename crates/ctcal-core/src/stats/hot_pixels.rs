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
//!
//! [`Detectability`] says how likely the search is to name a hot pixel of a given rate on a
//! given recording, so that the hot pixels it finds can stand for those it misses.

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

/// The pixels (index `y * width + x`) of the 8-neighbourhood of (x, y) on the sensor.
pub fn neighbours(width: usize, height: usize, x: usize, y: usize) -> impl Iterator<Item = usize> {
    (y.saturating_sub(1)..(y + 2).min(height))
        .flat_map(move |ny| (x.saturating_sub(1)..(x + 2).min(width)).map(move |nx| (nx, ny)))
        .filter(move |&p| p != (x, y))
        .map(move |(nx, ny)| ny * width + nx)
}

/// The largest count among the 8 neighbours of pixel (x, y).
fn neighbour_max(counts: &[u32], width: usize, height: usize, x: usize, y: usize) -> f64 {
    neighbours(width, height, x, y)
        .map(|p| counts[p])
        .max()
        .unwrap_or(0) as f64
}

/// The median count of the 8 neighbours of pixel (x, y): the scene's count there, as far
/// as its neighbours tell.
pub fn neighbour_median(counts: &[u32], width: usize, height: usize, x: usize, y: usize) -> f64 {
    let around: Vec<f64> = neighbours(width, height, x, y)
        .map(|p| counts[p] as f64)
        .collect();
    crate::stats::robust::median(&around).unwrap_or(0.0)
}

/// `1.4826 * MAD` of the residuals `c - m` over the active pixels (those that fired or
/// whose busiest neighbour did): the robust scale of the z-score. `None` when no pixel is
/// active.
fn residual_scale(counts: &[u32], width: usize, height: usize) -> Option<f64> {
    let mut absolute_residuals = Vec::new();
    for y in 0..height {
        for x in 0..width {
            let c = counts[y * width + x];
            if c == 0 {
                continue;
            }
            let m = neighbour_max(counts, width, height, x, y);
            absolute_residuals.push((c as f64 - m).abs());
        }
    }
    if absolute_residuals.is_empty() {
        return None;
    }
    let mid = absolute_residuals.len() / 2;
    let (_, mad, _) = absolute_residuals.select_nth_unstable_by(mid, f64::total_cmp);
    Some(1.4826 * *mad)
}

/// The smallest count at which a pixel whose busiest neighbour fired `m` is named, the
/// search's one rule: at least [`MIN_EVENTS`] and `z > Z_THRESHOLD`, i.e.
/// `c > m + Z * max(scale, sqrt(m + 1))`.
fn count_to_be_named(m: f64, scale: f64) -> u64 {
    let bound = m + Z_THRESHOLD * scale.max((m + 1.0).sqrt());
    (bound.floor() as u64 + 1).max(MIN_EVENTS as u64)
}

/// Finds hot pixels in a `width x height` map of per-pixel event counts over `duration_s`.
pub fn find_hot_pixels(
    counts: &[u32],
    width: usize,
    height: usize,
    duration_s: f64,
) -> Vec<HotPixel> {
    let Some(scale) = residual_scale(counts, width, height) else {
        return Vec::new();
    };
    let mut hot = Vec::new();
    for y in 0..height {
        for x in 0..width {
            let c = counts[y * width + x];
            if c < MIN_EVENTS {
                continue;
            }
            let m = neighbour_max(counts, width, height, x, y);
            if (c as u64) >= count_to_be_named(m, scale) {
                let z = (c as f64 - m) / scale.max((m + 1.0).sqrt());
                hot.push(HotPixel {
                    x: x as u16,
                    y: y as u16,
                    events: c as u64,
                    rate_hz: if duration_s > 0.0 {
                        c as f64 / duration_s
                    } else {
                        0.0
                    },
                    z,
                });
            }
        }
    }
    hot.sort_by(|a, b| {
        b.events
            .cmp(&a.events)
            .then(a.y.cmp(&b.y))
            .then(a.x.cmp(&b.x))
    });
    hot
}

/// How likely the search above is to name a hot pixel of a given rate placed at a random
/// kept pixel of a recording: the detection probability of a defect that fires a Poisson
/// train whatever the scene (as sensors' hot pixels do, and as simulators place them: at
/// random pixels). At pixel `p` the train adds `Poisson(rate * T)` events to the scene's
/// `c_p`, and is named when the sum reaches [`count_to_be_named`] for the pixel's busiest
/// neighbour `m_p` (the neighbours and the robust scale are the recording's own; one hot
/// pixel hardly moves either). Averaged over the kept pixels:
/// `pi(rate) = mean_p P(Poisson(rate T) >= need_p - c_p)`.
///
/// `pi` is the z-test's chance alone: the fit's later filters (a pixel the model names too,
/// one whose excess shows only while its neighbours fire, the model's own outliers) can
/// only lower it, so it is an upper bound and the weights below a lower one.
///
/// A slow hot pixel on a busy scene does not stand out: `pi` says which rates the search
/// sees, so that a count of named pixels can be turned into a fraction (Horvitz-Thompson:
/// each named pixel stands for `1 / pi` of its kind; Horvitz & Thompson, JASA 1952), and a
/// count of none bounds only the pixels fast enough to be seen.
#[derive(Clone, Debug, PartialEq)]
pub struct Detectability {
    /// (events a pixel lacks to be named, how many kept pixels lack that many), by deficit.
    deficits: Vec<(u64, usize)>,
    pixels: usize,
    duration_s: f64,
}

impl Detectability {
    /// The detectability of `counts` (a `width x height` map over `duration_s`) at the
    /// pixels `kept`. `None` without an active or a kept pixel, or without duration.
    pub fn new(
        counts: &[u32],
        kept: &[bool],
        width: usize,
        height: usize,
        duration_s: f64,
    ) -> Option<Self> {
        let scale = residual_scale(counts, width, height)?;
        let mut by_deficit = std::collections::BTreeMap::<u64, usize>::new();
        for y in 0..height {
            for x in 0..width {
                if !kept[y * width + x] {
                    continue;
                }
                let need = count_to_be_named(neighbour_max(counts, width, height, x, y), scale);
                let deficit = need.saturating_sub(counts[y * width + x] as u64);
                *by_deficit.entry(deficit).or_default() += 1;
            }
        }
        let pixels = by_deficit.values().sum();
        (pixels > 0 && duration_s > 0.0).then(|| Detectability {
            deficits: by_deficit.into_iter().collect(),
            pixels,
            duration_s,
        })
    }

    /// `pi(rate)`: the share of kept pixels at which a hot pixel of `rate_hz` is named.
    pub fn probability(&self, rate_hz: f64) -> f64 {
        let mean = rate_hz.max(0.0) * self.duration_s;
        let reached = |deficit: u64| -> f64 {
            if deficit == 0 {
                1.0
            } else if mean <= 0.0 {
                0.0
            } else {
                // P(X >= k) = P(X > k - 1)
                use statrs::distribution::{DiscreteCDF, Poisson};
                Poisson::new(mean).map_or(0.0, |d| d.sf(deficit - 1))
            }
        };
        self.deficits
            .iter()
            .map(|&(deficit, n)| n as f64 * reached(deficit))
            .sum::<f64>()
            / self.pixels as f64
    }

    /// The rate at which a hot pixel is named at `share` of the kept pixels (Brent's root
    /// of `pi(rate) - share` in the rate's logarithm, argmin's `BrentRoot`), between 0.1
    /// event and 10^7 events over the duration. `None` where `pi` is above `share` already
    /// at the lower end or below it at the upper end.
    pub fn rate_at(&self, share: f64) -> Option<f64> {
        use argmin::core::{CostFunction, Error, Executor};
        use argmin::solver::brent::BrentRoot;
        struct Gap<'a>(&'a Detectability, f64);
        impl CostFunction for Gap<'_> {
            type Param = f64;
            type Output = f64;
            fn cost(&self, log_rate: &f64) -> Result<f64, Error> {
                Ok(self.0.probability(log_rate.exp()) - self.1)
            }
        }
        let (lo, hi) = ((0.1 / self.duration_s).ln(), (1e7 / self.duration_s).ln());
        let gap = Gap(self, share);
        if gap.cost(&lo).ok()? >= 0.0 || gap.cost(&hi).ok()? <= 0.0 {
            return None;
        }
        let result = Executor::new(gap, BrentRoot::new(lo, hi, 1e-6))
            .configure(|state| state.param(0.5 * (lo + hi)).max_iters(100))
            .run()
            .ok()?;
        result.state.best_param.map(f64::exp)
    }
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

    /// Every pixel at 20 events over 10 s (MAD 0, so the scale is sqrt(21)): a pixel is
    /// named from 66 events (c > 20 + 10 sqrt(21) = 65.8), 46 more than the scene's. Half
    /// the pixels name a train whose mean is the lambda of P(Poisson(lambda) >= 46) = 1/2,
    /// 45.6671 (by the Poisson series, bisected): 4.56671 Hz.
    #[test]
    fn a_flat_scene_names_half_its_hot_pixels_at_the_poisson_median() {
        let counts = vec![20u32; 40 * 20];
        let d = Detectability::new(&counts, &[true; 800], 40, 20, 10.0).unwrap();
        let half = d.rate_at(0.5).unwrap();
        assert!((half - 4.56671).abs() < 1e-4, "{half}");
        assert!((d.probability(half) - 0.5).abs() < 1e-6);
        assert_eq!(d.probability(0.0), 0.0);
        assert!(d.probability(10.0) > 0.999);
        // pixels left out do not count: with only the first row kept, the same
        let mut first_row = [false; 800];
        first_row[..40].fill(true);
        let d = Detectability::new(&counts, &first_row, 40, 20, 10.0).unwrap();
        assert!((d.rate_at(0.5).unwrap() - half).abs() < 1e-9);
    }
}
