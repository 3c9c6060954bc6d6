//! The fit's frame-quality checks. The fit re-simulates the recording from its frames
//! upsampled along the optical flow, and frames lose contrast in two ways a re-simulation
//! inherits (Stoffregen et al., ECCV 2020, sec. 4: frame quality limits re-simulation):
//!
//! - the gap between frames: where the scene moves several pixels from one frame to the
//!   next, the flow and its interpolation smooth what happens in between. The final
//!   model's thresholds are profiled again on every frame, every 2nd and every 3rd frame
//!   (the same profile for each, so that only the frames differ; the motion gate of a
//!   usable interval doubled for the coarser ones, as far as the flow follows), and the
//!   distance of the full-rate value from the straight line's limit at infinite frame rate,
//!   plus the scatter about the line ([`crate::estimate::interval::frame_rate_systematic`],
//!   the same check `estimate aps` makes), is a systematic error of each threshold;
//! - the exposure: a frame averages the moving scene over its exposure (motion blur),
//!   which the simulation takes as an instant. The thresholds are profiled again on frames
//!   blurred by one more exposure's motion along the flow
//!   ([`PreparedFrames::motion_blurred`]); a straight line through the two exposures is
//!   extrapolated to none, and the distance is a second systematic (Richardson's deferred
//!   approach to the limit, 1911, with one step).
//!
//! Both add to the thresholds' standard errors in quadrature. A clean, slow case profiles
//! nearly the same thresholds in every check; what it still adds is the profile's own
//! step (the median of integer-count ratios is a step function, and a threshold the counts
//! fix poorly can land a step away under any change of the frames), which these
//! systematics do not yet tell apart from the frames' (`benches/coverage/`
//! `fit-frame-checks-2026-11-25/`: slow cases' median half-width 0.18 -> 0.30 in ln).

use super::super::observe::{Geometry, Observed};
use super::super::search::{Simulated, Simulation};
use super::super::{FitInput, FitOptions, Uncertain};
use crate::estimate::frames::{PreparedFrames, exposure_of};
use crate::estimate::interval::{FrameRatePoint, frame_rate_systematic};
use crate::events::{EventChunk, TimeUs};
use crate::sim::Sample;
use rayon::prelude::*;
use std::cell::Cell;
use std::collections::BTreeMap;

/// The thresholds each check profiled.
#[derive(Clone, Debug, Default)]
pub struct FrameQuality {
    /// At frame steps 1, 2, 3 (OFF, ON), the full rate first. Every point, the full rate's
    /// too, is profiled by the check from the final model's thresholds: a threshold profile
    /// ends at the tried value nearest balance, and the median of integer-count ratios
    /// moves in steps, so the same profile on the same frames is what a changed frame set
    /// is compared with (not the fit's own value, which may sit a step away).
    pub off: Vec<FrameRatePoint>,
    pub on: Vec<FrameRatePoint>,
    /// With the exposure's motion blur doubled: (exposure in us, OFF, ON), compared with
    /// the full-rate points.
    pub doubled_exposure: Option<(TimeUs, f64, f64)>,
    /// The frames' exposure is not known (no exposure check).
    pub exposure_unknown: bool,
    /// The frames' exposure is zero (no motion blur, no exposure check).
    pub instantaneous: bool,
    /// The thresholds could not be profiled again on the frames as they are (no check).
    pub not_profiled: bool,
}

/// What the checks read besides the fit's simulation.
pub struct Check<'a> {
    pub frames: &'a PreparedFrames,
    pub input: &'a FitInput<'a>,
    pub options: &'a FitOptions,
    pub fit_end: TimeUs,
    pub masked: &'a [bool],
}

/// What the checks' simulations share with the fit's (which, counting its runs in a
/// `Cell`, cannot cross threads itself).
struct Fine<'a> {
    events: &'a EventChunk,
    grid: Option<(TimeUs, TimeUs)>,
    seed: u64,
    hot_events: &'a EventChunk,
    /// The fit's frames as simulated, their geometry and the recording's statistics on it
    /// (kept where a check changes only the frames' content, not their times).
    runs: &'a [Vec<Sample>],
    geometry: &'a Geometry,
    real: &'a Observed,
}

/// A variant of the fit's frames.
#[derive(Clone, Copy)]
enum Variant {
    /// Every `n`-th frame (1: the frames as they are, the reference of the others).
    Step(usize),
    /// Blurred by one more exposure of this many microseconds.
    Blurred(TimeUs),
}

fn point(frame_interval_s: f64, step: usize, value: f64) -> FrameRatePoint {
    FrameRatePoint {
        frame_step: step,
        frame_interval_s,
        value,
    }
}

/// The model's thresholds profiled on `variant` of the frames (`None` where too few frame
/// intervals remain usable, or the profile fails), with the variant's median frame
/// interval (seconds) and the simulations run.
fn profiled_on(
    check: &Check,
    fine: &Fine,
    model: &Simulated,
    variant: Variant,
) -> Option<(f64, Simulated, usize)> {
    let own = own_frames(check, variant)?;
    let frames = own.frames.as_ref().unwrap_or(check.frames);
    let geometry_used = own.geometry.as_ref().unwrap_or(fine.geometry);
    let coarse = Simulation {
        runs: own.runs.as_deref().unwrap_or(fine.runs),
        width: frames.width,
        height: frames.height,
        geometry: geometry_used,
        events: fine.events,
        real: match &own.geometry {
            Some(g) => Observed::new(fine.events, g, check.masked),
            None => fine.real.clone(),
        },
        grid: fine.grid,
        seed: fine.seed,
        count: Cell::new(0),
        hot_events: fine.hot_events.clone(),
        lag_keys: Default::default(),
    };
    let profiled = coarse.profile(&model.params, check.masked, false).ok()?;
    let count = coarse.count.get();
    let interval_s = frames.median_interval_us() as f64 * 1e-6;
    Some((interval_s, profiled, count))
}

/// What a variant of the frames brings of its own; `None` in a field where it keeps the
/// fit's (its frames, their simulation runs, their geometry and statistics).
struct OwnFrames {
    frames: Option<PreparedFrames>,
    runs: Option<Vec<Vec<Sample>>>,
    geometry: Option<Geometry>,
}

/// The frames, runs and geometry of `variant` that differ from the fit's; `None` where
/// too few frame intervals remain usable.
fn own_frames(check: &Check, variant: Variant) -> Option<OwnFrames> {
    let (frames, runs, geometry) = match variant {
        // the fit's own frames, runs and statistics: only the profile is run again
        Variant::Step(1) => (None, None, None),
        Variant::Step(step) => {
            // the intervals `step` times longer: the motion gate doubles for them (the
            // flow's coarsest pyramid level, a quarter of the sensor with a 4 px window,
            // follows about 16 px; far beyond, a failing flow and not the frame rate would
            // move the thresholds), so the every-3rd-frame check keeps the intervals whose
            // motion the flow still follows
            let mut options = check.options.aps.frames.clone();
            options.max_motion_px *= step.min(2) as f64;
            let frames = check.frames.every(step, &options)?;
            let runs = frames.upsample_runs(0.5, check.options.aps.max_upsampled_bytes);
            let geometry = Geometry::new(
                &frames,
                check.input.excluded,
                check.options.blocks,
                check.fit_end,
            );
            (Some(frames), Some(runs), Some(geometry))
        }
        // the same frame times, bins and statistics: only the frames' content changes
        Variant::Blurred(exposure) => {
            let frames = check.frames.motion_blurred(exposure);
            let runs = frames.upsample_runs(0.5, check.options.aps.max_upsampled_bytes);
            (Some(frames), Some(runs), None)
        }
    };
    Some(OwnFrames {
        frames,
        runs,
        geometry,
    })
}

/// The checks of the final `model` (fitted on `simulation`'s frames); the simulations they
/// ran are added to the fit's count.
pub fn measure(check: &Check, simulation: &Simulation, model: &Simulated) -> FrameQuality {
    let fine = Fine {
        events: simulation.events,
        grid: simulation.grid,
        seed: simulation.seed,
        hot_events: &simulation.hot_events,
        runs: simulation.runs,
        geometry: simulation.geometry,
        real: &simulation.real,
    };
    let exposure =
        exposure_of(check.input.frames, check.options.aps.exposure_us).filter(|&e| e >= 0);
    let mut variants = vec![Variant::Step(1), Variant::Step(2), Variant::Step(3)];
    variants.extend(exposure.filter(|&e| e > 0).map(Variant::Blurred));
    let profiled: Vec<(Variant, f64, Simulated, usize)> = variants
        .par_iter()
        .filter_map(|&v| profiled_on(check, &fine, model, v).map(|(i, s, n)| (v, i, s, n)))
        .collect();
    let mut quality = FrameQuality {
        exposure_unknown: exposure.is_none(),
        instantaneous: exposure == Some(0),
        ..FrameQuality::default()
    };
    if !profiled.iter().any(|p| matches!(p.0, Variant::Step(1))) {
        quality.not_profiled = true;
        return quality;
    }
    for (variant, interval_s, p, count) in profiled {
        simulation.count.set(simulation.count.get() + count);
        match variant {
            Variant::Step(step) => {
                quality.off.push(point(interval_s, step, p.params.ct_off));
                quality.on.push(point(interval_s, step, p.params.ct_on));
            }
            Variant::Blurred(e) => {
                quality.doubled_exposure = Some((e, p.params.ct_off, p.params.ct_on));
            }
        }
    }
    for series in [&mut quality.off, &mut quality.on] {
        series.sort_by_key(|p| p.frame_step);
    }
    quality
}

/// Adds each threshold's frame-rate and exposure systematics to its standard error in
/// quadrature (the interval log-normal about the fitted value, as the fit's own) and
/// returns the assumptions that say what was measured.
pub fn widen(uncertainty: &mut BTreeMap<String, Uncertain>, quality: &FrameQuality) -> Vec<String> {
    if quality.not_profiled {
        return vec!["frame checks not run: the final model's thresholds could not be profiled again on its frames, so neither the gap between frames nor the exposure's motion blur is in the thresholds' intervals".into()];
    }
    if quality.on.is_empty() || quality.off.is_empty() {
        return Vec::new();
    }
    let mut rate_parts = Vec::new();
    let mut exposure_parts = Vec::new();
    let polarities = [
        (
            "ct_off",
            "OFF",
            &quality.off,
            quality.doubled_exposure.map(|d| d.1),
        ),
        (
            "ct_on",
            "ON",
            &quality.on,
            quality.doubled_exposure.map(|d| d.2),
        ),
    ];
    for (key, name, points, doubled) in polarities {
        let systematics = Systematics::of(name, points, doubled);
        if let Some(u) = uncertainty.get_mut(key) {
            systematics.widen(u);
        }
        rate_parts.extend(systematics.rate_part);
        exposure_parts.extend(systematics.exposure_part);
    }
    notes(quality, &rate_parts, &exposure_parts)
}

/// One threshold's frame-rate and exposure systematics, with what each check measured for
/// the notes (`None` where the check has nothing for it).
struct Systematics {
    rate: f64,
    exposure: f64,
    rate_part: Option<String>,
    exposure_part: Option<String>,
}

impl Systematics {
    /// From the threshold's points at frame steps 1, 2, 3 (`name`: OFF or ON) and its
    /// value with the exposure's motion blur doubled, where profiled.
    fn of(name: &str, points: &[FrameRatePoint], doubled: Option<f64>) -> Self {
        let (limit, rate) = frame_rate_systematic(points);
        let rate_part = (points.len() >= 2).then(|| {
            let values: Vec<String> = points.iter().map(|p| format!("{:.4}", p.value)).collect();
            format!(
                "{name} {} (limit {}, systematic {rate:.4})",
                values.join(" / "),
                limit.map_or("-".into(), |l| format!("{l:.4}"))
            )
        });
        let full = points[0].value;
        // a straight line through exposures e and 2e reaches e = 0 as far below the
        // full value as the doubled one lies above it
        let exposure = doubled.map_or(0.0, |d| (d - full).abs());
        let exposure_part = doubled.map(|d| {
            format!(
                "{name} {full:.4} / {d:.4} (limit {:.4}, systematic {exposure:.4})",
                2.0 * full - d
            )
        });
        Systematics {
            rate,
            exposure,
            rate_part,
            exposure_part,
        }
    }

    /// Adds both systematics to the threshold's standard error in quadrature, where it has
    /// one.
    fn widen(&self, u: &mut Uncertain) {
        let Some(se) = u.standard_error else { return };
        let systematic = self.rate.hypot(self.exposure);
        if systematic > 0.0 && u.value > 0.0 {
            *u = Uncertain::positive(u.value, Some(se.hypot(systematic)));
        }
    }
}

/// The assumptions the two checks add: what each measured (`rate_parts`, `exposure_parts`:
/// one entry a threshold), or why it was not run.
fn notes(quality: &FrameQuality, rate_parts: &[String], exposure_parts: &[String]) -> Vec<String> {
    let mut notes = Vec::new();
    if rate_parts.is_empty() {
        notes.push("frame-rate check not run: every 2nd and 3rd frame left no interval the optical flow follows (or their thresholds could not be profiled), so the gap between frames is not in the thresholds' intervals".into());
    } else {
        notes.push(format!(
            "frame-rate check: the final model's thresholds profiled again on every frame, every 2nd and every 3rd frame ({}); a straight line in the frame interval is extrapolated to infinite frame rate and the full-rate value's distance from it, plus the scatter about the line, is added to each threshold's standard error in quadrature",
            rate_parts.join("; ")
        ));
    }
    match quality.doubled_exposure {
        Some((e, ..)) => notes.push(format!(
            "exposure check: the thresholds profiled again on frames blurred by one more exposure's motion ({:.3} ms along the optical flow): {}; a straight line through the two exposures is extrapolated to none and the distance is added to each threshold's standard error in quadrature",
            e as f64 / 1e3,
            exposure_parts.join("; ")
        )),
        None if quality.instantaneous => notes.push("exposure check not needed: the frames' exposure is 0 (instantaneous frames have no motion blur)".into()),
        None if quality.exposure_unknown => notes.push("exposure check not run: the frames' exposure is not known (give it where it is known), so motion blur within an exposure is not in the thresholds' intervals".into()),
        None => notes.push("exposure check not run: the blurred frames could not be profiled, so motion blur within an exposure is not in the thresholds' intervals".into()),
    }
    notes
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series_of(values: &[f64]) -> Vec<FrameRatePoint> {
        values
            .iter()
            .enumerate()
            .map(|(i, &value)| FrameRatePoint {
                frame_step: i + 1,
                frame_interval_s: 0.02 * (i + 1) as f64,
                value,
            })
            .collect()
    }

    fn uncertainty(on: f64, off: f64) -> BTreeMap<String, Uncertain> {
        BTreeMap::from([
            ("ct_on".into(), Uncertain::positive(on, Some(0.01 * on))),
            ("ct_off".into(), Uncertain::positive(off, Some(0.01 * off))),
        ])
    }

    fn closed(u: &Uncertain) -> (f64, f64) {
        let [Some(lo), Some(hi)] = u.interval().expect("an interval") else {
            panic!("closed")
        };
        (lo, hi)
    }

    #[test]
    fn a_threshold_that_falls_with_the_frame_rate_widens_by_the_distance_to_the_limit() {
        // ON read 0.30 / 0.26 / 0.22 at steps 1 / 2 / 3: the limit is 0.34, 0.04 away
        let quality = FrameQuality {
            on: series_of(&[0.30, 0.26, 0.22]),
            off: series_of(&[0.40, 0.40, 0.40]),
            doubled_exposure: None,
            exposure_unknown: true,
            ..FrameQuality::default()
        };
        let mut u = uncertainty(0.30, 0.40);
        let notes = widen(&mut u, &quality);
        let on = u["ct_on"].standard_error.unwrap();
        assert!((on - (0.003f64).hypot(0.04)).abs() < 1e-9, "{on}");
        let (lo, hi) = closed(&u["ct_on"]);
        assert!(lo < 0.30 && hi > 0.34, "{lo} {hi}");
        // OFF did not move: its interval stays as it was
        assert!((u["ct_off"].standard_error.unwrap() - 0.004).abs() < 1e-12);
        assert!(
            notes[0].contains("ON 0.3000 / 0.2600 / 0.2200"),
            "{notes:?}"
        );
        assert!(notes[1].contains("exposure is not known"), "{notes:?}");
    }

    #[test]
    fn a_doubled_exposure_that_lowers_a_threshold_widens_it_by_as_much() {
        // doubling the blur takes ON from 0.30 to 0.27: no blur would read about 0.33
        let quality = FrameQuality {
            on: series_of(&[0.30]),
            off: series_of(&[0.40]),
            doubled_exposure: Some((5000, 0.40, 0.27)),
            ..FrameQuality::default()
        };
        let mut u = uncertainty(0.30, 0.40);
        let notes = widen(&mut u, &quality);
        let (_, hi) = closed(&u["ct_on"]);
        assert!(hi > 0.33 && hi < 0.40, "{hi}");
        assert!((u["ct_off"].standard_error.unwrap() - 0.004).abs() < 1e-12);
        assert_eq!(notes.len(), 2, "{notes:?}");
        assert!(notes[0].contains("frame-rate check not run"), "{notes:?}");
        assert!(
            notes[1].contains("5.000 ms") && notes[1].contains("limit 0.3300"),
            "{notes:?}"
        );
    }

    #[test]
    fn instantaneous_frames_need_no_exposure_check_and_a_failed_profile_is_said() {
        let quality = FrameQuality {
            on: series_of(&[0.30, 0.30]),
            off: series_of(&[0.40, 0.40]),
            instantaneous: true,
            ..FrameQuality::default()
        };
        let mut u = uncertainty(0.30, 0.40);
        let notes = widen(&mut u, &quality);
        assert!(notes[1].contains("exposure is 0"), "{notes:?}");
        assert_eq!(u["ct_on"].standard_error, Some(0.003));
        let failed = FrameQuality {
            not_profiled: true,
            ..FrameQuality::default()
        };
        let notes = widen(&mut u, &failed);
        assert!(notes[0].starts_with("frame checks not run"), "{notes:?}");
        assert_eq!(u["ct_on"].standard_error, Some(0.003));
    }

    #[test]
    fn thresholds_that_were_not_fitted_are_left_alone() {
        let mut u = uncertainty(0.30, 0.40);
        assert!(widen(&mut u, &FrameQuality::default()).is_empty());
        assert_eq!(u["ct_on"].standard_error, Some(0.003));
    }
}
