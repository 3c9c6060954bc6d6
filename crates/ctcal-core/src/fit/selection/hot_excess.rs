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
//!
//! The loop may leave mismatch out of the final model although event timing measures it
//! (a spread whose interval excludes 0 but short of the evidence the loop needs to try it),
//! and a fitted spread has its own interval. The pixels at the low tail of a spread the
//! data allow are outliers a defect-free sensor makes (coverage seeds 1001-1080 and
//! 2001-2080: 9 of 160 draws without hot pixels named 2 to 19, every one with a true
//! spread of 30-50 % of a threshold and no mismatch in the final model). So the count's
//! lower end is taken against `m_hi`, the most outliers the model makes at a spread the
//! data allow (a few spreads across its interval, Poisson spread of `n + m_hi`): where
//! such a model makes as many, the count reaches 0. The most, not the upper end's: the
//! search's scale is the robust spread of counts, which a wide mismatch raises, so a model
//! with a wider spread can name fewer outliers (draw 1018: none at 0.173). A spread at
//! which the model makes more outliers than the recording's `n` beyond Poisson chance
//! (`m_s - n > 1.96 sqrt(m_s + n)`) is one the recording rules out, even were every named
//! pixel a low threshold, and is not counted (draw 1076: 73 named, 381 at a spread of 0.22,
//! the upper end of a fitted 0.054). A model's count is one simulation's, Poisson like the
//! recording's: where `n` does not exceed it beyond chance (the exact conditional test of
//! two Poisson counts, Przyborowski & Wilenski, Biometrika 1940) the lower end is 0.
//!
//! A slow hot pixel on a busy scene is not named at all. The search's detection
//! probability at a random kept pixel, `pi(rate)` ([`Detectability`], from the recording's
//! own counts), turns the count into a fraction: each reported pixel counts `1 / pi` at its
//! excess rate over its neighbours' median (Horvitz & Thompson, JASA 1952), with `pi`
//! floored at 1/2, and the count's interval is scaled by the mean weight. Hot pixels at or
//! above the rate named at half the pixels ([`HotExcess::detection`]) are counted in full
//! (a count of none bounds them: Garwood's 3.69 over half the pixels), a slower one as
//! `2 pi` of one: slower hot pixels are not determinable.

use crate::estimate::interval::z95;
use crate::fit::{HotPixelDetection, Uncertain};
use crate::stats::binomial::{exceeds_by_more_than_chance, median_interval95, poisson95};
use crate::stats::hot_pixels::{Detectability, HotPixel, find_hot_pixels, neighbour_median};

/// The hot pixels a fit reports.
#[derive(Clone, Debug, PartialEq)]
pub struct HotExcess {
    /// The named pixels beyond the model's own outliers (highest z first).
    pub hot: Vec<HotPixel>,
    /// Outliers the final model makes by itself (away from the named pixels).
    pub model_outliers: usize,
    /// The most outliers the model makes at a threshold spread the data allow (at least
    /// `model_outliers`; `None`: not simulated).
    pub model_outliers_at_allowed_spreads: Option<usize>,
    /// The fraction of kept pixels that are hot, with its interval.
    pub fraction: Uncertain,
    /// The median rate of the reported pixels, with its interval (`None`: none reported).
    pub rate: Option<Uncertain>,
    /// Which hot pixels the search sees (`None`: not measurable).
    pub detection: Option<HotPixelDetection>,
}

/// The per-pixel counts of the recording and of the final model, over the same blocks.
pub struct Counts<'a> {
    pub real_named: &'a [HotPixel],
    /// The model's per-pixel counts (its named trains included: they are left out here);
    /// `None` where no model is simulated per pixel (the fit without frames): no outliers
    /// of its own are subtracted.
    pub model: Option<&'a [u32]>,
    /// The same model's counts at other threshold spreads the data allow (none: no spread
    /// is measured): the most outliers among them set the count's lower end.
    pub model_at_allowed_spreads: &'a [Vec<u32>],
    pub width: usize,
    pub height: usize,
    pub duration_s: f64,
    pub kept_pixels: usize,
    /// The recording's per-pixel counts over the same blocks (0 outside the kept pixels),
    /// and which pixels are kept: where a hot pixel could be.
    pub real: &'a [u32],
    pub kept: &'a [bool],
}

/// The recording's named pixels in excess of the model's own outliers.
pub fn excess(c: &Counts) -> HotExcess {
    let m = c.model.map_or(0, |model| model_outliers(model, c));
    let n = c.real_named.len();
    let m_upper = c
        .model_at_allowed_spreads
        .iter()
        .map(|model| model_outliers(model, c))
        .filter(|&m_s| !ruled_out(n, m_s))
        .fold(m, usize::max);
    let k = n.saturating_sub(m);
    let (_, hi) = count_interval(n, m);
    // without a simulated model (the fit without frames) there is no model count to test
    // against: the named count's own interval
    let (lo, _) = match c.model {
        Some(_) => count_interval(n, m_upper),
        None => poisson95(n),
    };
    let pixels = c.kept_pixels.max(1) as f64;
    let mut hot = c.real_named.to_vec();
    hot.sort_by(|a, b| b.z.total_cmp(&a.z));
    hot.truncate(k);
    let detectability = detectability(
        c.real,
        c.real_named,
        c.kept,
        (c.width, c.height),
        c.duration_s,
    );
    let weight = mean_weight(&hot, c, detectability.as_ref().map(|(_, d)| d));
    HotExcess {
        rate: median_rate(&hot, c)
            .map(|r| below_the_search(r, detectability.as_ref().map(|(_, d)| d))),
        fraction: Uncertain::with_interval(
            weight * k as f64 / pixels,
            None,
            [
                Some(weight * lo / pixels),
                Some((weight * hi / pixels).min(1.0)),
            ],
        ),
        hot,
        model_outliers: m,
        model_outliers_at_allowed_spreads: (!c.model_at_allowed_spreads.is_empty())
            .then_some(m_upper),
        detection: detectability.map(|(half, d)| detection(half, &d)),
    }
}

/// The 95 % interval of the named count `n` in excess of `m` outliers of the model's own:
/// Garwood's exact Poisson interval of `n` where `m = 0`, else `n - m` with the Poisson
/// spread of both counts, its upper end never below what a count of none leaves open. The
/// model's `m` is one simulation's count, Poisson itself: where `n` does not exceed it
/// beyond chance (the exact conditional test, [`exceeds_by_more_than_chance`]) the lower end
/// is 0 (two named against a model's none happen by chance a quarter of the time).
fn count_interval(n: usize, m: usize) -> (f64, f64) {
    let (lo, hi) = if m == 0 {
        poisson95(n)
    } else {
        let spread = z95() * ((n + m) as f64).sqrt();
        let k = n as f64 - m as f64;
        ((k - spread).max(0.0), (k + spread).max(poisson95(0).1))
    };
    (
        if exceeds_by_more_than_chance(n, m) {
            lo
        } else {
            0.0
        },
        hi,
    )
}

/// Whether a model that names `m_s` outliers is ruled out by a recording that names `n`:
/// more than Poisson chance allows (one-sided beyond 1.96 standard deviations of the
/// difference).
fn ruled_out(n: usize, m_s: usize) -> bool {
    m_s as f64 - n as f64 > z95() * ((m_s + n) as f64).sqrt()
}

/// The count outliers `model` makes by itself, away from the recording's named pixels
/// (their trains left out of it).
fn model_outliers(model: &[u32], c: &Counts) -> usize {
    let mut model = model.to_vec();
    for h in c.real_named {
        model[h.y as usize * c.width + h.x as usize] = 0;
    }
    find_hot_pixels(&model, c.width, c.height, c.duration_s)
        .into_iter()
        .filter(|p| !c.real_named.iter().any(|h| (h.x, h.y) == (p.x, p.y)))
        .count()
}

/// What the search sees, where the final model has no hot pixels: its reach on the
/// recording's per-pixel counts `real` (0 outside the `kept` pixels) over `duration_s`,
/// the `named` pixels' trains left out, so that the fit can say which hot pixels it would
/// have named.
pub fn search_reach(
    real: &[u32],
    named: &[HotPixel],
    kept: &[bool],
    size: (usize, usize),
    duration_s: f64,
) -> Option<HotPixelDetection> {
    detectability(real, named, kept, size, duration_s).map(|(half, d)| detection(half, &d))
}

/// The search's detectability on the scene without the `named` pixels' own trains (each at
/// its neighbours' median), with the rate it names at half the kept pixels.
fn detectability(
    real: &[u32],
    named: &[HotPixel],
    kept: &[bool],
    (width, height): (usize, usize),
    duration_s: f64,
) -> Option<(f64, Detectability)> {
    let mut scene = real.to_vec();
    for h in named {
        let (x, y) = (h.x as usize, h.y as usize);
        scene[y * width + x] = neighbour_median(real, width, height, x, y) as u32;
    }
    let d = Detectability::new(&scene, kept, width, height, duration_s)?;
    Some((d.rate_at(0.5)?, d))
}

/// What the search sees: the half-detection rate and `pi` on
/// [`HotPixelDetection::rates_hz`] with the half-detection rate among them (the curve is
/// steep there, and the coverage study reads it between its points).
fn detection(half: f64, d: &Detectability) -> HotPixelDetection {
    let mut rates = HotPixelDetection::rates_hz();
    let at = rates.partition_point(|&r| r < half);
    rates.insert(at, half);
    let curve = rates.iter().map(|&r| [r, d.probability(r)]).collect();
    HotPixelDetection::new(half, curve)
}

/// The mean Horvitz-Thompson weight `1 / max(pi, 1/2)` of the reported pixels, each at its
/// excess rate over the median of its 8 neighbours. With none reported their rate is
/// unknown: the weight is that of the slowest pixel counted in full (2), so that a count of
/// none bounds the hot pixels at the half-detection rate or faster; with some reported, the
/// bound is for pixels at their rates (one fast pixel found gives a lower upper end than
/// none found: it says the hot pixels there are fast). 1 where the detectability is not
/// measurable.
fn mean_weight(hot: &[HotPixel], c: &Counts, detectability: Option<&Detectability>) -> f64 {
    let Some(d) = detectability else {
        return 1.0;
    };
    if hot.is_empty() {
        return 2.0;
    }
    let weights: f64 = hot
        .iter()
        .map(|h| 1.0 / d.probability(excess_rate(h, c)).max(0.5))
        .sum();
    weights / hot.len() as f64
}

/// A named pixel's rate beyond the scene's there (its count less its neighbours' median),
/// per second.
fn excess_rate(h: &HotPixel, c: &Counts) -> f64 {
    let scene = neighbour_median(c.real, c.width, c.height, h.x as usize, h.y as usize);
    (h.events as f64 - scene).max(0.0) / c.duration_s.max(1e-9)
}

/// The median train rate of `hot`: each pixel's rate beyond the scene's there
/// ([`excess_rate`]), as the simulator adds a hot pixel's train on top of its normal events
/// ([`crate::sim::effects::hot_pixels`]); a slow hot pixel on a busy scene would otherwise
/// read high by its scene's rate. With the order-statistic interval of a median, or under
/// six pixels the range of their rates widened by each count's Poisson error
/// (1.96 sqrt(events) / seconds).
fn median_rate(hot: &[HotPixel], c: &Counts) -> Option<Uncertain> {
    let rates: Vec<f64> = hot.iter().map(|h| excess_rate(h, c)).collect();
    let rate = crate::stats::robust::median(&rates)?;
    let (lo, hi) = median_interval95(&rates).unwrap_or_else(|| {
        let poisson = |(h, r): (&HotPixel, &f64), side: f64| {
            (r + side * z95() * (h.events as f64).sqrt() / c.duration_s.max(1e-9)).max(0.0)
        };
        (
            hot.iter()
                .zip(&rates)
                .map(|p| poisson(p, -1.0))
                .fold(f64::INFINITY, f64::min),
            hot.iter()
                .zip(&rates)
                .map(|p| poisson(p, 1.0))
                .fold(0.0, f64::max),
        )
    });
    Some(Uncertain::with_interval(rate, None, [Some(lo), Some(hi)]))
}

/// Where the search names hot pixels at the reported rate at fewer than
/// [`FULLY_SEEN`] of the kept pixels, the named ones are the upper tail of their kind's
/// Poisson counts (those that happened to fire more), and the kind's rate can be lower than
/// theirs: the interval's lower end reaches down to the rate named at [`SLOWEST_SEEN`] of
/// the pixels. Coverage draw 77: 41 hot pixels at 12.5 Hz, under the 13.7 Hz named at half
/// the pixels; the 15 named read 16.1 [13.6, 18.5] Hz (`benches/coverage/hot-lag-2026-11-29`).
fn below_the_search(rate: Uncertain, detectability: Option<&Detectability>) -> Uncertain {
    let Some(d) = detectability else {
        return rate;
    };
    let Some([Some(lo), hi]) = rate.ci95 else {
        return rate;
    };
    if d.probability(rate.value) >= FULLY_SEEN {
        return rate;
    }
    let floor = d.rate_at(SLOWEST_SEEN).unwrap_or(0.0);
    Uncertain::with_interval(rate.value, rate.standard_error, [Some(lo.min(floor)), hi])
}

/// The share of the kept pixels at which the search names a hot pixel for its rate to be
/// taken as seen in full.
const FULLY_SEEN: f64 = 0.9;
/// The share at which the search still names a slow hot pixel: the lower end of the rate
/// of a kind the search sees in part.
const SLOWEST_SEEN: f64 = 0.1;

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

    const KEPT: [bool; 800] = [true; 800];

    fn counts<'a>(named: &'a [HotPixel], model: &'a [u32], real: &'a [u32]) -> Counts<'a> {
        Counts {
            real_named: named,
            model: Some(model),
            model_at_allowed_spreads: &[],
            width: 40,
            height: 20,
            duration_s: 10.0,
            kept_pixels: 800,
            real,
            kept: &KEPT,
        }
    }

    #[test]
    fn outliers_the_model_makes_as_often_are_not_hot() {
        let named = [
            pixel(3, 50.0, 40.0),
            pixel(9, 80.0, 40.0),
            pixel(15, 60.0, 40.0),
        ];
        let real = map(&[3, 9, 15]);
        // the model makes three outliers of its own elsewhere: nothing in excess
        let model = map(&[21, 27, 33]);
        let e = excess(&counts(&named, &model, &real));
        assert_eq!((e.model_outliers, e.hot.len()), (3, 0));
        assert_eq!(e.fraction.value, 0.0);
        let [lo, hi] = e.fraction.ci95.unwrap();
        // 0 - 3 +- 1.96 sqrt(6): the interval reaches 4.8 pixels, of those hot enough to
        // be named at half the pixels or more: twice that
        assert_eq!(lo, Some(0.0));
        assert!((hi.unwrap() * 800.0 - 2.0 * z95() * 6f64.sqrt()).abs() < 1e-9);
        // one named against five of the model's: -4 + 4.8 is under what none leaves open
        let model = map(&[21, 25, 29, 33, 37]);
        let e = excess(&counts(&named[..1], &model, &real));
        assert_eq!(e.model_outliers, 5);
        assert!((e.fraction.ci95.unwrap()[1].unwrap() * 800.0 - 2.0 * 3.6889).abs() < 1e-3);
        assert!(e.rate.is_none());
        // the scene's 20 events over 10 s: named from 66, 46 more, by half the pixels of
        // the 773 away from an outlier: P(Poisson(10 r) >= 46) = (400 - 3) / 773
        let half = e.detection.unwrap().detectable_above_hz;
        assert!((4.3..4.7).contains(&half), "{half}");
    }

    /// A slow hot pixel is named at few of the pixels a fast one is: it counts for more of
    /// its kind (at most twice, the weight at the half-detection rate).
    #[test]
    fn a_slow_named_pixel_stands_for_more_than_itself() {
        // a scene of 20 events a pixel over 10 s in rows 0-9 and 100 in rows 10-19: a train
        // is named from 66 in the quiet half, from 201 in the busy one (100 + 10 sqrt(101))
        let busy_half = |mut m: Vec<u32>| {
            m[400..].fill(100);
            m
        };
        // 70 events in the quiet half: z = 50 / sqrt(21) = 10.9, named; 5 Hz beyond the
        // scene, named at (1 + 351 P(Poisson(50) >= 46)) / 800 = 0.33 of the pixels
        let named = [HotPixel {
            x: 3,
            y: 5,
            events: 70,
            rate_hz: 7.0,
            z: 10.9,
        }];
        let mut real = busy_half(map(&[]));
        real[5 * 40 + 3] = 70;
        assert_eq!(find_hot_pixels(&real, 40, 20, 10.0).len(), 1);
        let model = busy_half(map(&[]));
        let e = excess(&counts(&named, &model, &real));
        assert_eq!(e.hot.len(), 1);
        assert!((e.fraction.value * 800.0 - 2.0).abs() < 1e-9);
        let model = map(&[]);
        // a fast one (38 Hz beyond the scene) is named at every pixel once its own train
        // is taken out of the scene (it hides no neighbour): it counts once
        let named = [pixel(3, 50.0, 40.0)];
        let real = map(&[3]);
        let e = excess(&counts(&named, &model, &real));
        assert!((e.fraction.value * 800.0 - 1.0).abs() < 1e-9);
    }

    /// A kind the search names at only part of the pixels may be slower than the named
    /// ones: the rate's lower end reaches the rate named at a tenth of the pixels. Scene: 20
    /// events a pixel over 10 s in rows 0-9, 100 in rows 10-19. The 360 pixels of rows 0-8
    /// need 46 more events, the rest over 100: a tenth is where P(Poisson(10 r) >= 46) =
    /// 80 / 360, r = 4.1 Hz (46 - 0.77 sqrt(46) = 40.8 events in 10 s). A kind at 40 Hz
    /// is named everywhere: its interval stays.
    #[test]
    fn the_rate_of_a_kind_the_search_sees_in_part_reaches_down_to_its_slowest_seen() {
        let mut scene = map(&[]);
        scene[400..].fill(100);
        let d = Detectability::new(&scene, &KEPT, 40, 20, 10.0).unwrap();
        let slow = Uncertain::with_interval(5.0, None, [Some(4.8), Some(5.2)]);
        let [lo, hi] = below_the_search(slow.clone(), Some(&d)).ci95.unwrap();
        assert!((3.9..4.3).contains(&lo.unwrap()), "{lo:?}");
        assert_eq!(hi, Some(5.2));
        let fast = Uncertain::with_interval(40.0, None, [Some(38.0), Some(42.0)]);
        assert_eq!(below_the_search(fast.clone(), Some(&d)), fast);
        assert_eq!(below_the_search(slow.clone(), None), slow);
    }

    #[test]
    fn without_model_outliers_every_named_pixel_counts_with_a_poisson_upper_end() {
        let named = [pixel(3, 50.0, 40.0), pixel(9, 80.0, 40.0)];
        // the model's trains at the named pixels are left out
        let model = map(&[3, 9]);
        let real = map(&[3, 9]);
        let e = excess(&counts(&named, &model, &real));
        assert_eq!((e.model_outliers, e.hot.len()), (0, 2));
        assert_eq!(e.hot[0].x, 9, "highest z first");
        let [lo, hi] = e.fraction.ci95.unwrap();
        // Garwood for 2 events: [0.242, 7.22], each named anywhere at its 38 Hz; but two
        // against the model's none (one simulation, Poisson too) is chance a quarter of the
        // time: the lower end is 0
        assert_eq!(lo, Some(0.0));
        assert!((hi.unwrap() * 800.0 - 7.2247).abs() < 1e-3, "{hi:?}");
        // the train beyond the scene's 20 events (2 Hz) at each: 400 - 20 events over 10 s;
        // each count's Poisson error, 1.96 sqrt(400) / 10, either side
        let rate = e.rate.unwrap();
        assert_eq!(rate.value, 38.0);
        let [lo, hi] = rate.ci95.unwrap();
        assert!((lo.unwrap() - (38.0 - 3.92)).abs() < 1e-3, "{lo:?}");
        assert!((hi.unwrap() - (38.0 + 3.92)).abs() < 1e-3, "{hi:?}");
    }

    /// A map of 20 a pixel with `count` outliers of 400 in rows 10, 13 and 16 (seven a row,
    /// five columns apart: none a neighbour of another or of row 5's).
    fn outliers_below(count: usize) -> Vec<u32> {
        let mut m = map(&[]);
        for i in 0..count {
            m[(10 + 3 * (i / 7)) * 40 + 2 + 5 * (i % 7)] = 400;
        }
        assert_eq!(find_hot_pixels(&m, 40, 20, 10.0).len(), count);
        m
    }

    /// Draw 1062's case in small: eight named pixels, a final model without mismatch that
    /// makes none, and the model at spreads the data allow that make one, eight and twenty.
    #[test]
    fn outliers_of_the_model_at_an_allowed_spread_bring_the_count_down_to_zero() {
        let columns: Vec<usize> = (0..8).map(|i| 1 + 4 * i).collect();
        let named: Vec<HotPixel> = columns
            .iter()
            .map(|&x| pixel(x as u16, 50.0, 40.0))
            .collect();
        let (real, model) = (map(&columns), map(&[]));
        let without = excess(&counts(&named, &model, &real));
        // eight against none is beyond chance (P = 1/256): Garwood's lower end for 8, 3.45
        let lo_without = without.fraction.ci95.unwrap()[0].unwrap();
        assert!((lo_without * 800.0 - 3.4538).abs() < 1e-3, "{lo_without}");
        // a spread whose model names 20 outliers against the recording's 8 is ruled out
        // (20 - 8 > 1.96 sqrt(28) = 10.4): alone, it changes nothing
        let many = outliers_below(20);
        let ruled_out_alone = excess(&Counts {
            model_at_allowed_spreads: std::slice::from_ref(&many),
            ..counts(&named, &model, &real)
        });
        assert_eq!(ruled_out_alone.model_outliers_at_allowed_spreads, Some(0));
        assert_eq!(ruled_out_alone.fraction.ci95, without.fraction.ci95);
        let allowed = [outliers_below(1), outliers_below(8), many];
        let with = excess(&Counts {
            model_at_allowed_spreads: &allowed,
            ..counts(&named, &model, &real)
        });
        // the value is the final model's: eight pixels beyond its none
        assert_eq!((with.hot.len(), with.model_outliers), (8, 0));
        assert_eq!(with.model_outliers_at_allowed_spreads, Some(8));
        assert_eq!(with.fraction.value, without.fraction.value);
        // its upper end as before (Garwood for 8: 15.76 pixels); its lower end from 8 - 8
        let [lo, hi] = with.fraction.ci95.unwrap();
        assert_eq!(lo, Some(0.0));
        assert_eq!(hi, without.fraction.ci95.unwrap()[1]);
        assert!((hi.unwrap() * 800.0 - 15.7632).abs() < 1e-3, "{hi:?}");
    }

    #[test]
    fn the_highest_of_more_named_pixels_than_the_model_explains_are_kept() {
        let named = [
            pixel(3, 50.0, 40.0),
            pixel(9, 900.0, 300.0),
            pixel(15, 60.0, 40.0),
        ];
        let model = map(&[30]);
        let real = map(&[3, 9, 15]);
        let e = excess(&counts(&named, &model, &real));
        assert_eq!(e.model_outliers, 1);
        let kept: Vec<u16> = e.hot.iter().map(|h| h.x).collect();
        assert_eq!(kept, vec![9, 15]);
    }
}
