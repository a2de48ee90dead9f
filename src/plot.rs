//! Charts shared by the jobs: one palette, one way to draw an SVG into a string, and chart
//! errors as [`GeltipError`]s.

use crate::error::{GeltipError, Result};
use plotters::prelude::*;

/// Series colours, in order (matplotlib's first colours, which users of these charts know).
pub const PALETTE: [RGBColor; 8] = [
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// Grey for published or reference figures drawn beside ours.
pub const REFERENCE_GREY: RGBColor = RGBColor(120, 120, 120);

/// Colour of series `k`.
pub fn colour(k: usize) -> RGBColor {
    PALETTE[k % PALETTE.len()]
}

/// A plotting error as a one-line [`GeltipError`] naming the chart.
pub fn chart_error(chart: &str, e: impl std::fmt::Display) -> GeltipError {
    GeltipError::input(format!("chart {chart}"), e.to_string())
}

/// Draws an SVG of `size` pixels with `draw` (given a white canvas) and returns its text.
pub fn svg(
    chart: &str,
    size: (u32, u32),
    draw: impl FnOnce(
        &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
    ) -> std::result::Result<(), Box<dyn std::error::Error>>,
) -> Result<String> {
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| chart_error(chart, e))?;
        draw(&root).map_err(|e| chart_error(chart, e))?;
        root.present().map_err(|e| chart_error(chart, e))?;
    }
    Ok(text)
}

/// Draws `chart`'s series labels at `position`, as every chart of geltip's shows them: a
/// black border on a nine-tenths white ground.
pub fn legend<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.9))
        .position(position)
        .draw()
}

/// A colour for `t` in 0..1 on a blue (0) - green - yellow - red (1) scale, for maps where
/// colour is a value; `t` outside 0..1 (or NaN) is clamped (NaN to 0).
pub fn heat(t: f64) -> RGBColor {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let stops = [
        (0.0, (49.0, 54.0, 149.0)),
        (0.33, (44.0, 160.0, 44.0)),
        (0.66, (240.0, 200.0, 30.0)),
        (1.0, (214.0, 39.0, 40.0)),
    ];
    let k = stops
        .iter()
        .rposition(|s| s.0 <= t)
        .unwrap_or(0)
        .min(stops.len() - 2);
    let (t0, a) = stops[k];
    let (t1, b) = stops[k + 1];
    let w = (t - t0) / (t1 - t0);
    let mix = |x: f64, y: f64| (x + (y - x) * w).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}
