//! Work limits of a simulation, estimated before it starts: a scene with a typo (1e9 Hz, a
//! 100,000-pixel-wide sensor, a year of duration) is refused with the estimate and the key
//! to change, instead of running for hours or asking for tens of gigabytes. Forcing runs it
//! anyway.
//!
//! The cost of a simulation is its pixel updates (samples x pixels; the simulator runs
//! about 2-7e8 of them per second and core, README `benches/`) and its memory (about 150
//! bytes of state and frame buffers per pixel).

use super::SimError;
use crate::hint::{Hint, Text};

/// The largest sensor side ctcal simulates or infers (more than any sensor sold).
pub const MAX_SIDE: usize = 4096;
/// Pixel updates a simulation may take without `--force` (a minute or two on 2 cores).
pub const MAX_PIXEL_UPDATES: f64 = 2e10;
/// Bytes of simulator state a simulation may take without `--force`.
pub const MAX_MEMORY_BYTES: f64 = 4e9;
/// Simulator state and frame buffers per pixel, bytes (an upper estimate).
const BYTES_PER_PIXEL: f64 = 150.0;

/// The fix `fix`, or forcing the work (`then` says what forcing does).
fn or_force(fix: &str, then: &str) -> Text {
    Text::from(format!("{fix}, or "))
        .act(Hint::Force)
        .words(then)
}

/// The estimated work of one simulation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Work {
    /// Input samples (frames, rendered scene frames or display refreshes).
    pub samples: f64,
    pub pixels: f64,
}

impl Work {
    pub fn new(samples: f64, width: usize, height: usize) -> Self {
        Self {
            samples,
            pixels: width as f64 * height as f64,
        }
    }

    pub fn pixel_updates(&self) -> f64 {
        self.samples * self.pixels
    }

    pub fn memory_bytes(&self) -> f64 {
        self.pixels * BYTES_PER_PIXEL
    }

    /// Refuses work over the budget unless `force`; `what` names the input and `fix` the
    /// keys that set the work.
    pub fn check(&self, what: &str, fix: &str, force: bool) -> Result<(), SimError> {
        if force {
            return Ok(());
        }
        let updates = self.pixel_updates();
        if updates.is_nan() || updates > MAX_PIXEL_UPDATES {
            return Err(SimError::OverBudget {
                problem: format!(
                    "{what}: {:.3e} samples of {:.0} pixels make {updates:.2e} pixel updates, over the budget of {MAX_PIXEL_UPDATES:.0e} (about {:.0} minutes on 2 cores)",
                    self.samples,
                    self.pixels,
                    updates / 4e8 / 60.0
                ),
                fix: or_force(fix, " to run it anyway"),
            });
        }
        let memory = self.memory_bytes();
        if memory.is_nan() || memory > MAX_MEMORY_BYTES {
            return Err(SimError::OverBudget {
                problem: format!(
                    "{what}: {:.0} pixels need about {:.1} GB of simulator state, over the budget of {:.0} GB",
                    self.pixels,
                    memory / 1e9,
                    MAX_MEMORY_BYTES / 1e9
                ),
                fix: or_force("simulate a smaller sensor", ""),
            });
        }
        Ok(())
    }
}

/// Events the noise effects of a simulation may make without `--force` (about 4 GB of IJRR
/// text, and minutes of writing).
pub const MAX_NOISE_EVENTS: f64 = 2e8;
/// Events one input sample may make without `--force`: they are held in memory together
/// (about 20 bytes each) before they are written.
pub const MAX_EVENTS_PER_SAMPLE: f64 = 2e7;
/// Multiply-adds of the display's optical blur a simulation may take without `--force`
/// (a minute or two on 2 cores).
pub const MAX_BLUR_TAPS: f64 = 2e10;

/// The work the pixel model's effects add to a simulation, from the parameters alone: the
/// expected noise events (leak, shot noise, hot pixels: their rates times the pixels and
/// the time span) and the display blur's multiply-adds.
#[derive(Clone, Debug, PartialEq)]
pub struct EffectWork {
    /// Expected events of each noise effect, by its PARAMS key.
    pub noise: Vec<(&'static str, f64)>,
    /// Input samples the events are spread over.
    pub samples: f64,
    /// Multiply-adds of the display blur (0 without one).
    pub blur_taps: f64,
}

impl EffectWork {
    /// The effects of `params` over `work.pixels` pixels and `span_s` seconds of
    /// `work.samples` samples, `frames` of them new images (each blurred once by a display).
    pub fn new(params: &super::PixelParams, work: &Work, span_s: f64, frames: f64) -> Self {
        let pixels = work.pixels;
        let span = span_s.max(0.0);
        let mut noise = Vec::new();
        // the leak that grows with the light counted at full white (255 DN, or a display's
        // white where that is brighter), its most
        let white = params
            .display
            .as_ref()
            .map_or(255.0, |d| d.white_dn.max(255.0));
        let leak = params.leak_rate_hz() + params.leak_rate_hz_per_dn() * white;
        if leak > 0.0 {
            // the mean of the per-pixel lognormal factor 10^(s N(0, 1))
            let s = params.leak_spread_decades() * std::f64::consts::LN_10;
            let key = if params.leak_rate_hz_per_dn() * white > params.leak_rate_hz() {
                "leak_rate_hz_per_dn"
            } else {
                "leak_rate_hz"
            };
            noise.push((key, pixels * span * leak * (s * s / 2.0).exp()));
        }
        let shot = params.shot_noise_rate_hz();
        if shot > 0.0 {
            noise.push(("shot_noise_rate_hz", pixels * span * shot));
        }
        if let Some((fraction, rate)) = params.hot_pixels() {
            noise.push((
                "hot_pixel_rate_hz",
                (fraction * pixels).round() * span * rate,
            ));
        }
        let blur_taps = match params.display.as_ref().and_then(|d| d.blur_px) {
            Some(sigma) if sigma > 0.0 => {
                let kernel = 2.0 * (3.0 * sigma).ceil() + 1.0;
                // a separable blur: a pass along rows and one across
                frames * pixels * 2.0 * kernel
            }
            _ => 0.0,
        };
        Self {
            noise,
            samples: work.samples,
            blur_taps,
        }
    }

    pub fn noise_events(&self) -> f64 {
        self.noise.iter().map(|(_, n)| n).sum()
    }

    /// Refuses work over the budgets unless `force`; `what` names the parameters.
    pub fn check(&self, what: &str, force: bool) -> Result<(), SimError> {
        if force {
            return Ok(());
        }
        let events = self.noise_events();
        let per_sample = events / (self.samples - 1.0).max(1.0);
        if events.is_nan() || events > MAX_NOISE_EVENTS || per_sample > MAX_EVENTS_PER_SAMPLE {
            let parts = self
                .noise
                .iter()
                .map(|(key, n)| format!("{key}: {n:.2e}"))
                .collect::<Vec<_>>()
                .join(", ");
            let largest = self
                .noise
                .iter()
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .map_or("the noise rates", |(key, _)| key);
            return Err(SimError::OverBudget {
                problem: format!(
                    "{what}: the noise effects would make about {events:.2e} events ({parts}), {per_sample:.2e} per input sample; the budget is {MAX_NOISE_EVENTS:.0e} events, {MAX_EVENTS_PER_SAMPLE:.0e} per sample (about 20 bytes each in memory, more on disk)"
                ),
                fix: or_force(
                    &format!(
                        "lower {largest} (rates are per pixel per second), simulate a shorter span or a smaller sensor"
                    ),
                    " to run it anyway",
                ),
            });
        }
        if self.blur_taps.is_nan() || self.blur_taps > MAX_BLUR_TAPS {
            return Err(SimError::OverBudget {
                problem: format!(
                    "{what}: the display blur (display.blur_px) takes {:.2e} multiply-adds, over the budget of {MAX_BLUR_TAPS:.0e} (about {:.0} minutes on 2 cores)",
                    self.blur_taps,
                    self.blur_taps / 4e8 / 60.0
                ),
                fix: or_force(
                    "lower display.blur_px (a sigma in pixels; optics blur a few pixels)",
                    " to run it anyway",
                ),
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether forcing is among the fixes of `e`.
    fn forcing_fixes(e: &SimError) -> bool {
        e.message().hints().any(|h| *h == Hint::Force)
    }

    #[test]
    fn noise_and_blur_are_budgeted_from_the_parameters() {
        let work = Work::new(501.0, 240, 180);
        let mut p = super::super::PixelParams::ideal(0.3, 0.3);
        p.shot_noise_rate_hz = Some(1.0);
        p.leak_rate_hz = Some(0.1);
        let effects = EffectWork::new(&p, &work, 1.0, 501.0);
        assert!((effects.noise_events() - 43_200.0 * 1.1).abs() < 500.0);
        assert!(effects.check("p.toml", false).is_ok());
        p.leak_rate_hz = Some(1e9);
        let e = EffectWork::new(&p, &work, 1.0, 501.0)
            .check("p.toml", false)
            .unwrap_err();
        assert!(forcing_fixes(&e), "{e}");
        let e = e.to_string();
        assert!(
            e.contains("p.toml") && e.contains("lower leak_rate_hz"),
            "{e}"
        );
        assert!(
            EffectWork::new(&p, &work, 1.0, 501.0)
                .check("p.toml", true)
                .is_ok()
        );
        let mut p = super::super::PixelParams::ideal(0.3, 0.3);
        p.hot_pixel_fraction = Some(0.01);
        p.hot_pixel_rate_hz = Some(1e6);
        let e = EffectWork::new(&p, &work, 1.0, 501.0)
            .check("p.toml", false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("lower hot_pixel_rate_hz"), "{e}");
        let mut p = super::super::PixelParams::ideal(0.3, 0.3);
        p.display = Some(super::super::DisplayParams {
            refresh_hz: 75.0,
            gamma: 2.0,
            black_level: 0.0,
            white_dn: 200.0,
            blur_px: Some(0.8),
            time_offset_s: None,
        });
        assert!(
            EffectWork::new(&p, &work, 1.0, 75.0)
                .check("p.toml", false)
                .is_ok()
        );
        p.display.as_mut().unwrap().blur_px = Some(1e6);
        let e = EffectWork::new(&p, &work, 1.0, 75.0)
            .check("p.toml", false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("display.blur_px"), "{e}");
    }

    #[test]
    fn budget_refuses_hours_of_work_and_force_allows_it() {
        // a 1 s texture at 1 kHz on a DAVIS240: 4.3e7 updates
        assert!(Work::new(1001.0, 240, 180).check("s", "f", false).is_ok());
        // a typo: 1e9 Hz for a second
        let e = Work::new(1e9, 240, 180).check("scene.toml", "lower render_hz", false);
        let e = e.unwrap_err();
        assert!(forcing_fixes(&e), "{e}");
        let e = e.to_string();
        assert!(e.contains("scene.toml") && e.contains("render_hz"));
        assert!(Work::new(1e9, 240, 180).check("s", "f", true).is_ok());
        assert!(
            Work::new(f64::NAN, 240, 180)
                .check("s", "f", false)
                .is_err()
        );
    }
}
