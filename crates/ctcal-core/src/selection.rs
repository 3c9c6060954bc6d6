//! Which pixels of a sensor an analysis keeps: a region of interest, a mask, and pixels
//! left out by name (hot pixels). Every per-pixel quantity (events per pixel per second,
//! active fraction, background rate) is then taken over the kept pixels only, as if the
//! sensor were just those pixels; the spatio-temporal support of an event still looks at
//! all of its neighbours (a moving edge does not stop at the border of a region).

use crate::events::Sensor;
use crate::hint::{Hint, Text};
use serde::Serialize;

/// A rectangle of pixels `x0 <= x < x1`, `y0 <= y < y1` (the upper bounds excluded, as in
/// array slices).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Roi {
    pub x0: u16,
    pub y0: u16,
    pub x1: u16,
    pub y1: u16,
}

impl Roi {
    /// Parses `X0,Y0,X1,Y1`.
    pub fn parse(text: &str) -> Result<Self, String> {
        let values: Vec<u16> = text
            .split(',')
            .map(|v| v.trim().parse::<u16>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("`{text}` is not X0,Y0,X1,Y1 (four whole pixel numbers)"))?;
        let [x0, y0, x1, y1] = values[..] else {
            return Err(format!("`{text}` is not X0,Y0,X1,Y1 (four numbers)"));
        };
        if x1 <= x0 || y1 <= y0 {
            return Err(format!(
                "`{text}` is empty: the region keeps x0 <= x < x1 and y0 <= y < y1, so x1 > x0 and y1 > y0"
            ));
        }
        Ok(Self { x0, y0, x1, y1 })
    }
}

impl std::fmt::Display for Roi {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{},{},{}", self.x0, self.y0, self.x1, self.y1)
    }
}

/// Why a selection cannot be made: what and the fix.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{problem}\n  fix: {fix}")]
pub struct SelectionError {
    pub problem: Text,
    pub fix: Text,
}

/// The kept pixels of a sensor.
#[derive(Clone, Debug, PartialEq)]
pub struct PixelSelection {
    sensor: Sensor,
    /// Row-major, one per pixel.
    keep: Vec<bool>,
    /// What was applied, in order, for reports.
    parts: Vec<String>,
}

impl PixelSelection {
    /// Every pixel.
    pub fn all(sensor: Sensor) -> Self {
        Self {
            sensor,
            keep: vec![true; sensor.pixels()],
            parts: Vec::new(),
        }
    }

    /// Keeps only the pixels inside `roi`, which must lie on the sensor.
    pub fn roi(mut self, roi: Roi) -> Result<Self, SelectionError> {
        let s = self.sensor;
        if roi.x1 > s.width || roi.y1 > s.height {
            return Err(SelectionError {
                problem: Text::default().name(Hint::Roi(roi)).words(format!(
                    " reaches beyond the {s} sensor (x < {}, y < {})",
                    s.width, s.height
                )),
                fix: format!(
                    "give X0,Y0,X1,Y1 with X1 <= {} and Y1 <= {} (X1 and Y1 are excluded)",
                    s.width, s.height
                )
                .into(),
            });
        }
        for y in 0..s.height {
            for x in 0..s.width {
                if !(roi.x0..roi.x1).contains(&x) || !(roi.y0..roi.y1).contains(&y) {
                    self.keep[y as usize * s.width as usize + x as usize] = false;
                }
            }
        }
        self.parts.push(format!(
            "region x {}..{}, y {}..{}",
            roi.x0, roi.x1, roi.y0, roi.y1
        ));
        Ok(self)
    }

    /// Keeps only the pixels `mask` keeps (row-major, the sensor's size); `source` names it.
    pub fn mask(mut self, mask: &[bool], source: &str) -> Result<Self, SelectionError> {
        if mask.len() != self.keep.len() {
            return Err(SelectionError {
                problem: format!(
                    "the mask {source} has {} values; the {} sensor has {} pixels",
                    mask.len(),
                    self.sensor,
                    self.keep.len()
                )
                .into(),
                fix: format!("give a mask of {} (H x W)", self.sensor).into(),
            });
        }
        for (k, &m) in self.keep.iter_mut().zip(mask) {
            *k &= m;
        }
        // an empty selection measures nothing: every rate would divide by zero pixels
        if !self.keep.contains(&true) {
            let problem = if mask.contains(&true) {
                format!(
                    "the mask {source} keeps no pixel inside the {}",
                    self.parts.join("; ")
                )
            } else {
                format!("the mask {source} keeps no pixel (every value is zero)")
            };
            return Err(SelectionError {
                problem: problem.into(),
                fix: "give a mask with non-zero values at the pixels to keep (zero = leave out)"
                    .into(),
            });
        }
        self.parts.push(format!("mask {source}"));
        Ok(self)
    }

    /// Leaves out the listed pixels (e.g. hot pixels); `what` names them.
    pub fn without(mut self, pixels: impl IntoIterator<Item = (u16, u16)>, what: &str) -> Self {
        let mut n = 0;
        for (x, y) in pixels {
            if self.sensor.contains(x, y) {
                let k = y as usize * self.sensor.width as usize + x as usize;
                n += self.keep[k] as usize;
                self.keep[k] = false;
            }
        }
        self.parts.push(format!("{n} {what} left out"));
        self
    }

    pub fn sensor(&self) -> Sensor {
        self.sensor
    }

    /// A selection of `sensor` keeping `keep` (row-major), with what this one applied and
    /// `part` ([`crate::region`] cuts one to a region).
    pub(crate) fn cut(&self, sensor: Sensor, keep: Vec<bool>, part: String) -> Self {
        debug_assert_eq!(keep.len(), sensor.pixels());
        let mut parts = self.parts.clone();
        parts.push(part);
        Self {
            sensor,
            keep,
            parts,
        }
    }

    /// Whether pixel (x, y) is kept.
    #[inline]
    pub fn keeps(&self, x: u16, y: u16) -> bool {
        self.keep[y as usize * self.sensor.width as usize + x as usize]
    }

    /// One flag per pixel (row-major): kept.
    pub fn kept_mask(&self) -> &[bool] {
        &self.keep
    }

    /// One flag per pixel (row-major): left out (what the estimators take).
    pub fn excluded(&self) -> Vec<bool> {
        self.keep.iter().map(|&k| !k).collect()
    }

    /// Number of kept pixels.
    pub fn kept(&self) -> usize {
        self.keep.iter().filter(|&&k| k).count()
    }

    /// Whether every pixel is kept (and nothing was applied).
    pub fn is_all(&self) -> bool {
        self.parts.is_empty()
    }

    /// What was applied, for reports (empty: the whole sensor).
    pub fn description(&self) -> String {
        if self.parts.is_empty() {
            "the whole sensor".into()
        } else {
            format!(
                "{} ({} of {} pixels kept)",
                self.parts.join("; "),
                self.kept(),
                self.keep.len()
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn region_mask_and_exclusions_combine() {
        let sensor = Sensor::new(4, 3);
        let roi = Roi::parse("1,0,3,2").unwrap();
        let mut mask = vec![true; 12];
        mask[1] = false; // (1, 0)
        let s = PixelSelection::all(sensor)
            .roi(roi)
            .unwrap()
            .mask(&mask, "m.png")
            .unwrap()
            .without([(2, 1), (0, 0)], "hot pixels");
        // the region keeps (1,0) (2,0) (1,1) (2,1); the mask drops (1,0), the list (2,1)
        assert_eq!(s.kept(), 2);
        assert!(s.keeps(2, 0) && s.keeps(1, 1) && !s.keeps(1, 0) && !s.keeps(3, 0));
        assert!(
            s.description().contains("1 hot pixels left out"),
            "{}",
            s.description()
        );
        assert_eq!(s.excluded().iter().filter(|&&e| e).count(), 10);
    }

    #[test]
    fn bad_regions_and_masks_say_why() {
        let sensor = Sensor::new(240, 180);
        assert!(Roi::parse("0,0,240").unwrap_err().contains("four"));
        assert!(Roi::parse("5,5,5,10").unwrap_err().contains("empty"));
        let roi = Roi::parse("0,0,241,180").unwrap();
        let e = PixelSelection::all(sensor).roi(roi).unwrap_err();
        assert_eq!(e.problem.hints().collect::<Vec<_>>(), [&Hint::Roi(roi)]);
        assert!(
            e.problem.to_string().contains("240x180") && e.fix.to_string().contains("X1 <= 240"),
            "{e}"
        );
        let e = PixelSelection::all(sensor)
            .mask(&[true; 10], "m.npy")
            .unwrap_err();
        assert!(
            e.problem.to_string().contains("10 values") && e.fix.to_string().contains("240x180"),
            "{e}"
        );
        // a mask that keeps nothing, alone or inside a region
        let e = PixelSelection::all(Sensor::new(4, 3))
            .mask(&[false; 12], "zero.png")
            .unwrap_err();
        assert!(
            e.problem.to_string().contains("zero.png keeps no pixel")
                && e.fix.to_string().contains("non-zero"),
            "{e}"
        );
        let mut corner = [false; 12];
        corner[0] = true;
        let e = PixelSelection::all(Sensor::new(4, 3))
            .roi(Roi::parse("2,1,4,3").unwrap())
            .unwrap()
            .mask(&corner, "corner.npy")
            .unwrap_err();
        assert!(
            e.problem
                .to_string()
                .contains("corner.npy keeps no pixel inside the region x 2..4"),
            "{e}"
        );
    }
}
