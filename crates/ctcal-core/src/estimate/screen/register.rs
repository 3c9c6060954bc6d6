//! Where the screen lies on the sensor, from the events of the played stimulus: a coarse
//! similarity ([`super::coarse`]), then alternately block-matched correspondences
//! ([`super::matching`]) and a homography fitted to them (normalised DLT and reprojection
//! error, one radial coefficient where an F-test asks for it, [`super::dlt`]), with
//! correspondences farther than three robust standard deviations (1.4826 MAD) from the fit
//! left out (a re-weighting in the spirit of Hartley & Zisserman Sec. 4.7, with a fixed
//! threshold instead of RANSAC since the start is already close), until the screen's
//! corners move less than 0.02 px.

use super::dlt::{self, Pair};
use super::images::{self, Stack};
use super::{coarse, matching};
use crate::events::{EventChunk, Frame, TimeUs};
use crate::sim::DisplayParams;
use crate::sim::log_response::LogMap;
use crate::sim::screen_geometry::{ScreenGeometry, ScreenWarp};
use std::sync::Arc;

/// Windows the stimulus is cut into.
const WINDOWS: usize = 8;
/// Correspondences a homography is fitted to at the least.
const MIN_POINTS: usize = 12;
/// Coarse correlation below which the screen is not found.
const MIN_COARSE_SCORE: f64 = 0.2;
/// Reprojection error (RMS) above which the registration is not trusted, pixels.
const MAX_RMS_PX: f64 = 1.5;

/// What the registration needs besides the geometry.
pub struct Inputs<'a> {
    pub events: &'a EventChunk,
    pub sensor: (usize, usize),
    pub excluded: &'a [bool],
    pub stimulus: &'a [Frame],
    pub offset_us: TimeUs,
    pub refresh_hz: f64,
    /// The sensor's log response the predictions are made through.
    pub log: LogMap,
}

/// What the stimulus is seen through: the display, then the sensor's log response.
#[derive(Clone, Copy)]
pub struct Through<'a> {
    pub display: &'a DisplayParams,
    pub log: LogMap,
}

/// A registered screen.
#[derive(Clone, Debug)]
pub struct Registration {
    pub geometry: ScreenGeometry,
    pub warp: Arc<ScreenWarp>,
    /// RMS and median of the inliers' reprojection residuals, sensor pixels.
    pub rms_px: f64,
    pub median_px: f64,
    pub points: usize,
    pub outliers: usize,
    /// The F-test's p-value for the radial coefficient (`None`: too few points to test).
    pub k1_p_value: Option<f64>,
    /// The coarse search's correlation.
    pub coarse_score: f64,
    pub iterations: usize,
    /// The stimulus points of the correspondences kept (where the geometry is measured).
    pub support: Vec<(f64, f64)>,
}

/// The events' images of the stimulus windows.
pub fn event_images(inputs: &Inputs) -> (Stack, Vec<(usize, usize)>) {
    let bounds = images::windows(inputs.stimulus.len(), WINDOWS);
    let stack = images::of_events(
        inputs.events,
        inputs.sensor,
        inputs.excluded,
        inputs.stimulus,
        &bounds,
        inputs.offset_us,
        1e6 / inputs.refresh_hz,
    );
    (stack, bounds)
}

fn corners(g: &ScreenGeometry) -> Vec<Option<(f64, f64)>> {
    let (w, h) = (g.stimulus.0 as f64, g.stimulus.1 as f64);
    [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)]
        .into_iter()
        .map(|s| g.to_sensor(s))
        .collect()
}

/// The largest distance between the stimulus corners' images under `a` and `b`.
pub fn corner_change(a: &ScreenGeometry, b: &ScreenGeometry) -> f64 {
    corners(a)
        .into_iter()
        .zip(corners(b))
        .map(|(p, q)| match (p, q) {
            (Some(p), Some(q)) => (p.0 - q.0).hypot(p.1 - q.1),
            _ => f64::INFINITY,
        })
        .fold(0.0, f64::max)
}

/// The largest distance between where `a` and `b` put the stimulus points `support`.
pub fn support_change(a: &ScreenGeometry, b: &ScreenGeometry, support: &[(f64, f64)]) -> f64 {
    support
        .iter()
        .map(|&s| match (a.to_sensor(s), b.to_sensor(s)) {
            (Some(p), Some(q)) => (p.0 - q.0).hypot(p.1 - q.1),
            _ => f64::INFINITY,
        })
        .fold(0.0, f64::max)
}

/// A fit and the correspondences it kept.
struct Robust {
    fit: dlt::GeometryFit,
    p_value: Option<f64>,
    outliers: usize,
    support: Vec<(f64, f64)>,
}

/// The robust fit: all pairs, then only those within three robust standard deviations
/// (at least 0.75 px) of the fit, twice.
fn robust_fit(template: &ScreenGeometry, pairs: &[Pair]) -> Option<Robust> {
    let mut kept: Vec<Pair> = pairs.to_vec();
    let mut result = dlt::fit(template, &kept)?;
    for _ in 0..2 {
        let distances: Vec<f64> = pairs
            .iter()
            .map(|&(s, q)| {
                result
                    .0
                    .geometry
                    .to_sensor(s)
                    .map_or(f64::INFINITY, |p| (p.0 - q.0).hypot(p.1 - q.1))
            })
            .collect();
        let mut sorted = distances.clone();
        sorted.sort_by(f64::total_cmp);
        let limit = (3.0 * 1.4826 * sorted[sorted.len() / 2]).max(0.75);
        kept = pairs
            .iter()
            .zip(&distances)
            .filter(|(_, d)| **d <= limit)
            .map(|(p, _)| *p)
            .collect();
        if kept.len() < MIN_POINTS {
            return None;
        }
        result = dlt::fit(template, &kept)?;
    }
    let outliers = pairs.len() - kept.len();
    let support = kept.iter().map(|p| p.0).collect();
    Some(Robust {
        fit: result.0,
        p_value: result.1,
        outliers,
        support,
    })
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Refines `start` against the events' images through `display`.
pub fn refine(
    real: &Stack,
    bounds: &[(usize, usize)],
    stimulus: &[Frame],
    through: Through,
    start: ScreenGeometry,
    first_radius: usize,
) -> Result<Registration, String> {
    let mut g = start;
    let mut radius = first_radius;
    let mut last = None;
    for number in 1..=8 {
        let (robust, count) = match_and_fit(real, bounds, stimulus, through, &g, radius)?;
        let change = corner_change(&g, &robust.fit.geometry);
        g = robust.fit.geometry.clone();
        last = Some(Iteration {
            robust,
            count,
            number,
        });
        if change < 0.02 {
            break;
        }
        radius = ((2.0 * change).ceil() as usize + 2).clamp(3, first_radius);
    }
    registered(last.expect("at least one iteration"))
}

/// One iteration of [`refine`]: the correspondences between the events' images and the
/// stimulus predicted through the geometry `g` (searched within `radius` px), and the
/// robust fit to them, with how many there were.
fn match_and_fit(
    real: &Stack,
    bounds: &[(usize, usize)],
    stimulus: &[Frame],
    through: Through,
    g: &ScreenGeometry,
    radius: usize,
) -> Result<(Robust, usize), String> {
    let warp = ScreenWarp::new(g);
    let predicted = images::predicted(stimulus, bounds, through, Some(&warp));
    let pairs = matching::correspondences(real, &predicted, &warp.on_screen(), g, radius);
    if pairs.len() < MIN_POINTS {
        return Err(format!(
            "only {} patches of the screen matched the stimulus (at least {MIN_POINTS} needed)",
            pairs.len()
        ));
    }
    let robust = robust_fit(g, &pairs)
        .ok_or("the matched points do not determine a homography (too few consistent ones)")?;
    Ok((robust, pairs.len()))
}

/// The last iteration of [`refine`]: its robust fit, the correspondences it was fitted to
/// and its number (counted from 1).
struct Iteration {
    robust: Robust,
    count: usize,
    number: usize,
}

/// The registration the last iteration gives; refused where its reprojection error is
/// above [`MAX_RMS_PX`].
fn registered(last: Iteration) -> Result<Registration, String> {
    let Iteration {
        robust:
            Robust {
                fit,
                p_value,
                outliers,
                support,
            },
        count,
        number,
    } = last;
    let mut norms: Vec<f64> = fit.residuals.iter().map(|r| r.0.hypot(r.1)).collect();
    let registration = Registration {
        warp: Arc::new(ScreenWarp::new(&fit.geometry)),
        geometry: fit.geometry,
        rms_px: fit.rms_px,
        median_px: median(&mut norms),
        points: count - outliers,
        outliers,
        k1_p_value: p_value,
        coarse_score: f64::NAN,
        iterations: number,
        support,
    };
    if registration.rms_px > MAX_RMS_PX {
        return Err(format!(
            "the screen's homography leaves {:.2} px RMS between the events and the stimulus (more than {MAX_RMS_PX} px)",
            registration.rms_px
        ));
    }
    Ok(registration)
}

/// Finds the screen: the coarse similarity, then [`refine`].
pub fn register(inputs: &Inputs, display: &DisplayParams) -> Result<Registration, String> {
    let (real, bounds) = event_images(inputs);
    if real.activity.iter().all(|im| im.iter().all(|&v| v == 0.0)) {
        return Err("no events fall in the stimulus's windows".into());
    }
    let stimulus_size = (
        inputs.stimulus[0].width as usize,
        inputs.stimulus[0].height as usize,
    );
    let through = Through {
        display,
        log: inputs.log,
    };
    let flat = images::predicted(inputs.stimulus, &bounds, through, None);
    let (pose, score) = coarse::search(&real, &flat)
        .ok_or("no placement of the stimulus on the sensor was tried")?;
    if score < MIN_COARSE_SCORE {
        return Err(format!(
            "the events' activity correlates with the stimulus's at {score:.2} at best (at least {MIN_COARSE_SCORE} needed): the stimulus does not seem to be on the sensor"
        ));
    }
    let mut start = ScreenGeometry::identity(stimulus_size, inputs.sensor);
    start.homography = pose.homography(stimulus_size);
    let fine_block = ((inputs.sensor.0 as f64 / 96.0).ceil()).max(1.0);
    let radius = (2.0 * fine_block).ceil() as usize + 3;
    let mut registration = refine(&real, &bounds, inputs.stimulus, through, start, radius)?;
    registration.coarse_score = score;
    Ok(registration)
}
