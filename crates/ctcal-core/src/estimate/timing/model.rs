//! The event-timing model, fitted by weighted least squares over every kept pair of
//! consecutive events ([`super::samples`]). With the frames read through `ln(DN + b)`, the
//! log change between a pixel's two events is its threshold, less what leak added:
//!
//! `y = C_pol + s (D0 + D1 DN) dt + beta (level - mean level) + kappa x + g_pol w`
//!
//! - `y` the log change in the direction of the second event (positive when consistent),
//!   `C_pol` the ON or OFF threshold;
//! - leak drifts the memorised level down at `D = D0 + D1 DN` log units per second (v2e's
//!   leak, and DVS-Voltmeter's which grows with brightness), so an ON event needs `D dt` less
//!   change and an OFF event `D dt` more: `s = -1` for ON, `+1` for OFF;
//! - `beta` the dependence on the pixel's log level: zero when the offset `b` is right,
//!   because a threshold does not depend on brightness. The offset is the root of
//!   `beta(b)`, its interval where `|beta|` stays within 1.96 of its bootstrap standard
//!   error ([`offset_interval`]);
//! - the photoreceptor's bandwidth: it follows the light with a lag `tau` that grows in the
//!   dark (`tau ~ 1 / photocurrent ~ 1 / (DN + b)`; Lichtsteiner et al. 2008; v2e), so at an
//!   event the frames are ahead of the pixel by `tau r`, `r` the log intensity's rate of
//!   change there. A pair's change is then off by `tau (r_second - r_first)`: zero on a
//!   steady ramp, large where an edge accelerates or stops. `x = s' (r1 - r0) / (DN + b)`
//!   (`s' = +1` ON, `-1` OFF) carries it, and `kappa = tau (DN + b)` gives the cutoff,
//!   `1 / (2 pi tau)`. Without the term a dim scene's thresholds come out high, and the
//!   offset would absorb what is the lag.
//! - `w` the pair's distance from the frames ([`Pair::interpolation`]: 0 when both events
//!   lie at frame times, 1 when both lie midway): the frames are measured at their times and
//!   interpolated between them, and where the interpolation misses part of the scene's
//!   change (a flow field smoothed across occlusions, rotation, texture finer than the flow
//!   resolves) the samples fall short in proportion to `w`. `g_pol` is the samples' change
//!   midway (negative where they fall short);
//!   `C_pol` is read at `w = 0`, at the frames. In the coverage study's multi-object scenes
//!   at 50 Hz the midway shortfall reached 15-20 % of the threshold; the frame-rate check
//!   (every 2nd and 3rd frame) saw a third of it.
//!
//! Noise events (shot noise, a neighbour's crossing, a hot pixel) break the chain; pairs far
//! from the mode of their polarity (below `mode (1 - w)` or above `mode (1 + 2 w)`) are left
//! out. Each pixel weighs the same in the fit (its pairs `1 / n` each), so that a pixel with
//! a low threshold, which fires more, does not pull the thresholds down.

use super::samples::Pair;
use crate::sim::log_response::LogMap;
#[cfg(target_arch = "x86_64")]
use crate::sim::simd::use_avx2;
use rand::{RngExt, SeedableRng};

/// The fitted coefficients at one offset.
#[derive(Clone, Debug, PartialEq)]
pub struct Coefficients {
    pub c_on: f64,
    pub c_off: f64,
    /// Leak drift at DN 0 (log units per second) and its growth per DN.
    pub drift: f64,
    pub drift_per_dn: f64,
    /// Dependence on the log level (per log unit of level).
    pub level_slope: f64,
    /// The photoreceptor's lag times its photocurrent, `tau (DN + b)`, seconds x DN.
    pub lag: f64,
    /// How much the frames' interpolation changes an ON and an OFF sample whose events
    /// both lie midway between frames (log units; [`Pair::interp`]).
    pub interp_on: f64,
    pub interp_off: f64,
}

impl Coefficients {
    /// The threshold pair `i` measures, the leak's and the lag's shares taken out.
    pub fn corrected(&self, pair: &Pair, v: &Values, i: usize) -> f64 {
        let dn = 0.5 * (pair.dn0 + pair.dn1) as f64;
        let s = if pair.on { -1.0 } else { 1.0 };
        let interp = if pair.on {
            self.interp_on
        } else {
            self.interp_off
        };
        v.y[i]
            - s * (self.drift + self.drift_per_dn * dn) * pair.dt as f64
            - self.lag * v.lag[i]
            - interp * pair.interpolation()
    }

    /// The photoreceptor cutoff the lag stands for at `dn` (Hz), where it is positive.
    pub fn cutoff_hz(&self, dn: f64, b: f64) -> Option<f64> {
        (self.lag > 0.0).then(|| (dn + b) / (std::f64::consts::TAU * self.lag))
    }
}

/// The pairs' log changes, levels and lag covariates at offset `b`.
pub struct Values {
    pub y: Vec<f64>,
    pub level: Vec<f64>,
    pub lag: Vec<f64>,
}

/// The pair's sample: the log change between its events through `log` at offset `b`,
/// signed by the second event's polarity (one threshold, or several, for a true change).
#[inline]
pub fn sample(p: &Pair, log: &LogMap, b: f32) -> f64 {
    let l = |dn: f32| log.apply(dn + b) as f64;
    let sign = if p.on { 1.0 } else { -1.0 };
    sign * (l(p.dn1) - l(p.dn0))
}

/// Pairs whose logs [`values`] takes together.
const LOG_BLOCK: usize = 64;

/// The [`Values`] of `pairs` at offset `b` (with AVX2 where the CPU has it: the same bits,
/// [`crate::sim::simd`]).
pub fn values(pairs: &[Pair], log: &LogMap, b: f32) -> Values {
    #[cfg(target_arch = "x86_64")]
    if use_avx2() {
        // SAFETY: use_avx2() is true only when the CPU has AVX2.
        return unsafe { values_avx2(pairs, log, b) };
    }
    values_portable(pairs, log, b)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn values_avx2(pairs: &[Pair], log: &LogMap, b: f32) -> Values {
    values_portable(pairs, log, b)
}

/// [`sample`] and the level and lag covariates of every pair, each of its seven logs taken
/// once. The logs of a block of pairs are taken in one loop over arrays (the intensities
/// gathered first), which the compiler vectorises: taken pair by pair they were most of the
/// offset search's fits.
#[inline(always)]
fn values_portable(pairs: &[Pair], log: &LogMap, b: f32) -> Values {
    let n = pairs.len();
    let (mut y, mut level, mut lag) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let span = f64::from(super::samples::RATE_SPAN_S);
    // per pair: dn0, dn1, their mean, and the four intensities around the events; offset
    let mut dn = [[0f32; LOG_BLOCK]; 7];
    let mut logs = [[0f32; LOG_BLOCK]; 7];
    let blocks = pairs
        .chunks(LOG_BLOCK)
        .zip(y.chunks_mut(LOG_BLOCK))
        .zip(level.chunks_mut(LOG_BLOCK))
        .zip(lag.chunks_mut(LOG_BLOCK));
    for (((block, y), level), lag) in blocks {
        let m = block.len();
        for (k, p) in block.iter().enumerate() {
            let mid = 0.5 * (p.dn0 + p.dn1);
            let [a0, a1, a2, a3] = p.around;
            for (j, v) in [p.dn0, p.dn1, mid, a0, a1, a2, a3].into_iter().enumerate() {
                dn[j][k] = v + b;
            }
        }
        for (row, out) in dn.iter().zip(&mut logs) {
            log.apply_frame(&row[..m], &mut out[..m]);
        }
        for (k, p) in block.iter().enumerate() {
            let l = |j: usize| logs[j][k] as f64;
            let sign = if p.on { 1.0 } else { -1.0 };
            y[k] = sign * (l(1) - l(0));
            level[k] = l(2);
            let r0 = (l(4) - l(3)) / span;
            let r1 = (l(6) - l(5)) / span;
            lag[k] = sign * (r1 - r0) / dn[2][k].max(1.0) as f64;
        }
    }
    Values { y, level, lag }
}

/// The mode of positive `values`: mean shift (repeatedly the mean within the relative
/// window) from the median and from every decile, the converged point whose window holds
/// the most values. Mean shift climbs to the nearest density peak (Fukunaga & Hostetler,
/// "The estimation of the gradient of a density function", 1975); from several starts the
/// largest peak wins. From the median alone it climbed to a peak of noise samples below the
/// threshold's when the median lay between them (a rotating natural image, OFF: 0.097 for
/// 0.35, half the samples rejected).
pub fn mode(values: &[f64], window: f64) -> Option<f64> {
    mode_of_sorted(&sorted_positive(values), window)
}

/// [`mode`] of values already positive, finite and in ascending order.
fn mode_of_sorted(sorted: &[f64], window: f64) -> Option<f64> {
    if sorted.len() < 10 {
        return None;
    }
    let within = |m: f64| -> usize {
        let a = sorted.partition_point(|&v| v < m * (1.0 - window));
        let b = sorted.partition_point(|&v| v <= m * (1.0 + window));
        b.saturating_sub(a)
    };
    let n = sorted.len();
    // the fifth decile is the median (`5 n / 10 == n / 2`), started from first
    let starts = std::iter::once(n / 2).chain(
        (1..10)
            .filter(|&decile| decile != 5)
            .map(|decile| (decile * n / 10).min(n - 1)),
    );
    let sums = PrefixSums::of(sorted);
    let mut best: Option<(f64, usize)> = None;
    for start in starts {
        let m = mean_shift(sorted, sorted[start], window, &sums);
        let held = within(m);
        if best.is_none_or(|(_, most)| held > most) {
            best = Some((m, held));
        }
    }
    best.map(|(m, _)| m)
}

/// The positive finite `values` in ascending order. Sorted by their bits: for positive floats
/// the bits order as the values do (and equal values are the same bits), so a radix sort of
/// the integers (`radsort`, least significant byte first, bytes all values share skipped)
/// gives the order a comparison sort would, in a few passes over the values instead of
/// `log n` (sorting was most of [`mode`] once its window sums were [`PrefixSums`]).
fn sorted_positive(values: &[f64]) -> Vec<f64> {
    let mut bits = Vec::with_capacity(values.len());
    for &v in values {
        push_if_positive(&mut bits, v);
    }
    sorted_from_bits(bits)
}

/// Adds the bits of `v` if it is positive and finite.
#[inline]
fn push_if_positive(bits: &mut Vec<u64>, v: f64) {
    if v > 0.0 && v.is_finite() {
        bits.push(v.to_bits());
    }
}

/// The values of positive finite `bits`, in ascending order.
fn sorted_from_bits(mut bits: Vec<u64>) -> Vec<f64> {
    radsort::sort(&mut bits);
    bits.into_iter().map(f64::from_bits).collect()
}

/// Exact running sums of positive values, so that the sum of any window `values[a..b]`
/// costs two lookups instead of `b - a` additions (a mean shift step summed up to half of
/// millions of samples; ten starts of up to 50 steps each made [`mode`] a third of a fit's
/// time on a recording of 3.9 M events). Each value is held as an integer multiple of
/// `2^-shift` (exact for every value within `2^(127 - 53 - log2 n)` of the largest), so a
/// window's sum is the exact sum rounded once: the same whatever the order or the windows
/// summed before, and at least as close as adding the window's values one by one.
struct PrefixSums {
    running: Vec<i128>,
    scale: [f64; 2],
}

impl PrefixSums {
    fn of(sorted: &[f64]) -> Self {
        let largest = sorted.last().copied().unwrap_or(1.0);
        // the running total stays below 2^126: n values of at most 2^(e + 1) each; the
        // shift (about -900 to 1200 over the finite floats) applied as two powers of two,
        // each finite, so that scaling stays exact at both ends of the range
        let shift = 126
            - (largest.log2().floor() as i32 + 1)
            - (sorted.len() as f64 + 1.0).log2().ceil() as i32;
        let up = powers_of_two(shift);
        let mut running = Vec::with_capacity(sorted.len() + 1);
        let mut total = 0i128;
        running.push(0);
        for &v in sorted {
            total += (v * up[0] * up[1]) as i128;
            running.push(total);
        }
        Self {
            running,
            scale: powers_of_two(-shift),
        }
    }

    /// The sum of `values[a..b]`.
    fn window(&self, a: usize, b: usize) -> f64 {
        (self.running[b] - self.running[a]) as f64 * self.scale[0] * self.scale[1]
    }
}

/// `2^e` as two factors whose product it is.
fn powers_of_two(e: i32) -> [f64; 2] {
    [2f64.powi(e / 2), 2f64.powi(e - e / 2)]
}

/// Mean shift over `sorted` values from `m`: the mean of the values within `m (1 +- window)`
/// until it stops moving (at most 50 steps).
fn mean_shift(sorted: &[f64], mut m: f64, window: f64, sums: &PrefixSums) -> f64 {
    for _ in 0..50 {
        let a = sorted.partition_point(|&v| v < m * (1.0 - window));
        let b = sorted.partition_point(|&v| v <= m * (1.0 + window));
        if b <= a {
            break;
        }
        let next = sums.window(a, b) / (b - a) as f64;
        let done = (next - m).abs() < 1e-7 * m;
        m = next;
        if done {
            break;
        }
    }
    m
}

/// Which pairs are kept: within the window around their polarity's mode. `None` when a
/// polarity has too few pairs for a mode.
pub fn kept(pairs: &[Pair], y: &[f64], window: f64) -> Option<Vec<bool>> {
    // each polarity's positive samples in one pass, `[OFF, ON]`
    let mut positive: [Vec<u64>; 2] = [Vec::new(), Vec::new()];
    for (p, &v) in pairs.iter().zip(y) {
        push_if_positive(&mut positive[p.on as usize], v);
    }
    let mut range = [(0.0, 0.0); 2];
    for on in [true, false] {
        let sorted = sorted_from_bits(std::mem::take(&mut positive[on as usize]));
        let m = mode_of_sorted(&sorted, window / 2.0)?;
        range[on as usize] = (m * (1.0 - window), m * (1.0 + 2.0 * window));
    }
    Some(
        pairs
            .iter()
            .zip(y)
            .map(|(p, &v)| {
                let (lo, hi) = range[p.on as usize];
                v >= lo && v <= hi
            })
            .collect(),
    )
}

/// Weights giving each pixel the same total: `1 / n` for its `n` kept pairs.
pub fn pixel_weights(pairs: &[Pair], keep: &[bool], pixels: usize) -> Vec<f64> {
    let mut n = vec![0u32; pixels];
    for (p, &k) in pairs.iter().zip(keep) {
        n[p.pixel as usize] += k as u32;
    }
    // one division a pixel rather than a pair (the same quotient)
    let share: Vec<f64> = n.iter().map(|&n| 1.0 / n.max(1) as f64).collect();
    pairs
        .iter()
        .zip(keep)
        .map(|(p, &k)| if k { share[p.pixel as usize] } else { 0.0 })
        .collect()
}

/// The weighted standard deviation of a polarity's pairs' distance from the frames
/// ([`Pair::interpolation`]) below which its trend is not fitted.
const MIN_INTERPOLATION_SPREAD: f64 = 0.05;

/// Weighted least squares of the model over the pairs with positive `weight`; `leak` adds
/// the drift columns. `None` when the system is singular.
pub fn fit(pairs: &[Pair], v: &Values, weight: &[f64], leak: bool) -> Option<Coefficients> {
    fit_columns(pairs, v, weight, leak, false)
}

/// [`fit`] of the pairs of one polarity (the other's weights 0): its threshold column and
/// trend are left out (coefficients 0) rather than making the fit fail.
pub fn fit_one_polarity(
    pairs: &[Pair],
    v: &Values,
    weight: &[f64],
    leak: bool,
) -> Option<Coefficients> {
    fit_columns(pairs, v, weight, leak, true)
}

fn fit_columns(
    pairs: &[Pair],
    v: &Values,
    weight: &[f64],
    leak: bool,
    one_polarity: bool,
) -> Option<Coefficients> {
    let wsum: f64 = weight.iter().sum();
    if wsum <= 0.0 {
        return None;
    }
    let mean_level = v.level.iter().zip(weight).map(|(l, w)| l * w).sum::<f64>() / wsum;
    let (sums, sums_y) = if leak {
        normal_sums::<8>(pairs, v, weight, mean_level)
    } else {
        normal_sums::<6>(pairs, v, weight, mean_level)
    };
    solve(&sums, &sums_y, leak, one_polarity)
}

/// The coefficients from the normal equations' sums `X^T W X` and `X^T W y` (the model's
/// columns, the level centred on its weighted mean; the first 8 columns with `leak`, else
/// 6): terms the pairs carry no information on are left out (coefficient 0). `None` when
/// the system is singular or a polarity without pairs is not `one_polarity`'s to leave out.
pub(super) fn solve(
    sums: &[[f64; 8]; 8],
    sums_y: &[f64; 8],
    leak: bool,
    one_polarity: bool,
) -> Option<Coefficients> {
    let k = if leak { 8 } else { 6 };
    let mut xtx = nalgebra::DMatrix::<f64>::from_fn(k, k, |a, b| sums[a][b]);
    let mut xty = nalgebra::DVector::<f64>::from_fn(k, |a, _| sums_y[a]);
    // a term the pairs carry no information on (no lag where every pair is a steady ramp,
    // no level spread, a polarity weighted out where that is asked for) is left out: its
    // coefficient 0; a polarity without pairs otherwise fails the fit
    let largest = (0..k).map(|a| xtx[(a, a)]).fold(0.0, f64::max);
    for a in 0..k {
        if xtx[(a, a)] <= 1e-12 * largest {
            if a < 2 && !one_polarity {
                return None;
            }
            for b in 0..k {
                xtx[(a, b)] = 0.0;
                xtx[(b, a)] = 0.0;
            }
            xtx[(a, a)] = 1.0;
            xty[a] = 0.0;
        }
    }
    // no trend to fit where the events' distance from the frames does not vary (a
    // simulator that stamps events at the frames' times): the interpolation terms left out
    for (a, pol) in [(4, 0), (5, 1)] {
        let spread = xtx[(a, a)] - xtx[(a, pol)].powi(2) / xtx[(pol, pol)].max(1e-300);
        if spread <= MIN_INTERPOLATION_SPREAD.powi(2) * xtx[(pol, pol)] {
            for b in 0..k {
                xtx[(a, b)] = 0.0;
                xtx[(b, a)] = 0.0;
            }
            xtx[(a, a)] = 1.0;
            xty[a] = 0.0;
        }
    }
    let beta = xtx.lu().solve(&xty)?;
    Some(Coefficients {
        c_on: beta[0],
        c_off: beta[1],
        level_slope: beta[2],
        lag: beta[3],
        interp_on: beta[4],
        interp_off: beta[5],
        drift: if leak { beta[6] } else { 0.0 },
        drift_per_dn: if leak { beta[7] } else { 0.0 },
    })
}

/// The sums of the normal equations over the pairs with positive `weight`, `X^T W X` and
/// `X^T W y`, for the first `K` columns of the model. Fixed-size arrays, summed pair by
/// pair in order (the same sums, to the bit, as any other layout summing in that order);
/// `K` a constant so that the inner loops unroll and vectorise (each element's sum keeps
/// its order, and `w row[a] row[b]` is evaluated as `(w row[a]) row[b]`).
fn normal_sums<const K: usize>(
    pairs: &[Pair],
    v: &Values,
    weight: &[f64],
    mean_level: f64,
) -> ([[f64; 8]; 8], [f64; 8]) {
    let mut xtx = [[0.0; 8]; 8];
    let mut xty = [0.0; 8];
    let n = pairs.len();
    let (weight, level, lag, y) = (&weight[..n], &v.level[..n], &v.lag[..n], &v.y[..n]);
    for (i, p) in pairs.iter().enumerate() {
        let w = weight[i];
        if w <= 0.0 {
            continue;
        }
        let row = columns(p, level[i] - mean_level, lag[i]);
        match (K == 8, p.on) {
            (true, true) => add_pair(&mut xtx, &mut xty, [0, 2, 3, 4, 6, 7], &row, w, y[i]),
            (true, false) => add_pair(&mut xtx, &mut xty, [1, 2, 3, 5, 6, 7], &row, w, y[i]),
            (false, true) => add_pair(&mut xtx, &mut xty, [0, 2, 3, 4], &row, w, y[i]),
            (false, false) => add_pair(&mut xtx, &mut xty, [1, 2, 3, 5], &row, w, y[i]),
        }
    }
    (xtx, xty)
}

/// One pair's terms of the normal equations' sums, over the columns `active` that can be
/// other than zero for its polarity (an ON pair's OFF and OFF-interpolation columns are 0,
/// and so are their products): the other sums would only gain zeros, so every sum is the
/// one the full `K x K` loop makes, in the same order, at 36 products a pair instead of 64
/// (16 instead of 36 without the leak's columns).
#[inline(always)]
fn add_pair<const N: usize>(
    xtx: &mut [[f64; 8]; 8],
    xty: &mut [f64; 8],
    active: [usize; N],
    row: &[f64; 8],
    w: f64,
    y: f64,
) {
    for a in active {
        let weighted = w * row[a];
        xty[a] += weighted * y;
        for b in active {
            xtx[a][b] += weighted * row[b];
        }
    }
}

/// The model's columns of pair `p` with its level (centred or not) and lag covariate:
/// ON, OFF, level, lag, ON and OFF distance from the frames, and the leak's drift and its
/// growth with DN (signed `+1` OFF, `-1` ON, as the samples are).
#[inline]
pub(super) fn columns(p: &Pair, level: f64, lag: f64) -> [f64; 8] {
    let s = if p.on { -1.0 } else { 1.0 };
    let dt = p.dt as f64;
    let dn = 0.5 * (p.dn0 + p.dn1) as f64;
    let (on, off) = (p.on as u8 as f64, (!p.on) as u8 as f64);
    let interp = p.interpolation();
    [
        on,
        off,
        level,
        lag,
        on * interp,
        off * interp,
        s * dt,
        s * dt * dn,
    ]
}

/// The whole fit at offset `b`: values, kept pairs, weights and coefficients.
pub fn fit_at(
    pairs: &[Pair],
    log: &LogMap,
    b: f32,
    window: f64,
    pixels: usize,
    leak: bool,
) -> Option<(Coefficients, Values, Vec<f64>)> {
    let v = values(pairs, log, b);
    let keep = kept(pairs, &v.y, window)?;
    let w = pixel_weights(pairs, &keep, pixels);
    let c = fit(pairs, &v, &w, leak)?;
    Some((c, v, w))
}

/// Resamples pixels with replacement: the weight of each pair multiplied by how often its
/// pixel was drawn.
pub fn resampled_weights(pairs: &[Pair], weight: &[f64], pixels: usize, seed: u64) -> Vec<f64> {
    let present: Vec<u32> = {
        let mut seen = vec![false; pixels];
        for (p, &w) in pairs.iter().zip(weight) {
            if w > 0.0 {
                seen[p.pixel as usize] = true;
            }
        }
        (0..pixels as u32).filter(|&p| seen[p as usize]).collect()
    };
    let times = draw_counts(&present, pixels, seed);
    pairs
        .iter()
        .zip(weight)
        .map(|(p, &w)| w * times[p.pixel as usize] as f64)
        .collect()
}

/// One bootstrap draw over `units` (indices below `len`, each a pixel or a pixel's slot):
/// as many draws with replacement as there are units, from `seed`; how often each index
/// was drawn. The one draw both the pair-by-pair and the moments bootstrap make
/// ([`super::moments`]), so that they draw the same pixels.
pub(super) fn draw_counts(units: &[u32], len: usize, seed: u64) -> Vec<u32> {
    let mut times = vec![0u32; len];
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
    for _ in 0..units.len() {
        times[units[rng.random_range(0..units.len())] as usize] += 1;
    }
    times
}

/// A function of the offset, each offset evaluated once. The bisections over the offset
/// ([`offset_root`], [`offset_interval`]) halve an `f32` interval 30-40 times, and after
/// about 24 halvings it is a few ULPs wide, so that they try offsets tried before; the
/// interval's search also starts at the root search's ends. The fits are deterministic, so
/// a remembered value is the value. Threads asking for an offset being evaluated wait for
/// it rather than evaluating it again.
pub struct Memo<T, F> {
    f: F,
    seen: std::sync::Mutex<std::collections::HashMap<u32, std::sync::Arc<std::sync::OnceLock<T>>>>,
}

impl<T: Clone, F: Fn(f32) -> T> Memo<T, F> {
    pub fn new(f: F) -> Self {
        Self {
            f,
            seen: Default::default(),
        }
    }

    /// `f(b)`, evaluated at the first call with `b` (by its bits).
    pub fn at(&self, b: f32) -> T {
        let cell = {
            let mut seen = self.seen.lock().expect("no evaluation panicked");
            std::sync::Arc::clone(seen.entry(b.to_bits()).or_default())
        };
        cell.get_or_init(|| (self.f)(b)).clone()
    }
}

/// The offset's interval: where the level slope is within `z` of its standard error of
/// zero, by bisection on each side of `centre` within `[lo, hi]` (the two sides at once);
/// a side that reaches its bound is `None` (the data do not bound the offset there).
pub fn offset_interval(
    slope: &(dyn Fn(f32) -> Option<f64> + Sync),
    centre: f32,
    bound: f64,
    (lo, hi): (f32, f32),
) -> [Option<f32>; 2] {
    let side = |limit: f32| -> Option<f32> {
        let outside = |b: f32| slope(b).is_none_or(|s| s.abs() > bound);
        if !outside(limit) {
            return None;
        }
        let (mut inside, mut out) = (centre, limit);
        for _ in 0..30 {
            let mid = 0.5 * (inside + out);
            if outside(mid) {
                out = mid;
            } else {
                inside = mid;
            }
        }
        Some(0.5 * (inside + out))
    };
    let (below, above) = rayon::join(|| side(lo), || side(hi));
    [below, above]
}

/// The offset where the level slope crosses zero, by bisection within `[lo, hi]` (the
/// slope rises with the offset: too small an offset exaggerates dark changes, so the
/// thresholds fall with the level, too large one compresses them).
pub fn offset_root(slope: &dyn Fn(f32) -> Option<f64>, (lo, hi): (f32, f32)) -> Option<f32> {
    let (s_lo, s_hi) = (slope(lo)?, slope(hi)?);
    if !(s_lo < 0.0 && s_hi > 0.0) {
        return None;
    }
    let (mut a, mut b) = (lo, hi);
    for _ in 0..40 {
        let mid = 0.5 * (a + b);
        if slope(mid)? < 0.0 {
            a = mid;
        } else {
            b = mid;
        }
    }
    Some(0.5 * (a + b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::LogResponse;

    #[test]
    fn window_sums_are_the_exact_sums_rounded_once() {
        // 0.1 ten times: added one by one 0.9999999999999999, exactly 1 rounded once
        let tenths = sorted_positive(&[0.1; 10]);
        assert_eq!(tenths.iter().sum::<f64>(), 0.9999999999999999);
        assert_eq!(PrefixSums::of(&tenths).window(0, 10), 1.0);
        // values twelve decades apart keep the small one's share, and any window's sum
        let spread = sorted_positive(&[1e3, 1e-9, -2.0, f64::NAN, 1.0, f64::INFINITY, 0.0]);
        assert_eq!(spread, vec![1e-9, 1.0, 1e3]);
        let sums = PrefixSums::of(&spread);
        assert_eq!(sums.window(0, 3), 1001.000000001);
        assert_eq!(sums.window(1, 3), 1001.0);
        assert_eq!(sums.window(0, 1), 1e-9);
        assert_eq!(sums.window(2, 2), 0.0);
    }

    #[test]
    fn the_mode_of_values_near_the_ends_of_the_floats_is_found() {
        // twenty values 0.1 % apart at 1e-305 and at 1e300 (a shift beyond 1000 binary
        // places either way): the mode is their mean, not a sum lost to the scaling
        for scale in [1e-305, 1e300] {
            let values: Vec<f64> = (0..20).map(|k| scale * (1.0 + 0.001 * k as f64)).collect();
            let m = mode(&values, 0.25).expect("twenty values");
            assert!((m / scale - 1.0095).abs() < 1e-9, "{m:e}");
        }
    }

    #[test]
    fn the_kept_pairs_are_those_near_each_polarity_s_mode() {
        // ON samples at 0.3 (eleven) and one far out; OFF at 0.4 (ten), one far, one negative
        let mut pairs = Vec::new();
        let mut y = Vec::new();
        for k in 0..11 {
            pairs.push(pair_at(k, true));
            y.push(0.3 + 0.001 * k as f64);
        }
        pairs.push(pair_at(11, true));
        y.push(0.9);
        for k in 0..10 {
            pairs.push(pair_at(20 + k, false));
            y.push(0.4 - 0.001 * k as f64);
        }
        pairs.push(pair_at(30, false));
        y.push(0.05);
        pairs.push(pair_at(31, false));
        y.push(-0.4);
        let keep = kept(&pairs, &y, 0.25).expect("both polarities have a mode");
        let kept_y: Vec<f64> = y
            .iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(v, _)| *v)
            .collect();
        assert_eq!(kept_y.len(), 21);
        assert!(
            kept_y.iter().all(|v| (0.29..=0.41).contains(v)),
            "{kept_y:?}"
        );
        // one polarity with under ten positive samples has no mode
        assert!(kept(&pairs[..12], &y[..12], 0.25).is_none());
    }

    fn pair_at(pixel: u32, on: bool) -> Pair {
        Pair {
            pixel,
            on,
            dn0: 50.0,
            dn1: 60.0,
            dt: 0.01,
            around: [50.0; 4],
            block: 0,
            interp: [0.0; 2],
        }
    }

    /// Pairs of an ideal pixel with thresholds 0.3 / 0.4 seen through `ln(DN + 25)`: each
    /// pair's DN change is one threshold in that response, at levels from 5 to 200 DN.
    fn pairs(drift: f64) -> Vec<Pair> {
        pairs_with(drift, 0.0)
    }

    /// As [`pairs`], with frames whose interpolation misses `loss` of the change midway
    /// between frames: a pair's change is `(1 - loss w)` of the threshold, `w` its
    /// distance from the frames ([`Pair::interpolation`]).
    fn pairs_with(drift: f64, loss: f64) -> Vec<Pair> {
        let mut out = Vec::new();
        for k in 0..4000u32 {
            let level = 5.0 + (k % 196) as f64;
            let on = k % 3 != 0;
            let dt = 0.02 + 0.001 * (k % 50) as f64;
            // events anywhere between frames
            let interp = [(k % 7) as f32 / 7.0, (k % 5) as f32 / 5.0];
            let w = 0.5 * (interp[0] + interp[1]) as f64;
            // the change the frames show: the threshold, less (ON) or more (OFF) the drift
            let c = if on {
                0.3 - drift * dt
            } else {
                0.4 + drift * dt
            } * (1.0 - loss * w);
            let (a, b) = if on {
                (level, (level + 25.0) * c.exp() - 25.0)
            } else {
                (level, (level + 25.0) * (-c).exp() - 25.0)
            };
            out.push(Pair {
                pixel: k % 1000,
                on,
                dn0: a as f32,
                dn1: b as f32,
                dt: dt as f32,
                // a steady ramp through both events: no lag
                around: [a as f32, a as f32, b as f32, b as f32],
                block: 0,
                interp,
            });
        }
        out
    }

    /// The values taken a block of logs at a time are those taken pair by pair, to the bit,
    /// with and without AVX2, for both responses, across a partial last block and around
    /// the lin-log knee.
    #[test]
    fn values_are_the_pair_by_pair_values() {
        let mut pairs = pairs(0.0);
        pairs.truncate(3 * LOG_BLOCK + 17);
        for (k, p) in pairs.iter_mut().enumerate() {
            p.around = [
                p.dn0 * 0.97,
                p.dn0 * 1.02,
                p.dn1 + 0.3 * (k % 3) as f32,
                p.dn1 * 1.01,
            ];
        }
        for kind in [LogResponse::V2e, LogResponse::Eps] {
            let log = LogMap::new(kind, 0.001);
            for b in [0.0f32, 7.5, -3.25] {
                let l = |dn: f32| log.apply(dn + b) as f64;
                let span = f64::from(super::super::samples::RATE_SPAN_S);
                let expected: Vec<[u64; 3]> = pairs
                    .iter()
                    .map(|p| {
                        let sign = if p.on { 1.0 } else { -1.0 };
                        let mid = 0.5 * (p.dn0 + p.dn1);
                        let r0 = (l(p.around[1]) - l(p.around[0])) / span;
                        let r1 = (l(p.around[3]) - l(p.around[2])) / span;
                        let lag = sign * (r1 - r0) / (mid + b).max(1.0) as f64;
                        [sample(p, &log, b), l(mid), lag].map(f64::to_bits)
                    })
                    .collect();
                let bits = |v: Values| -> Vec<[u64; 3]> {
                    (0..v.y.len())
                        .map(|i| [v.y[i], v.level[i], v.lag[i]].map(f64::to_bits))
                        .collect()
                };
                assert_eq!(bits(values(&pairs, &log, b)), expected);
                assert_eq!(bits(values_portable(&pairs, &log, b)), expected);
            }
        }
    }

    #[test]
    fn thresholds_are_read_at_the_frames_where_interpolation_loses_change() {
        let log = LogMap::new(LogResponse::V2e, 0.001);
        // midway between frames the interpolation shows 80 % of the change
        let pairs = pairs_with(0.0, 0.2);
        let (c, _, _) = fit_at(&pairs, &log, 25.0, 0.5, 1000, false).unwrap();
        assert!(
            (c.c_on - 0.3).abs() < 2e-3 && (c.c_off - 0.4).abs() < 2e-3,
            "{c:?}"
        );
        assert!(
            (c.interp_on + 0.06).abs() < 2e-3 && (c.interp_off + 0.08).abs() < 2e-3,
            "{c:?}"
        );
        // the plain mean of the samples is 0.2 x the mean distance (0.43) low
        let mean_on: f64 = pairs
            .iter()
            .filter(|p| p.on)
            .map(|p| 0.3 * (1.0 - 0.2 * p.interpolation()))
            .sum::<f64>()
            / pairs.iter().filter(|p| p.on).count() as f64;
        assert!(mean_on < 0.276, "{mean_on}");
    }

    #[test]
    fn events_at_one_distance_from_the_frames_fit_no_trend() {
        let log = LogMap::new(LogResponse::V2e, 0.001);
        let mut pairs = pairs(0.0);
        for p in &mut pairs {
            p.interp = [0.5, 0.5];
        }
        let (c, _, _) = fit_at(&pairs, &log, 25.0, 0.5, 1000, false).unwrap();
        assert_eq!((c.interp_on, c.interp_off), (0.0, 0.0));
        assert!((c.c_on - 0.3).abs() < 2e-3, "{c:?}");
    }

    #[test]
    fn one_polarity_alone_gives_its_own_offset() {
        let log = LogMap::new(LogResponse::V2e, 0.001);
        // ON pairs made through ln(DN + 25), OFF pairs through ln(DN + 5) (above the
        // response's linear part, 20 DN, at every offset near 5)
        let mut pairs = pairs(0.0);
        for (k, p) in pairs.iter_mut().enumerate() {
            if !p.on {
                let level = 40.0 + (k % 160) as f64;
                p.dn0 = level as f32;
                p.dn1 = ((level + 5.0) * (-0.4f64).exp() - 5.0) as f32;
                p.around = [p.dn0, p.dn0, p.dn1, p.dn1];
            }
        }
        let root = |on: bool| {
            let slope = |b: f32| {
                let (_, v, w) = fit_at(&pairs, &log, b, 0.5, 1000, false)?;
                let own: Vec<f64> = pairs
                    .iter()
                    .zip(&w)
                    .map(|(p, &w)| if p.on == on { w } else { 0.0 })
                    .collect();
                fit_one_polarity(&pairs, &v, &own, false).map(|c| c.level_slope)
            };
            offset_root(&slope, (0.0, 255.0)).unwrap()
        };
        let (on, off) = (root(true), root(false));
        assert!((on - 25.0).abs() < 1.0, "{on}");
        assert!((off - 5.0).abs() < 1.0, "{off}");
    }

    #[test]
    fn the_offset_is_where_thresholds_stop_depending_on_brightness() {
        let log = LogMap::new(LogResponse::V2e, 0.001);
        let pairs = pairs(0.0);
        let slope = |b: f32| fit_at(&pairs, &log, b, 0.5, 1000, false).map(|f| f.0.level_slope);
        // without the offset the dark changes are too large: thresholds fall with the level
        assert!(slope(0.0).unwrap() < -0.01, "{:?}", slope(0.0));
        assert!(slope(100.0).unwrap() > 0.01, "{:?}", slope(100.0));
        let b = offset_root(&slope, (0.0, 255.0)).unwrap();
        assert!((b - 25.0).abs() < 0.5, "{b}");
        let (c, _, _) = fit_at(&pairs, &log, b, 0.5, 1000, false).unwrap();
        assert!(
            (c.c_on - 0.3).abs() < 2e-3 && (c.c_off - 0.4).abs() < 2e-3,
            "{c:?}"
        );
    }

    #[test]
    fn leak_drift_is_taken_out_of_the_thresholds() {
        let log = LogMap::new(LogResponse::V2e, 0.001);
        let pairs = pairs(1.5);
        let (c, _, _) = fit_at(&pairs, &log, 25.0, 0.5, 1000, true).unwrap();
        assert!(
            (c.c_on - 0.3).abs() < 2e-3 && (c.c_off - 0.4).abs() < 2e-3,
            "{c:?}"
        );
        // the drift at the pairs' middle level (the two drift terms trade off across it)
        let at_100 = c.drift + 100.0 * c.drift_per_dn;
        assert!(
            (at_100 - 1.5).abs() < 0.02 && c.drift_per_dn.abs() < 1e-3,
            "{c:?}"
        );
        // without the drift term the thresholds split apart
        let (plain, _, _) = fit_at(&pairs, &log, 25.0, 0.5, 1000, false).unwrap();
        assert!(plain.c_on < 0.27 && plain.c_off > 0.43, "{plain:?}");
    }
}
