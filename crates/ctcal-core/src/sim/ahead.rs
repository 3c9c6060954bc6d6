//! A frame source produced one sample ahead on another thread: while the simulator
//! consumes sample k, sample k + 1 is rendered (a scene) or decoded (frames), so on two
//! cores the input's time hides behind the simulation's instead of adding to it.
//!
//! At most one sample is in flight beside the one being simulated: the channel holds
//! none, and the producer waits with its finished sample until the simulator takes it.
//! The samples, their order and any error are the inner source's; a panic on the
//! producer's thread is raised again in the caller's.
//!
//! `simulate --scene` does not use it: on two cores the rendering and the simulation
//! already share both, and pipelining them was not measurably faster; the measurement
//! (`examples/render_hidden.rs`, `benches/README.md`, "Rendering pipelined with the
//! simulation") uses it to show what a pipeline could hide.

use super::SimError;
use super::source::{FrameSource, Sample};
use std::sync::mpsc::{Receiver, channel, sync_channel};
use std::thread::JoinHandle;

type Message = Result<Sample, SimError>;

/// `inner`'s samples, each produced on another thread while the previous one is
/// simulated; `inner` itself where no thread can be started.
pub fn ahead<S: FrameSource + Send + 'static>(inner: S) -> Box<dyn FrameSource> {
    let (size, len_hint) = (inner.size(), inner.len_hint());
    let (sender, samples) = sync_channel::<Message>(0);
    let (give, take) = channel::<S>();
    let spawned = std::thread::Builder::new()
        .name("ctcal-ahead".into())
        .spawn(move || {
            let Ok(mut source) = take.recv() else { return };
            while let Some(message) = source.next_frame().transpose() {
                let failed = message.is_err();
                if sender.send(message).is_err() || failed {
                    break;
                }
            }
        });
    match spawned {
        Ok(producer) => {
            // the producer waits for its source, so it is there to take it
            let _ = give.send(inner);
            Box::new(Ahead {
                size,
                len_hint,
                samples: Some(samples),
                producer: Some(producer),
            })
        }
        Err(_) => Box::new(inner),
    }
}

/// The simulator's end of [`ahead`].
struct Ahead {
    size: (usize, usize),
    len_hint: Option<u64>,
    samples: Option<Receiver<Message>>,
    producer: Option<JoinHandle<()>>,
}

impl FrameSource for Ahead {
    fn size(&self) -> (usize, usize) {
        self.size
    }

    fn len_hint(&self) -> Option<u64> {
        self.len_hint
    }

    fn next_frame(&mut self) -> Result<Option<Sample>, SimError> {
        let Some(samples) = &self.samples else {
            return Ok(None);
        };
        if let Ok(message) = samples.recv() {
            return message.map(Some);
        }
        // the producer is done, or panicked: its panic goes on here
        self.samples = None;
        if let Some(Err(panic)) = self.producer.take().map(JoinHandle::join) {
            std::panic::resume_unwind(panic);
        }
        Ok(None)
    }
}

impl Drop for Ahead {
    fn drop(&mut self) {
        // a producer waiting to hand over a sample stops when the channel closes
        self.samples = None;
        if let Some(producer) = self.producer.take() {
            let _ = producer.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::Transition;

    /// `count` samples of 2 x 1 px, sample k at k us holding k; an error at `fail`, a
    /// panic at `panic`.
    struct Counting {
        count: u64,
        next: u64,
        fail: Option<u64>,
        panic: Option<u64>,
    }

    fn counting(count: u64) -> Counting {
        Counting {
            count,
            next: 0,
            fail: None,
            panic: None,
        }
    }

    impl FrameSource for Counting {
        fn size(&self) -> (usize, usize) {
            (2, 1)
        }

        fn len_hint(&self) -> Option<u64> {
            Some(self.count)
        }

        fn next_frame(&mut self) -> Result<Option<Sample>, SimError> {
            let k = self.next;
            self.next += 1;
            assert_ne!(Some(k), self.panic, "the source panics");
            if Some(k) == self.fail {
                return Err(SimError::Invalid(format!("sample {k} is broken")));
            }
            Ok((k < self.count).then(|| Sample {
                t: k as i64,
                dn: vec![k as f32; 2],
                transition: Transition::Linear,
            }))
        }
    }

    fn drain(source: &mut dyn FrameSource) -> Vec<Result<Option<i64>, String>> {
        let mut seen = Vec::new();
        loop {
            let next = source.next_frame();
            let end = !matches!(next, Ok(Some(_)));
            seen.push(next.map(|s| s.map(|s| s.t)).map_err(|e| e.to_string()));
            if end {
                return seen;
            }
        }
    }

    #[test]
    fn samples_come_in_order_then_none() {
        let mut source = ahead(counting(50));
        assert_eq!((source.size(), source.len_hint()), ((2, 1), Some(50)));
        let seen = drain(source.as_mut());
        let expected: Vec<_> = (0..50).map(|k| Ok(Some(k))).chain([Ok(None)]).collect();
        assert_eq!(seen, expected);
        assert!(matches!(source.next_frame(), Ok(None)));
    }

    #[test]
    fn an_error_comes_through_in_its_place() {
        let seen = drain(
            ahead(Counting {
                fail: Some(3),
                ..counting(10)
            })
            .as_mut(),
        );
        assert_eq!(seen.len(), 4);
        assert_eq!(seen[3], Err("sample 3 is broken".into()));
    }

    #[test]
    #[should_panic(expected = "the source panics")]
    fn a_panic_of_the_producer_is_raised_in_the_caller() {
        drain(
            ahead(Counting {
                panic: Some(2),
                ..counting(10)
            })
            .as_mut(),
        );
    }

    #[test]
    fn dropping_early_stops_the_producer() {
        let mut source = ahead(counting(u64::MAX));
        assert!(matches!(source.next_frame(), Ok(Some(_))));
        // joins the producer, which would otherwise run on forever
        drop(source);
    }
}
