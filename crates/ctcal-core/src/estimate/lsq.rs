//! The cross-check of the threshold maps: a per-pixel least-squares fit of the log change
//! between frames against the ON and OFF counts in between (Wang, Ng, van Goor & Mahony,
//! "Event camera calibration of per-pixel biased contrast threshold", ACRA 2019):
//! `L(t_k+1) - L(t_k) = Cp n+_k - Cn n-_k + e_k`, where `e_k` is the change of the pixel's
//! residual (its level relative to its last event), bounded by one threshold. With about one
//! event per pixel and interval that residual is as large as the signal and biases the fit
//! towards zero (regression dilution: an interval with an event is more likely to start
//! near the threshold), so consecutive intervals are joined into spans holding a few events
//! per active pixel; the residual stays bounded while the signal grows. Summed over all
//! pixels the same normal equations give a global estimate, independent of event timing. The per-pixel fit is noisy (the residual is of the order of a threshold), which
//! is why ctcal's maps come from event timing ([`super::timing`]); their correlation with
//! this fit says whether the two agree.

use super::frames::PreparedFrames;
use crate::events::{EventChunk, Sensor};
use serde::Serialize;

/// The global least-squares estimate and the agreement of its per-pixel maps with others.
#[derive(Clone, Debug, Serialize)]
pub struct LeastSquares {
    pub ct_on: f64,
    pub ct_off: f64,
    /// Frame intervals joined into one span of the fit.
    pub intervals_per_span: usize,
    /// Pixels whose own fit is well conditioned.
    pub pixels: usize,
    /// Correlation of the per-pixel fits with the given maps (pixels where both exist).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub map_correlation_on: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub map_correlation_off: Option<f64>,
}

/// Normal equations `[a b; b c] [Cp; Cn] = [d; e]` of one pixel (or all).
#[derive(Clone, Copy, Default)]
struct Normal {
    a: f64,
    b: f64,
    c: f64,
    d: f64,
    e: f64,
}

impl Normal {
    fn add(&mut self, on: f64, off: f64, change: f64) {
        // residual: change - Cp on + Cn off
        self.a += on * on;
        self.b -= on * off;
        self.c += off * off;
        self.d += on * change;
        self.e -= off * change;
    }

    fn merge(&mut self, o: &Normal) {
        self.a += o.a;
        self.b += o.b;
        self.c += o.c;
        self.d += o.d;
        self.e += o.e;
    }

    /// (Cp, Cn) when the system is well conditioned.
    fn solve(&self) -> Option<(f64, f64)> {
        let det = self.a * self.c - self.b * self.b;
        if det <= 1e-9 * (self.a * self.c).max(1e-12) || self.a < 2.0 || self.c < 2.0 {
            return None;
        }
        Some((
            (self.c * self.d - self.b * self.e) / det,
            (self.a * self.e - self.b * self.d) / det,
        ))
    }
}

/// Events per active pixel a span should hold.
const EVENTS_PER_SPAN: f64 = 3.0;

/// Fits `frames` against `events`; `maps` (ON, OFF) are compared with the per-pixel fits.
pub fn fit(
    events: &EventChunk,
    frames: &PreparedFrames,
    sensor: Sensor,
    excluded: &[bool],
    maps: Option<(&[f32], &[f32])>,
) -> Option<LeastSquares> {
    let span = intervals_per_span(events, frames, sensor)?;
    let normals = span_normals(events, frames, sensor, excluded, span);
    let mut total = Normal::default();
    normals.iter().for_each(|n| total.merge(n));
    let (ct_on, ct_off) = total.solve()?;
    let fitted: Vec<Option<(f64, f64)>> = normals.iter().map(Normal::solve).collect();
    let correlation = |pick: fn((f64, f64)) -> f64, map: &[f32]| {
        let pairs: Vec<(f64, f64)> = fitted
            .iter()
            .zip(map)
            .filter_map(|(f, &m)| Some((pick((*f)?), m as f64)).filter(|_| m.is_finite()))
            .collect();
        correlation(&pairs)
    };
    Some(LeastSquares {
        ct_on,
        ct_off,
        intervals_per_span: span,
        pixels: fitted.iter().filter(|f| f.is_some()).count(),
        map_correlation_on: maps.and_then(|(m, _)| correlation(|f| f.0, m)),
        map_correlation_off: maps.and_then(|(_, m)| correlation(|f| f.1, m)),
    })
}

/// Intervals per span: enough that an active pixel holds [`EVENTS_PER_SPAN`] events, from
/// the events per active pixel and used interval (`None` without a used interval).
fn intervals_per_span(
    events: &EventChunk,
    frames: &PreparedFrames,
    sensor: Sensor,
) -> Option<usize> {
    let width = sensor.width as usize;
    let used: Vec<usize> = (0..frames.flows.len())
        .filter(|&k| frames.flows[k].is_some())
        .collect();
    let (first, last) = (
        frames.times[*used.first()?],
        frames.times[*used.last()? + 1],
    );
    let lo = events.t.partition_point(|&t| t < first);
    let hi = events.t.partition_point(|&t| t < last);
    let mut active = vec![false; sensor.pixels()];
    for i in lo..hi {
        active[events.y[i] as usize * width + events.x[i] as usize] = true;
    }
    let active = active.iter().filter(|&&a| a).count().max(1);
    let per_interval = (hi - lo) as f64 / (active * used.len()) as f64;
    Some(((EVENTS_PER_SPAN / per_interval.max(1e-9)).round() as usize).max(1))
}

/// Each pixel's normal equations over spans of `span` intervals of the frames' runs: its ON
/// and OFF counts against the log change between the span's ends, where the pixel fired
/// and its frames are reliable throughout.
fn span_normals(
    events: &EventChunk,
    frames: &PreparedFrames,
    sensor: Sensor,
    excluded: &[bool],
    span: usize,
) -> Vec<Normal> {
    let pixels = sensor.pixels();
    let width = sensor.width as usize;
    let mut normals = vec![Normal::default(); pixels];
    let mut on = vec![0u32; pixels];
    let mut off = vec![0u32; pixels];
    for (run_first, run_last) in frames.runs() {
        let mut start = run_first;
        while start < run_last {
            let end = (start + span).min(run_last);
            let (t0, t1) = (frames.times[start], frames.times[end]);
            on.iter_mut().for_each(|v| *v = 0);
            off.iter_mut().for_each(|v| *v = 0);
            let a = events.t.partition_point(|&t| t < t0);
            let b = events.t.partition_point(|&t| t < t1);
            for i in a..b {
                let p = events.y[i] as usize * width + events.x[i] as usize;
                if events.on[i] {
                    on[p] += 1;
                } else {
                    off[p] += 1;
                }
            }
            let (d0, d1) = (&frames.dn[start], &frames.dn[end]);
            for p in 0..pixels {
                if excluded[p]
                    || on[p] + off[p] == 0
                    || !(start..end).all(|k| frames.reliable(k, p))
                {
                    continue;
                }
                let change = frames.log(d1.data[p]) - frames.log(d0.data[p]);
                normals[p].add(on[p] as f64, off[p] as f64, change as f64);
            }
            start = end;
        }
    }
    normals
}

/// Pearson correlation of pairs (`None` for fewer than 10).
pub fn correlation(pairs: &[(f64, f64)]) -> Option<f64> {
    if pairs.len() < 10 {
        return None;
    }
    let n = pairs.len() as f64;
    let (ma, mb) = pairs
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let (mut cov, mut va, mut vb) = (0.0, 0.0, 0.0);
    for (x, y) in pairs {
        cov += (x - ma) * (y - mb);
        va += (x - ma).powi(2);
        vb += (y - mb).powi(2);
    }
    (va > 0.0 && vb > 0.0).then(|| cov / (va * vb).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_equations_recover_two_thresholds() {
        // changes made exactly of 0.25 per ON and 0.35 per OFF event
        let mut n = Normal::default();
        for (on, off) in [(3.0, 0.0), (0.0, 2.0), (2.0, 1.0), (1.0, 3.0), (4.0, 2.0)] {
            n.add(on, off, 0.25 * on - 0.35 * off);
        }
        let (cp, cn) = n.solve().unwrap();
        assert!(
            (cp - 0.25).abs() < 1e-9 && (cn - 0.35).abs() < 1e-9,
            "{cp} {cn}"
        );
        assert!(Normal::default().solve().is_none());
        assert!(
            (correlation(
                &(0..20)
                    .map(|i| (i as f64, 2.0 * i as f64 + 1.0))
                    .collect::<Vec<_>>()
            )
            .unwrap()
                - 1.0)
                .abs()
                < 1e-12
        );
    }
}
