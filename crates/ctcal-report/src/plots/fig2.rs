//! The paper's Fig. 2 (Stoffregen et al. 2020): each sequence's events per pixel per second
//! as a dot per dataset, beside the calibration scene simulated at the presets CT 0.2 to 1.5.

use super::style::*;
use super::{DrawResult, FONT, Figure, err};
use crate::model::{Report, SequenceReport};
use plotters::coord::Shift;
use plotters::coord::combinators::WithKeyPoints;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::fmt::Write as _;

/// The paper's Fig. 2.
pub(super) struct Fig2<'a> {
    pub(super) report: &'a Report,
}

/// The chart of Fig. 2: dataset index across, events per pixel per second up (log).
type Fig2Chart<'a, DB> =
    ChartContext<'a, DB, Cartesian2d<RangedCoordf64, WithKeyPoints<LogCoord<f64>>>>;

impl Figure for Fig2<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        let datasets: Vec<&str> = self
            .report
            .datasets
            .iter()
            .map(|d| d.name.as_str())
            .collect();
        let n = datasets.len().max(1) as f64;
        let mut chart = self.axes(root, &datasets)?;
        for p in &self.report.presets {
            draw_preset(&mut chart, n, p.ct, p.events_per_pixel_per_second)?;
        }
        for (k, d) in self.report.datasets.iter().enumerate() {
            self.draw_dataset(&mut chart, n, k, &d.name)?;
        }
        Ok(())
    }

    fn csv(&self) -> String {
        let mut out = String::from("kind,dataset,sequence,ct,events_per_pixel_per_second\n");
        for s in &self.report.sequences {
            let _ = writeln!(
                out,
                "sequence,{},{},,{}",
                s.dataset,
                s.name,
                s.stats
                    .events_per_pixel_per_second
                    .map_or(String::new(), |v| v.to_string())
            );
        }
        for p in &self.report.presets {
            let _ = writeln!(out, "preset,,,{},{}", p.ct, p.events_per_pixel_per_second);
        }
        out
    }
}

impl Fig2<'_> {
    /// The chart with its caption and axes drawn: the `datasets` named across, a log axis
    /// up spanning every sequence's and preset's rate.
    fn axes<'a, DB: DrawingBackend>(
        &self,
        root: &'a DrawingArea<DB, Shift>,
        datasets: &[&str],
    ) -> Result<Fig2Chart<'a, DB>, String> {
        let n = datasets.len().max(1) as f64;
        let values = self
            .report
            .sequences
            .iter()
            .filter_map(|s| s.stats.events_per_pixel_per_second)
            .chain(
                self.report
                    .presets
                    .iter()
                    .map(|p| p.events_per_pixel_per_second),
            );
        let mut chart = ChartBuilder::on(root)
            .caption(
                "Events per pixel per second: sequences and simulated presets",
                (FONT, px(20)),
            )
            .margin(px(12))
            .x_label_area_size(px(45))
            .y_label_area_size(px(70))
            .build_cartesian_2d(-0.5f64..(n - 0.05), log_axis(log_range(values)))
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .y_label_formatter(&log_tick)
            .x_labels(datasets.len() * 2 + 1)
            .x_label_formatter(&|x| {
                let k = x.round();
                if (x - k).abs() < 0.01 && k >= 0.0 && (k as usize) < datasets.len() {
                    datasets[k as usize].to_string()
                } else {
                    String::new()
                }
            })
            .y_desc("events / pixel / s")
            .label_style((FONT, px(14)))
            .draw()
            .map_err(err)?;
        Ok(chart)
    }

    /// The `k`-th of `n` datasets, named `name`: a dot per sequence, spread across its
    /// place, each named beside it where at least 6 characters fit.
    fn draw_dataset<DB: DrawingBackend>(
        &self,
        chart: &mut Fig2Chart<'_, DB>,
        n: f64,
        k: usize,
        name: &str,
    ) -> DrawResult {
        let colour = PALETTE[k % PALETTE.len()];
        let members: Vec<&SequenceReport> = self
            .report
            .sequences
            .iter()
            .filter(|s| s.dataset == name)
            .collect();
        let count = members.len().max(1) as f64;
        let position = |i: usize| k as f64 + 0.5 * ((i as f64 + 0.5) / count - 0.5);
        chart
            .draw_series(members.iter().enumerate().filter_map(|(i, s)| {
                s.stats
                    .events_per_pixel_per_second
                    .map(|v| Circle::new((position(i), v), px(6), colour.filled()))
            }))
            .map_err(err)?;
        // sequence names beside their dots, cut to the room before the next dot (about
        // 7 pixels a character at this size); none where fewer than 6 characters fit
        let room_units = if members.len() > 1 { 0.5 / count } else { 0.7 };
        let pixels_per_unit = chart.plotting_area().dim_in_pixel().0 as f64 / n;
        let characters = (room_units * pixels_per_unit / 7.0) as usize;
        if characters >= 6 {
            chart
                .draw_series(members.iter().enumerate().filter_map(|(i, s)| {
                    s.stats.events_per_pixel_per_second.map(|v| {
                        Text::new(
                            shorten(&s.name, characters),
                            (position(i) + px(10) as f64 / pixels_per_unit, v),
                            (FONT, px(12)).into_font().color(&RGBColor(60, 60, 60)),
                        )
                    })
                }))
                .map_err(err)?;
        }
        Ok(())
    }
}

/// A preset's rate as a grey line across all `n` datasets, labelled with its threshold
/// `ct` at the right.
fn draw_preset<DB: DrawingBackend>(
    chart: &mut Fig2Chart<'_, DB>,
    n: f64,
    ct: f64,
    rate: f64,
) -> DrawResult {
    chart
        .draw_series(LineSeries::new(
            [(-0.5, rate), (n - 0.5, rate)],
            RGBColor(150, 150, 150).stroke_width(px(1)),
        ))
        .map_err(err)?;
    chart
        .draw_series(std::iter::once(Text::new(
            format!("CT {ct}"),
            (n - 0.45, rate),
            (FONT, px(13)).into_font().color(&RGBColor(90, 90, 90)),
        )))
        .map_err(err)?;
    Ok(())
}

/// `name` cut to `characters`, with an ellipsis where it was cut.
fn shorten(name: &str, characters: usize) -> String {
    if name.chars().count() <= characters {
        return name.to_string();
    }
    let kept: String = name.chars().take(characters.saturating_sub(1)).collect();
    format!("{kept}…")
}

#[cfg(test)]
mod tests {
    use super::shorten;

    #[test]
    fn long_names_are_cut_with_an_ellipsis() {
        assert_eq!(shorten("texture", 7), "texture");
        assert_eq!(shorten("texture_davis240c", 8), "texture…");
    }
}
