//! DVS-Voltmeter's pixel model (Lin, Ma, Guo & Wen, "DVS-Voltmeter: stochastic
//! process-based event simulator for dynamic vision sensors", ECCV 2022), re-implemented from
//! `src/simulator.py`, `src/simulator_utils.py` and `src/config.py` of Lynn0306/DVS-Voltmeter,
//! commit 9d86353ecfaaa1af82b9eb66b162f0bf80cd4861 (MIT licence; no code copied).
//!
//! - Model: the pixel voltage `V_d` since the last event is a Brownian motion with drift,
//!   and an event fires when it reaches `+1` (ON) or `-1` (OFF); it then restarts at 0.
//!   Between frames `a` (DN `L_a`, time `t_a` in us) and `b`, with `L = (L_a + L_b) / 2`:
//!   drift `mu = k1 (L_b - L_a) / (t_b - t_a) / (L + k2) + k4 + k5 L` and diffusion
//!   `sigma = k3 sqrt(L) / (L + k2) + k6` (per us and per sqrt(us), Eq. 10-11). The code uses
//!   the frames' 8-bit DN as `L`.
//! - Log response: the signal term integrates to `k1 * sum (dL / (L + k2))`, the midpoint
//!   rule for `k1 ln(L + k2)`, so the pixel compares `ln(DN + k2)` (`log_offset_dn = k2`,
//!   20 for the DAVIS346 parameters, 23 for the DVS240) against a threshold of `1 / k1` in
//!   those units (0.190 and 0.226). Per frame step the rule gives `2 atanh(x)` -> `2x`
//!   (`x = (L_b - L_a) / (L_a + L_b + 2 k2)`), a little less than the log for large steps.
//! - Timing (Algorithm 1): at each step the polarity whose barrier is hit first is drawn with
//!   the exit probability of a drifted Brownian motion between `-(1 + r)` and `1 - r` (`r` the
//!   residual voltage), then the hitting time from the inverse Gaussian of that barrier
//!   (mean `eps / c`, shape `(eps / sigma)^2`; drawn as in the code, including its treatment
//!   of a drift away from the barrier and its Levy draw when `c = 0`). A time before the next
//!   frame is an event (rounded to the microsecond, ties to even) and the draw repeats from
//!   it with `r = 0`; otherwise the residual becomes `r + (+-eps) (t_b - t_start) / dt` (the
//!   fraction of the drawn passage already elapsed) and the pixel waits for the next frame.
//! - Thresholds: exactly 1 (no mismatch, no per-event noise); all the randomness is in the
//!   diffusion. No refractory period, no bandwidth limit.
//! - Leak: the `k4 + k5 L` drift, growing with brightness: `(k4 + k5 DN) 1e6` ON events per
//!   second in a static scene (0.1 + 0.005 DN Hz for the DAVIS346 parameters).
//! - Noise: the diffusion `sigma`, largest in the dark relative to the signal.
//!
//! The repository's `config.py` publishes parameters for the DAVIS346 ("DVS346") and the
//! DVS240 only; it has none for the DVXplorer. Random draws use ctcal's generators (the
//! code's torch draws cannot be reproduced), so agreement with the Python code is
//! statistical.
//!
//! Side by side with the real code (`EventSim.generate_events`, torch 2.15, DAVIS346
//! parameters) on 40 frames (1 kHz) of a 64x48 texture moving at (300, 120) px/s, 20 seeds
//! each (`tests/cli/peers.rs` rechecks the counts):
//!
//! | input | real: events (sd), ON | ctcal: events (sd), ON | count-map corr. (real vs real) |
//! |---|---|---|---|
//! | 8-bit frames | 6450.0 (2.8), 2892.8 | 6449.1 (2.2), 2892.2 | 0.9986 (0.9982) |
//! | frames at 15 % | 1728.5 (1.3), 772.7 | 1728.4 (1.2), 772.6 | 0.9993 (1.0000) |
//!
//! Events per 1 ms bin correlate at 0.9995 and 0.9993 (real vs real 0.9997, 0.9994).

use super::super::rng::{Stream, generator};
use super::super::{FrameSource, SimError};
use crate::events::EventChunk;
use rand::{Rng, RngExt};
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::{Deserialize, Serialize};
use statrs::function::erf::{erf, erf_inv};

/// DVS-Voltmeter's sensor parameters (`cfg.SENSOR`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// `CAMERA_TYPE`: "DVS346" or "DVS240" for the published sets, else free text.
    pub camera_type: String,
    /// `K = [k1, k2, k3, k4, k5, k6]`.
    pub k: [f64; 6],
}

impl Default for Params {
    fn default() -> Self {
        Self::dvs346()
    }
}

impl Params {
    /// `config.py`'s DAVIS346 parameters (the default camera type).
    pub fn dvs346() -> Self {
        Self {
            camera_type: "DVS346".into(),
            k: [0.00018 * 29250.0, 20.0, 0.0001, 1e-7, 5e-9, 0.00001],
        }
    }

    /// `config.py`'s DVS240 parameters.
    pub fn dvs240() -> Self {
        Self {
            camera_type: "DVS240".into(),
            k: [0.000094 * 47065.0, 23.0, 0.0002, 1e-7, 5e-8, 0.00001],
        }
    }

    /// Drift (per us) and diffusion (per sqrt(us)) over a step from DN `a` to `b` in
    /// `dt_us` (Eq. 10-11 as `simulator.py` computes them).
    pub fn drift_diffusion(&self, a: f64, b: f64, dt_us: f64) -> (f64, f64) {
        let [k1, k2, k3, k4, k5, k6] = self.k;
        let avg = (a + b) / 2.0;
        let denominator = 1.0 / (avg + k2);
        let mu = k1 * (b - a) / dt_us * denominator + k4 + k5 * avg;
        let sigma = k3 * avg.sqrt() * denominator + k6;
        (mu, sigma)
    }

    pub(super) fn check(&self) -> Result<(), SimError> {
        let [k1, k2, k3, _, _, k6] = self.k;
        if self.k.iter().all(|k| k.is_finite()) && k1 > 0.0 && k2 >= 0.0 && k3 >= 0.0 && k6 >= 0.0 {
            Ok(())
        } else {
            Err(SimError::Invalid(
                "DVS-Voltmeter parameters: k must be finite with k1 > 0 and k2, k3, k6 >= 0".into(),
            ))
        }
    }
}

fn uniform(rng: &mut impl Rng) -> f64 {
    rng.random::<f64>()
}

fn normal_cdf(x: f64) -> f64 {
    0.5 * (1.0 + erf(x / std::f64::consts::SQRT_2))
}

/// `sample_truncated_normal(0, 1, -inf, b)` by inverse CDF, clamped as the code does.
fn truncated_normal_below(b: f64, rng: &mut impl Rng) -> f64 {
    let p = normal_cdf(b) * uniform(rng);
    let v = (2.0 * p - 1.0).clamp(-1.0, 1.0);
    let out = std::f64::consts::SQRT_2 * erf_inv(v);
    if out > b { b } else { out }
}

/// The hitting time of barrier `eps` for drift `c` and diffusion `sigma`
/// (`sample_IG_torch`): an inverse Gaussian by Michael-Schucany-Haas, its normal draw
/// truncated where the square root exists when `c < 0`, and `(eps/sigma)^2 / erfinv(1-u)^2`
/// when `c = 0`.
pub fn hitting_time(eps: f64, c: f64, sigma: f64, rng: &mut impl Rng) -> f64 {
    let scale = (eps / sigma).powi(2);
    if c == 0.0 {
        let ev = erf_inv(1.0 - uniform(rng));
        return scale / (ev * ev);
    }
    let x = if c > 0.0 {
        StandardNormal.sample(rng)
    } else {
        truncated_normal_below(-(-4.0 * eps * c / (sigma * sigma)).sqrt(), rng)
    };
    let mean = eps / c;
    let mu = mean / 2.0 / scale;
    let y = mean * x * x;
    let z = 4.0 * scale * y + y * y;
    let x = mean + mu * (y - z.sqrt());
    if uniform(rng) > mean / (mean + x) {
        mean * mean / x
    } else {
        x
    }
}

/// The probability that the ON barrier `a` is reached before the OFF barrier `-b`, with
/// the code's fallbacks (NaN -> 1, no drift -> 1/2).
pub fn p_first_on(a: f64, b: f64, c: f64, sigma: f64) -> f64 {
    if c == 0.0 {
        return 0.5;
    }
    let s2 = sigma * sigma;
    let exp_b = (2.0 * c * b / s2).exp();
    let exp_a = (-2.0 * c * a / s2).exp();
    let p = (exp_b - 1.0) / (exp_b - exp_a);
    if p.is_nan() { 1.0 } else { p }
}

/// One pixel over one frame step: events (rounded times) go to `emit`; returns the new
/// residual voltage.
fn step(
    residual: f64,
    (t_a, t_b): (f64, f64),
    (c, sigma): (f64, f64),
    rng: &mut Xoshiro256PlusPlus,
    mut emit: impl FnMut(f64, bool),
) -> f64 {
    let (mut start, mut residual) = (t_a, residual);
    loop {
        let (a, b) = (1.0 - residual, 1.0 + residual);
        let on = uniform(rng) <= p_first_on(a, b, c, sigma);
        let (eps, drift) = if on { (a, c) } else { (b, -c) };
        let dt = hitting_time(eps, drift, sigma, rng);
        let t_end = start + dt;
        if t_end - t_b < 0.0 {
            emit(t_end.round_ties_even(), on);
            start = t_end;
            residual = 0.0;
        } else {
            let signed = if on { eps } else { -eps };
            return residual + signed * (t_b - start) / dt;
        }
    }
}

/// Runs DVS-Voltmeter over `source` (times in us, DN as given); the first sample sets the
/// base frame.
pub fn simulate(
    source: &mut dyn FrameSource,
    params: &Params,
    seed: u64,
) -> Result<EventChunk, SimError> {
    params.check()?;
    let (width, _) = source.size();
    let Some(first) = source.next_frame()? else {
        return Err(SimError::Invalid("the input has no frames".into()));
    };
    let mut base: Vec<f64> = first.dn.iter().map(|&d| d as f64).collect();
    let mut residual = vec![0.0f64; base.len()];
    let mut rng = generator(seed, Stream::Rows, 0);
    let mut out = EventChunk::default();
    let mut t_a = first.t as f64;
    let mut frame: Vec<(i64, usize, bool)> = Vec::new();
    while let Some(sample) = source.next_frame()? {
        let t_b = sample.t as f64;
        if t_b <= t_a {
            return Err(SimError::Invalid(format!(
                "DVS-Voltmeter needs strictly increasing frame times ({t_b} us after {t_a} us)"
            )));
        }
        frame.clear();
        for (i, &dn) in sample.dn.iter().enumerate() {
            let b = dn as f64;
            let drift = params.drift_diffusion(base[i], b, t_b - t_a);
            residual[i] = step(residual[i], (t_a, t_b), drift, &mut rng, |t, on| {
                frame.push((t as i64, i, on))
            });
            base[i] = b;
        }
        frame.sort_by_key(|&(t, i, _)| (t, i));
        for &(t, i, on) in &frame {
            out.push(t, (i % width) as u16, (i / width) as u16, on);
        }
        t_a = t_b;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::pixel::Transition;
    use crate::sim::source::{ReplaySamples, Sample};
    use rand::SeedableRng;

    fn frames(dn: &[f32], times: &[i64], pixels: usize) -> Vec<Sample> {
        times
            .iter()
            .zip(dn)
            .map(|(&t, &d)| Sample {
                t,
                dn: vec![d; pixels],
                transition: Transition::Linear,
            })
            .collect()
    }

    /// The inverse Gaussian CDF (mean `m`, shape `l`) at `x` (the normal CDF from `erfc`,
    /// whose far tail the second term needs).
    fn ig_cdf(x: f64, m: f64, l: f64) -> f64 {
        let phi = |z: f64| 0.5 * statrs::function::erf::erfc(-z / std::f64::consts::SQRT_2);
        let s = (l / x).sqrt();
        phi(s * (x / m - 1.0)) + (2.0 * l / m).exp() * phi(-s * (x / m + 1.0))
    }

    #[test]
    fn drift_and_diffusion_follow_eq_10_11() {
        let p = Params::dvs346();
        // a static 100 DN pixel: leak 1e-7 + 5e-9 * 100 per us, diffusion 1e-4 * 10 / 120 + 1e-5
        let (mu, sigma) = p.drift_diffusion(100.0, 100.0, 1000.0);
        assert!((mu - 6e-7).abs() < 1e-18);
        assert!((sigma - (1e-3 / 120.0 + 1e-5)).abs() < 1e-15);
        // a step 100 -> 110 over 1 ms adds k1 * 10 / 1000 / 125 per us
        let (mu, _) = p.drift_diffusion(100.0, 110.0, 1000.0);
        assert!((mu - (5.265 * 10.0 / 1000.0 / 125.0 + 1e-7 + 5e-9 * 105.0)).abs() < 1e-15);
        // the exit probability of a strong drift is one-sided, of none a half
        assert_eq!(p_first_on(1.0, 1.0, 1e-3, 1e-5), 1.0);
        assert_eq!(p_first_on(1.0, 1.0, -1e-3, 1e-5), 0.0);
        assert_eq!(p_first_on(1.0, 1.0, 0.0, 1e-5), 0.5);
        // no drift, equal barriers, mild diffusion: symmetric
        assert!((p_first_on(0.5, 0.5, 1e-9, 1e-3) - 0.5).abs() < 1e-3);
    }

    #[test]
    fn hitting_times_have_the_inverse_gaussian_mean_and_cdf() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(2);
        let (eps, c, sigma): (f64, f64, f64) = (1.0, 2e-3, 2e-2);
        let (m, l) = (eps / c, (eps / sigma).powi(2));
        let n = 200_000;
        let draws: Vec<f64> = (0..n)
            .map(|_| hitting_time(eps, c, sigma, &mut rng))
            .collect();
        let mean = draws.iter().sum::<f64>() / n as f64;
        // variance m^3 / l = 5e4: standard error 0.5 us on a 500 us mean
        assert!((mean - m).abs() < 2.5, "{mean}");
        let below = draws.iter().filter(|&&d| d < 400.0).count() as f64 / n as f64;
        let p = ig_cdf(400.0, m, l);
        assert!(
            (below - p).abs() < 4.0 * (p * (1.0 - p) / n as f64).sqrt(),
            "{below} {p}"
        );
    }

    #[test]
    fn event_count_of_one_long_step_matches_the_passage_probability() {
        // 3072 static pixels at 100 DN, one 1 s step, leak only (no signal, no OFF: the
        // drift 4e-7 + 100 * 5e-9 per us is 180 diffusion units from the OFF barrier): over 4
        // seeds each pixel fires within the step with the inverse-Gaussian probability
        // P(T < 1e6 us), mean 1 / drift, shape (1 / sigma)^2
        let p = Params {
            camera_type: "test".into(),
            k: [5.265, 20.0, 0.0, 4e-7, 5e-9, 1e-4],
        };
        let (mu, sigma) = p.drift_diffusion(100.0, 100.0, 1e6);
        let prob = ig_cdf(1e6, 1.0 / mu, (1.0 / sigma).powi(2));
        assert!(prob > 0.1 && prob < 0.9, "{prob}");
        let n = 64 * 48;
        let samples = frames(&[100.0, 100.0], &[0, 1_000_000], n);
        let mut fired = 0;
        for seed in 0..4 {
            let events = simulate(&mut ReplaySamples::new(&samples, 64, 48), &p, seed).unwrap();
            assert!(events.on.iter().all(|&on| on));
            let mut pixels: Vec<(u16, u16)> = events.iter().map(|e| (e.x, e.y)).collect();
            pixels.sort_unstable();
            pixels.dedup();
            fired += pixels.len();
        }
        let trials = 4.0 * n as f64;
        let sd = (trials * prob * (1.0 - prob)).sqrt();
        assert!(
            (fired as f64 - trials * prob).abs() < 4.0 * sd,
            "{fired} vs {}",
            trials * prob
        );
    }

    #[test]
    fn a_static_scene_fires_at_the_leak_drift_across_frames() {
        // DAVIS346 parameters at 200 DN: drift 1e-7 + 200 * 5e-9 = 1.1e-6 per us, so an ON
        // event every 1 / 1.1e-6 us = 0.909 s (coefficient of variation sqrt(m sigma^2) =
        // 1.6 %); 500 frames of 10 ms (5 s) carry the residual voltage from frame to frame:
        // every pixel fires 5 times, the first at 0.909 s on average
        let p = Params::dvs346();
        let times: Vec<i64> = (0..=500).map(|k| k * 10_000).collect();
        let samples = frames(&vec![200.0; times.len()], &times, 64 * 48);
        let events = simulate(&mut ReplaySamples::new(&samples, 64, 48), &p, 3).unwrap();
        assert_eq!(events.len(), 5 * 3072);
        assert!(events.on.iter().all(|&on| on));
        let (mu, sigma) = p.drift_diffusion(200.0, 200.0, 1e4);
        let (m, cv) = (1.0 / mu, (sigma * sigma / mu).sqrt());
        let first: Vec<f64> = events.t[..3072].iter().map(|&t| t as f64).collect();
        let mean = first.iter().sum::<f64>() / 3072.0;
        assert!(
            (mean - m).abs() < 4.0 * m * cv / 3072f64.sqrt(),
            "{mean} vs {m}"
        );
    }

    #[test]
    fn a_brightness_ramp_fires_about_k1_per_log_unit_and_is_deterministic() {
        // 64 pixels from 30 to 240 DN over 100 steps of 1 ms: k1 ln(260/50) = 8.68 ON
        // events per pixel, minus the unfinished passage at the end
        let p = Params::dvs346();
        let times: Vec<i64> = (0..=100).map(|k| k * 1000).collect();
        let dn: Vec<f32> = (0..=100).map(|k| 30.0 + 2.1 * k as f32).collect();
        let samples = frames(&dn, &times, 64);
        let a = simulate(&mut ReplaySamples::new(&samples, 8, 8), &p, 11).unwrap();
        let b = simulate(&mut ReplaySamples::new(&samples, 8, 8), &p, 11).unwrap();
        assert_eq!(a, b);
        assert!(a.is_time_sorted());
        let per_pixel = a.len() as f64 / 64.0;
        assert!((7.5..=9.0).contains(&per_pixel), "{per_pixel}");
    }
}
