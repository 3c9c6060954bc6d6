//! Whether the recording's leak events start at its start: the fit without frames reads
//! leak as the ON excess of isolated events (Nozaki & Delbruck, IEEE TED 2017: a leaking
//! pixel fires ON at a steady rate in a static scene), which is the leak rate only where
//! the pixels' leak phases are spread at random, as in a camera that has been running. A
//! simulator (ctcal's, v2e's) starts every pixel's reference at the first frame, and a
//! camera resets its pixels when it starts, so a pixel's first leak event then comes one
//! leak period after the start: a leak slower than the time since the start fires no
//! isolated events yet, and the ON excess grows with time (coverage draw 7017, a 1.19 s
//! period in 0.97 s: 0.002-0.009 Hz over the first three quarters, then 0.038 and
//! 0.096 Hz; `benches/coverage/fresh-7001-7040-2026-12-04/leak-onset`). Where the later
//! (selection) blocks show more ON excess than the fit blocks beyond chance, the fit
//! blocks' excess is a lower bound on the leak, not its rate.

use super::measure::{BlockMeasure, Isolation};

/// The rise of the ON excess, in standard errors, that marks an onset.
pub const ONSET_Z: f64 = 3.0;

/// The ON excess over the fit blocks and over the later blocks (Hz per pixel, with their
/// Poisson standard errors), where the later one exceeds the first by [`ONSET_Z`]
/// standard errors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Onset {
    pub fit_hz: (f64, f64),
    pub later_hz: (f64, f64),
}

impl Onset {
    pub fn z(&self) -> f64 {
        (self.later_hz.0 - self.fit_hz.0) / self.fit_hz.1.hypot(self.later_hz.1)
    }

    pub fn evidence(&self) -> String {
        format!(
            "isolated ON events exceed OFF by {:.4} +- {:.4} Hz per pixel over the fit blocks and by {:.4} +- {:.4} Hz over the later (selection) blocks ({:.1} standard errors more): leak events that start a leak period after a reset (a simulator's first frame, a camera's start), so the fit blocks' excess is a lower bound on the leak, not its rate",
            self.fit_hz.0,
            self.fit_hz.1,
            self.later_hz.0,
            self.later_hz.1,
            self.z()
        )
    }
}

/// The ON excess of isolated events under `iso` over `blocks` and its standard error.
fn excess(blocks: &[&BlockMeasure], iso: Isolation) -> Option<(f64, f64)> {
    let i = BlockMeasure::isolated(blocks, iso);
    (i.pixel_seconds > 0.0).then(|| {
        (
            (i.on as f64 - i.off as f64) / i.pixel_seconds,
            ((i.on + i.off).max(1) as f64).sqrt() / i.pixel_seconds,
        )
    })
}

/// The onset, where the later blocks' ON excess rises above the fit blocks' by
/// [`ONSET_Z`] standard errors.
pub fn onset(fit: &[&BlockMeasure], later: &[&BlockMeasure], iso: Isolation) -> Option<Onset> {
    let o = Onset {
        fit_hz: excess(fit, iso)?,
        later_hz: excess(later, iso)?,
    };
    (o.z() >= ONSET_Z && o.later_hz.0 > 0.0).then_some(o)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::events_only::measure::Isolated;

    fn block(on: u64, off: u64, pixel_seconds: f64) -> BlockMeasure {
        let iso = Isolated {
            on,
            off,
            pixel_seconds,
        };
        BlockMeasure {
            seconds: 0.1,
            pixel_seconds,
            isolated: vec![iso; 12],
            signal_on: 0,
            signal_off: 0,
            intervals: Vec::new(),
            hot_events: Vec::new(),
            pixel_rate_hz: 0.0,
            signal_rate_hz: 0.0,
        }
    }

    #[test]
    fn an_on_excess_that_grows_after_the_fit_blocks_is_an_onset_and_a_steady_one_is_not() {
        let iso = Isolation {
            window: 0,
            radius: 0,
        };
        // draw 7017's counts, rounded: fit blocks 57 ON, 0 OFF over 4 x 2346 pixel-s
        // (0.0061 +- 0.0008 Hz), later blocks 88 ON over 2346 (0.0375 +- 0.0040 Hz):
        // (0.0375 - 0.0061) / hypot(0.0008, 0.0040) = 7.7 standard errors
        let fit: Vec<BlockMeasure> = [14, 14, 14, 15].map(|on| block(on, 0, 2346.0)).into();
        let later = [block(88, 0, 2346.0)];
        let o = onset(&fit.iter().collect::<Vec<_>>(), &[&later[0]], iso).expect("an onset");
        assert!((o.fit_hz.0 - 57.0 / 9384.0).abs() < 1e-9, "{o:?}");
        assert!((o.z() - 7.7).abs() < 0.1, "{}", o.z());
        // random phases: the same excess rate in every block
        let steady = [block(57, 0, 9384.0)];
        let same = [block(15, 0, 2346.0)];
        assert_eq!(onset(&[&steady[0]], &[&same[0]], iso), None);
        // shot noise (ON and OFF alike) rising later is not a leak onset
        let both = [block(88, 88, 2346.0)];
        assert_eq!(onset(&[&steady[0]], &[&both[0]], iso), None);
    }
}
