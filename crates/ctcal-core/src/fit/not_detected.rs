//! What a fit's "off" means for each effect the final model lacks. A simulator
//! configuration written from the fit sets such an effect to zero (no mismatch, no noise,
//! no bandwidth limit), and that zero is not a measurement: the loop did not call for the
//! effect, tried it and found its fall in error within chance, or kept it and later took it
//! out (no longer needed, or a look-alike in its place). Where the fit measured how strong
//! the effect would have had to be for this recording to show it (the noise and bandwidth
//! detection limits, and what the quiet pixels or the event timing's drift allow of the
//! noise; the hot-pixel search's reach; a refractory period's edge in the intervals; the
//! most event timing allows of a threshold spread), that is said: the effect, if present,
//! is likely weaker. Where the recording's own evidence still calls for a threshold spread
//! the loop did not keep, that is said too.

use super::effects::Effect;
use super::events_only::refractory::Edge;
use super::wording::{at_most_in_words, significant, spread_in_words};
use super::{FitResult, HotPixelDetection, Step};
use std::collections::BTreeMap;

/// Per parameter (PARAMS.toml key) of an effect the final model lacks and the data do not
/// leave unidentified: why it is off and, where measured, the strength this recording
/// would have shown. `interval_edge`, the lower edge of the fit run's same-pixel
/// intervals, bounds a refractory period.
pub fn of(result: &FitResult, interval_edge: Option<&Edge>) -> BTreeMap<String, String> {
    let set = serde_json::to_value(&result.params.model).unwrap_or_default();
    let is_set = |key: &str| set.get(key).is_some_and(|v| !v.is_null());
    let mut out = BTreeMap::new();
    for effect in Effect::ALL {
        let keys = parameters(effect);
        let unexplained = keys
            .iter()
            .all(|k| !is_set(k) && !result.why.contains_key(*k));
        if keys.is_empty() || !unexplained {
            continue;
        }
        let why = note(effect, result, interval_edge);
        for key in keys {
            out.insert(key.to_string(), why.clone());
        }
    }
    out
}

/// The PARAMS.toml keys that turn `effect` on (none for the display, which a configuration
/// does not carry).
fn parameters(effect: Effect) -> Vec<&'static str> {
    match effect {
        Effect::HotPixels => vec!["hot_pixel_fraction", "hot_pixel_rate_hz"],
        Effect::Display => Vec::new(),
        other => other.parameter().into_iter().collect(),
    }
}

/// Why `effect` is off, and the bound the recording sets on it where one was measured.
fn note(effect: Effect, result: &FitResult, interval_edge: Option<&Edge>) -> String {
    let decision = decision(effect, &result.steps);
    let bound = match effect {
        Effect::Refractory => interval_edge.and_then(refractory_bound),
        _ => bound(effect, result),
    };
    match bound {
        Some(bound) => format!("{} {decision}; {bound}", effect.name()),
        None => format!(
            "{} {decision}; how strong it would have to be for this recording to show it was not measured",
            effect.name()
        ),
    }
}

/// What the loop last decided about `effect`: its own step (`EFFECT`, `EFFECT (refit)`,
/// `EFFECT (again, with ... in)`), or a later step that took it out (`EFFECT (still
/// needed?)`, an alternative `OTHER in place of EFFECT?` kept).
fn decision(effect: Effect, steps: &[Step]) -> String {
    let name = effect.name();
    let own = |s: &&Step| s.effect == name || s.effect.starts_with(&format!("{name} ("));
    let replaced = |s: &&Step| s.kept && s.effect.ends_with(&format!(" in place of {name}?"));
    let Some(last) = steps.iter().rev().find(|s| own(s) || replaced(s)) else {
        return "not tried (not among the effects fitted)".to_string();
    };
    let was_kept = steps.iter().filter(own).any(|s| s.kept);
    let because = if last.reason.is_empty() {
        String::new()
    } else {
        format!(": {}", last.reason)
    };
    match (was_kept, replaced(&last)) {
        (_, true) => format!("kept, then replaced ({}){because}", last.effect),
        (true, false) => format!("kept, then removed ({}){because}", last.effect),
        (false, false) => format!("not kept{because}"),
    }
}

/// The strength at which this recording would have shown `effect`, where the fit measured
/// it.
fn bound(effect: Effect, result: &FitResult) -> Option<String> {
    match effect {
        Effect::ShotNoise | Effect::Leak => {
            let key = effect.parameter()?;
            let limit = result.noise_detection.as_ref()?.limits.get(key)?;
            let above = match (limit.called_for_above_hz, &limit.why) {
                (Some(hz), _) => Some(format!(
                    "its detection limit on this recording is {} Hz (noise_detection: a rate at which the model's evidence calls for it), so a rate above that is unlikely",
                    significant(hz)
                )),
                (None, Some(why)) => Some(format!("no detection limit: {why}")),
                (None, None) => None,
            };
            let at_most = limit.at_most_hz.map(|hz| at_most_in_words(effect, hz));
            let parts: Vec<String> = [above, at_most].into_iter().flatten().collect();
            (!parts.is_empty()).then(|| parts.join("; "))
        }
        Effect::Bandwidth => {
            let detection = result.bandwidth_detection.as_ref()?;
            match (detection.called_for_below_hz, &detection.why) {
                (Some(hz), _) => Some(format!(
                    "a cutoff at white of {} Hz or lower would have shown (in about 95 % of recordings of this scene: bandwidth_detection), so any cutoff is likely higher",
                    significant(hz)
                )),
                (None, Some(why)) => Some(format!("no detection limit: {why}")),
                (None, None) => None,
            }
        }
        Effect::HotPixels => hot_pixels_bound(result.hot_pixel_detection.as_ref()?),
        Effect::Mismatch => Some(spread_in_words(result.mismatch_detection.as_ref()?)),
        // timestamp jitter has no detection limit yet
        _ => None,
    }
}

/// The slowest hot pixel the search names at 95 % of the kept pixels or more, read off
/// `detection`'s curve at its first rate there (eight a decade: the exact rate is at or
/// below it).
fn hot_pixels_bound(detection: &HotPixelDetection) -> Option<String> {
    let Some(&[rate, _]) = detection.probability.iter().find(|[_, p]| *p >= 0.95) else {
        let &[fastest, share] = detection.probability.last()?;
        return Some(format!(
            "the hot-pixel search names even a pixel whose train fires {} Hz beyond its scene at only {:.0} % of the kept pixels (hot_pixel_detection, on this recording's counts): the recording does not bound hot pixels",
            significant(fastest),
            100.0 * share
        ));
    };
    Some(format!(
        "the hot-pixel search would name a pixel whose train fires {} Hz or faster beyond its scene at 95 % or more of the kept pixels (hot_pixel_detection, on this recording's counts: the search's test alone, which the fit's later checks can only lower), so a hot pixel that fast would likely have been named; slower ones hide among the scene's events",
        significant(rate)
    ))
}

/// What the lower edge of the same-pixel intervals says of a refractory period the loop
/// did not keep: a gap with the pile-up a refractory period leaves is named. The shortest
/// interval is no bound: a simulator (v2e, ctcal's own) lets shot-noise events through the
/// refractory period, so a recording made with a 0.5 ms period can hold 27 us intervals
/// (`data_samples/texture_davis240c`).
fn refractory_bound(edge: &Edge) -> Option<String> {
    (edge.found && edge.not_refractory.is_none()).then(|| {
        format!(
            "the fit run's same-pixel intervals have a lower edge at {:.0} us with the pile-up above it that a refractory period leaves (range {:.0}-{:.0} us): a refractory period near it is not ruled out",
            edge.edge_us, edge.range_us[0], edge.range_us[1]
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn edge(found: bool, not_refractory: Option<&str>) -> Edge {
        Edge {
            edge_us: 480.0,
            range_us: [420.0, 530.0],
            below: 3,
            above: 200,
            found,
            not_refractory: not_refractory.map(str::to_string),
            intervals: 5000,
        }
    }

    /// Only a gap with its pile-up speaks of a refractory period the loop did not keep;
    /// no gap, or a gap without the pile-up, bounds nothing (a simulator's noise events
    /// pass through the period).
    #[test]
    fn only_an_edge_with_its_pile_up_is_said_of_a_refractory_period() {
        let said = refractory_bound(&edge(true, None)).unwrap();
        assert!(said.contains("lower edge at 480 us") && said.contains("420-530 us"));
        assert_eq!(refractory_bound(&edge(false, None)), None);
        assert_eq!(refractory_bound(&edge(false, Some("no pile-up"))), None);
    }

    /// Where the search named no hot pixel, the slowest train it names at 95 % of the
    /// pixels is said, at the curve's first rate there; a curve that never gets there says
    /// that the recording does not bound them.
    #[test]
    fn hot_pixels_are_bounded_where_the_search_names_them_at_95_percent() {
        let detection = |curve: Vec<[f64; 2]>| HotPixelDetection::new(7.0, curve);
        let said = hot_pixels_bound(&detection(vec![
            [1.0, 0.02],
            [7.0, 0.5],
            [13.3, 0.93],
            [17.8, 0.97],
        ]))
        .unwrap();
        assert!(said.contains("17.8 Hz or faster"), "{said}");
        let unbounded = hot_pixels_bound(&detection(vec![[1.0, 0.2], [5623.0, 0.9]])).unwrap();
        assert!(
            unbounded.contains("5623 Hz") && unbounded.contains("only 90 %"),
            "{unbounded}"
        );
        assert_eq!(hot_pixels_bound(&detection(Vec::new())), None);
    }

    fn step(effect: &str, kept: bool, reason: &str) -> Step {
        let mut s = Step::untried(effect.to_string(), String::new(), 0.0);
        s.kept = kept;
        s.reason = reason.to_string();
        s
    }

    /// The loop's last word on an effect: an effect kept and then taken out is not called
    /// "not kept" with the reason it was kept for.
    #[test]
    fn the_last_decision_on_an_effect_is_said() {
        let steps = [
            step("thresholds", true, "the starting point"),
            step("leak", true, "error falls 8 %"),
            step("shot_noise", true, "error falls 30 %"),
            step(
                "leak (still needed?)",
                true,
                "without it the error rises 0.1 %: removed",
            ),
            step(
                "bandwidth in place of shot_noise?",
                true,
                "as good within chance",
            ),
            step("mismatch", false, "needs a fall of 0.08"),
        ];
        assert_eq!(
            decision(Effect::Leak, &steps),
            "kept, then removed (leak (still needed?)): without it the error rises 0.1 %: removed"
        );
        assert_eq!(
            decision(Effect::ShotNoise, &steps),
            "kept, then replaced (bandwidth in place of shot_noise?): as good within chance"
        );
        assert_eq!(
            decision(Effect::Mismatch, &steps),
            "not kept: needs a fall of 0.08"
        );
        assert_eq!(
            decision(Effect::Refractory, &steps),
            "not tried (not among the effects fitted)"
        );
    }
}
