//! The loop of a fit without frames: each effect measured on the fit blocks, added to the
//! noise model, and kept only when the model's distance on the selection blocks falls by
//! more than measured chance ([`crate::fit::selection::keep::decide`], the frame-based
//! fit's rule: the per-block relative fall's spread over the fit blocks).

use super::measure::BlockMeasure;
use super::model::{NoiseModel, Reference, distance};
use crate::fit::Step;
use crate::fit::observe::Role;
use crate::fit::selection::keep::decide;
use std::collections::BTreeMap;

/// A candidate change of the model, with what the fit blocks say for it.
pub struct Candidate {
    /// The effect's name (or `thresholds`).
    pub name: &'static str,
    pub evidence: String,
    /// The evidence in standard errors.
    pub score: f64,
    /// Whether the fit blocks call for it at all (else it is not tried).
    pub relevant: bool,
    pub parameters: BTreeMap<String, f64>,
    pub model: NoiseModel,
}

/// The measured blocks and their roles.
pub struct Judging<'a> {
    pub measures: &'a [BlockMeasure],
    pub role: &'a [Role],
    pub reference: Reference,
}

impl Judging<'_> {
    pub fn of(&self, role: Role) -> Vec<&BlockMeasure> {
        self.measures
            .iter()
            .zip(self.role)
            .filter(|(_, r)| **r == role)
            .map(|(m, _)| m)
            .collect()
    }

    /// Tries `candidate` against `current`: the step, and the model kept.
    pub fn try_step(&self, current: &NoiseModel, candidate: Candidate) -> (Step, NoiseModel) {
        let mut step = Step::untried(
            candidate.name.to_string(),
            candidate.evidence,
            candidate.score,
        );
        step.parameters = candidate.parameters;
        if !candidate.relevant {
            step.reason = "the fit blocks do not call for it".into();
            return (step, current.clone());
        }
        let selection = self.of(Role::Selection);
        let before = distance(current, &selection, self.reference);
        let after = distance(&candidate.model, &selection, self.reference);
        let falls: Vec<f64> = self
            .of(Role::Fit)
            .into_iter()
            .filter_map(|b| {
                let was = distance(current, &[b], self.reference).total;
                let now = distance(&candidate.model, &[b], self.reference).total;
                (was > 0.0).then(|| (was - now) / was)
            })
            .collect();
        let decision = decide(before.total, after.total, &falls, selection.len());
        step.error_before = Some(before.total);
        step.error_after = Some(after.total);
        step.components_after = Some(after);
        step.chance = decision.chance;
        step.kept = decision.kept;
        step.reason = decision.reason;
        let model = if decision.kept {
            candidate.model
        } else {
            current.clone()
        };
        (step, model)
    }
}
