//! Histograms of the per-pixel thresholds (the mismatch across pixels).

use super::style::*;
use super::{DrawResult, FONT, Figure, err};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::fmt::Write as _;

/// Histograms of per-pixel thresholds.
pub(super) struct Histograms {
    pub(super) series: Vec<(String, Vec<f64>)>,
}

impl Histograms {
    pub(super) fn bins(&self) -> (f64, f64, Vec<Vec<f64>>) {
        let all: Vec<f64> = self
            .series
            .iter()
            .flat_map(|s| s.1.iter().copied())
            .filter(|v| v.is_finite())
            .collect();
        let mut sorted = all.clone();
        sorted.sort_by(f64::total_cmp);
        let hi = sorted
            .get((sorted.len().max(1) - 1) * 99 / 100)
            .copied()
            .unwrap_or(1.0)
            .max(1e-3)
            * 1.1;
        let n = 40;
        let width = hi / n as f64;
        let counts = self
            .series
            .iter()
            .map(|(_, values)| {
                let mut c = vec![0.0; n];
                for &v in values.iter().filter(|v| v.is_finite() && **v >= 0.0) {
                    c[((v / width) as usize).min(n - 1)] += 1.0;
                }
                c
            })
            .collect();
        (hi, width, counts)
    }
}

impl Figure for Histograms {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        let (hi, width, counts) = self.bins();
        let top = counts.iter().flatten().copied().fold(1.0, f64::max) * 1.1;
        let mut chart = ChartBuilder::on(root)
            .caption("Per-pixel thresholds (event timing)", (FONT, px(20)))
            .margin(px(12))
            .x_label_area_size(px(45))
            .y_label_area_size(px(60))
            .build_cartesian_2d(0f64..hi, 0f64..top)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_label_formatter(&linear_tick)
            .y_label_formatter(&linear_tick)
            .x_desc("threshold (log units)")
            .y_desc("pixels")
            .label_style((FONT, px(14)))
            .draw()
            .map_err(err)?;
        for (k, (label, _)) in self.series.iter().enumerate() {
            let colour = colour_for(label, k);
            chart
                .draw_series(counts[k].iter().enumerate().map(|(i, &c)| {
                    let x = i as f64 * width;
                    Rectangle::new([(x, 0.0), (x + width, c)], colour.mix(0.45).filled())
                }))
                .map_err(err)?
                .label(label.clone())
                .legend(move |(x, y)| {
                    Rectangle::new(
                        [(x, y - px(5) as i32), (x + px(15) as i32, y + px(5) as i32)],
                        colour.mix(0.45).filled(),
                    )
                });
        }
        // each bar as its top edge
        let tops: Vec<Vec<(f64, f64)>> = counts
            .iter()
            .map(|series| {
                series
                    .iter()
                    .enumerate()
                    .flat_map(|(i, &c)| [(i as f64 * width, c), ((i + 1) as f64 * width, c)])
                    .collect()
            })
            .collect();
        draw_legend(&mut chart, 14, &tops)?;
        Ok(())
    }

    fn csv(&self) -> String {
        let (_, width, counts) = self.bins();
        let mut out = format!(
            "bin_start,{}\n",
            self.series
                .iter()
                .map(|s| s.0.as_str())
                .collect::<Vec<_>>()
                .join(",")
        );
        for i in 0..counts.first().map_or(0, |c| c.len()) {
            let _ = writeln!(
                out,
                "{},{}",
                i as f64 * width,
                counts
                    .iter()
                    .map(|c| c[i].to_string())
                    .collect::<Vec<_>>()
                    .join(",")
            );
        }
        out
    }
}
