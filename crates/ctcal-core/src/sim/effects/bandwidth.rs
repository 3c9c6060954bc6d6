//! Photoreceptor bandwidth: the log photoreceptor is a first-order low-pass filter whose
//! cutoff rises with photocurrent, so pixels are slower in the dark (Delbruck & Mead 1994;
//! Lichtsteiner et al. 2008). As in v2e, the cutoff at intensity DN is
//! `f(DN) = cutoff_hz * (DN + 20) / 275` (so `cutoff_hz` at full white), `tau = 1/(2 pi f)`.
//!
//! Between samples the input `u` is linear in time, and the filter `tau y' = u - y` is
//! advanced with its exact solution for a linear input (not v2e's Euler step):
//! `y(h) = u_b - b tau + (y_0 - u_a + b tau) e^(-h/tau)`, `b = (u_b - u_a) / h`.

/// The filter time constant (microseconds) at intensity `dn` for `cutoff_hz` at white.
#[inline(always)]
pub fn tau_us(dn: f32, cutoff_hz: f32) -> f32 {
    1.0 / rate_per_us(dn, cutoff_hz)
}

/// The cutoff (Hz) at intensity `dn` of a photoreceptor whose cutoff at white is
/// `cutoff_hz`: `cutoff_hz (DN + 20) / 275`.
pub fn cutoff_at_dn(dn: f64, cutoff_hz: f64) -> f64 {
    cutoff_hz * (dn.max(0.0) + 20.0) / 275.0
}

/// `1 / tau` in 1/us: `2 pi cutoff_hz (DN + 20) / 275 * 1e-6` (no division).
#[inline(always)]
pub fn rate_per_us(dn: f32, cutoff_hz: f32) -> f32 {
    let dn = if dn > 0.0 { dn } else { 0.0 };
    (std::f32::consts::TAU * 1e-6 / 275.0) * cutoff_hz * (dn + 20.0)
}

/// Advances the filter state `y0` over `h_us` while the input goes linearly from `u_a` to
/// `u_b`, with time constant `tau_us`. Exact for that input.
#[inline]
pub fn advance(y0: f32, u_a: f32, u_b: f32, h_us: f32, tau_us: f32) -> f32 {
    if h_us <= 0.0 {
        return y0;
    }
    advance_positive(y0, u_a, u_b, h_us, tau_us)
}

/// [`advance`] for `h_us > 0`, without the branch (for vectorised loops).
#[inline(always)]
pub fn advance_positive(y0: f32, u_a: f32, u_b: f32, h_us: f32, tau_us: f32) -> f32 {
    advance_with_rate(y0, u_a, u_b, h_us, 1.0 / h_us, 1.0 / tau_us)
}

/// The same step from the rate `1 / tau` and `1 / h` (one division instead of three).
#[inline(always)]
pub fn advance_with_rate(y0: f32, u_a: f32, u_b: f32, h_us: f32, inverse_h: f32, rate: f32) -> f32 {
    let slope_tau = (u_b - u_a) * inverse_h / rate;
    let decay = crate::sim::fast_math::exp(-h_us * rate);
    u_b - slope_tau + (y0 - u_a + slope_tau) * decay
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_constant_scales_with_intensity() {
        // 30 Hz at white: tau 5.305 ms at 255 DN (v2e's tau_s for d_bw_middim_texture)
        assert!((tau_us(255.0, 30.0) - 5305.165).abs() < 0.01);
        // at 45 DN the cutoff is 30 * 65 / 275 = 7.09 Hz
        assert!((tau_us(45.0, 30.0) - 1e6 / (std::f32::consts::TAU * 7.090_909)).abs() < 0.05);
    }

    #[test]
    fn step_response_is_exponential() {
        // constant input 1 from y0 = 0: after one tau, 1 - 1/e
        let y = advance(0.0, 1.0, 1.0, 1000.0, 1000.0);
        assert!((y - (1.0 - (-1.0f32).exp())).abs() < 1e-6);
        // a long interval on a fast filter: fully settled, no overflow
        assert_eq!(advance(0.0, 1.0, 1.0, 1e9, 1.0), 1.0);
    }

    #[test]
    fn ramp_response_lags_by_slope_times_tau() {
        // input u = t (per us) from y0 = 0: y(t) = t - tau (1 - e^(-t/tau))
        let (tau, t) = (100.0f32, 1000.0f32);
        let y = advance(0.0, 0.0, t, t, tau);
        assert!((y - (t - tau * (1.0 - (-t / tau).exp()))).abs() < 1e-3);
        // and splitting the ramp into two steps gives the same answer
        let y_mid = advance(0.0, 0.0, t / 2.0, t / 2.0, tau);
        let y2 = advance(y_mid, t / 2.0, t, t / 2.0, tau);
        assert!((y2 - y).abs() < 1e-3);
    }
}
