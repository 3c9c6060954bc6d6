//! What noise a fit with frames could have seen: for each noise effect the final model
//! lacks (shot noise, leak), a rate at which the recording's isolated events would have
//! called for it (its evidence reaching [`EVIDENCE_THRESHOLD`] standard errors, the rule
//! that decides which effects are tried).
//!
//! The evidence counts events without spatio-temporal support (the background-activity
//! filter of Delbruck 2008: no event at the 8 neighbours in the preceding 10 ms). In a busy
//! scene most of a noise effect's events fire beside the scene's own and are supported, so
//! the rate it takes to stand out is far above a static scene's; and where the model
//! already makes more isolated events than the recording (the frames' read noise simulated
//! as change), the effect must first make up that difference. Both are measured by
//! injection rather than assumed: the final model is simulated again with the effect at
//! [`PROBE_HZ`] (same seed, same blocks), and the isolated events it adds, scaled
//! linearly, give a candidate rate: the one whose expected evidence is [`MARGIN_Z`]
//! standard errors above the threshold, so that Poisson chance leaves it below the
//! threshold about 5 % of the time. Shot noise is memoryless and scales; leak does not: a
//! pixel's first leak event comes one leak period after the recording starts (the
//! simulator's reference starts at the first frame, as v2e's does), so a slow leak adds no
//! isolated event to a short recording at all. The candidate is therefore simulated in
//! turn and given only where its evidence reaches the threshold plus the margin, as the
//! candidate was scaled (checked at the threshold alone, one simulation just over it would
//! call for the effect in only about half of such recordings); otherwise the rate grows by
//! [`next_step`] (the square root of 2 where the threshold was reached, else 2), up to
//! [`CHECKS`] simulations. A noise effect not in the model may be present below the
//! rate given.
//!
//! Beside that trigger, each effect has a limit that does not depend on how many of its
//! events stand out (`at_most_hz`): for shot noise the quiet pixels' isolated OFF events,
//! for leak the event timing's drift, which a leak moves from a pixel's first event on. A
//! leak's isolated-event limit can lie far above what the recording allows: on coverage
//! draws 13015 and 13035 the trigger needed 7.8 and 5.1 Hz where the drift bounds the leak
//! below about 0.7 and 0.1 Hz (`benches/coverage/fit-unseen-effects-2026-12-07`).

use super::super::effects::quiet_noise::at_most_dark_hz;
use super::super::effects::{EVIDENCE_THRESHOLD, Effect, isolated_totals, leak, shot_noise};
use super::super::observe::Subset;
use super::super::search::Simulation;
use super::super::{NoiseDetection, NoiseLimit, Step};
use super::State;
use crate::fit::wording::{at_most_in_words, significant};
use std::collections::BTreeMap;

/// The rate the effect is first simulated at to measure how many of its events stay
/// isolated (Hz: the dark rate of shot noise, the leak's events per pixel-second).
pub const PROBE_HZ: f64 = 1.0;

/// The most simulations that check a candidate rate, per effect.
pub const CHECKS: usize = 4;

/// The factor to the next candidate rate after one whose evidence fell short of the margin:
/// the square root of 2 where it reached the threshold (the margin is 1.645 standard errors
/// further; shot noise's isolated events grow in proportion to its rate), else 2 (a leak
/// may add no isolated events at all until its period fits in the recording).
fn next_step(reached_threshold: bool) -> f64 {
    if reached_threshold {
        std::f64::consts::SQRT_2
    } else {
        2.0
    }
}

/// How far above the evidence threshold the candidate rate's expected evidence is, in
/// standard errors: the one-sided 95 % normal quantile.
pub const MARGIN_Z: f64 = 1.645;

/// An effect's evidence score: `(z, excess rate)` from the isolated events `[real OFF,
/// real ON, model OFF, model ON]` over `exposure` pixel-seconds.
type Score = fn([f64; 4], f64) -> (f64, f64);

/// The noise effects whose detection is measured, with their parameter, evidence score
/// and the excess rate below which they do not matter.
const NOISE: [(Effect, &str, Score, f64); 2] = [
    (
        Effect::ShotNoise,
        "shot_noise_rate_hz",
        shot_noise::score,
        shot_noise::RELEVANT_HZ,
    ),
    (Effect::Leak, "leak_rate_hz", leak::score, leak::RELEVANT_HZ),
];

/// One effect's evidence over the recording and the final model's isolated events.
#[derive(Clone, Copy)]
struct Evidence {
    base: [f64; 4],
    exposure: f64,
    score: Score,
    relevant_hz: f64,
}

impl Evidence {
    /// Whether the evidence reaches `z_needed` and matters with `k` times `added`
    /// ([OFF, ON]) on the recording's side.
    fn calls(&self, added: [f64; 2], k: f64, z_needed: f64) -> bool {
        let b = self.base;
        let t = [b[0] + k * added[0], b[1] + k * added[1], b[2], b[3]];
        let (z, rate) = (self.score)(t, self.exposure);
        z >= z_needed && rate > self.relevant_hz
    }

    /// The smallest multiple `k` of `added` at which the evidence reaches `z_needed`:
    /// scanned eight a decade from 1e-4 to 1e4, then bisected.
    fn multiple(&self, added: [f64; 2], z_needed: f64) -> Limit {
        if self.exposure <= 0.0 {
            return Limit::Never;
        }
        if self.calls(added, 0.0, EVIDENCE_THRESHOLD) {
            return Limit::AlreadyCalledFor;
        }
        let mut below = 0.0;
        for j in -32..=32 {
            let k = 10f64.powf(j as f64 / 8.0);
            if self.calls(added, k, z_needed) {
                let mut above = k;
                for _ in 0..40 {
                    let mid = 0.5 * (below + above);
                    if self.calls(added, mid, z_needed) {
                        above = mid;
                    } else {
                        below = mid;
                    }
                }
                return Limit::Rate(above);
            }
            below = k;
        }
        Limit::Never
    }
}

#[derive(Debug, PartialEq)]
enum Limit {
    /// The multiple of the probe at which the evidence calls for the effect.
    Rate(f64),
    AlreadyCalledFor,
    Never,
}

/// One effect's probes: the final model simulated again with the effect.
struct Probe<'a> {
    simulation: &'a Simulation<'a>,
    state: &'a State,
    effect: Effect,
    evidence: Evidence,
}

/// A rate found, or why none was, with the isolated events `[OFF, ON]` per pixel-second
/// per Hz the last probe added (where one ran).
type Found = (Result<f64, String>, Option<[f64; 2]>);

impl Probe<'_> {
    /// The model's isolated events `[OFF, ON]` on the fit blocks added by the effect at
    /// `rate_hz`.
    fn added(&self, rate_hz: f64) -> Result<[f64; 2], String> {
        let mut params = self.state.model.params.clone();
        self.effect.set(&mut params, rate_hz);
        let observed = self
            .simulation
            .observe(&params, &self.state.masked)
            .map_err(|e| format!("the probe simulation failed: {e}"))?;
        // the final model's own isolated events are in the evidence's base already
        let g = self.simulation.geometry;
        let (with, _) = isolated_totals(&self.simulation.real, &observed, g, Subset::Fit);
        let base = self.evidence.base;
        Ok([with[2] - base[2], with[3] - base[3]])
    }

    fn per_hz(&self, added: [f64; 2], rate_hz: f64) -> [f64; 2] {
        added.map(|a| a / self.evidence.exposure / rate_hz)
    }

    /// The probe at [`PROBE_HZ`] scaled to a candidate, then candidates checked.
    fn search(&self) -> Found {
        let added = match self.added(PROBE_HZ) {
            Ok(a) => a,
            Err(e) => return (Err(e), None),
        };
        let mut isolated = self.per_hz(added, PROBE_HZ);
        let mut rate = match self.evidence.multiple(added, EVIDENCE_THRESHOLD + MARGIN_Z) {
            Limit::Rate(k) => k * PROBE_HZ,
            Limit::AlreadyCalledFor => return (Err(ALREADY.into()), Some(isolated)),
            Limit::Never => return (Err(NEVER.into()), Some(isolated)),
        };
        let mut checked = rate;
        // the lowest rate checked whose evidence reached the threshold, short of the margin
        let mut reached: Option<f64> = None;
        for _ in 0..CHECKS {
            let added = match self.added(rate) {
                Ok(a) => a,
                Err(e) => return (Err(e), Some(isolated)),
            };
            isolated = self.per_hz(added, rate);
            // at the margin, as the candidate was scaled: one recording's evidence there
            // leaves the threshold behind in about 95 % of such recordings
            if self
                .evidence
                .calls(added, 1.0, EVIDENCE_THRESHOLD + MARGIN_Z)
            {
                return (Ok(rate), Some(isolated));
            }
            checked = rate;
            let at_threshold = self.evidence.calls(added, 1.0, EVIDENCE_THRESHOLD);
            if at_threshold && reached.is_none() {
                reached = Some(rate);
            }
            rate *= next_step(at_threshold);
        }
        let why = match reached {
            Some(first) => format!(
                "called for from {first:.3} Hz on, but never {MARGIN_Z} standard errors above the threshold at any rate checked (up to {checked:.3} Hz), so not in about 95 % of such recordings"
            ),
            None => format!(
                "not called for at any rate checked (up to {checked:.3} Hz): its isolated events grow more slowly than its rate (a leak's first event comes one period after the recording starts)"
            ),
        };
        (Err(why), Some(isolated))
    }

    /// The effect's limit: the rate found (none without pixel-time to count isolated
    /// events), whether the loop tried it (`steps`), and for shot noise the most dark rate
    /// the quiet pixels allow (`known`).
    fn limit(&self, steps: &[Step], known: super::Known) -> NoiseLimit {
        let tried = steps
            .iter()
            .any(|s| s.effect == self.effect.name() && s.simulations > 0);
        let (found, isolated) = if self.evidence.exposure > 0.0 {
            self.search()
        } else {
            (
                Err("no reliable pixel-time to count isolated events".into()),
                None,
            )
        };
        NoiseLimit {
            called_for_above_hz: found.as_ref().ok().copied(),
            isolated_hz_per_hz: isolated,
            tried,
            why: found.err(),
            at_most_hz: self.at_most_hz(known),
        }
    }

    /// The most of the effect the recording allows whatever the scene hides: for shot
    /// noise the quiet pixels' isolated OFF events, for leak the event timing's drift.
    fn at_most_hz(&self, known: super::Known) -> Option<f64> {
        match self.effect {
            Effect::ShotNoise => at_most_dark_hz(
                known.quiet_off,
                self.simulation.geometry,
                &self.state.model.params,
            ),
            Effect::Leak => known.leak_drift?.at_most_hz(),
            _ => None,
        }
    }
}

const ALREADY: &str = "the recording's isolated events call for it beside the final model (it was tried and not kept, or the model changed since)";

const NEVER: &str = "no rate up to 10 kHz would: the probe added no isolated events the evidence counts (the scene supports them, or a leak slower than the recording is long fires none)";

/// The limits for the noise effects the final model lacks, and the assumption that states
/// them; `None` where the model has every one of them.
pub fn detect(
    simulation: &Simulation,
    state: &State,
    steps: &[Step],
    known: super::Known,
) -> Option<(NoiseDetection, String)> {
    let params = &state.model.params;
    let g = simulation.geometry;
    let (base, exposure) = isolated_totals(&simulation.real, &state.model.observed, g, Subset::Fit);
    let mut limits = BTreeMap::new();
    for (effect, key, score, relevant_hz) in NOISE {
        let in_model = match effect {
            Effect::ShotNoise => params.shot_noise_rate_hz,
            _ => params.leak_rate_hz,
        };
        if in_model.is_some_and(|r| r > 0.0) {
            continue;
        }
        let probe = Probe {
            simulation,
            state,
            effect,
            evidence: Evidence {
                base,
                exposure,
                score,
                relevant_hz,
            },
        };
        limits.insert(key.to_string(), probe.limit(steps, known));
    }
    if limits.is_empty() {
        return None;
    }
    let note = assumption(&limits);
    Some((
        NoiseDetection {
            limits,
            probe_hz: PROBE_HZ,
            meaning: MEANING,
        },
        note,
    ))
}

const MEANING: &str = "per noise effect the final model lacks: a rate (shot noise: its dark rate; leak: events per pixel-second) at which the recording's isolated events would have called for it in about 95 % of recordings like this one (its evidence at 5 standard errors, the rule that decides which effects are tried), found by simulating the final model again with the effect (first at probe_hz, its added isolated events scaled to 1.645 standard errors above the threshold, then at that rate, raised by the square root of 2 (where the threshold was reached) or 2 until its evidence reaches those 1.645 standard errors above the threshold); isolated_hz_per_hz: the isolated OFF and ON events the effect adds per pixel-second of the fit blocks per Hz, at the last rate simulated; tried: the effect was called for and tried, and not kept; a slower one does not show in this recording and is not determinable from it; at_most_hz: the most the recording allows whatever the scene hides: for shot noise the dark rate its isolated OFF events at quiet pixels allow (95 %: their exact Poisson upper end over an OFF share of 1/2 and the smallest brightness factor of the frames), for leak the rate at the frames' median DN the event timing's drift allows (the drift over the ON threshold plus 1.96 times its standard error, each 6.28 of its bootstrap's (the most a leak-free recording's drift reached on the coverage draws), and a share of the rate for how low the drift reads a leak, in quadrature; how often it held is said beside it)";

/// The assumption's last sentence: each limit's `at_most_hz` in words (empty where none
/// was measured).
fn allowed_whatever_the_scene_hides(limits: &BTreeMap<String, NoiseLimit>) -> String {
    let allowed: Vec<String> = limits
        .iter()
        .filter_map(|(key, l)| {
            let m = l.at_most_hz?;
            Some(format!(
                "{}: {}",
                name(key),
                at_most_in_words(effect_of(key), m)
            ))
        })
        .collect();
    if allowed.is_empty() {
        return String::new();
    }
    format!(". Whatever the scene hides, {}", allowed.join("; "))
}

/// The noise effect whose parameter is `key`.
fn effect_of(key: &str) -> Effect {
    NOISE
        .iter()
        .find(|(_, k, _, _)| *k == key)
        .map_or(Effect::ShotNoise, |(effect, ..)| *effect)
}

/// How the assumption names the noise effect of `key`.
fn name(key: &str) -> &'static str {
    match effect_of(key) {
        Effect::ShotNoise => "shot noise (dark rate)",
        _ => "leak",
    }
}

fn assumption(limits: &BTreeMap<String, NoiseLimit>) -> String {
    let parts: Vec<String> = limits
        .iter()
        .map(|(key, l)| {
            let (name, tried) = (name(key), if l.tried { "; tried and not kept" } else { "" });
            match (l.called_for_above_hz, &l.why) {
                (Some(r), _) => {
                    let [off, on] = l.isolated_hz_per_hz.unwrap_or([0.0; 2]);
                    format!(
                        "{name} at {} Hz (isolated OFF / ON events {off:.3} / {on:.3} per pixel-second per Hz{tried})",
                        significant(r)
                    )
                }
                (None, Some(why)) => format!("{name}: no rate ({why}{tried})"),
                (None, None) => format!("{name}: no rate{tried}"),
            }
        })
        .collect();
    let allowed = allowed_whatever_the_scene_hides(limits);
    format!(
        "noise the recording would show: {} would have made its isolated events call for the effect in about 95 % of such recordings (5 standard errors; the final model simulated again with the effect, {PROBE_HZ} Hz first, then the rate found, raised by the square root of 2 or 2 until its evidence is 1.645 standard errors above the threshold, at most {CHECKS} times); a noise effect not in the model may be present below that rate, which this recording does not determine{allowed}",
        parts.join("; ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limit(called_for_above_hz: Option<f64>, at_most_hz: Option<f64>) -> NoiseLimit {
        NoiseLimit {
            called_for_above_hz,
            isolated_hz_per_hz: Some([0.4, 0.5]),
            tried: false,
            why: called_for_above_hz.is_none().then(|| NEVER.to_string()),
            at_most_hz,
        }
    }

    /// The trigger's rates in one sentence, then what the recording allows whatever the
    /// scene hides, each with what measured it (the DAVIS346's fit: shot noise 0.0241 Hz
    /// with its quiet pixels' 0.00106 Hz, leak with no rate and the drift's 1.06 Hz).
    #[test]
    fn the_assumption_gives_the_trigger_s_rates_then_what_the_recording_allows() {
        let limits = BTreeMap::from([
            ("leak_rate_hz".to_string(), limit(None, Some(1.06))),
            (
                "shot_noise_rate_hz".to_string(),
                limit(Some(0.0241), Some(0.00106)),
            ),
        ]);
        let text = assumption(&limits);
        let (trigger, allowed) = text.split_once(". Whatever the scene hides, ").unwrap();
        assert!(
            trigger.contains("leak: no rate (no rate up to 10 kHz would")
                && trigger.contains("shot noise (dark rate) at 0.0241 Hz"),
            "{trigger}"
        );
        assert!(
            allowed.starts_with("leak: the event timing's drift allows at most 1.06 Hz")
                && allowed.contains(
                    "shot noise (dark rate): the quiet pixels' isolated OFF events allow at most 0.00106 Hz (95 %)"
                ),
            "{allowed}"
        );
        let without = BTreeMap::from([("leak_rate_hz".to_string(), limit(Some(0.7), None))]);
        assert!(!assumption(&without).contains("Whatever the scene hides"));
    }

    fn evidence(base: [f64; 4], score: Score) -> Evidence {
        Evidence {
            base,
            exposure: 1000.0,
            score,
            relevant_hz: 0.005,
        }
    }

    #[test]
    fn the_candidate_is_where_the_added_isolated_events_reach_the_evidence_threshold() {
        // recording and model both 1000 isolated events a polarity over 1000 pixel-seconds;
        // the probe adds 200 ON and 200 OFF; shot noise's score at k: 2 (200 k) /
        // sqrt(4000 + 400 k + 1) = 5 at 400 k = 5 sqrt(4001 + 400 k): k = 0.82254
        let base = [1000.0; 4];
        let Limit::Rate(k) = evidence(base, shot_noise::score).multiple([200.0; 2], 5.0) else {
            panic!("a rate")
        };
        let z = 400.0 * k / (4001.0 + 400.0 * k).sqrt();
        assert!((z - EVIDENCE_THRESHOLD).abs() < 1e-6, "{k} {z}");
        assert!((k - 0.82254).abs() < 1e-4, "{k}");
        // 1.645 standard errors above it (95 % of recordings call for it): k = 1.10744
        let Limit::Rate(k95) =
            evidence(base, shot_noise::score).multiple([200.0; 2], EVIDENCE_THRESHOLD + MARGIN_Z)
        else {
            panic!("a rate")
        };
        assert!((k95 - 1.10744).abs() < 1e-4, "{k95}");
        // the model 300 isolated events a polarity above the recording: the probe must
        // first make them up (1.5 probes), and the counts then match the first case's
        let Limit::Rate(k2) =
            evidence([700.0, 700.0, 1000.0, 1000.0], shot_noise::score).multiple([200.0; 2], 5.0)
        else {
            panic!("a rate")
        };
        assert!((k2 - (k + 1.5)).abs() < 1e-6, "{k2}");
    }

    #[test]
    fn leak_needs_isolated_on_events_beyond_off_ones_and_a_call_already_made_is_said() {
        let base = [1000.0; 4];
        // a probe adding OFF and ON alike (shot noise's signature) never calls for leak
        assert_eq!(
            evidence(base, leak::score).multiple([100.0, 100.0], 5.0),
            Limit::Never
        );
        // ON only: (100 k) / sqrt(4001 + 100 k) = 5 at k = 3.2901
        let Limit::Rate(k) = evidence(base, leak::score).multiple([0.0, 100.0], 5.0) else {
            panic!("a rate")
        };
        assert!(
            (100.0 * k / (4001.0 + 100.0 * k).sqrt() - 5.0).abs() < 1e-6,
            "{k}"
        );
        // the recording's ON excess already calls for it (400 / sqrt(4401) = 6.0)
        assert_eq!(
            evidence([1000.0, 1400.0, 1000.0, 1000.0], leak::score).multiple([0.0, 100.0], 5.0),
            Limit::AlreadyCalledFor
        );
        // no pixel-time: nothing to count
        let mut none = evidence(base, leak::score);
        none.exposure = 0.0;
        assert_eq!(none.multiple([0.0, 100.0], 5.0), Limit::Never);
    }
}
