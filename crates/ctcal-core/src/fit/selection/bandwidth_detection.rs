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
//! are scanned down from [`HIGHEST_HZ`], [`PER_DECADE`] a decade, to the effect's lowest;
//! between the first that calls for it and the one before, [`BISECTIONS`] halvings in the
//! logarithm.

use super::super::effects::bandwidth::{self, NoiseFloor};
use super::super::effects::{Context, EVIDENCE_THRESHOLD, Effect, Evidence};
use super::super::observe::Observed;
use super::super::search::Simulation;
use super::super::{BandwidthDetection, Step};
use super::noise_detection::MARGIN_Z;
use crate::estimate::EstimateError;
use crate::events::EventChunk;

/// The highest cutoff at white tried, Hz: at 2 kHz the filter's time constant is under
/// 0.3 ms at 20 DN, below a frame interval's resolution of the lag.
pub const HIGHEST_HZ: f64 = 2000.0;

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
) -> Option<(BandwidthDetection, String)> {
    if context.model.cutoff_hz.is_some() {
        return None;
    }
    let tried = steps
        .iter()
        .any(|s| s.effect == Effect::Bandwidth.name() && s.simulations > 0);
    let own = bandwidth::evidence(context);
    let (limit, evidence) = if own.calls_for() {
        (Err(ALREADY.to_string()), Vec::new())
    } else {
        let probes = Probes {
            simulation,
            context,
            masked,
            floor: bandwidth::noise_of(context),
        };
        probes.scan()
    };
    let detection = BandwidthDetection {
        called_for_below_hz: limit.as_ref().ok().copied(),
        evidence,
        recording_evidence: own.score,
        tried,
        why: limit.err(),
        meaning: MEANING,
    };
    let note = assumption(&detection);
    Some((detection, note))
}

/// Simulated recordings with a cutoff, against the final model.
struct Probes<'a> {
    simulation: &'a Simulation<'a>,
    context: &'a Context<'a>,
    masked: &'a [bool],
    floor: NoiseFloor,
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
        let recording = self.simulation.events_of(&params, seed)?;
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
    fn scan(&self) -> (Result<f64, String>, Tried) {
        let mut tried = Vec::new();
        let found = self.search(&mut tried).unwrap_or_else(|e| {
            Err(format!(
                "a simulation with a cutoff failed: {} ({})",
                e.problem, e.fix
            ))
        });
        (found, tried)
    }

    fn search(&self, tried: &mut Tried) -> Result<Result<f64, String>, EstimateError> {
        let model = self.model_events()?;
        let mut calls = |cutoff: f64| -> Result<bool, EstimateError> {
            let e = self.evidence(&model, cutoff)?;
            tried.push([cutoff, e.score]);
            Ok(e.relevant && e.score >= EVIDENCE_THRESHOLD + MARGIN_Z)
        };
        let lowest = Effect::Bandwidth.range(HIGHEST_HZ).0;
        let step = 10f64.powf(1.0 / PER_DECADE);
        let mut above: Option<f64> = None;
        let mut cutoff = HIGHEST_HZ;
        while cutoff >= lowest * (1.0 - 1e-9) {
            if calls(cutoff)? {
                let Some(mut not) = above else {
                    return Ok(Ok(cutoff));
                };
                let mut called: f64 = cutoff;
                for _ in 0..BISECTIONS {
                    let mid = (called * not).sqrt();
                    if calls(mid)? {
                        called = mid;
                    } else {
                        not = mid;
                    }
                }
                return Ok(Ok(called));
            }
            above = Some(cutoff);
            cutoff /= step;
        }
        Ok(Err(format!(
            "no cutoff from {HIGHEST_HZ:.0} down to {lowest:.0} Hz at white would: the scene's changes are too slow, or its pixels too bright, for the photoreceptor's filter to thin or delay its events beyond the recording's noise"
        )))
    }
}

const ALREADY: &str = "the recording's own evidence calls for bandwidth beside the final model (it was tried and not kept, or an effect that explains the same residual was preferred): a cutoff may be present; the recording does not determine it";

const MEANING: &str = "where the final model has no photoreceptor cutoff: called_for_below_hz, the highest cutoff at white (v2e's law: the cutoff scales with DN + 20) at which a recording of this scene would have made the bandwidth evidence call for the effect in about 95 % of such recordings (5 + 1.645 standard errors), found by simulating the final model with the cutoff and an independent seed and comparing it with the final model as the recording is, each standard error held at least at the real recording's beside the final model; cutoffs scanned down from 2 kHz, four a decade, then two bisections; evidence: [cutoff_hz, standard errors] of every cutoff simulated; recording_evidence: the recording's own bandwidth evidence beside the final model (standard errors); tried: the effect was called for and tried, and not kept; a faster photoreceptor (a higher cutoff) may be present and is not determinable from this recording";

fn assumption(d: &BandwidthDetection) -> String {
    let tried = if d.tried { "; tried and not kept" } else { "" };
    match (d.called_for_below_hz, &d.why) {
        (Some(hz), _) => format!(
            "photoreceptor bandwidth the recording would show: a cutoff at white of {hz:.0} Hz or lower would have made the bandwidth evidence call for the effect in about 95 % of recordings of this scene (the final model simulated with the cutoff and an independent seed, {} simulations; the recording's own evidence {:.1} standard errors{tried}); a faster photoreceptor may be present, which this recording does not determine",
            d.evidence.len(),
            d.recording_evidence,
        ),
        (None, Some(why)) => format!("photoreceptor bandwidth: no detection limit ({why}{tried})"),
        (None, None) => format!("photoreceptor bandwidth: no detection limit{tried}"),
    }
}
