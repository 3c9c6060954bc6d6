//! The photoreceptor's log response: the log-domain value `L(DN)` a pixel compares.
//!
//! - v2e lin-log (Hu, Liu & Delbruck, "v2e", CVPR Workshops 2021): `L = ln(DN)` for
//!   DN > 20 and `L = DN * ln(20) / 20` below, continuous at 20 DN. The linear part models
//!   the photoreceptor's dark floor and keeps `L` finite at 0 DN.
//! - eps: `L = ln(DN / 255 + eps)` (the common `log(I + eps)` of ESIM-style simulators).

use super::fast_math;
use super::params::LogResponse;

/// `ln(20) / 20`: slope of the v2e response's linear part.
const LINEAR_SLOPE: f32 = 0.149_786_62;

/// A log response with its parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogMap {
    kind: LogResponse,
    eps: f32,
}

impl LogMap {
    pub fn new(kind: LogResponse, eps: f64) -> Self {
        Self {
            kind,
            eps: eps as f32,
        }
    }

    /// Which response this is.
    pub fn response(&self) -> LogResponse {
        self.kind
    }

    /// The offset of the `eps` response.
    pub fn eps(&self) -> f64 {
        self.eps as f64
    }

    /// The log-domain value of intensity `dn` (camera DN). Inlined into every frame loop:
    /// as a call per pixel it kept `apply_frame` scalar (a third of a simulation's time).
    #[inline(always)]
    pub fn apply(&self, dn: f32) -> f32 {
        match self.kind {
            LogResponse::V2e => {
                // both branches computed, then selected: keeps the frame loop vectorised
                let log = fast_math::ln(if dn > 20.0 { dn } else { 20.0 });
                if dn > 20.0 { log } else { dn * LINEAR_SLOPE }
            }
            LogResponse::Eps => fast_math::ln(dn * (1.0 / 255.0) + self.eps),
        }
    }

    /// The intensity (camera DN) whose log-domain value is `value` (the inverse of
    /// [`Self::apply`]).
    pub fn inverse(&self, value: f32) -> f32 {
        match self.kind {
            LogResponse::V2e => {
                if value > 20f32.ln() {
                    fast_math::exp(value)
                } else {
                    value / LINEAR_SLOPE
                }
            }
            LogResponse::Eps => 255.0 * (fast_math::exp(value) - self.eps),
        }
    }

    /// Maps a frame of DN values into `out`.
    #[inline(always)]
    pub fn apply_frame(&self, dn: &[f32], out: &mut [f32]) {
        for (o, &d) in out.iter_mut().zip(dn) {
            *o = self.apply(d);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn v2e_lin_log_is_continuous_at_20_dn() {
        let m = LogMap::new(LogResponse::V2e, 0.001);
        assert!((m.apply(20.0) - 20f32.ln()).abs() < 1e-6);
        assert!((m.apply(20.0001) - m.apply(20.0)).abs() < 1e-4);
        assert_eq!(m.apply(0.0), 0.0);
        assert!((m.apply(100.0) - 100f32.ln()).abs() < 1e-6);
        // the screen black of dev_screen_checker (1 DN) sits at 0.1498
        assert!((m.apply(1.0) - 0.1498).abs() < 1e-4);
    }

    #[test]
    fn inverse_undoes_the_response() {
        for kind in [LogResponse::V2e, LogResponse::Eps] {
            let m = LogMap::new(kind, 0.001);
            for dn in [0.5f32, 5.0, 19.9, 20.0, 21.0, 90.0, 255.0, 400.0] {
                let back = m.inverse(m.apply(dn));
                assert!(
                    (back - dn).abs() <= 1e-4 * dn.max(1.0),
                    "{kind:?} {dn} -> {back}"
                );
            }
        }
    }

    #[test]
    fn eps_response() {
        let m = LogMap::new(LogResponse::Eps, 0.001);
        assert!((m.apply(255.0) - 1.001f32.ln()).abs() < 1e-6);
        assert!((m.apply(0.0) - 0.001f32.ln()).abs() < 1e-5);
    }
}
