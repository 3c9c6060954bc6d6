//! Per-pixel sums of the corrected threshold samples, the basis of the threshold maps and of
//! the frozen mismatch `sigma` (and of every bootstrap draw of it).
//!
//! The pixels that hold pairs are numbered once per pair set ([`PixelSlots`]), in
//! ascending pixel order, so that each sum is a dense array indexed by slot: no map per
//! call, and the sums come out in pixel order with each pixel's samples added in pair order.

use super::model::{Coefficients, Values};
use super::samples::Pair;

/// The pixels that hold pairs, in ascending order, and each pair's slot among them.
pub struct PixelSlots {
    pixels: Vec<u32>,
    slot: Vec<u32>,
}

impl PixelSlots {
    pub fn new(pairs: &[Pair]) -> Self {
        let mut pixels: Vec<u32> = pairs.iter().map(|p| p.pixel).collect();
        pixels.sort_unstable();
        pixels.dedup();
        let slot = pairs
            .iter()
            .map(|p| pixels.binary_search(&p.pixel).expect("a pair's pixel") as u32)
            .collect();
        Self { pixels, slot }
    }

    /// How many pixels hold pairs.
    pub fn len(&self) -> usize {
        self.pixels.len()
    }

    /// Whether no pixel holds a pair.
    pub fn is_empty(&self) -> bool {
        self.pixels.is_empty()
    }

    /// The slot of pair `i`.
    pub fn slot_of(&self, i: usize) -> usize {
        self.slot[i] as usize
    }
}

/// Per-pixel (sum, count, sum of squares) of the corrected kept samples of one polarity,
/// each pixel once or as often as a bootstrap drew it, and the pixel of each entry.
pub type PixelSums = (Vec<(f64, u32, f64)>, Vec<usize>);

/// The per-pixel sums of the pairs of polarity `on` with positive `weight` (the fit's own
/// weights: each pixel once; `None` with fewer than 10 entries).
pub fn pixel_sums(
    pairs: &[Pair],
    slots: &PixelSlots,
    values: &Values,
    weight: &[f64],
    c: &Coefficients,
    on: bool,
) -> Option<PixelSums> {
    let [off_sums, on_sums] = slot_sums(pairs, slots, values, weight, c, [!on, on]);
    expand(slots, if on { &on_sums } else { &off_sums }, |_| 1)
}

/// [`pixel_sums`] of both polarities, `[OFF, ON]`, in one pass over the pairs, with
/// `weight` a bootstrap draw's ([`super::model::resampled_weights`]): each pixel repeated as
/// often as it was drawn, the weights of its pairs of both polarities summed (the fit gives
/// each pixel's pairs `1 / n`, so they sum to the draw count; one polarity's alone sum to a
/// fraction of it).
pub fn pixel_sums_both(
    pairs: &[Pair],
    slots: &PixelSlots,
    values: &Values,
    weight: &[f64],
    c: &Coefficients,
) -> [Option<PixelSums>; 2] {
    let sums = slot_sums(pairs, slots, values, weight, c, [true, true]);
    let drawn = |slot: usize| (sums[0][slot].3 + sums[1][slot].3).round() as usize;
    [0, 1].map(|k| expand(slots, &sums[k], drawn))
}

/// Per slot: the sum, count, sum of squares and weight of the corrected samples.
type SlotSums = Vec<(f64, u32, f64, f64)>;

/// The [`SlotSums`] of the samples with positive weight, `[OFF, ON]`; a polarity not
/// `wanted` is left empty.
fn slot_sums(
    pairs: &[Pair],
    slots: &PixelSlots,
    values: &Values,
    weight: &[f64],
    c: &Coefficients,
    wanted: [bool; 2],
) -> [SlotSums; 2] {
    let empty = |want: bool| {
        vec![(0.0f64, 0u32, 0.0f64, 0.0f64); if want { slots.pixels.len() } else { 0 }]
    };
    let mut by_slot = [empty(wanted[0]), empty(wanted[1])];
    for (i, p) in pairs.iter().enumerate() {
        if !wanted[p.on as usize] || weight[i] <= 0.0 {
            continue;
        }
        let v = c.corrected(p, values, i);
        let e = &mut by_slot[p.on as usize][slots.slot[i] as usize];
        e.0 += v;
        e.1 += 1;
        e.2 += v * v;
        e.3 += weight[i];
    }
    by_slot
}

/// The slots' sums in pixel order, each pixel `repeats(slot)` times, at least once
/// (`None` with fewer than 10 entries).
fn expand(
    slots: &PixelSlots,
    by_slot: &SlotSums,
    repeats: impl Fn(usize) -> usize,
) -> Option<PixelSums> {
    let mut sums = Vec::new();
    let mut which = Vec::new();
    for (slot, (&pixel, &(s, n, sq, _))) in slots.pixels.iter().zip(by_slot).enumerate() {
        if n == 0 {
            continue;
        }
        for _ in 0..repeats(slot).max(1) {
            sums.push((s, n, sq));
            which.push(pixel as usize);
        }
    }
    (sums.len() >= 10).then_some((sums, which))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pair(pixel: u32, on: bool, dn1: f32) -> Pair {
        Pair {
            pixel,
            on,
            dn0: 100.0,
            dn1,
            dt: 0.01,
            around: [100.0, 100.0, dn1, dn1],
            block: 0,
            interp: [0.0; 2],
        }
    }

    #[test]
    fn sums_come_in_pixel_order_and_repeat_as_often_as_drawn() {
        // pixels visited out of order, every fourth pair OFF
        let pairs: Vec<Pair> = (0..24)
            .map(|k| {
                pair(
                    [7, 3, 40, 12][k % 4] + (k as u32 / 4) * 100,
                    k % 4 != 1,
                    130.0,
                )
            })
            .collect();
        let slots = PixelSlots::new(&pairs);
        let values = Values {
            y: (0..pairs.len()).map(|k| 0.1 * k as f64).collect(),
            level: vec![0.0; pairs.len()],
            lag: vec![0.0; pairs.len()],
        };
        let c = Coefficients {
            c_on: 0.3,
            c_off: 0.3,
            drift: 0.0,
            interp_on: 0.0,
            interp_off: 0.0,
            drift_per_dn: 0.0,
            level_slope: 0.0,
            lag: 0.0,
        };
        let mut weight = vec![1.0; pairs.len()];
        weight[0] = 2.0; // pixel 7 drawn twice (its only pair)
        let (sums, which) = pixel_sums_both(&pairs, &slots, &values, &weight, &c)[1]
            .clone()
            .unwrap();
        let mut expected: Vec<usize> = (0..24)
            .filter(|k| k % 4 != 1)
            .map(|k: usize| [7, 3, 40, 12][k % 4] + (k / 4) * 100)
            .collect();
        expected.sort_unstable();
        expected.insert(0, 7);
        assert_eq!(which, expected);
        assert_eq!(sums[0], sums[1]);
        assert!((sums[0].0 - 0.0).abs() < 1e-12 && sums[0].1 == 1);
        assert!(pixel_sums(&pairs[..8], &slots, &values, &weight, &c, false).is_none());
        // the fit's own weights: each pixel once (6 OFF pairs: too few)
        let once = pixel_sums(&pairs, &slots, &values, &weight, &c, true).unwrap();
        assert_eq!(once.1, expected[1..]);
        assert!(pixel_sums_both(&pairs, &slots, &values, &weight, &c)[0].is_none());
        let more: Vec<Pair> = pairs.iter().chain(&pairs).copied().collect();
        let slots = PixelSlots::new(&more);
        let values = Values {
            y: (0..more.len()).map(|k| 0.07 * k as f64).collect(),
            level: vec![0.0; more.len()],
            lag: vec![0.0; more.len()],
        };
        // two pairs a pixel, weighed 1/2 each as the fit weighs them: drawn once
        let weight = vec![0.5; more.len()];
        let [off, on] = pixel_sums_both(&more, &slots, &values, &weight, &c);
        assert_eq!(off, pixel_sums(&more, &slots, &values, &weight, &c, false));
        assert!(on.is_some());
        assert_eq!(on, pixel_sums(&more, &slots, &values, &weight, &c, true));
    }
}
