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
}

/// Per-pixel (sum, count, sum of squares) of the corrected kept samples of one polarity,
/// with every pixel drawn `weight * n` times (1 when the weights are the fit's own), and the
/// pixel of each entry.
pub type PixelSums = (Vec<(f64, u32, f64)>, Vec<usize>);

/// The per-pixel sums of the pairs of polarity `on` with positive `weight` (`None` with
/// fewer than 10 entries).
pub fn pixel_sums(
    pairs: &[Pair],
    slots: &PixelSlots,
    values: &Values,
    weight: &[f64],
    c: &Coefficients,
    on: bool,
) -> Option<PixelSums> {
    let [off_sums, on_sums] = slot_sums(pairs, slots, values, weight, c, [!on, on]);
    expand(slots, if on { &on_sums } else { &off_sums })
}

/// [`pixel_sums`] of both polarities, `[OFF, ON]`, in one pass over the pairs (each
/// polarity's sums the same, to the bit, as its own pass: every slot sums in pair order).
pub fn pixel_sums_both(
    pairs: &[Pair],
    slots: &PixelSlots,
    values: &Values,
    weight: &[f64],
    c: &Coefficients,
) -> [Option<PixelSums>; 2] {
    slot_sums(pairs, slots, values, weight, c, [true, true]).map(|sums| expand(slots, &sums))
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

/// The slots' sums in pixel order, each pixel repeated as often as it was drawn (`None`
/// with fewer than 10 entries).
fn expand(slots: &PixelSlots, by_slot: &SlotSums) -> Option<PixelSums> {
    let mut sums = Vec::new();
    let mut which = Vec::new();
    for (&pixel, &(s, n, sq, w)) in slots.pixels.iter().zip(by_slot) {
        if n == 0 {
            continue;
        }
        // a pixel drawn m times weighs m (its pairs' weights sum to m)
        for _ in 0..(w.round() as usize).max(1) {
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
            span: 0.002,
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
        weight[0] = 2.0; // pixel 7 drawn twice
        let (sums, which) = pixel_sums(&pairs, &slots, &values, &weight, &c, true).unwrap();
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
        // both polarities in one pass are each polarity's own (6 OFF pairs: too few)
        let [off, on] = pixel_sums_both(&pairs, &slots, &values, &weight, &c);
        assert!(off.is_none());
        assert_eq!(on.unwrap(), (sums, which));
        let more: Vec<Pair> = pairs.iter().chain(&pairs).copied().collect();
        let slots = PixelSlots::new(&more);
        let values = Values {
            y: (0..more.len()).map(|k| 0.07 * k as f64).collect(),
            level: vec![0.0; more.len()],
            lag: vec![0.0; more.len()],
        };
        let weight = vec![1.0; more.len()];
        let [off, on] = pixel_sums_both(&more, &slots, &values, &weight, &c);
        assert_eq!(off, pixel_sums(&more, &slots, &values, &weight, &c, false));
        assert!(off.is_some());
        assert_eq!(on, pixel_sums(&more, &slots, &values, &weight, &c, true));
    }
}
