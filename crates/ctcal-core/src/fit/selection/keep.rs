//! Whether a candidate model is better than the current one: its distance on the judging
//! blocks (selection, never fitted on) must fall by more than chance. Chance is measured,
//! not assumed: the relative fall of the distance from one model to the other, block by
//! block over the fit blocks (those with events), scatters by `s` (sampling noise and the
//! blocks' different content), so the relative fall over `n` judging blocks moves by about
//! `s / sqrt(n)`; an effect is kept when its relative fall exceeds twice that (one-sided
//! ~98 %) and a parsimony floor of 1 % (an effect too small to matter is left out even when
//! measurable). With fewer than three fit blocks chance cannot be measured and a 2 % floor
//! stands in (said in the assumptions).

use super::super::metric::Components;
use super::super::observe::{Observed, Role, Subset};
use super::super::search::Simulation;
use crate::stats::robust::sample_std_dev;

/// The smallest relative gain that keeps an effect, whatever chance says.
pub const PARSIMONY: f64 = 0.01;
/// The relative gain needed where chance cannot be measured (under three fit blocks).
pub const UNMEASURED_CHANCE: f64 = 0.02;

/// The judgement of a candidate against the current model.
pub struct Verdict {
    pub before: Components,
    pub after: Components,
    /// The gain that chance alone would give (twice its standard error), `None` where
    /// it could not be measured.
    pub chance: Option<f64>,
    pub kept: bool,
    pub reason: String,
}

/// Judges `candidate` against `current` on the judging blocks.
pub fn judge(
    simulation: &Simulation,
    current: &Observed,
    candidate: &Observed,
    kept_pixels: &[bool],
) -> Verdict {
    let g = simulation.geometry;
    let subset = g.judging();
    let before = simulation.distance(current, subset, kept_pixels);
    let after = simulation.distance(candidate, subset, kept_pixels);
    let judging_blocks = (0..g.blocks).filter(|&b| g.in_subset(b, subset)).count();
    let relative_falls: Vec<f64> = g
        .blocks_of(Role::Fit)
        .into_iter()
        .filter_map(|b| {
            let was = simulation
                .distance(current, Subset::Block(b), kept_pixels)
                .total;
            let now = simulation
                .distance(candidate, Subset::Block(b), kept_pixels)
                .total;
            (was > 0.0).then(|| (was - now) / was)
        })
        .collect();
    let Decision {
        chance,
        kept,
        reason,
    } = decide(before.total, after.total, &relative_falls, judging_blocks);
    Verdict {
        before,
        after,
        chance,
        kept,
        reason,
    }
}

/// A keep decision from the distances alone.
pub struct Decision {
    pub chance: Option<f64>,
    pub kept: bool,
    pub reason: String,
}

/// Keeps a candidate whose distance on the `judging_blocks` falls from `before` to `after`
/// by more than chance: twice the standard deviation of the per-block `relative_falls` (fit
/// blocks) over the square root of the judging blocks, and at least [`PARSIMONY`]; with
/// fewer than three relative falls, [`UNMEASURED_CHANCE`] stands in.
pub fn decide(before: f64, after: f64, relative_falls: &[f64], judging_blocks: usize) -> Decision {
    let gain = before - after;
    let chance = (relative_falls.len() >= 3)
        .then(|| sample_std_dev(relative_falls))
        .flatten()
        .map(|s| 2.0 * s / (judging_blocks.max(1) as f64).sqrt() * before);
    let floor = match chance {
        Some(c) => c.max(PARSIMONY * before),
        None => UNMEASURED_CHANCE * before,
    };
    let kept = gain > floor;
    let change = -100.0 * gain / before.max(1e-12);
    let reason = if kept {
        format!(
            "error on the selection blocks {before:.4} -> {after:.4} ({change:+.1} %; chance {})",
            describe(chance)
        )
    } else {
        format!(
            "error on the selection blocks {before:.4} -> {after:.4} ({change:+.1} %): needs a fall of {floor:.4} (chance {}, at least {:.0} %)",
            describe(chance),
            100.0 * PARSIMONY
        )
    };
    Decision {
        chance,
        kept,
        reason,
    }
}

fn describe(chance: Option<f64>) -> String {
    chance.map_or("not measurable: under three fit blocks".into(), |c| {
        format!("{c:.4}")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_effect_is_kept_when_its_fall_beats_measured_chance() {
        // per-block falls of 10, 20 and 30 %: standard deviation 0.1; over four judging
        // blocks chance is 2 x 0.1 / 2 = 10 % of the distance before
        let falls = [0.1, 0.2, 0.3];
        let kept = decide(2.0, 1.7, &falls, 4);
        assert!((kept.chance.unwrap() - 0.2).abs() < 1e-12);
        assert!(kept.kept, "{}", kept.reason);
        let not = decide(2.0, 1.85, &falls, 4);
        assert!(!not.kept, "{}", not.reason);
        assert!(
            not.reason.contains("needs a fall of 0.2000"),
            "{}",
            not.reason
        );
        // more judging blocks, less chance: the same fall of 7.5 % is kept over 16
        assert!(decide(2.0, 1.85, &falls, 16).kept);
    }

    #[test]
    fn without_three_fit_blocks_a_fixed_fall_stands_in_and_says_so() {
        let falls = [0.5, 0.1];
        let d = decide(1.0, 0.979, &falls, 3);
        assert!(d.chance.is_none() && d.kept, "{}", d.reason);
        let d = decide(1.0, 0.981, &falls, 3);
        assert!(!d.kept);
        assert!(d.reason.contains("not measurable"), "{}", d.reason);
    }

    #[test]
    fn an_effect_too_small_to_matter_is_left_out_even_when_measurable() {
        // identical falls: chance is 0, and the 1 % parsimony floor decides
        let falls = [0.004, 0.004, 0.004, 0.004];
        assert!(!decide(1.0, 0.991, &falls, 5).kept);
        assert!(decide(1.0, 0.989, &falls, 5).kept);
        // a candidate that is worse is never kept
        assert!(!decide(1.0, 1.2, &falls, 5).kept);
    }
}
