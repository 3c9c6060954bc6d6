//! The thresholds of every method for one sequence, with their 95 % intervals and the
//! truth where the recording carries it.

use super::style::*;
use super::{DrawResult, FONT, Figure, err};
use crate::estimate::Interval;
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::fmt::Write as _;

/// One method's thresholds with their 95 % intervals.
pub(super) struct MethodRow {
    pub(super) method: String,
    /// `None`: not determinable.
    pub(super) on: Option<f64>,
    /// A side is `None` where the interval is open (an extrapolation): drawn to the axis.
    pub(super) on_ci95: Option<Interval>,
    pub(super) off: Option<f64>,
    pub(super) off_ci95: Option<Interval>,
}

/// The thresholds of every method of a sequence.
pub(super) struct Methods {
    pub(super) rows: Vec<MethodRow>,
    pub(super) truth: Option<(f64, f64)>,
}

/// The chart of the method figure: method index across, threshold up.
type MethodChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// One polarity's marks: its x offset from the method's place, colour, legend label and
/// which thresholds of a row (0: ON, 1: OFF).
type Polarity = (f64, RGBColor, &'static str, usize);

impl Figure for Methods {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        let n = self.rows.len().max(1) as f64;
        let hi = self.top();
        let mut chart = self.axes(root, n, hi)?;
        let mut drawn: Vec<Vec<(f64, f64)>> = Vec::new();
        if let Some((on, off)) = self.truth {
            draw_truth(&mut chart, n, (on, off), &mut drawn)?;
        }
        for polarity in [
            (-0.1, PALETTE[0], "ON", 0usize),
            (0.1, PALETTE[1], "OFF", 1usize),
        ] {
            self.draw_polarity(&mut chart, polarity, hi, &mut drawn)?;
        }
        draw_legend(&mut chart, 14, &drawn)?;
        Ok(())
    }

    fn csv(&self) -> String {
        let mut out = String::from("method,ct_on,ct_on_lo,ct_on_hi,ct_off,ct_off_lo,ct_off_hi\n");
        let ci = |c: Option<Interval>| {
            let side = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
            c.map_or(",".to_string(), |[a, b]| format!("{},{}", side(a), side(b)))
        };
        let value = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
        for r in &self.rows {
            let _ = writeln!(
                out,
                "{},{},{},{},{}",
                r.method,
                value(r.on),
                ci(r.on_ci95),
                value(r.off),
                ci(r.off_ci95)
            );
        }
        if let Some((on, off)) = self.truth {
            let _ = writeln!(out, "truth,{on},,,{off},,");
        }
        out
    }
}

impl Methods {
    /// The top of the threshold axis: 15 % above the largest finite value, interval end or
    /// truth (at least 0.1).
    fn top(&self) -> f64 {
        let values: Vec<f64> = self
            .rows
            .iter()
            .flat_map(|r| {
                [r.on, r.off]
                    .into_iter()
                    .chain(r.on_ci95.into_iter().flatten())
                    .chain(r.off_ci95.into_iter().flatten())
                    .flatten()
            })
            .chain(self.truth.into_iter().flat_map(|t| [t.0, t.1]))
            .filter(|v| v.is_finite())
            .collect();
        values.iter().copied().fold(0.1, f64::max) * 1.15
    }

    /// The chart with its caption and axes drawn: `n` methods named across, thresholds
    /// from 0 to `hi` up.
    fn axes<'a, DB: DrawingBackend>(
        &self,
        root: &'a DrawingArea<DB, Shift>,
        n: f64,
        hi: f64,
    ) -> Result<MethodChart<'a, DB>, String> {
        let names: Vec<String> = self.rows.iter().map(|r| r.method.clone()).collect();
        let mut chart = ChartBuilder::on(root)
            .caption(
                "Contrast thresholds by method (95 % intervals)",
                (FONT, px(20)),
            )
            .margin(px(12))
            .x_label_area_size(px(45))
            .y_label_area_size(px(60))
            .build_cartesian_2d(-0.5f64..(n - 0.5), 0f64..hi)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .y_label_formatter(&linear_tick)
            .x_labels(self.rows.len().max(1))
            .x_label_formatter(&|x| {
                let k = x.round();
                if (x - k).abs() < 0.01 && k >= 0.0 && (k as usize) < names.len() {
                    names[k as usize].clone()
                } else {
                    String::new()
                }
            })
            .y_desc("threshold (log units)")
            .label_style((FONT, px(14)))
            .draw()
            .map_err(err)?;
        Ok(chart)
    }

    /// One polarity's (`pick`: 0 ON, 1 OFF) determined thresholds as (x, value, interval),
    /// x the method's place moved by `shift`.
    fn polarity_points(&self, pick: usize, shift: f64) -> Vec<(f64, f64, Option<Interval>)> {
        self.rows
            .iter()
            .enumerate()
            .filter_map(|(k, r)| {
                let (v, ci) = if pick == 0 {
                    (r.on, r.on_ci95)
                } else {
                    (r.off, r.off_ci95)
                };
                Some((k as f64 + shift, v?, ci))
            })
            .collect()
    }

    /// One polarity's thresholds: each method's dot and 95 % interval, an open side drawn
    /// thinner to the axis; every mark's extent added to `drawn` (for the legend's place).
    fn draw_polarity<DB: DrawingBackend>(
        &self,
        chart: &mut MethodChart<'_, DB>,
        (shift, colour, label, pick): Polarity,
        hi: f64,
        drawn: &mut Vec<Vec<(f64, f64)>>,
    ) -> DrawResult {
        let points = self.polarity_points(pick, shift);
        // an open side runs to the axis, drawn thinner
        let (bottom, top) = (0.0, hi);
        for (x, v, ci) in &points {
            let [lo, up] = ci.unwrap_or([Some(*v), Some(*v)]);
            drawn.push(vec![(*x, lo.unwrap_or(bottom)), (*x, up.unwrap_or(top))]);
        }
        chart
            .draw_series(points.iter().filter_map(|(x, v, ci)| {
                let [lo, up] = (*ci)?;
                Some(PathElement::new(
                    [(*x, lo.unwrap_or(*v)), (*x, up.unwrap_or(*v))],
                    colour.stroke_width(px(2)),
                ))
            }))
            .map_err(err)?;
        chart
            .draw_series(points.iter().flat_map(|(x, v, ci)| {
                let [lo, up] = ci.unwrap_or([Some(*v), Some(*v)]);
                [
                    lo.is_none().then_some((bottom, *v)),
                    up.is_none().then_some((*v, top)),
                ]
                .into_iter()
                .flatten()
                .map(|(a, b)| {
                    PathElement::new([(*x, a), (*x, b)], colour.mix(0.5).stroke_width(px(1)))
                })
                .collect::<Vec<_>>()
            }))
            .map_err(err)?;
        chart
            .draw_series(
                points
                    .iter()
                    .map(|(x, v, _)| Circle::new((*x, *v), px(6), colour.filled())),
            )
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| Circle::new((x + px(10) as i32, y), px(5), colour.filled()));
        Ok(())
    }
}

/// The true ON and OFF thresholds as faint lines across all `n` methods, added to `drawn`.
fn draw_truth<DB: DrawingBackend>(
    chart: &mut MethodChart<'_, DB>,
    n: f64,
    (on, off): (f64, f64),
    drawn: &mut Vec<Vec<(f64, f64)>>,
) -> DrawResult {
    drawn.push(vec![(-0.5, on), (n - 0.5, on)]);
    drawn.push(vec![(-0.5, off), (n - 0.5, off)]);
    for (value, colour, label) in [(on, PALETTE[0], "true ON"), (off, PALETTE[1], "true OFF")] {
        chart
            .draw_series(LineSeries::new(
                [(-0.5, value), (n - 0.5, value)],
                colour.mix(0.5).stroke_width(px(1)),
            ))
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| {
                PathElement::new([(x, y), (x + px(20) as i32, y)], colour.mix(0.5))
            });
    }
    Ok(())
}
