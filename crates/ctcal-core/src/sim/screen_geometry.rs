//! A screen seen by the camera at an angle: where each stimulus pixel lands on the sensor,
//! and what each sensor pixel sees of the screen.
//!
//! - Geometry: `p = D(H s)`: a homography `H` (the image of a plane under a pinhole camera,
//!   Hartley & Zisserman, *Multiple View Geometry*, 2nd ed. 2004, ch. 2 and 13) from stimulus
//!   pixel coordinates `s` to ideal sensor coordinates, then one coefficient of radial lens
//!   distortion about the sensor centre `c`, `D(u) = c + (u - c) (1 + k1 |u - c|^2 / R^2)`,
//!   with `R` the sensor's half diagonal (the first term of Brown's model, as in Zhang 2000).
//! - Coordinates are continuous pixel coordinates on both sides: pixel `(i, j)` covers
//!   `[i, i + 1) x [j, j + 1)`, its centre at `(i + 0.5, j + 0.5)`.
//! - Resampling is area-correct: a camera images radiance, which the mapping does not
//!   change, so a sensor pixel receives the mean of the screen's light over its footprint on
//!   the screen. The footprint is the quadrilateral of the pixel's four corners mapped back
//!   onto the screen, clipped against every stimulus pixel (Sutherland-Hodgman) for the
//!   overlap areas; the weights are the overlaps over the footprint's area (exact for an
//!   affine footprint, to second order in the pixel size for a projective one). The share
//!   of a footprint off the screen sees the ambient level (the screen's black). The
//!   display's optical blur then acts in sensor pixels ([`camera_dn`]).

use super::display::DisplayModel;
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};

/// A point in continuous pixel coordinates.
pub type Point = (f64, f64);

/// A plane-to-plane projective map, row-major 3 x 3, acting on `(x, y, 1)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Homography(pub [[f64; 3]; 3]);

impl Homography {
    pub const IDENTITY: Homography =
        Homography([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);

    pub fn from_matrix(m: &Matrix3<f64>) -> Self {
        Homography(std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)])))
    }

    pub fn matrix(&self) -> Matrix3<f64> {
        Matrix3::from_fn(|r, c| self.0[r][c])
    }

    /// The image of `(x, y)`; `None` where the point maps to infinity or behind the camera.
    pub fn apply(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let m = &self.0;
        let w = m[2][0] * x + m[2][1] * y + m[2][2];
        if w <= 1e-12 {
            return None;
        }
        Some((
            (m[0][0] * x + m[0][1] * y + m[0][2]) / w,
            (m[1][0] * x + m[1][1] * y + m[1][2]) / w,
        ))
    }

    pub fn inverse(&self) -> Option<Homography> {
        self.matrix()
            .try_inverse()
            .map(|m| Homography::from_matrix(&m).normalized())
    }

    /// The same map scaled so that the bottom-right entry is 1 (or, where it is about 0, so
    /// that the matrix has unit norm with a positive bottom-right entry).
    pub fn normalized(&self) -> Homography {
        let m = self.matrix();
        let scale = if m[(2, 2)].abs() > 1e-12 {
            m[(2, 2)]
        } else {
            m.norm().copysign(m[(2, 2)])
        };
        Homography::from_matrix(&(m / scale))
    }

    /// `other` after `self`.
    pub fn then(&self, other: &Homography) -> Homography {
        Homography::from_matrix(&(other.matrix() * self.matrix())).normalized()
    }

    /// A translation by `(dx, dy)`.
    pub fn translation(dx: f64, dy: f64) -> Homography {
        Homography([[1.0, 0.0, dx], [0.0, 1.0, dy], [0.0, 0.0, 1.0]])
    }
}

/// Where the screen lies on the sensor: `p = D(H s)` (see the module documentation).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScreenGeometry {
    /// Stimulus pixel coordinates to ideal (undistorted) sensor coordinates.
    pub homography: Homography,
    /// Radial distortion about the sensor centre, per squared half diagonal.
    pub k1: f64,
    /// Stimulus size (W, H), screen pixels.
    pub stimulus: (usize, usize),
    /// Sensor size (W, H).
    pub sensor: (usize, usize),
}

impl ScreenGeometry {
    /// Screen pixels on sensor pixels one to one.
    pub fn identity(stimulus: (usize, usize), sensor: (usize, usize)) -> Self {
        Self {
            homography: Homography::IDENTITY,
            k1: 0.0,
            stimulus,
            sensor,
        }
    }

    /// Whether this is the 1:1 mapping of a stimulus of the sensor's size.
    pub fn is_identity(&self) -> bool {
        self.k1 == 0.0 && self.homography == Homography::IDENTITY && self.stimulus == self.sensor
    }

    fn centre_and_radius(&self) -> ((f64, f64), f64) {
        let (w, h) = (self.sensor.0 as f64, self.sensor.1 as f64);
        ((w / 2.0, h / 2.0), 0.5 * w.hypot(h))
    }

    /// Ideal sensor coordinates to distorted ones.
    pub fn distort(&self, u: (f64, f64)) -> (f64, f64) {
        if self.k1 == 0.0 {
            return u;
        }
        let ((cx, cy), r) = self.centre_and_radius();
        let (dx, dy) = (u.0 - cx, u.1 - cy);
        let f = 1.0 + self.k1 * (dx * dx + dy * dy) / (r * r);
        (cx + dx * f, cy + dy * f)
    }

    /// Distorted sensor coordinates to ideal ones (Newton on the radius); `None` where the
    /// distortion folds over (no ideal point maps there).
    pub fn undistort(&self, p: (f64, f64)) -> Option<(f64, f64)> {
        if self.k1 == 0.0 {
            return Some(p);
        }
        let ((cx, cy), r) = self.centre_and_radius();
        let (dx, dy) = ((p.0 - cx) / r, (p.1 - cy) / r);
        let rd = dx.hypot(dy);
        if rd < 1e-15 {
            return Some(p);
        }
        // solve ru (1 + k1 ru^2) = rd for the ideal radius ru
        let mut ru = rd;
        for _ in 0..30 {
            let f = ru * (1.0 + self.k1 * ru * ru) - rd;
            let slope = 1.0 + 3.0 * self.k1 * ru * ru;
            if slope <= 1e-9 {
                return None;
            }
            let step = f / slope;
            ru -= step;
            if step.abs() < 1e-13 {
                break;
            }
        }
        if !(ru.is_finite() && ru >= 0.0 && 1.0 + 3.0 * self.k1 * ru * ru > 0.0) {
            return None;
        }
        let scale = ru / rd;
        Some((cx + dx * scale * r, cy + dy * scale * r))
    }

    /// Where stimulus point `s` lands on the sensor.
    pub fn to_sensor(&self, s: (f64, f64)) -> Option<(f64, f64)> {
        self.homography.apply(s.0, s.1).map(|u| self.distort(u))
    }

    /// The stimulus point sensor point `p` sees.
    pub fn to_stimulus(&self, p: (f64, f64)) -> Option<(f64, f64)> {
        let u = self.undistort(p)?;
        self.homography.inverse()?.apply(u.0, u.1)
    }

    /// A [`Self::to_stimulus`] for many points (the inverse computed once).
    pub fn inverse_map(&self) -> Option<impl Fn(Point) -> Option<Point> + '_> {
        let inverse = self.homography.inverse()?;
        Some(move |p: (f64, f64)| {
            let u = self.undistort(p)?;
            inverse.apply(u.0, u.1)
        })
    }
}

/// The area-weighted resampling of one [`ScreenGeometry`]: per sensor pixel, the stimulus
/// pixels its footprint overlaps and their weights, and the share of it on the screen.
#[derive(Clone, Debug)]
pub struct ScreenWarp {
    sensor: (usize, usize),
    stimulus: (usize, usize),
    /// Per sensor pixel, its range in `entries` (`starts[p]..starts[p + 1]`).
    starts: Vec<u32>,
    entries: Vec<(u32, f32)>,
    coverage: Vec<f32>,
}

/// Footprints larger than this many stimulus pixels (seen nearly edge-on) are sampled on a
/// grid instead of clipped exactly.
const MAX_EXACT_FOOTPRINT: f64 = 4096.0;

impl ScreenWarp {
    pub fn new(geometry: &ScreenGeometry) -> Self {
        let (sw, sh) = geometry.sensor;
        let inverse = geometry.inverse_map();
        // every pixel corner mapped back once
        let corners: Vec<Option<(f64, f64)>> = (0..=sh)
            .flat_map(|y| (0..=sw).map(move |x| (x as f64, y as f64)))
            .map(|p| inverse.as_ref().and_then(|f| f(p)))
            .collect();
        let mut warp = Self {
            sensor: geometry.sensor,
            stimulus: geometry.stimulus,
            starts: Vec::with_capacity(sw * sh + 1),
            entries: Vec::new(),
            coverage: Vec::with_capacity(sw * sh),
        };
        warp.starts.push(0);
        let mut scratch = Clip::default();
        for y in 0..sh {
            for x in 0..sw {
                let at = |dx: usize, dy: usize| corners[(y + dy) * (sw + 1) + x + dx];
                let quad = [at(0, 0), at(1, 0), at(1, 1), at(0, 1)];
                let covered = match quad {
                    [Some(a), Some(b), Some(c), Some(d)] => {
                        warp.add_footprint(&[a, b, c, d], &mut scratch)
                    }
                    _ => 0.0,
                };
                warp.coverage.push(covered as f32);
                warp.starts.push(warp.entries.len() as u32);
            }
        }
        warp
    }

    /// Adds the overlaps of one footprint (weights relative to its area); returns the share
    /// on the screen.
    fn add_footprint(&mut self, quad: &[(f64, f64); 4], scratch: &mut Clip) -> f64 {
        let area = polygon_area(quad);
        if !(area.is_finite() && area > 1e-12) {
            return 0.0;
        }
        let (w, h) = (self.stimulus.0 as f64, self.stimulus.1 as f64);
        let (lo_x, hi_x) = bounds(quad.iter().map(|p| p.0));
        let (lo_y, hi_y) = bounds(quad.iter().map(|p| p.1));
        let (x0, x1) = (lo_x.floor().max(0.0), hi_x.ceil().min(w));
        let (y0, y1) = (lo_y.floor().max(0.0), hi_y.ceil().min(h));
        if x0 >= x1 || y0 >= y1 {
            return 0.0;
        }
        if (x1 - x0) * (y1 - y0) > MAX_EXACT_FOOTPRINT {
            return self.add_sampled(quad);
        }
        let mut covered = 0.0;
        for j in y0 as usize..y1 as usize {
            scratch.strip(quad, 1, j as f64, j as f64 + 1.0);
            if scratch.strip.len() < 3 {
                continue;
            }
            for i in x0 as usize..x1 as usize {
                let overlap = scratch.cell_area(i as f64, i as f64 + 1.0);
                if overlap > 1e-12 {
                    let weight = overlap / area;
                    covered += weight;
                    self.entries
                        .push(((j * self.stimulus.0 + i) as u32, weight as f32));
                }
            }
        }
        covered.min(1.0)
    }

    /// A huge footprint: 32 x 32 samples of the quadrilateral (bilinear in its corners).
    fn add_sampled(&mut self, quad: &[(f64, f64); 4]) -> f64 {
        const N: usize = 32;
        let mut weights = std::collections::BTreeMap::new();
        let (w, h) = self.stimulus;
        for a in 0..N {
            for b in 0..N {
                let (u, v) = ((a as f64 + 0.5) / N as f64, (b as f64 + 0.5) / N as f64);
                let lerp = |p: (f64, f64), q: (f64, f64), t: f64| {
                    (p.0 + (q.0 - p.0) * t, p.1 + (q.1 - p.1) * t)
                };
                let top = lerp(quad[0], quad[1], u);
                let bottom = lerp(quad[3], quad[2], u);
                let s = lerp(top, bottom, v);
                if s.0 >= 0.0 && s.1 >= 0.0 && s.0 < w as f64 && s.1 < h as f64 {
                    let index = s.1 as usize * w + s.0 as usize;
                    *weights.entry(index as u32).or_insert(0.0) += 1.0 / (N * N) as f64;
                }
            }
        }
        let covered: f64 = weights.values().sum();
        self.entries
            .extend(weights.into_iter().map(|(i, w)| (i, w as f32)));
        covered
    }

    pub fn sensor_size(&self) -> (usize, usize) {
        self.sensor
    }

    pub fn stimulus_size(&self) -> (usize, usize) {
        self.stimulus
    }

    /// Per sensor pixel, the share of its area that sees the screen (0..1).
    pub fn coverage(&self) -> &[f32] {
        &self.coverage
    }

    /// Per sensor pixel, whether it sees only the screen.
    pub fn on_screen(&self) -> Vec<bool> {
        self.coverage.iter().map(|&c| c >= 0.9999).collect()
    }

    /// The sensor image of a stimulus-sized image `lit` (any linear quantity, e.g. camera
    /// DN), with `ambient` where the sensor sees beside the screen.
    pub fn apply(&self, lit: &[f32], ambient: f32) -> Vec<f32> {
        debug_assert_eq!(lit.len(), self.stimulus.0 * self.stimulus.1);
        (0..self.coverage.len())
            .map(|p| self.sensor_value(p, |i| lit[i], ambient))
            .collect()
    }

    /// The stimulus pixels sensor pixel `p`'s footprint overlaps, with their weights.
    pub(super) fn footprint(&self, p: usize) -> &[(u32, f32)] {
        &self.entries[self.starts[p] as usize..self.starts[p + 1] as usize]
    }

    /// Sensor pixel `p`'s value in [`Self::apply`], the stimulus pixel `i` at `lit(i)`: every
    /// caller sums the same terms in the same order, so the same value has the same bits.
    #[inline(always)]
    pub(super) fn sensor_value(&self, p: usize, lit: impl Fn(usize) -> f32, ambient: f32) -> f32 {
        let on: f32 = self
            .footprint(p)
            .iter()
            .map(|&(i, w)| w * lit(i as usize))
            .sum();
        on + (1.0 - self.coverage[p]).max(0.0) * ambient
    }
}

/// The camera DN a screen frame (screen DN, stimulus-sized) makes on the sensor: the
/// display's luminance per screen pixel, resampled through the warp (the screen's black
/// beside it), then the display's optical blur in sensor pixels.
pub fn camera_dn(model: &DisplayModel, warp: &ScreenWarp, screen: &[f32]) -> Vec<f32> {
    let lit = model.lit(screen);
    let (w, h) = warp.sensor_size();
    model.blur(warp.apply(&lit, model.luminance_dn(0.0)), w, h)
}

fn bounds(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    })
}

/// Shoelace area of a simple polygon (absolute).
fn polygon_area(points: &[(f64, f64)]) -> f64 {
    let n = points.len();
    let twice: f64 = (0..n)
        .map(|i| {
            let (a, b) = (points[i], points[(i + 1) % n]);
            a.0 * b.1 - b.0 * a.1
        })
        .sum();
    0.5 * twice.abs()
}

/// Sutherland-Hodgman clipping of a polygon to a slab `lo <= coordinate < hi` (axis 0: x,
/// 1: y).
fn clip_slab(input: &[(f64, f64)], axis: usize, lo: f64, hi: f64, out: &mut Vec<(f64, f64)>) {
    let mut half = Vec::with_capacity(input.len() + 2);
    clip_half(input, axis, lo, true, &mut half);
    out.clear();
    clip_half(&half, axis, hi, false, out);
}

/// Keeps the part of `input` with coordinate `>= bound` (`above`) or `<= bound`.
fn clip_half(
    input: &[(f64, f64)],
    axis: usize,
    bound: f64,
    above: bool,
    out: &mut Vec<(f64, f64)>,
) {
    let coordinate = |p: &(f64, f64)| if axis == 0 { p.0 } else { p.1 };
    let inside = |p: &(f64, f64)| {
        if above {
            coordinate(p) >= bound
        } else {
            coordinate(p) <= bound
        }
    };
    let n = input.len();
    for i in 0..n {
        let (a, b) = (input[i], input[(i + 1) % n]);
        let (a_in, b_in) = (inside(&a), inside(&b));
        if a_in {
            out.push(a);
        }
        if a_in != b_in {
            let t = (bound - coordinate(&a)) / (coordinate(&b) - coordinate(&a));
            out.push((a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t));
        }
    }
}

/// Scratch space for clipping one footprint row by row.
#[derive(Default)]
struct Clip {
    strip: Vec<(f64, f64)>,
    cell: Vec<(f64, f64)>,
}

impl Clip {
    /// The footprint's part in the row slab `[lo, hi)` of `axis`.
    fn strip(&mut self, quad: &[(f64, f64); 4], axis: usize, lo: f64, hi: f64) {
        clip_slab(quad, axis, lo, hi, &mut self.strip);
    }

    /// The area of the current strip inside the column slab `[lo, hi)`.
    fn cell_area(&mut self, lo: f64, hi: f64) -> f64 {
        let strip = std::mem::take(&mut self.strip);
        clip_slab(&strip, 0, lo, hi, &mut self.cell);
        self.strip = strip;
        if self.cell.len() < 3 {
            0.0
        } else {
            polygon_area(&self.cell)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geometry(h: Homography, stimulus: (usize, usize), sensor: (usize, usize)) -> ScreenGeometry {
        ScreenGeometry {
            homography: h,
            k1: 0.0,
            stimulus,
            sensor,
        }
    }

    fn scale(s: f64) -> Homography {
        Homography([[s, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, 1.0]])
    }

    #[test]
    fn identity_copies_every_pixel() {
        let warp = ScreenWarp::new(&ScreenGeometry::identity((5, 4), (5, 4)));
        let lit: Vec<f32> = (0..20).map(|v| v as f32).collect();
        assert_eq!(warp.apply(&lit, 99.0), lit);
        assert!(warp.on_screen().iter().all(|&o| o));
    }

    #[test]
    fn a_half_pixel_shift_averages_neighbours() {
        let warp = ScreenWarp::new(&geometry(Homography::translation(0.5, 0.0), (4, 1), (4, 1)));
        let out = warp.apply(&[0.0, 10.0, 20.0, 30.0], 100.0);
        // sensor pixel 0 sees half of stimulus pixel 0 and half off the screen
        assert!((out[0] - 50.0).abs() < 1e-4, "{out:?}");
        assert!(
            (out[1] - 5.0).abs() < 1e-4 && (out[3] - 25.0).abs() < 1e-4,
            "{out:?}"
        );
    }

    #[test]
    fn a_smaller_screen_averages_blocks_and_a_larger_one_repeats_pixels() {
        let lit: Vec<f32> = (0..16).map(|v| v as f32).collect();
        let half = ScreenWarp::new(&geometry(scale(0.5), (4, 4), (2, 2)));
        assert_eq!(half.apply(&lit, 0.0), vec![2.5, 4.5, 10.5, 12.5]);
        let double = ScreenWarp::new(&geometry(scale(2.0), (4, 4), (8, 8)));
        let out = double.apply(&lit, 0.0);
        assert_eq!(out[0], 0.0);
        assert_eq!(out[8 + 3], 1.0);
        assert_eq!(out[7 * 8 + 7], 15.0);
    }

    #[test]
    fn a_perspective_warp_keeps_the_light_of_a_flat_screen() {
        // a flat screen stays flat wherever it is fully seen, whatever the angle
        let h = Homography([[0.9, 0.1, 20.0], [-0.05, 0.8, 15.0], [0.001, 0.0004, 1.0]]);
        let warp = ScreenWarp::new(&geometry(h, (60, 40), (100, 80)));
        let out = warp.apply(&[7.0; 2400], 0.0);
        for (p, &c) in warp.coverage().iter().enumerate() {
            assert!((out[p] - 7.0 * c).abs() < 1e-3, "{p}");
        }
        let seen = warp.coverage().iter().filter(|&&c| c > 0.999).count();
        assert!(seen > 1000, "{seen}");
    }

    #[test]
    fn distortion_inverts_and_points_round_trip() {
        let h = Homography([[0.9, 0.1, 20.0], [-0.05, 0.8, 15.0], [0.001, 0.0004, 1.0]]);
        let g = ScreenGeometry {
            homography: h,
            k1: -0.08,
            stimulus: (60, 40),
            sensor: (100, 80),
        };
        for s in [(0.0, 0.0), (30.0, 20.0), (59.0, 39.5)] {
            let p = g.to_sensor(s).unwrap();
            let back = g.to_stimulus(p).unwrap();
            assert!(
                (back.0 - s.0).abs() < 1e-9 && (back.1 - s.1).abs() < 1e-9,
                "{s:?}"
            );
        }
    }
}
