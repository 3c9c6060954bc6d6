//! Shared look of the report's plots: the palette, the viridis colour map and the tick
//! labels and key points of linear and logarithmic axes, and the legend box.

use super::FONT;
use plotters::coord::CoordTranslate;
use plotters::coord::combinators::WithKeyPoints;
use plotters::prelude::*;

thread_local! {
    /// Pixels per layout unit of the figure being drawn (2 for the PNGs, 1 for the SVGs).
    static SCALE: std::cell::Cell<u32> = const { std::cell::Cell::new(1) };
}

/// A size in layout units (fonts, margins, strokes, marks) in pixels of the figure being
/// drawn.
pub(super) fn px(n: u32) -> u32 {
    n * SCALE.with(|s| s.get())
}

/// Runs `draw` with `scale` pixels per layout unit.
pub(super) fn scaled<T>(scale: u32, draw: impl FnOnce() -> T) -> T {
    let before = SCALE.with(|s| s.replace(scale));
    let out = draw();
    SCALE.with(|s| s.set(before));
    out
}

/// Colours of series, in order.
pub(super) const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// One colour per meaning across every figure: ON and OFF thresholds, the recording, the
/// ideal (thresholds only) model and simulations of it, the fitted model; other series take
/// the rest of the palette in order.
pub(super) const ON: RGBColor = PALETTE[0];
pub(super) const OFF: RGBColor = PALETTE[1];
pub(super) const RECORDING: RGBColor = RGBColor(40, 40, 40);
pub(super) const SIMULATED: RGBColor = PALETTE[4];
pub(super) const FITTED: RGBColor = PALETTE[2];

/// The colour of a series by its label (see [`ON`]); `k`: its place among the others.
pub(super) fn colour_for(label: &str, k: usize) -> RGBColor {
    match label {
        "ON" | "true ON" => ON,
        "OFF" | "true OFF" => OFF,
        "recording" | "all events" => RECORDING,
        "ideal model" => SIMULATED,
        "fitted model" => FITTED,
        _ => [PALETTE[3], PALETTE[5], PALETTE[6], PALETTE[7]][k % 4],
    }
}

/// The viridis colour map at `v` in [0, 1] (its eight anchor colours, linearly blended).
pub(super) fn viridis(v: f64) -> RGBColor {
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
pub(super) fn log_tick(v: &f64) -> String {
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
pub(super) fn log_axis(range: std::ops::Range<f64>) -> WithKeyPoints<LogCoord<f64>> {
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
pub(super) fn linear_tick(v: &f64) -> String {
    let text = format!("{v:.6}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" {
        "0".into()
    } else {
        text.into()
    }
}

/// The range of positive values, padded, for a log axis.
pub(super) fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
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

/// The legend box every figure uses: translucent white, black border, in the corner of the
/// plot that the fewest of `data` cross ([`emptiest_corner`]): each polyline of `data` in
/// the chart's own coordinates (a single point is a polyline of one).
pub(super) fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    font_size: u32,
    data: &[Vec<CT::From>],
) -> Result<(), String> {
    let pixels: Vec<Vec<(i32, i32)>> = data
        .iter()
        .map(|line| {
            line.iter()
                .map(|p| chart.as_coord_spec().translate(p))
                .collect()
        })
        .collect();
    let (x, y) = chart.plotting_area().get_pixel_range();
    let position = emptiest_corner(&pixels, (x.start, x.end), (y.start, y.end));
    chart
        .configure_series_labels()
        .position(position)
        .legend_area_size(px(30))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT, px(font_size)))
        .draw()
        .map_err(|e| e.to_string())
}

/// Where a legend hides the least: of the four corner boxes (45 % of the plot's width, 35 %
/// of its height, about a legend's size), the one the fewest samples of `lines` fall in
/// (pixel coordinates; each segment sampled every 4 px); the upper right on ties.
fn emptiest_corner(
    lines: &[Vec<(i32, i32)>],
    (x0, x1): (i32, i32),
    (y0, y1): (i32, i32),
) -> SeriesLabelPosition {
    let (w, h) = (f64::from(x1 - x0), f64::from(y1 - y0));
    // (right, upper) of upper right, upper left, lower right, lower left
    let corners = [(true, true), (false, true), (true, false), (false, false)];
    let mut counts = [0usize; 4];
    let mut visit = |x: f64, y: f64| {
        for (k, &(right, upper)) in corners.iter().enumerate() {
            let in_x = if right {
                x >= f64::from(x0) + 0.55 * w
            } else {
                x <= f64::from(x0) + 0.45 * w
            };
            let in_y = if upper {
                y <= f64::from(y0) + 0.35 * h
            } else {
                y >= f64::from(y1) - 0.35 * h
            };
            counts[k] += usize::from(in_x && in_y);
        }
    };
    for line in lines {
        if let [only] = line.as_slice() {
            visit(f64::from(only.0), f64::from(only.1));
        }
        for pair in line.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            let length = f64::from(b.0 - a.0).hypot(f64::from(b.1 - a.1));
            let steps = ((length / 4.0).ceil() as usize).clamp(1, 2000);
            for i in 0..=steps {
                let f = i as f64 / steps as f64;
                visit(
                    f64::from(a.0) + f * f64::from(b.0 - a.0),
                    f64::from(a.1) + f * f64::from(b.1 - a.1),
                );
            }
        }
    }
    match (0..4).min_by_key(|&k| counts[k]).unwrap_or(0) {
        1 => SeriesLabelPosition::UpperLeft,
        2 => SeriesLabelPosition::LowerRight,
        3 => SeriesLabelPosition::LowerLeft,
        _ => SeriesLabelPosition::UpperRight,
    }
}

#[cfg(test)]
mod legend_tests {
    use super::*;

    fn name(p: SeriesLabelPosition) -> &'static str {
        match p {
            SeriesLabelPosition::UpperRight => "upper right",
            SeriesLabelPosition::UpperLeft => "upper left",
            SeriesLabelPosition::LowerRight => "lower right",
            SeriesLabelPosition::LowerLeft => "lower left",
            _ => "other",
        }
    }

    #[test]
    fn a_legend_goes_where_the_data_are_not() {
        // a falling curve (upper left to lower right) leaves the upper right and lower left
        // empty: upper right wins the tie
        let falling = vec![vec![(0, 0), (1000, 800)]];
        assert_eq!(
            name(emptiest_corner(&falling, (0, 1000), (0, 800))),
            "upper right"
        );
        // a rising curve crosses the upper right: the upper left is empty
        let rising = vec![vec![(0, 800), (1000, 0)]];
        assert_eq!(
            name(emptiest_corner(&rising, (0, 1000), (0, 800))),
            "upper left"
        );
        // a horizontal line near the top and a point cloud at the lower left
        let mixed = vec![
            vec![(0, 100), (1000, 100)],
            vec![(100, 700)],
            vec![(120, 650)],
        ];
        assert_eq!(
            name(emptiest_corner(&mixed, (0, 1000), (0, 800))),
            "lower right"
        );
        assert_eq!(
            name(emptiest_corner(&[], (0, 1000), (0, 800))),
            "upper right"
        );
    }
}
