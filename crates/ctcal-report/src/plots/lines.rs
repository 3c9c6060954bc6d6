//! Named (x, y) series on linear or logarithmic axes: rate timelines, residuals of the fit
//! and same-pixel interval distributions; two side by side as a pair.

use super::style::*;
use super::{DrawResult, FONT, Figure, err};
use plotters::coord::Shift;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::fmt::Write as _;

/// A set of named (x, y) series on linear or log axes.
pub(super) struct Lines {
    pub(super) title: String,
    pub(super) x_label: String,
    pub(super) y_label: String,
    pub(super) log_x: bool,
    pub(super) series: Vec<(String, Vec<(f64, f64)>)>,
    /// Draw a horizontal line at zero.
    pub(super) zero: bool,
}

impl Figure for Lines {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        let (x0, x1, y0, y1) = self.extent();
        if self.log_x {
            let range = (x0 / 1.3)..(x1 * 1.3);
            let chart = self
                .builder(root)
                .build_cartesian_2d(log_axis(range), y0..y1)
                .map_err(err)?;
            self.draw_on_chart(chart, (x0, x1))?;
        } else {
            let px = ((x1 - x0) * 0.02).max(1e-9);
            let chart = self
                .builder(root)
                .build_cartesian_2d((x0 - px)..(x1 + px), y0..y1)
                .map_err(err)?;
            self.draw_on_chart(chart, (x0, x1))?;
        }
        Ok(())
    }

    fn csv(&self) -> String {
        let mut out = String::from("series,x,y\n");
        for (label, points) in &self.series {
            for (x, y) in points {
                let _ = writeln!(out, "{},{x},{y}", label.replace(',', ";"));
            }
        }
        out
    }
}

impl Lines {
    /// The data's extent (x0, x1, y0, y1): of the finite points (x > 0 on a log axis), with
    /// zero where a zero line is drawn, y padded by 8 %; 1 to 10 by 0 to 1 without data.
    fn extent(&self) -> (f64, f64, f64, f64) {
        let points = || {
            self.series
                .iter()
                .flat_map(|s| s.1.iter())
                .filter(|p| p.0.is_finite() && p.1.is_finite())
        };
        let (mut x0, mut x1, mut y0, mut y1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for &(x, y) in points() {
            if self.log_x && x <= 0.0 {
                continue;
            }
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
        if !x0.is_finite() {
            (x0, x1, y0, y1) = (1.0, 10.0, 0.0, 1.0);
        }
        if self.zero {
            y0 = y0.min(0.0);
            y1 = y1.max(0.0);
        }
        let pad = ((y1 - y0) * 0.08).max(1e-6);
        (x0, x1, y0 - pad, y1 + pad)
    }

    /// The chart's builder: the title, margin and label areas.
    fn builder<'a, DB: DrawingBackend>(
        &self,
        root: &'a DrawingArea<DB, Shift>,
    ) -> ChartBuilder<'a, '_, DB> {
        let mut b = ChartBuilder::on(root);
        b.caption(self.title.as_str(), (FONT, px(19)))
            .margin(px(12))
            .x_label_area_size(px(45))
            .y_label_area_size(px(65));
        b
    }

    /// Everything on the chart (linear or log x from `x0` to `x1`): the mesh, the zero line,
    /// the series and (for more than one) their legend.
    fn draw_on_chart<'a, DB: DrawingBackend + 'a, X>(
        &self,
        mut chart: ChartContext<'a, DB, Cartesian2d<X, RangedCoordf64>>,
        (x0, x1): (f64, f64),
    ) -> DrawResult
    where
        X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let mut mesh = chart.configure_mesh();
        mesh.x_desc(self.x_label.as_str())
            .y_desc(self.y_label.as_str())
            .light_line_style(RGBColor(242, 242, 242))
            .y_label_formatter(&linear_tick)
            .label_style((FONT, px(14)));
        if self.log_x {
            mesh.x_label_formatter(&|v: &f64| log_tick(v));
        } else {
            mesh.x_label_formatter(&|v: &f64| linear_tick(v));
        }
        mesh.draw().map_err(err)?;
        if self.zero {
            chart
                .draw_series(LineSeries::new([(x0, 0.0), (x1, 0.0)], BLACK.mix(0.4)))
                .map_err(err)?;
        }
        let drawn = self.draw_each_series(&mut chart)?;
        if self.series.len() > 1 {
            draw_legend(&mut chart, 13, &drawn)?;
        }
        Ok(())
    }

    /// Each series as a line with dots at its points (the finite ones, x > 0 on a log
    /// axis), labelled for the legend; returns the points drawn.
    fn draw_each_series<DB: DrawingBackend, X>(
        &self,
        chart: &mut ChartContext<'_, DB, Cartesian2d<X, RangedCoordf64>>,
    ) -> Result<Vec<Vec<(f64, f64)>>, String>
    where
        X: Ranged<ValueType = f64>,
    {
        let mut drawn = Vec::new();
        for (k, (label, series)) in self.series.iter().enumerate() {
            let colour = colour_for(label, k);
            let valid: Vec<(f64, f64)> = series
                .iter()
                .copied()
                .filter(|p| p.0.is_finite() && p.1.is_finite() && (!self.log_x || p.0 > 0.0))
                .collect();
            chart
                .draw_series(LineSeries::new(valid.clone(), colour.stroke_width(px(2))))
                .map_err(err)?
                .label(label.clone())
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + px(20) as i32, y)], colour.stroke_width(px(2)))
                });
            chart
                .draw_series(
                    valid
                        .iter()
                        .map(|&p| Circle::new(p, px(3), colour.filled())),
                )
                .map_err(err)?;
            drawn.push(valid);
        }
        Ok(drawn)
    }
}

/// Two line figures side by side.
pub(super) struct Pair(pub(super) Lines, pub(super) Lines);

impl Figure for Pair {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        let (left, right) = root.split_horizontally(root.dim_in_pixel().0 as i32 / 2);
        self.0.draw(&left)?;
        self.1.draw(&right)
    }

    fn csv(&self) -> String {
        let mut out = String::from("panel,series,x,y\n");
        for (panel, lines) in [(&self.0.title, &self.0), (&self.1.title, &self.1)] {
            for line in lines.csv().lines().skip(1) {
                let _ = writeln!(out, "{},{line}", panel.replace(',', ";"));
            }
        }
        out
    }
}
