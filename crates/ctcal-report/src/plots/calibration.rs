//! The events-per-pixel-per-second against threshold calibration curve of `estimate eppps`,
//! with the recording's rate and the estimate marked.

use super::style::*;
use super::{DrawResult, FONT, Figure, err};
use plotters::coord::Shift;
use plotters::coord::combinators::WithKeyPoints;
use plotters::prelude::*;
use std::fmt::Write as _;

/// A point of the e/pix/s calibration curve.
#[derive(serde::Deserialize)]
pub(super) struct CurvePoint {
    pub(super) ct: f64,
    pub(super) events_per_pixel_per_second: f64,
    pub(super) lo: f64,
    pub(super) hi: f64,
}

/// The eppps calibration curve of a sequence.
pub(super) struct Calibration {
    pub(super) curve: Vec<CurvePoint>,
    pub(super) recording: f64,
    pub(super) estimate: f64,
}

/// The chart of the calibration curve: threshold across, events per pixel per second up,
/// both log.
type CalibrationChart<'a, DB> =
    ChartContext<'a, DB, Cartesian2d<WithKeyPoints<LogCoord<f64>>, WithKeyPoints<LogCoord<f64>>>>;

/// The thresholds across, the calibration's range.
const CT_RANGE: std::ops::Range<f64> = 0.07..2.2;

impl Figure for Calibration {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        let mut chart = self.axes(root)?;
        self.draw_simulated(&mut chart)?;
        self.draw_recording(&mut chart)?;
        let curve: Vec<(f64, f64)> = self
            .curve
            .iter()
            .map(|p| (p.ct, p.events_per_pixel_per_second))
            .collect();
        let data = [
            curve,
            vec![
                (CT_RANGE.start, self.recording),
                (CT_RANGE.end, self.recording),
            ],
            vec![(self.estimate, self.recording)],
        ];
        draw_legend(&mut chart, 14, &data)?;
        Ok(())
    }

    fn csv(&self) -> String {
        let mut out = String::from("ct,events_per_pixel_per_second,lo,hi\n");
        for p in &self.curve {
            let _ = writeln!(
                out,
                "{},{},{},{}",
                p.ct, p.events_per_pixel_per_second, p.lo, p.hi
            );
        }
        let _ = writeln!(out, "{},{},,", self.estimate, self.recording);
        out
    }
}

impl Calibration {
    /// The chart with its caption and axes drawn: the thresholds across, a log axis up
    /// spanning the curve's range and the recording's rate.
    fn axes<'a, DB: DrawingBackend>(
        &self,
        root: &'a DrawingArea<DB, Shift>,
    ) -> Result<CalibrationChart<'a, DB>, String> {
        let values = self
            .curve
            .iter()
            .flat_map(|p| [p.lo, p.hi, p.events_per_pixel_per_second])
            .chain([self.recording]);
        let mut chart = ChartBuilder::on(root)
            .caption(
                "Calibration curve: simulated scenes of matched dynamics",
                (FONT, px(20)),
            )
            .margin(px(12))
            .x_label_area_size(px(45))
            .y_label_area_size(px(70))
            .build_cartesian_2d(log_axis(CT_RANGE), log_axis(log_range(values)))
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_label_formatter(&log_tick)
            .y_label_formatter(&log_tick)
            .light_line_style(RGBColor(242, 242, 242))
            .x_desc("contrast threshold")
            .y_desc("events / pixel / s")
            .label_style((FONT, px(14)))
            .draw()
            .map_err(err)?;
        Ok(chart)
    }

    /// The simulated curve: its range over the scenes as a band, its mean as a line.
    fn draw_simulated<DB: DrawingBackend>(
        &self,
        chart: &mut CalibrationChart<'_, DB>,
    ) -> DrawResult {
        let band: Vec<(f64, f64)> = self
            .curve
            .iter()
            .map(|p| (p.ct, p.hi))
            .chain(self.curve.iter().rev().map(|p| (p.ct, p.lo)))
            .filter(|p| p.1 > 0.0)
            .collect();
        chart
            .draw_series(std::iter::once(Polygon::new(band, SIMULATED.mix(0.2))))
            .map_err(err)?;
        chart
            .draw_series(LineSeries::new(
                self.curve
                    .iter()
                    .map(|p| (p.ct, p.events_per_pixel_per_second)),
                SIMULATED.stroke_width(px(2)),
            ))
            .map_err(err)?
            .label("simulated (mean, range over scenes)")
            .legend(|(x, y)| {
                PathElement::new(
                    [(x, y), (x + px(20) as i32, y)],
                    SIMULATED.stroke_width(px(2)),
                )
            });
        Ok(())
    }

    /// The recording's rate as a line across, the estimate as a dot where it meets the
    /// curve.
    fn draw_recording<DB: DrawingBackend>(
        &self,
        chart: &mut CalibrationChart<'_, DB>,
    ) -> DrawResult {
        chart
            .draw_series(LineSeries::new(
                [
                    (CT_RANGE.start, self.recording),
                    (CT_RANGE.end, self.recording),
                ],
                RECORDING.stroke_width(px(2)),
            ))
            .map_err(err)?
            .label(format!("the recording: {:.3} e/pix/s", self.recording))
            .legend(|(x, y)| {
                PathElement::new(
                    [(x, y), (x + px(20) as i32, y)],
                    RECORDING.stroke_width(px(2)),
                )
            });
        chart
            .draw_series(std::iter::once(Circle::new(
                (self.estimate, self.recording),
                px(7),
                RECORDING.filled(),
            )))
            .map_err(err)?
            .label(format!("estimate CT {:.3}", self.estimate))
            .legend(|(x, y)| Circle::new((x + px(10) as i32, y), px(5), RECORDING.filled()));
        Ok(())
    }
}
