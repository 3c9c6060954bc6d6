//! Per-pixel maps as heat maps with square pixels and a colour bar: the ON and OFF threshold
//! maps of `estimate aps`, and the event counts with the hot pixels circled.

use super::style::*;
use super::{DrawResult, FONT, Figure, err};
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::fmt::Write as _;

/// A per-pixel map drawn as a heat map, block-averaged to at most 180 cells a side.
pub(super) struct Heat {
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) values: Vec<f64>,
    pub(super) label: String,
}

impl Heat {
    pub(super) fn blocks(&self) -> (usize, usize, usize, Vec<f64>) {
        let block = self.width.max(self.height).div_ceil(180).max(1);
        let (bw, bh) = (self.width.div_ceil(block), self.height.div_ceil(block));
        let mut out = vec![f64::NAN; bw * bh];
        for by in 0..bh {
            for bx in 0..bw {
                let (mut sum, mut n) = (0.0, 0.0);
                for y in by * block..((by + 1) * block).min(self.height) {
                    for x in bx * block..((bx + 1) * block).min(self.width) {
                        let v = self.values[y * self.width + x];
                        if v.is_finite() {
                            sum += v;
                            n += 1.0;
                        }
                    }
                }
                if n > 0.0 {
                    out[by * bw + bx] = sum / n;
                }
            }
        }
        (block, bw, bh, out)
    }

    /// The 2nd and 98th percentiles of the finite values.
    pub(super) fn range(&self) -> (f64, f64) {
        let mut v: Vec<f64> = self
            .values
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .collect();
        if v.is_empty() {
            return (0.0, 1.0);
        }
        v.sort_by(f64::total_cmp);
        let q = |f: f64| v[((v.len() - 1) as f64 * f) as usize];
        let (lo, hi) = (q(0.02), q(0.98));
        if hi > lo { (lo, hi) } else { (lo, lo + 1.0) }
    }

    /// Draws the map on `area`: the heat map at its left with square pixels, `marks`
    /// circled on it, and its colour bar at the right.
    pub(super) fn draw_on<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        marks: &[(u16, u16)],
    ) -> DrawResult {
        let (lo, hi) = self.range();
        let (plot, bar) = area.split_horizontally(area.dim_in_pixel().0 as i32 - px(100) as i32);
        let layout = self.layout(plot.dim_in_pixel());
        self.draw_map(&plot, &layout, (lo, hi), marks)?;
        self.draw_colour_bar(&bar, &layout, (lo, hi))
    }

    /// The heat map's margins and label areas on a plot of `(pw, ph)` pixels, its pixels
    /// square: the spare room becomes margin.
    fn layout(&self, (pw, ph): (u32, u32)) -> Layout {
        let (margin, caption, x_labels, y_labels) = (px(8), px(30), px(30), px(45));
        let room_w = pw.saturating_sub(2 * margin + y_labels).max(1) as f64;
        let room_h = ph.saturating_sub(2 * margin + caption + x_labels).max(1) as f64;
        let scale = (room_w / self.width as f64).min(room_h / self.height as f64);
        Layout {
            margin,
            caption,
            x_labels,
            y_labels,
            spare_w: ((room_w - scale * self.width as f64) / 2.0).max(0.0) as u32,
            spare_h: ((room_h - scale * self.height as f64) / 2.0).max(0.0) as u32,
        }
    }

    /// The heat map: its axes, its blocks coloured from `lo` to `hi` (grey without a
    /// value), and `marks` circled.
    fn draw_map<DB: DrawingBackend>(
        &self,
        plot: &DrawingArea<DB, Shift>,
        layout: &Layout,
        (lo, hi): (f64, f64),
        marks: &[(u16, u16)],
    ) -> DrawResult {
        let Layout {
            margin,
            spare_w,
            spare_h,
            ..
        } = *layout;
        let mut chart = ChartBuilder::on(plot)
            .caption(&self.label, (FONT, px(17)))
            .margin(margin)
            .margin_left(margin + spare_w)
            .margin_right(margin + spare_w)
            .margin_top(margin + spare_h)
            .margin_bottom(margin + spare_h)
            .x_label_area_size(layout.x_labels)
            .y_label_area_size(layout.y_labels)
            .build_cartesian_2d(0f64..self.width as f64, self.height as f64..0f64)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_label_formatter(&linear_tick)
            .y_label_formatter(&linear_tick)
            .label_style((FONT, px(12)))
            .draw()
            .map_err(err)?;
        self.draw_blocks(&mut chart, (lo, hi))?;
        chart
            .draw_series(marks.iter().map(|&(x, y)| {
                Circle::new(
                    (x as f64 + 0.5, y as f64 + 0.5),
                    px(8),
                    RGBColor(230, 30, 30).stroke_width(px(2)),
                )
            }))
            .map_err(err)?;
        Ok(())
    }

    /// The map's blocks (of [`Self::blocks`]) coloured from `lo` to `hi`, grey without a
    /// value.
    fn draw_blocks<DB: DrawingBackend>(
        &self,
        chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
        (lo, hi): (f64, f64),
    ) -> DrawResult {
        let (block, bw, bh, values) = self.blocks();
        chart
            .draw_series((0..bh).flat_map(|by| {
                let values = &values;
                (0..bw).map(move |bx| {
                    let v = values[by * bw + bx];
                    let colour = if v.is_finite() {
                        viridis((v - lo) / (hi - lo))
                    } else {
                        RGBColor(225, 225, 225)
                    };
                    let (x0, y0) = ((bx * block) as f64, (by * block) as f64);
                    Rectangle::new(
                        [(x0, y0), (x0 + block as f64, y0 + block as f64)],
                        colour.filled(),
                    )
                })
            }))
            .map_err(err)?;
        Ok(())
    }

    /// The colour bar from `lo` to `hi` beside the map, as tall as its plot area.
    fn draw_colour_bar<DB: DrawingBackend>(
        &self,
        bar: &DrawingArea<DB, Shift>,
        layout: &Layout,
        (lo, hi): (f64, f64),
    ) -> DrawResult {
        let Layout {
            margin, spare_h, ..
        } = *layout;
        let mut scale = ChartBuilder::on(bar)
            .margin_top(margin + spare_h + layout.caption)
            .margin_bottom(margin + spare_h + layout.x_labels)
            .margin_left(px(6))
            .margin_right(px(4))
            .right_y_label_area_size(px(64))
            .build_cartesian_2d(0f64..1.0, lo..hi)
            .map_err(err)?;
        scale
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_labels(5)
            .y_label_formatter(&linear_tick)
            .y_desc(self.label.as_str())
            .axis_desc_style((FONT, px(12)))
            .label_style((FONT, px(11)))
            .draw()
            .map_err(err)?;
        scale
            .draw_series((0..64).map(|k| {
                let (a, b) = (
                    lo + (hi - lo) * k as f64 / 64.0,
                    lo + (hi - lo) * (k + 1) as f64 / 64.0,
                );
                Rectangle::new(
                    [(0.0, a), (1.0, b)],
                    viridis((k as f64 + 0.5) / 64.0).filled(),
                )
            }))
            .map_err(err)?;
        Ok(())
    }
}

/// Where a heat map sits on its plot (pixels): the margin, the caption's and the label
/// areas' sizes, and the spare room on each side that keeps its pixels square.
#[derive(Clone, Copy)]
struct Layout {
    margin: u32,
    caption: u32,
    x_labels: u32,
    y_labels: u32,
    spare_w: u32,
    spare_h: u32,
}

/// Per-pixel threshold maps, ON and OFF.
pub(super) struct ThresholdMaps {
    pub(super) on: Heat,
    pub(super) off: Heat,
}

impl Figure for ThresholdMaps {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        let (left, right) = root.split_horizontally(root.dim_in_pixel().0 as i32 / 2);
        self.on.draw_on(&left, &[])?;
        self.off.draw_on(&right, &[])
    }

    fn csv(&self) -> String {
        let mut out = String::from("x,y,ct_on,ct_off\n");
        for i in 0..self.on.values.len() {
            let (a, b) = (self.on.values[i], self.off.values[i]);
            if a.is_finite() || b.is_finite() {
                let show = |v: f64| {
                    if v.is_finite() {
                        v.to_string()
                    } else {
                        String::new()
                    }
                };
                let _ = writeln!(
                    out,
                    "{},{},{},{}",
                    i % self.on.width,
                    i / self.on.width,
                    show(a),
                    show(b)
                );
            }
        }
        out
    }
}

/// Per-pixel event counts with the hot pixels circled.
pub(super) struct Counts {
    pub(super) heat: Heat,
    pub(super) hot: Vec<(u16, u16)>,
}

impl Figure for Counts {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        self.heat.draw_on(root, &self.hot)
    }

    fn csv(&self) -> String {
        let mut out = String::from("x,y,log10_events_plus_1,hot\n");
        for (i, v) in self.heat.values.iter().enumerate() {
            let (x, y) = ((i % self.heat.width) as u16, (i / self.heat.width) as u16);
            if *v > 0.0 {
                let _ = writeln!(out, "{x},{y},{v},{}", self.hot.contains(&(x, y)) as u8);
            }
        }
        out
    }
}
