//! Threshold root-finding, shared by the methods that re-simulate a recording (`aps`'
//! re-simulation, `screen`): the threshold of one polarity at which the simulated counts
//! match the recorded ones, the root of `f(c)` = the median log ratio simulated / real
//! ([`super::resim::log_ratio`]), which falls as `c` grows (a larger threshold fires fewer
//! events).
//!
//! The root is bracketed by walking from the current value in the direction the sign of
//! `f` points, in steps that double on a log scale (an exponential search; Bentley & Yao,
//! "An almost optimal algorithm for unbounded searching", 1976), and then located by
//! Brent's method (argmin's `BrentRoot`; Brent, *Algorithms for Minimization without
//! Derivatives*, 1973, ch. 4). Every value of `f` is a full simulation, so each is computed
//! once: the walk's last two probes are Brent's bracket and are not simulated again.
//!
//! A median of count ratios is a step function, and where the median cell's counts are
//! equal it is exactly 0 over a range of thresholds. Brent stops at the first point of that
//! plateau it meets, which depends on the bracket; the middle of the plateau does not, and
//! is returned instead (its ends found by bisection to a 64th of the bracket).

use super::EstimateError;
use argmin::core::{CostFunction, Error as ArgminError, Executor};
use argmin::solver::brent::BrentRoot;
use std::sync::Mutex;

/// How the bracket is searched and the root located.
#[derive(Clone, Copy, Debug)]
pub struct Search {
    /// The walk's first step, in ln(threshold); each further step doubles.
    pub first_log_step: f64,
    /// The thresholds the walk may reach: `[lowest, highest]`.
    pub limits: [f64; 2],
    /// Brent's tolerance, relative to the start.
    pub relative_tolerance: f64,
    /// Brent's iterations at most.
    pub max_iterations: u64,
}

/// What the search found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Crossing {
    /// The threshold where the counts match.
    Root(f64),
    /// No sign change between the start and the limit the walk reached: the simulation
    /// makes too many events even at `reached` (`too_many`), or too few.
    Beyond { reached: f64, too_many: bool },
}

/// The root of `f` from `start` (see the module docs). `f` is called once per distinct
/// threshold.
pub fn threshold_root(
    f: impl Fn(f64) -> Result<f64, EstimateError>,
    start: f64,
    search: &Search,
) -> Result<Crossing, EstimateError> {
    let cached = Cached {
        f,
        seen: Mutex::new(Vec::new()),
    };
    let [lowest, highest] = search.limits;
    if !(lowest.is_finite() && highest.is_finite() && lowest > 0.0 && highest >= lowest) {
        return Err(EstimateError::new(
            format!(
                "no thresholds to search: the range {lowest} .. {highest} is not a range of positive values"
            ),
            "report this as a bug, with the recording",
        ));
    }
    if !start.is_finite() {
        return Err(EstimateError::new(
            format!("the threshold search cannot start at {start}"),
            "report this as a bug, with the recording",
        ));
    }
    let start = start.clamp(lowest, highest);
    let at_start = cached.value(start)?;
    let (root, ends) = if at_start == 0.0 {
        (start, (start, start))
    } else {
        let (lo, hi) = match bracket(&cached, start, at_start > 0.0, search)? {
            Ok(bracket) => bracket,
            Err(beyond) => return Ok(beyond),
        };
        let root = if cached.value(lo)? == 0.0 {
            lo
        } else if cached.value(hi)? == 0.0 {
            hi
        } else {
            brent(&cached, (lo, hi), start, search)?
        };
        (root, (lo, hi))
    };
    Ok(Crossing::Root(plateau_middle(&cached, root, ends, search)?))
}

/// The walk from `start` (where `f` is positive when `too_many`) to the first probe where
/// `f` is 0 or changes sign: the bracket `(lo, hi)`, or [`Crossing::Beyond`] at a limit.
fn bracket<F: Fn(f64) -> Result<f64, EstimateError>>(
    cached: &Cached<F>,
    start: f64,
    too_many: bool,
    search: &Search,
) -> Result<Result<(f64, f64), Crossing>, EstimateError> {
    let [lowest, highest] = search.limits;
    // f > 0: too many simulated events, so the threshold must grow
    let (limit, direction) = if too_many {
        (highest, 1.0)
    } else {
        (lowest, -1.0)
    };
    let mut previous = start;
    let mut step = search.first_log_step;
    loop {
        if previous == limit {
            return Ok(Err(Crossing::Beyond {
                reached: limit,
                too_many,
            }));
        }
        let probe = (previous.ln() + direction * step)
            .exp()
            .clamp(lowest, highest);
        let value = cached.value(probe)?;
        if value == 0.0 || (value > 0.0) != too_many {
            return Ok(Ok((previous.min(probe), previous.max(probe))));
        }
        previous = probe;
        step *= 2.0;
    }
}

/// Brent's root of `f` within `(lo, hi)`, where it changes sign.
fn brent<F: Fn(f64) -> Result<f64, EstimateError>>(
    cached: &Cached<F>,
    (lo, hi): (f64, f64),
    start: f64,
    search: &Search,
) -> Result<f64, EstimateError> {
    let solver = BrentRoot::new(lo, hi, search.relative_tolerance * start);
    let result = Executor::new(cached, solver)
        .configure(|state| state.param(start).max_iters(search.max_iterations))
        .run()
        .map_err(|e| {
            EstimateError::new(
                format!("the threshold's root search failed: {e}"),
                "report this as a bug",
            )
        })?;
    Ok(result.state.best_param.unwrap_or(0.5 * (lo + hi)))
}

/// The middle of the plateau of zeros `root` lies on (`root` itself where `f(root)` is not
/// exactly 0). `probes` are points already known, used as the outer ends where `f` is not 0
/// there; on a side without one, the search walks outwards from `root` as the bracket did.
fn plateau_middle<F: Fn(f64) -> Result<f64, EstimateError>>(
    cached: &Cached<F>,
    root: f64,
    probes: (f64, f64),
    search: &Search,
) -> Result<f64, EstimateError> {
    if cached.value(root)? != 0.0 {
        return Ok(root);
    }
    let [lowest, highest] = search.limits;
    // a point beyond the plateau on the side `direction` (-1 below, +1 above)
    let outside = |direction: f64| -> Result<f64, EstimateError> {
        let known = if direction < 0.0 {
            probes.0.min(probes.1)
        } else {
            probes.0.max(probes.1)
        };
        if (known - root) * direction > 0.0 && cached.value(known)? != 0.0 {
            return Ok(known);
        }
        let (mut c, mut step) = (root, search.first_log_step);
        loop {
            c = (c.ln() + direction * step).exp().clamp(lowest, highest);
            if cached.value(c)? != 0.0 || c == lowest || c == highest {
                return Ok(c);
            }
            step *= 2.0;
        }
    };
    // one end of the plateau: from `zero` (f = 0) towards `outside` (f != 0)
    let edge = |mut zero: f64, mut outside: f64| -> Result<f64, EstimateError> {
        for _ in 0..6 {
            let mid = 0.5 * (zero + outside);
            if cached.value(mid)? == 0.0 {
                zero = mid;
            } else {
                outside = mid;
            }
        }
        Ok(zero)
    };
    let left = edge(root, outside(-1.0)?)?;
    let right = edge(root, outside(1.0)?)?;
    Ok(0.5 * (left + right))
}

/// `f` with its values kept, so that no threshold is simulated twice.
struct Cached<F> {
    f: F,
    seen: Mutex<Vec<(f64, f64)>>,
}

impl<F: Fn(f64) -> Result<f64, EstimateError>> Cached<F> {
    fn value(&self, c: f64) -> Result<f64, EstimateError> {
        let known = self
            .seen
            .lock()
            .map_err(|_| {
                EstimateError::new("a root search's cache was poisoned", "report this as a bug")
            })?
            .iter()
            .find(|(at, _)| *at == c)
            .map(|(_, v)| *v);
        if let Some(v) = known {
            return Ok(v);
        }
        let v = (self.f)(c)?;
        if let Ok(mut seen) = self.seen.lock() {
            seen.push((c, v));
        }
        Ok(v)
    }
}

impl<F: Fn(f64) -> Result<f64, EstimateError>> CostFunction for &Cached<F> {
    type Param = f64;
    type Output = f64;
    fn cost(&self, c: &f64) -> Result<f64, ArgminError> {
        Ok(self.value(*c)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    const SEARCH: Search = Search {
        first_log_step: 0.25,
        limits: [0.01, 6.0],
        relative_tolerance: 1e-6,
        max_iterations: 60,
    };

    /// A count ratio falling as 1/c: ln(c0 / c), root at c0.
    fn falling(c0: f64) -> impl Fn(f64) -> Result<f64, EstimateError> {
        move |c: f64| Ok((c0 / c).ln())
    }

    #[test]
    fn finds_roots_far_above_and_below_the_start() {
        for root in [0.012, 0.05, 0.3, 1.7, 5.5] {
            let Crossing::Root(found) = threshold_root(falling(root), 0.3, &SEARCH).unwrap() else {
                panic!("no root found for {root}");
            };
            assert!((found / root - 1.0).abs() < 1e-4, "{found} for {root}");
        }
    }

    #[test]
    fn says_which_side_a_root_beyond_the_limits_lies() {
        assert_eq!(
            threshold_root(falling(9.0), 0.3, &SEARCH).unwrap(),
            Crossing::Beyond {
                reached: 6.0,
                too_many: true
            }
        );
        assert_eq!(
            threshold_root(falling(0.005), 0.3, &SEARCH).unwrap(),
            Crossing::Beyond {
                reached: 0.01,
                too_many: false
            }
        );
    }

    #[test]
    fn a_start_or_limits_that_are_not_positive_thresholds_are_an_error_not_a_panic() {
        // a coverage draw's event timing gave ON -0.001: limits -0.0004 .. -0.0016
        let search = Search {
            limits: [-0.0004, -0.0016],
            ..SEARCH
        };
        let e = threshold_root(falling(0.3), -0.001, &search).unwrap_err();
        assert!(
            e.to_string().contains("not a range of positive values"),
            "{e}"
        );
        let e = threshold_root(falling(0.3), f64::NAN, &SEARCH).unwrap_err();
        assert!(e.to_string().contains("cannot start at NaN"), "{e}");
    }

    #[test]
    fn simulates_no_threshold_twice() {
        let calls = Cell::new(0);
        let seen = std::cell::RefCell::new(Vec::new());
        let f = |c: f64| {
            calls.set(calls.get() + 1);
            assert!(!seen.borrow().contains(&c), "{c} evaluated twice");
            seen.borrow_mut().push(c);
            Ok((0.8 / c).ln())
        };
        threshold_root(f, 0.3, &SEARCH).unwrap();
        // start, the walk 0.39, 0.49, 0.81 (bracket), then Brent's interior points only
        assert!(calls.get() < 20, "{} simulations", calls.get());
    }

    #[test]
    fn a_plateau_of_zeros_gives_its_middle_from_any_start() {
        let f = |c: f64| {
            Ok(if c < 0.4 {
                1.0
            } else if c > 0.6 {
                -1.0
            } else {
                0.0
            })
        };
        for start in [0.1, 0.3, 0.45, 0.9, 3.0] {
            let Crossing::Root(found) = threshold_root(f, start, &SEARCH).unwrap() else {
                panic!("no root from {start}");
            };
            // each end found to a 64th of the bracket the walk made
            assert!((found - 0.5).abs() < 0.03, "{found} from {start}");
        }
    }
}
