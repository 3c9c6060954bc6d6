//! The report's plots, drawn with plotters as PNG and SVG from one drawing routine each
//! ([`Figure`]), with the data behind each as CSV. Text uses DejaVu Sans from the `dejavu`
//! crate (registered once; the machine's fonts are never looked up).
//!
//! - beside the biases that differ between recordings of one sensor: thresholds and
//!   background rate against each bias value (measured pairs, no model);
//! - the paper's Fig. 2: each sequence's events per pixel per second as a dot per dataset,
//!   beside the calibration scene simulated at the fixed presets CT 0.2 to 1.5;
//! - per sequence: the e/pix/s-versus-CT calibration curve with the recording marked; the
//!   thresholds of every method with their intervals (and the truth); the per-pixel
//!   threshold maps and their histogram; the rate timeline; the per-pixel counts with the
//!   hot pixels; the fit's residuals by intensity and by rate of change for the ideal model
//!   and after each effect; the same-pixel interval distributions, real against simulated.

mod bias;
mod calibration;
mod fig2;
mod heat;
mod histograms;
mod lines;
mod methods;
mod style;

use super::model::{PixelData, Report, SequenceReport};
use calibration::{Calibration, CurvePoint};
use fig2::Fig2;
use heat::{Counts, Heat, ThresholdMaps};
use histograms::Histograms;
use lines::{Lines, Pair};
use methods::{MethodRow, Methods};
use plotters::coord::Shift;
use plotters::prelude::*;

pub(super) const FONT: &str = "sans-serif";
/// A figure's size in layout units: the SVG's pixels; the PNG has [`PNG_SCALE`] times as
/// many each way (1800 px wide, for print).
pub(super) const SIZE: (u32, u32) = (900, 560);
pub(super) const PNG_SCALE: u32 = 2;

fn register_fonts() {
    static FONTS: std::sync::Once = std::sync::Once::new();
    FONTS.call_once(|| {
        // DejaVu is valid TrueType: registration cannot fail
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
        let _ = plotters::style::register_font(FONT, FontStyle::Bold, dejavu::sans::bold());
    });
}

/// A rendered plot.
#[derive(Clone, Debug)]
pub struct Plot {
    /// File stem (`plots/<name>.png`, `.svg`, `.csv`).
    pub name: String,
    pub title: String,
    pub png: Vec<u8>,
    pub svg: String,
    pub csv: String,
}

pub(super) type DrawResult = Result<(), String>;

/// A figure drawn the same way on any backend.
pub(super) trait Figure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult;
    fn csv(&self) -> String;
}

pub(super) fn err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

fn render(name: String, title: &str, figure: &impl Figure) -> Result<Plot, String> {
    register_fonts();
    let (w, h) = (SIZE.0 * PNG_SCALE, SIZE.1 * PNG_SCALE);
    let mut pixels = vec![255u8; (w * h * 3) as usize];
    style::scaled(PNG_SCALE, || -> DrawResult {
        let root = BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        figure.draw(&root)?;
        root.present().map_err(err)
    })?;
    let (w, h) = SIZE;
    let image =
        image::RgbImage::from_raw(w * PNG_SCALE, h * PNG_SCALE, pixels).ok_or("bitmap size")?;
    let mut png = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(err)?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        figure.draw(&root)?;
        root.present().map_err(err)?;
    }
    Ok(Plot {
        name,
        title: title.to_string(),
        png,
        svg,
        csv: figure.csv(),
    })
}

/// The paper's Fig. 2 of the whole report.
pub fn fig2(report: &Report) -> Result<Plot, String> {
    render(
        "events_per_pixel_per_second".into(),
        "Events per pixel per second by dataset, beside the simulated presets (Stoffregen et al. 2020, Fig. 2)",
        &Fig2 { report },
    )
}

/// One figure per bias that differs between recordings of one sensor: the best thresholds
/// and the background rate against the bias value.
pub fn bias_sweeps(report: &Report) -> Vec<Result<Plot, String>> {
    let sequences: Vec<&SequenceReport> = report.sequences.iter().collect();
    crate::bias_sweep::sweeps(&sequences)
        .iter()
        .map(|(bias, points)| {
            render(
                format!("bias_sweep_{bias}"),
                &format!(
                    "Thresholds and background rate against {bias}, one point per recording (measured pairs, joined in order; no bias model)"
                ),
                &bias::sweep(bias, points),
            )
        })
        .collect()
}

/// Series of a distribution cut to the range where some series has a non-zero share (the
/// empty bins at either end say nothing and would stretch the log axis).
fn over_the_data(mut series: Vec<(String, Vec<(f64, f64)>)>) -> Vec<(String, Vec<(f64, f64)>)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (x, _) in series.iter().flat_map(|s| s.1.iter()).filter(|p| p.1 > 0.0) {
        lo = lo.min(*x);
        hi = hi.max(*x);
    }
    for s in &mut series {
        s.1.retain(|p| p.0 >= lo && p.0 <= hi);
    }
    series
}

/// Residual bins with fewer events (real and simulated together) are not drawn.
const MIN_RESIDUAL_EVENTS: u64 = 20;

/// The plots of one sequence.
pub fn sequence(s: &SequenceReport, pixels: &PixelData) -> Vec<Result<Plot, String>> {
    let mut plots = Vec::new();
    plots.extend(calibration_curve(s));
    plots.extend(thresholds_by_method(s));
    plots.extend(threshold_maps(s, pixels));
    plots.extend(rate_timeline(s));
    plots.extend(pixel_counts(s, pixels));
    plots.extend(fit_residuals(s));
    plots
}

type Plots = Vec<Result<Plot, String>>;

/// eppps' events per pixel per second against the threshold, the recording's rate on it.
fn calibration_curve(s: &SequenceReport) -> Plots {
    let mut plots = Vec::new();
    let name = |what: &str| format!("{}/{what}", s.name);
    if let Some(e) = s.estimate("eppps")
        && let Some(curve) = e.extra.get("calibration_curve")
        && let Ok(curve) = serde_json::from_value::<Vec<CurvePoint>>(curve.clone())
    {
        let recording = e.extra["recording"]["events_per_pixel_per_second"]
            .as_f64()
            .unwrap_or(f64::NAN);
        plots.push(render(
            name("calibration_curve"),
            &format!(
                "{}: events per pixel per second against threshold (estimate eppps)",
                s.name
            ),
            &Calibration {
                curve,
                recording,
                estimate: e.ct.unwrap_or(f64::NAN),
            },
        ));
    }
    plots
}

/// Each method's thresholds with their intervals (and the truth of a simulation).
fn thresholds_by_method(s: &SequenceReport) -> Plots {
    let mut plots = Vec::new();
    let name = |what: &str| format!("{}/{what}", s.name);
    let mut rows: Vec<MethodRow> = s
        .methods
        .iter()
        .filter_map(|m| m.estimate.as_ref())
        .map(|e| MethodRow {
            method: e.method.to_string(),
            on: e.ct_on,
            on_ci95: e.ct_on_ci95,
            off: e.ct_off,
            off_ci95: e.ct_off_ci95,
        })
        .collect();
    if let Some(f) = &s.fit {
        let ci = |key: &str, _: f64| f.uncertainties.get(key).and_then(|u| u.interval());
        if let Some((on, off)) = s.fitted_thresholds() {
            rows.push(MethodRow {
                method: "fit".into(),
                on: Some(on),
                on_ci95: ci("ct_on", on),
                off: Some(off),
                off_ci95: ci("ct_off", off),
            });
        }
    }
    if !rows.is_empty() {
        let truth = s
            .truth
            .as_ref()
            .and_then(|t| Some((*t.params.get("ct_on")?, *t.params.get("ct_off")?)));
        plots.push(render(
            name("thresholds"),
            &format!("{}: contrast thresholds by method", s.name),
            &Methods { rows, truth },
        ));
    }
    plots
}

/// aps' per-pixel thresholds as maps and histograms.
fn threshold_maps(s: &SequenceReport, pixels: &PixelData) -> Plots {
    let mut plots = Vec::new();
    let name = |what: &str| format!("{}/{what}", s.name);
    if let Some(maps) = &pixels.maps {
        let heat = |values: &[f32], label: &str| Heat {
            width: maps.width,
            height: maps.height,
            values: values.iter().map(|&v| v as f64).collect(),
            label: label.to_string(),
        };
        plots.push(render(
            name("threshold_maps"),
            &format!(
                "{}: per-pixel thresholds from event timing (grey: too little evidence)",
                s.name
            ),
            &ThresholdMaps {
                on: heat(&maps.ct_on, "ON threshold"),
                off: heat(&maps.ct_off, "OFF threshold"),
            },
        ));
        plots.push(render(
            name("threshold_histogram"),
            &format!("{}: distribution of per-pixel thresholds", s.name),
            &Histograms {
                series: vec![
                    ("ON".into(), maps.ct_on.iter().map(|&v| v as f64).collect()),
                    (
                        "OFF".into(),
                        maps.ct_off.iter().map(|&v| v as f64).collect(),
                    ),
                ],
            },
        ));
    }
    plots
}

/// The event rate over the recording.
fn rate_timeline(s: &SequenceReport) -> Plots {
    let mut plots = Vec::new();
    let name = |what: &str| format!("{}/{what}", s.name);
    plots.push(render(
        name("rate_timeline"),
        &format!("{}: event rate over time", s.name),
        &Lines {
            title: "Event rate over time".into(),
            x_label: "time from the first event (s)".into(),
            y_label: "events / pixel / s".into(),
            log_x: false,
            series: vec![(
                "all events".into(),
                s.stats
                    .rate_timeline
                    .iter()
                    .filter_map(|w| {
                        Some((w.t_s + 0.5 * w.window_s, w.events_per_pixel_per_second?))
                    })
                    .collect(),
            )],
            zero: false,
        },
    ));
    plots
}

/// Events per pixel, hot pixels circled.
fn pixel_counts(s: &SequenceReport, pixels: &PixelData) -> Plots {
    let mut plots = Vec::new();
    let name = |what: &str| format!("{}/{what}", s.name);
    if !pixels.counts.is_empty() {
        let (w, h) = (s.stats.width as usize, s.stats.height as usize);
        plots.push(render(
            name("pixel_counts"),
            &format!(
                "{}: events per pixel (log10 of events + 1), hot pixels circled",
                s.name
            ),
            &Counts {
                heat: Heat {
                    width: w,
                    height: h,
                    values: pixels
                        .counts
                        .iter()
                        .map(|&c| (c as f64 + 1.0).log10())
                        .collect(),
                    label: "log10(events + 1)".into(),
                },
                hot: s.stats.hot_pixels.iter().map(|p| (p.x, p.y)).collect(),
            },
        ));
    }
    plots
}

/// The fit's residuals as each effect was added, and the same-pixel interval
/// distributions of the recording and the models.
fn fit_residuals(s: &SequenceReport) -> Plots {
    let mut plots = Vec::new();
    if let Some((f, residuals_before, residuals_after)) = s
        .fit
        .as_ref()
        .and_then(|f| Some((f, f.residuals_before.as_ref()?, f.residuals_after.as_ref()?)))
    {
        plots.push(residuals_by_effect(s, f, residuals_before));
        plots.push(intervals(s, residuals_before, residuals_after));
    }
    plots
}

/// A series of residual bins, (x, ln(simulated / real)): bins with too few events to say
/// anything are left out.
fn supported_points(bins: &[crate::fit::residuals::Bin]) -> Vec<(f64, f64)> {
    bins.iter()
        .filter(|b| b.real + b.simulated >= MIN_RESIDUAL_EVENTS)
        .map(|b| (b.x, b.log_ratio))
        .collect()
}

/// The residuals by scene intensity and by rate of change: the ideal model's
/// (`residuals_before`), then after each effect the fit kept.
fn residuals_by_effect(
    s: &SequenceReport,
    f: &crate::fit::FitResult,
    residuals_before: &crate::fit::residuals::Residuals,
) -> Result<Plot, String> {
    let mut intensity = vec![(
        "ideal model".to_string(),
        supported_points(&residuals_before.by_intensity),
    )];
    let mut change = vec![(
        "ideal model".to_string(),
        supported_points(&residuals_before.by_rate_of_change),
    )];
    for step in f.steps.iter().filter(|st| st.kept) {
        if let Some(after) = &step.residuals_after {
            intensity.push((
                format!("+ {}", step.effect),
                supported_points(&after.by_intensity),
            ));
            change.push((
                format!("+ {}", step.effect),
                supported_points(&after.by_rate_of_change),
            ));
        }
    }
    render(
        format!("{}/fit_residuals", s.name),
        &format!(
            "{}: the fit's residuals, ln(simulated / real) supported events, as each effect was added",
            s.name
        ),
        &Pair(
            Lines {
                title: "by scene intensity".into(),
                x_label: "intensity (DN)".into(),
                y_label: "ln(simulated / real)".into(),
                log_x: true,
                series: intensity,
                zero: true,
            },
            Lines {
                title: "by rate of change".into(),
                x_label: "log-intensity change (1/s)".into(),
                y_label: "ln(simulated / real)".into(),
                log_x: true,
                series: change,
                zero: true,
            },
        ),
    )
}

/// A share-per-bin distribution as a series: each bin's share at its lower edge (the
/// first bin left out).
fn distribution(label: &str, values: &[f64], starts: &[f64]) -> (String, Vec<(f64, f64)>) {
    (
        label.to_string(),
        starts
            .iter()
            .zip(values)
            .skip(1)
            .map(|(&x, &y)| (x, y))
            .collect::<Vec<_>>(),
    )
}

/// The same-pixel interval distributions of the recording, the ideal model (`before`)
/// and the fitted one (`after`).
fn intervals(
    s: &SequenceReport,
    before: &crate::fit::residuals::Residuals,
    after: &crate::fit::residuals::Residuals,
) -> Result<Plot, String> {
    let (before, after) = (&before.intervals, &after.intervals);
    render(
        format!("{}/intervals", s.name),
        &format!(
            "{}: same-pixel inter-event intervals, recording against simulations",
            s.name
        ),
        &Lines {
            title: "Same-pixel inter-event intervals".into(),
            x_label: "interval (s)".into(),
            y_label: "share of intervals per bin".into(),
            log_x: true,
            series: over_the_data(vec![
                distribution("recording", &after.real, &after.bin_start_s),
                distribution("ideal model", &before.simulated, &before.bin_start_s),
                distribution("fitted model", &after.simulated, &after.bin_start_s),
            ]),
            zero: false,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::style::viridis;
    use super::*;

    #[test]
    fn a_line_plot_renders_to_png_svg_and_csv() {
        let plot = render(
            "t".into(),
            "title",
            &Lines {
                title: "lines".into(),
                x_label: "x".into(),
                y_label: "y".into(),
                log_x: true,
                series: vec![("a".into(), vec![(1.0, 2.0), (10.0, -1.0)])],
                zero: true,
            },
        )
        .unwrap();
        assert_eq!(&plot.png[1..4], b"PNG");
        let image = image::load_from_memory(&plot.png).unwrap().to_rgb8();
        assert_eq!(image.dimensions(), (1800, 1120));
        // a series of no fixed meaning takes the first colour left for such series (blue
        // and red mean ON and OFF)
        assert!(image.pixels().any(|p| p.0 == [255, 127, 14]));
        assert!(!image.pixels().any(|p| p.0 == [31, 119, 180]));
        assert!(plot.svg.starts_with("<svg") && plot.svg.contains("lines"));
        assert_eq!(plot.csv, "series,x,y\na,1,2\na,10,-1\n");
    }

    #[test]
    fn one_colour_per_meaning() {
        use super::style::{OFF, ON, colour_for};
        assert_eq!(colour_for("ON", 5), ON);
        assert_eq!(colour_for("true OFF", 0), OFF);
        assert_eq!(colour_for("ideal model", 0), colour_for("ideal model", 3));
        for k in 0..8 {
            assert_ne!(colour_for("+ leak", k), ON);
            assert_ne!(colour_for("+ leak", k), OFF);
            assert_ne!(colour_for("+ leak", k), colour_for("fitted model", 0));
        }
    }

    #[test]
    fn viridis_runs_from_purple_to_yellow() {
        assert_eq!(viridis(0.0), RGBColor(68, 1, 84));
        assert_eq!(viridis(1.0), RGBColor(253, 231, 37));
        assert_eq!(viridis(2.0), RGBColor(253, 231, 37));
    }
}
