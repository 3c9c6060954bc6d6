//! A sample-and-hold input as the peers see it: each peer reads its frames one way only
//! (ESIM and DVS-Voltmeter interpolate the log linearly between frames, IEBCS holds each
//! frame over the interval before it), and none reads ctcal's [`Transition::Hold`]. A
//! display that refreshes at 67 Hz fed to ESIM frame by frame would be seen as a cross-fade
//! over the whole 15 ms period: a different display from the one the case declares, whose
//! events come spread over the period as if the photoreceptor were slow. So before a held
//! sample the previous picture is repeated 1 us before the refresh ([`HeldAsSteps`]), and
//! every peer sees the step at the refresh, as a camera in front of the screen would.

use crate::sim::SimError;
use crate::sim::pixel::Transition;
use crate::sim::source::{FrameSource, Sample};

/// The source's samples, with the previous picture repeated 1 us before every held one;
/// every sample it gives is linear from the one before.
pub struct HeldAsSteps<'a> {
    inner: &'a mut dyn FrameSource,
    previous: Option<Sample>,
    queued: Option<Sample>,
}

impl<'a> HeldAsSteps<'a> {
    pub fn new(inner: &'a mut dyn FrameSource) -> Self {
        Self {
            inner,
            previous: None,
            queued: None,
        }
    }
}

impl FrameSource for HeldAsSteps<'_> {
    fn size(&self) -> (usize, usize) {
        self.inner.size()
    }

    fn next_frame(&mut self) -> Result<Option<Sample>, SimError> {
        let next = match self.queued.take() {
            Some(sample) => sample,
            None => match self.inner.next_frame()? {
                Some(sample) => sample,
                None => return Ok(None),
            },
        };
        let before = match &self.previous {
            Some(p) if next.transition == Transition::Hold && next.t - 1 > p.t => Some(Sample {
                t: next.t - 1,
                dn: p.dn.clone(),
                transition: Transition::Linear,
            }),
            _ => None,
        };
        let next = Sample {
            transition: Transition::Linear,
            ..next
        };
        self.previous = Some(next.clone());
        Ok(Some(match before {
            Some(hold) => {
                self.queued = Some(next);
                hold
            }
            None => next,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::source::ReplaySamples;

    fn sample(t: i64, dn: f32, transition: Transition) -> Sample {
        Sample {
            t,
            dn: vec![dn],
            transition,
        }
    }

    fn drained(samples: &[Sample]) -> Vec<(i64, f32)> {
        let mut replay = ReplaySamples::new(samples, 1, 1);
        let mut held = HeldAsSteps::new(&mut replay);
        let mut out = Vec::new();
        while let Some(s) = held.next_frame().unwrap() {
            assert_eq!(s.transition, Transition::Linear);
            out.push((s.t, s.dn[0]));
        }
        out
    }

    #[test]
    fn a_held_sample_is_preceded_by_the_previous_picture_1_us_before() {
        let hold = [
            sample(0, 10.0, Transition::Hold),
            sample(15_000, 50.0, Transition::Hold),
            sample(30_000, 20.0, Transition::Hold),
        ];
        assert_eq!(
            drained(&hold),
            [
                (0, 10.0),
                (14_999, 10.0),
                (15_000, 50.0),
                (29_999, 50.0),
                (30_000, 20.0)
            ]
        );
    }

    #[test]
    fn linear_samples_and_samples_1_us_apart_pass_unchanged() {
        let linear = [
            sample(0, 10.0, Transition::Linear),
            sample(1000, 50.0, Transition::Linear),
            sample(1001, 20.0, Transition::Hold),
        ];
        assert_eq!(drained(&linear), [(0, 10.0), (1000, 50.0), (1001, 20.0)]);
    }
}
