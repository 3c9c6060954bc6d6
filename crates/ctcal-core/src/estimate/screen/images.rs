//! The images the screen registration compares, per time window of the stimulus: what the
//! events show (ON minus OFF counts, and ON plus OFF) and what the stimulus predicts (the
//! change of log intensity over the window, and the sum of its absolute changes at every
//! refresh, which an ideal pixel turns into `1 / C` times as many events).

use super::register::Through;
use crate::events::{EventChunk, Frame, TimeUs};
use crate::sim::display::DisplayModel;
use crate::sim::screen_geometry::{ScreenWarp, camera_dn};

/// Signed and unsigned images of several windows, one size.
#[derive(Clone, Debug)]
pub struct Stack {
    pub width: usize,
    pub height: usize,
    /// Per window: ON - OFF (events) or the log change over the window (prediction).
    pub signed: Vec<Vec<f32>>,
    /// Per window: ON + OFF (events) or the summed absolute log changes (prediction).
    pub activity: Vec<Vec<f32>>,
}

impl Stack {
    fn zeros(width: usize, height: usize, windows: usize) -> Self {
        Self {
            width,
            height,
            signed: vec![vec![0.0; width * height]; windows],
            activity: vec![vec![0.0; width * height]; windows],
        }
    }

    pub fn windows(&self) -> usize {
        self.signed.len()
    }
}

/// The stimulus's frame transitions cut into about `count` windows of equal length:
/// window `w` holds the transitions into frames `bounds[w].0 + 1 ..= bounds[w].1`.
pub fn windows(frames: usize, count: usize) -> Vec<(usize, usize)> {
    let transitions = frames.saturating_sub(1);
    let count = count.clamp(1, transitions.max(1));
    (0..count)
        .map(|w| (w * transitions / count, (w + 1) * transitions / count))
        .filter(|(a, b)| b > a)
        .collect()
}

/// The events of each window: those from half a refresh before its first transition to
/// half a refresh after its last (refresh `k` at `offset + stimulus[k].t`).
pub fn of_events(
    events: &EventChunk,
    size: (usize, usize),
    excluded: &[bool],
    stimulus: &[Frame],
    bounds: &[(usize, usize)],
    offset_us: TimeUs,
    period_us: f64,
) -> Stack {
    let mut stack = Stack::zeros(size.0, size.1, bounds.len());
    let half = (0.5 * period_us).round() as TimeUs;
    for (w, &(a, b)) in bounds.iter().enumerate() {
        let start = offset_us + stimulus[a + 1].t - half;
        let end = offset_us + stimulus[b].t + half;
        let from = events.t.partition_point(|&t| t < start);
        let to = events.t.partition_point(|&t| t < end);
        for i in from..to {
            let p = events.y[i] as usize * size.0 + events.x[i] as usize;
            if p >= excluded.len() || excluded[p] {
                continue;
            }
            stack.signed[w][p] += if events.on[i] { 1.0 } else { -1.0 };
            stack.activity[w][p] += 1.0;
        }
    }
    stack
}

/// The prediction of a stimulus through a display and the sensor's log response: in
/// stimulus coordinates (no warp, no blur) or on the sensor through `warp` (with the
/// display's blur).
pub fn predicted(
    stimulus: &[Frame],
    bounds: &[(usize, usize)],
    through: Through,
    warp: Option<&ScreenWarp>,
) -> Stack {
    let model = DisplayModel::new(through.display);
    let log = through.log;
    let (w, h) = match warp {
        Some(warp) => warp.sensor_size(),
        None => (stimulus[0].width as usize, stimulus[0].height as usize),
    };
    let image = |k: usize| -> Vec<f32> {
        let dn: Vec<f32> = stimulus[k].pixels.iter().map(|&p| p as f32).collect();
        let camera = match warp {
            Some(warp) => camera_dn(&model, warp, &dn),
            None => model.lit(&dn),
        };
        camera.into_iter().map(|v| log.apply(v)).collect()
    };
    let mut stack = Stack::zeros(w, h, bounds.len());
    for (window, &(a, b)) in bounds.iter().enumerate() {
        let first = image(a);
        let mut previous = first.clone();
        for k in a + 1..=b {
            let current = image(k);
            for (p, value) in stack.activity[window].iter_mut().enumerate() {
                *value += (current[p] - previous[p]).abs();
            }
            previous = current;
        }
        for (p, value) in stack.signed[window].iter_mut().enumerate() {
            *value = previous[p] - first[p];
        }
    }
    stack
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_cover_every_transition_once() {
        let w = windows(75, 8);
        assert_eq!(w.len(), 8);
        assert_eq!(w[0].0, 0);
        assert_eq!(w[7].1, 74);
        assert!(w.windows(2).all(|p| p[0].1 == p[1].0));
        assert_eq!(windows(3, 8), vec![(0, 1), (1, 2)]);
    }
}
