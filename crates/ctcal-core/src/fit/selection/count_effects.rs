//! How far the fitted thresholds move with each count effect's parameter. The thresholds
//! are fitted to the event counts the model makes with its effects held at their fitted
//! values. A slow photoreceptor and a refractory period thin the events as a higher
//! threshold does, and leak and shot noise add events as a lower one does. So where a
//! polarity's events are mostly an effect's (noise or leak beside few scene events, a
//! photoreceptor that filters most of the scene), the threshold is fixed by the small
//! difference of two large counts: the effect's own uncertainty moves it, and a profile at
//! one value does not show that.
//!
//! Measured cases:
//! - Coverage draw 10023: 1.3 Hz of shot noise at 41 DN made about 80 % of the events.
//!   With the noise read 15 % high, ON was fitted at 4.42 [2.57, 7.60] for a true 0.74.
//! - Draw 13010 (DVS-Voltmeter, objects drifting at 10 px/s): 127,291 of the 127,304
//!   events were ON, nearly all a leak's. With the leak kept at 8.6 Hz [4.4, 17.0], ON was
//!   fitted at 0.98 [0.55, 1.77] for a true 0.47.
//!
//! Where the final model has such an effect and its thresholds are fitted, they are
//! profiled again with the effect's parameter at each end of its 95 % interval and at the
//! fitted value. It is the same profile each time, so that only the parameter differs, as
//! in [`super::frame_quality`]. A rate or a period whose interval reaches 0 is taken at 0.
//! A cutoff is taken at no lower than the searched range's 2 Hz, and as no filter at all
//! where its interval is open above; an open rate or period is not taken.
//!
//! A threshold that reaches an end of the profile's range at any of them is not determined
//! by the counts beside the effect. Otherwise the largest log change, read as 1.96
//! standard deviations, widens its interval in quadrature in ln C (as the method
//! systematic does). The effect's parameter is a nuisance parameter profiled over its
//! range, not fixed at its value (profile likelihood, e.g. Cox & Hinkley, *Theoretical
//! Statistics*, 1974, sec. 9.3).
//!
//! An effect the final model lacks can still be there below what the recording would have
//! shown: the fit's detections say how much shot noise or leak its isolated events would
//! not have called for, and which photoreceptor cutoff the bandwidth evidence would not
//! have ([`unseen`]). Such an effect moves the thresholds as a fitted one does, so the
//! thresholds are profiled again with it at that limit ([`check_unseen`]) and judged by the
//! same rule, the profile without it as the reference. A photoreceptor that no cutoff
//! detection bounds (a scene too slow or too dim for any cutoff to show) is not profiled:
//! the searched range's 2 Hz would withhold most thresholds on a prior no measurement
//! supports; `bandwidth_detection` says so.
//!
//! A first rule for shot noise that also withheld a threshold moving by more than a
//! factor 2 withheld two that covered the truth (draws 10006 and 10020: OFF 0.857 and
//! 0.475 for 0.795 and 0.489, moving to 1.71 and 1.20 at the noise's upper end). Widened,
//! they still cover. The other three effects were added on seeds 13001-17040
//! (`benches/coverage/fit-count-effects-2026-12-07`).

use super::super::Uncertain;
use super::super::effects::{Effect, leak, shot_noise};
use super::super::search::{Simulation, THRESHOLD_RANGE};
use super::State;
use super::method_systematic::widen_ln;
use crate::estimate::interval::z95;
use crate::sim::PixelParams;
use std::collections::BTreeMap;

/// The effects whose parameters trade against the thresholds in the counts, in the order
/// they are checked.
pub(super) const COUNT_EFFECTS: [Effect; 4] = [
    Effect::ShotNoise,
    Effect::Leak,
    Effect::Bandwidth,
    Effect::Refractory,
];

/// Where an effect's parameter is set for a profile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum End {
    At(f64),
    /// The effect switched off (a photoreceptor without a filter).
    Absent,
}

/// The thresholds (OFF, ON) profiled at the low end of an effect's parameter, at the fitted
/// value and at the high end (`None` for an end the interval leaves open).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Profiles {
    pub at: [Option<End>; 3],
    pub off: [Option<f64>; 3],
    pub on: [Option<f64>; 3],
}

/// What one effect's check found: the note for `assumptions`, and the thresholds it leaves
/// undetermined with why.
pub struct CountCheck {
    pub note: String,
    pub undetermined: Vec<(String, String)>,
}

/// Profiles the final model's thresholds at the ends of each count effect's interval
/// ([`COUNT_EFFECTS`]) and applies [`judge`]: one [`CountCheck`] for each effect the model has
/// with an interval. The profile at the fitted values is run once for all of them.
pub fn check(simulation: &Simulation, state: &mut State) -> Vec<CountCheck> {
    let mut fitted: Option<Option<PixelParams>> = None;
    let mut checks = Vec::new();
    for effect in COUNT_EFFECTS {
        let Some(ends) = ends_for(effect, state) else {
            continue;
        };
        let mid = fitted
            .get_or_insert_with(|| profiled(simulation, state, &state.model.params))
            .clone();
        let mut off = [None; 3];
        let mut on = [None; 3];
        for (k, end) in ends.iter().enumerate() {
            let found = match (k, end) {
                (1, _) => mid.clone(),
                (_, Some(end)) => {
                    let mut params = state.model.params.clone();
                    match *end {
                        End::At(v) => effect.set(&mut params, v),
                        End::Absent => effect.clear(&mut params),
                    }
                    profiled(simulation, state, &params)
                }
                (_, None) => None,
            };
            off[k] = found.as_ref().map(|p| p.ct_off);
            on[k] = found.as_ref().map(|p| p.ct_on);
        }
        let profiles = Profiles { at: ends, off, on };
        checks.push(judge(effect, &profiles, &mut state.uncertainty));
    }
    checks
}

/// An effect the final model lacks, set at the most of it the recording would not have
/// shown: a noise rate just below the one at which its isolated events would have called
/// for it ([`crate::fit::NoiseLimit`]; for shot noise also the most the quiet pixels allow),
/// a cutoff at white just above the one at which the bandwidth evidence would have
/// ([`crate::fit::BandwidthDetection`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unseen {
    pub effect: Effect,
    pub at: f64,
}

/// The count effects the final model lacks that this recording could hide, each at the
/// most it would not have shown ([`Unseen`]). A noise limit below the rate that matters
/// ([`leak::RELEVANT_HZ`], [`shot_noise::RELEVANT_HZ`]) is left out, as is an effect the
/// loop tried and did not keep (the look-alikes' reach covers those), and a photoreceptor
/// no cutoff detection bounds (named in the note of `bandwidth_detection`).
pub fn unseen(
    params: &PixelParams,
    noise: Option<&crate::fit::NoiseDetection>,
    bandwidth: Option<&crate::fit::BandwidthDetection>,
) -> Vec<Unseen> {
    let lacks = |effect: Effect| effect.value(params).is_none_or(|v| v <= 0.0);
    let usable = |v: &f64| v.is_finite() && *v > 0.0;
    let limit = |key: &str| noise?.limits.get(key).filter(|l| !l.tried);
    let mut found = Vec::new();
    if lacks(Effect::ShotNoise)
        && let Some(l) = limit("shot_noise_rate_hz")
        && let Some(at) = [l.called_for_above_hz, l.at_most_hz]
            .into_iter()
            .flatten()
            .filter(usable)
            .reduce(f64::min)
            .filter(|&at| at > shot_noise::RELEVANT_HZ)
    {
        found.push(Unseen {
            effect: Effect::ShotNoise,
            at,
        });
    }
    if lacks(Effect::Leak)
        && let Some(at) = limit("leak_rate_hz")
            .and_then(|l| l.called_for_above_hz)
            .filter(|at| usable(at) && *at > leak::RELEVANT_HZ)
    {
        found.push(Unseen {
            effect: Effect::Leak,
            at,
        });
    }
    if lacks(Effect::Bandwidth)
        && let Some(at) = bandwidth
            .filter(|b| !b.tried)
            .and_then(|b| b.called_for_below_hz)
            .filter(usable)
    {
        found.push(Unseen {
            effect: Effect::Bandwidth,
            at,
        });
    }
    found
}

/// Profiles the final model's thresholds again without each [`Unseen`] effect (as the
/// model is) and with it at the most the recording would not have shown, and applies the
/// same verdict as [`judge`]: what an effect the recording cannot rule out would do to the
/// thresholds is part of their intervals, or leaves them undetermined (coverage draws
/// 17002 and 17008, DVS-Voltmeter: a drift the model lacked made most ON events, and the
/// counts read ON 0.17 and 0.08 for 0.82 and 0.52, where a leak of 6.1 and 3.5 Hz would not
/// have shown in their isolated events).
pub fn check_unseen(
    simulation: &Simulation,
    state: &mut State,
    unseen: &[Unseen],
) -> Vec<CountCheck> {
    if unseen.is_empty() {
        return Vec::new();
    }
    let without = profiled(simulation, state, &state.model.params);
    unseen
        .iter()
        .map(|u| {
            let mut params = state.model.params.clone();
            u.effect.set(&mut params, u.at);
            let with = profiled(simulation, state, &params);
            let pair = |f: fn(&PixelParams) -> f64| [without.as_ref().map(f), with.as_ref().map(f)];
            judge_unseen(
                *u,
                [pair(|p| p.ct_off), pair(|p| p.ct_on)],
                &mut state.uncertainty,
            )
        })
        .collect()
}

/// [`judge`] for an [`Unseen`] effect: `values` (OFF, ON) profiled without it and with it.
pub fn judge_unseen(
    unseen: Unseen,
    values: [[Option<f64>; 2]; 2],
    uncertainty: &mut BTreeMap<String, Uncertain>,
) -> CountCheck {
    let words = words(unseen.effect);
    let (most, source) = match unseen.effect {
        Effect::Bandwidth => ("the lowest", "`bandwidth_detection`"),
        _ => ("the most", "`noise_detection`"),
    };
    let how = format!(
        "{} at {:.4}{}, {most} this recording would not have shown ({source}), and without it",
        words.subject, unseen.at, words.unit
    );
    let mut parts = Vec::new();
    let mut undetermined = Vec::new();
    for (pol, (key, name)) in [("ct_off", "OFF"), ("ct_on", "ON")].into_iter().enumerate() {
        let said = Said {
            key,
            name,
            lead: words.lead[pol],
            within: words.within[pol],
        };
        let profiled = Profiled {
            how: how.clone(),
            within: format!("unseen in this recording, {}", said.within),
            model_setting: format!("without {}", words.subject),
        };
        let (part, why) = judge_one(&said, &values[pol], 0, &profiled, uncertainty);
        parts.push(part);
        undetermined.extend(why.map(|why| (key.to_string(), why)));
    }
    let note = format!(
        "unseen {}: the final model has none; its thresholds profiled again without it and with {how} (each threshold without / with): {}; a threshold's log change, read as 1.96 standard deviations, widens its interval in quadrature, and one that reaches an end of the profile's range is not determined",
        words.check,
        parts.join("; ")
    );
    CountCheck { note, undetermined }
}

/// `params` with the thresholds profiled on the fit blocks (`None` where the profile fails).
fn profiled(simulation: &Simulation, state: &State, params: &PixelParams) -> Option<PixelParams> {
    simulation
        .profile(params, &state.masked, false)
        .ok()
        .map(|s| s.params)
}

/// The ends to profile `effect` at, where the model has it with an interval.
fn ends_for(effect: Effect, state: &State) -> Option<[Option<End>; 3]> {
    let value = effect.value(&state.model.params).filter(|v| *v > 0.0)?;
    let interval = state.uncertainty.get(effect.parameter()?)?.interval()?;
    Some(ends_of(effect, value, interval))
}

/// The low end, the fitted `value` and the high end of `effect`'s parameter to profile at
/// (see the module docs). An end that is not a finite number counts as open, and the ends
/// are kept on their sides of the value.
fn ends_of(effect: Effect, value: f64, [lo, hi]: [Option<f64>; 2]) -> [Option<End>; 3] {
    let lo = lo
        .filter(|v| v.is_finite())
        .unwrap_or(0.0)
        .clamp(0.0, value);
    let hi = hi.filter(|v| v.is_finite()).map(|hi| hi.max(value));
    match effect {
        Effect::Bandwidth => [
            Some(End::At(lo.max(effect.range(value).0).min(value))),
            Some(End::At(value)),
            Some(hi.map_or(End::Absent, End::At)),
        ],
        _ => [Some(End::At(lo)), Some(End::At(value)), hi.map(End::At)],
    }
}

/// How the notes and reasons name an effect's check.
struct Words {
    /// The check's name in `assumptions`.
    check: &'static str,
    /// The effect, as what the thresholds are profiled with.
    subject: &'static str,
    /// Its parameter, as "the fitted ...".
    quantity: &'static str,
    /// Its parameter, as what has an interval.
    parameter: &'static str,
    unit: &'static str,
    /// What a threshold at the profile's end says about the polarity's events (OFF, ON).
    lead: [&'static str; 2],
    /// What the effect may do within its interval, where a threshold reaches an end (OFF,
    /// ON).
    within: [&'static str; 2],
}

fn words(effect: Effect) -> Words {
    let both = |s: &'static str| [s, s];
    match effect {
        Effect::ShotNoise => Words {
            check: "noise-rate check",
            subject: "the shot noise",
            quantity: "rate",
            parameter: "the noise rate",
            unit: " Hz",
            lead: both("the events of this polarity are mostly the shot noise's"),
            within: both("the noise alone may make the recording's events of this polarity"),
        },
        // a leak fires ON events; its drift holds back the OFF ones
        Effect::Leak => Words {
            check: "leak-rate check",
            subject: "the leak",
            quantity: "rate",
            parameter: "the leak rate",
            unit: " Hz",
            lead: [
                "the leak's drift decides how many events of this polarity there are",
                "the events of this polarity are mostly the leak's",
            ],
            within: [
                "the leak's drift may hold back the recording's events of this polarity as much as any threshold does",
                "the leak alone may make the recording's events of this polarity",
            ],
        },
        Effect::Bandwidth => Words {
            check: "cutoff check",
            subject: "the photoreceptor's cutoff",
            quantity: "cutoff",
            parameter: "the cutoff",
            unit: " Hz",
            lead: both(
                "the photoreceptor's filter decides how many events of this polarity there are",
            ),
            within: both(
                "the filter may thin the recording's events of this polarity as much as any threshold does",
            ),
        },
        Effect::Refractory => Words {
            check: "refractory check",
            subject: "the refractory period",
            quantity: "period",
            parameter: "the refractory period",
            unit: " s",
            lead: both("the refractory period decides how many events of this polarity there are"),
            within: both(
                "the period may drop the recording's events of this polarity as much as any threshold does",
            ),
        },
        // not count effects: never checked, named by their own names
        Effect::Mismatch | Effect::TimestampJitter | Effect::HotPixels | Effect::Display => Words {
            check: effect.name(),
            subject: effect.name(),
            quantity: "value",
            parameter: effect.name(),
            unit: "",
            lead: both("this effect decides how many events of this polarity there are"),
            within: both(
                "the effect may change the recording's events of this polarity as much as any threshold does",
            ),
        },
    }
}

/// Widens or withholds each threshold by how far `profiles` move it (see the module docs).
pub fn judge(
    effect: Effect,
    profiles: &Profiles,
    uncertainty: &mut BTreeMap<String, Uncertain>,
) -> CountCheck {
    let words = words(effect);
    let mut parts = Vec::new();
    let mut undetermined = Vec::new();
    for (pol, (key, name, values)) in [
        ("ct_off", "OFF", profiles.off),
        ("ct_on", "ON", profiles.on),
    ]
    .into_iter()
    .enumerate()
    {
        let said = Said {
            key,
            name,
            lead: words.lead[pol],
            within: words.within[pol],
        };
        let profiled = Profiled {
            how: format!(
                "{} at its 95 % interval's ends and at the fitted {} ({})",
                words.parameter,
                words.quantity,
                end_list(profiles.at, words.unit)
            ),
            within: format!("within {}'s interval {}", words.parameter, said.within),
            model_setting: format!("at the fitted {}", words.quantity),
        };
        let (part, why) = judge_one(&said, &values, 1, &profiled, uncertainty);
        parts.push(part);
        undetermined.extend(why.map(|why| (key.to_string(), why)));
    }
    let note = format!(
        "{}: the final model's thresholds profiled again with {} at the low end of its 95 % interval, at the fitted {} and at the high end ({}): {}; a threshold's largest log change, read as 1.96 standard deviations, widens its interval in quadrature, and one that reaches an end of the profile's range is not determined",
        words.check,
        words.subject,
        words.quantity,
        end_list(profiles.at, words.unit),
        parts.join("; ")
    );
    CountCheck { note, undetermined }
}

/// One threshold as the check names it: `key` in `uncertainty`, `name` in the note, and
/// the polarity's words for why it is not determined.
struct Said<'a> {
    key: &'a str,
    name: &'a str,
    lead: &'a str,
    within: &'a str,
}

/// How a threshold was profiled, for its part of the note and its reason: `how` the
/// effect was set ("the leak rate at its 95 % interval's ends and at the fitted rate
/// (...)"), `within` what the effect may do there, `model_setting` where the model holds
/// it ("at the fitted rate").
struct Profiled {
    how: String,
    within: String,
    model_setting: String,
}

/// One threshold's verdict from its `values` profiled as `profiled` says, `values[mid]` at
/// the model's own setting: its part of the note, and why it is not determined where it
/// reaches an end of the profile's range; otherwise its interval widened by its largest
/// log change.
fn judge_one(
    said_as: &Said,
    values: &[Option<f64>],
    mid: usize,
    profiled: &Profiled,
    uncertainty: &mut BTreeMap<String, Uncertain>,
) -> (String, Option<String>) {
    let Said {
        key, name, lead, ..
    } = *said_as;
    let listed = values
        .iter()
        .map(|v| shown(*v))
        .collect::<Vec<_>>()
        .join(" / ");
    let said = format!("{name} {listed}");
    let Some(mid) = values[mid] else {
        return (
            format!("{said} (not profiled {})", profiled.model_setting),
            None,
        );
    };
    let at_bound = values
        .iter()
        .flatten()
        .any(|v| *v <= THRESHOLD_RANGE.0 * 1.0001 || *v >= THRESHOLD_RANGE.1 * 0.9999);
    if at_bound {
        let why = format!(
            "{lead}: profiled again with {}, {key} reads {listed}, reaching an end of the profile's range ({} to {}): {}, so the counts do not fix the threshold",
            profiled.how, THRESHOLD_RANGE.0, THRESHOLD_RANGE.1, profiled.within,
        );
        return (format!("{said}: not determined"), Some(why));
    }
    let ln_change = values
        .iter()
        .flatten()
        .map(|v| (v / mid).ln().abs())
        .fold(0.0, f64::max);
    let widened = widen_ln(uncertainty, key, ln_change / z95());
    let part = match widened {
        Some(w) if ln_change > 0.0 => format!("{said}: {w}"),
        _ => said,
    };
    (part, None)
}

/// A profiled threshold to four decimals, `-` where there is none.
fn shown(v: Option<f64>) -> String {
    v.map_or("-".to_string(), |v| format!("{v:.4}"))
}

/// The three ends, `open` where the interval leaves one open; the unit once at the end,
/// or after each value where one is the effect switched off.
fn end_list(at: [Option<End>; 3], unit: &str) -> String {
    let absent = at.contains(&Some(End::Absent));
    let list = at
        .iter()
        .map(|end| match end {
            Some(End::At(v)) if absent => format!("{v:.4}{unit}"),
            Some(End::At(v)) => format!("{v:.4}"),
            Some(End::Absent) => "none".to_string(),
            None => "open".to_string(),
        })
        .collect::<Vec<_>>()
        .join(" / ");
    if absent {
        list
    } else {
        format!("{list}{unit}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::{BandwidthDetection, NoiseDetection, NoiseLimit};

    fn uncertainty() -> BTreeMap<String, Uncertain> {
        BTreeMap::from([
            (
                "ct_off".to_string(),
                Uncertain::with_interval(0.40, None, [Some(0.30), Some(0.55)]),
            ),
            (
                "ct_on".to_string(),
                Uncertain::with_interval(4.42, None, [Some(2.57), Some(7.60)]),
            ),
        ])
    }

    /// OFF moves 0.38 / 0.40 / 0.44: ln(0.44 / 0.40) = 0.09531, a standard deviation of
    /// 0.04863 in ln C, so [0.30, 0.55] becomes 0.40 exp(-hypot(ln(0.40 / 0.30), 1.96 x
    /// 0.04863)) = 0.40 exp(-hypot(0.28768, 0.09531)) = 0.29542 and 0.40 exp(hypot(0.31845,
    /// 0.09531)) = 0.55773; ON moves 1.10 / 4.42 / 5.0 (draw 10023's kind): not determined.
    #[test]
    fn a_threshold_follows_the_noise_rate_into_its_interval_or_out_of_determination() {
        let mut u = uncertainty();
        let profiles = Profiles {
            at: [
                Some(End::At(1.39)),
                Some(End::At(1.51)),
                Some(End::At(1.89)),
            ],
            off: [Some(0.38), Some(0.40), Some(0.44)],
            on: [Some(1.10), Some(4.42), Some(5.0)],
        };
        let share = judge(Effect::ShotNoise, &profiles, &mut u);
        let [lo, hi] = u["ct_off"].ci95.unwrap();
        assert!((lo.unwrap() - 0.29542).abs() < 1e-4, "{lo:?}");
        assert!((hi.unwrap() - 0.55773).abs() < 1e-4, "{hi:?}");
        assert_eq!(share.undetermined.len(), 1);
        assert_eq!(share.undetermined[0].0, "ct_on");
        assert!(share.undetermined[0].1.contains("1.1000 / 4.4200 / 5.0000"));
        assert!(share.note.contains("1.3900 / 1.5100 / 1.8900 Hz"));
        // a factor 2.49 inside the range (draw 10020's OFF): widened by ln 2.49 = 0.91229
        // in quadrature, [0.30, 0.55] about 0.40 -> upper end 0.40 exp(hypot(0.31845,
        // 0.91229)) = 1.0512
        let mut u = uncertainty();
        let far = Profiles {
            at: [Some(End::At(0.1)), Some(End::At(0.2)), Some(End::At(0.4))],
            off: [Some(0.40), Some(0.40), Some(0.996)],
            on: [Some(4.42), Some(4.42), Some(4.42)],
        };
        assert!(
            judge(Effect::ShotNoise, &far, &mut u)
                .undetermined
                .is_empty()
        );
        let [_, hi] = u["ct_off"].ci95.unwrap();
        assert!((hi.unwrap() - 1.0512).abs() < 1e-3, "{hi:?}");
        // a threshold the noise barely moves keeps its interval within rounding
        let mut u = uncertainty();
        let steady = Profiles {
            at: [Some(End::At(0.0)), Some(End::At(0.2)), None],
            off: [Some(0.40), Some(0.40), None],
            on: [Some(4.30), Some(4.42), None],
        };
        let share = judge(Effect::ShotNoise, &steady, &mut u);
        assert!(share.undetermined.is_empty());
        assert_eq!(u["ct_off"].ci95, Some([Some(0.30), Some(0.55)]));
        let [lo, _] = u["ct_on"].ci95.unwrap();
        assert!(lo.unwrap() < 2.57, "{lo:?}");
        assert!(share.note.contains("0.0000 / 0.2000 / open Hz"));
    }

    /// A cutoff of 250 Hz whose interval reaches 0 and is open above (as draw 16001's
    /// did), profiled from the searched range's bottom (2 Hz) to no filter at all. Here OFF
    /// reaches the profile's lower end at 2 Hz (the filter leaves too few events for any
    /// threshold): not determined. ON moves 3.0 / 4.42 / 4.6: ln(4.42 / 3.0) = 0.38752
    /// in quadrature with ln(7.60 / 4.42) = 0.54201 above: 4.42 exp(0.66631) = 8.6058.
    #[test]
    fn a_cutoff_open_above_is_profiled_without_a_filter_and_named_so() {
        let mut u = uncertainty();
        let profiles = Profiles {
            at: [Some(End::At(2.0)), Some(End::At(250.0)), Some(End::Absent)],
            off: [Some(0.02), Some(0.40), Some(0.42)],
            on: [Some(3.0), Some(4.42), Some(4.6)],
        };
        let share = judge(Effect::Bandwidth, &profiles, &mut u);
        assert!(share.note.starts_with("cutoff check:"), "{}", share.note);
        assert!(
            share.note.contains("(2.0000 Hz / 250.0000 Hz / none)"),
            "{}",
            share.note
        );
        assert_eq!(share.undetermined.len(), 1);
        let (key, why) = &share.undetermined[0];
        assert_eq!(key, "ct_off");
        assert!(
            why.starts_with("the photoreceptor's filter decides"),
            "{why}"
        );
        assert!(
            why.contains("within the cutoff's interval the filter may thin"),
            "{why}"
        );
        let [_, hi] = u["ct_on"].ci95.unwrap();
        assert!((hi.unwrap() - 8.6058).abs() < 1e-3, "{hi:?}");
    }

    #[test]
    fn the_ends_profiled_are_the_intervals_on_their_sides_of_the_value() {
        let at = |v| Some(End::At(v));
        // a rate from 0 (the effect off) to open above: its open end is not taken
        assert_eq!(
            ends_of(Effect::Leak, 8.6, [Some(0.0), None]),
            [at(0.0), at(8.6), None]
        );
        assert_eq!(
            ends_of(Effect::Leak, 8.6, [Some(4.36), Some(17.0)]),
            [at(4.36), at(8.6), at(17.0)]
        );
        // a cutoff from below the searched range to open above: 2 Hz to no filter
        assert_eq!(
            ends_of(Effect::Bandwidth, 250.0, [Some(0.0), None]),
            [at(2.0), at(250.0), Some(End::Absent)]
        );
        // ends that are not numbers are open; ends on the wrong side stop at the value
        assert_eq!(
            ends_of(Effect::Refractory, 0.01, [Some(f64::NAN), Some(f64::NAN)]),
            [at(0.0), at(0.01), None]
        );
        assert_eq!(
            ends_of(Effect::ShotNoise, 1.0, [Some(1.5), Some(0.5)]),
            [at(1.0), at(1.0), at(1.0)]
        );
        assert_eq!(
            ends_of(Effect::Bandwidth, 1.5, [Some(0.5), Some(3.0)]),
            [at(1.5), at(1.5), at(3.0)]
        );
    }

    fn noise_limit(called: Option<f64>, at_most: Option<f64>, tried: bool) -> NoiseLimit {
        NoiseLimit {
            called_for_above_hz: called,
            isolated_hz_per_hz: None,
            tried,
            why: None,
            at_most_hz: at_most,
        }
    }

    fn detections(
        shot: NoiseLimit,
        leak: NoiseLimit,
        cutoff: Option<f64>,
    ) -> (NoiseDetection, BandwidthDetection) {
        let noise = NoiseDetection {
            limits: BTreeMap::from([
                ("shot_noise_rate_hz".to_string(), shot),
                ("leak_rate_hz".to_string(), leak),
            ]),
            probe_hz: 1.0,
            meaning: "",
        };
        let bandwidth = BandwidthDetection {
            called_for_below_hz: cutoff,
            evidence: Vec::new(),
            recording_evidence: None,
            simulations: 0,
            tried: false,
            why: None,
            meaning: "",
        };
        (noise, bandwidth)
    }

    /// Shot noise at the lower of its two limits (the rate its isolated events would call
    /// for it at, the most the quiet pixels allow), a leak at its limit, a cutoff at its
    /// limit; none for an effect the model has, one tried and not kept, or a limit below
    /// the rate that matters.
    #[test]
    fn unseen_effects_are_the_ones_the_model_lacks_at_their_detection_limits() {
        let ideal = PixelParams::ideal(0.3, 0.4);
        let (noise, bandwidth) = detections(
            noise_limit(Some(1.39), Some(0.0175), false),
            noise_limit(Some(6.14), None, false),
            Some(136.9),
        );
        let found = unseen(&ideal, Some(&noise), Some(&bandwidth));
        let at = |effect| found.iter().find(|u| u.effect == effect).map(|u| u.at);
        assert_eq!(at(Effect::ShotNoise), Some(0.0175));
        assert_eq!(at(Effect::Leak), Some(6.14));
        assert_eq!(at(Effect::Bandwidth), Some(136.9));
        assert_eq!(found.len(), 3);
        // a model with shot noise and a cutoff: only the leak is unseen
        let mut model = ideal.clone();
        model.shot_noise_rate_hz = Some(0.5);
        model.cutoff_hz = Some(300.0);
        let found = unseen(&model, Some(&noise), Some(&bandwidth));
        assert_eq!(
            found,
            vec![Unseen {
                effect: Effect::Leak,
                at: 6.14
            }]
        );
        // tried and not kept, below what matters, not a number, or no limit: none
        let (noise, mut bandwidth) = detections(
            noise_limit(Some(1.39), Some(0.002), false),
            noise_limit(Some(6.14), None, true),
            Some(f64::NAN),
        );
        assert!(unseen(&ideal, Some(&noise), Some(&bandwidth)).is_empty());
        bandwidth.called_for_below_hz = None;
        assert!(unseen(&ideal, None, Some(&bandwidth)).is_empty());
        assert!(unseen(&ideal, None, None).is_empty());
    }

    /// A leak of 6.1429 Hz the recording would not have shown: OFF does not move (its
    /// interval stays), ON moves 4.42 -> 4.9: ln(4.9 / 4.42) = 0.10310 in quadrature with
    /// ln(4.42 / 2.57) = 0.54223 below and ln(7.60 / 4.42) = 0.54201 above: 4.42
    /// exp(-0.55195) = 2.54516 and 4.42 exp(0.55173) = 7.67422. With ON reaching the
    /// profile's upper end (5.0) it is not determined, with why.
    #[test]
    fn an_unseen_leak_widens_or_withholds_the_threshold_it_moves() {
        let leak = Unseen {
            effect: Effect::Leak,
            at: 6.1429,
        };
        let mut u = uncertainty();
        let check = judge_unseen(
            leak,
            [[Some(0.40), Some(0.40)], [Some(4.42), Some(4.9)]],
            &mut u,
        );
        assert!(check.undetermined.is_empty());
        assert_eq!(u["ct_off"].ci95, Some([Some(0.30), Some(0.55)]));
        let [lo, hi] = u["ct_on"].ci95.unwrap();
        assert!((lo.unwrap() - 2.54516).abs() < 1e-4, "{lo:?}");
        assert!((hi.unwrap() - 7.67422).abs() < 1e-4, "{hi:?}");
        assert!(
            check.note.starts_with(
                "unseen leak-rate check: the final model has none; its thresholds profiled again without it and with the leak at 6.1429 Hz, the most this recording would not have shown (`noise_detection`), and without it (each threshold without / with): OFF 0.4000 / 0.4000; ON 4.4200 / 4.9000: ct_on"
            ),
            "{}",
            check.note
        );
        let mut u = uncertainty();
        let check = judge_unseen(
            leak,
            [[Some(0.40), Some(0.40)], [Some(0.17), Some(5.0)]],
            &mut u,
        );
        assert_eq!(check.undetermined.len(), 1);
        let (key, why) = &check.undetermined[0];
        assert_eq!(key, "ct_on");
        assert!(
            why.starts_with("the events of this polarity are mostly the leak's: profiled again with the leak at 6.1429 Hz"),
            "{why}"
        );
        assert!(
            why.ends_with("unseen in this recording, the leak alone may make the recording's events of this polarity, so the counts do not fix the threshold"),
            "{why}"
        );
    }

    /// A leak fires ON events and holds back OFF ones: each polarity's reason says which.
    #[test]
    fn a_leak_names_what_it_does_to_each_polarity() {
        let mut u = uncertainty();
        let profiles = Profiles {
            at: [Some(End::At(4.4)), Some(End::At(8.6)), Some(End::At(17.0))],
            off: [Some(0.40), Some(0.40), Some(5.0)],
            on: [Some(0.07), Some(4.42), Some(5.0)],
        };
        let check = judge(Effect::Leak, &profiles, &mut u);
        let why: BTreeMap<_, _> = check.undetermined.into_iter().collect();
        assert!(why["ct_on"].starts_with("the events of this polarity are mostly the leak's"));
        assert!(
            why["ct_off"].starts_with("the leak's drift decides"),
            "{}",
            why["ct_off"]
        );
        assert!(check.note.starts_with("leak-rate check:"), "{}", check.note);
    }
}
