//! Hot pixels beyond the model's own outliers.
//!
//! The hot-pixel search ([`crate::stats::hot_pixels`]: a robust z-score of each pixel's
//! count against its busiest neighbour) runs first in the loop, on a model without
//! mismatch or noise. But a pixel with a low threshold fires more events of every kind —
//! shot noise and leak scale with `nominal / threshold` (v2e; Hu, Liu & Delbruck, *v2e*,
//! CVPRW 2021), and a fine texture's crossings with `1 / threshold` — so a recording with
//! strong threshold mismatch and noise has count outliers without a single defective pixel
//! (200-draw study, `benches/coverage/after-2026-11-25/`: 12 of the 38 cases without hot
//! pixels named 2 to 114).
//!
//! The final model has the mismatch and noise the loop found. Its own simulation, searched
//! the same way (its named hot trains left out), gives the number of outliers the model
//! makes, `m`. Of the recording's `n` named pixels, the `n - m` of highest z are reported
//! as hot; the count's interval carries both counts' Poisson spread (variance `n + m`,
//! its upper end at least Garwood's 3.69 for a count of none), or is Garwood's exact
//! Poisson interval of `n` when the model makes none. The pixels stay
//! masked and simulated as named either way (they are outliers to the model too).

use crate::estimate::interval::z95;
use crate::fit::Uncertain;
use crate::stats::binomial::{median_interval95, poisson95};
use crate::stats::hot_pixels::{HotPixel, find_hot_pixels};

/// The hot pixels a fit reports.
#[derive(Clone, Debug, PartialEq)]
pub struct HotExcess {
    /// The named pixels beyond the model's own outliers (highest z first).
    pub hot: Vec<HotPixel>,
    /// Outliers the final model makes by itself (away from the named pixels).
    pub model_outliers: usize,
    /// The fraction of kept pixels that are hot, with its interval.
    pub fraction: Uncertain,
    /// The median rate of the reported pixels, with its interval (`None`: none reported).
    pub rate: Option<Uncertain>,
}

/// The per-pixel counts of the recording and of the final model, over the same blocks.
pub struct Counts<'a> {
    pub real_named: &'a [HotPixel],
    /// The model's per-pixel counts (its named trains included: they are left out here).
    pub model: &'a [u32],
    pub width: usize,
    pub height: usize,
    pub duration_s: f64,
    pub kept_pixels: usize,
}

/// The recording's named pixels in excess of the model's own outliers.
pub fn excess(c: &Counts) -> HotExcess {
    let mut model = c.model.to_vec();
    for h in c.real_named {
        model[h.y as usize * c.width + h.x as usize] = 0;
    }
    let m = find_hot_pixels(&model, c.width, c.height, c.duration_s)
        .into_iter()
        .filter(|p| !c.real_named.iter().any(|h| (h.x, h.y) == (p.x, p.y)))
        .count();
    let n = c.real_named.len();
    let k = n.saturating_sub(m);
    let (lo, hi) = if m == 0 {
        poisson95(n)
    } else {
        let spread = z95() * ((n + m) as f64).sqrt();
        let k = n as f64 - m as f64;
        // never below what a count of none leaves open (Garwood's upper end for 0)
        ((k - spread).max(0.0), (k + spread).max(poisson95(0).1))
    };
    let pixels = c.kept_pixels.max(1) as f64;
    let mut hot = c.real_named.to_vec();
    hot.sort_by(|a, b| b.z.total_cmp(&a.z));
    hot.truncate(k);
    HotExcess {
        rate: median_rate(&hot),
        fraction: Uncertain::with_interval(
            k as f64 / pixels,
            None,
            [Some(lo / pixels), Some((hi / pixels).min(1.0))],
        ),
        hot,
        model_outliers: m,
    }
}

/// The median rate of `hot` with the order-statistic interval of a median, or under six
/// pixels the range of their rates widened by each rate's Poisson error
/// (1.96 / sqrt(events)).
fn median_rate(hot: &[HotPixel]) -> Option<Uncertain> {
    let rates: Vec<f64> = hot.iter().map(|h| h.rate_hz).collect();
    let rate = crate::stats::robust::median(&rates)?;
    let (lo, hi) = median_interval95(&rates).unwrap_or_else(|| {
        let poisson = |h: &HotPixel, side: f64| {
            h.rate_hz * (1.0 + side * z95() / (h.events.max(1) as f64).sqrt()).max(0.0)
        };
        (
            hot.iter()
                .map(|h| poisson(h, -1.0))
                .fold(f64::INFINITY, f64::min),
            hot.iter().map(|h| poisson(h, 1.0)).fold(0.0, f64::max),
        )
    });
    Some(Uncertain::with_interval(rate, None, [Some(lo), Some(hi)]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pixel(x: u16, z: f64, rate_hz: f64) -> HotPixel {
        HotPixel {
            x,
            y: 5,
            events: (rate_hz * 10.0) as u64,
            rate_hz,
            z,
        }
    }

    /// A flat 40 x 20 map at 20 events a pixel, with outliers at the given columns of row 5.
    fn map(outliers: &[usize]) -> Vec<u32> {
        let mut m = vec![20u32; 40 * 20];
        for &x in outliers {
            m[5 * 40 + x] = 400;
        }
        m
    }

    fn counts<'a>(named: &'a [HotPixel], model: &'a [u32]) -> Counts<'a> {
        Counts {
            real_named: named,
            model,
            width: 40,
            height: 20,
            duration_s: 10.0,
            kept_pixels: 800,
        }
    }

    #[test]
    fn outliers_the_model_makes_as_often_are_not_hot() {
        let named = [
            pixel(3, 50.0, 40.0),
            pixel(9, 80.0, 40.0),
            pixel(15, 60.0, 40.0),
        ];
        // the model makes three outliers of its own elsewhere: nothing in excess
        let model = map(&[21, 27, 33]);
        let e = excess(&counts(&named, &model));
        assert_eq!((e.model_outliers, e.hot.len()), (3, 0));
        assert_eq!(e.fraction.value, 0.0);
        let [lo, hi] = e.fraction.ci95.unwrap();
        // 0 - 3 +- 1.96 sqrt(6): the interval reaches 4.8 pixels
        assert_eq!(lo, Some(0.0));
        assert!((hi.unwrap() * 800.0 - z95() * 6f64.sqrt()).abs() < 1e-9);
        // one named against five of the model's: -4 + 4.8 is under what none leaves open
        let model = map(&[21, 25, 29, 33, 37]);
        let e = excess(&counts(&named[..1], &model));
        assert_eq!(e.model_outliers, 5);
        assert!((e.fraction.ci95.unwrap()[1].unwrap() * 800.0 - 3.6889).abs() < 1e-3);
        assert!(e.rate.is_none());
    }

    #[test]
    fn without_model_outliers_every_named_pixel_is_hot_with_a_poisson_interval() {
        let named = [pixel(3, 50.0, 40.0), pixel(9, 80.0, 40.0)];
        // the model's trains at the named pixels are left out
        let model = map(&[3, 9]);
        let e = excess(&counts(&named, &model));
        assert_eq!((e.model_outliers, e.hot.len()), (0, 2));
        assert_eq!(e.hot[0].x, 9, "highest z first");
        let [lo, hi] = e.fraction.ci95.unwrap();
        // Garwood for 2 events: [0.242, 7.22]
        assert!((lo.unwrap() * 800.0 - 0.2422).abs() < 1e-3, "{lo:?}");
        assert!((hi.unwrap() * 800.0 - 7.2247).abs() < 1e-3, "{hi:?}");
        assert_eq!(e.rate.unwrap().value, 40.0);
    }

    #[test]
    fn the_highest_of_more_named_pixels_than_the_model_explains_are_kept() {
        let named = [
            pixel(3, 50.0, 40.0),
            pixel(9, 900.0, 300.0),
            pixel(15, 60.0, 40.0),
        ];
        let model = map(&[30]);
        let e = excess(&counts(&named, &model));
        assert_eq!(e.model_outliers, 1);
        let kept: Vec<u16> = e.hot.iter().map(|h| h.x).collect();
        assert_eq!(kept, vec![9, 15]);
    }
}
