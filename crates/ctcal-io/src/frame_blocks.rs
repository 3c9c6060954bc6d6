//! Blocks of consecutive frames that stand for a recording with more frames than the
//! estimators take.
//!
//! The frame-based estimators interpolate between neighbouring frames along the optical
//! flow, which holds for frames a few pixels of motion apart. Thinning a long recording to
//! every k-th frame moves its frames apart until the flow no longer holds (a 60 s recording
//! at 25 Hz thinned to 120 frames would be re-simulated from frames 0.5 s apart). A window
//! is thinned evenly only while its frames stay at most [`MAX_SPACING_US`] apart (a 500 Hz
//! recording of a second to every 5th frame); beyond, it is measured on a few blocks of
//! consecutive frames (thinned to that spacing at most), one in each equal part
//! of the recording (so that slow changes of brightness or scene over the recording are
//! sampled), each placed where its part holds the most events (events are the
//! information a threshold estimate rests on). An interval's events count up to the 75th
//! percentile of the counts of the intervals that hold any, so that a burst of
//! fast motion, whose frames the flow may not follow, does not choose a block by itself;
//! windows equal under that cap are told apart by their whole counts. Only the chosen
//! blocks' frames and events are kept: memory is bounded by the blocks, not the recording
//! (the events between are decoded, counted and dropped).

/// The farthest apart thinning puts frames, µs: 40 ms, the 25 Hz APS rate of the DAVIS240C
/// and DAVIS346 recordings (IJRR, MVSEC) on which the frame-based methods are checked, whose
/// flow interpolation holds at their usual motion. A window whose frames, thinned to the
/// frame limit, stay at most this far apart is thinned evenly (all of it is measured);
/// otherwise it is measured on blocks of frames at most this far apart.
pub const MAX_SPACING_US: i64 = 40_000;

/// Pixels of the largest sensor a frame limit counts whole frames for: the DAVIS346 (346 x
/// 260), the largest APS sensor the frame methods are checked on. The frame methods' time
/// and memory grow with frames x pixels (prepared frames, a flow field per interval, the
/// upsampled runs), and a larger sensor gives more samples per frame, so a larger sensor
/// takes proportionally fewer frames (a 1280 x 720 sensor 1 / 10.2 of them).
pub const LIMIT_PIXELS: usize = 346 * 260;

/// The fewest frames a larger sensor's limit comes down to (two blocks of
/// [`BLOCK_FRAMES`]), or the limit itself where it is smaller.
pub const MIN_SCALED_FRAMES: usize = 2 * BLOCK_FRAMES;

/// The frame limit for frames of `pixels` pixels: `max_frames` up to [`LIMIT_PIXELS`],
/// proportionally fewer above (the same frame pixels), at least [`MIN_SCALED_FRAMES`].
pub fn scaled_limit(max_frames: usize, pixels: usize) -> usize {
    if pixels <= LIMIT_PIXELS {
        return max_frames;
    }
    let scaled = (max_frames as u128 * LIMIT_PIXELS as u128 / pixels as u128) as usize;
    scaled.max(MIN_SCALED_FRAMES.min(max_frames)).max(2)
}

/// How a window's frames are brought to the frame limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Plan {
    /// Every frame.
    All,
    /// Every `k`-th frame over the whole window.
    Stride(usize),
    /// Blocks of every `step`-th frame ([`choose`] on the thinned frames).
    Blocks { step: usize },
}

/// The plan for frames at `times` (sorted) and at most `max_frames` of them.
pub fn plan(times: &[i64], max_frames: usize) -> Plan {
    let stride = times.len().div_ceil(max_frames.max(2)).max(1);
    if stride == 1 {
        return Plan::All;
    }
    let mut gaps: Vec<i64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    gaps.sort_unstable();
    let spacing = gaps.get(gaps.len() / 2).copied().unwrap_or(0).max(1);
    let step = ((MAX_SPACING_US / spacing) as usize).max(1);
    if stride <= step {
        Plan::Stride(stride)
    } else {
        Plan::Blocks { step }
    }
}

/// The event counts between every `step`-th frame, from those between neighbours.
pub fn thinned_counts(counts: &[u64], step: usize) -> Vec<u64> {
    let frames = (counts.len() + 1).div_ceil(step);
    (0..frames.saturating_sub(1))
        .map(|k| counts[k * step..(k + 1) * step].iter().sum())
        .collect()
}

/// Frames per block the choice aims at (the fit splits a recording into fit, selection and
/// test blocks of several intervals each, so that a block must hold a few of them).
pub const BLOCK_FRAMES: usize = 20;

/// Blocks of consecutive frames as index ranges `first..=last` into the frames, in time
/// order. `counts[k]` is the number of events between frames `k` and `k + 1` (one fewer
/// than the frames). At most `max_frames` frames in all, in `max_frames / BLOCK_FRAMES`
/// blocks (at least one); all frames in one block when they fit.
pub fn choose(counts: &[u64], max_frames: usize) -> Vec<(usize, usize)> {
    let frames = counts.len() + 1;
    let max_frames = max_frames.max(2);
    if frames <= max_frames {
        return vec![(0, frames - 1)];
    }
    let blocks = (max_frames / BLOCK_FRAMES).max(1);
    let length = max_frames / blocks;
    let cap = burst_cap(counts);
    let scores: Vec<(u64, u64)> = counts.iter().map(|&c| (c.min(cap), c)).collect();
    (0..blocks)
        .map(|j| {
            let (lo, hi) = (j * frames / blocks, (j + 1) * frames / blocks);
            let first = best_window(&scores[lo..hi - 1], length - 1) + lo;
            (first, first + length - 1)
        })
        .collect()
}

/// The count an interval contributes at most: the 75th percentile of the intervals that
/// hold events (0 when none does).
pub fn burst_cap(counts: &[u64]) -> u64 {
    let mut active: Vec<u64> = counts.iter().copied().filter(|&c| c > 0).collect();
    active.sort_unstable();
    active
        .get(active.len().saturating_sub(1) * 3 / 4)
        .copied()
        .unwrap_or(0)
}

/// The start of the run of `width` values with the largest sum of capped counts, then of
/// whole counts (the earliest of equals); `values` holds at least `width >= 1`.
fn best_window(values: &[(u64, u64)], width: usize) -> usize {
    let add = |a: (u64, u64), b: (u64, u64)| (a.0 + b.0, a.1 + b.1);
    let mut sum = values[..width].iter().fold((0, 0), |s, &v| add(s, v));
    let (mut best, mut best_sum) = (0, sum);
    for start in 1..=values.len() - width {
        let (enter, leave) = (values[start + width - 1], values[start - 1]);
        sum = (sum.0 + enter.0 - leave.0, sum.1 + enter.1 - leave.1);
        if sum > best_sum {
            (best, best_sum) = (start, sum);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_larger_sensor_takes_fewer_frames_of_the_same_pixels() {
        assert_eq!(scaled_limit(120, 240 * 180), 120);
        assert_eq!(scaled_limit(120, 346 * 260), 120);
        // 1280 x 720: 120 x 89,960 / 921,600 = 11.7, raised to two blocks
        assert_eq!(scaled_limit(120, 1280 * 720), 40);
        // 640 x 480: 120 x 89,960 / 307,200 = 35.1
        assert_eq!(scaled_limit(120, 640 * 480), 40);
        assert_eq!(scaled_limit(1000, 1280 * 720), 97);
        assert_eq!(scaled_limit(10, 1280 * 720), 10);
    }

    #[test]
    fn frames_close_enough_are_thinned_evenly_and_far_ones_in_blocks() {
        let at = |n: usize, dt: i64| (0..n as i64).map(|k| k * dt).collect::<Vec<_>>();
        assert_eq!(plan(&at(100, 40_000), 120), Plan::All);
        // 500 Hz for 1 s: every 5th frame is 10 ms apart, within 40 ms
        assert_eq!(plan(&at(501, 2_000), 120), Plan::Stride(5));
        // 25 Hz for 64 s: every 14th frame would be 560 ms apart
        assert_eq!(plan(&at(1600, 40_000), 120), Plan::Blocks { step: 1 });
        // 200 Hz for 60 s: blocks of every 8th frame (40 ms)
        assert_eq!(plan(&at(12_000, 5_000), 120), Plan::Blocks { step: 8 });
        // 10 frames thinned by 3: frames 0, 3, 6, 9
        assert_eq!(
            thinned_counts(&[1, 2, 3, 4, 5, 6, 7, 8, 9], 3),
            vec![6, 15, 24]
        );
        // 9 frames: 0, 3, 6 (the last two intervals after frame 6 lead to no kept frame)
        assert_eq!(thinned_counts(&[1, 2, 3, 4, 5, 6, 7, 8], 3), vec![6, 15]);
        assert_eq!(thinned_counts(&[1, 2, 3, 4], 1), vec![1, 2, 3, 4]);
    }

    #[test]
    fn all_frames_in_one_block_when_they_fit() {
        assert_eq!(choose(&[5; 9], 10), vec![(0, 9)]);
    }

    #[test]
    fn one_block_per_part_where_the_events_are() {
        // 100 frames, 40 allowed: two blocks of 20, one in each half
        let mut counts = vec![1u64; 99];
        for c in &mut counts[10..29] {
            *c = 50;
        }
        for c in &mut counts[70..89] {
            *c = 50;
        }
        assert_eq!(choose(&counts, 40), vec![(10, 29), (70, 89)]);
    }

    #[test]
    fn a_burst_does_not_choose_alone() {
        // the first half: one interval of 10,000 events early, steady activity later
        let mut counts = vec![0u64; 99];
        counts[2] = 10_000;
        for c in &mut counts[25..49] {
            *c = 100;
        }
        for c in &mut counts[50..] {
            *c = 100;
        }
        // the cap is 100 (the 75th percentile of the intervals with events): the burst counts
        // 100, the steady run 19 x 100
        assert_eq!(burst_cap(&counts), 100);
        let blocks = choose(&counts, 40);
        assert_eq!(blocks[0], (25, 44));
        assert_eq!(blocks.len(), 2);
        assert!(blocks[1].0 >= 50 && blocks[1].1 <= 99);
    }

    #[test]
    fn motion_in_few_intervals_still_chooses_them() {
        // 200 frames, quiet (a few noise events) but for two short stretches of motion
        let mut counts = vec![3u64; 199];
        for c in &mut counts[30..40] {
            *c = 5_000;
        }
        for c in &mut counts[150..165] {
            *c = 8_000;
        }
        let blocks = choose(&counts, 40);
        assert!(blocks[0].0 <= 30 && blocks[0].1 >= 40, "{blocks:?}");
        assert!(blocks[1].0 <= 150 && blocks[1].1 >= 164, "{blocks:?}");
        // a limit under two frames still gives a block of two
        assert_eq!(choose(&counts, 0).len(), 1);
        assert_eq!(choose(&counts, 0)[0].1 - choose(&counts, 0)[0].0, 1);
    }

    #[test]
    fn blocks_stay_in_their_parts_and_within_the_limit() {
        let counts: Vec<u64> = (0..1499u64).map(|k| (k * 7919) % 1000).collect();
        let blocks = choose(&counts, 120);
        assert_eq!(blocks.len(), 6);
        for (j, &(a, b)) in blocks.iter().enumerate() {
            assert_eq!(b - a + 1, 20);
            assert!(
                a >= j * 1500 / 6 && b < (j + 1) * 1500 / 6,
                "block {j}: {a}..={b}"
            );
        }
    }
}
