//! The simulation side of the fit: a model simulated on the recording's own frames
//! (upsampled along the optical flow, [`crate::estimate::frames`]), its statistics, and the
//! two searches:
//!
//! - thresholds, profiled out: for any other parameters, `Cp` and `Cn` are those at which
//!   the median count-cell log ratio of each polarity is zero (as many cells over-predicted
//!   as under-predicted); counts scale about as `1 / C`, so a secant step in `ln C` from the
//!   current thresholds converges in two or three simulations;
//! - an effect's parameter: argmin's Brent minimisation (golden section with parabolic
//!   steps; Brent, "Algorithms for minimization without derivatives", 1973) of the distance
//!   on the fit blocks over the logarithm of the parameter, thresholds profiled at every
//!   point; for a refractory period, the threshold mismatch is profiled with the thresholds
//!   ([`Simulation::profile_mismatch`]).
//!
//! The simulator is deterministic for a seed, and every simulation uses the same one, so
//! the objective is the same function at every evaluation (common random numbers: the same
//! pixels draw the same mismatch, leak factors and noise).

use super::effects::mismatch::RANGE as MISMATCH_RANGE;
use super::metric::{Components, dispersion, dispersion_log_ratio, distance, median_ratios};
use super::observe::lag::LagKeys;
use super::observe::{Geometry, Observed, Subset};
use crate::estimate::{EstimateError, Interval, quantise, resim};
use crate::events::{EventChunk, TimeUs};
use crate::sim::{PixelParams, Sample};
use argmin::core::{CostFunction, Error as ArgminError, Executor};
use argmin::solver::brent::BrentOpt;
use std::cell::{Cell, OnceCell, RefCell};

/// The recording's frames as simulator input, with what every comparison needs.
pub struct Simulation<'a> {
    pub runs: &'a [Vec<Sample>],
    pub width: usize,
    pub height: usize,
    pub geometry: &'a Geometry,
    /// The recording's events, and their statistics (with the current mask).
    pub events: &'a crate::events::EventChunk,
    pub real: Observed,
    /// The recording's timestamp grid, applied to simulated events too.
    pub grid: Option<(TimeUs, TimeUs)>,
    pub seed: u64,
    /// Simulations run so far.
    pub count: Cell<usize>,
    /// The named hot pixels' events (a Poisson process at each one's rate and polarity
    /// share, measured on the fit blocks), added to every simulation so that the model and
    /// the recording are compared on the same pixels.
    pub hot_events: EventChunk,
    /// The recording's side of its lag behind each simulation
    /// ([`super::observe::lag`]), grouped on first use.
    pub lag_keys: OnceCell<LagKeys>,
}

/// How far above the recording's shortest intervals a refractory period may lie: a
/// timestamp jitter of 0.3 ms puts the 1 % quantile of the intervals 25 % below a 3.8 ms
/// period (a coverage draw, 2026-11-27), the bin edge above it may be 10 % below.
pub const JITTER_ALLOWANCE: f64 = 1.5;

/// The factor either side of a threshold that balanced at its start where
/// [`Simulation::settle_flat`] probes.
pub const FLAT_PROBE: f64 = 1.1;

/// The range a threshold profile searches: a threshold that ends at either end was not
/// matched inside it, and is a bound rather than a measurement
/// ([`super::selection`] reports it so).
pub const THRESHOLD_RANGE: (f64, f64) = (0.02, 5.0);

/// Secant steps of the threshold profile after its first simulation.
const PROFILE_STEPS: usize = 4;

/// Secant steps of the mismatch profile ([`Simulation::profile_mismatch`]).
const MISMATCH_STEPS: usize = 2;

/// A dispersion log ratio this close to zero is matched: the pooled within-tile index's
/// relative standard error is about 2 % (see [`super::effects::mismatch`]).
const DISPERSION_MATCHED: f64 = 0.02;

fn threshold_of(p: &PixelParams, polarity: usize) -> f64 {
    if polarity == 1 { p.ct_on } else { p.ct_off }
}

fn set_threshold(p: &mut PixelParams, polarity: usize, value: f64) {
    if polarity == 1 {
        p.ct_on = value;
    } else {
        p.ct_off = value;
    }
}

/// The next threshold of a profile from its tried `(ln C, median log ratio)` points: a
/// secant step in `ln C`. Counts scale about as `1 / C`, so the slope starts at -1 and a
/// measured slope is held within [-2, -0.5]: the median of integer-count ratios moves in
/// steps, and a flat stretch between two close tries would otherwise throw the step far.
fn secant_step(history: &[(f64, f64)]) -> f64 {
    let &(x1, y1) = history.last().expect("a profile step follows a try");
    let slope = match history {
        [.., (x0, y0), _] if (x1 - x0).abs() > 1e-6 => ((y1 - y0) / (x1 - x0)).clamp(-2.0, -0.5),
        _ => -1.0,
    };
    let c = x1.exp();
    (x1 - y1 / slope)
        .exp()
        .clamp(c / 2.0, c * 2.0)
        .clamp(THRESHOLD_RANGE.0, THRESHOLD_RANGE.1)
}

/// The next mismatch of a profile from its tried `(ln ct_sigma, dispersion log ratio)`
/// points: a secant step in `ln ct_sigma`. Mismatch adds `mean x (sigma / C)^2` to a
/// pixel's index of dispersion, so the log index rises with a slope of up to 2 in
/// `ln sigma`, less where the scene's own spread dominates: the slope starts at 1 and a
/// measured one is held within [0.25, 4]; a step at most doubles or halves the spread.
fn mismatch_step(history: &[(f64, f64)]) -> f64 {
    let &(x1, y1) = history.last().expect("a mismatch step follows a try");
    let slope = match history {
        [.., (x0, y0), _] if (x1 - x0).abs() > 1e-6 => ((y1 - y0) / (x1 - x0)).clamp(0.25, 4.0),
        _ => 1.0,
    };
    let sigma = x1.exp();
    (x1 - y1 / slope)
        .exp()
        .clamp(sigma / 2.0, sigma * 2.0)
        .clamp(MISMATCH_RANGE.0, MISMATCH_RANGE.1)
}

/// A simulated model: its parameters (thresholds profiled) and statistics.
#[derive(Clone)]
pub struct Simulated {
    pub params: PixelParams,
    pub observed: Observed,
}

impl Simulation<'_> {
    /// The statistics of `params` simulated on the frames; `masked` pixels left out. Hot
    /// pixels are never simulated here (they are masked in the recording instead).
    pub fn observe(
        &self,
        params: &PixelParams,
        masked: &[bool],
    ) -> Result<Observed, EstimateError> {
        let events = self.events_of(params, self.seed)?;
        let keys = self
            .lag_keys
            .get_or_init(|| Observed::lag_keys(self.events, self.geometry));
        Ok(Observed::paired(&events, self.geometry, masked, keys))
    }

    /// The events of `params` simulated on the frames with `seed`, on the recording's
    /// timestamp grid and with the named hot pixels' trains (never simulated hot pixels).
    pub fn events_of(&self, params: &PixelParams, seed: u64) -> Result<EventChunk, EstimateError> {
        self.count.set(self.count.get() + 1);
        let mut p = params.clone();
        p.seed = Some(seed);
        p.hot_pixel_fraction = None;
        p.hot_pixel_rate_hz = None;
        let mut events = resim::simulate(self.runs, self.width, self.height, &p)?;
        if let Some(grid) = self.grid {
            quantise(&mut events, grid);
        }
        if !self.hot_events.is_empty() {
            events = EventChunk::merged(&events, &self.hot_events);
        }
        Ok(events)
    }

    /// `params` with its thresholds profiled (see the module docs), unless `fixed`.
    pub fn profile(
        &self,
        params: &PixelParams,
        masked: &[bool],
        fixed: bool,
    ) -> Result<Simulated, EstimateError> {
        let mut p = params.clone();
        let mut observed = self.observe(&p, masked)?;
        if fixed {
            return Ok(Simulated {
                params: p,
                observed,
            });
        }
        // per polarity (OFF, ON): every (ln C, median log ratio) tried
        let mut history: [Vec<(f64, f64)>; 2] = [Vec::new(), Vec::new()];
        for round in 0..=PROFILE_STEPS {
            let medians = median_ratios(&self.real, &observed, self.geometry, Subset::Fit);
            let mut moved = false;
            for pol in 0..2 {
                let Some(m) = medians[pol] else { continue };
                let c = threshold_of(&p, pol);
                if !(c.is_finite() && c > 0.0) {
                    return Err(EstimateError::new(
                        format!("the threshold profile reached {c} (it must stay positive)"),
                        "report this as a bug, with the recording",
                    ));
                }
                history[pol].push((c.ln(), m));
                if m.abs() < 0.003 || round == PROFILE_STEPS {
                    continue;
                }
                set_threshold(&mut p, pol, secant_step(&history[pol]));
                moved = true;
            }
            if !moved {
                break;
            }
            observed = self.observe(&p, masked)?;
        }
        // the median ratio is a step function of C (counts are integers): a secant step
        // can overshoot, so the profile ends at the tried threshold closest to balance
        let mut best = p.clone();
        for (pol, tried) in history.iter().enumerate() {
            if let Some(&(ln_c, _)) = tried.iter().min_by(|a, b| a.1.abs().total_cmp(&b.1.abs())) {
                set_threshold(&mut best, pol, ln_c.exp());
            }
        }
        if best.ct_on != p.ct_on || best.ct_off != p.ct_off {
            observed = self.observe(&best, masked)?;
        }
        Ok(Simulated {
            params: best,
            observed,
        })
    }

    /// `params` with its thresholds profiled and its threshold mismatch (`ct_sigma`, where
    /// the model has one) moved by up to [`MISMATCH_STEPS`] secant steps towards the
    /// recording's within-tile dispersion of per-pixel counts ([`dispersion`]) on the fit
    /// blocks, the thresholds profiled again at each; the tried model with the lowest
    /// distance on the fit blocks is returned.
    ///
    /// For a search whose effect changes how counts spread over pixels as mismatch does:
    /// a refractory period caps the busiest pixels and narrows the spread, so a mismatch
    /// fitted without it is too small, and a period searched with that mismatch held is
    /// judged by a dispersion the mismatch, not the period, gets wrong (coverage draw 5009,
    /// 2026-12-02: at the true 3.7 ms the intervals' distance fell 0.196 -> 0.018 and the
    /// dispersion's rose 0.040 -> 0.258; the search ended at 2.2 ms).
    pub fn profile_mismatch(
        &self,
        params: &PixelParams,
        masked: &[bool],
        fixed: bool,
        kept: &[bool],
    ) -> Result<Simulated, EstimateError> {
        let g = self.geometry;
        let mut current = self.profile(params, masked, fixed)?;
        let real = dispersion(&self.real.pixels_of(g, Subset::Fit), g, kept);
        let (Some(real), Some(_)) = (real, params.ct_sigma) else {
            return Ok(current);
        };
        let error_of = |s: &Simulated| self.distance(&s.observed, Subset::Fit, kept).total;
        let mut best = (error_of(&current), current.clone());
        let mut history = Vec::new();
        for _ in 0..MISMATCH_STEPS {
            let simulated = dispersion(&current.observed.pixels_of(g, Subset::Fit), g, kept);
            let (Some(sigma), Some(simulated)) = (current.params.ct_sigma, simulated) else {
                break;
            };
            let ratio = dispersion_log_ratio(real, simulated);
            history.push((sigma.ln(), ratio));
            if ratio.abs() < DISPERSION_MATCHED {
                break;
            }
            let mut p = current.params.clone();
            p.ct_sigma = Some(mismatch_step(&history));
            current = self.profile(&p, masked, fixed)?;
            let error = error_of(&current);
            if error < best.0 {
                best = (error, current.clone());
            }
        }
        Ok(best.1)
    }

    /// `profiled` (the thresholds profiled from `start`) with each threshold that balanced
    /// at its very first evaluation read again from two probes [`FLAT_PROBE`] either side.
    /// The median cell ratio is a step function of the threshold (counts are integers),
    /// flat around its root: a start that happens to lie on the flat step would otherwise
    /// be reported as the fitted value. The threshold is taken where the line through the
    /// probes' medians crosses zero (within the probes), or kept where both probes balance
    /// as well (then the interval says how little the counts fix it).
    pub fn settle_flat(
        &self,
        start: &PixelParams,
        profiled: Simulated,
        masked: &[bool],
    ) -> Result<Simulated, EstimateError> {
        let flat: Vec<usize> = (0..2)
            .filter(|&pol| threshold_of(&profiled.params, pol) == threshold_of(start, pol))
            .collect();
        if flat.is_empty() {
            return Ok(profiled);
        }
        let mut probes: [Vec<(f64, f64)>; 2] = [Vec::new(), Vec::new()];
        for factor in [FLAT_PROBE, 1.0 / FLAT_PROBE] {
            let mut p = profiled.params.clone();
            for &pol in &flat {
                set_threshold(&mut p, pol, threshold_of(&profiled.params, pol) * factor);
            }
            let medians = median_ratios(
                &self.real,
                &self.observe(&p, masked)?,
                self.geometry,
                Subset::Fit,
            );
            for &pol in &flat {
                if let Some(m) = medians[pol] {
                    probes[pol].push((threshold_of(&p, pol).ln(), m));
                }
            }
        }
        let mut settled = profiled.params.clone();
        for &pol in &flat {
            if let [(x1, m1), (x2, m2)] = probes[pol][..]
                && m1 != m2
            {
                let root = (x1 - m1 * (x2 - x1) / (m2 - m1)).clamp(x1.min(x2), x1.max(x2));
                set_threshold(&mut settled, pol, root.exp());
            }
        }
        if settled == profiled.params {
            return Ok(profiled);
        }
        Ok(Simulated {
            observed: self.observe(&settled, masked)?,
            params: settled,
        })
    }

    /// The largest value `effect`'s parameter can take in this recording, read from the
    /// recording itself. A refractory period cannot be much longer than the recording's
    /// shortest same-pixel intervals (a change inside the period is delayed to its end or
    /// dropped, so no interval is shorter): [`JITTER_ALLOWANCE`] times the upper edge of the
    /// interval bin where the fit blocks' interval distribution passes 1 % (the share a
    /// jittered or noisy timestamp may fall below it; with under 100 intervals, the
    /// shortest one's bin); without any interval, the fit blocks' duration. `None`: no
    /// limit for this effect.
    pub fn upper_limit(&self, effect: super::effects::Effect) -> Option<f64> {
        use super::observe::{INTERVAL_BINS, interval_bin_start};
        if effect != super::effects::Effect::Refractory {
            return None;
        }
        let counts = self.real.intervals_of(self.geometry, Subset::Fit);
        let total: f64 = counts.iter().map(|&c| c as f64).sum();
        if total == 0.0 {
            return Some(self.geometry.duration_of(Subset::Fit));
        }
        let mut cumulative = 0.0;
        (0..INTERVAL_BINS - 1).find_map(|k| {
            cumulative += counts[k] as f64;
            (cumulative >= 0.01 * total).then(|| JITTER_ALLOWANCE * interval_bin_start(k + 1))
        })
    }

    /// The distance of `observed` from the recording over `subset`.
    pub fn distance(&self, observed: &Observed, subset: Subset, kept: &[bool]) -> Components {
        distance(&self.real, observed, self.geometry, subset, kept)
    }

    /// The recording's statistics with `masked` pixels left out.
    pub fn observe_real(&self, masked: &[bool]) -> Observed {
        Observed::new(self.events, self.geometry, masked)
    }
}

/// One evaluation of a parameter search.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Evaluation {
    pub value: f64,
    pub fit_error: f64,
    pub ct_on: f64,
    pub ct_off: f64,
}

/// The search of one effect's parameter.
struct Search<'a, 'b> {
    simulation: &'b Simulation<'a>,
    effect: super::effects::Effect,
    masked: &'b [bool],
    kept: &'b [bool],
    fixed_thresholds: bool,
    /// The mismatch profiled at every point as well ([`Simulation::profile_mismatch`]).
    mismatch_profiled: bool,
    /// Every point evaluated, and the best model so far.
    evaluations: RefCell<Vec<Evaluation>>,
    best: RefCell<Option<(f64, Simulated)>>,
    /// The thresholds of the last point (the next starts there).
    warm: RefCell<PixelParams>,
    /// Why the search stopped, where a cost could not be computed. Held by the caller: the
    /// executor drops the problem when a cost fails, and this error (with its fix) is
    /// what the caller reports.
    failure: &'b RefCell<Option<EstimateError>>,
}

impl Search<'_, '_> {
    /// Records a failure the search cannot go on from (a line search handed something
    /// not finite would step to NaN) and the error that stops the executor.
    fn fail(&self, what: String) -> ArgminError {
        *self.failure.borrow_mut() = Some(EstimateError::new(
            format!("the {} search failed: {what}", self.effect),
            "report this as a bug, with the recording",
        ));
        ArgminError::msg("the search failed")
    }
}

impl CostFunction for Search<'_, '_> {
    type Param = f64;
    type Output = f64;

    fn cost(&self, log_value: &f64) -> Result<f64, ArgminError> {
        let value = log_value.exp();
        if !value.is_finite() {
            return Err(self.fail(format!("the line search stepped to {value}")));
        }
        let mut p = self.warm.borrow().clone();
        self.effect.set(&mut p, value);
        let profiled = if self.mismatch_profiled {
            self.simulation
                .profile_mismatch(&p, self.masked, self.fixed_thresholds, self.kept)
        } else {
            self.simulation
                .profile(&p, self.masked, self.fixed_thresholds)
        };
        let simulated = match profiled {
            Ok(s) => s,
            Err(e) => {
                *self.failure.borrow_mut() = Some(e);
                return Err(ArgminError::msg("simulation failed"));
            }
        };
        let error = self
            .simulation
            .distance(&simulated.observed, Subset::Fit, self.kept)
            .total;
        if !error.is_finite() {
            return Err(self.fail(format!("the distance at {value} is {error}")));
        }
        self.evaluations.borrow_mut().push(Evaluation {
            value,
            fit_error: error,
            ct_on: simulated.params.ct_on,
            ct_off: simulated.params.ct_off,
        });
        {
            let mut warm = self.warm.borrow_mut();
            warm.ct_on = simulated.params.ct_on;
            warm.ct_off = simulated.params.ct_off;
            warm.ct_sigma = simulated.params.ct_sigma;
        }
        let mut best = self.best.borrow_mut();
        if best.as_ref().is_none_or(|(e, _)| error < *e) {
            *best = Some((error, simulated));
        }
        Ok(error)
    }
}

/// The result of a parameter search.
pub struct Searched {
    pub value: f64,
    pub model: Simulated,
    pub fit_error: f64,
    /// Standard error of the value, from the curvature of the fit error around the
    /// minimum against `noise` (how much the error moves by chance).
    pub standard_error: Option<f64>,
    /// The value sits at an end of the searched range: a bound, not a measurement.
    pub at_bound: Option<f64>,
    pub evaluations: Vec<Evaluation>,
    /// How much the fit error moves by chance (the scale of `standard_error`).
    pub noise: f64,
}

impl Searched {
    /// The value with its standard error and 95 % interval: log-normal from the curvature
    /// (`value * exp(+-1.96 sigma(ln value))`), else the profile of the evaluated values
    /// ([`profile_interval`]).
    pub fn uncertain(&self) -> super::Uncertain {
        match self.standard_error {
            Some(se) => super::Uncertain::positive(self.value, Some(se)),
            None if self.at_bound.is_none() => super::Uncertain::with_interval(
                self.value,
                None,
                profile_interval(&self.evaluations, self.value, self.noise),
            ),
            None => super::Uncertain::positive(self.value, None),
        }
    }
}

/// A 95 % interval read off the evaluated points of a search, for when no parabola fits
/// (flat or one-sided errors): on each side, the nearest evaluated value whose fit error
/// exceeds the minimum by `1.96^2 noise` (the rise a parabola with standard error
/// `sigma` has at 1.96 sigma, see [`curvature_error`]); a side where every evaluated value
/// stays within that rise is open (`None`): the data do not bound it within the range
/// searched.
pub fn profile_interval(evaluations: &[Evaluation], value: f64, noise: f64) -> Interval {
    let Some(minimum) = evaluations.iter().map(|e| e.fit_error).reduce(f64::min) else {
        return [None, None];
    };
    let rise = crate::estimate::interval::z95().powi(2) * noise.max(0.0);
    let beyond = |e: &&Evaluation| e.fit_error > minimum + rise;
    let lo = evaluations
        .iter()
        .filter(|e| e.value < value)
        .filter(beyond)
        .map(|e| e.value)
        .reduce(f64::max);
    let hi = evaluations
        .iter()
        .filter(|e| e.value > value)
        .filter(beyond)
        .map(|e| e.value)
        .reduce(f64::min);
    [lo, hi]
}

/// Searches `effect`'s parameter over `range` (Brent in its logarithm) on top of `base`.
#[allow(clippy::too_many_arguments)]
pub fn search(
    simulation: &Simulation,
    base: &PixelParams,
    effect: super::effects::Effect,
    range: (f64, f64),
    masked: &[bool],
    kept: &[bool],
    fixed_thresholds: bool,
    noise: f64,
) -> Result<Searched, EstimateError> {
    search_profiled(
        simulation,
        base,
        effect,
        range,
        (masked, kept),
        (fixed_thresholds, false),
        noise,
    )
}

/// [`search`], and with `mismatch` the threshold mismatch profiled at every point as well
/// ([`Simulation::profile_mismatch`]) where `base` has one: the returned model's `ct_sigma`
/// is the one profiled at the best point.
pub fn search_profiled(
    simulation: &Simulation,
    base: &PixelParams,
    effect: super::effects::Effect,
    range: (f64, f64),
    (masked, kept): (&[bool], &[bool]),
    (fixed_thresholds, mismatch): (bool, bool),
    noise: f64,
) -> Result<Searched, EstimateError> {
    let range = within_limit(valid_range(range), simulation.upper_limit(effect));
    let failure = RefCell::new(None);
    let problem = Search {
        simulation,
        effect,
        masked,
        kept,
        fixed_thresholds,
        mismatch_profiled: mismatch && base.ct_sigma.is_some(),
        evaluations: RefCell::new(Vec::new()),
        best: RefCell::new(None),
        warm: RefCell::new(base.clone()),
        failure: &failure,
    };
    let problem = minimised(problem, range)?;
    searched(problem, range, noise)
}

/// `problem` after Brent's search in the logarithm of `range`, or the failure that
/// stopped it.
fn minimised<'a, 'b>(
    problem: Search<'a, 'b>,
    range: (f64, f64),
) -> Result<Search<'a, 'b>, EstimateError> {
    let (effect, failure) = (problem.effect, problem.failure);
    let solver = BrentOpt::new(range.0.ln(), range.1.ln()).set_tolerance(0.03, 0.01);
    let result = Executor::new(problem, solver)
        .configure(|s| s.max_iters(16))
        .run();
    if let Some(e) = failure.take() {
        return Err(e);
    }
    match result {
        Ok(r) => Ok(r.problem.problem.expect("the executor keeps its problem")),
        Err(e) => Err(EstimateError::new(
            format!("the {effect} search failed: {e}"),
            "report this as a bug",
        )),
    }
}

/// The best point of a finished search over `range`, with its standard error against
/// `noise` (none at an end of the range).
fn searched(problem: Search, range: (f64, f64), noise: f64) -> Result<Searched, EstimateError> {
    let effect = problem.effect;
    let evaluations = problem.evaluations.into_inner();
    let Some((fit_error, model)) = problem.best.into_inner() else {
        return Err(EstimateError::new(
            format!("the {effect} search evaluated nothing"),
            "report this as a bug",
        ));
    };
    let value = evaluations
        .iter()
        .find(|e| e.fit_error == fit_error)
        .map_or(range.0, |e| e.value);
    let at_bound = [range.0, range.1]
        .into_iter()
        .find(|end| (value / end).ln().abs() < 0.05);
    Ok(Searched {
        standard_error: curvature_error(&evaluations, value, noise).filter(|_| at_bound.is_none()),
        at_bound,
        value,
        model,
        fit_error,
        evaluations,
        noise,
    })
}

/// A search range with both ends positive and finite and the lower below the upper (the
/// upper raised to twice the lower where an effect's own limits crossed).
fn valid_range((lo, hi): (f64, f64)) -> (f64, f64) {
    let lo = if lo.is_finite() && lo > 0.0 { lo } else { 1e-6 };
    let hi = if hi.is_finite() && hi > 2.0 * lo {
        hi
    } else {
        2.0 * lo
    };
    (lo, hi)
}

/// `range` with its upper end at most `limit` (the lower end kept a factor 4 below it).
fn within_limit((lo, hi): (f64, f64), limit: Option<f64>) -> (f64, f64) {
    match limit {
        Some(limit) if limit > 0.0 && hi > limit => (lo.min(limit / 4.0), limit),
        _ => (lo, hi),
    }
}

/// The standard error of a searched value: a parabola `e(x) = a (x - x0)^2 + b` through
/// the evaluations nearest the minimum (in `x = ln value`), and the distance at which the
/// error rises by `noise`: `sigma(ln value) = sqrt(noise / a)`.
pub fn curvature_error(evaluations: &[Evaluation], value: f64, noise: f64) -> Option<f64> {
    let x0 = value.ln();
    let mut near: Vec<(f64, f64)> = evaluations
        .iter()
        .map(|e| (e.value.ln() - x0, e.fit_error))
        .collect();
    near.sort_by(|a, b| a.0.abs().total_cmp(&b.0.abs()));
    near.dedup_by(|a, b| (a.0 - b.0).abs() < 1e-9);
    near.truncate(5);
    if near.len() < 3 || noise <= 0.0 {
        return None;
    }
    // least squares of e = a x^2 + c x + b
    let n = near.len() as f64;
    let (mut s4, mut s3, mut s2, mut s1, mut y2, mut y1, mut y0) =
        (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for &(x, y) in &near {
        s4 += x.powi(4);
        s3 += x.powi(3);
        s2 += x * x;
        s1 += x;
        y2 += y * x * x;
        y1 += y * x;
        y0 += y;
    }
    let m = nalgebra::Matrix3::new(s4, s3, s2, s3, s2, s1, s2, s1, n);
    let solution = m.lu().solve(&nalgebra::Vector3::new(y2, y1, y0))?;
    let a = solution[0];
    (a > 0.0).then(|| value * (noise / a).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn evaluation(value: f64, fit_error: f64) -> Evaluation {
        Evaluation {
            value,
            fit_error,
            ct_on: 0.3,
            ct_off: 0.3,
        }
    }

    #[test]
    fn a_profile_interval_ends_where_the_error_rises_past_chance_and_stays_open_where_it_does_not()
    {
        // minimum 1.0 at 2; a rise of 3.84 x 0.01 = 0.0384 is the 95 % line
        let tried = [
            evaluation(0.5, 1.0 + 0.01),
            evaluation(1.0, 1.0 + 0.05),
            evaluation(1.5, 1.0 + 0.02),
            evaluation(2.0, 1.0),
            evaluation(3.0, 1.0 + 0.03),
            evaluation(4.0, 1.0 + 0.2),
            evaluation(8.0, 1.0 + 0.5),
        ];
        assert_eq!(profile_interval(&tried, 2.0, 0.01), [Some(1.0), Some(4.0)]);
        // nothing below 2 rises by 0.0384 when chance is twice as large: open below
        assert_eq!(profile_interval(&tried, 2.0, 0.02), [None, Some(4.0)]);
        assert_eq!(profile_interval(&[], 2.0, 0.01), [None, None]);
    }

    #[test]
    fn a_range_is_cut_at_the_limit_the_recording_sets() {
        assert_eq!(within_limit((0.2, 5.0), Some(0.001)), (0.00025, 0.001));
        assert_eq!(within_limit((1e-5, 5e-4), Some(0.001)), (1e-5, 5e-4));
        assert_eq!(within_limit((0.2, 5.0), None), (0.2, 5.0));
    }

    #[test]
    fn a_mismatch_step_moves_the_spread_towards_the_recordings_dispersion() {
        // the model's counts 0.258 less dispersed (log) at 0.043: the first step has slope 1
        let first = mismatch_step(&[(0.043f64.ln(), -0.258)]);
        assert!((first - 0.043 * 0.258f64.exp()).abs() < 1e-12, "{first}");
        // a point that matched stays where it is, whatever the measured slope (here 2)
        let (x0, x1) = (0.043f64.ln(), 0.043f64.ln() + 0.129);
        let second = mismatch_step(&[(x0, -0.258), (x1, 0.0)]);
        assert!((second - x1.exp()).abs() < 1e-12, "{second}");
        // a measured slope of 1 (0.129 gained over 0.129 in ln sigma): the step is the ratio
        let next = mismatch_step(&[(x0, -0.258), (x1, -0.129)]);
        assert!((next - (x1 + 0.129).exp()).abs() < 1e-12, "{next}");
        // a measured slope of 4 (held there from 6): a quarter of the ratio
        let steep = mismatch_step(&[(x0, -0.9), (x1, -0.126)]);
        assert!((steep - (x1 + 0.126 / 4.0).exp()).abs() < 1e-12, "{steep}");
        // a step at most doubles the spread, and stays in the mismatch's range
        assert!((mismatch_step(&[(0.01f64.ln(), -5.0)]) - 0.02).abs() < 1e-12);
        assert_eq!(mismatch_step(&[(0.25f64.ln(), -0.5)]), MISMATCH_RANGE.1);
    }

    #[test]
    fn curvature_gives_the_width_of_a_parabola() {
        // e = 4 (ln v - ln 2)^2 + 1: rises by 0.04 at ln v - ln 2 = 0.1
        let evaluations: Vec<Evaluation> = [-0.3, -0.1, 0.0, 0.05, 0.2]
            .iter()
            .map(|&d: &f64| Evaluation {
                value: 2.0 * d.exp(),
                fit_error: 4.0 * d * d + 1.0,
                ct_on: 0.3,
                ct_off: 0.3,
            })
            .collect();
        let se = curvature_error(&evaluations, 2.0, 0.04).unwrap();
        assert!((se - 0.2).abs() < 1e-9, "{se}");
    }
}
