//! Coverage broken down by what a case was (scene family, generator, each effect present,
//! brightness, speed, threshold size, frame count), so that a miss can be traced to what
//! causes it.

use super::score::{Score, score};
use crate::coverage::method::Method;
use crate::coverage::record::RunRecord;
use serde::Serialize;

/// A group of cases: its label and who belongs to it.
pub struct Group {
    pub label: String,
    pub contains: Box<dyn Fn(&RunRecord) -> bool>,
}

fn group(label: impl Into<String>, contains: impl Fn(&RunRecord) -> bool + 'static) -> Group {
    Group {
        label: label.into(),
        contains: Box::new(contains),
    }
}

fn mean_dn(r: &RunRecord) -> f64 {
    r.truth.as_ref().map_or(r.case.brightness_dn, |t| t.mean_dn)
}

/// The log-intensity standard deviation of a case's procedural texture (a texture or
/// rotation scene drawn from [`crate::sim::scene::canvas::TextureParams`]); `None` for a
/// photograph, objects, a checkerboard or a screen.
fn texture_log_std(r: &RunRecord) -> Option<f64> {
    let crate::coverage::RecordingSpec::Scene { scene } = &r.case.recording else {
        return None;
    };
    let texture = scene.texture.as_ref()?;
    texture.image.is_none().then_some(texture.texture.log_std)
}

/// Whether a texture's log std is below the lowest of `estimate eppps`' prior photographs
/// at any floor it scans (`rocket` at a floor of 52 % of its mean: 0.497): a texture below it
/// is less contrasty than every scene the prior stands for, and events alone read its
/// thresholds high in proportion (`benches/coverage/eppps-rotation-2026-12-04`).
fn below_prior(log_std: f64) -> bool {
    log_std < crate::estimate::eppps::prior::log_std_range().0
}

/// The mean light below which `estimate eppps` without frames leaves its scope: its scans
/// are of ideal pixels, and under about 20 DN of a DAVIS's frames (the light where v2e's
/// response turns linear and DVS-Voltmeter's ln(DN + 20-23) flattens, the dark current
/// as large as the photocurrent) the photoreceptor's cutoff, proportional to the light,
/// thins the events of a scene's changes, and leak events weigh against few signal ones
/// (the coverage draws' misses, `benches/coverage/eppps-scope-2026-12-04`).
pub const PRIOR_DIMMEST_DN: f64 = 20.0;

/// Whether a case lies in the scope of the prior of `estimate eppps` without frames: a
/// scene seen directly (not a screen), as contrasty as the prior's photographs or more
/// (a photograph, objects, a checkerboard, a texture of log std >= their lowest), with a
/// mean light of [`PRIOR_DIMMEST_DN`] or more.
fn in_prior_scope(r: &RunRecord) -> bool {
    !r.case.is_screen()
        && !texture_log_std(r).is_some_and(below_prior)
        && mean_dn(r) >= PRIOR_DIMMEST_DN
}

fn thresholds(r: &RunRecord) -> (f64, f64) {
    (r.case.params.ct_on, r.case.params.ct_off)
}

/// Every group the records have members in.
pub fn groups(records: &[RunRecord]) -> Vec<Group> {
    let mut all = kind_groups();
    all.extend(effect_groups(records));
    all.extend(prior_scope_groups());
    all.extend(light_and_speed_groups());
    all.extend(threshold_and_frame_groups());
    all.retain(|g| records.iter().any(|r| (g.contains)(r)));
    all
}

/// A group per scene family and per generator.
fn kind_groups() -> Vec<Group> {
    let mut all = Vec::new();
    for family in crate::coverage::SceneFamily::ALL {
        all.push(group(format!("family {}", family.name()), move |r| {
            r.case.family == family
        }));
    }
    for generator in crate::coverage::Generator::ALL {
        all.push(group(format!("generator {}", generator.name()), move |r| {
            r.case.generator == generator
        }));
    }
    all
}

/// A group per effect some record has (mismatch and display aside), and the group of
/// cases with none of them.
fn effect_groups(records: &[RunRecord]) -> Vec<Group> {
    let mut effects: Vec<String> = records
        .iter()
        .flat_map(|r| crate::coverage::truth::effects_present(&r.case.params))
        .filter(|e| e != "mismatch" && e != "display")
        .collect();
    effects.sort();
    effects.dedup();
    let mut all: Vec<Group> = effects
        .into_iter()
        .map(|effect| {
            group(format!("with {effect}"), move |r| {
                crate::coverage::truth::effects_present(&r.case.params).contains(&effect)
            })
        })
        .collect();
    all.push(group("no effect but mismatch (and display)", |r| {
        crate::coverage::truth::effects_present(&r.case.params)
            .iter()
            .all(|e| e == "mismatch" || e == "display")
    }));
    all
}

/// The procedural textures below and above the contrast of eppps' prior, and the cases in
/// and outside the prior's scope.
fn prior_scope_groups() -> Vec<Group> {
    let lowest = crate::estimate::eppps::prior::log_std_range().0;
    vec![
        group(
            format!("procedural texture less contrasty than eppps' prior (log std < {lowest:.3})"),
            |r| texture_log_std(r).is_some_and(below_prior),
        ),
        group(format!("procedural texture, log std >= {lowest:.3}"), |r| {
            texture_log_std(r).is_some_and(|s| !below_prior(s))
        }),
        group(
            format!(
                "in the scope of eppps' prior (contrast of its photographs or more, >= {PRIOR_DIMMEST_DN} DN)"
            ),
            in_prior_scope,
        ),
        group(
            format!(
                "outside it (a less contrasty texture, or < {PRIOR_DIMMEST_DN} DN; not a screen)"
            ),
            |r| !r.case.is_screen() && !in_prior_scope(r),
        ),
    ]
}

/// The cases by mean light (dim, mid, bright) and by speed (slow, medium, fast).
fn light_and_speed_groups() -> Vec<Group> {
    vec![
        group("dim (mean < 30 DN)", |r| mean_dn(r) < 30.0),
        group("mid (30-100 DN)", |r| (30.0..=100.0).contains(&mean_dn(r))),
        group("bright (> 100 DN)", |r| mean_dn(r) > 100.0),
        group("slow (< 60 px/s)", |r| r.case.speed_px_s < 60.0),
        group("medium (60-200 px/s)", |r| {
            (60.0..=200.0).contains(&r.case.speed_px_s)
        }),
        group("fast (> 200 px/s)", |r| r.case.speed_px_s > 200.0),
    ]
}

/// The cases by threshold (small, large, asymmetric) and those with few APS frames.
fn threshold_and_frame_groups() -> Vec<Group> {
    vec![
        group("small CT (min < 0.25)", |r| {
            let (p, n) = thresholds(r);
            p.min(n) < 0.25
        }),
        group("large CT (max > 0.6)", |r| {
            let (p, n) = thresholds(r);
            p.max(n) > 0.6
        }),
        group("asymmetric (|Cp - Cn| > 0.3)", |r| {
            let (p, n) = thresholds(r);
            (p - n).abs() > 0.3
        }),
        group("few APS frames (< 20)", |r| {
            r.truth
                .as_ref()
                .is_some_and(|t| !r.case.is_screen() && t.aps_frames < 20)
        }),
    ]
}

/// One cell: covered of determinable, of cases.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Cell {
    pub cases: usize,
    pub determinable: usize,
    pub covered: usize,
}

/// One line of a method's breakdown.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BreakdownRow {
    pub method: Method,
    pub group: String,
    /// One cell per parameter of [`Breakdown::parameters`].
    pub cells: Vec<Cell>,
}

/// A method's breakdown over its threshold parameters.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Breakdown {
    pub method: Method,
    pub parameters: Vec<String>,
    pub rows: Vec<BreakdownRow>,
}

fn cell(records: &[&RunRecord], parameter: &str) -> Cell {
    let mut cell = Cell::default();
    for score in records.iter().filter_map(|r| score(r, parameter)) {
        cell.cases += 1;
        if let Score::Value { covered, .. } = score {
            cell.determinable += 1;
            cell.covered += covered as usize;
        }
    }
    cell
}

impl Breakdown {
    pub fn tabulate(records: &[RunRecord], method: Method, parameters: Vec<String>) -> Self {
        let runs: Vec<&RunRecord> = records.iter().filter(|r| r.method == method).collect();
        let rows = groups(records)
            .into_iter()
            .filter_map(|g| {
                let members: Vec<&RunRecord> =
                    runs.iter().copied().filter(|r| (g.contains)(r)).collect();
                (!members.is_empty()).then(|| BreakdownRow {
                    method,
                    group: g.label,
                    cells: parameters.iter().map(|p| cell(&members, p)).collect(),
                })
            })
            .collect();
        Breakdown {
            method,
            parameters,
            rows,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coverage::record::committed;

    const SCOPE: &str = "benches/coverage/eppps-scope-2026-12-04/results-8001-8030.compact.jsonl";

    #[test]
    fn the_prior_s_scope_leaves_out_less_contrasty_textures_and_dim_scenes() {
        // 8014: a rotating texture of log std 0.242 at 40 DN, below the photographs' 0.497
        let texture = committed(SCOPE, 8014);
        assert_eq!(texture_log_std(&texture), Some(0.241752));
        assert!(!in_prior_scope(&texture));
        // 8022: a photograph at 15 DN, under the 20 DN the scans' ideal pixels reach
        let dim = committed(SCOPE, 8022);
        assert_eq!(texture_log_std(&dim), None);
        assert!(mean_dn(&dim) < PRIOR_DIMMEST_DN && !in_prior_scope(&dim));
        // 8002: objects at 55 DN are in it
        let objects = committed(SCOPE, 8002);
        assert!(mean_dn(&objects) >= PRIOR_DIMMEST_DN && in_prior_scope(&objects));
    }
}
