//! The bootstrap over pixels at the cost of the pixels, not of the pairs.
//!
//! The event timing's errors come from a bootstrap that resamples pixels with replacement
//! (Efron & Tibshirani, *An Introduction to the Bootstrap*, 1993, ch. 6; the pixel is the
//! unit because a pixel's samples share its threshold): each draw weighs every pair by how
//! often its pixel was drawn, refits the model ([`super::model`]) and sums each pixel's
//! corrected samples. Done pair by pair, a draw costs the pairs: a dense recording (10 M
//! events on 192 x 144 pixels, 5 M pairs) spent minutes per estimate in its 200 draws.
//!
//! Every sum a draw needs is a sum over pairs of products of the model's columns and the
//! sample: the normal equations' `X^T W X` and `X^T W y`, and per pixel the count, sum and
//! sum of squares of the corrected samples `y - sum_j beta_j x_j` (linear in the
//! coefficients). Within a pixel the weights are one constant ([`super::model::pixel_weights`]:
//! `1 / n`) times the draw count, so a draw's sums are each pixel's own moments (count,
//! column sums, cross products, per polarity) times its count: the moments are summed once
//! and each draw costs one pass over the pixels. The level column is centred on the draw's
//! weighted mean as [`super::model::fit`] centres it, by the exact change of columns
//! `level - m (ON + OFF)` (every pair is ON or OFF).
//!
//! The result is the pair-by-pair bootstrap's, draw for draw (the same pixels drawn from the
//! same seeds), to rounding: the sums are added in another order (tested below to 1e-9).
//! Where pixels hold fewer than 8 pairs on average (the moments then cost more than they
//! save), the moments would take more memory than the pairs themselves (a large sensor), or
//! a pixel's pairs do not share one weight, the draws run pair by pair.

use super::model::{self, Coefficients, Values, columns, resampled_weights};
use super::pixels::{PixelSlots, pixel_sums_both};
use super::samples::Pair;

/// The columns past the two polarity indicators: level, lag, the ON and OFF distance from
/// the frames, the drift and its growth with DN ([`columns`]).
const REST: usize = 6;

/// The columns of [`REST`] a polarity's pairs can hold other than 0: all but the other
/// polarity's distance from the frames (`on * interp` is 0 for an OFF pair, `off * interp`
/// for an ON one). Its moments are kept over these five alone.
const OWN: usize = 5;

/// The entries of a symmetric `OWN x OWN` matrix on and above its diagonal.
const TRIANGLE: usize = OWN * (OWN + 1) / 2;

/// Per polarity (`[OFF, ON]`), the [`REST`] column of each own column.
const OWN_COLUMNS: [[usize; OWN]; 2] = [[0, 1, 3, 4, 5], [0, 1, 2, 4, 5]];

/// The index in the packed upper triangle of entry `(a, b)`, `a <= b < OWN` (row by row).
const fn packed(a: usize, b: usize) -> usize {
    a * OWN - a * (a.saturating_sub(1)) / 2 + (b - a)
}

/// The pairs per pixel from which the moments pay: a draw costs about as much per pixel
/// from moments as per pair pair by pair, and the moments are summed once beforehand
/// (measured: with 2-5 pairs a pixel, 346 x 260, the moments made `estimate aps` 15-20 %
/// slower and took 60-85 MB more).
const MIN_PAIRS_PER_PIXEL: usize = 8;

/// The moments of one pixel's kept pairs of one polarity: their count, the sums of the
/// polarity's own columns past the indicators and of the sample, and their cross products.
///
/// Only the own columns ([`OWN`]) and only the upper triangle of the cross products are
/// kept: the other polarity's column sums to zero and its terms add `+-0.0` to sums that are
/// never `-0.0` (they start at `+0.0` and no addition of finite values makes `-0.0` from
/// it), and `x_a x_b` is `x_b x_a` to the bit, added in the same order. Every sum a draw
/// makes from them is the full moments' to the bit, from 45 % less memory (224 bytes, not
/// 408: the draws read every pixel's moments twice, and were bound by memory).
#[derive(Clone, Copy, Debug, Default)]
pub struct Moments {
    n: u32,
    x: [f64; OWN],
    y: f64,
    xx: [f64; TRIANGLE],
    xy: [f64; OWN],
    yy: f64,
}

impl Moments {
    /// Adds a pair of polarity `on` with columns `rest` and sample `y`.
    fn add(&mut self, on: bool, rest: &[f64; REST], y: f64) {
        let x = OWN_COLUMNS[on as usize].map(|c| rest[c]);
        self.n += 1;
        self.y += y;
        self.yy += y * y;
        for a in 0..OWN {
            self.x[a] += x[a];
            self.xy[a] += x[a] * y;
            for b in a..OWN {
                self.xx[packed(a, b)] += x[a] * x[b];
            }
        }
    }

    /// Count, sum and sum of squares of the samples corrected by `by` (a [`Correction`]
    /// of this polarity): the terms of `y - sum_a beta_a x_a` and its square in the order
    /// the full `REST x REST` loop adds them, less the terms that are `+-0.0`.
    fn corrected(&self, by: &Correction) -> (f64, u32, f64) {
        let mut sum = self.y;
        let mut squares = self.yy;
        // own column 0 is the level, which the samples are not corrected for
        for a in 1..OWN {
            sum -= by.beta[a] * self.x[a];
            squares -= by.twice[a] * self.xy[a];
            for b in 1..OWN {
                squares += by.products[a][b] * self.xx[packed(a.min(b), a.max(b))];
            }
        }
        (sum, self.n, squares)
    }
}

/// The corrections of [`Coefficients::corrected`] (lag, the polarity's distance from the
/// frames, drift, drift per DN; the level is not corrected) over one polarity's own
/// columns, with the products [`Moments::corrected`] takes of them computed once per draw
/// instead of once per pixel (`2 beta_a` and `beta_a beta_b`, the same floats).
struct Correction {
    beta: [f64; OWN],
    twice: [f64; OWN],
    products: [[f64; OWN]; OWN],
}

/// The correction of each of the rest columns (the level's is 0: it is not corrected).
fn rest_corrections(c: &Coefficients) -> [f64; REST] {
    [
        0.0,
        c.lag,
        c.interp_on,
        c.interp_off,
        c.drift,
        c.drift_per_dn,
    ]
}

impl Correction {
    fn new(c: &Coefficients, on: bool) -> Self {
        let rest = rest_corrections(c);
        let beta = OWN_COLUMNS[on as usize].map(|col| rest[col]);
        Self {
            beta,
            twice: beta.map(|b| 2.0 * b),
            products: beta.map(|a| beta.map(|b| a * b)),
        }
    }
}

/// One bootstrap draw: how often each pixel (slot) was drawn, or the seed of a draw made
/// pair by pair.
pub enum Draw {
    Counts(Vec<u32>),
    Seed(u64),
}

/// Refits and per-pixel sums of resampled pixels, from the pixels' moments or pair by pair.
pub enum Resampler<'a> {
    Moments {
        /// Per slot, `[OFF, ON]`.
        slots: Vec<[Moments; 2]>,
        /// Per slot, the weight each of its kept pairs has in the fit.
        weight: Vec<f64>,
        /// The slots with a kept pair, in pixel order: the units drawn.
        present: Vec<u32>,
    },
    Pairs {
        pairs: &'a [Pair],
        slots: &'a PixelSlots,
        values: &'a Values,
        weights: &'a [f64],
        pixels: usize,
    },
}

impl<'a> Resampler<'a> {
    /// The resampler of `pairs` with their `values` and fit `weights` (`slots` their
    /// pixels): from moments where pixels hold 8 pairs or more on average, the moments take
    /// no more memory than the pairs (or 64 MB) and every pixel's kept pairs share one
    /// weight; else pair by pair.
    pub fn new(
        pairs: &'a [Pair],
        slots: &'a PixelSlots,
        values: &'a Values,
        weights: &'a [f64],
        pixels: usize,
    ) -> Self {
        let by_pairs = Self::Pairs {
            pairs,
            slots,
            values,
            weights,
            pixels,
        };
        let bytes = slots.len() * std::mem::size_of::<[Moments; 2]>();
        if pairs.len() < MIN_PAIRS_PER_PIXEL * slots.len()
            || bytes > std::mem::size_of_val(pairs).max(64 << 20)
        {
            return by_pairs;
        }
        let (mut level, mut total) = (0.0, 0.0);
        for (&w, &l) in weights.iter().zip(&values.level) {
            if w > 0.0 {
                level += w * l;
                total += w;
            }
        }
        // the moments' level is taken from the kept pairs' weighted mean level, so that
        // centring it on a draw's mean moves it little (no cancellation of large sums)
        let reference_level = level / total.max(1e-300);
        let mut moments = vec![[Moments::default(); 2]; slots.len()];
        let mut weight = vec![0.0; slots.len()];
        for (i, p) in pairs.iter().enumerate() {
            let w = weights[i];
            if w <= 0.0 {
                continue;
            }
            let slot = slots.slot_of(i);
            if weight[slot] == 0.0 {
                weight[slot] = w;
            } else if weight[slot] != w {
                return by_pairs;
            }
            let row = columns(p, values.level[i] - reference_level, values.lag[i]);
            let rest: &[f64; REST] = row[2..].try_into().expect("six columns");
            moments[slot][p.on as usize].add(p.on, rest, values.y[i]);
        }
        let present = (0..slots.len() as u32)
            .filter(|&s| weight[s as usize] > 0.0)
            .collect();
        Self::Moments {
            slots: moments,
            weight,
            present,
        }
    }

    /// The draw of seed `seed`: the pixels with a kept pair, drawn with replacement as
    /// often as there are such pixels (the draws of [`resampled_weights`]).
    pub fn draw(&self, seed: u64) -> Draw {
        match self {
            Self::Moments { slots, present, .. } => {
                Draw::Counts(model::draw_counts(present, slots.len(), seed))
            }
            Self::Pairs { .. } => Draw::Seed(seed),
        }
    }

    /// The model refitted to `draw` ([`model::fit`] with the resampled weights).
    pub fn fit(&self, draw: &Draw, leak: bool) -> Option<Coefficients> {
        match (self, draw) {
            (Self::Moments { slots, weight, .. }, Draw::Counts(times)) => {
                let (xtx, xty) = normal_sums(slots, weight, times)?;
                model::solve(&xtx, &xty, leak, false)
            }
            (
                Self::Pairs {
                    pairs,
                    values,
                    weights,
                    pixels,
                    ..
                },
                &Draw::Seed(seed),
            ) => model::fit(
                pairs,
                values,
                &resampled_weights(pairs, weights, *pixels, seed),
                leak,
            ),
            _ => unreachable!("a draw is made by its own resampler"),
        }
    }

    /// The refit and the per-pixel (sum, count, sum of squares) of the corrected samples of
    /// each polarity, `[OFF, ON]`, each pixel repeated as often as it was drawn (`None` for
    /// a polarity with fewer than 10 entries).
    pub fn fit_and_sums(&self, draw: &Draw, leak: bool) -> Option<(Coefficients, PolaritySums)> {
        match (self, draw) {
            (Self::Moments { slots, .. }, Draw::Counts(times)) => {
                let c = self.fit(draw, leak)?;
                let sums = [0, 1].map(|polarity| {
                    let by = Correction::new(&c, polarity == 1);
                    let mut out = Vec::new();
                    for (m, &t) in slots.iter().zip(times) {
                        let m = &m[polarity];
                        if t > 0 && m.n > 0 {
                            out.extend(std::iter::repeat_n(m.corrected(&by), t as usize));
                        }
                    }
                    (out.len() >= 10).then_some(out)
                });
                Some((c, sums))
            }
            (
                Self::Pairs {
                    pairs,
                    slots,
                    values,
                    weights,
                    pixels,
                },
                &Draw::Seed(seed),
            ) => {
                let w = resampled_weights(pairs, weights, *pixels, seed);
                let c = model::fit(pairs, values, &w, leak)?;
                let sums = pixel_sums_both(pairs, slots, values, &w, &c).map(|s| s.map(|s| s.0));
                Some((c, sums))
            }
            _ => unreachable!("a draw is made by its own resampler"),
        }
    }
}

/// Per polarity, `[OFF, ON]`, each drawn pixel's (sum, count, sum of squares) of corrected
/// samples, repeated as often as it was drawn; `None` with fewer than 10 entries.
pub type PolaritySums = [Option<Vec<(f64, u32, f64)>>; 2];

/// The normal equations' sums of a draw, the level centred on the draw's weighted mean
/// (`None` when nothing is drawn).
fn normal_sums(
    slots: &[[Moments; 2]],
    weight: &[f64],
    times: &[u32],
) -> Option<([[f64; 8]; 8], [f64; 8])> {
    let (mut xtx, mut xty) = drawn_sums(slots, weight, times);
    let total = xtx[0][0] + xtx[1][1];
    if total <= 0.0 {
        return None;
    }
    // the indicator rows mirrored into their columns
    let (on_row, off_row) = (xtx[0], xtx[1]);
    for (row, (&on, &off)) in xtx.iter_mut().zip(on_row.iter().zip(&off_row)).skip(2) {
        row[0] = on;
        row[1] = off;
    }
    // centre the level on the draw's weighted mean: column 2 becomes level - m (ON + OFF)
    let mean = (xtx[0][2] + xtx[1][2]) / total;
    let indicators: [f64; 8] = std::array::from_fn(|b| xtx[0][b] + xtx[1][b]);
    xtx[2][2] += mean * (mean * total - 2.0 * indicators[2]);
    for b in (0..8).filter(|&b| b != 2) {
        xtx[2][b] -= mean * indicators[b];
        xtx[b][2] = xtx[2][b];
    }
    xty[2] -= mean * (xty[0] + xty[1]);
    Some((xtx, xty))
}

/// The sums of a draw's pixels' moments, each weighed by its weight times its count: the
/// indicators' rows and the columns past them, the level not centred and the indicators'
/// columns left 0.
fn drawn_sums(slots: &[[Moments; 2]], weight: &[f64], times: &[u32]) -> ([[f64; 8]; 8], [f64; 8]) {
    let mut xtx = [[0.0; 8]; 8];
    let mut xty = [0.0; 8];
    for ((m, &w), &t) in slots.iter().zip(weight).zip(times) {
        if t == 0 {
            continue;
        }
        let f = w * t as f64;
        // column 0 is ON, 1 OFF; the moments are [OFF, ON]
        for (indicator, m, own) in [(1usize, &m[0], OWN_COLUMNS[0]), (0, &m[1], OWN_COLUMNS[1])] {
            if m.n == 0 {
                continue;
            }
            xtx[indicator][indicator] += f * m.n as f64;
            xty[indicator] += f * m.y;
            for a in 0..OWN {
                xtx[indicator][2 + own[a]] += f * m.x[a];
                xty[2 + own[a]] += f * m.xy[a];
                for b in a..OWN {
                    xtx[2 + own[a]][2 + own[b]] += f * m.xx[packed(a, b)];
                }
            }
        }
    }
    // the cross products below the diagonal: the same terms in the same order as above it
    for (a, b) in (2..8).flat_map(|a| (a + 1..8).map(move |b| (a, b))) {
        xtx[b][a] = xtx[a][b];
    }
    (xtx, xty)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::rng::{Stream, generator};
    use rand::RngExt;

    /// Pairs of 300 pixels with 1-40 pairs each, both polarities, levels, lags, distances
    /// from the frames and times spread, and a few pairs left out (weight 0).
    fn pairs_and_values() -> (Vec<Pair>, Values, Vec<f64>) {
        let mut rng = generator(7, Stream::Scene, 3);
        let mut pairs = Vec::new();
        for pixel in 0..300u32 {
            let n = rng.random_range(1..40);
            for _ in 0..n {
                let dn0 = rng.random_range(10.0..200.0f32);
                pairs.push(Pair {
                    pixel: pixel * 7 % 1000,
                    on: rng.random_range(0.0..1.0f32) < 0.6,
                    dn0,
                    dn1: dn0 * rng.random_range(0.7..1.4f32),
                    dt: rng.random_range(0.001..0.2f32),
                    around: [dn0; 4],
                    block: 0,
                    interp: [rng.random_range(0.0..1.0f32), rng.random_range(0.0..1.0f32)],
                });
            }
        }
        let values = Values {
            y: (0..pairs.len())
                .map(|_| rng.random_range(0.1..0.6))
                .collect(),
            level: pairs
                .iter()
                .map(|p| ((p.dn0 + p.dn1) as f64).ln())
                .collect(),
            lag: (0..pairs.len())
                .map(|_| rng.random_range(-0.01..0.01))
                .collect(),
        };
        let keep: Vec<bool> = (0..pairs.len())
            .map(|_| rng.random_range(0.0..1.0f64) < 0.9)
            .collect();
        let weights = model::pixel_weights(&pairs, &keep, 1000);
        (pairs, values, weights)
    }

    #[test]
    fn draws_from_moments_are_the_draws_made_pair_by_pair() {
        let (pairs, values, weights) = pairs_and_values();
        let slots = PixelSlots::new(&pairs);
        let moments = Resampler::new(&pairs, &slots, &values, &weights, 1000);
        assert!(matches!(moments, Resampler::Moments { .. }));
        let by_pairs = Resampler::Pairs {
            pairs: &pairs,
            slots: &slots,
            values: &values,
            weights: &weights,
            pixels: 1000,
        };
        for seed in [11u64, 12, 500] {
            for leak in [false, true] {
                let (a, sums_a) = moments.fit_and_sums(&moments.draw(seed), leak).unwrap();
                let (b, sums_b) = by_pairs.fit_and_sums(&by_pairs.draw(seed), leak).unwrap();
                let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 * (1.0 + y.abs());
                for (x, y) in [
                    (a.c_on, b.c_on),
                    (a.c_off, b.c_off),
                    (a.level_slope, b.level_slope),
                    (a.lag, b.lag),
                    (a.interp_on, b.interp_on),
                    (a.interp_off, b.interp_off),
                    (a.drift, b.drift),
                    (a.drift_per_dn, b.drift_per_dn),
                ] {
                    assert!(close(x, y), "seed {seed} leak {leak}: {x} vs {y}");
                }
                for (sa, sb) in sums_a.iter().zip(&sums_b) {
                    let (sa, sb) = (sa.as_ref().unwrap(), sb.as_ref().unwrap());
                    assert_eq!(sa.len(), sb.len());
                    for (p, q) in sa.iter().zip(sb) {
                        assert_eq!(p.1, q.1);
                        assert!(close(p.0, q.0) && close(p.2, q.2), "{p:?} vs {q:?}");
                    }
                }
                // a different draw gives different thresholds: the comparison can fail
                let (c, _) = by_pairs
                    .fit_and_sums(&by_pairs.draw(seed + 1), leak)
                    .unwrap();
                assert!(!close(c.c_on, b.c_on));
            }
        }
    }

    /// A pixel's moments over all six columns and the whole cross-product matrix, summed
    /// and used as they were before the moments kept the own columns' upper triangle.
    #[derive(Clone, Copy, Default)]
    struct Full {
        n: u32,
        x: [f64; REST],
        y: f64,
        xx: [[f64; REST]; REST],
        xy: [f64; REST],
        yy: f64,
    }

    impl Full {
        fn add(&mut self, x: &[f64; REST], y: f64) {
            self.n += 1;
            self.y += y;
            self.yy += y * y;
            for a in 0..REST {
                self.x[a] += x[a];
                self.xy[a] += x[a] * y;
                for b in 0..REST {
                    self.xx[a][b] += x[a] * x[b];
                }
            }
        }

        fn corrected(&self, beta: &[f64; REST]) -> (f64, u32, f64) {
            let (mut sum, mut squares) = (self.y, self.yy);
            for a in 0..REST {
                sum -= beta[a] * self.x[a];
                squares -= 2.0 * beta[a] * self.xy[a];
                for b in 0..REST {
                    squares += beta[a] * beta[b] * self.xx[a][b];
                }
            }
            (sum, self.n, squares)
        }
    }

    /// The sums the full moments gave, pixel by pixel and for the normal equations: the
    /// same to the bit.
    #[test]
    fn the_own_columns_triangle_gives_the_full_moments_sums() {
        let (pairs, values, weights) = pairs_and_values();
        let slots = PixelSlots::new(&pairs);
        let Resampler::Moments {
            slots: own, weight, ..
        } = Resampler::new(&pairs, &slots, &values, &weights, 1000)
        else {
            panic!("moments expected");
        };
        let mut full = vec![[Full::default(); 2]; slots.len()];
        let (mut level, mut total) = (0.0, 0.0);
        for (&w, &l) in weights.iter().zip(&values.level) {
            if w > 0.0 {
                level += w * l;
                total += w;
            }
        }
        for (i, p) in pairs.iter().enumerate().filter(|&(i, _)| weights[i] > 0.0) {
            let row = columns(p, values.level[i] - level / total, values.lag[i]);
            let rest: &[f64; REST] = row[2..].try_into().unwrap();
            full[slots.slot_of(i)][p.on as usize].add(rest, values.y[i]);
        }
        let times: Vec<u32> = (0..slots.len() as u32).map(|s| s % 3).collect();
        let c = Coefficients {
            c_on: 0.3,
            c_off: 0.25,
            drift: 0.013,
            drift_per_dn: -2e-4,
            level_slope: 0.07,
            lag: 0.003,
            interp_on: -0.021,
            interp_off: 0.034,
        };
        let beta = rest_corrections(&c);
        for polarity in [0, 1] {
            let by = Correction::new(&c, polarity == 1);
            for (m, f) in own.iter().zip(&full) {
                let (a, b) = (m[polarity].corrected(&by), f[polarity].corrected(&beta));
                assert_eq!(
                    (a.0.to_bits(), a.1, a.2.to_bits()),
                    (b.0.to_bits(), b.1, b.2.to_bits())
                );
            }
        }
        let (mut xtx, mut xty) = ([[0.0f64; 8]; 8], [0.0f64; 8]);
        for ((m, &w), &t) in full
            .iter()
            .zip(&weight)
            .zip(&times)
            .filter(|(_, t)| **t > 0)
        {
            let f = w * t as f64;
            for (indicator, m) in [(1usize, &m[0]), (0, &m[1])] {
                if m.n == 0 {
                    continue;
                }
                xtx[indicator][indicator] += f * m.n as f64;
                xty[indicator] += f * m.y;
                for a in 0..REST {
                    xtx[indicator][2 + a] += f * m.x[a];
                    xty[2 + a] += f * m.xy[a];
                    for b in 0..REST {
                        xtx[2 + a][2 + b] += f * m.xx[a][b];
                    }
                }
            }
        }
        let bits = |(m, v): ([[f64; 8]; 8], [f64; 8])| {
            (m.map(|row| row.map(f64::to_bits)), v.map(f64::to_bits))
        };
        assert_eq!(bits(drawn_sums(&own, &weight, &times)), bits((xtx, xty)));
    }

    #[test]
    fn pixels_whose_pairs_weigh_differently_are_resampled_pair_by_pair() {
        let (pairs, values, mut weights) = pairs_and_values();
        let slots = PixelSlots::new(&pairs);
        let first_kept = weights.iter().position(|&w| w > 0.0).unwrap();
        let same_pixel = (first_kept + 1..pairs.len())
            .find(|&i| pairs[i].pixel == pairs[first_kept].pixel && weights[i] > 0.0)
            .unwrap();
        weights[same_pixel] *= 2.0;
        let r = Resampler::new(&pairs, &slots, &values, &weights, 1000);
        assert!(matches!(r, Resampler::Pairs { .. }));
    }
}
