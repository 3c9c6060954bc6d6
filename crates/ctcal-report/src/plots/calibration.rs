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

/// The points of the curve a log axis can show: those whose rate is above zero (the
/// simulated scenes gave events). A threshold so high that no scene gave any is in the CSV,
/// not on the chart, which would draw it as a stroke along its lower edge.
fn drawable(curve: &[CurvePoint]) -> impl Iterator<Item = &CurvePoint> {
    curve.iter().filter(|p| p.events_per_pixel_per_second > 0.0)
}

/// The thresholds across: the drawable curve's and the estimate's, a tenth wider on
/// either side (an estimate beyond the curve, an extrapolation, is drawn where it is).
fn ct_range(curve: &[CurvePoint], estimate: f64) -> std::ops::Range<f64> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for ct in drawable(curve).map(|p| p.ct).chain([estimate]) {
        if ct.is_finite() && ct > 0.0 {
            lo = lo.min(ct);
            hi = hi.max(ct);
        }
    }
    if !lo.is_finite() {
        return 0.07..2.2;
    }
    (lo / 1.1)..(hi * 1.1)
}

impl Calibration {
    /// Whether the estimate lies outside the thresholds simulated (an extrapolation).
    fn extrapolated(&self) -> bool {
        let cts = self.curve.iter().map(|p| p.ct);
        let (lo, hi) = cts.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| {
            (lo.min(c), hi.max(c))
        });
        !self.curve.is_empty() && !(lo..=hi).contains(&self.estimate)
    }
}

impl Figure for Calibration {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        let across = ct_range(&self.curve, self.estimate);
        let mut chart = self.axes(root, across.clone())?;
        self.draw_simulated(&mut chart)?;
        self.draw_recording(&mut chart, across.clone())?;
        let curve: Vec<(f64, f64)> = drawable(&self.curve)
            .map(|p| (p.ct, p.events_per_pixel_per_second))
            .collect();
        let data = [
            curve,
            vec![(across.start, self.recording), (across.end, self.recording)],
            vec![(self.estimate, self.recording)],
        ];
        draw_legend(&mut chart, 14, &data)?;
        Ok(())
    }

    /// One row per point: `series` says whether it is a point of the simulated curve
    /// (`lo`/`hi` its range over the scenes) or the recording's rate at the estimate (no
    /// range; `ct` empty where the estimate was not determined).
    fn csv(&self) -> String {
        let mut out = String::from("series,ct,events_per_pixel_per_second,lo,hi\n");
        for p in &self.curve {
            let _ = writeln!(
                out,
                "simulated,{},{},{},{}",
                p.ct, p.events_per_pixel_per_second, p.lo, p.hi
            );
        }
        let known = |v: f64| {
            if v.is_finite() {
                v.to_string()
            } else {
                String::new()
            }
        };
        let series = if self.extrapolated() && self.estimate.is_finite() {
            "recording_extrapolated"
        } else {
            "recording"
        };
        let _ = writeln!(
            out,
            "{series},{},{},,",
            known(self.estimate),
            known(self.recording)
        );
        out
    }
}

impl Calibration {
    /// The chart with its caption and axes drawn: the thresholds across, a log axis up
    /// spanning the curve's range and the recording's rate.
    fn axes<'a, DB: DrawingBackend>(
        &self,
        root: &'a DrawingArea<DB, Shift>,
        across: std::ops::Range<f64>,
    ) -> Result<CalibrationChart<'a, DB>, String> {
        let values = drawable(&self.curve)
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
            .build_cartesian_2d(log_axis(across), log_axis(log_range(values)))
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
        let shown: Vec<&CurvePoint> = drawable(&self.curve).collect();
        let band: Vec<(f64, f64)> = shown
            .iter()
            .map(|p| (p.ct, p.hi))
            .chain(shown.iter().rev().map(|p| (p.ct, p.lo)))
            .filter(|p| p.1 > 0.0)
            .collect();
        chart
            .draw_series(std::iter::once(Polygon::new(band, SIMULATED.mix(0.2))))
            .map_err(err)?;
        chart
            .draw_series(LineSeries::new(
                shown.iter().map(|p| (p.ct, p.events_per_pixel_per_second)),
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
    /// curve (hollow, and said, where it is an extrapolation beyond the simulated curve; no
    /// dot where it was not determined).
    fn draw_recording<DB: DrawingBackend>(
        &self,
        chart: &mut CalibrationChart<'_, DB>,
        across: std::ops::Range<f64>,
    ) -> DrawResult {
        chart
            .draw_series(LineSeries::new(
                [(across.start, self.recording), (across.end, self.recording)],
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
        if !self.estimate.is_finite() {
            return Ok(());
        }
        let (style, label) = if self.extrapolated() {
            (
                RECORDING.stroke_width(px(2)),
                format!(
                    "estimate CT {:.3}, extrapolated beyond the simulated curve",
                    self.estimate
                ),
            )
        } else {
            (
                RECORDING.filled(),
                format!("estimate CT {:.3}", self.estimate),
            )
        };
        chart
            .draw_series(std::iter::once(Circle::new(
                (self.estimate, self.recording),
                px(7),
                style,
            )))
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| Circle::new((x + px(10) as i32, y), px(5), style));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve() -> Vec<CurvePoint> {
        // at 3.0 no simulated scene gave an event: in the CSV, not on the log chart
        [(0.2, 4.0), (0.4, 1.5), (0.8, 0.4), (3.0, 0.0)]
            .into_iter()
            .map(|(ct, r)| CurvePoint {
                ct,
                events_per_pixel_per_second: r,
                lo: r * 0.8,
                hi: r * 1.2,
            })
            .collect()
    }

    #[test]
    fn an_estimate_beyond_the_curve_is_drawn_where_it_is_and_said_to_be_extrapolated() {
        let beyond = Calibration {
            curve: curve(),
            recording: 0.1,
            estimate: 4.0,
        };
        let across = ct_range(&beyond.curve, beyond.estimate);
        assert!((across.start - 0.2 / 1.1).abs() < 1e-12);
        assert!((across.end - 4.0 * 1.1).abs() < 1e-12);
        assert!(beyond.extrapolated());
        assert_eq!(
            beyond.csv(),
            "series,ct,events_per_pixel_per_second,lo,hi\n\
             simulated,0.2,4,3.2,4.8\n\
             simulated,0.4,1.5,1.2000000000000002,1.7999999999999998\n\
             simulated,0.8,0.4,0.32000000000000006,0.48\n\
             simulated,3,0,0,0\n\
             recording_extrapolated,4,0.1,,\n"
        );
        let plot = super::super::render("t".into(), "title", &beyond).unwrap();
        assert!(plot.svg.contains("extrapolated beyond the simulated curve"));
    }

    #[test]
    fn an_estimate_not_determined_has_no_threshold_and_no_dot() {
        let unknown = Calibration {
            curve: curve(),
            recording: 2.0,
            estimate: f64::NAN,
        };
        let across = ct_range(&unknown.curve, unknown.estimate);
        assert!((across.end - 0.8 * 1.1).abs() < 1e-12);
        assert!(unknown.csv().ends_with("\nrecording,,2,,\n"));
        let plot = super::super::render("t".into(), "title", &unknown).unwrap();
        assert!(!plot.svg.contains("estimate CT"));
    }
}
