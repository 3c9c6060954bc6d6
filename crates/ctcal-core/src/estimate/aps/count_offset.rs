//! The frames' log offset as the event counts see it, against the event timing's.
//!
//! The event timing fits the offset `b` in `ln(DN + b)` where its threshold samples stop
//! depending on brightness ([`crate::estimate::timing`]). A photoreceptor bandwidth limit
//! distorts exactly those samples: its time constant goes as one over the photocurrent
//! (Lichtsteiner, Posch & Delbruck, JSSC 2008; v2e's `cutoff_hz (DN + 20) / 275`), so a
//! dark pixel's events come late, and the frames' change between two of them is not one
//! threshold. The timing's first-order lag term does not hold once the time constant
//! nears the time the signal takes to change, and the offset absorbs what is left: on the
//! coverage study's draw 46 (a 42.6 Hz photoreceptor, v2e's lin-log response, whose offset
//! is about 1 DN) the timing fitted b = 35.6 DN and both estimators read ON 0.34 for a
//! true 0.475; given b = 1.2 they read 0.463 and 0.478.
//!
//! Counts are far less sensitive to a lag: a low-pass delays events and removes only those
//! of changes faster than itself. So the re-simulation gives a second measure of `b`: the
//! offset at which its dark cells (below the median frame value of the cells with events)
//! are simulated as well as its bright ones, the difference of their mean log ratios of
//! simulated to real counts crossing zero (a larger offset compresses dark changes, so the
//! difference falls as `b` grows). Its standard error comes from the cells' scatter,
//! through the difference's slope in `b`. Where the two measures disagree, the offsets
//! the thresholds' systematic error spans cover both ([`reconcile`]).

use super::{ApsInput, ApsOptions, Pass, lag_resolved, run_pass, simulated_sigma};
use crate::estimate::EstimateError;
use crate::estimate::frames::PreparedFrames;
use crate::estimate::resim::{Cells, Counts, Resimulation, fit_with};
use crate::estimate::timing::OFFSET_PRIOR;
use crate::events::TimeUs;
use crate::sim::Sample;
use crate::stats::robust;
use serde::Serialize;

/// Cells with at least this many real events (both polarities) are compared.
const MIN_CELL_EVENTS: u32 = 10;

/// Cells each of the dark and the bright half needs.
const MIN_CELLS: usize = 5;

/// The dark-bright difference is searched for a root only beyond this many standard
/// errors (two-sided 99 %): within it the counts agree with the timing's offset.
const DISAGREEMENT_Z: f64 = 2.576;

/// Bisection steps of the root search once bracketed (the bracket shrinks to 1/16).
const ROOT_STEPS: usize = 4;

/// The first step away from the timing's offset, DN (or half that offset, if larger).
const FIRST_STEP_DN: f32 = 1.0;

/// Which cells are dark: below the median frame value of the cells with events.
pub struct Brightness {
    dark: Vec<Option<bool>>,
}

/// How the dark cells' counts agree with a simulation against the bright cells'.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct DarkBright {
    /// Mean `ln((s + 1/2) / (r + 1/2))` over the dark cells less that over the bright
    /// cells (both polarities together): positive where the simulation makes too many
    /// events in the dark.
    pub difference: f64,
    pub standard_error: f64,
}

impl Brightness {
    /// The dark and bright cells of `cells` over `frames`, with enough events in `real`;
    /// `None` when either half has fewer than [`MIN_CELLS`].
    pub fn new(cells: &Cells, frames: &PreparedFrames, real: &Counts) -> Option<Self> {
        let levels = cells.mean_levels(frames);
        let busy = |i: usize| real.on[i] + real.off[i] >= MIN_CELL_EVENTS;
        let busy_levels: Vec<f64> = levels
            .iter()
            .enumerate()
            .filter(|(i, _)| busy(*i))
            .filter_map(|(_, l)| *l)
            .collect();
        let median = robust::median(&busy_levels)?;
        let dark: Vec<Option<bool>> = levels
            .iter()
            .enumerate()
            .map(|(i, l)| l.filter(|_| busy(i)).map(|l| l < median))
            .collect();
        let size = |d: bool| dark.iter().filter(|&&c| c == Some(d)).count();
        (size(true) >= MIN_CELLS && size(false) >= MIN_CELLS).then_some(Self { dark })
    }

    /// The dark-bright difference of `simulated` against `real`.
    pub fn compare(&self, real: &Counts, simulated: &Counts) -> DarkBright {
        let mut ratios: [Vec<f64>; 2] = Default::default();
        for (i, d) in self.dark.iter().enumerate() {
            if let Some(d) = d {
                let r = (real.on[i] + real.off[i]) as f64;
                let s = (simulated.on[i] + simulated.off[i]) as f64;
                ratios[usize::from(*d)].push(((s + 0.5) / (r + 0.5)).ln());
            }
        }
        // (mean, squared standard error of the mean) of each half
        let [bright, dark] = ratios.map(|v| {
            let n = v.len() as f64;
            let variance = robust::sample_variance(&v).unwrap_or(f64::NAN);
            (v.iter().sum::<f64>() / n, variance / n)
        });
        DarkBright {
            difference: dark.0 - bright.0,
            standard_error: (dark.1 + bright.1).sqrt(),
        }
    }
}

/// The offset the counts give.
#[derive(Clone, Debug, Serialize)]
pub struct CountOffset {
    /// Where the dark-bright difference crosses zero, DN (a bound of the search where it
    /// does not within it: see `at_bound`).
    pub offset_dn: f32,
    /// Its 95 % interval, from the difference's standard error and its slope in `b`.
    pub ci95: [f32; 2],
    /// The difference at the timing's offset.
    pub at_timing_offset: DarkBright,
    /// The root lies at or beyond this end of the search range (the prior's).
    pub at_bound: bool,
}

/// What the re-simulation of the counts' offset needs: the full pass's cells, real counts,
/// the simulation at its thresholds, and the recording's timestamp grid.
pub struct Setup<'a> {
    pub cells: &'a Cells,
    pub real: &'a Counts,
    pub simulated: &'a Counts,
    pub grid: Option<(crate::events::TimeUs, crate::events::TimeUs)>,
    pub width: usize,
    pub height: usize,
    /// The frames' log response the runs are simulated through.
    pub log_map: crate::sim::log_response::LogMap,
}

/// The dark-bright difference of the re-simulation at the timing's offset, where it lies
/// beyond [`DISAGREEMENT_Z`] standard errors (the counts disagree with that offset); `None`
/// where they agree.
pub fn disagreement(setup: &Setup, brightness: &Brightness) -> Option<DarkBright> {
    let at_own = brightness.compare(setup.real, setup.simulated);
    (at_own.difference.abs() > DISAGREEMENT_Z * at_own.standard_error).then_some(at_own)
}

/// The offset of the counts, searched from the timing's offset `own`, where the
/// difference is `at_own` ([`disagreement`]). `runs` are the frames upsampled at `own`;
/// the search shifts them in place and leaves them shifted (upsample again to use them).
/// `start` are the re-simulation's thresholds at `own`, `sigma` its mismatch. `None` where
/// the root lies on the other side of `own` from the prior's end, or a fit fails.
pub fn search(
    setup: &Setup,
    brightness: &Brightness,
    (runs, own): (&mut [Vec<Sample>], f32),
    at_own: DarkBright,
    start: (f64, f64),
    sigma: f64,
) -> Option<CountOffset> {
    let mut probe = OffsetProbe {
        setup,
        brightness,
        runs,
        own,
        shifted: 0.0,
        thresholds: start,
        sigma,
    };
    // the difference falls as the offset grows: step away from `own` towards the root,
    // doubling the step, until the sign changes or the prior's end is reached; each fit
    // starts from the last thresholds
    let (direction, bound) = if at_own.difference < 0.0 {
        (-1.0f32, OFFSET_PRIOR.0)
    } else {
        (1.0, OFFSET_PRIOR.1)
    };
    if (bound - own) * direction <= 0.0 {
        return None;
    }
    let Some(((near, d_near), (far, d_far))) =
        probe.bracket(at_own.difference, direction, bound)?
    else {
        return Some(CountOffset {
            offset_dn: bound,
            ci95: [bound.min(own), bound.max(own)],
            at_timing_offset: at_own,
            at_bound: true,
        });
    };
    // the slope over the bracket, for the root's standard error
    let slope = (d_far - d_near) / (far - near) as f64;
    let root = probe.root((near, d_near), (far, d_far))?;
    let half = (1.96 * at_own.standard_error / slope.abs().max(1e-12)) as f32;
    Some(CountOffset {
        offset_dn: root,
        ci95: [(root - half).max(OFFSET_PRIOR.0), root + half],
        at_timing_offset: at_own,
        at_bound: false,
    })
}

/// A trial offset (DN) and the counts' dark-bright difference there.
type Trial = (f32, f64);

/// The counts' dark-bright difference at a trial offset: the upsampled runs shifted
/// there in place and re-simulated, the thresholds fitted from the last trial's.
struct OffsetProbe<'s, 'r> {
    setup: &'s Setup<'s>,
    brightness: &'s Brightness,
    runs: &'r mut [Vec<Sample>],
    /// The offset the runs were upsampled at.
    own: f32,
    /// How far they are shifted from it now.
    shifted: f32,
    thresholds: (f64, f64),
    sigma: f64,
}

impl OffsetProbe<'_, '_> {
    /// The difference at offset `b` (`None` where the fit fails).
    fn at(&mut self, b: f32) -> Option<DarkBright> {
        shift_runs(self.runs, b - self.own - self.shifted);
        self.shifted = b - self.own;
        let setup = self.setup;
        let resim = Resimulation::new(
            self.runs,
            (setup.width, setup.height),
            setup.cells,
            setup.real,
            setup.grid,
            setup.log_map,
        );
        let r = fit_with(&resim, self.thresholds, self.sigma, None, 1).ok()?;
        self.thresholds = (r.ct_on, r.ct_off);
        Some(self.brightness.compare(setup.real, &r.counts))
    }

    /// Offsets stepped from `own` (its difference `d_own`) in `direction`, the step
    /// doubling, until the difference changes sign: the last two (offset, difference)
    /// pairs, nearer first; `Some(None)` where the prior's end `bound` is reached first.
    fn bracket(
        &mut self,
        d_own: f64,
        direction: f32,
        bound: f32,
    ) -> Option<Option<(Trial, Trial)>> {
        let own = self.own;
        let mut step = (0.5 * own.abs()).max(FIRST_STEP_DN);
        let mut near = (own, d_own);
        loop {
            let b = if direction > 0.0 {
                (own + step).min(bound)
            } else {
                (own - step).max(bound)
            };
            let d = self.at(b)?.difference;
            if d.signum() != d_own.signum() {
                return Some(Some((near, (b, d))));
            }
            if b == bound {
                return Some(None);
            }
            near = (b, d);
            step *= 2.0;
        }
    }

    /// The root within the bracket `a`, `b` ((offset, difference) pairs of opposite
    /// signs): [`ROOT_STEPS`] bisections, then the secant.
    fn root(&mut self, a: Trial, b: Trial) -> Option<f32> {
        let ((mut lo, mut d_lo), (mut hi, mut d_hi)) = if a.0 < b.0 { (a, b) } else { (b, a) };
        for _ in 0..ROOT_STEPS {
            let mid = 0.5 * (lo + hi);
            let d = self.at(mid)?.difference;
            if d > 0.0 {
                (lo, d_lo) = (mid, d);
            } else {
                (hi, d_hi) = (mid, d);
            }
        }
        Some(lo + (hi - lo) * (d_lo / (d_lo - d_hi)) as f32)
    }
}

/// The counts' offset and whether it moved the frames' offset or its range.
pub(super) struct FromCounts {
    pub(super) found: CountOffset,
    /// The timing's offset, DN.
    timing_offset_dn: f32,
    changed: bool,
}

/// The frames' offset as the counts give it ([`search`]), where the timing fitted
/// one and the re-simulation's dark cells disagree with its bright ones at it. Where the
/// two offsets' intervals do not overlap, the frames' offset and range are reconciled
/// ([`reconcile`]) and the full pass (with its upsampled `runs`) is made
/// again at them.
pub(super) fn offset_from_counts(
    input: &ApsInput,
    excluded: &[bool],
    frames: &mut PreparedFrames,
    options: &ApsOptions,
    (runs, full): (&mut Vec<Vec<Sample>>, &mut Pass),
    timing_offset: Option<&crate::estimate::timing::Offset>,
    grid: Option<(TimeUs, TimeUs)>,
) -> Result<Option<FromCounts>, EstimateError> {
    let Some(timing_offset) = timing_offset.filter(|o| o.source == "fitted") else {
        return Ok(None);
    };
    let Some(found) = searched(frames, runs, full, grid) else {
        return Ok(None);
    };
    let timing = (frames.offset, frames.offset_range);
    let changed = reconciled(frames, timing_offset, found.as_ref(), full);
    // the search shifted the runs, whether or not it found the offset
    *runs = frames.upsample_runs(0.5, options.max_upsampled_bytes);
    if changed {
        *full = run_pass(input, excluded, frames, runs, options, None)?;
    }
    Ok(found.map(|found| FromCounts {
        found,
        timing_offset_dn: timing.0,
        changed,
    }))
}

/// The counts' offset ([`search`]) from the `full` pass's re-simulation, its `runs`
/// shifted in place; `None` where it is not searched (no re-simulation, too few dark or
/// bright cells, or the two agree at the timing's offset: `runs` as they were).
fn searched(
    frames: &PreparedFrames,
    runs: &mut [Vec<Sample>],
    full: &Pass,
    grid: Option<(TimeUs, TimeUs)>,
) -> Option<Option<CountOffset>> {
    let resim = full.resim.as_ref()?;
    let brightness = Brightness::new(&full.cells, frames, &full.real)?;
    let setup = Setup {
        cells: &full.cells,
        real: &full.real,
        simulated: &resim.counts,
        grid,
        width: frames.width,
        height: frames.height,
        log_map: frames.log_map,
    };
    let at_own = disagreement(&setup, &brightness)?;
    Some(search(
        &setup,
        &brightness,
        (runs, frames.offset),
        at_own,
        (resim.ct_on, resim.ct_off),
        simulated_sigma(&full.timing),
    ))
}

/// Moves the frames' offset and range to those [`reconcile`] gives for the counts' offset
/// `found` against the timing's; whether they moved.
fn reconciled(
    frames: &mut PreparedFrames,
    timing_offset: &crate::estimate::timing::Offset,
    found: Option<&CountOffset>,
    full: &Pass,
) -> bool {
    let timing = (frames.offset, frames.offset_range);
    // a root at the prior's end is no offset met in practice: it moves nothing
    let change = found.filter(|f| !f.at_bound).and_then(|found| {
        reconcile(
            timing,
            timing_offset.ci95,
            found,
            lag_resolved(&full.timing.lag).is_some(),
        )
    });
    if let Some((offset, range)) = change {
        frames.offset = offset;
        frames.offset_range = range;
    }
    change.is_some()
}

/// The counts' offset, in words for the assumptions.
pub(super) fn assumption(c: &FromCounts, frames: &PreparedFrames) -> String {
    let f = &c.found;
    if f.at_bound {
        // the search stopped at the prior's end: the counts place the offset nowhere a
        // black level is met in practice, so they neither confirm nor move the timing's
        return format!(
            "the frames' log offset from the counts: at the event timing's b = {:.1} DN the re-simulation's dark cells differ from its bright ones by {:+.3} (+- {:.3}) in mean log ratio of simulated to real counts, and the difference keeps its sign up to {:.1} DN, the end of the prior range: the counts agree only beyond it, where no black level is met in practice, so they do not move the timing's offset (kept)",
            c.timing_offset_dn,
            f.at_timing_offset.difference,
            f.at_timing_offset.standard_error,
            f.offset_dn
        );
    }
    let found = format!(
        "at b = {:.1} DN (95 % {:.1} .. {:.1})",
        f.offset_dn, f.ci95[0], f.ci95[1]
    );
    let head = format!(
        "the frames' log offset from the counts: at the event timing's b = {:.1} DN the re-simulation's dark cells differ from its bright ones by {:+.3} (+- {:.3}) in mean log ratio of simulated to real counts; they agree {found}",
        c.timing_offset_dn, f.at_timing_offset.difference, f.at_timing_offset.standard_error
    );
    if c.changed {
        format!(
            "{head}. The two offsets disagree (a photoreceptor lag distorts the timing's samples and hardly the counts), so the thresholds' systematic error spans the offsets {:.1} .. {:.1} DN, and they are read at b = {:.1} DN ({})",
            frames.offset_range.0,
            frames.offset_range.1,
            frames.offset,
            if frames.offset != c.timing_offset_dn {
                "the counts' offset: the timing finds a photoreceptor lag, which pushes its offset up"
            } else {
                "the timing's offset: the timing finds no photoreceptor lag, or the counts' offset is the larger, which a lag does not explain"
            }
        )
    } else {
        format!("{head}, within the timing's offset interval: the timing's offset kept")
    }
}

/// Adds `delta` DN to every sample of `runs`.
fn shift_runs(runs: &mut [Vec<Sample>], delta: f32) {
    if delta == 0.0 {
        return;
    }
    for s in runs.iter_mut().flatten() {
        s.dn.iter_mut().for_each(|v| *v += delta);
    }
}

/// The offsets the thresholds' systematic error spans and the offset they are read at,
/// given the timing's (`own`: its offset and range, `timing_ci95` its offset's 95 %
/// interval, a side `None` where the data leave it open) and the counts': where the two
/// offsets' intervals overlap, unchanged; else the range covers both, and the offset is
/// the counts' where the timing found a photoreceptor lag (`lag_resolved`: the effect that
/// distorts the timing's samples and hardly the counts) and the counts' offset is the
/// smaller (a lag makes dark pixels' samples look larger, as a too small offset would, so
/// it pushes the timing's offset up, never down), else the timing's. Returns the new
/// (offset, range) where they change.
pub fn reconcile(
    (offset, (range_lo, range_hi)): (f32, (f32, f32)),
    timing_ci95: [Option<f32>; 2],
    counts: &CountOffset,
    lag_resolved: bool,
) -> Option<(f32, (f32, f32))> {
    let (lo, hi) = (
        timing_ci95[0].unwrap_or(range_lo),
        timing_ci95[1].unwrap_or(range_hi),
    );
    if counts.ci95[0] <= hi && counts.ci95[1] >= lo {
        return None;
    }
    let range = (range_lo.min(counts.ci95[0]), range_hi.max(counts.ci95[1]));
    let offset = if lag_resolved && counts.offset_dn < offset {
        counts.offset_dn
    } else {
        offset
    };
    Some((offset, range))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn counts(on: &[u32], off: &[u32]) -> Counts {
        Counts {
            on: on.to_vec(),
            off: off.to_vec(),
        }
    }

    #[test]
    fn dark_minus_bright_is_the_difference_of_mean_log_ratios_with_their_errors() {
        // cells 0-2 dark, 3-5 bright, 6 without a class
        let brightness = Brightness {
            dark: vec![
                Some(true),
                Some(true),
                Some(true),
                Some(false),
                Some(false),
                Some(false),
                None,
            ],
        };
        let real = counts(&[10, 20, 30, 10, 20, 30, 50], &[9, 19, 29, 9, 19, 29, 0]);
        // the dark cells simulated with twice their events, the bright ones as they are
        let simulated = counts(&[20, 40, 60, 10, 20, 30, 0], &[18, 38, 58, 9, 19, 29, 0]);
        let d = brightness.compare(&real, &simulated);
        let dark: Vec<f64> = [(38.0, 19.0), (78.0, 39.0), (118.0, 59.0)]
            .iter()
            .map(|(s, r): &(f64, f64)| ((s + 0.5) / (r + 0.5)).ln())
            .collect();
        let mean = dark.iter().sum::<f64>() / 3.0;
        let var = dark.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 2.0;
        assert!((d.difference - mean).abs() < 1e-12, "{d:?}");
        // the bright cells agree exactly: only the dark cells' scatter
        assert!(
            (d.standard_error - (var / 3.0).sqrt()).abs() < 1e-12,
            "{d:?}"
        );
        assert!(d.difference > 0.6 && d.difference < 2f64.ln());
    }

    fn found(offset_dn: f32, ci95: [f32; 2]) -> CountOffset {
        CountOffset {
            offset_dn,
            ci95,
            at_timing_offset: DarkBright {
                difference: -0.1,
                standard_error: 0.01,
            },
            at_bound: false,
        }
    }

    #[test]
    fn offsets_that_overlap_leave_the_timings() {
        let timing = (6.3, (0.3, 6.9));
        let ci = [Some(5.8), Some(6.9)];
        assert_eq!(reconcile(timing, ci, &found(6.5, [6.0, 7.0]), true), None);
        // the counts' interval touching the timing's from below
        assert_eq!(reconcile(timing, ci, &found(4.0, [2.0, 5.8]), true), None);
    }

    #[test]
    fn a_lag_moves_the_offset_down_to_the_counts_and_the_range_spans_both() {
        // draw 46: the timing's 35.6 (33.9 .. 37.3), the counts' 2.8 (0 .. 7.6)
        let timing = (35.6, (26.0, 37.3));
        let ci = [Some(33.9), Some(37.3)];
        let counts = found(2.8, [0.0, 7.6]);
        assert_eq!(
            reconcile(timing, ci, &counts, true),
            Some((2.8, (0.0, 37.3)))
        );
        // without a lag the timing's offset stays, the range still spans both
        assert_eq!(
            reconcile(timing, ci, &counts, false),
            Some((35.6, (0.0, 37.3)))
        );
    }

    #[test]
    fn counts_above_the_timing_widen_the_range_but_a_lag_does_not_explain_them() {
        // draw 84: the timing's 5.4 (4.9 .. 5.7), the counts' 9.1 (8.1 .. 10.0)
        let timing = (5.4, (4.9, 5.7));
        let ci = [Some(4.9), Some(5.7)];
        assert_eq!(
            reconcile(timing, ci, &found(9.1, [8.1, 10.0]), true),
            Some((5.4, (4.9, 10.0)))
        );
    }
}
