//! Where the screen roughly is: an exhaustive search over similarities (scale, rotation,
//! translation) of the correlation between the events' activity and the stimulus's
//! predicted activity, on block-averaged images (a coarse-to-fine template search, as in
//! Szeliski, *Computer Vision: Algorithms and Applications*, 2nd ed. 2022, Sec. 9.1.1 on
//! hierarchical motion estimation). The score is the normalised cross-correlation over the
//! whole sensor (the prediction zero beside the screen), averaged over the windows, so a
//! screen placed too small or too large is penalised by the events it leaves unexplained.

use super::images::Stack;
use crate::sim::screen_geometry::Homography;
use rayon::prelude::*;

/// A similarity from stimulus to sensor: `p = s R(theta) (x - c) + t`, `c` the stimulus
/// centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub scale: f64,
    pub theta: f64,
    pub t: (f64, f64),
}

impl Pose {
    fn rotate(&self, v: (f64, f64), sign: f64) -> (f64, f64) {
        let (s, c) = (sign * self.theta).sin_cos();
        (c * v.0 - s * v.1, s * v.0 + c * v.1)
    }

    pub fn homography(&self, stimulus: (usize, usize)) -> Homography {
        let (c, s) = (self.theta.cos() * self.scale, self.theta.sin() * self.scale);
        let (cx, cy) = (stimulus.0 as f64 / 2.0, stimulus.1 as f64 / 2.0);
        Homography([
            [c, -s, self.t.0 - (c * cx - s * cy)],
            [s, c, self.t.1 - (s * cx + c * cy)],
            [0.0, 0.0, 1.0],
        ])
    }
}

/// The activity images block-summed by `factor`.
fn reduce(
    images: &[Vec<f32>],
    size: (usize, usize),
    factor: usize,
) -> (Vec<Vec<f32>>, usize, usize) {
    let (w, h) = (size.0 / factor, size.1 / factor);
    let reduced = images
        .iter()
        .map(|image| {
            let mut out = vec![0f32; w * h];
            for y in 0..h * factor {
                for x in 0..w * factor {
                    out[(y / factor) * w + x / factor] += image[y * size.0 + x];
                }
            }
            out
        })
        .collect();
    (reduced, w, h)
}

/// The predicted activity of every window, as the sensor would see it at `pose` (up to a
/// translation), on a grid of `factor` sensor pixels: the template, its size, and the
/// sensor position (full resolution) of its top-left corner relative to the translation.
struct Template {
    images: Vec<Vec<f32>>,
    width: usize,
    height: usize,
    origin: (f64, f64),
}

/// The [`Template`] of `predicted` at `pose` on a grid of `factor` sensor pixels; `None`
/// where it would be empty or larger than 2^22 pixels.
fn template(predicted: &Stack, pose: &Pose, factor: usize) -> Option<Template> {
    let (lo, hi) = mapped_bounds(predicted, pose);
    let f = factor as f64;
    let (width, height) = (
        ((hi.0 - lo.0) / f).ceil() as usize,
        ((hi.1 - lo.1) / f).ceil() as usize,
    );
    if width == 0 || height == 0 || width * height > 1 << 22 {
        return None;
    }
    Some(Template {
        images: sampled(predicted, pose, lo, f, (width, height)),
        width,
        height,
        origin: lo,
    })
}

/// The bounding box (lowest and highest corner) of the stimulus mapped by `pose`, relative
/// to its translation.
fn mapped_bounds(predicted: &Stack, pose: &Pose) -> ((f64, f64), (f64, f64)) {
    let (sw, sh) = (predicted.width as f64, predicted.height as f64);
    let centre = (sw / 2.0, sh / 2.0);
    let mapped: Vec<(f64, f64)> = [(0.0, 0.0), (sw, 0.0), (sw, sh), (0.0, sh)]
        .iter()
        .map(|&(x, y)| {
            let r = pose.rotate((x - centre.0, y - centre.1), 1.0);
            (pose.scale * r.0, pose.scale * r.1)
        })
        .collect();
    let lo = mapped.iter().fold((f64::INFINITY, f64::INFINITY), |a, p| {
        (a.0.min(p.0), a.1.min(p.1))
    });
    let hi = mapped
        .iter()
        .fold((f64::NEG_INFINITY, f64::NEG_INFINITY), |a, p| {
            (a.0.max(p.0), a.1.max(p.1))
        });
    (lo, hi)
}

/// The template's images: each of its `width x height` pixels (`f` sensor pixels a side,
/// the first at `lo`) sums k x k samples of every window's predicted activity, each at the
/// nearest stimulus pixel (k from the pixel's size in stimulus pixels, 1 to 6).
fn sampled(
    predicted: &Stack,
    pose: &Pose,
    lo: (f64, f64),
    f: f64,
    (width, height): (usize, usize),
) -> Vec<Vec<f32>> {
    let (sw, sh) = (predicted.width as f64, predicted.height as f64);
    let centre = (sw / 2.0, sh / 2.0);
    // k x k samples per template pixel, nearest stimulus pixel
    let k = ((f / pose.scale).ceil() as usize).clamp(1, 6);
    let mut images = vec![vec![0f32; width * height]; predicted.windows()];
    for v in 0..height {
        for u in 0..width {
            for a in 0..k {
                for b in 0..k {
                    let q = (
                        lo.0 + f * (u as f64 + (a as f64 + 0.5) / k as f64),
                        lo.1 + f * (v as f64 + (b as f64 + 0.5) / k as f64),
                    );
                    let r = pose.rotate(q, -1.0);
                    let (x, y) = (centre.0 + r.0 / pose.scale, centre.1 + r.1 / pose.scale);
                    if x < 0.0 || y < 0.0 || x >= sw || y >= sh {
                        continue;
                    }
                    let p = y as usize * predicted.width + x as usize;
                    for (image, source) in images.iter_mut().zip(&predicted.activity) {
                        image[v * width + u] += source[p];
                    }
                }
            }
        }
    }
    images
}

/// The sensor side at one resolution: block-summed activity with its sums.
struct Level {
    images: Vec<Vec<f32>>,
    width: usize,
    height: usize,
    factor: usize,
    /// Per window: sum and variance (per pixel) of the image.
    moments: Vec<(f64, f64)>,
}

impl Level {
    fn new(real: &Stack, factor: usize) -> Self {
        let (images, width, height) = reduce(&real.activity, (real.width, real.height), factor);
        let n = (width * height) as f64;
        let moments = images
            .iter()
            .map(|im| {
                let sum: f64 = im.iter().map(|&v| v as f64).sum();
                let squares: f64 = im.iter().map(|&v| (v as f64).powi(2)).sum();
                (sum, squares / n - (sum / n).powi(2))
            })
            .collect();
        Self {
            images,
            width,
            height,
            factor,
            moments,
        }
    }

    /// The mean over windows of the correlation of the template placed with its top-left
    /// pixel at `(ox, oy)`; `None` when less than `min_visible` of it is on the sensor.
    fn score(&self, t: &Template, ox: isize, oy: isize, min_visible: f64) -> Option<f64> {
        let x0 = ox.max(0) as usize;
        let y0 = oy.max(0) as usize;
        let x1 = (ox + t.width as isize).min(self.width as isize);
        let y1 = (oy + t.height as isize).min(self.height as isize);
        if x1 <= x0 as isize || y1 <= y0 as isize {
            return None;
        }
        let (x1, y1) = (x1 as usize, y1 as usize);
        let visible = ((x1 - x0) * (y1 - y0)) as f64;
        if visible < min_visible * (t.width * t.height).min(self.width * self.height) as f64 {
            return None;
        }
        let n = (self.width * self.height) as f64;
        let mut total = 0.0;
        let mut used = 0;
        for (w, (image, tpl)) in self.images.iter().zip(&t.images).enumerate() {
            let (sum_d, var_d) = self.moments[w];
            let (mut sp, mut spp, mut spd) = (0.0f64, 0.0f64, 0.0f64);
            for y in y0..y1 {
                let ty = (y as isize - oy) as usize;
                let row = &image[y * self.width..];
                let trow = &tpl[ty * t.width..];
                let (mut a, mut b, mut c) = (0f32, 0f32, 0f32);
                for x in x0..x1 {
                    let p = trow[(x as isize - ox) as usize];
                    a += p;
                    b += p * p;
                    c += p * row[x];
                }
                sp += a as f64;
                spp += b as f64;
                spd += c as f64;
            }
            let var_p = spp / n - (sp / n).powi(2);
            if var_p <= 0.0 || var_d <= 0.0 {
                continue;
            }
            total += (spd / n - sp * sum_d / (n * n)) / (var_p * var_d).sqrt();
            used += 1;
        }
        (used > 0).then(|| total / used as f64)
    }

    /// The best translation of `pose`'s template within `range` level pixels of `around`
    /// (full-resolution translation; `None`: everywhere).
    fn best(
        &self,
        predicted: &Stack,
        pose: &Pose,
        around: Option<(f64, f64)>,
        range: isize,
    ) -> Option<(Pose, f64)> {
        let t = template(predicted, pose, self.factor)?;
        let f = self.factor as f64;
        let ((x_lo, x_hi), (y_lo, y_hi)) = match around {
            // translation = f * o - origin
            Some(c) => {
                let (cx, cy) = (
                    ((c.0 + t.origin.0) / f).round() as isize,
                    ((c.1 + t.origin.1) / f).round() as isize,
                );
                ((cx - range, cx + range), (cy - range, cy + range))
            }
            None => (
                (-(t.width as isize) + 1, self.width as isize - 1),
                (-(t.height as isize) + 1, self.height as isize - 1),
            ),
        };
        let mut best: Option<(Pose, f64)> = None;
        for oy in y_lo..=y_hi {
            for ox in x_lo..=x_hi {
                if let Some(s) = self.score(&t, ox, oy, 0.3)
                    && best.is_none_or(|b| s > b.1)
                {
                    let translation = (f * ox as f64 - t.origin.0, f * oy as f64 - t.origin.1);
                    best = Some((
                        Pose {
                            t: translation,
                            ..*pose
                        },
                        s,
                    ));
                }
            }
        }
        best
    }
}

fn best_of(candidates: Vec<Option<(Pose, f64)>>) -> Option<(Pose, f64)> {
    candidates
        .into_iter()
        .flatten()
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

/// The similarity that best explains the events' activity (`real`, sensor-sized) by the
/// stimulus's (`predicted`, stimulus-sized), with its score (mean correlation).
pub fn search(real: &Stack, predicted: &Stack) -> Option<(Pose, f64)> {
    let (w, h) = (real.width as f64, real.height as f64);
    let fit = (w / predicted.width as f64).min(h / predicted.height as f64);
    // coarse: about 32 blocks across, every scale from 1/2.5 to 2 of the fitting one
    let coarse = Level::new(real, ((w / 32.0).ceil() as usize).max(1));
    let mut poses = Vec::new();
    let mut scale = fit / 2.5;
    while scale <= fit * 2.0 {
        for degrees in [-6.0f64, 0.0, 6.0] {
            poses.push(Pose {
                scale,
                theta: degrees.to_radians(),
                t: (0.0, 0.0),
            });
        }
        scale *= 1.1;
    }
    let found = best_of(
        poses
            .par_iter()
            .map(|p| coarse.best(predicted, p, None, 0))
            .collect(),
    )?;
    // fine: about 96 blocks across, near the coarse pose
    let fine = Level::new(real, ((w / 96.0).ceil() as usize).max(1));
    let mut near = Vec::new();
    for ds in -3..=3 {
        for dt in -2..=2 {
            near.push(Pose {
                scale: found.0.scale * 1.03f64.powi(ds),
                theta: found.0.theta + (dt as f64 * 1.5).to_radians(),
                t: found.0.t,
            });
        }
    }
    let range = (coarse.factor / fine.factor) as isize + 2;
    best_of(
        near.par_iter()
            .map(|p| fine.best(predicted, p, Some(found.0.t), range))
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pose_maps_the_stimulus_centre_to_its_translation() {
        let pose = Pose {
            scale: 0.8,
            theta: 0.1,
            t: (50.0, 40.0),
        };
        let h = pose.homography((100, 60));
        let p = h.apply(50.0, 30.0).unwrap();
        assert!((p.0 - 50.0).abs() < 1e-12 && (p.1 - 40.0).abs() < 1e-12);
        let q = h.apply(60.0, 30.0).unwrap();
        assert!((q.0 - 50.0 - 8.0 * 0.1f64.cos()).abs() < 1e-12);
    }
}
