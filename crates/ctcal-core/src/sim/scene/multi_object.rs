//! Multi-object 2D scenes (Stoffregen et al. 2020, after ESIM's "multi-object 2D" renderer):
//! a textured background and 0-30 textured foreground objects, each moving along a random
//! affine trajectory (translation at a drawn speed through a random point of the image,
//! constant rotation rate, scale changing linearly), occluding each other in depth order.
//!
//! Speeds, rotation rates and scales are drawn uniformly from the ranges in the scene file;
//! `calib/scenes/multi_object_{slow,medium,fast,variety}.toml` hold the four speed classes of
//! the paper's scene generator (esim_config_generator). Textures are procedural
//! ([`super::canvas`]) or grey images from `textures_dir`. Object edges are anti-aliased by
//! pixel coverage so that edges move smoothly rather than in whole-pixel jumps.

use super::canvas::{Canvas, TextureParams};
use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Parameters of a multi-object scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MultiObjectScene {
    /// Number of foreground objects, inclusive range.
    pub objects: [u32; 2],
    pub background_velocity_px_s: [f64; 2],
    pub background_angular_velocity_deg_s: [f64; 2],
    pub background_scale: [f64; 2],
    pub object_velocity_px_s: [f64; 2],
    pub object_angular_velocity_deg_s: [f64; 2],
    pub object_scale: [f64; 2],
    /// Object radius before scaling, pixels.
    #[serde(default = "default_object_size")]
    pub object_size_px: [f64; 2],
    /// A folder of grey PNG images to use as textures instead of procedural ones.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub textures_dir: Option<PathBuf>,
    /// The background texture (procedural).
    #[serde(default)]
    pub background_texture: TextureParams,
}

/// The most foreground objects a scene may have.
pub const MAX_OBJECTS: u32 = 1000;

fn default_object_size() -> [f64; 2] {
    [12.0, 40.0]
}

#[derive(Clone, Debug)]
enum Shape {
    Ellipse {
        rx: f64,
        ry: f64,
    },
    Rectangle {
        hx: f64,
        hy: f64,
    },
    /// A regular polygon; `normals` holds `(sin, cos)` of its edges' normal angles
    /// `TAU k / sides`, computed once ([`Shape::polygon`]) instead of at every pixel.
    Polygon {
        sides: u32,
        apothem: f64,
        normals: Vec<(f64, f64)>,
    },
}

impl Shape {
    fn polygon(sides: u32, apothem: f64) -> Self {
        let step = std::f64::consts::TAU / sides as f64;
        let normals = (0..sides).map(|k| (step * k as f64).sin_cos()).collect();
        Shape::Polygon {
            sides,
            apothem,
            normals,
        }
    }

    /// Approximate signed distance (negative inside) in unscaled object units.
    #[cfg(test)]
    fn distance(&self, qx: f64, qy: f64) -> f64 {
        let mut d = [0.0];
        self.distances(&[qx], &[qy], &mut d);
        d[0]
    }

    /// [`Self::distance`] of the points `(qx[k], qy[k])` into `d[k]`: one shape's loop over
    /// a row, so that it vectorises (a polygon takes its edges one at a time over the row,
    /// each point's maximum in the same order as edge by edge).
    #[inline(always)]
    fn distances(&self, qx: &[f64], qy: &[f64], d: &mut [f64]) {
        let points = d.iter_mut().zip(qx).zip(qy);
        match self {
            &Shape::Ellipse { rx, ry } => {
                for ((d, qx), qy) in points {
                    *d = ((qx / rx).hypot(qy / ry) - 1.0) * rx.min(ry);
                }
            }
            &Shape::Rectangle { hx, hy } => {
                for ((d, qx), qy) in points {
                    *d = (qx.abs() - hx).max(qy.abs() - hy);
                }
            }
            Shape::Polygon {
                apothem, normals, ..
            } => {
                d.fill(f64::NEG_INFINITY);
                for &(s, c) in normals {
                    for ((d, qx), qy) in d.iter_mut().zip(qx).zip(qy) {
                        *d = d.max(qx * c + qy * s - apothem);
                    }
                }
            }
        }
    }

    fn radius(&self) -> f64 {
        match *self {
            Shape::Ellipse { rx, ry } => rx.max(ry),
            Shape::Rectangle { hx, hy } => hx.hypot(hy),
            Shape::Polygon { sides, apothem, .. } => {
                apothem / (std::f64::consts::PI / sides as f64).cos()
            }
        }
    }
}

/// A drawn trajectory: position through a point of the image, rotation, linear scale.
#[derive(Clone, Debug)]
struct Trajectory {
    point: [f64; 2],
    velocity: [f64; 2],
    pass_time: f64,
    angle0: f64,
    angular_velocity: f64,
    scale0: f64,
    scale1: f64,
    duration: f64,
}

impl Trajectory {
    fn draw(
        rng: &mut impl Rng,
        width: usize,
        height: usize,
        duration: f64,
        speed: [f64; 2],
        angular: [f64; 2],
        scale: [f64; 2],
    ) -> Self {
        let uniform = |rng: &mut dyn FnMut() -> f64, [lo, hi]: [f64; 2]| lo + (hi - lo) * rng();
        let mut r = || rng.random::<f64>();
        let point = [
            width as f64 * (0.5 + 0.9 * (r() - 0.5)),
            height as f64 * (0.5 + 0.9 * (r() - 0.5)),
        ];
        let speed = uniform(&mut r, speed);
        let direction = std::f64::consts::TAU * r();
        let angular_velocity =
            uniform(&mut r, angular).to_radians() * if r() < 0.5 { -1.0 } else { 1.0 };
        Self {
            point,
            velocity: [speed * direction.cos(), speed * direction.sin()],
            pass_time: duration * r(),
            angle0: std::f64::consts::TAU * r(),
            angular_velocity,
            scale0: uniform(&mut r, scale),
            scale1: uniform(&mut r, scale),
            duration,
        }
    }

    /// Centre, angle and scale at time t.
    fn pose(&self, t: f64) -> ([f64; 2], f64, f64) {
        let dt = t - self.pass_time;
        let f = if self.duration > 0.0 {
            (t / self.duration).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (
            [
                self.point[0] + self.velocity[0] * dt,
                self.point[1] + self.velocity[1] * dt,
            ],
            self.angle0 + self.angular_velocity * t,
            self.scale0 + (self.scale1 - self.scale0) * f,
        )
    }

    fn max_speed(&self, radius: f64) -> f64 {
        self.velocity[0].hypot(self.velocity[1])
            + self.angular_velocity.abs() * radius * self.scale0.max(self.scale1)
    }
}

#[derive(Clone, Debug)]
struct Object {
    shape: Shape,
    texture: usize,
    trajectory: Trajectory,
}

/// A realised multi-object scene.
#[derive(Clone, Debug)]
pub struct MultiObjectWorld {
    textures: Vec<Canvas>,
    background: Trajectory,
    objects: Vec<Object>,
}

impl MultiObjectScene {
    /// Draws the scene (objects, textures, trajectories) from `rng`.
    pub fn realise(
        &self,
        width: usize,
        height: usize,
        duration: f64,
        images: Vec<Canvas>,
        rng: &mut impl Rng,
    ) -> MultiObjectWorld {
        let count = rng.random_range(self.objects[0]..=self.objects[1].max(self.objects[0]));
        let mut textures = Vec::new();
        let background_texture = if images.is_empty() {
            Canvas::generate(&self.background_texture, rng)
        } else {
            images[rng.random_range(0..images.len())].clone()
        };
        textures.push(background_texture);
        let background = Trajectory::draw(
            rng,
            width,
            height,
            duration,
            self.background_velocity_px_s,
            self.background_angular_velocity_deg_s,
            self.background_scale,
        );
        let mut objects = Vec::new();
        for _ in 0..count {
            let size = self.object_size_px[0]
                + (self.object_size_px[1] - self.object_size_px[0]) * rng.random::<f64>();
            let aspect = 0.5 + rng.random::<f64>() * 0.5;
            let shape = match rng.random_range(0..3u32) {
                0 => Shape::Ellipse {
                    rx: size,
                    ry: size * aspect,
                },
                1 => Shape::Rectangle {
                    hx: size,
                    hy: size * aspect,
                },
                _ => Shape::polygon(rng.random_range(3..=8), size),
            };
            let texture = if images.is_empty() {
                let params = TextureParams {
                    canvas_px: 128,
                    mean_dn: 20.0 + 200.0 * rng.random::<f64>(),
                    log_std: 0.15 + 0.45 * rng.random::<f64>(),
                    min_dn: 5.0,
                    max_dn: 250.0,
                    spectrum_beta: 0.8 + 0.6 * rng.random::<f64>(),
                    blur_px: 1.0,
                };
                textures.push(Canvas::generate(&params, rng));
                textures.len() - 1
            } else {
                textures.push(images[rng.random_range(0..images.len())].clone());
                textures.len() - 1
            };
            let trajectory = Trajectory::draw(
                rng,
                width,
                height,
                duration,
                self.object_velocity_px_s,
                self.object_angular_velocity_deg_s,
                self.object_scale,
            );
            objects.push(Object {
                shape,
                texture,
                trajectory,
            });
        }
        MultiObjectWorld {
            textures,
            background,
            objects,
        }
    }
}

impl MultiObjectWorld {
    /// Fastest image motion, px/s.
    pub fn max_speed_px_s(&self, width: usize, height: usize) -> f64 {
        let half_diagonal = (width as f64).hypot(height as f64) / 2.0;
        self.objects
            .iter()
            .map(|o| o.trajectory.max_speed(o.shape.radius()))
            .fold(self.background.max_speed(half_diagonal), f64::max)
    }

    pub fn object_count(&self) -> usize {
        self.objects.len()
    }

    /// Renders rows `rows` into `out` (those rows only): the background, then every object
    /// over it in depth order. Coordinates are computed a row at a time and the textures
    /// sampled along the row at once ([`Canvas::sample_many`]).
    pub fn render(&self, width: usize, rows: std::ops::Range<usize>, t: f64, out: &mut [f32]) {
        let mut row = RowBuffers::new(width);
        // background: the image is the texture seen through the inverse of its motion
        let (centre, angle, scale) = self.background.pose(t);
        let (s, c) = angle.sin_cos();
        for (y, out) in rows.clone().zip(out.chunks_exact_mut(width)) {
            let dy = y as f64 - centre[1];
            for (x, (qx, qy)) in row.xs.iter_mut().zip(&mut row.ys).enumerate() {
                let dx = x as f64 - centre[0];
                (*qx, *qy) = ((c * dx + s * dy) / scale, (-s * dx + c * dy) / scale);
            }
            self.textures[0].sample_many(&row.xs, &row.ys, out);
        }
        for object in &self.objects {
            self.render_object(object, width, rows.clone(), t, &mut row, out);
        }
    }

    /// Blends one object over rows `rows` of `out`, by its pixel coverage.
    fn render_object(
        &self,
        object: &Object,
        width: usize,
        rows: std::ops::Range<usize>,
        t: f64,
        row: &mut RowBuffers,
        out: &mut [f32],
    ) {
        let (centre, angle, scale) = object.trajectory.pose(t);
        let reach = object.shape.radius() * scale + 1.0;
        let (x_lo, x_hi) = (
            (centre[0] - reach).floor().max(0.0),
            (centre[0] + reach).ceil().min(width as f64 - 1.0),
        );
        let (y_lo, y_hi) = (
            (centre[1] - reach).floor().max(rows.start as f64),
            (centre[1] + reach).ceil().min(rows.end as f64 - 1.0),
        );
        if x_lo > x_hi || y_lo > y_hi {
            return;
        }
        let (s, c) = angle.sin_cos();
        let texture = &self.textures[object.texture];
        let (x_lo, span) = (x_lo as usize, (x_hi - x_lo) as usize + 1);
        for y in y_lo as usize..=y_hi as usize {
            let dy = y as f64 - centre[1];
            let pose = Pose {
                centre,
                sin: s,
                cos: c,
                scale,
            };
            cover_row(&object.shape, &pose, dy, x_lo, span, row);
            // the pixels the object covers, gathered (written at `m` always, kept where
            // covered: no branch), then sampled at once and blended
            let mut m = 0;
            for i in 0..span {
                let coverage = row.coverage[i];
                (row.xs[m], row.ys[m]) = (row.qx[i] + 64.0, row.qy[i] + 64.0);
                (row.coverage[m], row.column[m]) = (coverage, x_lo + i);
                m += usize::from(coverage > 0.0);
            }
            texture.sample_many(&row.xs[..m], &row.ys[..m], &mut row.values[..m]);
            let line = &mut out[(y - rows.start) * width..][..width];
            for ((&x, &value), &coverage) in
                row.column[..m].iter().zip(&row.values).zip(&row.coverage)
            {
                let pixel = &mut line[x];
                *pixel += (value - *pixel) * coverage;
            }
        }
    }
}

/// An object's pose at one time: centre, rotation and scale.
struct Pose {
    centre: [f64; 2],
    sin: f64,
    cos: f64,
    scale: f64,
}

/// The object-space points (`row.qx`, `row.qy`) and pixel coverages (`row.coverage`) of
/// pixels `x_lo..x_lo + span` of the row at `dy` below the object's centre; with AVX2 when
/// the CPU has it (the same operations, so the same bits).
fn cover_row(shape: &Shape, pose: &Pose, dy: f64, x_lo: usize, span: usize, row: &mut RowBuffers) {
    #[cfg(target_arch = "x86_64")]
    if super::canvas::use_avx2() {
        // SAFETY: use_avx2() is true only when the CPU has AVX2.
        unsafe { cover_row_avx2(shape, pose, dy, x_lo, span, row) };
        return;
    }
    cover_row_portable(shape, pose, dy, x_lo, span, row);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn cover_row_avx2(
    shape: &Shape,
    pose: &Pose,
    dy: f64,
    x_lo: usize,
    span: usize,
    row: &mut RowBuffers,
) {
    cover_row_portable(shape, pose, dy, x_lo, span, row);
}

#[inline(always)]
fn cover_row_portable(
    shape: &Shape,
    pose: &Pose,
    dy: f64,
    x_lo: usize,
    span: usize,
    row: &mut RowBuffers,
) {
    let Pose {
        centre,
        sin: s,
        cos: c,
        scale,
    } = *pose;
    let (qx, qy) = (&mut row.qx[..span], &mut row.qy[..span]);
    // columns as i32 (a sensor is at most MAX_SIDE wide): the same f64, and a conversion
    // AVX2 has
    for ((x, qx), qy) in (x_lo as i32..).zip(qx.iter_mut()).zip(qy.iter_mut()) {
        let dx = x as f64 - centre[0];
        (*qx, *qy) = ((c * dx + s * dy) / scale, (-s * dx + c * dy) / scale);
    }
    let distance = &mut row.distance[..span];
    shape.distances(qx, qy, distance);
    for (coverage, d) in row.coverage.iter_mut().zip(distance.iter()) {
        *coverage = (0.5 - d * scale).clamp(0.0, 1.0) as f32;
    }
}

/// A row's object-space points, distances and coverages, the sample coordinates and columns
/// of the covered pixels and their sampled values, reused from row to row.
struct RowBuffers {
    qx: Vec<f64>,
    qy: Vec<f64>,
    distance: Vec<f64>,
    xs: Vec<f64>,
    ys: Vec<f64>,
    coverage: Vec<f32>,
    column: Vec<usize>,
    values: Vec<f32>,
}

impl RowBuffers {
    fn new(width: usize) -> Self {
        Self {
            qx: vec![0.0; width],
            qy: vec![0.0; width],
            distance: vec![0.0; width],
            xs: vec![0.0; width],
            ys: vec![0.0; width],
            coverage: vec![0.0; width],
            column: vec![0; width],
            values: vec![0.0; width],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shape_distances_are_negative_inside_and_zero_on_the_edge() {
        let e = Shape::Ellipse { rx: 10.0, ry: 5.0 };
        assert!(e.distance(0.0, 0.0) < 0.0);
        assert!(e.distance(10.0, 0.0).abs() < 1e-9);
        let r = Shape::Rectangle { hx: 4.0, hy: 2.0 };
        assert_eq!(r.distance(4.0, 0.0), 0.0);
        assert_eq!(r.distance(6.0, 0.0), 2.0);
        let square = Shape::polygon(4, 3.0);
        assert!((square.distance(3.0, 0.0)).abs() < 1e-9);
        assert!((square.radius() - 3.0 * 2f64.sqrt()).abs() < 1e-9);
    }

    #[test]
    fn trajectory_passes_its_point_at_its_time() {
        let t = Trajectory {
            point: [100.0, 50.0],
            velocity: [10.0, -5.0],
            pass_time: 0.4,
            angle0: 0.0,
            angular_velocity: 1.0,
            scale0: 1.0,
            scale1: 2.0,
            duration: 1.0,
        };
        let (c, a, s) = t.pose(0.4);
        assert_eq!(c, [100.0, 50.0]);
        assert!((a - 0.4).abs() < 1e-12);
        assert!((s - 1.4).abs() < 1e-12);
    }
}
