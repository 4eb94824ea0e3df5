//! Thin helpers over plotters' SVG backend: line plots (optionally log axes), grids of
//! sub-plots and heatmaps, rendered to SVG text (written by `io::files::write_atomic`).

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::ops::Range;
use thiserror::Error;

/// Size of a single plot in pixels (width, height).
pub const PLOT_SIZE: (u32, u32) = (900, 600);
/// Fractional margin added on each side of the data range.
pub const RANGE_MARGIN: f64 = 0.05;

/// One curve: `y[i]` against `x[i]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend entry.
    pub label: String,
    /// Abscissae (any unit; same length as `y`).
    pub x: Vec<f64>,
    /// Ordinates.
    pub y: Vec<f64>,
}

/// A 2-D line chart. Non-finite points (and non-positive values on a log
/// axis) are skipped; lines break at skipped points.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LinePlot {
    /// Caption above the chart.
    pub title: String,
    /// x-axis description (include the unit, e.g. `"s [m]"`).
    pub x_label: String,
    /// y-axis description (include the unit).
    pub y_label: String,
    /// Curves, drawn in order with distinct colours.
    pub series: Vec<Series>,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// Where the legend goes (the corner the curves leave free).
    pub legend: Legend,
}

/// A corner of the plot for the legend.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Legend {
    #[default]
    UpperRight,
    UpperLeft,
    LowerLeft,
}

/// Errors from the plotting helpers.
#[derive(Debug, Error)]
pub enum PlotError {
    /// The plot has no series at all.
    #[error("plot '{title}' has no series")]
    NoSeries { title: String },
    /// A series with zero points.
    #[error("series '{series}' of plot '{title}' is empty")]
    EmptySeries { title: String, series: String },
    /// `x` and `y` lengths differ.
    #[error("series '{series}' of plot '{title}' has {x_len} x values but {y_len} y values")]
    LengthMismatch { title: String, series: String, x_len: usize, y_len: usize },
    /// Every point is non-finite (or non-positive on a log axis).
    #[error("plot '{title}' has no plottable point (log_x = {log_x}, log_y = {log_y}; non-finite and, on log axes, non-positive values are dropped)")]
    NoPlottablePoints { title: String, log_x: bool, log_y: bool },
    /// [`render_panels_svg`] called with no panels or zero columns.
    #[error("invalid panel grid: {panels} panel(s) in {cols} column(s)")]
    InvalidGrid { panels: usize, cols: usize },
    /// Drawing failed inside plotters.
    #[error("drawing plot '{title}' failed: {detail}")]
    Draw { title: String, detail: String },
}

fn draw_err(title: &str, e: impl std::fmt::Display) -> PlotError {
    PlotError::Draw { title: title.to_string(), detail: e.to_string() }
}

fn keep(v: f64, log: bool) -> bool {
    v.is_finite() && (!log || v > 0.0)
}

/// Validates `plot` and returns the padded (x, y) ranges.
fn ranges(plot: &LinePlot) -> Result<(Range<f64>, Range<f64>), PlotError> {
    if plot.series.is_empty() {
        return Err(PlotError::NoSeries { title: plot.title.clone() });
    }
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for s in &plot.series {
        if s.x.len() != s.y.len() {
            return Err(PlotError::LengthMismatch {
                title: plot.title.clone(),
                series: s.label.clone(),
                x_len: s.x.len(),
                y_len: s.y.len(),
            });
        }
        if s.x.is_empty() {
            return Err(PlotError::EmptySeries { title: plot.title.clone(), series: s.label.clone() });
        }
        for (&x, &y) in s.x.iter().zip(&s.y) {
            if keep(x, plot.log_x) && keep(y, plot.log_y) {
                (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            }
        }
    }
    if x0 > x1 {
        return Err(PlotError::NoPlottablePoints { title: plot.title.clone(), log_x: plot.log_x, log_y: plot.log_y });
    }
    Ok((pad(x0, x1, plot.log_x), pad(y0, y1, plot.log_y)))
}

/// Adds a margin (multiplicative on log axes); widens a zero-width range.
fn pad(lo: f64, hi: f64, log: bool) -> Range<f64> {
    if log {
        let (a, b) = (lo.log10(), hi.log10());
        let m = if b > a { RANGE_MARGIN * (b - a) } else { 0.5 };
        return 10f64.powf(a - m)..10f64.powf(b + m);
    }
    if hi > lo {
        let m = RANGE_MARGIN * (hi - lo);
        (lo - m)..(hi + m)
    } else {
        let m = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        (lo - m)..(hi + m)
    }
}

/// Draws one plot into `area` with the given coordinate specs.
fn draw_with<DB, X, Y>(area: &DrawingArea<DB, Shift>, plot: &LinePlot, xs: X, ys: Y) -> Result<(), PlotError>
where
    DB: DrawingBackend,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let t = plot.title.as_str();
    let mut chart = ChartBuilder::on(area)
        .caption(t, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(75)
        .build_cartesian_2d(xs, ys)
        .map_err(|e| draw_err(t, e))?;
    chart
        .configure_mesh()
        .x_desc(plot.x_label.as_str())
        .y_desc(plot.y_label.as_str())
        .x_label_formatter(&|v| format_tick(*v))
        .y_label_formatter(&|v| format_tick(*v))
        .draw()
        .map_err(|e| draw_err(t, e))?;
    for (i, s) in plot.series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        // Split into runs of plottable points so lines break at gaps.
        let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
        for (&x, &y) in s.x.iter().zip(&s.y) {
            if keep(x, plot.log_x) && keep(y, plot.log_y) {
                if let Some(r) = runs.last_mut() {
                    r.push((x, y));
                }
            } else if runs.last().is_some_and(|r| !r.is_empty()) {
                runs.push(Vec::new());
            }
        }
        let mut labelled = false;
        for run in runs.into_iter().filter(|r| !r.is_empty()) {
            let style = ShapeStyle::from(color).stroke_width(2);
            let drawn = chart.draw_series(LineSeries::new(run, style)).map_err(|e| draw_err(t, e))?;
            if !labelled {
                drawn.label(s.label.as_str()).legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
                labelled = true;
            }
        }
    }
    chart
        .configure_series_labels()
        .position(match plot.legend {
            Legend::UpperRight => SeriesLabelPosition::UpperRight,
            Legend::UpperLeft => SeriesLabelPosition::UpperLeft,
            Legend::LowerLeft => SeriesLabelPosition::LowerLeft,
        })
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| draw_err(t, e))?;
    Ok(())
}

/// Compact tick labels: plain decimals for moderate magnitudes, else `1.5e-3`.
pub(crate) fn format_tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".to_string()
    } else if (1e-3..1e4).contains(&a) {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        let s = format!("{v:.2e}");
        match s.split_once('e') {
            Some((m, e)) => format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.')),
            None => s,
        }
    }
}

fn draw_plot<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, plot: &LinePlot) -> Result<(), PlotError> {
    let (xr, yr) = ranges(plot)?;
    match (plot.log_x, plot.log_y) {
        (false, false) => draw_with(area, plot, xr, yr),
        (true, false) => draw_with(area, plot, xr.log_scale(), yr),
        (false, true) => draw_with(area, plot, xr, yr.log_scale()),
        (true, true) => draw_with(area, plot, xr.log_scale(), yr.log_scale()),
    }
}

/// Renders `draw` into an in-memory SVG of `size` pixels.
fn render(
    size: (u32, u32),
    title: &str,
    draw: impl FnOnce(&DrawingArea<SVGBackend, Shift>) -> Result<(), PlotError>,
) -> Result<String, PlotError> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| draw_err(title, e))?;
        draw(&root)?;
        root.present().map_err(|e| draw_err(title, e))?;
    }
    Ok(svg)
}

/// `plot` as a 900×600 SVG (with legend, axis labels and auto ranges padded by
/// [`RANGE_MARGIN`]).
pub fn render_svg(plot: &LinePlot) -> Result<String, PlotError> {
    ranges(plot)?; // validate before rendering
    render(PLOT_SIZE, &plot.title, |root| draw_plot(root, plot))
}

/// `panels` as a grid with `cols` columns (rows as needed) in one SVG; each panel is 900×600
/// scaled to fit a width of at most 1800 px. Errors if any panel is invalid, `panels` is
/// empty or `cols` is 0.
pub fn render_panels_svg(panels: &[LinePlot], cols: usize) -> Result<String, PlotError> {
    if panels.is_empty() || cols == 0 {
        return Err(PlotError::InvalidGrid { panels: panels.len(), cols });
    }
    for p in panels {
        ranges(p)?;
    }
    let cols = cols.min(panels.len());
    let rows = panels.len().div_ceil(cols);
    let (pw, ph) = if cols <= 2 { PLOT_SIZE } else { (1800 / cols as u32, 1200 / cols as u32) };
    let size = (pw * cols as u32, ph * rows as u32);
    let title = panels.first().map_or("", |p| p.title.as_str());
    render(size, title, |root| {
        for (area, plot) in root.split_evenly((rows, cols)).iter().zip(panels) {
            draw_plot(area, plot)?;
        }
        Ok(())
    })
}

/// A value field over a regular grid drawn as coloured cells (a kymograph): `values[i][j]` at
/// `(x[i], y[j])`, a diverging colour map symmetric about 0 (blue < 0 < red), clipped at
/// `±limit`.
#[derive(Debug, Clone, PartialEq)]
pub struct Heatmap {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub values: Vec<Vec<f64>>,
    pub limit: f64,
}

impl Heatmap {
    /// A kymograph: frames along x, arc length `s` [mm] along y.
    pub fn kymograph(title: String, frames: Vec<f64>, s_mm: Vec<f64>, values: Vec<Vec<f64>>, limit: f64) -> Self {
        Heatmap { title, x_label: "frame".into(), y_label: "s [mm]".into(), x: frames, y: s_mm, values, limit }
    }
}

fn diverging(v: f64, limit: f64) -> RGBColor {
    let t = if limit > 0.0 && v.is_finite() { (v / limit).clamp(-1.0, 1.0) } else { 0.0 };
    let (r, g, b) = if t >= 0.0 { (1.0, 1.0 - t, 1.0 - t) } else { (1.0 + t, 1.0 + t, 1.0) };
    RGBColor((r * 255.0) as u8, (g * 255.0) as u8, (b * 255.0) as u8)
}

/// Heatmaps side by side (one row) in one SVG.
pub fn render_heatmaps_svg(maps: &[Heatmap]) -> Result<String, PlotError> {
    if maps.is_empty() {
        return Err(PlotError::InvalidGrid { panels: 0, cols: 0 });
    }
    for m in maps {
        if m.x.len() < 2
            || m.y.len() < 2
            || m.values.len() != m.x.len()
            || m.values.iter().any(|r| r.len() != m.y.len())
        {
            return Err(PlotError::LengthMismatch {
                title: m.title.clone(),
                series: "values".into(),
                x_len: m.x.len(),
                y_len: m.y.len(),
            });
        }
    }
    let size = (PLOT_SIZE.0 * maps.len() as u32, PLOT_SIZE.1);
    let title = maps[0].title.clone();
    render(size, &title, |root| {
        for (m, area) in maps.iter().zip(root.split_evenly((1, maps.len()))) {
            let (x0, x1) = (m.x[0], m.x[m.x.len() - 1]);
            let (y0, y1) = (m.y[0], m.y[m.y.len() - 1]);
            let mut chart = ChartBuilder::on(&area)
                .caption(&m.title, ("sans-serif", 20))
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(70)
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(|e| draw_err(&m.title, e))?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_desc(m.x_label.as_str())
                .y_desc(m.y_label.as_str())
                .draw()
                .map_err(|e| draw_err(&m.title, e))?;
            let half = |v: &[f64], i: usize| -> (f64, f64) {
                let lo = if i == 0 { v[0] } else { 0.5 * (v[i - 1] + v[i]) };
                let hi = if i + 1 == v.len() { v[i] } else { 0.5 * (v[i] + v[i + 1]) };
                (lo, hi)
            };
            let cells = (0..m.x.len()).flat_map(|i| (0..m.y.len()).map(move |j| (i, j))).map(|(i, j)| {
                let (xa, xb) = half(&m.x, i);
                let (ya, yb) = half(&m.y, j);
                Rectangle::new([(xa, ya), (xb, yb)], diverging(m.values[i][j], m.limit).filled())
            });
            chart.draw_series(cells).map_err(|e| draw_err(&m.title, e))?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series(label: &str, f: impl Fn(f64) -> f64) -> Series {
        let x: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        Series { label: label.into(), y: x.iter().map(|&v| f(v)).collect(), x }
    }

    fn plot(series: Vec<Series>) -> LinePlot {
        LinePlot {
            title: "Tip deflection".into(),
            x_label: "time [s]".into(),
            y_label: "y(L) [m]".into(),
            series,
            ..Default::default()
        }
    }

    #[test]
    fn renders_svg_with_labels() {
        let mut s2 = series("constant", |_| 3.0);
        s2.y[7] = f64::NAN;
        s2.x[8] = f64::INFINITY;
        let svg = render_svg(&plot(vec![series("rust", |x| x.sin()), s2])).unwrap();
        for text in ["Tip deflection", "time [s]", "y(L) [m]", "rust", "constant", "width=\"900\"", "height=\"600\""] {
            assert!(svg.contains(text), "missing {text}");
        }
        // Only a constant series: zero range must still work.
        render_svg(&plot(vec![series("flat", |_| 0.0)])).unwrap();
    }

    #[test]
    fn log_axes() {
        let mut p = plot(vec![series("err", |x| 10f64.powf(-x)), series("with zero", |x| x)]);
        p.log_y = true;
        p.log_x = true; // x = 0 is dropped
        let svg = render_svg(&p).unwrap();
        assert!(svg.contains("err") && svg.contains("with zero"));
        let all_negative = LinePlot { log_y: true, ..plot(vec![series("neg", |x| -1.0 - x)]) };
        assert!(matches!(render_svg(&all_negative), Err(PlotError::NoPlottablePoints { log_y: true, .. })));
    }

    #[test]
    fn bad_input_errors() {
        let empty = plot(vec![Series { label: "nothing".into(), x: vec![], y: vec![] }]);
        let e = render_svg(&empty).unwrap_err();
        assert!(matches!(e, PlotError::EmptySeries { .. }));
        assert!(e.to_string().contains("'nothing'") && e.to_string().contains("empty"), "{e}");
        assert!(matches!(render_svg(&plot(vec![])), Err(PlotError::NoSeries { .. })));
        let mismatch = plot(vec![Series { label: "m".into(), x: vec![1.0, 2.0], y: vec![1.0] }]);
        assert!(matches!(render_svg(&mismatch), Err(PlotError::LengthMismatch { x_len: 2, y_len: 1, .. })));
        assert!(matches!(render_panels_svg(&[], 2), Err(PlotError::InvalidGrid { .. })));
        assert!(matches!(render_panels_svg(&[plot(vec![series("a", |x| x)])], 0), Err(PlotError::InvalidGrid { .. })));
    }

    #[test]
    fn tick_format() {
        assert_eq!(format_tick(1e-5), "1e-5");
        assert_eq!(format_tick(-2.5e6), "-2.5e6");
        assert_eq!(format_tick(0.25), "0.25");
        assert_eq!(format_tick(0.0), "0");
        assert_eq!(format_tick(3.0), "3");
    }

    #[test]
    fn panels_grid() {
        let names = ["position", "kappa_1", "kappa_2", "kappa_3"];
        let panels: Vec<LinePlot> = names
            .iter()
            .enumerate()
            .map(|(i, n)| LinePlot {
                title: n.to_string(),
                x_label: "s [m]".into(),
                y_label: format!("{n} [1/m]"),
                series: vec![series(&format!("rust {n}"), move |x| (x * i as f64).cos()), series("freefem", |x| x)],
                ..Default::default()
            })
            .collect();
        let svg = render_panels_svg(&panels, 2).unwrap();
        for n in names {
            assert!(svg.contains(n) && svg.contains(&format!("rust {n}")), "{n}");
        }
        assert!(svg.contains("width=\"1800\"") && svg.contains("height=\"1200\""));
    }
}
