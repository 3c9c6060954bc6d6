//! The display fitted with the thresholds (step 3 of [`super`]): the squared log ratios of
//! every region's count over the stimulus ([`Joint`]) minimised by Nelder-Mead (argmin)
//! from several starts, each first placed on its black level by a coarse profile
//! ([`black_level_start`]): the counts are steps in the parameters, and a simplex started
//! far from the black level stalls on their plateaus (ideal pixels behind the display of
//! the coverage study's draw 3035: fits stuck at 15-40x the cost of the right black level,
//! their thresholds 1.5x the truth).

use super::{GammaPrior, ResponsePrior, Setup, WHITE_STARTS_DN};
use crate::estimate::EstimateError;
use crate::sim::DisplayParams;
use crate::sim::log_response::LogMap;
use argmin::core::{
    CostFunction, Error as ArgminError, Executor, IterState, State, TerminationReason,
    TerminationStatus,
};
use argmin::solver::neldermead::NelderMead;
use nalgebra::DVector;
use serde_json::json;

/// Squared log ratios of all cells, for the joint fit: parameters `ln Cp, ln Cn,
/// ln black_level, ln blur_px` and, where white is fitted (not for a measured screen
/// model, nor under the pure log whose offset the black level carries), `ln white_dn`, at
/// the display gamma `gamma`, through the sensor's log response `log`.
pub(super) struct Joint<'a, 'b> {
    pub setup: &'b Setup<'a>,
    pub screen: &'b DisplayParams,
    pub gamma: f64,
    pub log: LogMap,
}

/// Where a fit's parameters sit in its vector.
const P_WHITE: usize = 4;

impl Joint<'_, '_> {
    pub fn display(&self, p: &DVector<f64>) -> DisplayParams {
        let mut d = self.screen.clone();
        d.gamma = self.gamma;
        d.black_level = p[2].exp().clamp(1e-5, 0.5);
        d.blur_px = Some(p[3].exp().clamp(0.05, 3.0));
        if let Some(white) = p.get(P_WHITE) {
            d.white_dn = white.exp().clamp(2.0, 2000.0);
        }
        d
    }
}

impl CostFunction for Joint<'_, '_> {
    type Param = DVector<f64>;
    type Output = f64;
    fn cost(&self, p: &DVector<f64>) -> Result<f64, ArgminError> {
        let display = self.display(p);
        let simulated =
            self.setup
                .counts_through((p[0].exp(), p[1].exp()), Some(&display), self.log)?;
        let squared = |r: &[u32], s: &[u32]| -> f64 {
            r.iter()
                .zip(s)
                .filter(|(r, s)| **r >= 5 || **s >= 5)
                .map(|(&r, &s)| ((s as f64 + 1.0) / (r as f64 + 1.0)).ln().powi(2))
                .sum()
        };
        Ok(squared(&self.setup.real.on, &simulated.on)
            + squared(&self.setup.real.off, &simulated.off))
    }
}

/// A fit of the display with the thresholds, at one gamma from one start.
pub(super) struct DisplayFit {
    /// The sensor's log response the fit simulated.
    pub log: LogMap,
    pub gamma: f64,
    pub white_start_dn: f64,
    pub param: DVector<f64>,
    pub cost: f64,
    /// Not continued after the first round ([`HOPELESS_COST`]).
    pub set_aside: bool,
}

/// The display fits from every start (see [`fit_displays`]).
pub(super) struct DisplayFits(Vec<DisplayFit>);

impl DisplayFits {
    pub fn best(&self) -> &DisplayFit {
        self.0
            .iter()
            .min_by(|a, b| a.cost.total_cmp(&b.cost))
            .expect("at least one fit")
    }

    /// The thresholds of the other fits whose cost is within [`COMPATIBLE_COST`] of the
    /// best's.
    pub fn compatible(&self) -> Vec<(f64, f64)> {
        let best = self.best().cost;
        self.0
            .iter()
            .filter(|f| f.cost <= COMPATIBLE_COST * best)
            .map(|f| (f.param[0].exp(), f.param[1].exp()))
            .collect()
    }

    /// Whether a fit through another log response than the best's explains the counts as
    /// well ([`COMPATIBLE_COST`]).
    pub fn other_response_compatible(&self) -> bool {
        let best = self.best();
        self.0
            .iter()
            .any(|f| f.log != best.log && f.cost <= COMPATIBLE_COST * best.cost)
    }

    pub fn json(&self) -> serde_json::Value {
        let best = self.best().cost;
        self.0
            .iter()
            .map(|f| {
                json!({
                    "response": super::response_name(f.log),
                    "gamma": f.gamma,
                    "white_dn_start": f.white_start_dn,
                    "ct_on": f.param[0].exp(),
                    "ct_off": f.param[1].exp(),
                    "white_dn": f.param.get(P_WHITE).map_or(f.white_start_dn, |w| w.exp()),
                    "black_level": f.param[2].exp(),
                    "cost": f.cost,
                    "compatible": f.cost <= COMPATIBLE_COST * best,
                    "set_aside": f.set_aside,
                })
            })
            .collect()
    }
}

/// Fits whose cost is at most this multiple of the best's are taken as explaining the counts
/// as well (the residuals are dominated by what ideal pixels lack -- mismatch, noise --
/// not by count noise, so a likelihood ratio over the cells would exclude every fit but the
/// best, and which fit is best along the valley is itself down to that mismatch): on the
/// coverage study's on-screen cases and the shipped samples the fits along the valley cost
/// up to 2.6x the best (the truth lying among them), fits stuck away from it 20-50x.
pub(super) const COMPATIBLE_COST: f64 = 3.0;

/// The joint fits from every [`display_starts`], two at a time: the counts do not resolve
/// gamma from the camera DN of white (nor, through the sensor's dark response, white from
/// the threshold), and each fit ends where its start leads it along that valley. The fits
/// are made in two rounds ([`FIRST_ROUND`]); those the first leaves far from the best
/// ([`HOPELESS_COST`]) are not continued.
pub(super) fn fit_displays(
    setup: &Setup,
    screen: &DisplayParams,
    (gamma_prior, response_prior): (GammaPrior, ResponsePrior),
    naive: (f64, f64),
) -> Result<DisplayFits, EstimateError> {
    use rayon::prelude::*;
    let starts = display_starts(screen, gamma_prior, response_prior);
    let first: Vec<Result<Running, EstimateError>> = starts
        .par_iter()
        .map(|start| Running::start(setup, screen, start, naive)?.iterate(FIRST_ROUND))
        .collect();
    let leading = first
        .iter()
        .flatten()
        .map(|f| f.state.best_cost)
        .fold(f64::INFINITY, f64::min);
    let fits: Vec<Result<DisplayFit, EstimateError>> = first
        .into_par_iter()
        .map(|fit| {
            let fit = fit?;
            let hopeless = fit.state.best_cost > HOPELESS_COST * leading;
            let fit = if hopeless {
                fit
            } else {
                fit.iterate(ITERATIONS)?
            };
            Ok(fit.result(hopeless))
        })
        .collect();
    let mut done = Vec::new();
    let mut failure = None;
    for fit in fits {
        match fit {
            Ok(fit) if fit.cost.is_finite() => done.push(fit),
            Ok(_) => {}
            Err(e) => failure = Some(e),
        }
    }
    match (done.is_empty(), failure) {
        (true, Some(e)) => Err(e),
        (true, None) => Err(EstimateError::new(
            "the display fit found no finite cost from any start",
            "report this as a bug",
        )),
        _ => Ok(DisplayFits(done)),
    }
}

/// The Nelder-Mead iterations of a display fit.
const ITERATIONS: u64 = 140;

/// The Nelder-Mead iterations every display fit makes before the fits are compared
/// ([`HOPELESS_COST`]). On `dev_screen_checker` the fits' costs fell by at most 1.5x after
/// 40 iterations (7.2 to 4.9; by 2.1x after 30).
const FIRST_ROUND: u64 = 40;

/// A fit whose cost after [`FIRST_ROUND`] is above this multiple of the lowest is not
/// continued: to end within [`COMPATIBLE_COST`] of the best it would have to fall by
/// more than 2x while the best stood still, beyond what the fits fall after that round.
/// Such fits (stuck on a plateau of the counts far from the black level, 5-50x the best's
/// cost) made a third of the Nelder-Mead evaluations, and only their incompatibility is
/// used. Continuing the others resumes their simplex, so they end where a single run would.
const HOPELESS_COST: f64 = 2.0 * COMPATIBLE_COST;

type Simplex = NelderMead<DVector<f64>, f64>;
type SimplexState = IterState<DVector<f64>, (), (), (), (), f64>;

/// A display fit under way: its problem, and the Nelder-Mead simplex and state to resume.
struct Running<'a, 'b> {
    problem: Joint<'a, 'b>,
    white_start_dn: f64,
    solver: Simplex,
    state: SimplexState,
}

impl<'a, 'b> Running<'a, 'b> {
    /// The fit from `start`, placed on its black level ([`black_level_start`]), before its
    /// first iteration.
    fn start(
        setup: &'b Setup<'a>,
        screen: &'b DisplayParams,
        start: &DisplayStart,
        naive: (f64, f64),
    ) -> Result<Self, EstimateError> {
        let mut from = vec![
            naive.0.ln(),
            naive.1.ln(),
            screen.black_level.max(1e-4).ln(),
            screen.blur_px.unwrap_or(0.7).max(0.1).ln(),
        ];
        if let Some(white) = start.white_fitted_from {
            from.push(white.max(2.0).ln());
        }
        let problem = Joint {
            setup,
            screen,
            gamma: start.gamma,
            log: start.log,
        };
        let from = black_level_start(&problem, DVector::from_vec(from))?;
        let steps = [0.15, 0.15, 0.5, 0.3, 0.5];
        let solver = NelderMead::new(simplex_around(&from, &steps[..from.len()]))
            .with_sd_tolerance(2e-3)
            .map_err(|e| EstimateError::new(e.to_string(), "report this as a bug"))?;
        Ok(Self {
            problem,
            white_start_dn: start.white_fitted_from.unwrap_or(screen.white_dn),
            solver,
            state: SimplexState::new().param(from),
        })
    }

    /// The fit continued to `iterations` in all ([`resumed`]).
    fn iterate(self, iterations: u64) -> Result<Self, EstimateError> {
        let (problem, solver, state) = resumed(self.problem, self.solver, self.state, iterations)
            .map_err(|e| {
            EstimateError::new(format!("display fit: {e}"), "report this as a bug")
        })?;
        Ok(Self {
            problem,
            solver,
            state,
            ..self
        })
    }

    /// The fit's best parameters (`set_aside`: not continued after the first round).
    fn result(self, set_aside: bool) -> DisplayFit {
        let param = self.state.best_param.or(self.state.param).expect("a start");
        DisplayFit {
            log: self.problem.log,
            gamma: self.problem.gamma,
            white_start_dn: self.white_start_dn,
            param,
            cost: self.state.best_cost,
            set_aside,
        }
    }
}

/// Where one display fit starts.
struct DisplayStart {
    log: LogMap,
    gamma: f64,
    /// The camera DN of white the fit starts from (`None`: not fitted, the screen model's).
    white_fitted_from: Option<f64>,
}

/// The display fits' starts: for each candidate response, the prior's centre from the
/// screen model's white and from a dim white, and both ends from a dim and a bright white
/// ([`WHITE_STARTS_DN`]); where white is not fitted (a measured screen model, whose white
/// is kept, or the pure log whose offset the black level absorbs, under which it drops
/// out) one fit per gamma.
fn display_starts(
    screen: &DisplayParams,
    gamma_prior: GammaPrior,
    response_prior: ResponsePrior,
) -> Vec<DisplayStart> {
    let [low, high] = gamma_prior.range();
    let mut starts = Vec::new();
    for (log, white_matters) in response_prior.candidates() {
        let fitted = white_matters && gamma_prior == GammaPrior::Displays;
        let start = |gamma: f64, white: f64| DisplayStart {
            log,
            gamma,
            white_fitted_from: fitted.then_some(white),
        };
        starts.push(start(gamma_prior.centre(), screen.white_dn));
        if fitted {
            starts.push(start(gamma_prior.centre(), WHITE_STARTS_DN[0]));
        }
        for gamma in [low, high] {
            if fitted {
                starts.extend(WHITE_STARTS_DN.map(|white| start(gamma, white)));
            } else {
                starts.push(start(gamma, screen.white_dn));
            }
        }
    }
    starts
}

/// Nelder-Mead on `problem` continued from `state` to `iterations` in all, unless it has
/// converged: argmin's executor skips the solver's initialisation once iterations were
/// made, so the simplex goes on where it stopped, without evaluating it again, and a run
/// in rounds is the single run.
fn resumed<O>(
    problem: O,
    solver: Simplex,
    mut state: SimplexState,
    iterations: u64,
) -> Result<(O, Simplex, SimplexState), ArgminError>
where
    O: CostFunction<Param = DVector<f64>, Output = f64>,
{
    match state.termination_status {
        TerminationStatus::Terminated(TerminationReason::MaxItersReached) => {
            state.termination_status = TerminationStatus::NotTerminated;
        }
        TerminationStatus::Terminated(_) => return Ok((problem, solver, state)),
        TerminationStatus::NotTerminated => {}
    }
    let mut result = Executor::new(problem, solver)
        .configure(|_| state.max_iters(iterations))
        .run()?;
    let problem = result
        .problem
        .take_problem()
        .expect("the executor returns its problem");
    Ok((problem, result.solver, result.state))
}

/// The black levels a fit's start is chosen among, as fractions of white: from a
/// 100,000:1 contrast ratio (OLED and local-dimming panels) over 1,000:1 (a typical LCD)
/// to 3:1 (a projector in a lit room), a factor of about 3 apart above 1e-4. Through a pure log the
/// black level also carries the sensor's dark offset (see [`super::ResponsePrior`]), which
/// can lift it to that end.
const BLACK_LEVELS: [f64; 9] = [1e-5, 1e-4, 3e-4, 1e-3, 3e-3, 0.01, 0.03, 0.1, 0.3];

/// The factor a start threshold is lowered by where it fires no event at a black level
/// ([`black_level_start`]), and how many times (down to 1/64 of the start). A dim screen
/// seen through a sensor whose dark offset is large against it (DVS-Voltmeter's
/// `ln(DN + k2)`, `k2` 20-36 DN, behind a white of 70 DN: about 1.1 in log between white
/// and black) fires nothing at the naive thresholds once the black level carries that
/// offset, and no count ratio scales a start that fires nothing: every fit then started
/// from a black level 10^2-10^4 too low (coverage draw 38 of 2026-11-25, made again with
/// ctcal's own pixel through that response: 1.82 / 2.71 [1.27, 2.37] / [1.17, 4.26] for
/// 0.64).
const SILENT_STEP: f64 = 4.0;
const SILENT_TRIES: usize = 3;

/// `from` with the black level of [`BLACK_LEVELS`] or the screen model's whose counts match
/// best, each tried with the thresholds scaled by its ratio of simulated to recorded events
/// per polarity (an ideal pixel's count is inversely proportional to its threshold), after
/// lowering a threshold that fires nothing ([`SILENT_STEP`]): two simulations a level where
/// both fire.
fn black_level_start(problem: &Joint, from: DVector<f64>) -> Result<DVector<f64>, EstimateError> {
    let real = &problem.setup.real;
    let total = |c: &[u32]| c.iter().map(|&n| n as f64).sum::<f64>();
    let (real_on, real_off) = (total(&real.on), total(&real.off));
    let mut best = (f64::INFINITY, from.clone());
    // the model's black level where it is not on the grid (a black level of 0 is the
    // grid's lowest)
    let model_black = problem.screen.black_level.max(BLACK_LEVELS[0]);
    let off_grid = (!BLACK_LEVELS.contains(&model_black)).then_some(model_black);
    let [low, high] = super::THRESHOLD_LIMITS.map(f64::ln);
    for black in BLACK_LEVELS.into_iter().chain(off_grid) {
        let mut p = from.clone();
        p[2] = black.ln();
        let simulate = |p: &DVector<f64>| {
            problem.setup.counts_through(
                (p[0].exp(), p[1].exp()),
                Some(&problem.display(p)),
                problem.log,
            )
        };
        let mut simulated = simulate(&p)?;
        // a threshold above every log step the display makes at this level fires nothing,
        // and no count ratio scales it: lowered by SILENT_STEP until it fires
        for _ in 0..SILENT_TRIES {
            let silent = [
                total(&simulated.on) == 0.0 && real_on > 0.0,
                total(&simulated.off) == 0.0 && real_off > 0.0,
            ];
            if silent == [false, false] {
                break;
            }
            for k in (0..2).filter(|&k| silent[k]) {
                p[k] = (p[k] - SILENT_STEP.ln()).max(low);
            }
            simulated = simulate(&p)?;
        }
        let (on, off) = (total(&simulated.on), total(&simulated.off));
        if on > 0.0 && real_on > 0.0 {
            p[0] += (on / real_on).ln();
        }
        if off > 0.0 && real_off > 0.0 {
            p[1] += (off / real_off).ln();
        }
        p[0] = p[0].clamp(low, high);
        p[1] = p[1].clamp(low, high);
        let cost = problem
            .cost(&p)
            .map_err(|e| EstimateError::new(e.to_string(), "report this as a bug"))?;
        if cost < best.0 {
            best = (cost, p);
        }
    }
    Ok(best.1)
}

/// A Nelder-Mead start simplex: `start` and, for each coordinate, `start` moved by its step.
fn simplex_around(start: &DVector<f64>, steps: &[f64]) -> Vec<DVector<f64>> {
    (0..=steps.len())
        .map(|k| {
            let mut v = start.clone();
            if k > 0 {
                v[k - 1] += steps[k - 1];
            }
            v
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock's valley, which Nelder-Mead descends slowly.
    struct Valley;

    impl CostFunction for Valley {
        type Param = DVector<f64>;
        type Output = f64;
        fn cost(&self, p: &DVector<f64>) -> Result<f64, ArgminError> {
            Ok((1.0 - p[0]).powi(2) + 100.0 * (p[1] - p[0] * p[0]).powi(2))
        }
    }

    /// A fit made in rounds ends where the single run does, bit for bit (here converging in
    /// the second round).
    #[test]
    fn a_fit_resumed_in_rounds_is_the_single_run() {
        let solver = || {
            let from = DVector::from_vec(vec![-1.2, 1.0]);
            NelderMead::new(simplex_around(&from, &[0.1, 0.1]))
                .with_sd_tolerance(1e-12)
                .unwrap()
        };
        let (_, _, single) = resumed(Valley, solver(), SimplexState::new(), 150).unwrap();
        let (_, rest, first) = resumed(Valley, solver(), SimplexState::new(), 40).unwrap();
        let (_, _, rounds) = resumed(Valley, rest, first, 150).unwrap();
        assert!((41..150).contains(&single.iter), "{}", single.iter);
        assert_eq!(rounds.iter, single.iter);
        assert_eq!(rounds.best_cost.to_bits(), single.best_cost.to_bits());
        assert_eq!(rounds.best_param, single.best_param);
    }
}
