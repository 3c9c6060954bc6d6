//! What photoreceptor bandwidth a fit with frames could have seen: where the final model has
//! no cutoff, the highest cutoff (at white, under v2e's law that the cutoff scales with the
//! photocurrent, [`crate::fit::effects::bandwidth`]) at which a recording of this scene would
//! have made the bandwidth evidence call for the effect in about 95 % of such recordings. A
//! slower photoreceptor (a lower cutoff) would have been tried; a faster one may be present
//! and is not determinable from this recording.
//!
//! Bandwidth thins and delays the events of fast changes in the dark, so whether it shows
//! depends on the scene (how dark, how fast its changes): it is measured by injection, not
//! assumed. The final model is simulated with a cutoff and an independent seed (a recording
//! the final model describes but for the cutoff) and compared with the final model as the
//! recording is; the evidence is the effect's own rule (count deficit and lag that grow in
//! the dark, [`crate::fit::effects::bandwidth::evidence`]) with each standard error held at
//! least at the real recording's beside the final model
//! ([`crate::fit::effects::bandwidth::NoiseFloor`]), which holds what the model misses: a
//! simulated recording scatters less about the model than a real one. The cutoff calls for
//! the effect where that evidence reaches [`EVIDENCE_THRESHOLD`] plus [`MARGIN_Z`] standard
//! errors (the evidence of one recording scatters by about one standard error, so chance
//! leaves it below the threshold in about 5 %) and matters (the rule's relevance). Cutoffs
//! are scanned down from the highest the fit searches, [`PER_DECADE`] a decade, to its
//! lowest ([`highest_calling`]); between the first that calls for it and the one before,
//! [`BISECTIONS`] halvings in the logarithm. Where the recording has nothing the evidence
//! reads (too few count cells for a slope, and no lag in any intensity bin) there is no
//! noise to judge a signal against, and no limit; nor where the final model holds a
//! refractory period, bandwidth's look-alike ([`super::alternatives`]), which takes up a
//! cutoff's signal when it is fitted (the limit is read against a model the recording would
//! have moved).
//!
//! Where the frames' times were aligned to the recording's events
//! ([`crate::estimate::align`]: the shift within a quarter of a frame interval at which the
//! events agree best with the frames), a lag every pixel shares was taken up by that shift:
//! a photoreceptor that lags the whole scene alike looks like frames stamped late. Each
//! simulated recording is aligned the same way before it is compared: moved earlier by the
//! lag its paired events show, the median over the intensity bins weighted by their events,
//! within the alignment's reach. Without it the probes read a lag the recording could not
//! show: coverage draws 10006 (a 16 Hz cutoff at white, frames shifted +6.6 ms) and 10022
//! (241 Hz in a 16 DN scene, +3.2 ms) were given limits of 77 and 500 Hz, above their own
//! cutoffs, which the fit had not found.

use super::super::effects::bandwidth::{self, NoiseFloor};
use super::super::effects::{Context, EVIDENCE_THRESHOLD, Effect, Evidence};
use super::super::observe::lag::BinDelay;
use super::super::observe::{Observed, Subset};
use super::super::search::Simulation;
use super::super::{BandwidthDetection, Step};
use super::noise_detection::MARGIN_Z;
use crate::estimate::EstimateError;
use crate::events::{EventChunk, TimeUs};

/// Cutoffs scanned per decade.
pub const PER_DECADE: f64 = 4.0;

/// Halvings of the logarithmic step between the last cutoff that did not call for the
/// effect and the first that did: a factor of 10^(1/16) = 1.15.
pub const BISECTIONS: usize = 2;

/// Added to the fit's seed for the simulated recordings, so that their noise (mismatch,
/// shot noise, leak phases) is drawn independently of the model's.
const RECORDING_SEED: u64 = 0x0062_616e_6477_6964;

/// The bandwidth detection of the final model, and the assumption that states it; `None`
/// where the model has a cutoff.
pub fn detect(
    simulation: &Simulation,
    context: &Context,
    masked: &[bool],
    steps: &[Step],
    frames_aligned: bool,
) -> Option<(BandwidthDetection, String)> {
    if context.model.cutoff_hz.is_some() {
        return None;
    }
    let tried = steps
        .iter()
        .any(|s| s.effect == Effect::Bandwidth.name() && s.simulations > 0);
    let own = bandwidth::evidence(context);
    let floor = bandwidth::noise_of(context);
    let before = simulation.count.get();
    let look_alike = Effect::Refractory
        .value(context.model)
        .is_some_and(|r| r > 0.0);
    let (limit, evidence) = if look_alike {
        (Err(LOOK_ALIKE.to_string()), Vec::new())
    } else if floor.reads_nothing() {
        (Err(NOTHING.to_string()), Vec::new())
    } else if own.calls_for() {
        (Err(ALREADY.to_string()), Vec::new())
    } else {
        let quarter_us = (simulation.geometry.frame_interval_s * 0.25e6).round() as TimeUs;
        let probes = Probes {
            simulation,
            context,
            masked,
            floor,
            alignment_reach_us: frames_aligned.then_some(quarter_us),
        };
        probes.scan()
    };
    let (called_for_below_hz, why) = match limit {
        Ok(Limit::Below(hz)) => (Some(hz), None),
        Ok(Limit::AtLeast(hz)) => (Some(hz), Some(format!("{AT_LEAST} ({hz:.0} Hz)"))),
        Err(why) => (None, Some(why)),
    };
    let detection = BandwidthDetection {
        called_for_below_hz,
        evidence,
        recording_evidence: (!floor.reads_nothing()).then_some(own.score),
        simulations: simulation.count.get() - before,
        tried,
        why,
        meaning: MEANING,
    };
    let note = assumption(&detection);
    Some((detection, note))
}

/// What the scan found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Limit {
    /// The highest cutoff that calls for the effect, below one that does not.
    Below(f64),
    /// The highest cutoff scanned already calls for it: the limit is that or higher.
    AtLeast(f64),
}

/// The highest cutoff of `range` (Hz, low to high) at which `calls` holds: scanned down
/// from the top, [`PER_DECADE`] a decade, to the first that calls, then [`BISECTIONS`]
/// halvings in the logarithm between it and the one above; `None` where none down to the
/// bottom does. The evidence rises as the cutoff falls, so the first that calls from the
/// top is the limit.
pub fn highest_calling<E>(
    range: (f64, f64),
    mut calls: impl FnMut(f64) -> Result<bool, E>,
) -> Result<Option<Limit>, E> {
    let (lowest, highest) = range;
    let step = 10f64.powf(1.0 / PER_DECADE);
    let mut above: Option<f64> = None;
    let mut cutoff = highest;
    while cutoff >= lowest * (1.0 - 1e-9) {
        if calls(cutoff)? {
            let Some(mut not) = above else {
                return Ok(Some(Limit::AtLeast(cutoff)));
            };
            let mut called = cutoff;
            for _ in 0..BISECTIONS {
                let mid = (called * not).sqrt();
                if calls(mid)? {
                    called = mid;
                } else {
                    not = mid;
                }
            }
            return Ok(Some(Limit::Below(called)));
        }
        above = Some(cutoff);
        cutoff /= step;
    }
    Ok(None)
}

/// Simulated recordings with a cutoff, against the final model.
struct Probes<'a> {
    simulation: &'a Simulation<'a>,
    context: &'a Context<'a>,
    masked: &'a [bool],
    floor: NoiseFloor,
    /// Where the frames' times were aligned to the recording's events: how far the
    /// alignment reaches (a quarter of the frame interval), microseconds.
    alignment_reach_us: Option<TimeUs>,
}

/// `[cutoff_hz, evidence]` of every cutoff simulated, in the order tried.
type Tried = Vec<[f64; 2]>;

impl Probes<'_> {
    /// The final model's events (the model's seed), compared with every probe.
    fn model_events(&self) -> Result<EventChunk, EstimateError> {
        self.simulation
            .events_of(self.context.model, self.simulation.seed)
    }

    /// The evidence of a recording with `cutoff_hz` against the final model.
    fn evidence(&self, model: &EventChunk, cutoff_hz: f64) -> Result<Evidence, EstimateError> {
        let g = self.simulation.geometry;
        let mut params = self.context.model.clone();
        Effect::Bandwidth.set(&mut params, cutoff_hz);
        let seed = self.simulation.seed.wrapping_add(RECORDING_SEED);
        let mut recording = self.simulation.events_of(&params, seed)?;
        if let Some(reach_us) = self.alignment_reach_us {
            let keys = Observed::lag_keys(&recording, g);
            let paired = Observed::paired(model, g, self.masked, &keys);
            let lag_us = alignment_shift_us(&paired.delay_of(g, Subset::Fit), reach_us);
            let step = self.simulation.grid.map_or(1, |(period, _)| period.max(1));
            let shift = (lag_us as f64 / step as f64).round() as TimeUs * step;
            for t in &mut recording.t {
                *t -= shift;
            }
        }
        let real = Observed::new(&recording, g, self.masked);
        let keys = Observed::lag_keys(&recording, g);
        let sim = Observed::paired(model, g, self.masked, &keys);
        let context = Context {
            real: &real,
            sim: &sim,
            ..*self.context
        };
        Ok(bandwidth::evidence_over(&context, &self.floor))
    }

    /// The highest cutoff that calls for the effect, or why there is none, with every
    /// cutoff tried.
    fn scan(&self) -> (Result<Limit, String>, Tried) {
        let mut tried = Vec::new();
        let range = Effect::Bandwidth.range(1.0);
        let found = self.model_events().and_then(|model| {
            highest_calling(range, |cutoff| {
                let e = self.evidence(&model, cutoff)?;
                tried.push([cutoff, e.score]);
                Ok(e.relevant && e.score >= EVIDENCE_THRESHOLD + MARGIN_Z)
            })
        });
        let found = match found {
            Ok(Some(limit)) => Ok(limit),
            Ok(None) => Err(format!(
                "no cutoff from {:.0} down to {:.0} Hz at white would: the scene's changes are too slow, or its pixels too bright, for the photoreceptor's filter to thin or delay its events beyond the recording's noise",
                range.1, range.0
            )),
            Err(e) => Err(format!(
                "a simulation with a cutoff failed: {} ({})",
                e.problem, e.fix
            )),
        };
        (found, tried)
    }
}

/// The shift the frame-time alignment takes from a recording whose events lag a model's
/// by `delays` (per intensity bin, [`Observed::delay_of`]), microseconds: the median of the
/// bins' lags weighted by their paired events (the alignment weighs every event alike),
/// within `reach_us` either way; 0 where no bin has a lag.
fn alignment_shift_us(delays: &[Option<BinDelay>], reach_us: TimeUs) -> TimeUs {
    let mut lags: Vec<(f64, u32)> = delays
        .iter()
        .flatten()
        .map(|d| (d.common.median_s, d.common.events))
        .collect();
    lags.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: u64 = lags.iter().map(|l| l.1 as u64).sum();
    let mut below = 0u64;
    let median_s = lags.iter().find_map(|&(lag, events)| {
        below += events as u64;
        (2 * below >= total).then_some(lag)
    });
    median_s.map_or(0, |lag| {
        ((lag * 1e6).round() as TimeUs).clamp(-reach_us, reach_us)
    })
}

const LOOK_ALIKE: &str = "the final model holds a refractory period, bandwidth's look-alike (both thin the events of fast changes): a cutoff may stand in its place, its signal taken up by the period, so the recording does not bound it (coverage draw 9007: a true 69 Hz cutoff fitted as a refractory period, where a limit read against that model said 200 Hz)";

const NOTHING: &str = "the recording has nothing the bandwidth evidence reads (too few count cells of different intensity for a slope, and no intensity bin with enough paired ON and OFF events for a lag): no noise to judge a cutoff's signal against";

const AT_LEAST: &str =
    "the highest cutoff the fit searches already calls for the effect: the limit is that or higher";

const ALREADY: &str = "the recording's own evidence calls for bandwidth beside the final model (it was tried and not kept, or an effect that explains the same residual was preferred): a cutoff may be present; the recording does not determine it";

const MEANING: &str = "where the final model has no photoreceptor cutoff: called_for_below_hz, the highest cutoff at white (v2e's law: the cutoff scales with DN + 20) at which a recording of this scene would have made the bandwidth evidence call for the effect in about 95 % of such recordings (5 + 1.645 standard errors), found by simulating the final model with the cutoff and an independent seed and comparing it with the final model as the recording is (moved in time as the frames' alignment moved the recording's, where it did: a lag every pixel shares is taken up by it), each standard error held at least at the real recording's beside the final model; cutoffs scanned down from 5 kHz (the highest the fit searches), four a decade, then two bisections; evidence: [cutoff_hz, standard errors] of every cutoff simulated; recording_evidence: the recording's own bandwidth evidence beside the final model (standard errors; null where it has nothing the evidence reads); simulations: how many this took (the final model once, then one per cutoff); tried: the effect was called for and tried, and not kept; a faster photoreceptor (a higher cutoff) may be present and is not determinable from this recording";

fn assumption(d: &BandwidthDetection) -> String {
    let tried = if d.tried { "; tried and not kept" } else { "" };
    match (d.called_for_below_hz, &d.why) {
        (Some(hz), _) => format!(
            "photoreceptor bandwidth the recording would show: a cutoff at white of {hz:.0} Hz or lower would have made the bandwidth evidence call for the effect in about 95 % of recordings of this scene (the final model simulated with the cutoff and an independent seed, {} simulations; the recording's own evidence {}{tried}{}); a faster photoreceptor may be present, which this recording does not determine",
            d.simulations,
            d.recording_evidence
                .map_or("not read".to_string(), |z| format!(
                    "{z:.1} standard errors"
                )),
            d.why.as_ref().map_or(String::new(), |w| format!("; {w}")),
        ),
        (None, Some(why)) => format!("photoreceptor bandwidth: no detection limit ({why}{tried})"),
        (None, None) => format!("photoreceptor bandwidth: no detection limit{tried}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::observe::lag::BinLag;

    fn delay(median_ms: f64, events: u32) -> Option<BinDelay> {
        Some(BinDelay {
            common: BinLag {
                median_s: median_ms * 1e-3,
                standard_error_s: 1e-4,
                events,
            },
            off_s: median_ms * 1e-3,
            on_s: median_ms * 1e-3,
        })
    }

    /// Lags of 9, 4 and 1 ms in bins of 100, 300 and 250 paired events: the weighted
    /// median is the 4 ms bin's (100 + 300 of 650 events reach half); within a reach of
    /// 3 ms it is 3 ms; no bin, no shift.
    #[test]
    fn the_alignment_takes_the_event_weighted_median_lag_within_its_reach() {
        let delays = [delay(9.0, 100), None, delay(4.0, 300), delay(1.0, 250)];
        assert_eq!(alignment_shift_us(&delays, 10_000), 4_000);
        assert_eq!(alignment_shift_us(&delays, 3_000), 3_000);
        let ahead = [delay(-5.0, 10), delay(2.0, 5)];
        assert_eq!(alignment_shift_us(&ahead, 10_000), -5_000);
        assert_eq!(alignment_shift_us(&[None, None], 10_000), 0);
    }

    /// The scan against an evidence that calls for the effect at and below `limit`,
    /// recording every cutoff tried.
    fn scan(limit: f64) -> (Option<Limit>, Vec<f64>) {
        let mut tried = Vec::new();
        let found = highest_calling::<()>((2.0, 5000.0), |c| {
            tried.push(c);
            Ok(c <= limit)
        })
        .unwrap();
        (found, tried)
    }

    #[test]
    fn the_scan_steps_down_four_a_decade_then_bisects_twice_towards_the_limit() {
        // 5000, 2812, 1581, 889, 500, 281, 158.1 (not at or below 150), 88.9 (below): then
        // sqrt(88.9 x 158.1) = 118.6 (below), sqrt(118.6 x 158.1) = 136.9 (below)
        let (found, tried) = scan(150.0);
        let Some(Limit::Below(hz)) = found else {
            panic!("{found:?}")
        };
        assert_eq!(tried.len(), 8 + BISECTIONS, "{tried:?}");
        assert!((tried[7] - 5000.0 / 10f64.powf(7.0 / 4.0)).abs() < 1e-9);
        assert!(
            (hz - 5000.0 * 10f64.powf(-7.0 / 4.0 + 3.0 / 16.0)).abs() < 1e-9,
            "{hz}"
        );
        assert!(hz <= 150.0 && hz > 150.0 / 10f64.powf(1.0 / 16.0), "{hz}");
    }

    #[test]
    fn a_top_that_already_calls_is_a_lower_bound_and_none_down_to_the_bottom_is_none() {
        let (found, tried) = scan(1e6);
        assert_eq!(found, Some(Limit::AtLeast(5000.0)));
        assert_eq!(tried, [5000.0]);
        // 5000 down to 2 Hz four a decade: 14 cutoffs, the last 2.81 Hz
        let (found, tried) = scan(1.0);
        assert_eq!(found, None);
        assert_eq!(tried.len(), 14, "{tried:?}");
        assert!((tried[13] - 5000.0 / 10f64.powf(13.0 / 4.0)).abs() < 1e-9);
        // an error stops the scan and is passed on
        let failed = highest_calling(
            (2.0, 5000.0),
            |c| if c < 1000.0 { Err("x") } else { Ok(false) },
        );
        assert_eq!(failed, Err("x"));
    }
}
