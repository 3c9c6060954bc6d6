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

/// The legend box every figure uses: translucent white over the plot, black border.
pub(super) fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    font_size: u32,
) -> Result<(), String> {
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .legend_area_size(px(30))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT, px(font_size)))
        .draw()
        .map_err(|e| e.to_string())
}
