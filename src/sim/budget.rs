//! Work limits of a simulation, estimated before it starts: a scene with a typo (1e9 Hz, a
//! 100,000-pixel-wide sensor, a year of duration) is refused with the estimate and the key
//! to change, instead of running for hours or asking for tens of gigabytes. `--force` runs
//! it anyway.
//!
//! The cost of a simulation is its pixel updates (samples x pixels; the simulator runs
//! about 2-7e8 of them per second and core, README `benches/`) and its memory (about 150
//! bytes of state and frame buffers per pixel).

use super::SimError;

/// The largest sensor side ctcal simulates or infers (more than any sensor sold).
pub const MAX_SIDE: usize = 4096;
/// Pixel updates a simulation may take without `--force` (a minute or two on 2 cores).
pub const MAX_PIXEL_UPDATES: f64 = 2e10;
/// Bytes of simulator state a simulation may take without `--force`.
pub const MAX_MEMORY_BYTES: f64 = 4e9;
/// Simulator state and frame buffers per pixel, bytes (an upper estimate).
const BYTES_PER_PIXEL: f64 = 150.0;

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
            return Err(SimError::Invalid(format!(
                "{what}: {:.3e} samples of {:.0} pixels make {updates:.2e} pixel updates, over the budget of {MAX_PIXEL_UPDATES:.0e} (about {:.0} minutes on 2 cores)\n  fix: {fix}, or pass --force to run it anyway",
                self.samples,
                self.pixels,
                updates / 4e8 / 60.0
            )));
        }
        let memory = self.memory_bytes();
        if memory.is_nan() || memory > MAX_MEMORY_BYTES {
            return Err(SimError::Invalid(format!(
                "{what}: {:.0} pixels need about {:.1} GB of simulator state, over the budget of {:.0} GB\n  fix: simulate a smaller sensor, or pass --force",
                self.pixels,
                memory / 1e9,
                MAX_MEMORY_BYTES / 1e9
            )));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budget_refuses_hours_of_work_and_force_allows_it() {
        // a 1 s texture at 1 kHz on a DAVIS240: 4.3e7 updates
        assert!(Work::new(1001.0, 240, 180).check("s", "f", false).is_ok());
        // a typo: 1e9 Hz for a second
        let e = Work::new(1e9, 240, 180).check("scene.toml", "lower render_hz", false);
        let e = e.unwrap_err().to_string();
        assert!(e.contains("scene.toml") && e.contains("render_hz") && e.contains("--force"));
        assert!(Work::new(1e9, 240, 180).check("s", "f", true).is_ok());
        assert!(
            Work::new(f64::NAN, 240, 180)
                .check("s", "f", false)
                .is_err()
        );
    }
}
