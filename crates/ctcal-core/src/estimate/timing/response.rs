//! Which log response the frames are read through: the frames' own (v2e's lin-log by
//! default) or a pure `ln(DN + b)`, and whether the events can tell them apart.
//!
//! Each candidate is fitted at its own offset and scored by how far its samples scatter
//! about the model (the weighted mean absolute residual over the mean threshold). Where the
//! pixels leave the score ratio uncertain (a dim scene of a few hundred events), the choice
//! is a coin the data did not flip, and the thresholds the other response gives are carried
//! into the intervals ([`OtherResponse`]): a dim scene is where the two differ most, since
//! the lin-log response is linear below 20 DN and `ln(DN + b)` compresses it by `b`
//! (coverage draw 4078, mean 11 DN: 0.067 against the true 0.44 under the pure log, 0.49
//! under lin-log).
//!
//! The ratio's uncertainty is a bootstrap over pixels with both candidates' residuals drawn
//! together (common random numbers), their fits held fixed.

use super::model::{self, Coefficients};
use super::pixels::PixelSlots;
use super::samples::Pair;
use super::{Fit, Offset, TimingOptions, find_offset, whole_fit};
use crate::estimate::frames::PreparedFrames;
use crate::sim::LogResponse;
use crate::sim::log_response::LogMap;
use rayon::prelude::*;
use serde::Serialize;

/// A pure log must scatter this much less than the frames' own response to replace it.
pub const REPLACE_MARGIN: f64 = 0.98;

/// Bootstrap draws of the score ratio.
const RATIO_DRAWS: usize = 200;

/// The response not chosen, where the events cannot rule it out: its thresholds at its own
/// offset, and the ratio of its score to the chosen one's with a 95 % interval.
#[derive(Clone, Debug, Serialize)]
pub struct OtherResponse {
    #[serde(skip)]
    pub log_map: LogMap,
    /// `v2e` or `eps` (a pure `ln(DN + b)`).
    pub response: &'static str,
    pub offset_dn: f32,
    pub ct_on: f64,
    pub ct_off: f64,
    /// The thresholds the chosen response gives at its own offset (before the polarities'
    /// offsets are joined to it), for the ratio.
    pub chosen_ct_on: f64,
    pub chosen_ct_off: f64,
    /// Its score over the chosen response's (below 1: it scatters less).
    pub score_ratio: f64,
    pub score_ratio_ci95: [f64; 2],
}

impl OtherResponse {
    /// How many times the chosen thresholds the other response's are, ON and OFF.
    pub fn threshold_ratios(&self) -> [f64; 2] {
        [
            self.ct_on / self.chosen_ct_on,
            self.ct_off / self.chosen_ct_off,
        ]
    }
}

/// The response and offset the events choose, and the other response where they cannot
/// rule it out.
pub(super) struct Chosen {
    pub log_map: LogMap,
    pub offset: Offset,
    pub other: Option<OtherResponse>,
}

/// One candidate response fitted at its offset.
struct Candidate {
    map: LogMap,
    offset: Offset,
    coefficients: Option<Coefficients>,
    /// Per pixel slot: the weighted absolute residuals over the mean threshold, and the
    /// weights.
    sums: Vec<[f64; 2]>,
}

impl Candidate {
    fn score(&self) -> f64 {
        score(&self.sums, None)
    }
}

/// The response and offset: each candidate response (the frames' own; with
/// `choose_response` also a pure `ln(DN + b)`) at its offset, the pure log chosen where it
/// scatters [`REPLACE_MARGIN`] less; the other kept where the ratio's 95 % interval reaches
/// across that margin.
pub(super) fn choose(pairs: &[Pair], frames: &PreparedFrames, options: &TimingOptions) -> Chosen {
    let slots = PixelSlots::new(pairs);
    let mut candidates = fitted_candidates(pairs, frames, options, &slots);
    let own = candidates.remove(0);
    let Some(pure) = candidates.pop() else {
        return Chosen {
            log_map: own.map,
            offset: own.offset,
            other: None,
        };
    };
    let ratio = pure.score() / own.score();
    let replace = ratio < REPLACE_MARGIN;
    let ci = ratio_interval(&pure.sums, &own.sums, slots.len());
    let clear = if replace {
        ci[1] < REPLACE_MARGIN
    } else {
        ci[0] >= REPLACE_MARGIN
    };
    let (chosen, other) = if replace { (pure, own) } else { (own, pure) };
    let other = if clear {
        None
    } else {
        other_response(&chosen, other, replace, ratio, ci)
    };
    Chosen {
        log_map: chosen.map,
        offset: chosen.offset,
        other,
    }
}

/// The candidate responses, each fitted at its own offset in parallel: the frames' own
/// first, then (with `fit_offset` and `choose_response`, where the frames' own is not
/// already one) a pure `ln(DN + b)`.
fn fitted_candidates(
    pairs: &[Pair],
    frames: &PreparedFrames,
    options: &TimingOptions,
    slots: &PixelSlots,
) -> Vec<Candidate> {
    let pixels = frames.width * frames.height;
    let mut maps = vec![frames.log_map];
    if options.fit_offset
        && options.choose_response
        && frames.log_map.response() != LogResponse::Eps
    {
        maps.push(LogMap::new(LogResponse::Eps, 0.0));
    }
    maps.into_par_iter()
        .map(|map| {
            let fit = whole_fit(pairs, &map, pixels, options);
            let offset = find_offset(pairs, frames, options, &fit);
            candidate(pairs, slots, map, offset, &fit)
        })
        .collect()
}

/// The response not chosen, kept where the events could not rule it out: its thresholds
/// beside the chosen one's, and the score ratio (with its interval `ci` of the pure log's
/// over the frames' own) turned to the other's over the chosen's. `None` where either
/// response's thresholds are missing or not positive.
fn other_response(
    chosen: &Candidate,
    other: Candidate,
    replace: bool,
    ratio: f64,
    ci: [f64; 2],
) -> Option<OtherResponse> {
    let positive = |c: &Coefficients| [c.c_on, c.c_off].iter().all(|v| v.is_finite() && *v > 0.0);
    match (&chosen.coefficients, &other.coefficients) {
        (Some(c), Some(o)) if positive(c) && positive(o) => Some(OtherResponse {
            log_map: other.map,
            response: response_name(other.map.response()),
            offset_dn: other.offset.offset_dn,
            ct_on: o.c_on,
            ct_off: o.c_off,
            chosen_ct_on: c.c_on,
            chosen_ct_off: c.c_off,
            score_ratio: if replace { 1.0 / ratio } else { ratio },
            score_ratio_ci95: if replace {
                [1.0 / ci[1], 1.0 / ci[0]]
            } else {
                ci
            },
        }),
        _ => None,
    }
}

fn response_name(response: LogResponse) -> &'static str {
    match response {
        LogResponse::Eps => "eps",
        _ => "v2e",
    }
}

fn candidate(
    pairs: &[Pair],
    slots: &PixelSlots,
    map: LogMap,
    offset: Offset,
    fit: &Fit<'_>,
) -> Candidate {
    let fitted = fit(offset.offset_dn);
    let sums = fitted
        .as_ref()
        .map(|(c, v, w)| residual_sums(pairs, slots, c, v, w))
        .unwrap_or_default();
    Candidate {
        map,
        offset,
        coefficients: fitted.map(|f| f.0),
        sums,
    }
}

/// Per pixel slot, the weighted absolute residuals of the kept pairs over the mean
/// threshold, and their weights.
fn residual_sums(
    pairs: &[Pair],
    slots: &PixelSlots,
    c: &Coefficients,
    v: &model::Values,
    w: &[f64],
) -> Vec<[f64; 2]> {
    let scale = (0.5 * (c.c_on + c.c_off)).max(1e-12);
    let mut sums = vec![[0.0; 2]; slots.len()];
    for (i, p) in pairs.iter().enumerate() {
        if w[i] > 0.0 {
            let ct = if p.on { c.c_on } else { c.c_off };
            let s = &mut sums[slots.slot_of(i)];
            s[0] += w[i] * (c.corrected(p, v, i) - ct).abs() / scale;
            s[1] += w[i];
        }
    }
    sums
}

/// The weighted mean absolute residual over the mean threshold, of every pixel slot
/// (`times` `None`) or of a draw (how often each slot was drawn); infinite without one.
fn score(sums: &[[f64; 2]], times: Option<&[u32]>) -> f64 {
    let (mut residual, mut weight) = (0.0, 0.0);
    for (k, s) in sums.iter().enumerate() {
        let n = times.map_or(1.0, |t| t[k] as f64);
        residual += n * s[0];
        weight += n * s[1];
    }
    if weight > 0.0 {
        residual / weight
    } else {
        f64::INFINITY
    }
}

/// The 95 % interval (2.5th and 97.5th percentiles) of `score(a) / score(b)` over pixel
/// draws common to both (draws without a score left out); `[inf, inf]` where either has
/// no fit, or half the draws have no score.
fn ratio_interval(a: &[[f64; 2]], b: &[[f64; 2]], slots: usize) -> [f64; 2] {
    if a.len() != slots || b.len() != slots || slots == 0 {
        return [f64::INFINITY; 2];
    }
    let units: Vec<u32> = (0..slots as u32).collect();
    let mut ratios: Vec<f64> = (0..RATIO_DRAWS)
        .into_par_iter()
        .map(|k| {
            let times = model::draw_counts(&units, slots, 9000 + k as u64);
            score(a, Some(&times)) / score(b, Some(&times))
        })
        // a draw of only pixels without kept pairs has no score
        .filter(|r| r.is_finite())
        .collect();
    if ratios.len() < RATIO_DRAWS / 2 {
        return [f64::INFINITY; 2];
    }
    ratios.sort_by(f64::total_cmp);
    let at = |q: f64| ratios[(q * (ratios.len() - 1) as f64).round() as usize];
    [at(0.025), at(0.975)]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand-computed: slots (residual, weight) (1, 2) and (3, 2) give 4 / 4 = 1; a draw of
    /// the second slot twice gives 6 / 4.
    #[test]
    fn score_is_the_weighted_mean_of_the_drawn_slots() {
        let sums = [[1.0, 2.0], [3.0, 2.0]];
        assert_eq!(score(&sums, None), 1.0);
        assert_eq!(score(&sums, Some(&[0, 2])), 1.5);
        assert_eq!(score(&sums, Some(&[0, 0])), f64::INFINITY);
    }

    /// A response whose every pixel scatters half as much has the ratio 0.5 in every draw;
    /// one that is better in some pixels and worse in others has an interval across 1.
    #[test]
    fn ratio_interval_follows_the_pixels() {
        let b: Vec<[f64; 2]> = (0..50).map(|k| [1.0 + k as f64 * 0.1, 1.0]).collect();
        let half: Vec<[f64; 2]> = b.iter().map(|s| [0.5 * s[0], s[1]]).collect();
        let [lo, hi] = ratio_interval(&half, &b, 50);
        assert!(
            (lo - 0.5).abs() < 1e-12 && (hi - 0.5).abs() < 1e-12,
            "{lo} {hi}"
        );
        let mixed: Vec<[f64; 2]> = b
            .iter()
            .enumerate()
            .map(|(k, s)| [if k % 2 == 0 { 0.6 } else { 1.4 } * s[0], s[1]])
            .collect();
        let [lo, hi] = ratio_interval(&mixed, &b, 50);
        assert!(lo < 1.0 && hi > 1.0 && hi - lo > 0.1, "{lo} {hi}");
        assert_eq!(ratio_interval(&b, &b[..3], 50), [f64::INFINITY; 2]);
    }
}
