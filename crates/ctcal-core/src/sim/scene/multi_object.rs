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
use std::ops::Range;
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
    /// over it in depth order, leaving out what a later object covers with coverage 1
    /// ([`Mode::Culled`]: the same frame). Coordinates are computed a row at a time and the
    /// textures sampled along the row at once ([`Canvas::sample_many`]).
    pub fn render(&self, width: usize, rows: Range<usize>, t: f64, out: &mut [f32]) {
        self.render_with(width, rows, t, out, Mode::Culled);
    }

    /// [`Self::render`] in `mode`: first the pieces of rows to draw, objects from the front
    /// (so that each knows what the objects above it cover), then the background and the
    /// pieces from the back (depth order, as [`blend`] needs). Returns the number of texture
    /// samples taken.
    fn render_with(
        &self,
        width: usize,
        rows: Range<usize>,
        t: f64,
        out: &mut [f32],
        mode: Mode,
    ) -> usize {
        let placed: Vec<Placed> = self
            .objects
            .iter()
            .filter_map(|o| Placed::new(o, &self.textures, width, &rows, t, mode))
            .collect();
        let mut covered = vec![Covered::default(); rows.len()];
        let mut pieces = Vec::new();
        for (index, object) in placed.iter().enumerate().rev() {
            let cull = mode == Mode::Culled;
            object.pieces(index, rows.start, cull, &mut covered, &mut pieces);
        }
        let mut row = RowBuffers::new(width);
        let mut samples = self.render_background(width, rows.clone(), t, &covered, &mut row, out);
        for piece in pieces.iter().rev() {
            let line = &mut out[(piece.y - rows.start) * width..][..width];
            samples += placed[piece.object].render_piece(piece, &mut row, line);
        }
        samples
    }

    /// The background over rows `rows` of `out`, but for the columns of each row that
    /// `covered` holds: the image is the texture seen through the inverse of its motion.
    /// Returns the number of pixels drawn.
    fn render_background(
        &self,
        width: usize,
        rows: Range<usize>,
        t: f64,
        covered: &[Covered],
        row: &mut RowBuffers,
        out: &mut [f32],
    ) -> usize {
        let mut drawn = 0;
        let (centre, angle, scale) = self.background.pose(t);
        let (s, c) = angle.sin_cos();
        let lines = rows.zip(out.chunks_exact_mut(width)).zip(covered);
        for ((y, line), covered) in lines {
            let dy = y as f64 - centre[1];
            covered.gaps(0..width, |gap| {
                let (xs, ys) = (&mut row.xs[..gap.len()], &mut row.ys[..gap.len()]);
                for (x, (qx, qy)) in gap.clone().zip(xs.iter_mut().zip(ys.iter_mut())) {
                    let dx = x as f64 - centre[0];
                    (*qx, *qy) = ((c * dx + s * dy) / scale, (-s * dx + c * dy) / scale);
                }
                drawn += gap.len();
                self.textures[0].sample_many(xs, ys, &mut line[gap]);
            });
        }
        drawn
    }
}

/// How [`MultiObjectWorld::render_with`] decides an object's pixels. `render` takes
/// `Culled`; `Exact` and `Bounded` are the references the tests compare it with.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(not(test), allow(dead_code))]
enum Mode {
    /// The exact distance at every pixel of each object's bounding square.
    Exact,
    /// [`Bounds`] decide the pixels clearly inside or outside (the same values: see there).
    Bounded,
    /// As `Bounded`, and a pixel that a later object covers with coverage 1 (as [`Bounds`]
    /// decide it) is neither sampled nor blended, for the background and every object
    /// under it. The same frame to the bit as `Bounded`: at coverage 1 [`blend`] gives the
    /// covering object's value whatever is below, so nothing drawn before it there can
    /// show; and the pixels still drawn get the same points, coverages and samples (each
    /// pixel's values depend on its column alone, not on which others are drawn with it).
    Culled,
}

/// An object at one time, within a band of rows: its shape, texture, pose, the columns and
/// rows of its bounding square and its [`Bounds`] (none in [`Mode::Exact`] or outside their
/// guard).
struct Placed<'a> {
    shape: &'a Shape,
    texture: &'a Canvas,
    pose: Pose,
    square: (usize, usize),
    ys: std::ops::RangeInclusive<usize>,
    bounds: Option<Bounds>,
}

impl<'a> Placed<'a> {
    /// `object` at `t` on rows `rows` of a frame `width` wide, or `None` if its bounding
    /// square misses them.
    fn new(
        object: &'a Object,
        textures: &'a [Canvas],
        width: usize,
        rows: &Range<usize>,
        t: f64,
        mode: Mode,
    ) -> Option<Self> {
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
            return None;
        }
        let (sin, cos) = angle.sin_cos();
        let pose = Pose {
            centre,
            sin,
            cos,
            scale,
        };
        let bounds = match mode {
            Mode::Exact => None,
            Mode::Bounded | Mode::Culled => Bounds::new(&object.shape, &pose, reach),
        };
        Some(Self {
            shape: &object.shape,
            texture: &textures[object.texture],
            pose,
            square: (x_lo as usize, x_hi as usize),
            ys: y_lo as usize..=y_hi as usize,
            bounds,
        })
    }

    /// Appends to `pieces` (tagged `index`) the parts of its rows to draw: the columns it
    /// may cover but those `covered` holds (row `y` at `covered[y - first_row]`); with
    /// `cull`, then adds to `covered` the columns it covers with coverage 1.
    fn pieces(
        &self,
        index: usize,
        first_row: usize,
        cull: bool,
        covered: &mut [Covered],
        pieces: &mut Vec<Piece>,
    ) {
        for y in self.ys.clone() {
            let Some(cover) = self.row(y) else {
                continue;
            };
            let inner = cover.lo + cover.inner.start..cover.lo + cover.inner.end;
            let covered = &mut covered[y - first_row];
            covered.gaps(cover.lo..cover.hi + 1, |columns| {
                let inner = inner.start.max(columns.start)..inner.end.min(columns.end);
                pieces.push(Piece {
                    object: index,
                    y,
                    columns,
                    inner,
                });
            });
            if cull && !inner.is_empty() {
                covered.insert(inner);
            }
        }
    }

    /// The columns of row `y` to render: [`Bounds::row`], or the whole bounding square.
    fn row(&self, y: usize) -> Option<RowCover> {
        let dy = y as f64 - self.pose.centre[1];
        match &self.bounds {
            Some(b) => b.row(dy, self.square),
            None => Some(RowCover {
                lo: self.square.0,
                hi: self.square.1,
                inner: 0..0,
            }),
        }
    }

    /// Blends `piece` of this object over `line` (its row of the frame) by pixel coverage;
    /// returns the number of pixels sampled.
    fn render_piece(&self, piece: &Piece, row: &mut RowBuffers, line: &mut [f32]) -> usize {
        let dy = piece.y as f64 - self.pose.centre[1];
        let (x_lo, span) = (piece.columns.start, piece.columns.len());
        let inner = if piece.inner.is_empty() {
            0..0
        } else {
            piece.inner.start - x_lo..piece.inner.end - x_lo
        };
        cover_row(self.shape, &self.pose, dy, x_lo, span, inner, row);
        // the pixels the object covers, gathered (written at `m` always, kept where
        // covered: no branch), then sampled at once and blended
        let mut m = 0;
        for i in 0..span {
            let coverage = row.coverage[i];
            (row.xs[m], row.ys[m]) = (row.qx[i] + 64.0, row.qy[i] + 64.0);
            (row.coverage[m], row.column[m]) = (coverage, x_lo + i);
            m += usize::from(coverage > 0.0);
        }
        self.texture
            .sample_many(&row.xs[..m], &row.ys[..m], &mut row.values[..m]);
        for ((&x, &value), &coverage) in row.column[..m].iter().zip(&row.values).zip(&row.coverage)
        {
            let pixel = &mut line[x];
            *pixel = blend(*pixel, value, coverage);
        }
        m
    }
}

/// Columns `columns` of row `y` of the placed object `object` to draw, of which those in
/// `inner` (columns too, empty or not within `columns` if none) have coverage 1.
struct Piece {
    object: usize,
    y: usize,
    columns: Range<usize>,
    inner: Range<usize>,
}

/// The columns of one row that objects already placed (those above) cover with coverage
/// 1: sorted, disjoint ranges with a gap between each two.
#[derive(Clone, Debug, Default)]
struct Covered(Vec<Range<usize>>);

impl Covered {
    /// Calls `f` with each largest range of `span` outside the set (never empty), left to
    /// right.
    fn gaps(&self, span: Range<usize>, mut f: impl FnMut(Range<usize>)) {
        let mut start = span.start;
        for r in &self.0 {
            if r.start >= span.end {
                break;
            }
            if r.end <= start {
                continue;
            }
            if r.start > start {
                f(start..r.start);
            }
            start = r.end;
        }
        if start < span.end {
            f(start..span.end);
        }
    }

    /// Adds the columns `add` (not empty), merging the ranges it overlaps or touches.
    fn insert(&mut self, add: Range<usize>) {
        // the ranges before `i` end before `add` with a gap, those from `j` start after it
        let i = self.0.partition_point(|r| r.end < add.start);
        let j = self.0.partition_point(|r| r.start <= add.end);
        let merged = if i < j {
            self.0[i].start.min(add.start)..self.0[j - 1].end.max(add.end)
        } else {
            add
        };
        self.0.splice(i..j, [merged]);
    }
}

/// The pixel `below` with an object's `value` over it at `coverage` (in 0..=1): `below +
/// (value - below) * coverage`, and exactly `value` at coverage 1.
///
/// Why the case: `below + (value - below) * 1` is `value` when `value - below` is exact
/// (Sterbenz: `below / 2 <= value <= 2 below`), else it may be an ulp off (about 15 % of
/// pairs of values in 5-250 DN), so what is under a covered pixel still counted. Taken as
/// `value`, the pixel no longer depends on anything drawn before it, and
/// [`MultiObjectWorld::render`] leaves out what a later object covers ([`Mode::Culled`];
/// changed from the plain blend on 2026-12-07, see benches/README.md).
#[inline(always)]
fn blend(below: f32, value: f32, coverage: f32) -> f32 {
    if coverage == 1.0 {
        value
    } else {
        below + (value - below) * coverage
    }
}

/// An object's pose at one time: centre, rotation and scale.
struct Pose {
    centre: [f64; 2],
    sin: f64,
    cos: f64,
    scale: f64,
}

/// The columns of one row to render: `lo..=hi` (the others have no coverage), of which
/// `inner` (offsets from `lo`) have coverage 1.
#[derive(Debug, PartialEq)]
struct RowCover {
    lo: usize,
    hi: usize,
    inner: std::ops::Range<usize>,
}

/// Margin of [`Bounds`], both in distance (pixels, the level of `d * scale`) and in columns.
const MARGIN: f64 = 1.0 / 64.0;

/// An object's outline at one pose, as a row's columns: which pixels of a row its coverage
/// `(0.5 - d * scale).clamp(0, 1)` ([`cover_row`]) leaves at 0 (skipped) and which at
/// exactly 1 (no distance computed), so that only the band along the edge takes the exact
/// distance (an ellipse's `hypot`).
///
/// In real numbers, along a row `d * scale` is a convex function of the column for all three
/// shapes (an ellipse's scaled norm, a maximum of affine functions), so the columns where it
/// is below a level `L` are an interval: a quadratic's roots for an ellipse, the intersection
/// of the half-planes' bounds for a rectangle (four edges) and a polygon. [`Bounds::row`]
/// computes this interval for `L = 0.5 + MARGIN` (outside it `d * scale >= 0.5 + MARGIN`)
/// and for `L = -0.5 - MARGIN` (inside it `d * scale <= -0.5 - MARGIN`), and widens the
/// first, narrows the second by another `MARGIN` in columns.
///
/// Why a decided pixel gets the same bits as the exact path. Under the guard of
/// [`Bounds::new`] (finite pose, scale above 2^-20, centre within 2^20 px, reach within 2^12
/// px, an ellipse's axes within 4x) every quantity is below 2^16 in magnitude (columns and
/// row offsets within the bounding square, `a * scale`, `k^2 / A` below), and each is a few
/// roundings (relative error 2^-53 each) from its real value:
/// - The exact path's `d * scale` is within `2^-53 * 2^16 * 16 = 2^-33` px of its real
///   value (`dx = x - cx` is the rounded difference, `qx`, `qy` two products, a sum and a
///   division, then one edge's product-sum, or `hypot` (under 1 ulp), `- 1`, `* min`,
///   `* scale`). So where the real `d * scale >= 0.5 + MARGIN / 2`, the computed one is
///   above 0.5, `0.5 - d * scale` rounds to at most 0 (rounding is monotone) and the pixel
///   is not blended; where it is `<= -0.5 - MARGIN / 2`, `0.5 - d * scale` is above 1 and
///   the coverage is exactly `1.0`.
/// - Half-planes: an edge with unit normal `(u, v)` in pixel space and offset `a` keeps
///   `u dx + v dy < a scale + L`, i.e. `u dx < R`. The column bound `cx + R / u` is computed
///   with `R` within `2^-33` of its real value, the division within `2^-53 |R|`, the sum
///   within `2^-53 * 2^14` wherever it bounds a pixel of the square (a bound far outside
///   the square decides nothing): a column excluded by `MARGIN` past the computed bound has
///   a real `u dx - R > -2^-30`, so the edge's (and the maximum's) `d * scale` is at least
///   `L - 2^-30`; likewise a column inside every narrowed bound has `d * scale <= L + 2^-30`
///   for every edge. `u = 0` keeps a row whole or drops it by the sign of `R` (the same
///   argument, without the division).
/// - Ellipse: `h^2 = (qx / rx)^2 + (qy / ry)^2 < k^2` with `k = 1 + L / (scale min(rx, ry))`
///   is `A (dx - m)^2 < A w^2`, `m = -dy P / A`, `w^2 = k^2 / A - dy^2 D / A^2` (`A`, `P`, `D`
///   per pose). `m` is within `2^-53 * 2^14` and `w^2` (a difference of terms below 2^28)
///   within `2^-53 * 2^32 = 2^-21` of their real values, so `w = sqrt(max(w^2, 0))` within
///   `sqrt(2^-21) < 2^-10` (`|sqrt a - sqrt b| <= sqrt |a - b|`), and the computed interval's
///   ends within `2^-10 + 2^-30 < MARGIN` columns of the real interval's at level `L`
///   (a row the real interval misses by less keeps a computed interval of width 0 at `m`).
///   Widened (narrowed) by `MARGIN`, every column outside (inside) is outside (inside) the
///   real interval: `d * scale >= 0.5 + MARGIN` (`<= -0.5 - MARGIN`). The inner level is
///   taken only where `k scale min(rx, ry) = scale min(rx, ry) + L >= 1/16` (else no pixel
///   is decided 1), which keeps `k^2 / A` and the guard's bounds.
///
/// So every pixel decided here gets what the exact path gives (not blended, or coverage
/// `1.0` with the same object-space point): a margin of 2^-6 against errors below 2^-9.
/// `bounds_decide_pixels_as_the_exact_distance_does` checks it to the bit.
#[derive(Debug)]
struct Bounds {
    cx: f64,
    kind: BoundsKind,
}

#[derive(Debug)]
enum BoundsKind {
    /// `h^2 = A dx^2 + 2 dy P dx + dy^2 Q`, `D = A Q - P^2 = (c^2 + s^2)^2 / (ax ay)^2`
    /// (`ax = scale rx`, `ay = scale ry`); `k^2` at the two levels (the inner one `None`
    /// where it is not taken).
    Ellipse {
        a: f64,
        p: f64,
        d: f64,
        k2_out: f64,
        k2_in: Option<f64>,
    },
    /// Edges `(u, v, a * scale)`: `u dx + v dy - a scale` is the edge's `d * scale`.
    Edges(Vec<(f64, f64, f64)>),
}

impl Bounds {
    /// The bounds of `shape` at `pose`, or `None` outside the guard (every pixel then takes
    /// the exact distance).
    fn new(shape: &Shape, pose: &Pose, reach: f64) -> Option<Self> {
        let Pose {
            centre,
            sin: s,
            cos: c,
            scale,
        } = *pose;
        let finite = [centre[0], centre[1], s, c, scale, reach]
            .iter()
            .all(|v| v.is_finite());
        let guard = finite
            && scale >= 2f64.powi(-20)
            && centre[0].abs() <= 2f64.powi(20)
            && centre[1].abs() <= 2f64.powi(20)
            && reach <= 2f64.powi(12);
        if !guard {
            return None;
        }
        let kind = match shape {
            &Shape::Ellipse { rx, ry } => {
                let (lo, hi) = (rx.min(ry), rx.max(ry));
                if !(lo > 0.0 && hi <= 4.0 * lo) {
                    return None;
                }
                let (ax, ay) = (scale * rx, scale * ry);
                let (ix, iy) = (1.0 / (ax * ax), 1.0 / (ay * ay));
                let a = c * c * ix + s * s * iy;
                let p = c * s * (ix - iy);
                let radius = scale * lo;
                let k = |level: f64| 1.0 + level / radius;
                let k_in = k(-0.5 - MARGIN);
                BoundsKind::Ellipse {
                    a,
                    p,
                    // A Q - P^2, without the cancellation
                    d: (c * c + s * s).powi(2) * ix * iy,
                    k2_out: k(0.5 + MARGIN).powi(2),
                    k2_in: (radius - 0.5 - MARGIN >= 1.0 / 16.0).then_some(k_in * k_in),
                }
            }
            &Shape::Rectangle { hx, hy } => {
                let edges = [
                    (1.0, 0.0, hx),
                    (-1.0, 0.0, hx),
                    (0.0, 1.0, hy),
                    (0.0, -1.0, hy),
                ];
                BoundsKind::Edges(edges.iter().map(|&e| edge(e, pose)).collect())
            }
            Shape::Polygon {
                apothem, normals, ..
            } => BoundsKind::Edges(
                normals
                    .iter()
                    .map(|&(ns, nc)| edge((nc, ns, *apothem), pose))
                    .collect(),
            ),
        };
        Some(Self {
            cx: centre[0],
            kind,
        })
    }

    /// The columns of the row at `dy` below the centre to render, within `square` (the
    /// bounding square's columns), or `None` if the object covers none.
    fn row(&self, dy: f64, square: (usize, usize)) -> Option<RowCover> {
        let (outer, inner) = match &self.kind {
            &BoundsKind::Ellipse {
                a,
                p,
                d,
                k2_out,
                k2_in,
            } => {
                let m = -dy * p / a;
                let chord = |k2: f64| {
                    let w = (k2 / a - dy * dy * d / (a * a)).max(0.0).sqrt();
                    (self.cx + m - w, self.cx + m + w)
                };
                let inner = k2_in.map_or((f64::INFINITY, f64::NEG_INFINITY), chord);
                (chord(k2_out), inner)
            }
            BoundsKind::Edges(edges) => {
                let (mut outer, mut inner) = (
                    (f64::NEG_INFINITY, f64::INFINITY),
                    (f64::NEG_INFINITY, f64::INFINITY),
                );
                for &(u, v, a) in edges {
                    let base = a - v * dy;
                    for (range, level) in [(&mut outer, 0.5 + MARGIN), (&mut inner, -0.5 - MARGIN)]
                    {
                        let r = base + level;
                        if u > 0.0 {
                            range.1 = range.1.min(self.cx + r / u);
                        } else if u < 0.0 {
                            range.0 = range.0.max(self.cx + r / u);
                        } else if r <= 0.0 {
                            *range = (f64::INFINITY, f64::NEG_INFINITY);
                        }
                    }
                }
                (outer, inner)
            }
        };
        let (x_lo, x_hi) = (square.0 as f64, square.1 as f64);
        let lo = (outer.0 - MARGIN).ceil().max(x_lo);
        let hi = (outer.1 + MARGIN).floor().min(x_hi);
        // never NaN: `max` and `min` take the square's end over a NaN
        if lo > hi {
            return None;
        }
        let in_lo = (inner.0 + MARGIN).ceil().max(lo);
        let in_hi = (inner.1 - MARGIN).floor().min(hi);
        let (lo, hi) = (lo as usize, hi as usize);
        let inner = if in_lo <= in_hi {
            in_lo as usize - lo..in_hi as usize - lo + 1
        } else {
            0..0
        };
        Some(RowCover { lo, hi, inner })
    }
}

/// An edge of unit normal `(nx, ny)` and offset `a` in object space as [`BoundsKind::Edges`]
/// holds it at `pose`: `nx qx + ny qy = (u dx + v dy) / scale`.
fn edge((nx, ny, a): (f64, f64, f64), pose: &Pose) -> (f64, f64, f64) {
    let (s, c) = (pose.sin, pose.cos);
    (nx * c - ny * s, nx * s + ny * c, a * pose.scale)
}

/// The object-space points (`row.qx`, `row.qy`) and pixel coverages (`row.coverage`) of
/// pixels `x_lo..x_lo + span` of the row at `dy` below the object's centre, the pixels at
/// offsets `inner` covered (coverage 1, no distance: [`Bounds`]); with AVX2 when the CPU has
/// it (the same operations, so the same bits).
fn cover_row(
    shape: &Shape,
    pose: &Pose,
    dy: f64,
    x_lo: usize,
    span: usize,
    inner: std::ops::Range<usize>,
    row: &mut RowBuffers,
) {
    #[cfg(target_arch = "x86_64")]
    if super::canvas::use_avx2() {
        // SAFETY: use_avx2() is true only when the CPU has AVX2.
        unsafe { cover_row_avx2(shape, pose, dy, x_lo, span, inner, row) };
        return;
    }
    cover_row_portable(shape, pose, dy, x_lo, span, inner, row);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn cover_row_avx2(
    shape: &Shape,
    pose: &Pose,
    dy: f64,
    x_lo: usize,
    span: usize,
    inner: std::ops::Range<usize>,
    row: &mut RowBuffers,
) {
    cover_row_portable(shape, pose, dy, x_lo, span, inner, row);
}

#[inline(always)]
fn cover_row_portable(
    shape: &Shape,
    pose: &Pose,
    dy: f64,
    x_lo: usize,
    span: usize,
    inner: std::ops::Range<usize>,
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
    // the band left of the inner columns and the band right of them
    for band in [0..inner.start, inner.end.max(inner.start)..span] {
        let distance = &mut row.distance[band.clone()];
        shape.distances(&qx[band.clone()], &qy[band.clone()], distance);
        for (coverage, d) in row.coverage[band].iter_mut().zip(distance.iter()) {
            *coverage = (0.5 - d * scale).clamp(0.0, 1.0) as f32;
        }
    }
    row.coverage[inner].fill(1.0);
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

    /// A random shape of up to 60 px and pose (some at right angles, some with an edge on
    /// a pixel's half-way point, a coverage level's edge), and its bounding square's reach.
    fn random_case(rng: &mut impl Rng) -> (Shape, Pose, f64) {
        let size = if rng.random_bool(0.2) {
            rng.random_range(0.3..2.0)
        } else {
            rng.random_range(0.3..60.0)
        };
        let shape = match rng.random_range(0..3u32) {
            0 => Shape::Ellipse {
                rx: size,
                ry: size * rng.random_range(0.25..1.0),
            },
            1 => Shape::Rectangle {
                hx: size,
                hy: size * rng.random_range(0.2..1.0),
            },
            _ => Shape::polygon(rng.random_range(3..=8), size),
        };
        let scale = match rng.random_range(0..4u32) {
            0 => 1.0,
            1 => rng.random_range(0.01..0.2),
            _ => rng.random_range(0.2..3.0),
        };
        let angle = match rng.random_range(0..3u32) {
            0 => std::f64::consts::FRAC_PI_4 * rng.random_range(0..8) as f64,
            _ => rng.random_range(0.0..std::f64::consts::TAU),
        };
        let mut centre = [
            rng.random_range(-30.0..270.0),
            rng.random_range(-30.0..210.0),
        ];
        match rng.random_range(0..4u32) {
            0 => centre = centre.map(f64::round),
            1 => {
                // an edge (or axis end) at a coverage level's boundary, to the last bits
                let extent = match shape {
                    Shape::Ellipse { rx, .. } => rx,
                    Shape::Rectangle { hx, .. } => hx,
                    Shape::Polygon { apothem, .. } => apothem,
                };
                let tiny = [0.0, 1e-13, -1e-13, 1e-9, -1e-9][rng.random_range(0..5)];
                let level = [0.5, -0.5][rng.random_range(0..2)];
                centre[0] = centre[0].round() - extent * scale - level + tiny;
                centre[1] = centre[1].round() + [0.0, 0.5][rng.random_range(0..2)];
            }
            _ => {}
        }
        let (sin, cos) = angle.sin_cos();
        let reach = shape.radius() * scale + 1.0;
        let pose = Pose {
            centre,
            sin,
            cos,
            scale,
        };
        (shape, pose, reach)
    }

    #[test]
    fn bounds_decide_pixels_as_the_exact_distance_does() {
        use rand::SeedableRng;
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(19);
        let width = 240usize;
        let (mut exact, mut fast) = (RowBuffers::new(width), RowBuffers::new(width));
        let (mut pixels, mut decided) = (0usize, 0usize);
        for case in 0..20_000 {
            let (shape, pose, reach) = random_case(&mut rng);
            let [cx, cy] = pose.centre;
            let x_lo = (cx - reach).floor().max(0.0);
            let x_hi = (cx + reach).ceil().min(width as f64 - 1.0);
            let (y_lo, y_hi) = (
                (cy - reach).floor().max(0.0),
                (cy + reach).ceil().min(179.0),
            );
            if x_lo > x_hi || y_lo > y_hi {
                continue;
            }
            let square = (x_lo as usize, x_hi as usize);
            let span = square.1 - square.0 + 1;
            let bounds = Bounds::new(&shape, &pose, reach).expect("within the guard");
            for y in y_lo as usize..=y_hi as usize {
                let dy = y as f64 - cy;
                cover_row(&shape, &pose, dy, square.0, span, 0..0, &mut exact);
                pixels += span;
                let Some(cover) = bounds.row(dy, square) else {
                    decided += span;
                    for i in 0..span {
                        assert!(exact.coverage[i] <= 0.0, "case {case} row {y}: {shape:?}");
                    }
                    continue;
                };
                let fast_span = cover.hi - cover.lo + 1;
                cover_row(
                    &shape,
                    &pose,
                    dy,
                    cover.lo,
                    fast_span,
                    cover.inner.clone(),
                    &mut fast,
                );
                decided += span - fast_span + cover.inner.len();
                for (i, x) in (square.0..=square.1).enumerate() {
                    let e = exact.coverage[i];
                    if x < cover.lo || x > cover.hi {
                        assert!(e <= 0.0, "case {case} ({x}, {y}): {e} {shape:?}");
                        continue;
                    }
                    let k = x - cover.lo;
                    let same = fast.coverage[k].to_bits() == e.to_bits()
                        && fast.qx[k].to_bits() == exact.qx[i].to_bits()
                        && fast.qy[k].to_bits() == exact.qy[i].to_bits();
                    assert!(same, "case {case} ({x}, {y}) {cover:?} {shape:?}");
                }
            }
        }
        // most pixels are decided by the bounds
        assert!(decided * 10 > pixels * 7, "{decided} of {pixels}");
    }

    #[test]
    fn bounds_give_way_outside_their_guard() {
        let pose = |scale: f64, centre: [f64; 2]| Pose {
            centre,
            sin: 0.0,
            cos: 1.0,
            scale,
        };
        let ellipse = Shape::Ellipse { rx: 10.0, ry: 5.0 };
        assert!(Bounds::new(&ellipse, &pose(1.0, [10.0, 10.0]), 11.0).is_some());
        assert!(Bounds::new(&ellipse, &pose(f64::NAN, [10.0, 10.0]), 11.0).is_none());
        assert!(Bounds::new(&ellipse, &pose(1.0, [3e6, 10.0]), 11.0).is_none());
        assert!(Bounds::new(&ellipse, &pose(1.0, [10.0, 10.0]), 1e4).is_none());
        let thin = Shape::Ellipse { rx: 10.0, ry: 2.0 };
        assert!(Bounds::new(&thin, &pose(1.0, [10.0, 10.0]), 11.0).is_none());
        // a small ellipse decides no pixel covered, only uncovered ones
        let small = Shape::Ellipse { rx: 0.5, ry: 0.5 };
        let b = Bounds::new(&small, &pose(1.0, [10.2, 10.0]), 1.5).unwrap();
        let row = b.row(0.0, (8, 12)).unwrap();
        assert_eq!((row.lo, row.hi, row.inner), (10, 11, 0..0));
        assert_eq!(b.row(1.2, (8, 12)), None);
    }

    /// A scene of 25-30 objects of 0.5-40 px (scaled 0.05-1.5), many overlapping.
    fn crowded_scene() -> MultiObjectScene {
        MultiObjectScene {
            objects: [25, 30],
            background_velocity_px_s: [0.1, 40.0],
            background_angular_velocity_deg_s: [0.0, 45.0],
            background_scale: [1.0, 1.5],
            object_velocity_px_s: [0.1, 600.0],
            object_angular_velocity_deg_s: [0.0, 60.0],
            object_scale: [0.05, 1.5],
            object_size_px: [0.5, 40.0],
            textures_dir: None,
            background_texture: TextureParams {
                canvas_px: 128,
                ..Default::default()
            },
        }
    }

    /// `world` at `t` in `mode`, in bands of `band` rows (as the parallel renderer draws),
    /// into a frame that holds `fill` before.
    fn rendered(world: &MultiObjectWorld, t: f64, mode: Mode, band: usize, fill: f32) -> Vec<f32> {
        let (width, height) = (240, 180);
        let mut out = vec![fill; width * height];
        for (k, out) in out.chunks_mut(width * band).enumerate() {
            let rows = k * band..(k * band + band).min(height);
            world.render_with(width, rows, t, out, mode);
        }
        out
    }

    #[test]
    fn rendering_with_bounds_is_the_exact_rendering_to_the_bit() {
        use rand::SeedableRng;
        let scene = crowded_scene();
        let (width, height) = (240, 180);
        for seed in 0..4 {
            let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
            let world = scene.realise(width, height, 1.0, Vec::new(), &mut rng);
            for k in 0..20 {
                let t = k as f64 / 19.0;
                let a = rendered(&world, t, Mode::Bounded, height, 0.0);
                let b = rendered(&world, t, Mode::Exact, height, 0.0);
                // and in bands, as the parallel renderer does
                let c = rendered(&world, t, Mode::Bounded, 7, 0.0);
                for (i, ((a, b), c)) in a.iter().zip(&b).zip(&c).enumerate() {
                    assert_eq!(a.to_bits(), b.to_bits(), "seed {seed} t {t} pixel {i}");
                    assert_eq!(c.to_bits(), b.to_bits(), "seed {seed} t {t} pixel {i}");
                }
            }
        }
    }

    /// Culling (`render`) against the same bounds without it, whole frames to the bit: the
    /// crowded scene and scenes of 1-60 objects up to 80 px, whole and in bands, into frames
    /// that hold NaN before (a pixel left out and never drawn over would show).
    #[test]
    fn culling_is_the_rendering_without_it_to_the_bit() {
        use rand::SeedableRng;
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(20);
        let (width, height) = (240, 180);
        let (mut all, mut culled) = (0usize, 0usize);
        for case in 0..12 {
            let mut scene = crowded_scene();
            if case % 3 != 0 {
                let count = rng.random_range(1..=60);
                scene.objects = [count, count];
                scene.object_size_px = [rng.random_range(0.5..10.0), rng.random_range(10.0..80.0)];
                scene.object_scale = [0.2, rng.random_range(0.2..2.0)];
            }
            let world = scene.realise(width, height, 1.0, Vec::new(), &mut rng);
            for k in 0..10 {
                let t = k as f64 / 9.0;
                let mut whole = vec![f32::NAN; width * height];
                culled += world.render_with(width, 0..height, t, &mut whole, Mode::Culled);
                let mut reference = vec![0f32; width * height];
                all += world.render_with(width, 0..height, t, &mut reference, Mode::Bounded);
                let bands = rendered(&world, t, Mode::Culled, [1, 7, 8][k % 3], f32::NAN);
                for (i, ((a, b), c)) in whole.iter().zip(&reference).zip(&bands).enumerate() {
                    assert_eq!(a.to_bits(), b.to_bits(), "case {case} t {t} pixel {i}");
                    assert_eq!(c.to_bits(), b.to_bits(), "case {case} t {t} pixel {i}");
                }
            }
        }
        // and it leaves out a good part of the samples
        assert!(culled * 10 < all * 9, "{culled} of {all} samples");
    }

    /// How many texture samples a frame of each multi-object scene of `calib/scenes` takes
    /// with and without culling (`cargo test ... samples_of_the_calib_scenes -- --nocapture`
    /// prints them): culling leaves out at least a fifth of them in the crowded ones.
    #[test]
    fn samples_of_the_calib_scenes() {
        let scenes = [
            (
                "slow",
                include_str!("../../../../../calib/scenes/multi_object_slow.toml"),
            ),
            (
                "medium",
                include_str!("../../../../../calib/scenes/multi_object_medium.toml"),
            ),
            (
                "fast",
                include_str!("../../../../../calib/scenes/multi_object_fast.toml"),
            ),
            (
                "variety",
                include_str!("../../../../../calib/scenes/multi_object_variety.toml"),
            ),
        ];
        for (name, text) in scenes {
            let spec = super::super::SceneSpec::from_toml(text, name.as_ref()).unwrap();
            let super::super::Scene::MultiObject(world) = spec.realise().unwrap() else {
                panic!("{name} is a multi-object scene");
            };
            let (width, height) = (spec.width, spec.height);
            let (mut all, mut culled) = (0usize, 0usize);
            let mut out = vec![0f32; width * height];
            for k in 0..20 {
                let t = spec.duration_s * k as f64 / 19.0;
                all += world.render_with(width, 0..height, t, &mut out, Mode::Bounded);
                culled += world.render_with(width, 0..height, t, &mut out, Mode::Culled);
            }
            let objects = world.object_count();
            println!(
                "{name} ({objects} objects): {} -> {} samples per frame",
                all / 20,
                culled / 20
            );
            if objects >= 10 {
                assert!(culled * 5 < all * 4, "{name}: {culled} of {all}");
            }
        }
    }

    #[test]
    fn covered_columns_are_a_set_of_ranges() {
        use rand::SeedableRng;
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(21);
        for _ in 0..2000 {
            let mut covered = Covered::default();
            let mut bits = [false; 64];
            for _ in 0..rng.random_range(0..12) {
                let start = rng.random_range(0..63);
                let add = start..rng.random_range(start + 1..=64);
                bits[add.clone()].fill(true);
                covered.insert(add);
                // sorted, disjoint, a gap between each two, and the columns of `bits`
                assert!(
                    covered.0.windows(2).all(|w| w[0].end < w[1].start),
                    "{covered:?}"
                );
                let mut set = [false; 64];
                covered.0.iter().for_each(|r| set[r.clone()].fill(true));
                assert_eq!(set, bits);
            }
            let start = rng.random_range(0..64);
            let span = start..rng.random_range(start..=64);
            let mut outside = [false; 64];
            let mut last_end = None;
            covered.gaps(span.clone(), |gap| {
                assert!(!gap.is_empty() && span.start <= gap.start && gap.end <= span.end);
                // largest: a gap neither touches the one before nor runs on past its end
                assert!(last_end.is_none_or(|end| end < gap.start));
                assert!(gap.end == span.end || bits[gap.end]);
                assert!(gap.start == span.start || bits[gap.start - 1]);
                last_end = Some(gap.end);
                outside[gap].fill(true);
            });
            for x in 0..64 {
                assert_eq!(
                    outside[x],
                    span.contains(&x) && !bits[x],
                    "{covered:?} {span:?}"
                );
            }
        }
    }

    #[test]
    fn the_blend_at_coverage_one_is_the_value() {
        // 0.1 - 3.0 is not exact in f32: the plain blend is an ulp off
        let (below, value) = (3.0f32, 0.1f32);
        assert_ne!((below + (value - below) * 1.0).to_bits(), value.to_bits());
        assert_eq!(blend(below, value, 1.0).to_bits(), value.to_bits());
        assert_eq!(blend(f32::NAN, value, 1.0).to_bits(), value.to_bits());
        assert_eq!(blend(2.0, 4.0, 0.5), 3.0);
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
