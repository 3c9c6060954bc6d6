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

/// Fewest usable steps for the regression (five coefficients and their spread).
const FEWEST_STEPS: usize = 16;

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
    /// `a0 dL+ + c0 dL- + a1 dL+' + c1 dL-' + b dt` (ordinary least squares; `dL+`, `dL-`
    /// the step's rise and fall of log intensity at the pixel, `dL+'`, `dL-'` those of the
    /// equally long stretch before it): `b` is the rate the scene does not explain. The
    /// previous stretch's terms are a distributed lag: a photoreceptor of limited bandwidth
    /// (Lichtsteiner et al. 2008, Sec. III; slower in the dark, v2e's intensity-dependent
    /// cutoff) fires for a change up to a few time constants after it, so a step's events
    /// follow the changes before it as well; without them a lagging pixel's events look
    /// like a rate no change explains. The train is ruled out when `b` plus
    /// [`Z_ONE_SIDED`] of its heteroscedasticity-robust standard error (White's HC1: counts
    /// are Poisson, their variance grows with them) stays below `train_hz`. Too few usable
    /// steps, or changes that do not vary enough to tell the terms apart (a steady ramp),
    /// leave the question open: `false`.
    pub fn explains(&self, own: &[TimeUs], x: u16, y: u16, train_hz: f64) -> bool {
        match self.unexplained_rate(own, x, y) {
            Some((rate, se)) => rate + Z_ONE_SIDED * se < train_hz,
            None => false,
        }
    }

    /// One step's regressors (rise, fall, the stretch before's rise and fall, seconds)
    /// and count; `None` where the frames do not tell the brightness at its ends.
    fn row(&self, own: &[TimeUs], x: u16, y: u16, (a, b): (TimeUs, TimeUs)) -> Option<Row> {
        let log = |t: TimeUs| (self.log_at)(x, y, t).map(f64::from);
        let (before, start, end) = (log(a - (b - a))?, log(a)?, log(b)?);
        let (lagged, change) = (start - before, end - start);
        let count = own.partition_point(|&t| t < b) - own.partition_point(|&t| t < a);
        let design = Design::new(
            change.max(0.0),
            (-change).max(0.0),
            lagged.max(0.0),
            (-lagged).max(0.0),
            (b - a) as f64 * 1e-6,
        );
        Some((design, count as f64))
    }

    /// The rate `b` the brightness changes leave unexplained, with its robust standard
    /// error (`None`: not determinable).
    fn unexplained_rate(&self, own: &[TimeUs], x: u16, y: u16) -> Option<(f64, f64)> {
        let rows: Vec<Row> = self
            .steps
            .iter()
            .filter_map(|&step| self.row(own, x, y, step))
            .collect();
        let n = rows.len();
        if n < FEWEST_STEPS {
            return None;
        }
        let xtx: Gram = rows.iter().map(|(d, _)| d * d.transpose()).sum();
        let xty: Design = rows.iter().map(|(d, y)| d * *y).sum();
        // a term that never varies (no fall of brightness at this pixel) carries nothing:
        // dropped by regularising its diagonal
        let mut xtx_kept = xtx;
        for k in 0..RATE {
            if xtx_kept[(k, k)] <= 1e-12 * xtx_kept[(RATE, RATE)] {
                xtx_kept[(k, k)] += 1.0;
            }
        }
        let inverse = xtx_kept.try_inverse()?;
        let beta = inverse * xty;
        let meat: Gram = rows
            .iter()
            .map(|(d, y)| d * d.transpose() * (y - d.dot(&beta)).powi(2))
            .sum();
        let covariance = inverse * meat * inverse * (n as f64 / (n - TERMS) as f64);
        let se = covariance[(RATE, RATE)].max(0.0).sqrt();
        (beta[RATE].is_finite() && se.is_finite()).then_some((beta[RATE], se))
    }
}

/// Terms of the regression: four brightness changes and the step's length.
const TERMS: usize = 5;
/// The index of the constant rate `b` (the step's length in seconds).
const RATE: usize = TERMS - 1;
type Design = nalgebra::SVector<f64, TERMS>;
type Gram = nalgebra::SMatrix<f64, TERMS, TERMS>;
type Row = (Design, f64);

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

    /// A slow photoreceptor (first-order low-pass, time constant 8 ms: a 20 Hz cutoff, as
    /// in a dim scene) fires the same low threshold's bursts up to a step late (40 degrees
    /// of the sine's 60 ms cycle): the stretch before each step explains them, and a 300 Hz
    /// train on top is still found, its rate within four standard errors.
    #[test]
    fn a_lagging_low_threshold_is_explained_by_the_changes_before_each_step() {
        let tau_us = 8_000.0;
        let samples: Vec<f32> = (0..500_000)
            .step_by(50)
            .map(filtered_step(&sine, tau_us))
            .collect();
        let lagging = |t: TimeUs| samples[(t / 50) as usize];
        let log_at = |_: u16, _: u16, t: TimeUs| Some(sine(t));
        let scene = trace(&log_at);
        let bursts = low_threshold(&lagging, 0.01, 500_000);
        assert!(bursts.len() > 150, "{}", bursts.len());
        let (b, se) = scene.unexplained_rate(&bursts, 0, 0).unwrap();
        assert!(scene.explains(&bursts, 0, 0, 250.0), "{b} +- {se}");
        let mut with_train = poisson_times(&mut rng(8), 300.0, 0.0, 0.5);
        with_train.extend(&bursts);
        with_train.sort_unstable();
        let (b, se) = scene.unexplained_rate(&with_train, 0, 0).unwrap();
        assert!(!scene.explains(&with_train, 0, 0, 250.0), "{b} +- {se}");
        assert!((b - 300.0).abs() < 4.0 * se, "{b} +- {se}");
    }

    /// The first-order low-pass of `log` (Euler steps of 50 us from its value at 0), for
    /// times called in order every 50 us.
    fn filtered_step(log: &dyn Fn(TimeUs) -> f32, tau_us: f64) -> impl FnMut(TimeUs) -> f32 + '_ {
        let mut y = log(0) as f64;
        move |t| {
            y += (log(t) as f64 - y) * (50.0 / tau_us);
            y as f32
        }
    }

    /// Where the frames do not tell the pixel's brightness, nothing is decided.
    #[test]
    fn without_the_brightness_the_question_stays_open() {
        let unknown = |_: u16, _: u16, _: TimeUs| None;
        let bursts = low_threshold(&sine, 0.01, 500_000);
        assert!(!trace(&unknown).explains(&bursts, 0, 0, 250.0));
    }
}
