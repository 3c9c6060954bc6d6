//! Homographies from point correspondences, the classical way (Hartley & Zisserman,
//! *Multiple View Geometry*, 2nd ed. 2004, ch. 4): the normalised direct linear transform
//! (Algorithm 4.2: both point sets moved to their centroid and scaled to a mean distance of
//! sqrt(2), the 2n x 9 system solved by the singular vector of the smallest singular value,
//! the result denormalised), then the geometric (reprojection) error minimised by
//! Levenberg-Marquardt (Sec. 4.2.2 and A6.2), optionally with one radial-distortion
//! coefficient ([`crate::sim::screen_geometry`]), which is kept only where an F-test says
//! it lowers the residual significantly and it removes at least a quarter of the RMS
//! residual (matched points carry small systematic errors that a free coefficient would
//! otherwise absorb; a real lens leaves residuals of pixels without it).

use crate::sim::screen_geometry::{Homography, ScreenGeometry};
use nalgebra::{DMatrix, DVector, Matrix3};
use statrs::distribution::{ContinuousCDF, FisherSnedecor};

/// One correspondence: a stimulus point and where it was seen on the sensor.
pub type Pair = ((f64, f64), (f64, f64));

/// The share of the RMS residual a radial coefficient must leave at most to be kept.
const MATERIAL_GAIN: f64 = 0.75;

/// The similarity that moves `points` to their centroid at a mean distance of sqrt(2).
fn normalising(points: impl Iterator<Item = (f64, f64)> + Clone) -> Matrix3<f64> {
    let n = points.clone().count().max(1) as f64;
    let (cx, cy) = points
        .clone()
        .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
    let mean = points.map(|p| (p.0 - cx).hypot(p.1 - cy)).sum::<f64>() / n;
    let s = if mean > 1e-12 {
        std::f64::consts::SQRT_2 / mean
    } else {
        1.0
    };
    Matrix3::new(s, 0.0, -s * cx, 0.0, s, -s * cy, 0.0, 0.0, 1.0)
}

fn transform(m: &Matrix3<f64>, p: (f64, f64)) -> (f64, f64) {
    let w = m[(2, 0)] * p.0 + m[(2, 1)] * p.1 + m[(2, 2)];
    (
        (m[(0, 0)] * p.0 + m[(0, 1)] * p.1 + m[(0, 2)]) / w,
        (m[(1, 0)] * p.0 + m[(1, 1)] * p.1 + m[(1, 2)]) / w,
    )
}

/// The normalised DLT homography of at least four correspondences (`None` when they do not
/// determine one, e.g. three of four collinear).
pub fn dlt(pairs: &[Pair]) -> Option<Homography> {
    if pairs.len() < 4 {
        return None;
    }
    let t = normalising(pairs.iter().map(|p| p.0));
    let t_prime = normalising(pairs.iter().map(|p| p.1));
    // at least 9 rows, so that the SVD holds the null vector
    let rows = (2 * pairs.len()).max(9);
    let mut a = DMatrix::<f64>::zeros(rows, 9);
    for (i, &(s, q)) in pairs.iter().enumerate() {
        let (x, y) = transform(&t, s);
        let (u, v) = transform(&t_prime, q);
        let r = 2 * i;
        for (c, value) in [(3, -x), (4, -y), (5, -1.0), (6, v * x), (7, v * y), (8, v)] {
            a[(r, c)] = value;
        }
        for (c, value) in [(0, x), (1, y), (2, 1.0), (6, -u * x), (7, -u * y), (8, -u)] {
            a[(r + 1, c)] = value;
        }
    }
    let svd = a.svd(false, true);
    let v_t = svd.v_t?;
    let smallest = svd.singular_values.argmin().0;
    let values = svd.singular_values.as_slice();
    // a second null vector: the points do not determine the map
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    if sorted[1] < 1e-9 * sorted[8].max(1e-300) {
        return None;
    }
    let h = v_t.row(smallest);
    let normalised = Matrix3::from_fn(|r, c| h[3 * r + c]);
    let m = t_prime.try_inverse()? * normalised * t;
    (m[(2, 2)].abs() > 1e-15).then(|| Homography::from_matrix(&m).normalized())
}

/// A fit of a geometry to correspondences.
#[derive(Clone, Debug)]
pub struct GeometryFit {
    pub geometry: ScreenGeometry,
    /// Root mean square of the reprojection residuals, sensor pixels.
    pub rms_px: f64,
    /// The residual of each pair (observed minus fitted), sensor pixels.
    pub residuals: Vec<(f64, f64)>,
}

/// The pairs' reprojection residuals under `geometry` (`None` where a point does not map).
fn residuals(geometry: &ScreenGeometry, pairs: &[Pair]) -> Option<Vec<(f64, f64)>> {
    pairs
        .iter()
        .map(|&(s, q)| geometry.to_sensor(s).map(|p| (q.0 - p.0, q.1 - p.1)))
        .collect()
}

fn rms(residuals: &[(f64, f64)]) -> f64 {
    let n = residuals.len().max(1) as f64;
    (residuals.iter().map(|r| r.0 * r.0 + r.1 * r.1).sum::<f64>() / n).sqrt()
}

/// The geometry of `params`: the homography in the pairs' normalised frames (8 entries,
/// the last fixed at 1) and, when `with_k1`, the distortion as the 9th.
struct Frames {
    t: Matrix3<f64>,
    t_prime_inverse: Matrix3<f64>,
    template: ScreenGeometry,
}

impl Frames {
    fn geometry(&self, p: &DVector<f64>) -> ScreenGeometry {
        let h = Matrix3::new(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], 1.0);
        let mut g = self.template.clone();
        g.homography = Homography::from_matrix(&(self.t_prime_inverse * h * self.t)).normalized();
        g.k1 = if p.len() > 8 { p[8] } else { 0.0 };
        g
    }

    fn params(&self, g: &ScreenGeometry, with_k1: bool) -> Option<DVector<f64>> {
        let t_prime = self.t_prime_inverse.try_inverse()?;
        let h = t_prime * g.homography.matrix() * self.t.try_inverse()?;
        if h[(2, 2)].abs() < 1e-12 {
            return None;
        }
        let h = h / h[(2, 2)];
        let mut v: Vec<f64> = (0..8).map(|i| h[(i / 3, i % 3)]).collect();
        if with_k1 {
            v.push(g.k1);
        }
        Some(DVector::from_vec(v))
    }
}

/// Minimises the reprojection error of `pairs` over the homography (and k1 when
/// `with_k1`) from `start`.
pub fn refine(start: &ScreenGeometry, pairs: &[Pair], with_k1: bool) -> Option<GeometryFit> {
    let frames = Frames {
        t: normalising(pairs.iter().map(|p| p.0)),
        t_prime_inverse: normalising(pairs.iter().map(|p| p.1)).try_inverse()?,
        template: start.clone(),
    };
    let x0 = frames.params(start, with_k1)?;
    let residual_vector = |p: &DVector<f64>| -> Option<DVector<f64>> {
        let r = residuals(&frames.geometry(p), pairs)?;
        Some(DVector::from_iterator(
            2 * r.len(),
            r.iter().flat_map(|r| [r.0, r.1]),
        ))
    };
    let best = levenberg_marquardt(x0, residual_vector, 100)?;
    let geometry = frames.geometry(&best);
    let residuals = residuals(&geometry, pairs)?;
    Some(GeometryFit {
        geometry,
        rms_px: rms(&residuals),
        residuals,
    })
}

/// The homography fitted to `pairs` (normalised DLT, then the reprojection error), and
/// with one radial coefficient where an F-test at 1 % says it lowers the residual
/// significantly and it removes at least a quarter of the RMS residual.
pub fn fit(template: &ScreenGeometry, pairs: &[Pair]) -> Option<(GeometryFit, Option<f64>)> {
    let mut start = template.clone();
    start.homography = dlt(pairs)?;
    start.k1 = 0.0;
    let plain = refine(&start, pairs, false)?;
    let n = 2 * pairs.len();
    if n <= 12 {
        return Some((plain, None));
    }
    let Some(distorted) = refine(&plain.geometry, pairs, true) else {
        return Some((plain, None));
    };
    let rss = |f: &GeometryFit| f.rms_px.powi(2) * pairs.len() as f64;
    let dof = (n - 9) as f64;
    let f = (rss(&plain) - rss(&distorted)) / (rss(&distorted) / dof).max(1e-300);
    let critical = FisherSnedecor::new(1.0, dof)
        .map(|d| d.inverse_cdf(0.99))
        .unwrap_or(f64::INFINITY);
    let p_value = FisherSnedecor::new(1.0, dof)
        .map(|d| 1.0 - d.cdf(f.max(0.0)))
        .ok();
    if f > critical && distorted.rms_px < MATERIAL_GAIN * plain.rms_px {
        Some((distorted, p_value))
    } else {
        Some((plain, p_value))
    }
}

/// Levenberg-Marquardt on a residual vector with a forward-difference Jacobian
/// (Marquardt's diagonal scaling); `None` when the start does not evaluate.
pub fn levenberg_marquardt(
    x0: DVector<f64>,
    f: impl Fn(&DVector<f64>) -> Option<DVector<f64>>,
    iterations: usize,
) -> Option<DVector<f64>> {
    let mut x = x0;
    let mut r = f(&x)?;
    let mut cost = r.norm_squared();
    let mut lambda = 1e-3;
    for _ in 0..iterations {
        let mut j = DMatrix::<f64>::zeros(r.len(), x.len());
        for k in 0..x.len() {
            let step = 1e-7 * x[k].abs().max(1e-3);
            let mut xp = x.clone();
            xp[k] += step;
            let rp = f(&xp)?;
            j.set_column(k, &((rp - &r) / step));
        }
        let jtj = j.transpose() * &j;
        let gradient = j.transpose() * &r;
        let mut improved = false;
        for _ in 0..10 {
            let mut a = jtj.clone();
            for k in 0..x.len() {
                a[(k, k)] += lambda * jtj[(k, k)].max(1e-12);
            }
            let Some(delta) = a.lu().solve(&(-&gradient)) else {
                lambda *= 10.0;
                continue;
            };
            let candidate = &x + &delta;
            if let Some(rc) = f(&candidate) {
                let c = rc.norm_squared();
                if c < cost {
                    let relative = (cost - c) / cost.max(1e-300);
                    x = candidate;
                    r = rc;
                    cost = c;
                    lambda = (lambda * 0.3).max(1e-12);
                    improved = relative > 1e-12;
                    break;
                }
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn truth() -> Homography {
        Homography([[0.82, 0.07, 31.0], [-0.04, 0.95, 12.0], [9e-4, -4e-4, 1.0]])
    }

    fn template() -> ScreenGeometry {
        ScreenGeometry::identity((240, 180), (240, 180))
    }

    fn grid() -> Vec<(f64, f64)> {
        (0..7)
            .flat_map(|i| (0..5).map(move |j| (20.0 + 30.0 * i as f64, 15.0 + 35.0 * j as f64)))
            .collect()
    }

    #[test]
    fn four_exact_points_give_the_homography() {
        let h = truth();
        let pairs: Vec<Pair> = [(0.0, 0.0), (240.0, 0.0), (240.0, 180.0), (0.0, 180.0)]
            .into_iter()
            .map(|s| (s, h.apply(s.0, s.1).unwrap()))
            .collect();
        let found = dlt(&pairs).unwrap();
        for r in 0..3 {
            for c in 0..3 {
                assert!((found.0[r][c] - h.0[r][c]).abs() < 1e-9 * (1.0 + h.0[r][c].abs()));
            }
        }
        // collinear points determine nothing
        let line: Vec<Pair> = (0..5)
            .map(|i| ((i as f64, i as f64), (i as f64, 0.0)))
            .collect();
        assert!(dlt(&line).is_none());
    }

    #[test]
    fn noisy_points_are_fitted_to_the_noise_level_without_distortion() {
        let h = truth();
        // deterministic pseudo-noise of +-0.3 px
        let pairs: Vec<Pair> = grid()
            .into_iter()
            .enumerate()
            .map(|(i, s)| {
                let q = h.apply(s.0, s.1).unwrap();
                let e = ((i * 7919) % 13) as f64 / 13.0 - 0.5;
                let f = ((i * 104_729) % 11) as f64 / 11.0 - 0.5;
                (s, (q.0 + 0.6 * e, q.1 + 0.6 * f))
            })
            .collect();
        let (fit, _) = fit(&template(), &pairs).unwrap();
        assert_eq!(fit.geometry.k1, 0.0, "no distortion in the data");
        assert!(fit.rms_px < 0.3, "{}", fit.rms_px);
        for s in grid() {
            let (a, b) = (
                h.apply(s.0, s.1).unwrap(),
                fit.geometry.to_sensor(s).unwrap(),
            );
            assert!((a.0 - b.0).hypot(a.1 - b.1) < 0.3, "{s:?}");
        }
    }

    #[test]
    fn distortion_is_fitted_when_the_points_call_for_it() {
        let mut g = template();
        g.homography = truth();
        g.k1 = -0.12;
        let pairs: Vec<Pair> = grid()
            .into_iter()
            .map(|s| (s, g.to_sensor(s).unwrap()))
            .collect();
        let (fit, _) = fit(&template(), &pairs).unwrap();
        assert!((fit.geometry.k1 + 0.12).abs() < 1e-4, "{}", fit.geometry.k1);
        assert!(fit.rms_px < 1e-4, "{}", fit.rms_px);
    }
}
