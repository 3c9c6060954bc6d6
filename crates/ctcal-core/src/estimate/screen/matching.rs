//! Point correspondences between the stimulus and the sensor by block matching (the
//! normalised cross-correlation of small patches, Lewis 1995 "Fast normalized
//! cross-correlation"; sub-pixel peak by a parabola through the neighbours on each axis):
//! the events of every window are compared with the stimulus predicted on the sensor under
//! the current geometry; where a patch's events are best explained `d` pixels away from
//! its prediction, the stimulus point the geometry puts at the patch centre is seen at the
//! centre plus `d`.

use super::dlt::Pair;
use super::images::Stack;
use crate::sim::screen_geometry::ScreenGeometry;
use rayon::prelude::*;

/// Half the side of a patch, pixels.
const HALF: usize = 8;
/// Spacing of the patch centres, pixels.
const STEP: usize = 8;
/// Correlation below which a match is not trusted.
const MIN_SCORE: f64 = 0.5;

/// The zero-mean normalised correlation of two equally long sample lists.
fn ncc(a: &[f32], b: &[f32]) -> f64 {
    let n = a.len() as f64;
    let (sa, sb) = (
        a.iter().map(|&v| v as f64).sum::<f64>(),
        b.iter().map(|&v| v as f64).sum::<f64>(),
    );
    let (mut saa, mut sbb, mut sab) = (0.0, 0.0, 0.0);
    for (&x, &y) in a.iter().zip(b) {
        let (x, y) = (x as f64, y as f64);
        saa += x * x;
        sbb += y * y;
        sab += x * y;
    }
    let var = (saa - sa * sa / n) * (sbb - sb * sb / n);
    if var <= 1e-12 {
        0.0
    } else {
        (sab - sa * sb / n) / var.sqrt()
    }
}

/// The patch of every window of `images` centred on pixel `(cx, cy)`, concatenated.
fn patch(images: &[Vec<f32>], width: usize, cx: usize, cy: usize) -> Vec<f32> {
    let mut out = Vec::with_capacity(images.len() * (2 * HALF + 1).pow(2));
    for image in images {
        for y in cy - HALF..=cy + HALF {
            out.extend_from_slice(&image[y * width + cx - HALF..=y * width + cx + HALF]);
        }
    }
    out
}

/// The score of the events' patch at `(cx, cy)` against the predicted patches.
fn score(real: &Stack, predicted: &(Vec<f32>, Vec<f32>), cx: usize, cy: usize) -> f64 {
    let signed = ncc(&predicted.0, &patch(&real.signed, real.width, cx, cy));
    let activity = ncc(&predicted.1, &patch(&real.activity, real.width, cx, cy));
    0.5 * (signed + activity)
}

/// The vertex of the parabola through (-1, a), (0, b), (1, c); `None` unless a peak.
fn vertex(a: f64, b: f64, c: f64) -> Option<f64> {
    let curvature = a - 2.0 * b + c;
    (curvature < 0.0).then(|| 0.5 * (a - c) / curvature)
}

/// The correspondence of the patch centred on pixel `(cx, cy)`, searching `radius` pixels.
fn one(
    real: &Stack,
    predicted: &Stack,
    g: &ScreenGeometry,
    (cx, cy): (usize, usize),
    radius: usize,
) -> Option<Pair> {
    let (w, h) = (real.width, real.height);
    let model = (
        patch(&predicted.signed, w, cx, cy),
        patch(&predicted.activity, w, cx, cy),
    );
    let r = radius as isize;
    let inside = |x: isize, y: isize| {
        x - HALF as isize >= 0
            && y - HALF as isize >= 0
            && x + (HALF as isize) < w as isize
            && y + (HALF as isize) < h as isize
    };
    let mut best = (f64::NEG_INFINITY, 0isize, 0isize);
    let side = 2 * r + 1;
    let mut scores = vec![f64::NAN; (side * side) as usize];
    for dy in -r..=r {
        for dx in -r..=r {
            let (x, y) = (cx as isize + dx, cy as isize + dy);
            if !inside(x, y) {
                continue;
            }
            let s = score(real, &model, x as usize, y as usize);
            scores[((dy + r) * side + dx + r) as usize] = s;
            if s > best.0 {
                best = (s, dx, dy);
            }
        }
    }
    let (s, dx, dy) = best;
    if s < MIN_SCORE || dx.abs() == r || dy.abs() == r {
        return None;
    }
    let at = |dx: isize, dy: isize| scores[((dy + r) * side + dx + r) as usize];
    let sub_x = vertex(at(dx - 1, dy), s, at(dx + 1, dy))?;
    let sub_y = vertex(at(dx, dy - 1), s, at(dx, dy + 1))?;
    let centre = (cx as f64 + 0.5, cy as f64 + 0.5);
    let seen = (centre.0 + dx as f64 + sub_x, centre.1 + dy as f64 + sub_y);
    Some((g.to_stimulus(centre)?, seen))
}

/// Correspondences from every patch that sees only the screen (`on_screen`), whose
/// prediction has structure and whose events are many enough.
pub fn correspondences(
    real: &Stack,
    predicted: &Stack,
    on_screen: &[bool],
    g: &ScreenGeometry,
    radius: usize,
) -> Vec<Pair> {
    let (w, h) = (real.width, real.height);
    let margin = HALF + radius + 1;
    if w <= 2 * margin || h <= 2 * margin {
        return Vec::new();
    }
    let centres: Vec<(usize, usize)> = (margin..h - margin)
        .step_by(STEP)
        .flat_map(|y| (margin..w - margin).step_by(STEP).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            (y - HALF..=y + HALF).all(|yy| (x - HALF..=x + HALF).all(|xx| on_screen[yy * w + xx]))
        })
        .filter(|&(x, y)| {
            let events: f32 = patch(&real.activity, w, x, y).iter().sum();
            let model = patch(&predicted.activity, w, x, y);
            let (lo, hi) = model
                .iter()
                .fold((f32::INFINITY, f32::NEG_INFINITY), |a, &v| {
                    (a.0.min(v), a.1.max(v))
                });
            events >= 20.0 && hi - lo > 0.05
        })
        .collect();
    centres
        .par_iter()
        .filter_map(|&c| one(real, predicted, g, c, radius))
        .collect()
}
