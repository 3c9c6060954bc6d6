//! Photoreceptor bandwidth: the photoreceptor is a first-order low-pass filter whose
//! cutoff is proportional to the photocurrent, so in the dark a fast change is smoothed and
//! crosses fewer thresholds (Lichtsteiner, Posch & Delbruck, JSSC 2008; modelled as v2e does,
//! cutoff `cutoff_hz * (DN + 20) / 275`, [`crate::sim::effects::bandwidth`]).
//!
//! Signature: against a model without it, the recording has a count deficit that grows as
//! intensity falls and change gets faster: the filter's time constant goes as one over the
//! intensity, so what it removes depends on the change rate over the intensity. Evidence:
//! the weighted least-squares slope of the count-cell log ratio `ln(simulated / real)`
//! against `ln(change rate / intensity)` is positive (the model over-predicts fast changes
//! in the dark), in standard errors from the scatter of the cells about the line; it matters
//! when the ratio changes by more than 10 % across the cells seen. Noise, which adds events
//! where the scene changes slowly, is kept out: the cells count supported events only.
//!
//! A bandwidth that delays events without thinning them (slow changes, or a cutoff well
//! above the change rates) leaves the counts alone; it shows in the recording's lag behind
//! the model ([`crate::fit::observe::lag`]). A first-order low-pass lags a ramp by its time
//! constant `1 / (2 pi fc)`, and under the cutoff law above that is `tau_1(DN) / cutoff_hz`
//! with `tau_1 = 275 / (2 pi (DN + 20))` seconds, so the recording lags more in the dark.
//! The lag of a bin is the lag both its ON and OFF events show (the smaller median lag
//! where the two have one sign, none where they differ): a threshold the model puts off
//! moves one polarity's events and not the other's, a delay moves both alike
//! ([`crate::fit::observe::lag`], which pairs the starts of bursts, so that a delay of
//! tens of milliseconds does not pair with the next event). Evidence: a darker intensity
//! bin than the brightest seen whose lag, on its own or over the brightest bin's where
//! that lags too (the whole scene dim), is largest in standard errors; it matters when the
//! lag is above a fifth of a frame interval ([`LAG_RELEVANT`]). The search starts at the cutoff
//! that explains it, `tau_1(dark) / lag` or `(tau_1(dark) - tau_1(bright)) / excess`. The
//! brightest bin lagging alone is not read as a bandwidth, and a lag alike at every
//! intensity (a frame timestamp offset) that calls for the search is not kept by it: the
//! distance's `lag` component is taken about its mean.
//! A filter lags a ramp by its time constant only where the ramp is long against it, and a
//! lag near half the burst gap (100 ms) can pair with the next burst: coverage draw 6006's
//! darkest bin (time constant 85 ms) reads 38 to 44 ms. So the lag's shape is not fitted
//! here. The evidence is the stronger of the two.

use super::{Context, Effect, Evidence};
use crate::fit::metric::cell_ratios;
use crate::fit::observe::lag::BinDelay;
use crate::fit::observe::{Geometry, INTENSITY_BINS, cell_of};

/// The evidence of the counts or of the lag, whichever is stronger.
pub fn evidence(c: &Context) -> Evidence {
    evidence_over(c, &NoiseFloor::default())
}

/// The standard errors the evidence divides by, held at least at another comparison's: a
/// detection limit judges the signal a simulated cutoff leaves in a simulated recording
/// against the noise of the real one beside the model, which holds what the model misses
/// (the fit's bandwidth detection, `fit::selection::bandwidth_detection`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoiseFloor {
    /// The count part's standard error of the slope (infinite where the other comparison
    /// has too few cells for one).
    pub count_slope: f64,
    /// The lag part's standard error of each intensity bin's median lag, seconds; infinite
    /// where the other comparison has no lag in the bin (too few paired events): a
    /// recording like it has none to read there either.
    pub lag_s: [f64; INTENSITY_BINS],
}

impl NoiseFloor {
    /// Whether the comparison it was read from had nothing the evidence reads: no count
    /// slope and no lag in any intensity bin (every floor infinite).
    pub fn reads_nothing(&self) -> bool {
        self.count_slope.is_infinite() && self.lag_s.iter().all(|s| s.is_infinite())
    }
}

/// The standard errors of `c`'s evidence, as a floor for another's.
pub fn noise_of(c: &Context) -> NoiseFloor {
    let mut floor = NoiseFloor {
        count_slope: f64::INFINITY,
        lag_s: [f64::INFINITY; INTENSITY_BINS],
    };
    if let Some((_, se, _)) = weighted_slope(&count_points(c)) {
        floor.count_slope = se;
    }
    for (bin, delay) in c.sim.delay_of(c.geometry, c.subset).iter().enumerate() {
        if let Some(d) = delay {
            floor.lag_s[bin] = d.common.standard_error_s;
        }
    }
    floor
}

/// [`evidence`] with its standard errors held at least at `floor`.
pub fn evidence_over(c: &Context, floor: &NoiseFloor) -> Evidence {
    let counts = count_evidence(c, floor);
    match lag_evidence(c, floor) {
        Some(lag) if lag.relevant && (lag.score > counts.score || !counts.relevant) => Evidence {
            text: format!("{}; {}", lag.text, counts.text),
            ..lag
        },
        Some(lag) => Evidence {
            text: format!("{}; {}", counts.text, lag.text),
            ..counts
        },
        None => counts,
    }
}

/// The time constant (seconds) of a cutoff of 1 Hz at white at `dn` under v2e's law.
fn tau_of_1_hz(dn: f64) -> f64 {
    275.0 / (2.0 * std::f64::consts::PI * (dn + 20.0))
}

/// The lag, in frame intervals, the lag part needs to matter: above the re-simulation's own
/// timing error between frames. Fitted models without a bandwidth on coverage draws that
/// have none left 0.08 (draw 6017, pooled polarities) and 0.04 (6014, the mean of ON and
/// OFF; pooled it read 0.21, a threshold level error); a 117 Hz cutoff in a 30 DN scene
/// (6023) lags 0.24, a 20 Hz one (6006) 2.7. Draw 6029 (a rotation at 570 px/s, 7 px a
/// frame, no bandwidth) lagged 0.76 of an interval more at 57 DN than at 113 DN in the mean
/// of its polarities, its OFF events alone late (its OFF threshold fitted 31 % low), and the
/// search kept a 194 Hz cutoff; the lag both polarities show is none.
pub const LAG_RELEVANT: f64 = 0.2;

/// One reading of the lag: a darker bin's lag, on its own or over the brightest bin's.
struct LagReading {
    dark: usize,
    excess_s: f64,
    z: f64,
    cutoff_hz: f64,
    against: Option<usize>,
    /// The dark bin's OFF and ON median lags, seconds.
    polarities_s: (f64, f64),
}

/// The lag part (see the module docs); `None` without two intensity bins of paired events.
fn lag_evidence(c: &Context, floor: &NoiseFloor) -> Option<Evidence> {
    let g = c.geometry;
    let relevant_s = LAG_RELEVANT * g.frame_interval_s;
    let best = strongest_lag(&floored_delays(c, floor), g, relevant_s)?;
    Some(Evidence {
        effect: Effect::Bandwidth,
        score: best.z,
        relevant: best.excess_s > relevant_s,
        text: best.text(g),
        other_start: None,
        start: (best.excess_s > 0.0).then(|| {
            let (lo, hi) = Effect::Bandwidth.range(100.0);
            best.cutoff_hz.clamp(lo, hi)
        }),
    })
}

/// The intensity bins with paired events, darkest first, each with the delay both
/// polarities show; its standard error held at least at `floor`'s.
fn floored_delays(c: &Context, floor: &NoiseFloor) -> Vec<(usize, BinDelay)> {
    c.sim
        .delay_of(c.geometry, c.subset)
        .iter()
        .enumerate()
        .filter_map(|(bin, lag)| {
            lag.map(|mut l| {
                let se = &mut l.common.standard_error_s;
                *se = se.max(floor.lag_s[bin]);
                (bin, l)
            })
        })
        .collect()
}

/// Of every darker bin's readings, on its own and over the brightest bin, the one whose
/// lag is relevant (above `relevant_s`) and largest in standard errors; `None` without two
/// bins.
fn strongest_lag(bins: &[(usize, BinDelay)], g: &Geometry, relevant_s: f64) -> Option<LagReading> {
    let &(bright, reference) = bins.last()?;
    let tau = |bin: usize| tau_of_1_hz(g.intensity_centres[bin]);
    bins[..bins.len() - 1]
        .iter()
        .flat_map(|&(dark, d)| {
            let (l, reference) = (d.common, reference.common);
            let polarities_s = (d.off_s, d.on_s);
            let own = LagReading {
                dark,
                excess_s: l.median_s,
                z: l.median_s / l.standard_error_s,
                cutoff_hz: tau(dark) / l.median_s,
                against: None,
                polarities_s,
            };
            // over the brightest bin only where it lags too (a dim scene): a brightest bin
            // ahead of the model would add its lead to the dark bin's lag
            let excess_s = l.median_s - reference.median_s;
            let over = (reference.median_s > 0.0).then_some(LagReading {
                dark,
                excess_s,
                z: excess_s / l.standard_error_s.hypot(reference.standard_error_s),
                cutoff_hz: (tau(dark) - tau(bright)) / excess_s,
                against: Some(bright),
                polarities_s,
            });
            std::iter::once(own).chain(over)
        })
        .max_by(|a, b| {
            (a.excess_s > relevant_s)
                .cmp(&(b.excess_s > relevant_s))
                .then(a.z.total_cmp(&b.z))
        })
}

impl LagReading {
    /// What the reading says: no lag both polarities show, or the lag and the cutoff that
    /// explains it.
    fn text(&self, g: &Geometry) -> String {
        let centre = |bin: usize| g.intensity_centres[bin];
        match self.against {
            _ if self.excess_s <= 0.0 => format!(
                "no lag that the recording's ON and OFF events both show (at {:.0} DN OFF {:+.2} ms, ON {:+.2} ms: a delay moves both, a threshold the model puts off one)",
                centre(self.dark),
                self.polarities_s.0 * 1e3,
                self.polarities_s.1 * 1e3,
            ),
            Some(bright) => format!(
                "the recording's ON and OFF events both lag the model by {:.2} ms more at {:.0} DN than at {:.0} DN ({:.1} standard errors; OFF {:+.2} ms, ON {:+.2} ms at {:.0} DN), as a cutoff of {:.0} Hz at white would",
                self.excess_s * 1e3,
                centre(self.dark),
                centre(bright),
                self.z,
                self.polarities_s.0 * 1e3,
                self.polarities_s.1 * 1e3,
                centre(self.dark),
                self.cutoff_hz
            ),
            None => format!(
                "the recording's ON and OFF events both lag the model by {:.2} ms at {:.0} DN ({:.1} standard errors; OFF {:+.2} ms, ON {:+.2} ms), as a cutoff of {:.0} Hz at white would",
                self.excess_s * 1e3,
                centre(self.dark),
                self.z,
                self.polarities_s.0 * 1e3,
                self.polarities_s.1 * 1e3,
                self.cutoff_hz
            ),
        }
    }
}

/// The count part (see the module docs).
fn count_evidence(c: &Context, floor: &NoiseFloor) -> Evidence {
    let Some((slope, se, spread)) = weighted_slope(&count_points(c)) else {
        return Evidence::none(Effect::Bandwidth, "too few intensity levels to compare");
    };
    let se = se.max(floor.count_slope);
    let change = slope * spread;
    Evidence {
        effect: Effect::Bandwidth,
        score: if se > 0.0 { slope / se } else { 0.0 },
        relevant: change > 0.10,
        text: format!(
            "log(simulated/real) counts rise by {slope:.3} (+- {se:.3}) per unit of ln(change rate / intensity): the model makes {:.0} % more events for fast changes in the dark than for slow changes in the bright, relative to the recording",
            100.0 * (change.exp() - 1.0)
        ),
        other_start: None,
        start: Some(100.0),
    }
}

/// The count cells as `(ln(change rate / intensity), ln(simulated / real), weight)`.
fn count_points(c: &Context) -> Vec<(f64, f64, f64)> {
    let g = c.geometry;
    cell_ratios(c.real, c.sim, g, c.subset)
        .iter()
        .map(|&(ratio, real, index)| {
            let (intensity, change, _) = cell_of(index);
            let x = (g.change_centres[change] / g.intensity_centres[intensity]).ln();
            (x, ratio, real as f64 + 0.5)
        })
        .collect()
}

/// Weighted least-squares slope of `y` on `x` (points `(x, y, weight)`), its standard
/// error from the weighted scatter about the line, and the range of `x`.
pub fn weighted_slope(points: &[(f64, f64, f64)]) -> Option<(f64, f64, f64)> {
    if points.len() < 4 {
        return None;
    }
    let w: f64 = points.iter().map(|p| p.2).sum();
    let mx = points.iter().map(|p| p.0 * p.2).sum::<f64>() / w;
    let my = points.iter().map(|p| p.1 * p.2).sum::<f64>() / w;
    let sxx: f64 = points.iter().map(|p| p.2 * (p.0 - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let slope = points
        .iter()
        .map(|p| p.2 * (p.0 - mx) * (p.1 - my))
        .sum::<f64>()
        / sxx;
    let intercept = my - slope * mx;
    let residual: f64 = points
        .iter()
        .map(|p| p.2 * (p.1 - intercept - slope * p.0).powi(2))
        .sum();
    // the weighted residual variance per unit weight, scaled to the effective sample size
    let n = points.len() as f64;
    let se = (residual / (n - 2.0) / sxx).sqrt();
    let lo = points.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let hi = points.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
    Some((slope, se, hi - lo))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_slope_of_a_line_with_scatter() {
        let points: Vec<(f64, f64, f64)> = (0..20)
            .map(|i| {
                let x = i as f64 * 0.2;
                (
                    x,
                    1.0 - 0.5 * x + if i % 2 == 0 { 0.01 } else { -0.01 },
                    100.0,
                )
            })
            .collect();
        let (slope, se, spread) = weighted_slope(&points).unwrap();
        assert!((slope + 0.5).abs() < 1e-3, "{slope}");
        assert!(se > 0.0 && se < 0.01, "{se}");
        assert!((spread - 3.8).abs() < 1e-9);
    }

    use crate::estimate::frames::PreparedFrames;
    use crate::events::{EventChunk, TimeUs};
    use crate::fit::effects::EVIDENCE_THRESHOLD;
    use crate::fit::effects::fixture::{self, Fixture, THRESHOLD, chunk};
    use std::f64::consts::SQRT_2;

    /// Intensities (DN) of the scene's rows of cells: the centres of intensity bins 2 to 5.
    const INTENSITY: [f64; 4] = [20.0 * SQRT_2, 40.0 * SQRT_2, 80.0 * SQRT_2, 201.99];
    /// Change rates (log units per second) of its columns of cells: the centres of change
    /// bins 1 to 6.
    const CHANGE: [f64; 6] = [
        0.25 * SQRT_2,
        0.5 * SQRT_2,
        SQRT_2,
        2.0 * SQRT_2,
        4.0 * SQRT_2,
        8.0 * SQRT_2,
    ];
    /// Frame interval, seconds, and the recording's length.
    const DT: f64 = 0.02;
    const SECONDS: f64 = 4.0;

    /// A 24 x 16 scene of 4 x 4-pixel cells, one per intensity (rows) and change rate
    /// (columns): each cell's value goes up and down by `change * DT` in log every frame
    /// (50 frames a second), so that the frames show that change rate.
    fn scene() -> PreparedFrames {
        fixture::frames(24, 16, &fixture::frame_times(SECONDS, DT), |x, y, k| {
            (INTENSITY[y / 4] * (CHANGE[x / 4] * DT * (k % 2) as f64).exp()) as f32
        })
    }

    /// Events of the scene: every pixel of a cell crosses a threshold of 0.2 at the same
    /// instants, `change / 0.2` times a second (ON while its value rises, OFF while it
    /// falls), so that each event has its neighbours' support. `kept(intensity, change)`
    /// is the share of a cell's events that fire (the others are evenly left out).
    fn events(kept: impl Fn(f64, f64) -> f64) -> EventChunk {
        delayed_events(kept, |_, _| 0.0)
    }

    /// [`events`], each cell's `delay(intensity, on)` seconds later.
    fn delayed_events(
        kept: impl Fn(f64, f64) -> f64,
        delay: impl Fn(f64, bool) -> f64,
    ) -> EventChunk {
        let mut out = Vec::new();
        for (row, &intensity) in INTENSITY.iter().enumerate() {
            for (column, &change) in CHANGE.iter().enumerate() {
                let period = THRESHOLD / change;
                let share = kept(intensity, change);
                let mut n = 0usize;
                loop {
                    let t = (n as f64 + 0.5) * period;
                    if t >= SECONDS {
                        break;
                    }
                    let fires = ((n + 1) as f64 * share).floor() > (n as f64 * share).floor();
                    n += 1;
                    if !fires {
                        continue;
                    }
                    let on = ((t / DT) as usize).is_multiple_of(2);
                    let at = ((t + delay(intensity, on)) * 1e6) as TimeUs;
                    for y in 4 * row..4 * row + 4 {
                        for x in 4 * column..4 * column + 4 {
                            out.push((at, x as u16, y as u16, on));
                        }
                    }
                }
            }
        }
        chunk(out)
    }

    /// A first-order low-pass with cutoff `cutoff_hz * (DN + 20) / 275` (v2e's): a texture
    /// of 0.5 log units peak to peak changing at `change` log units per second varies at
    /// `change` Hz, whose amplitude (and so its threshold crossings) the filter scales by
    /// `1 / sqrt(1 + (f / fc)^2)`.
    fn low_pass(cutoff_hz: f64) -> impl Fn(f64, f64) -> f64 {
        move |intensity, change| {
            let fc = cutoff_hz * (intensity + 20.0) / 275.0;
            1.0 / (1.0 + (change / fc).powi(2)).sqrt()
        }
    }

    #[test]
    fn a_20_hz_cutoff_calls_for_bandwidth_and_starts_at_the_fixed_100_hz() {
        let model = events(|_, _| 1.0);
        let recording = events(low_pass(20.0));
        let f = Fixture::new(&scene(), &recording, &model);
        let e = evidence(&f.context());
        // nearly every event kept in the slowest, brightest cell, 30 % in the fastest,
        // darkest: a slope of about 0.25 in about 9.5 standard errors
        assert!(e.calls_for(), "{e:?}");
        assert!(e.score > EVIDENCE_THRESHOLD, "{e:?}");
        assert!(e.score > 8.0 && e.score < 11.0, "{e:?}");
        // the search starts at 100 Hz whatever the evidence and spans 2 to 5000 Hz
        assert_eq!(e.start, Some(100.0));
        let (lo, hi) = crate::fit::effects::Effect::Bandwidth.range(100.0);
        assert!(lo < 20.0 && 20.0 < hi);
    }

    #[test]
    fn a_noise_floor_divides_the_signal_by_the_larger_standard_error() {
        let model = events(|_, _| 1.0);
        let recording = events(low_pass(20.0));
        let f = Fixture::new(&scene(), &recording, &model);
        let context = f.context();
        let own = noise_of(&context);
        let plain = evidence(&context);
        // a floor below the comparison's own standard errors changes nothing
        assert_eq!(evidence_over(&context, &own), plain);
        // twice the count part's standard error halves its score; the lag part (no lag in
        // these events) stays below it
        let doubled = NoiseFloor {
            count_slope: 2.0 * own.count_slope,
            ..own
        };
        let e = evidence_over(&context, &doubled);
        assert!(own.count_slope > 0.0, "{own:?}");
        assert!(
            (e.score - plain.score / 2.0).abs() < 1e-9,
            "{e:?} {plain:?}"
        );
        assert!(!e.calls_for(), "{e:?}");
        // a lag floor raises each bin's standard error alike
        let delayed = delayed_events(|_, _| 1.0, |dn, _| tau_of_1_hz(dn) / 150.0);
        let f = Fixture::new(&scene(), &delayed, &model);
        let context = f.context();
        let lag = evidence(&context);
        let own = noise_of(&context);
        let floor = NoiseFloor {
            lag_s: own.lag_s.map(|s| 4.0 * s),
            ..own
        };
        let e = evidence_over(&context, &floor);
        assert!(
            (e.score - lag.score / 4.0).abs() < 0.05 * lag.score,
            "{e:?} {lag:?}"
        );
    }

    #[test]
    fn a_delay_that_grows_in_the_dark_calls_for_bandwidth_and_starts_at_its_cutoff() {
        // every event kept, each cell's events as late as a 150 Hz cutoff's time constant
        // at its intensity: 6.1 ms at 28 DN to 1.3 ms at 202 DN (under half the fastest
        // cell's 17.7 ms between events), and no count deficit
        let model = events(|_, _| 1.0);
        let recording = delayed_events(|_, _| 1.0, |dn, _| tau_of_1_hz(dn) / 150.0);
        let f = Fixture::new(&scene(), &recording, &model);
        let e = evidence(&f.context());
        assert!(e.calls_for(), "{e:?}");
        assert!(
            e.text
                .starts_with("the recording's ON and OFF events both lag"),
            "{e:?}"
        );
        // the start: 1 / slope, within the offsets' 0.25 ms bins
        let start = e.start.unwrap();
        assert!((start - 150.0).abs() < 8.0, "{start}");
        // the brightest bin 6 ms late, the others on time: not a bandwidth
        let bright = delayed_events(|_, _| 1.0, |dn, _| if dn > 200.0 { 0.006 } else { 0.0 });
        let f = Fixture::new(&scene(), &bright, &model);
        assert!(!evidence(&f.context()).calls_for());
        // 6 ms late everywhere calls for the search, on the lag alone (the distance's lag
        // component, taken about its mean, then keeps no bandwidth for it)
        let constant = delayed_events(|_, _| 1.0, |_, _| 0.006);
        let f = Fixture::new(&scene(), &constant, &model);
        let e = evidence(&f.context());
        assert!(e.calls_for() && e.text.contains(" ms at "), "{e:?}");
    }

    #[test]
    fn the_distance_sees_a_lag_that_grows_in_the_dark_and_not_one_alike_everywhere() {
        use crate::fit::metric::distance;
        use crate::fit::observe::Subset;
        let model = events(|_, _| 1.0);
        let lag_of = |recording: &EventChunk| {
            let f = Fixture::new(&scene(), recording, &model);
            distance(&f.real, &f.sim, &f.geometry, Subset::Fit, &f.kept)
                .lag
                .expect("a simulation paired with the recording")
        };
        // 6 ms late everywhere: no lag about the mean (within the 0.25 ms bins, 1/80 of
        // the 20 ms frame interval)
        let constant = lag_of(&delayed_events(|_, _| 1.0, |_, _| 0.006));
        assert!(constant < 0.0125, "{constant}");
        // a 150 Hz cutoff's time constants, in frame intervals: 0.30, 0.19, 0.11, 0.07
        let lags: Vec<f64> = INTENSITY
            .iter()
            .map(|&dn| tau_of_1_hz(dn) / 150.0 / DT)
            .collect();
        let mean = lags.iter().sum::<f64>() / 4.0;
        let expected = (lags.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / 4.0).sqrt();
        let measured = lag_of(&delayed_events(|_, _| 1.0, |dn, _| tau_of_1_hz(dn) / 150.0));
        assert!(
            (measured - expected).abs() < 0.0125,
            "{measured} {expected}"
        );
        assert!(expected > 0.08, "{expected}");
    }

    #[test]
    fn a_level_error_that_moves_on_and_off_events_apart_is_not_a_bandwidth() {
        // the model's thresholds a few per cent off: ON events late and OFF events early by
        // the same amount, more in the bright (6 ms at 202 DN, 0.8 ms at 28 DN); both
        // polarities in every bin, their mean on time
        use crate::fit::observe::Subset;
        let model = events(|_, _| 1.0);
        let level = |dn: f64, on: bool| 0.006 * dn / 202.0 * if on { 1.0 } else { -1.0 };
        let delays = |recording: &EventChunk| -> Vec<f64> {
            let f = Fixture::new(&scene(), recording, &model);
            let e = evidence(&f.context());
            assert!(!e.calls_for(), "{e:?}");
            f.sim
                .delay_of(&f.geometry, Subset::Fit)
                .iter()
                .flatten()
                .map(|l| l.common.median_s)
                .collect()
        };
        let read = delays(&delayed_events(|_, _| 1.0, level));
        assert_eq!(read.len(), 4, "{read:?}");
        // within the offsets' 0.25 ms bins
        assert!(read.iter().all(|d| d.abs() < 0.25e-3), "{read:?}");
        // the ON events' delays alone are not a delay both polarities show: none beyond
        // the OFF events' own (on time, within the offsets' 0.25 ms bins), and no bandwidth
        let on_late = delayed_events(|_, _| 1.0, |dn, on| if on { level(dn, on) } else { 0.0 });
        let f = Fixture::new(&scene(), &on_late, &model);
        assert!(!evidence(&f.context()).calls_for());
        let brightest = f.sim.delay_of(&f.geometry, Subset::Fit)[5].unwrap();
        assert!((brightest.on_s - 6e-3).abs() < 0.25e-3, "{brightest:?}");
        assert!(brightest.common.median_s.abs() < 0.25e-3, "{brightest:?}");
    }

    #[test]
    fn a_lag_of_one_polarity_alone_is_not_a_bandwidth() {
        // OFF events 6 ms late at 28 DN and 1.5 ms from 112 DN, ON events 1 ms early (the
        // model's OFF threshold off, coverage draw 6029): no lag both polarities show
        let model = events(|_, _| 1.0);
        let off_late = |dn: f64, on: bool| {
            if on {
                -0.001
            } else {
                0.006 * 28.0 / dn.min(112.0)
            }
        };
        let f = Fixture::new(&scene(), &delayed_events(|_, _| 1.0, off_late), &model);
        let e = evidence(&f.context());
        assert!(!e.calls_for(), "{e:?}");
        let none = "no lag that the recording's ON and OFF events both show";
        assert!(e.text.contains(none), "{e:?}");
        // the same lags in both polarities are a bandwidth's
        let both = |dn: f64, _| 0.006 * 28.0 / dn.min(112.0);
        let f = Fixture::new(&scene(), &delayed_events(|_, _| 1.0, both), &model);
        let e = evidence(&f.context());
        assert!(e.calls_for() && e.score > 20.0, "{e:?}");
    }

    #[test]
    fn the_model_as_the_recording_does_not_call_for_bandwidth() {
        let recording = events(low_pass(20.0));
        let f = Fixture::new(&scene(), &recording, &recording);
        let e = evidence(&f.context());
        assert!(!e.calls_for(), "{e:?}");
        assert_eq!(e.score, 0.0);
    }

    #[test]
    fn a_deficit_alike_in_every_cell_does_not_call_for_bandwidth() {
        // thresholds 40 % higher than the model's: 1 event in 1.4 everywhere
        let model = events(|_, _| 1.0);
        let recording = events(|_, _| 1.0 / 1.4);
        let f = Fixture::new(&scene(), &recording, &model);
        let e = evidence(&f.context());
        assert!(!e.calls_for(), "{e:?}");
    }
}
