//! Inputs of the simulator: a stream of intensity samples (camera DN frames with times and
//! how the input moves between them), from an IJRR frame folder, a scene, or a display
//! showing either.

use super::SimError;
use super::display::DisplayModel;
use super::pixel::Transition;
use crate::events::TimeUs;
use crate::io::FrameList;

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

/// Frames of an `images.txt` folder; the sensor size is the image size.
pub struct FolderSource {
    list: FrameList,
    next: usize,
    size: (usize, usize),
}

impl FolderSource {
    pub fn new(list: FrameList) -> Result<Self, SimError> {
        let Some((w, h)) = list.image_size()? else {
            return Err(SimError::Input(crate::io::InputError::invalid(
                &list.index_path,
                "lists no frames",
                "give a folder whose images.txt names at least two frames",
            )));
        };
        Ok(Self {
            list,
            next: 0,
            size: (w as usize, h as usize),
        })
    }
}

impl FrameSource for FolderSource {
    fn size(&self) -> (usize, usize) {
        self.size
    }

    fn len_hint(&self) -> Option<u64> {
        Some(self.list.len() as u64)
    }

    fn next_frame(&mut self) -> Result<Option<Sample>, SimError> {
        if self.next >= self.list.len() {
            return Ok(None);
        }
        let frame = self.list.load(self.next)?;
        if (frame.width as usize, frame.height as usize) != self.size {
            return Err(SimError::Input(crate::io::InputError::corrupt(
                &self.list.index_path,
                format!("line {}", self.list.entries[self.next].line),
                format!(
                    "image is {}x{} but the first image is {}x{}",
                    frame.width, frame.height, self.size.0, self.size.1
                ),
                "give frames of one size",
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
/// (sample and hold), through its gamma, black level, white level and optical blur.
pub struct DisplaySource<S> {
    inner: S,
    model: DisplayModel,
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
            shown: None,
            pending: None,
            refresh: 0,
            first_t: None,
            offset_us,
            done: false,
        }
    }

    fn refresh_time(&self, k: u64) -> TimeUs {
        self.first_t.unwrap_or(0)
            + (k as f64 * 1e6 / self.model.params().refresh_hz).round() as TimeUs
    }
}

impl<S: FrameSource> FrameSource for DisplaySource<S> {
    fn size(&self) -> (usize, usize) {
        self.inner.size()
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
            self.shown = Some(self.model.camera_dn(&p.dn, w, h));
            changed = true;
            self.pending = self.inner.next_frame()?;
        }
        if !changed && self.pending.is_none() {
            // the stimulus ended: the last frame is shown for one more refresh, then stop
            self.done = true;
        }
        let Some(shown) = &self.shown else {
            return Ok(None);
        };
        self.refresh += 1;
        Ok(Some(Sample {
            t: t + self.offset_us,
            dn: shown.clone(),
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
