//! Inputs of the simulator: a stream of intensity samples (camera DN frames with times and
//! how the input moves between them), from frames in memory, frames the caller decodes one
//! at a time, a scene, or a display showing any of them.

use super::SimError;
use super::display::DisplayModel;
use super::footprints::{self, Footprints, Uniform};
use super::pixel::Transition;
use super::screen_geometry::{self, ScreenWarp};
use crate::events::{Frame, TimeUs};

/// One intensity sample.
#[derive(Clone, Debug)]
pub struct Sample {
    pub t: TimeUs,
    /// Camera DN, row-major W x H.
    pub dn: Vec<f32>,
    /// How the input reaches this sample from the previous one.
    pub transition: Transition,
}

/// A sequence of samples.
pub trait FrameSource {
    fn size(&self) -> (usize, usize);
    /// Number of samples, where known (for progress).
    fn len_hint(&self) -> Option<u64> {
        None
    }
    fn next_frame(&mut self) -> Result<Option<Sample>, SimError>;
}

/// 8-bit frames held in memory (decoded once), replayed as samples: the input of every
/// re-simulation an estimator or a fit runs many times. [`Self::rewind`] starts over.
#[derive(Clone, Debug)]
pub struct MemoryFrames<'a> {
    frames: &'a [Frame],
    size: (usize, usize),
    next: usize,
    transition: Transition,
}

impl<'a> MemoryFrames<'a> {
    /// Frames of one size in time order (checked); `transition` says how the input moves
    /// between them (linear for video, hold for a display).
    pub fn new(frames: &'a [Frame], transition: Transition) -> Result<Self, SimError> {
        let Some(first) = frames.first() else {
            return Err(SimError::Invalid("no frames to simulate from".into()));
        };
        let size = (first.width as usize, first.height as usize);
        for (i, pair) in frames.windows(2).enumerate() {
            if (pair[1].width as usize, pair[1].height as usize) != size {
                return Err(SimError::Invalid(format!(
                    "frame {} is {}x{} but frame 0 is {}x{}",
                    i + 1,
                    pair[1].width,
                    pair[1].height,
                    size.0,
                    size.1
                )));
            }
            if pair[1].t < pair[0].t {
                return Err(SimError::Invalid(format!(
                    "frame {} at {} us is earlier than frame {} at {} us",
                    i + 1,
                    pair[1].t,
                    i,
                    pair[0].t
                )));
            }
        }
        Ok(Self {
            frames,
            size,
            next: 0,
            transition,
        })
    }

    /// Starts again at the first frame.
    pub fn rewind(&mut self) {
        self.next = 0;
    }
}

impl FrameSource for MemoryFrames<'_> {
    fn size(&self) -> (usize, usize) {
        self.size
    }

    fn len_hint(&self) -> Option<u64> {
        Some(self.frames.len() as u64)
    }

    fn next_frame(&mut self) -> Result<Option<Sample>, SimError> {
        let Some(frame) = self.frames.get(self.next) else {
            return Ok(None);
        };
        self.next += 1;
        Ok(Some(Sample {
            t: frame.t,
            dn: frame.pixels.iter().map(|&p| p as f32).collect(),
            transition: self.transition,
        }))
    }
}

/// Samples already in memory (e.g. frames upsampled once for many simulations), replayed
/// from the start every time a source is made of them.
pub struct ReplaySamples<'a> {
    samples: &'a [Sample],
    size: (usize, usize),
    next: usize,
}

impl<'a> ReplaySamples<'a> {
    pub fn new(samples: &'a [Sample], width: usize, height: usize) -> Self {
        Self {
            samples,
            size: (width, height),
            next: 0,
        }
    }
}

impl FrameSource for ReplaySamples<'_> {
    fn size(&self) -> (usize, usize) {
        self.size
    }

    fn len_hint(&self) -> Option<u64> {
        Some(self.samples.len() as u64)
    }

    fn next_frame(&mut self) -> Result<Option<Sample>, SimError> {
        let sample = self.samples.get(self.next).cloned();
        self.next += 1;
        Ok(sample)
    }
}

/// Frames decoded one at a time by the caller's `load(i)` (e.g. PNGs listed in an
/// `images.txt`), so that a long frame sequence is never all in memory.
pub struct LoadedFrames<F> {
    count: usize,
    size: (usize, usize),
    next: usize,
    load: F,
}

impl<F: FnMut(usize) -> Result<Frame, SimError>> LoadedFrames<F> {
    /// `count` frames of `size` (W, H); a frame of another size is an error.
    pub fn new(count: usize, size: (usize, usize), load: F) -> Self {
        Self {
            count,
            size,
            next: 0,
            load,
        }
    }
}

impl<F: FnMut(usize) -> Result<Frame, SimError>> FrameSource for LoadedFrames<F> {
    fn size(&self) -> (usize, usize) {
        self.size
    }

    fn len_hint(&self) -> Option<u64> {
        Some(self.count as u64)
    }

    fn next_frame(&mut self) -> Result<Option<Sample>, SimError> {
        if self.next >= self.count {
            return Ok(None);
        }
        let frame = (self.load)(self.next)?;
        if (frame.width as usize, frame.height as usize) != self.size {
            return Err(SimError::Invalid(format!(
                "frame {} is {}x{} but the first frame is {}x{}: give frames of one size",
                self.next, frame.width, frame.height, self.size.0, self.size.1
            )));
        }
        self.next += 1;
        Ok(Some(Sample {
            t: frame.t,
            dn: frame.pixels.iter().map(|&p| p as f32).collect(),
            transition: Transition::Linear,
        }))
    }
}

/// A display showing another source's frames: at every refresh it shows the latest frame
/// (sample and hold), through its gamma, black level, white level and optical blur; seen
/// at an angle when it has a [`ScreenWarp`] ([`Self::seen_through`]).
pub struct DisplaySource<S> {
    inner: S,
    model: DisplayModel,
    warp: Option<std::sync::Arc<ScreenWarp>>,
    /// The inner frames' footprints through `warp`, in order ([`Self::seen_with`]), and
    /// the display's uniform images; how many inner frames were taken.
    footprints: Option<std::sync::Arc<[Footprints]>>,
    uniform: Uniform,
    taken: usize,
    shown: Option<Vec<f32>>,
    pending: Option<Sample>,
    refresh: u64,
    first_t: Option<TimeUs>,
    offset_us: TimeUs,
    done: bool,
}

impl<S: FrameSource> DisplaySource<S> {
    pub fn new(inner: S, model: DisplayModel) -> Self {
        let offset_us = (model.params().time_offset_s.unwrap_or(0.0) * 1e6).round() as TimeUs;
        Self {
            inner,
            model,
            warp: None,
            footprints: None,
            uniform: Uniform::default(),
            taken: 0,
            shown: None,
            pending: None,
            refresh: 0,
            first_t: None,
            offset_us,
            done: false,
        }
    }

    /// The screen seen through `warp` (stimulus-sized frames in, sensor-sized samples out).
    pub fn seen_through(mut self, warp: std::sync::Arc<ScreenWarp>) -> Self {
        self.warp = Some(warp);
        self
    }

    /// [`Self::seen_through`], with the footprints of the inner source's frames through
    /// `warp`, frame by frame ([`Footprints::of_frames`]): the same samples, each frame's
    /// uniform footprints rendered once per DN ([`footprints`]).
    pub fn seen_with(
        mut self,
        warp: std::sync::Arc<ScreenWarp>,
        footprints: std::sync::Arc<[Footprints]>,
    ) -> Self {
        self.footprints = Some(footprints);
        self.seen_through(warp)
    }

    /// The camera DN of the inner source's next frame `dn` through the display and `warp`.
    fn warped(&mut self, warp: &ScreenWarp, dn: &[f32]) -> Vec<f32> {
        let index = self.taken;
        self.taken += 1;
        match self.footprints.as_ref().and_then(|f| f.get(index)) {
            Some(f) => footprints::camera_dn(&self.model, warp, dn, f, &mut self.uniform),
            None => screen_geometry::camera_dn(&self.model, warp, dn),
        }
    }

    /// The frame shown at the refresh just made: moved out when the next frame replaces it
    /// by the next refresh (the screen's frames come at its refresh rate), else copied.
    fn shown_now(&mut self) -> Vec<f32> {
        let next = self.refresh_time(self.refresh);
        let replaced = self.pending.as_ref().is_some_and(|p| p.t <= next);
        match &mut self.shown {
            Some(shown) if replaced => std::mem::take(shown),
            Some(shown) => shown.clone(),
            None => Vec::new(),
        }
    }

    fn refresh_time(&self, k: u64) -> TimeUs {
        self.first_t.unwrap_or(0)
            + (k as f64 * 1e6 / self.model.params().refresh_hz).round() as TimeUs
    }
}

impl<S: FrameSource> FrameSource for DisplaySource<S> {
    fn size(&self) -> (usize, usize) {
        match &self.warp {
            Some(warp) => warp.sensor_size(),
            None => self.inner.size(),
        }
    }

    fn next_frame(&mut self) -> Result<Option<Sample>, SimError> {
        if self.done {
            return Ok(None);
        }
        if self.pending.is_none() {
            self.pending = self.inner.next_frame()?;
        }
        if self.first_t.is_none() {
            let Some(first) = self.pending.as_ref() else {
                return Ok(None);
            };
            self.first_t = Some(first.t);
        }
        let t = self.refresh_time(self.refresh);
        // the latest content at this refresh
        let mut changed = false;
        while let Some(p) = &self.pending {
            if p.t > t {
                break;
            }
            let (w, h) = self.inner.size();
            let p = self.pending.take().expect("checked");
            self.shown = Some(match self.warp.clone() {
                Some(warp) if warp.stimulus_size() == (w, h) => self.warped(&warp, &p.dn),
                Some(warp) => {
                    return Err(SimError::Invalid(format!(
                        "the screen geometry is for a {}x{} stimulus, the frames are {w}x{h}",
                        warp.stimulus_size().0,
                        warp.stimulus_size().1
                    )));
                }
                None => self.model.camera_dn(&p.dn, w, h),
            });
            changed = true;
            self.pending = self.inner.next_frame()?;
        }
        if !changed && self.pending.is_none() {
            // the stimulus ended: the last frame is shown for one more refresh, then stop
            self.done = true;
        }
        if self.shown.is_none() {
            return Ok(None);
        }
        self.refresh += 1;
        Ok(Some(Sample {
            t: t + self.offset_us,
            dn: self.shown_now(),
            transition: Transition::Hold,
        }))
    }
}

impl<S: FrameSource + ?Sized> FrameSource for Box<S> {
    fn size(&self) -> (usize, usize) {
        (**self).size()
    }

    fn len_hint(&self) -> Option<u64> {
        (**self).len_hint()
    }

    fn next_frame(&mut self) -> Result<Option<Sample>, SimError> {
        (**self).next_frame()
    }
}
