//! The report's plots, drawn with plotters as PNG and SVG from one drawing routine each
//! ([`Figure`]), with the data behind each as CSV. Text uses DejaVu Sans from the `dejavu`
//! crate (registered once; the machine's fonts are never looked up).
//!
//! - the paper's Fig. 2: each sequence's events per pixel per second as a dot per dataset,
//!   beside the calibration scene simulated at the fixed presets CT 0.2 to 1.5;
//! - per sequence: the e/pix/s-versus-CT calibration curve with the recording marked; the
//!   thresholds of every method with their intervals (and the truth); the per-pixel
//!   threshold maps and their histogram; the rate timeline; the per-pixel counts with the
//!   hot pixels; the fit's residuals by intensity and by rate of change for the ideal model
//!   and after each effect; the same-pixel interval distributions, real against simulated.

use super::model::{Report, SequenceReport};
use plotters::coord::Shift;
use plotters::coord::combinators::WithKeyPoints;
use plotters::prelude::*;
use std::fmt::Write as _;

const FONT: &str = "sans-serif";
const SIZE: (u32, u32) = (900, 560);

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

type DrawResult = Result<(), String>;

/// A figure drawn the same way on any backend.
trait Figure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult;
    fn csv(&self) -> String;
}

fn err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

fn render(name: String, title: &str, figure: &impl Figure) -> Result<Plot, String> {
    register_fonts();
    let (w, h) = SIZE;
    let mut pixels = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        figure.draw(&root)?;
        root.present().map_err(err)?;
    }
    let image = image::RgbImage::from_raw(w, h, pixels).ok_or("bitmap size")?;
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

/// Colours of series, in order.
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// The viridis colour map at `v` in [0, 1] (its eight anchor colours, linearly blended).
fn viridis(v: f64) -> RGBColor {
    const ANCHORS: [(u8, u8, u8); 8] = [
        (68, 1, 84),
        (70, 50, 126),
        (54, 92, 141),
        (39, 127, 142),
        (31, 161, 135),
        (74, 193, 109),
        (160, 218, 57),
        (253, 231, 37),
    ];
    let v = v.clamp(0.0, 1.0) * (ANCHORS.len() - 1) as f64;
    let k = (v.floor() as usize).min(ANCHORS.len() - 2);
    let f = v - k as f64;
    let mix = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    let (a, b) = (ANCHORS[k], ANCHORS[k + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// A log axis's tick label: the plain value of a key point m x 10^k.
fn log_tick(v: &f64) -> String {
    if !(v.is_finite() && *v > 0.0) {
        return String::new();
    }
    let exponent = (v.log10() + 1e-9).floor();
    if (-4.0..5.0).contains(&exponent) {
        let decimals = (-exponent).max(0.0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.0e}")
    }
}

/// A log axis over `range` labelled at 1, 2 and 5 times the powers of ten inside it (every
/// integer multiple when fewer than two of those fall inside, only the powers of ten when
/// more than twelve do), with light grid lines at the other integer multiples.
fn log_axis(range: std::ops::Range<f64>) -> WithKeyPoints<LogCoord<f64>> {
    let multiples = |mantissas: &[f64]| -> Vec<f64> {
        let (lo, hi) = (
            range.start.log10().floor() as i32,
            range.end.log10().ceil() as i32,
        );
        (lo..=hi)
            .flat_map(|k| mantissas.iter().map(move |m| m * 10f64.powi(k)))
            .filter(|v| range.contains(v))
            .collect()
    };
    let all = multiples(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
    let mut bold = multiples(&[1.0, 2.0, 5.0]);
    if bold.len() < 2 {
        bold = all.clone();
    } else if bold.len() > 12 {
        bold = multiples(&[1.0]);
    }
    let light: Vec<f64> = all.into_iter().filter(|v| !bold.contains(v)).collect();
    range
        .log_scale()
        .with_key_points(bold)
        .with_light_points(light)
}

/// A linear axis's tick label: at most six decimals, trailing zeros dropped, no `-0`.
fn linear_tick(v: &f64) -> String {
    let text = format!("{v:.6}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" {
        "0".into()
    } else {
        text.into()
    }
}

/// The range of positive values, padded, for a log axis.
fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && *v > 0.0) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return 0.01..10.0;
    }
    (lo / 2.0)..(hi * 2.0)
}

/// The paper's Fig. 2.
struct Fig2<'a> {
    report: &'a Report,
}

impl Figure for Fig2<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        let datasets: Vec<&str> = self
            .report
            .datasets
            .iter()
            .map(|d| d.name.as_str())
            .collect();
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
                (FONT, 20),
            )
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
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
            .label_style((FONT, 14))
            .draw()
            .map_err(err)?;
        for p in &self.report.presets {
            chart
                .draw_series(LineSeries::new(
                    [
                        (-0.5, p.events_per_pixel_per_second),
                        (n - 0.5, p.events_per_pixel_per_second),
                    ],
                    RGBColor(150, 150, 150).stroke_width(1),
                ))
                .map_err(err)?;
            chart
                .draw_series(std::iter::once(Text::new(
                    format!("CT {}", p.ct),
                    (n - 0.45, p.events_per_pixel_per_second),
                    (FONT, 13).into_font().color(&RGBColor(90, 90, 90)),
                )))
                .map_err(err)?;
        }
        for (k, d) in self.report.datasets.iter().enumerate() {
            let colour = PALETTE[k % PALETTE.len()];
            let members: Vec<&SequenceReport> = self
                .report
                .sequences
                .iter()
                .filter(|s| s.dataset == d.name)
                .collect();
            let count = members.len().max(1) as f64;
            let position = |i: usize| k as f64 + 0.5 * ((i as f64 + 0.5) / count - 0.5);
            chart
                .draw_series(members.iter().enumerate().filter_map(|(i, s)| {
                    s.stats
                        .events_per_pixel_per_second
                        .map(|v| Circle::new((position(i), v), 6, colour.filled()))
                }))
                .map_err(err)?;
            // sequence names beside their dots, while they fit
            if members.len() <= 8 {
                chart
                    .draw_series(members.iter().enumerate().filter_map(|(i, s)| {
                        s.stats.events_per_pixel_per_second.map(|v| {
                            Text::new(
                                s.name.clone(),
                                (position(i) + 0.03, v),
                                (FONT, 12).into_font().color(&RGBColor(60, 60, 60)),
                            )
                        })
                    }))
                    .map_err(err)?;
            }
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

/// A point of the e/pix/s calibration curve.
#[derive(serde::Deserialize)]
struct CurvePoint {
    ct: f64,
    events_per_pixel_per_second: f64,
    lo: f64,
    hi: f64,
}

/// The eppps calibration curve of a sequence.
struct Calibration {
    curve: Vec<CurvePoint>,
    recording: f64,
    estimate: f64,
}

impl Figure for Calibration {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        let values = self
            .curve
            .iter()
            .flat_map(|p| [p.lo, p.hi, p.events_per_pixel_per_second])
            .chain([self.recording]);
        let mut chart = ChartBuilder::on(root)
            .caption(
                "Calibration curve: simulated scenes of matched dynamics",
                (FONT, 20),
            )
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(log_axis(0.07f64..2.2), log_axis(log_range(values)))
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_label_formatter(&log_tick)
            .y_label_formatter(&log_tick)
            .light_line_style(RGBColor(242, 242, 242))
            .x_desc("contrast threshold")
            .y_desc("events / pixel / s")
            .label_style((FONT, 14))
            .draw()
            .map_err(err)?;
        let band: Vec<(f64, f64)> = self
            .curve
            .iter()
            .map(|p| (p.ct, p.hi))
            .chain(self.curve.iter().rev().map(|p| (p.ct, p.lo)))
            .filter(|p| p.1 > 0.0)
            .collect();
        chart
            .draw_series(std::iter::once(Polygon::new(band, PALETTE[0].mix(0.2))))
            .map_err(err)?;
        chart
            .draw_series(LineSeries::new(
                self.curve
                    .iter()
                    .map(|p| (p.ct, p.events_per_pixel_per_second)),
                PALETTE[0].stroke_width(2),
            ))
            .map_err(err)?
            .label("simulated (mean, range over scenes)")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], PALETTE[0].stroke_width(2)));
        chart
            .draw_series(LineSeries::new(
                [(0.07, self.recording), (2.2, self.recording)],
                PALETTE[1].stroke_width(2),
            ))
            .map_err(err)?
            .label(format!("the recording: {:.3} e/pix/s", self.recording))
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], PALETTE[1].stroke_width(2)));
        chart
            .draw_series(std::iter::once(Circle::new(
                (self.estimate, self.recording),
                7,
                PALETTE[1].filled(),
            )))
            .map_err(err)?
            .label(format!("estimate CT {:.3}", self.estimate))
            .legend(|(x, y)| Circle::new((x + 10, y), 5, PALETTE[1].filled()));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font((FONT, 14))
            .draw()
            .map_err(err)?;
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

/// One method's thresholds with their 95 % intervals.
struct MethodRow {
    method: String,
    on: f64,
    on_ci95: Option<[f64; 2]>,
    off: f64,
    off_ci95: Option<[f64; 2]>,
}

/// The thresholds of every method of a sequence.
struct Methods {
    rows: Vec<MethodRow>,
    truth: Option<(f64, f64)>,
}

impl Figure for Methods {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        let n = self.rows.len().max(1) as f64;
        let values: Vec<f64> = self
            .rows
            .iter()
            .flat_map(|r| {
                [r.on, r.off]
                    .into_iter()
                    .chain(r.on_ci95.into_iter().flatten())
                    .chain(r.off_ci95.into_iter().flatten())
            })
            .chain(self.truth.into_iter().flat_map(|t| [t.0, t.1]))
            .filter(|v| v.is_finite())
            .collect();
        let hi = values.iter().copied().fold(0.1, f64::max) * 1.15;
        let names: Vec<String> = self.rows.iter().map(|r| r.method.clone()).collect();
        let mut chart = ChartBuilder::on(root)
            .caption("Contrast thresholds by method (95 % intervals)", (FONT, 20))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(60)
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
            .label_style((FONT, 14))
            .draw()
            .map_err(err)?;
        if let Some((on, off)) = self.truth {
            for (value, colour, label) in
                [(on, PALETTE[0], "true ON"), (off, PALETTE[1], "true OFF")]
            {
                chart
                    .draw_series(LineSeries::new(
                        [(-0.5, value), (n - 0.5, value)],
                        colour.mix(0.5).stroke_width(1),
                    ))
                    .map_err(err)?
                    .label(label)
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour.mix(0.5)));
            }
        }
        for (shift, colour, label, pick) in [
            (-0.1, PALETTE[0], "ON", 0usize),
            (0.1, PALETTE[1], "OFF", 1usize),
        ] {
            let points: Vec<(f64, f64, Option<[f64; 2]>)> = self
                .rows
                .iter()
                .enumerate()
                .map(|(k, r)| {
                    let (v, ci) = if pick == 0 {
                        (r.on, r.on_ci95)
                    } else {
                        (r.off, r.off_ci95)
                    };
                    (k as f64 + shift, v, ci)
                })
                .collect();
            chart
                .draw_series(points.iter().filter_map(|(x, _, ci)| {
                    ci.map(|[lo, hi]| {
                        PathElement::new([(*x, lo), (*x, hi)], colour.stroke_width(2))
                    })
                }))
                .map_err(err)?;
            chart
                .draw_series(
                    points
                        .iter()
                        .map(|(x, v, _)| Circle::new((*x, *v), 6, colour.filled())),
                )
                .map_err(err)?
                .label(label)
                .legend(move |(x, y)| Circle::new((x + 10, y), 5, colour.filled()));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font((FONT, 14))
            .draw()
            .map_err(err)?;
        Ok(())
    }

    fn csv(&self) -> String {
        let mut out = String::from("method,ct_on,ct_on_lo,ct_on_hi,ct_off,ct_off_lo,ct_off_hi\n");
        let ci = |c: Option<[f64; 2]>| c.map_or(",".to_string(), |[a, b]| format!("{a},{b}"));
        for r in &self.rows {
            let _ = writeln!(
                out,
                "{},{},{},{},{}",
                r.method,
                r.on,
                ci(r.on_ci95),
                r.off,
                ci(r.off_ci95)
            );
        }
        if let Some((on, off)) = self.truth {
            let _ = writeln!(out, "truth,{on},,,{off},,");
        }
        out
    }
}

/// A per-pixel map drawn as a heat map, block-averaged to at most 180 cells a side.
struct Heat {
    width: usize,
    height: usize,
    values: Vec<f64>,
    label: String,
}

impl Heat {
    fn blocks(&self) -> (usize, usize, usize, Vec<f64>) {
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
    fn range(&self) -> (f64, f64) {
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

    fn draw_on<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        marks: &[(u16, u16)],
    ) -> DrawResult {
        let (block, bw, bh, values) = self.blocks();
        let (lo, hi) = self.range();
        let (plot, bar) = area.split_horizontally(area.dim_in_pixel().0 as i32 - 90);
        // square pixels: the spare room becomes margin
        let (margin, caption, x_labels, y_labels) = (8u32, 30u32, 30u32, 45u32);
        let (pw, ph) = plot.dim_in_pixel();
        let room_w = pw.saturating_sub(2 * margin + y_labels).max(1) as f64;
        let room_h = ph.saturating_sub(2 * margin + caption + x_labels).max(1) as f64;
        let scale = (room_w / self.width as f64).min(room_h / self.height as f64);
        let spare_w = ((room_w - scale * self.width as f64) / 2.0).max(0.0) as u32;
        let spare_h = ((room_h - scale * self.height as f64) / 2.0).max(0.0) as u32;
        let mut chart = ChartBuilder::on(&plot)
            .caption(&self.label, (FONT, 17))
            .margin(margin)
            .margin_left(margin + spare_w)
            .margin_right(margin + spare_w)
            .margin_top(margin + spare_h)
            .margin_bottom(margin + spare_h)
            .x_label_area_size(x_labels)
            .y_label_area_size(y_labels)
            .build_cartesian_2d(0f64..self.width as f64, self.height as f64..0f64)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_label_formatter(&linear_tick)
            .y_label_formatter(&linear_tick)
            .label_style((FONT, 12))
            .draw()
            .map_err(err)?;
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
        chart
            .draw_series(marks.iter().map(|&(x, y)| {
                Circle::new(
                    (x as f64 + 0.5, y as f64 + 0.5),
                    8,
                    RGBColor(230, 30, 30).stroke_width(2),
                )
            }))
            .map_err(err)?;
        // the colour bar
        let mut scale = ChartBuilder::on(&bar)
            .margin_top(margin + spare_h + caption)
            .margin_bottom(margin + spare_h + x_labels)
            .y_label_area_size(55)
            .build_cartesian_2d(0f64..1.0, lo..hi)
            .map_err(err)?;
        scale
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_labels(5)
            .y_label_formatter(&linear_tick)
            .label_style((FONT, 11))
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

/// Per-pixel threshold maps, ON and OFF.
struct ThresholdMaps {
    on: Heat,
    off: Heat,
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

/// Histograms of per-pixel thresholds.
struct Histograms {
    series: Vec<(String, Vec<f64>)>,
}

impl Histograms {
    fn bins(&self) -> (f64, f64, Vec<Vec<f64>>) {
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
            .caption("Per-pixel thresholds (event timing)", (FONT, 20))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(0f64..hi, 0f64..top)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_label_formatter(&linear_tick)
            .y_label_formatter(&linear_tick)
            .x_desc("threshold (log units)")
            .y_desc("pixels")
            .label_style((FONT, 14))
            .draw()
            .map_err(err)?;
        for (k, (label, _)) in self.series.iter().enumerate() {
            let colour = PALETTE[k % PALETTE.len()];
            chart
                .draw_series(counts[k].iter().enumerate().map(|(i, &c)| {
                    let x = i as f64 * width;
                    Rectangle::new([(x, 0.0), (x + width, c)], colour.mix(0.45).filled())
                }))
                .map_err(err)?
                .label(label.clone())
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 15, y + 5)], colour.mix(0.45).filled())
                });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font((FONT, 14))
            .draw()
            .map_err(err)?;
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

/// A set of named (x, y) series on linear or log axes.
struct Lines {
    title: String,
    x_label: String,
    y_label: String,
    log_x: bool,
    series: Vec<(String, Vec<(f64, f64)>)>,
    /// Draw a horizontal line at zero.
    zero: bool,
}

impl Figure for Lines {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
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
        let (y0, y1) = (y0 - pad, y1 + pad);
        let colours = |k: usize| PALETTE[k % PALETTE.len()];
        macro_rules! finish {
            ($chart:expr) => {{
                let mut chart = $chart;
                let mut mesh = chart.configure_mesh();
                mesh.x_desc(self.x_label.as_str())
                    .y_desc(self.y_label.as_str())
                    .light_line_style(RGBColor(242, 242, 242))
                    .y_label_formatter(&linear_tick)
                    .label_style((FONT, 14));
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
                for (k, (label, series)) in self.series.iter().enumerate() {
                    let colour = colours(k);
                    let valid: Vec<(f64, f64)> = series
                        .iter()
                        .copied()
                        .filter(|p| {
                            p.0.is_finite() && p.1.is_finite() && (!self.log_x || p.0 > 0.0)
                        })
                        .collect();
                    chart
                        .draw_series(LineSeries::new(valid.clone(), colour.stroke_width(2)))
                        .map_err(err)?
                        .label(label.clone())
                        .legend(move |(x, y)| {
                            PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(2))
                        });
                    chart
                        .draw_series(valid.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                        .map_err(err)?;
                }
                if self.series.len() > 1 {
                    chart
                        .configure_series_labels()
                        .background_style(WHITE.mix(0.85))
                        .border_style(BLACK)
                        .label_font((FONT, 13))
                        .draw()
                        .map_err(err)?;
                }
            }};
        }
        let builder = |root| {
            let mut b = ChartBuilder::on(root);
            b.caption(self.title.as_str(), (FONT, 19))
                .margin(12)
                .x_label_area_size(45)
                .y_label_area_size(65);
            b
        };
        if self.log_x {
            let range = (x0 / 1.3)..(x1 * 1.3);
            finish!(
                builder(root)
                    .build_cartesian_2d(log_axis(range), y0..y1)
                    .map_err(err)?
            );
        } else {
            let px = ((x1 - x0) * 0.02).max(1e-9);
            finish!(
                builder(root)
                    .build_cartesian_2d((x0 - px)..(x1 + px), y0..y1)
                    .map_err(err)?
            );
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

/// Two line figures side by side.
struct Pair(Lines, Lines);

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

/// Per-pixel event counts with the hot pixels circled.
struct Counts {
    heat: Heat,
    hot: Vec<(u16, u16)>,
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

/// Every plot of the report.
pub fn all(report: &Report) -> Vec<Result<Plot, String>> {
    let mut plots = vec![render(
        "events_per_pixel_per_second".into(),
        "Events per pixel per second by dataset, beside the simulated presets (Stoffregen et al. 2020, Fig. 2)",
        &Fig2 { report },
    )];
    for s in &report.sequences {
        plots.extend(sequence(s));
    }
    plots
}

/// Residual bins with fewer events (real and simulated together) are not drawn.
const MIN_RESIDUAL_EVENTS: u64 = 20;

/// The plots of one sequence.
pub fn sequence(s: &SequenceReport) -> Vec<Result<Plot, String>> {
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
                estimate: e.ct,
            },
        ));
    }
    let mut rows: Vec<MethodRow> = s
        .methods
        .iter()
        .filter_map(|m| m.estimate.as_ref())
        .map(|e| MethodRow {
            method: e.method.to_string(),
            on: e.ct_on,
            on_ci95: Some(e.ct_on_ci95),
            off: e.ct_off,
            off_ci95: Some(e.ct_off_ci95),
        })
        .collect();
    if let Some(f) = &s.fit {
        let ci = |key: &str, v: f64| {
            f.uncertainties
                .get(key)
                .and_then(|u| u.standard_error)
                .map(|se| [v - 1.96 * se, v + 1.96 * se])
        };
        rows.push(MethodRow {
            method: "fit".into(),
            on: f.params.ct_on,
            on_ci95: ci("ct_on", f.params.ct_on),
            off: f.params.ct_off,
            off_ci95: ci("ct_off", f.params.ct_off),
        });
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
    if let Some(maps) = &s.maps {
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
                    .map(|w| (w.t_s + 0.5 * w.window_s, w.events_per_pixel_per_second))
                    .collect(),
            )],
            zero: false,
        },
    ));
    if !s.pixel_counts.is_empty() {
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
                    values: s
                        .pixel_counts
                        .iter()
                        .map(|&c| (c as f64 + 1.0).log10())
                        .collect(),
                    label: "log10(events + 1)".into(),
                },
                hot: s.stats.hot_pixels.iter().map(|p| (p.x, p.y)).collect(),
            },
        ));
    }
    if let Some(f) = &s.fit {
        // bins with too few events to say anything are left out
        let points = |bins: &[crate::fit::residuals::Bin]| -> Vec<(f64, f64)> {
            bins.iter()
                .filter(|b| b.real + b.simulated >= MIN_RESIDUAL_EVENTS)
                .map(|b| (b.x, b.log_ratio))
                .collect()
        };
        let mut intensity = vec![(
            "ideal model".to_string(),
            points(&f.residuals_before.by_intensity),
        )];
        let mut change = vec![(
            "ideal model".to_string(),
            points(&f.residuals_before.by_rate_of_change),
        )];
        for step in f.steps.iter().filter(|st| st.kept) {
            if let Some(after) = &step.residuals_after {
                intensity.push((format!("+ {}", step.effect), points(&after.by_intensity)));
                change.push((
                    format!("+ {}", step.effect),
                    points(&after.by_rate_of_change),
                ));
            }
        }
        plots.push(render(
            name("fit_residuals"),
            &format!("{}: the fit's residuals, ln(simulated / real) supported events, as each effect was added", s.name),
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
        ));
        let distribution = |label: &str, values: &[f64], starts: &[f64]| {
            (
                label.to_string(),
                starts
                    .iter()
                    .zip(values)
                    .skip(1)
                    .map(|(&x, &y)| (x, y))
                    .collect::<Vec<_>>(),
            )
        };
        let (before, after) = (&f.residuals_before.intervals, &f.residuals_after.intervals);
        plots.push(render(
            name("intervals"),
            &format!(
                "{}: same-pixel inter-event intervals, recording against simulations",
                s.name
            ),
            &Lines {
                title: "Same-pixel inter-event intervals".into(),
                x_label: "interval (s)".into(),
                y_label: "share of intervals per bin".into(),
                log_x: true,
                series: vec![
                    distribution("recording", &after.real, &after.bin_start_s),
                    distribution("ideal model", &before.simulated, &before.bin_start_s),
                    distribution("fitted model", &after.simulated, &after.bin_start_s),
                ],
                zero: false,
            },
        ));
    }
    plots
}

#[cfg(test)]
mod tests {
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
        assert_eq!(image.dimensions(), SIZE);
        // the line is drawn in the first palette colour
        assert!(image.pixels().any(|p| p.0 == [31, 119, 180]));
        assert!(plot.svg.starts_with("<svg") && plot.svg.contains("lines"));
        assert_eq!(plot.csv, "series,x,y\na,1,2\na,10,-1\n");
    }

    #[test]
    fn viridis_runs_from_purple_to_yellow() {
        assert_eq!(viridis(0.0), RGBColor(68, 1, 84));
        assert_eq!(viridis(1.0), RGBColor(253, 231, 37));
        assert_eq!(viridis(2.0), RGBColor(253, 231, 37));
    }
}
