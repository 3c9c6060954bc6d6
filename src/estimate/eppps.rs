//! `estimate eppps`: the contrast threshold at which simulated scenes of the recording's
//! dynamics make as many events per pixel per second as the recording (Stoffregen et al.,
//! ECCV 2020, Sec. 3.1 and Fig. 2), made sound:
//!
//! - the calibration scenes are multi-object 2D scenes (their generator's "medium" class,
//!   [`crate::sim::scene::multi_object`]) whose motion is matched to the recording's, measured
//!   ([`super::dynamics`]): the flow speed of its frames, or without frames the edge speed
//!   of its events, matched at the threshold being estimated (that statistic depends on the
//!   threshold too, so speed and threshold are found together, by iteration);
//! - with frames, events per pixel per second are compared relative to the scene's rate of
//!   log-intensity change `R`, which removes the dependence on how much contrast the scene
//!   has; without frames, the textures' log contrast is that of natural images (the
//!   procedural texture's 1/f spectrum, log standard deviation 0.45);
//! - several scene samples (seeds) are simulated at thresholds 0.08-2.0; the calibration
//!   curve is inverted per sample, and the spread over samples is the interval;
//! - both the recording and the simulations go through the same spatio-temporal support
//!   filter, so that sensor noise (absent from the ideal simulation) does not count;
//! - the calibration scenes move everywhere, as the paper's did: a recording whose view is
//!   mostly static reads as a sensor with high thresholds. The share of the view that is
//!   active (8 x 8 pixel tiles x 50 ms windows holding at least 4 supported events) is
//!   reported, and said in the assumptions when it is small. (Comparing only active cells
//!   does not fix it: which cells count as active depends on the threshold itself.)
//!
//! ON and OFF thresholds come from inverting the ON and OFF rates separately.

use super::dynamics::{self, FrameDynamics};
use super::frames::PreparedFrames;
use super::interval::{Measured, z95};
use super::{CtEstimate, Determinable, EstimateError, EstimatorReport, Progress};
use crate::events::{EventChunk, Sensor, TimeUs};
use crate::sim::scene::canvas::TextureParams;
use crate::sim::scene::multi_object::MultiObjectScene;
use crate::sim::scene::{SceneKind, SceneSource, SceneSpec};
use crate::sim::{FrameSource, PixelParams, Sample};
use crate::stats::support::supported;
use serde::Serialize;
use serde_json::json;

/// The thresholds of the calibration curve.
pub const CT_GRID: [f64; 11] = [0.08, 0.12, 0.16, 0.2, 0.3, 0.4, 0.5, 0.75, 1.0, 1.5, 2.0];
/// The fixed presets of the paper's Fig. 2.
pub const PRESETS: [f64; 5] = [0.2, 0.5, 0.75, 1.0, 1.5];

/// Settings of `estimate eppps`.
#[derive(Clone, Debug)]
pub struct EpppsOptions {
    /// Scene samples (seeds).
    pub scenes: usize,
    /// Length of each calibration scene, seconds.
    pub duration_s: f64,
    /// Largest calibration scene, pixels (smaller sensors are simulated at their size).
    pub max_width: usize,
    pub max_height: usize,
    /// Use the frames' dynamics when there are frames.
    pub use_frames: bool,
    pub seed: u64,
}

impl Default for EpppsOptions {
    fn default() -> Self {
        Self {
            scenes: 4,
            duration_s: 1.0,
            max_width: 240,
            max_height: 180,
            use_frames: true,
            seed: 2020,
        }
    }
}

/// One point of the calibration curve.
#[derive(Clone, Debug, Serialize)]
pub struct CurvePoint {
    pub ct: f64,
    /// Mean over scene samples, and the range of the samples.
    pub events_per_pixel_per_second: f64,
    pub lo: f64,
    pub hi: f64,
}

/// Where the recording falls against one fixed preset of the paper's Fig. 2.
#[derive(Clone, Debug, Serialize)]
pub struct PresetPoint {
    pub ct: f64,
    /// The calibration scenes' events per pixel per second at this threshold, scaled to
    /// the recording's dynamics.
    pub events_per_pixel_per_second: f64,
}

/// Side of the activity tiles, pixels, and length of the activity windows.
const ACTIVITY_TILE: usize = 8;
const ACTIVITY_WINDOW_US: TimeUs = 50_000;
/// Supported events that make a tile-window cell active.
const ACTIVE_EVENTS: u32 = 4;

/// Events per pixel per second of `events` (ON, OFF; supported events over the kept
/// pixels), and the share of active tile-window cells.
struct Rates {
    on: f64,
    off: f64,
    active_fraction: f64,
}

fn rates(events: &EventChunk, sensor: Sensor, excluded: &[bool], window_us: TimeUs) -> Rates {
    let none = Rates {
        on: 0.0,
        off: 0.0,
        active_fraction: 0.0,
    };
    if events.len() < 2 {
        return none;
    }
    let support = supported(events, sensor, window_us);
    let width = sensor.width as usize;
    let tiles_x = width.div_ceil(ACTIVITY_TILE);
    let tiles = tiles_x * (sensor.height as usize).div_ceil(ACTIVITY_TILE);
    let first = events.t[0];
    let duration_us = events.t[events.len() - 1] - first;
    // one window of tiles at a time (events are time-sorted), so memory does not depend
    // on the time span
    let mut tile_counts = vec![0u32; tiles];
    let mut touched: Vec<usize> = Vec::new();
    let (mut active, mut window) = (0usize, 0 as TimeUs);
    let mut close_window = |counts: &mut [u32], touched: &mut Vec<usize>| {
        for &k in touched.iter() {
            active += (counts[k] >= ACTIVE_EVENTS) as usize;
            counts[k] = 0;
        }
        touched.clear();
    };
    let (mut on, mut off) = (0u64, 0u64);
    for (i, &is_supported) in support.iter().enumerate() {
        let (x, y) = (events.x[i] as usize, events.y[i] as usize);
        if !is_supported || excluded[y * width + x] {
            continue;
        }
        if events.on[i] {
            on += 1;
        } else {
            off += 1;
        }
        let w = (events.t[i] - first) / ACTIVITY_WINDOW_US;
        if w != window {
            close_window(&mut tile_counts, &mut touched);
            window = w;
        }
        let k = (y / ACTIVITY_TILE) * tiles_x + x / ACTIVITY_TILE;
        if tile_counts[k] == 0 {
            touched.push(k);
        }
        tile_counts[k] += 1;
    }
    close_window(&mut tile_counts, &mut touched);
    // every tile of every window of the span counts, busy or not
    let cells = tiles * ((duration_us / ACTIVITY_WINDOW_US) as usize + 1);
    let kept = excluded.iter().filter(|&&e| !e).count().max(1) as f64;
    let scale = 1.0 / (kept * (duration_us as f64 * 1e-6).max(1e-6));
    Rates {
        on: on as f64 * scale,
        off: off as f64 * scale,
        active_fraction: active as f64 / cells as f64,
    }
}

/// A calibration scene moving at about `speed` px/s.
fn scene(width: usize, height: usize, duration_s: f64, speed: f64, seed: u64) -> SceneSpec {
    let v = speed.max(1.0);
    SceneSpec {
        kind: SceneKind::MultiObject,
        width,
        height,
        duration_s,
        seed,
        render_hz: None,
        aps: None,
        texture: None,
        checkerboard: None,
        multi_object: Some(MultiObjectScene {
            objects: [3, 8],
            background_velocity_px_s: [0.8 * v, 1.2 * v],
            background_angular_velocity_deg_s: [0.0, 10.0],
            background_scale: [1.0, 1.3],
            object_velocity_px_s: [0.5 * v, 1.5 * v],
            object_angular_velocity_deg_s: [0.0, 20.0],
            object_scale: [0.5, 1.2],
            object_size_px: [12.0, 40.0],
            textures_dir: None,
            background_texture: TextureParams::default(),
        }),
    }
}

/// A rendered calibration scene: its samples, and its log-intensity change rate.
struct Rendered {
    samples: Vec<Sample>,
    width: usize,
    height: usize,
    log_change_rate: f64,
}

fn render(spec: &SceneSpec) -> Result<Rendered, EstimateError> {
    let bug = |e: crate::sim::SimError| {
        EstimateError::new(format!("calibration scene: {e}"), "report this as a bug")
    };
    let realised = spec.realise().map_err(bug)?;
    let mut source = SceneSource::new(spec, realised);
    let mut samples = Vec::new();
    while let Some(sample) = source.next_frame().map_err(bug)? {
        samples.push(sample);
    }
    let log = crate::sim::log_response::LogMap::new(crate::sim::LogResponse::V2e, 0.001);
    let mut variation = 0.0f64;
    for pair in samples.windows(2) {
        variation += pair[0]
            .dn
            .iter()
            .zip(&pair[1].dn)
            .map(|(&a, &b)| (log.apply(b) - log.apply(a)).abs() as f64)
            .sum::<f64>();
    }
    let duration = (samples[samples.len() - 1].t - samples[0].t) as f64 * 1e-6;
    Ok(Rendered {
        log_change_rate: variation / ((spec.width * spec.height) as f64 * duration),
        width: spec.width,
        height: spec.height,
        samples,
    })
}

fn simulate(rendered: &Rendered, ct: f64) -> Result<EventChunk, EstimateError> {
    super::resim::simulate(
        std::slice::from_ref(&rendered.samples),
        rendered.width,
        rendered.height,
        &PixelParams::ideal(ct, ct),
    )
}

/// The calibration curve of one rendered scene: (ON, OFF) rates and the active fraction
/// per grid threshold; thresholds outside `near` (a range around the current estimate)
/// are not simulated and read as NaN.
fn curve(
    rendered: &Rendered,
    window_us: TimeUs,
    near: (f64, f64),
) -> Result<Vec<(f64, f64, f64)>, EstimateError> {
    let sensor = Sensor::new(rendered.width as u16, rendered.height as u16);
    let excluded = vec![false; sensor.pixels()];
    CT_GRID
        .iter()
        .map(|&ct| {
            if ct < near.0 || ct > near.1 {
                return Ok((f64::NAN, f64::NAN, f64::NAN));
            }
            let r = rates(&simulate(rendered, ct)?, sensor, &excluded, window_us);
            Ok((r.on, r.off, r.active_fraction))
        })
        .collect()
}

/// The threshold at which a decreasing curve `rate(ct)` (on [`CT_GRID`]) reaches `target`,
/// interpolated in log-log; `None` outside the curve.
fn invert(rates: &[f64], target: f64) -> Option<f64> {
    for k in 0..CT_GRID.len() - 1 {
        let (r0, r1) = (rates[k], rates[k + 1]);
        if r0 >= target && target >= r1 && r0 > 0.0 && r1 > 0.0 {
            let f = (target.ln() - r0.ln()) / (r1.ln() - r0.ln());
            return Some((CT_GRID[k].ln() + f * (CT_GRID[k + 1].ln() - CT_GRID[k].ln())).exp());
        }
    }
    None
}

/// What `estimate eppps` reads.
pub struct EpppsInput<'a> {
    pub sensor: Sensor,
    pub events: &'a EventChunk,
    /// The recording's frames, prepared (when it has frames and they are used).
    pub frames: Option<&'a PreparedFrames>,
    pub excluded: &'a [bool],
}

/// Estimates the threshold of `input` by events per pixel per second.
pub fn estimate(
    input: &EpppsInput,
    options: &EpppsOptions,
    progress: Progress,
) -> Result<CtEstimate, EstimateError> {
    let (excluded, hot) = super::exclude_hot_pixels(input.events, input.sensor, input.excluded);
    let mut assumptions = Vec::new();
    if hot > 0 {
        assumptions.push(format!("{hot} hot pixels left out"));
    }
    let duration = (input.events.t[input.events.len() - 1] - input.events.t[0]) as f64 * 1e-6;
    if input.events.len() < 1000 || duration <= 0.0 {
        return Err(EstimateError::new(
            format!(
                "{} events over {duration:.3} s are too few to measure a rate",
                input.events.len()
            ),
            "use a longer part of the recording",
        ));
    }
    let frame_dynamics: Option<FrameDynamics> = if options.use_frames {
        input.frames.and_then(|f| dynamics::from_frames(f, 0.5))
    } else {
        None
    };
    let (width, height) = calibration_size(input.sensor, options);
    progress("dynamics of the recording", 0.0);
    let mut speed = match &frame_dynamics {
        Some(d) => d.speed_median_px_s,
        None => dynamics::edge_speed(input.events, input.sensor, 200_000).ok_or_else(|| {
            EstimateError::new(
                "too few moving edges in the events to measure their speed",
                "use a part of the recording where the scene moves",
            )
        })?,
    };
    let support_us =
        |speed: f64| ((3.0 / speed.max(1e-3)) * 1e6).clamp(30_000.0, 100_000.0) as TimeUs;
    let mut estimate: f64;
    let mut renders: Vec<Rendered> = Vec::new();
    let mut curves: Vec<Vec<(f64, f64, f64)>> = Vec::new();
    let mut real = rates(input.events, input.sensor, &excluded, support_us(speed));
    // without frames: the edge-speed statistic depends on the threshold, so speed and
    // threshold are matched together, in three rounds: the threshold at the events' own
    // speed, then twice the speed re-matched at the threshold found (the intermediate
    // rounds with two scene samples, the second only near the estimate); with frames one
    // round suffices
    let rounds = if frame_dynamics.is_some() { 1 } else { 3 };
    let mut near = (0.0, f64::INFINITY);
    // the recording's own edge speed (without frames, where the search starts)
    let real_speed = speed;
    let mut real_window = support_us(speed);
    let mut round = 0;
    while round < rounds {
        progress(
            "simulating calibration scenes",
            (round as f64 + 0.1) / rounds as f64,
        );
        let window = support_us(speed);
        if window != real_window {
            real = rates(input.events, input.sensor, &excluded, window);
            real_window = window;
        }
        // a few hundred pixels of travel are enough: fast scenes are simulated shorter
        let length = (300.0 / speed.max(1.0)).clamp(0.25, options.duration_s);
        let samples = if round + 1 < rounds {
            options.scenes.min(2)
        } else {
            options.scenes
        };
        renders = (0..samples)
            .map(|k| {
                render(&scene(
                    width,
                    height,
                    length,
                    speed,
                    options.seed + k as u64,
                ))
            })
            .collect::<Result<_, _>>()?;
        let range = if round + 1 == rounds {
            (0.0, f64::INFINITY)
        } else {
            near
        };
        curves = renders
            .iter()
            .map(|r| curve(r, window, range))
            .collect::<Result<_, _>>()?;
        let normalised = |rates: &[f64], rendered: &Rendered| -> Vec<f64> {
            match &frame_dynamics {
                Some(d) => rates
                    .iter()
                    .map(|r| r * d.log_change_rate / rendered.log_change_rate)
                    .collect(),
                None => rates.to_vec(),
            }
        };
        let mut found = Vec::new();
        for (c, r) in curves.iter().zip(&renders) {
            let total: Vec<f64> = c.iter().map(|(a, b, _)| a + b).collect();
            if let Some(ct) = invert(&normalised(&total, r), real.on + real.off) {
                found.push(ct);
            }
        }
        if found.is_empty() {
            // outside the simulated range: the next round simulates every threshold
            near = (0.0, f64::INFINITY);
            round += 1;
            continue;
        }
        estimate = found.iter().sum::<f64>() / found.len() as f64;
        near = (estimate / 1.8, estimate * 1.8);
        if frame_dynamics.is_none() && round + 1 < rounds {
            // the edge speed of a calibration scene at the estimate, against the recording's
            let scene_events = simulate(&renders[0], estimate)?;
            let scene_sensor = Sensor::new(width as u16, height as u16);
            let Some(scene_speed) = dynamics::edge_speed(&scene_events, scene_sensor, 200_000)
            else {
                break;
            };
            let correction = (real_speed / scene_speed).clamp(0.25, 4.0);
            speed *= correction;
            // matched within 10 %: the next round is the last
            if (correction - 1.0).abs() < 0.1 {
                round = rounds - 1;
                continue;
            }
        }
        round += 1;
    }
    progress("inverting the calibration curves", 0.9);
    let scale = |r: &Rendered| {
        frame_dynamics
            .as_ref()
            .map_or(1.0, |d| d.log_change_rate / r.log_change_rate)
    };
    let invert_each = |pick: fn(&(f64, f64, f64)) -> f64, target: f64| -> Vec<f64> {
        curves
            .iter()
            .zip(&renders)
            .filter_map(|(c, r)| {
                let rates: Vec<f64> = c.iter().map(|p| pick(p) * scale(r)).collect();
                invert(&rates, target)
            })
            .collect()
    };
    let on_samples = invert_each(|p| p.0, real.on);
    let off_samples = invert_each(|p| p.1, real.off);
    let measure = |samples: &[f64], which: &str| -> Result<Measured, EstimateError> {
        if samples.is_empty() {
            return Err(EstimateError::new(
                format!(
                    "the recording's {which} rate lies outside the calibration curve (thresholds {} to {})",
                    CT_GRID[0],
                    CT_GRID[CT_GRID.len() - 1]
                ),
                "check that the recording shows a moving scene (not noise or flicker), or use `estimate aps`",
            ));
        }
        let n = samples.len() as f64;
        let mean = samples.iter().sum::<f64>() / n;
        let sd = if samples.len() > 1 {
            (samples.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
        } else {
            0.1 * mean
        };
        // the scenes differ from the recording by more than their own spread: the
        // dynamics are matched on one or two statistics only; 10 % of the value stays as a
        // systematic error of that match
        Ok(Measured::new(
            mean,
            sd / n.sqrt(),
            (sd.powi(2) + (0.1 * mean).powi(2)).sqrt(),
        ))
    };
    let on = measure(&on_samples, "ON")?;
    let off = measure(&off_samples, "OFF")?;
    let mut result = CtEstimate::from_parts(
        "eppps",
        &on,
        &off,
        Determinable {
            lo: CT_GRID[0],
            hi: CT_GRID[CT_GRID.len() - 1],
            what: "the calibration curve",
        },
    );
    // the calibration curve (rate where the scene moves, as inverted) and the presets
    let point = |k: usize| -> CurvePoint {
        let values: Vec<f64> = curves
            .iter()
            .zip(&renders)
            .map(|(c, r)| (c[k].0 + c[k].1) * scale(r))
            .collect();
        let n = values.len() as f64;
        CurvePoint {
            ct: CT_GRID[k],
            events_per_pixel_per_second: values.iter().sum::<f64>() / n,
            lo: values.iter().copied().fold(f64::INFINITY, f64::min),
            hi: values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    };
    let calibration_curve: Vec<CurvePoint> = (0..CT_GRID.len()).map(point).collect();
    let presets: Vec<PresetPoint> = PRESETS
        .iter()
        .filter_map(|&ct| {
            let k = CT_GRID.iter().position(|&g| (g - ct).abs() < 1e-9)?;
            Some(PresetPoint {
                ct,
                events_per_pixel_per_second: calibration_curve[k].events_per_pixel_per_second,
            })
        })
        .collect();
    let real_total = real.on + real.off;
    let scene_active = curves
        .iter()
        .filter_map(|c| {
            let k = CT_GRID
                .iter()
                .position(|&g| g >= estimate_mean(&on_samples, &off_samples))?;
            Some(c[k].2)
        })
        .fold(0.0f64, f64::max);
    if real.active_fraction < 0.5 * scene_active {
        assumptions.push(format!(
            "only {:.0} % of the recording's view is active (calibration scenes: {:.0} %): the method assumes the whole view moves, so this estimate is biased high; prefer `estimate aps` or a part of the recording where more moves",
            100.0 * real.active_fraction,
            100.0 * scene_active
        ));
    }
    let between = presets
        .windows(2)
        .find(|w| {
            w[0].events_per_pixel_per_second >= real_total
                && real_total >= w[1].events_per_pixel_per_second
        })
        .map(|w| format!("between the presets CT {} and CT {}", w[0].ct, w[1].ct))
        .unwrap_or_else(|| {
            if presets
                .first()
                .is_some_and(|p| real_total > p.events_per_pixel_per_second)
            {
                format!("above the CT {} preset", PRESETS[0])
            } else {
                format!("below the CT {} preset", PRESETS[PRESETS.len() - 1])
            }
        });
    assumptions.push(match &frame_dynamics {
        Some(d) => format!(
            "dynamics from the frames: flow speed {:.1} px/s (median), log-intensity change {:.2} per pixel per second; rates compared relative to it",
            d.speed_median_px_s, d.log_change_rate
        ),
        None => format!(
            "dynamics from the events: calibration scenes moving at {speed:.1} px/s match the recording's edge speed; their textures have natural-image contrast (1/f spectrum, log std 0.45)"
        ),
    });
    assumptions.push(format!(
        "{} multi-object calibration scenes of {width}x{height} px, {} s each, ideal pixels (ON = OFF threshold); only events with spatio-temporal support counted, in the recording and the scenes alike",
        options.scenes, options.duration_s
    ));
    result.assumptions = assumptions;
    result.estimators = vec![EstimatorReport {
        name: "events_per_pixel_per_second",
        description: "the threshold at which calibration scenes of matched dynamics make the recording's ON (OFF) events per pixel per second; mean over scene samples",
        ct_on: on,
        ct_off: off,
        frame_rate_series_on: Vec::new(),
        frame_rate_series_off: Vec::new(),
        details: json!({
            "per_scene_on": on_samples,
            "per_scene_off": off_samples,
            "z95": z95(),
        }),
    }];
    result
        .extra
        .insert("calibration_curve".into(), json!(calibration_curve));
    result.extra.insert("presets".into(), json!(presets));
    result
        .extra
        .insert("preset_position".into(), json!(between));
    result.extra.insert(
        "recording".into(),
        json!({
            "events_per_pixel_per_second": real_total,
            "on_per_pixel_per_second": real.on,
            "off_per_pixel_per_second": real.off,
            "active_fraction": real.active_fraction,
            "counted": "events with spatio-temporal support over the kept pixels; active fraction: share of 8 x 8 px x 50 ms cells holding at least 4 of them",
            "frame_dynamics": frame_dynamics,
            "matched_speed_px_s": speed,
        }),
    );
    progress("done", 1.0);
    Ok(result)
}

/// The mean of the ON and OFF samples' means (0 without samples).
fn estimate_mean(on: &[f64], off: &[f64]) -> f64 {
    let all: Vec<f64> = on.iter().chain(off).copied().collect();
    if all.is_empty() {
        0.0
    } else {
        all.iter().sum::<f64>() / all.len() as f64
    }
}

/// The calibration scenes' size: the sensor's, scaled down (keeping its shape) to fit the
/// largest calibration scene.
fn calibration_size(sensor: Sensor, options: &EpppsOptions) -> (usize, usize) {
    let (w, h) = (sensor.width as f64, sensor.height as f64);
    let scale = (options.max_width as f64 / w)
        .min(options.max_height as f64 / h)
        .min(1.0);
    (
        ((w * scale).round() as usize).max(32),
        ((h * scale).round() as usize).max(32),
    )
}
