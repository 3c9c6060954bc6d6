//! Whether a pixel's events follow its own brightness: the frames, interpolated along their
//! optical flow, give each named pixel's log intensity over time, and a pixel whose counts
//! are explained by its rising and falling log intensity alone, with no room left for a
//! constant-rate train, is the scene's (a low threshold under mismatch fires
//! `dL / C` events for a change `dL`: the event-generation model of Lichtsteiner et al.,
//! IEEE JSSC 2008), not a defect (which fires at its rate whatever the scene does).

use crate::events::TimeUs;

/// Sub-steps each frame interval is cut into: short enough that a pixel's brightness
/// changes differ from step to step (the leverage that separates the train from the
/// scene), long enough to hold a few events of a pixel at hundreds of hertz.
pub const STEPS_PER_INTERVAL: usize = 4;

/// One-sided normal quantile at which the train's rate must exceed what the scene leaves
/// room for (0.001, as the silence test: about 40 pixels are tested in a fit).
const Z_ONE_SIDED: f64 = 3.09;

/// Fewest usable steps for the regression (three coefficients and their spread).
const FEWEST_STEPS: usize = 12;

/// The scene at the named pixels: the time steps judged, and the log intensity of a pixel
/// at a time (`None` where the frames do not tell it reliably: near black, clipped, outside
/// the used intervals).
pub struct SceneTrace<'a> {
    pub steps: Vec<(TimeUs, TimeUs)>,
    pub log_at: &'a dyn Fn(u16, u16, TimeUs) -> Option<f32>,
}

impl SceneTrace<'_> {
    /// `STEPS_PER_INTERVAL` steps in each of the frame intervals `intervals` (start, end),
    /// each ending a microsecond before the next interval begins.
    pub fn steps_of(intervals: impl Iterator<Item = (TimeUs, TimeUs)>) -> Vec<(TimeUs, TimeUs)> {
        let mut steps = Vec::new();
        for (a, b) in intervals.filter(|&(a, b)| b - a > STEPS_PER_INTERVAL as TimeUs) {
            let cut = |j: usize| a + (b - 1 - a) * j as TimeUs / STEPS_PER_INTERVAL as TimeUs;
            steps.extend((0..STEPS_PER_INTERVAL).map(|j| (cut(j), cut(j + 1))));
        }
        steps
    }

    /// Whether the pixel's events (`own`, time-sorted) are its brightness changes' with no
    /// room for a train at `train_hz`. Each step's count is fitted as
    /// `a dL+ + c dL- + b dt` (ordinary least squares; `dL+`, `dL-` the step's rise and
    /// fall of log intensity at the pixel): `b` is the rate the scene does not explain.
    /// The train is ruled out when `b` plus [`Z_ONE_SIDED`] of its heteroscedasticity-robust
    /// standard error (White's HC1: counts are Poisson, their variance grows with them)
    /// stays below `train_hz`. Too few usable steps, or changes that do not vary enough to
    /// tell the terms apart (a steady ramp), leave the question open: `false`.
    pub fn explains(&self, own: &[TimeUs], x: u16, y: u16, train_hz: f64) -> bool {
        match self.unexplained_rate(own, x, y) {
            Some((rate, se)) => rate + Z_ONE_SIDED * se < train_hz,
            None => false,
        }
    }

    /// The rate `b` the brightness changes leave unexplained, with its robust standard
    /// error (`None`: not determinable).
    fn unexplained_rate(&self, own: &[TimeUs], x: u16, y: u16) -> Option<(f64, f64)> {
        let mut rows: Vec<([f64; 3], f64)> = Vec::new();
        for &(a, b) in &self.steps {
            let (Some(la), Some(lb)) = ((self.log_at)(x, y, a), (self.log_at)(x, y, b)) else {
                continue;
            };
            let change = (lb - la) as f64;
            let count = own.partition_point(|&t| t < b) - own.partition_point(|&t| t < a);
            rows.push((
                [change.max(0.0), (-change).max(0.0), (b - a) as f64 * 1e-6],
                count as f64,
            ));
        }
        let n = rows.len();
        if n < FEWEST_STEPS {
            return None;
        }
        let design = |r: &[f64; 3]| nalgebra::Vector3::new(r[0], r[1], r[2]);
        let xtx: nalgebra::Matrix3<f64> = rows
            .iter()
            .map(|(r, _)| design(r) * design(r).transpose())
            .sum();
        let xty: nalgebra::Vector3<f64> = rows.iter().map(|(r, y)| design(r) * *y).sum();
        // a term that never varies (no fall of brightness at this pixel) carries nothing:
        // dropped by regularising its diagonal
        let mut xtx_kept = xtx;
        for k in 0..2 {
            if xtx_kept[(k, k)] <= 1e-12 * xtx_kept[(2, 2)] {
                xtx_kept[(k, k)] += 1.0;
            }
        }
        let inverse = xtx_kept.try_inverse()?;
        let beta = inverse * xty;
        let meat: nalgebra::Matrix3<f64> = rows
            .iter()
            .map(|(r, y)| {
                let residual = y - design(r).dot(&beta);
                design(r) * design(r).transpose() * residual.powi(2)
            })
            .sum();
        let covariance = inverse * meat * inverse * (n as f64 / (n - 3) as f64);
        let se = covariance[(2, 2)].max(0.0).sqrt();
        (beta[2].is_finite() && se.is_finite()).then_some((beta[2], se))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::effects::fixture::{poisson_times, rng};

    /// A pixel's log intensity: a sine of 0.15 amplitude over 60 ms (a textured scene
    /// sliding past), sampled at 30 Hz frames over 0.5 s.
    fn sine(t: TimeUs) -> f32 {
        (0.15 * (t as f64 * 1e-6 * std::f64::consts::TAU / 0.06).sin()) as f32
    }

    fn trace<'a>(log_at: &'a dyn Fn(u16, u16, TimeUs) -> Option<f32>) -> SceneTrace<'a> {
        let frames = (0..15).map(|k| (k * 33_333, (k + 1) * 33_333));
        SceneTrace {
            steps: SceneTrace::steps_of(frames),
            log_at,
        }
    }

    /// The events of a threshold `c` on the rises of `log` (ON only, as a pixel whose OFF
    /// threshold is far larger): one event per `c` of rise since the last.
    fn low_threshold(log: &dyn Fn(TimeUs) -> f32, c: f32, end: TimeUs) -> Vec<TimeUs> {
        let mut reference = log(0);
        let mut events = Vec::new();
        for t in (0..end).step_by(50) {
            let l = log(t);
            if l < reference {
                reference = l;
            }
            while l - reference >= c {
                reference += c;
                events.push(t);
            }
        }
        events
    }

    /// A threshold of 0.01 on a sliding texture (0.3 of rise a cycle, 16.7 cycles a
    /// second: 500 Hz of ON events in bursts on the rises) leaves no room for a train at 250 Hz; a Poisson train at 300 Hz added to
    /// the same events does not fit the brightness and is kept; so is a train alone on a
    /// static pixel of the scene, whose changes carry nothing.
    #[test]
    fn a_low_threshold_follows_its_brightness_and_a_train_does_not() {
        let log_at = |_: u16, _: u16, t: TimeUs| Some(sine(t));
        let scene = trace(&log_at);
        let end = 500_000;
        let bursts = low_threshold(&sine, 0.01, end);
        let rate = bursts.len() as f64 / 0.5;
        assert!((400.0..700.0).contains(&rate), "{rate}");
        assert!(scene.explains(&bursts, 0, 0, 250.0));
        let mut r = rng(7);
        let mut with_train = poisson_times(&mut r, 300.0, 0.0, 0.5);
        with_train.extend(&bursts);
        with_train.sort_unstable();
        assert!(!scene.explains(&with_train, 0, 0, 250.0));
        let (b, se) = scene.unexplained_rate(&with_train, 0, 0).unwrap();
        assert!((b - 300.0).abs() < 4.0 * se, "{b} +- {se}");
        let flat = |_: u16, _: u16, _: TimeUs| Some(0.0f32);
        let train = poisson_times(&mut r, 300.0, 0.0, 0.5);
        assert!(!trace(&flat).explains(&train, 0, 0, 250.0));
    }

    /// Where the frames do not tell the pixel's brightness, nothing is decided.
    #[test]
    fn without_the_brightness_the_question_stays_open() {
        let unknown = |_: u16, _: u16, _: TimeUs| None;
        let bursts = low_threshold(&sine, 0.01, 500_000);
        assert!(!trace(&unknown).explains(&bursts, 0, 0, 250.0));
    }
}
