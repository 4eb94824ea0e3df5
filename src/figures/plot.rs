//! Thin helpers over plotters' SVG backend: line plots (optionally log axes) and grids of
//! sub-plots, rendered to SVG text (written by `io::files::write_atomic`); the text, tick and
//! title conventions that the heatmaps ([`super::heatmap`]) and posture figures share.
//!
//! Every figure follows the same rules: text at least [`MIN_TEXT_PX`] px at the saved size,
//! the legend in a strip beside the data (never over it), tick labels without floating-point
//! noise (a tick within 1e-9 of the axis span of 0 is "0"), and on every heatmap a colour bar
//! with the quantity and its unit ([`super::heatmap::draw_colour_bar`], shared with the posture
//! figures).

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::ops::Range;
use thiserror::Error;

/// Size of a single plot in pixels (width, height).
pub const PLOT_SIZE: (u32, u32) = (900, 600);
/// Fractional margin added on each side of the data range (linear axes).
pub const RANGE_MARGIN: f64 = 0.05;
pub use super::figure_text::MIN_TEXT_PX;
pub(crate) use super::figure_text::{
    axis_tick, fit_font, font, format_tick, nice_ticks, text_style, wrap, CHAR_WIDTH, DESC_PX, LEGEND_PX, TICK_PX,
    TITLE_PX, TITLE_STRIP,
};

/// A qualitative palette (Tableau 10): distinct at a glance and in print.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Colour `i` of the palette (cycling).
pub(crate) fn palette(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// How a curve is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mark {
    /// A solid line (a solution).
    #[default]
    Line,
    /// A dashed line (a reference).
    Dashed,
    /// Open circles, at most [`MAX_MARKERS`] per curve, drawn under the lines (data).
    Markers,
}

/// At most this many markers per curve (every k-th point).
pub const MAX_MARKERS: usize = 40;

/// One curve: `y[i]` against `x[i]`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Series {
    /// Legend entry.
    pub label: String,
    /// Abscissae (any unit; same length as `y`).
    pub x: Vec<f64>,
    /// Ordinates.
    pub y: Vec<f64>,
    /// Line, dashed line or markers.
    pub mark: Mark,
    /// Palette index of its colour; `None`: the curve's position in the plot.
    pub colour: Option<usize>,
    /// Line width [px]; 0: 2 px.
    pub width: u32,
}

impl Series {
    /// A solid curve in the colour of its position.
    pub fn new(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Series { label: label.into(), x, y, ..Default::default() }
    }
    /// The same curve drawn as `mark`.
    pub fn marked(mut self, mark: Mark) -> Self {
        self.mark = mark;
        self
    }
    /// The same curve in palette colour `i` (pairs of data and solution share one).
    pub fn coloured(mut self, i: usize) -> Self {
        self.colour = Some(i);
        self
    }
    /// Curve `i` of a comparison of runs whose curves may lie on each other: each narrower than
    /// the one before (4, 3, 2, 1 px …) and every second one dashed, so that all stay visible.
    pub fn nth_of_many(mut self, i: usize) -> Self {
        self.width = 4u32.saturating_sub(i as u32).max(1);
        if i % 2 == 1 {
            self.mark = Mark::Dashed;
        }
        self
    }
}

/// A shaded interval of x with a label (e.g. the clamped end elements).
#[derive(Debug, Clone, PartialEq)]
pub struct Band {
    /// From this x …
    pub from: f64,
    /// … to this x (the plot's unit).
    pub to: f64,
    /// Written at the top of the band.
    pub label: String,
}

/// How an axis maps its values: linearly, or by their logarithm (only positive values drawn).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Scale {
    #[default]
    Linear,
    Log,
}

impl Scale {
    /// Is this a logarithmic axis?
    pub fn is_log(self) -> bool {
        self == Scale::Log
    }
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
    /// Curves, drawn in order with distinct colours (markers first, under the lines).
    pub series: Vec<Series>,
    /// The x axis's scale.
    pub x_scale: Scale,
    /// The y axis's scale (a log axis is padded to whole decades, so that it always has
    /// labelled ticks).
    pub y_scale: Scale,
    /// Whether the legend strip is drawn.
    pub legend: Legend,
    /// Shaded x intervals.
    pub bands: Vec<Band>,
    /// The y values drawn, if not all: points outside `(lo, hi)` are left out like
    /// non-finite ones (a line breaks there), and the axis spans the points kept.
    pub y_window: Option<(f64, f64)>,
}

/// The legend of a plot: in a strip right of the data, or none.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Legend {
    /// Beside the data, right of the axes.
    #[default]
    Right,
    /// No legend (a single curve described by the axis).
    Hidden,
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
    /// A grid of panels (`super::panels`) with no panels or zero columns.
    #[error("invalid panel grid: {panels} panel(s) in {cols} column(s)")]
    InvalidGrid { panels: usize, cols: usize },
    /// Drawing failed inside plotters.
    #[error("drawing plot '{title}' failed: {detail}")]
    Draw { title: String, detail: String },
}

pub(crate) fn draw_err(title: &str, e: impl std::fmt::Display) -> PlotError {
    PlotError::Draw { title: title.to_string(), detail: e.to_string() }
}

fn keep(v: f64, scale: Scale) -> bool {
    v.is_finite() && (scale == Scale::Linear || v > 0.0)
}

/// Whether the point (x, y) of `plot` is drawn: finite, positive on a log axis, y inside the
/// plot's window.
fn kept(plot: &LinePlot, x: f64, y: f64) -> bool {
    keep(x, plot.x_scale) && keep(y, plot.y_scale) && plot.y_window.is_none_or(|(lo, hi)| lo <= y && y <= hi)
}

/// Validates `plot` and returns the padded (x, y) ranges.
pub(crate) fn ranges(plot: &LinePlot) -> Result<(Range<f64>, Range<f64>), PlotError> {
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
            if kept(plot, x, y) {
                (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            }
        }
    }
    if x0 > x1 {
        return Err(PlotError::NoPlottablePoints {
            title: plot.title.clone(),
            log_x: plot.x_scale.is_log(),
            log_y: plot.y_scale.is_log(),
        });
    }
    Ok((pad(x0, x1, plot.x_scale), pad(y0, y1, plot.y_scale)))
}

/// Adds a margin; a log axis is widened to whole decades (at least one), so that it has
/// labelled ticks; a zero-width linear range is widened.
fn pad(lo: f64, hi: f64, scale: Scale) -> Range<f64> {
    if scale == Scale::Log {
        let a = (lo.log10() + 1e-9).floor();
        let b = (hi.log10() - 1e-9).ceil().max(a + 1.0);
        // a hair beyond the decades, so that round-off keeps both end ticks inside
        return 10f64.powf(a) * (1.0 - 1e-9)..10f64.powf(b) * (1.0 + 1e-9);
    }
    if hi > lo {
        let m = RANGE_MARGIN * (hi - lo);
        (lo - m)..(hi + m)
    } else {
        let m = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        (lo - m)..(hi + m)
    }
}

/// Writes `title` centred in a strip `height` px high at the top of `area` (at most `max_px`
/// px, smaller for a long title) and returns the rest of `area`.
pub(crate) fn title_strip<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    height: u32,
    max_px: u32,
) -> Result<DrawingArea<DB, Shift>, PlotError> {
    let (w, _) = area.dim_in_pixel();
    let (head, body) = area.split_vertically(height);
    let style =
        TextStyle::from(font(fit_font(title, w.saturating_sub(20), max_px))).pos(Pos::new(HPos::Center, VPos::Center));
    head.draw_text(title, &style, (w as i32 / 2, height as i32 / 2)).map_err(|e| draw_err(title, e))?;
    Ok(body)
}

/// The stroke of curve `i` of a plot.
fn stroke(s: &Series, i: usize) -> ShapeStyle {
    ShapeStyle::from(palette(s.colour.unwrap_or(i))).stroke_width(if s.width == 0 { 2 } else { s.width })
}

/// Width of the legend strip of `plot` in a panel `width` px wide.
fn legend_width(plot: &LinePlot, width: u32) -> u32 {
    if plot.legend == Legend::Hidden {
        return 0;
    }
    let longest = plot.series.iter().map(|s| s.label.chars().count()).max().unwrap_or(0) as f64;
    ((longest * CHAR_WIDTH * LEGEND_PX as f64) as u32 + 60).clamp(140, (width * 2) / 5)
}

/// The legend of `plot` in its strip: a sample of each curve's mark and its label, wrapped.
fn draw_legend<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, plot: &LinePlot, top: i32) -> Result<(), PlotError> {
    let t = plot.title.as_str();
    let (w, _) = area.dim_in_pixel();
    let chars = ((w as f64 - 52.0) / (CHAR_WIDTH * LEGEND_PX as f64)).max(8.0) as usize;
    let line_h = (LEGEND_PX as f64 * 1.25) as i32;
    let mut y = top + line_h / 2;
    for (i, s) in plot.series.iter().enumerate() {
        let st = stroke(s, i);
        match s.mark {
            Mark::Line => area.draw(&PathElement::new(vec![(6, y), (38, y)], st)),
            Mark::Dashed => [(6, 14), (20, 28), (34, 38)]
                .iter()
                .try_for_each(|&(a, b)| area.draw(&PathElement::new(vec![(a, y), (b, y)], st))),
            Mark::Markers => [12, 30].iter().try_for_each(|&x| area.draw(&Circle::new((x, y), 4, st.stroke_width(2)))),
        }
        .map_err(|e| draw_err(t, e))?;
        for (k, l) in wrap(&s.label, chars).iter().enumerate() {
            area.draw_text(l, &text_style(LEGEND_PX), (46, y + k as i32 * line_h)).map_err(|e| draw_err(t, e))?;
            if k > 0 {
                y += line_h;
            }
        }
        y += line_h + 4;
    }
    Ok(())
}

/// Draws one plot into `area` with the given coordinate specs: title strip, chart, legend
/// strip on the right.
fn draw_with<DB, X, Y>(
    area: &DrawingArea<DB, Shift>,
    plot: &LinePlot,
    xs: X,
    ys: Y,
    (ax, ay): (Axis, Axis),
) -> Result<(), PlotError>
where
    DB: DrawingBackend,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let t = plot.title.as_str();
    let (w, _) = area.dim_in_pixel();
    let body = title_strip(area, t, TITLE_STRIP, TITLE_PX)?;
    let lw = legend_width(plot, w);
    let (chart_area, legend_area) = body.split_horizontally(w - lw);
    let mut chart = ChartBuilder::on(&chart_area)
        .margin(10)
        .margin_right(right_margin(plot, ax, lw))
        .x_label_area_size(58)
        .y_label_area_size(96)
        .build_cartesian_2d(xs, ys)
        .map_err(|e| draw_err(t, e))?;
    chart
        .configure_mesh()
        .x_desc(plot.x_label.as_str())
        .y_desc(plot.y_label.as_str())
        .label_style(font(TICK_PX))
        .axis_desc_style(font(DESC_PX))
        .x_label_formatter(&|v| ax.label(*v))
        .y_label_formatter(&|v| ay.label(*v))
        .light_line_style(BLACK.mix(0.04))
        .bold_line_style(BLACK.mix(0.12))
        .draw()
        .map_err(|e| draw_err(t, e))?;
    let (yr, top) = (chart.y_range(), chart.plotting_area().get_pixel_range().1.start - body.get_base_pixel().1);
    for b in &plot.bands {
        let shade = Rectangle::new([(ax.to(b.from), yr.start), (ax.to(b.to), yr.end)], BLACK.mix(0.10).filled());
        chart.draw_series(std::iter::once(shade)).map_err(|e| draw_err(t, e))?;
        // the label inside the band's edge nearer the middle of the plot
        let (left, _) = chart.backend_coord(&(ax.to(b.from), yr.end));
        let (right, py) = chart.backend_coord(&(ax.to(b.to), yr.end));
        let middle = chart.plotting_area().get_pixel_range().0;
        let base = chart_area.get_base_pixel();
        let (x, anchor) =
            if left - middle.start < middle.end - right { (left + 4, HPos::Left) } else { (right - 4, HPos::Right) };
        let style = text_style(LEGEND_PX).pos(Pos::new(anchor, VPos::Top));
        chart_area.draw_text(&b.label, &style, (x - base.0, py - base.1 + 4)).map_err(|e| draw_err(t, e))?;
    }
    for i in drawing_order(plot) {
        let s = &plot.series[i];
        let style = stroke(s, i);
        let every = s.x.len().div_ceil(MAX_MARKERS).max(1);
        for run in plottable_runs(plot, s, (ax, ay)) {
            match s.mark {
                Mark::Line => chart.draw_series(LineSeries::new(run, style)).map(|_| ()),
                Mark::Dashed => chart.draw_series(DashedLineSeries::new(run, 9, 6, style)).map(|_| ()),
                Mark::Markers => chart
                    .draw_series(run.into_iter().step_by(every).map(|p| Circle::new(p, 4, style.stroke_width(2))))
                    .map(|_| ()),
            }
            .map_err(|e| draw_err(t, e))?;
        }
    }
    if lw > 0 {
        draw_legend(&legend_area, plot, top)?;
    }
    Ok(())
}

/// The margin right of the chart [px]: 10, or, without a legend strip (`legend_width` 0) to
/// take it, room for half the widest tick label of the x axis's ends, which is centred on the
/// chart's right edge and was cut off at the figure's edge.
fn right_margin(plot: &LinePlot, ax: Axis, legend_width: u32) -> u32 {
    if legend_width > 0 {
        return 10;
    }
    let Ok((xr, _)) = ranges(plot) else { return 10 };
    let chars = [xr.start, xr.end].iter().map(|v| ax.label(ax.to(*v)).chars().count()).max().unwrap_or(0);
    10 + (chars as f64 * CHAR_WIDTH * TICK_PX as f64 / 2.0).ceil() as u32
}

/// The order the series of `plot` are drawn in: markers first, so that the lines of the
/// solution lie on the data.
fn drawing_order(plot: &LinePlot) -> Vec<usize> {
    let order = (0..plot.series.len()).filter(|&i| plot.series[i].mark == Mark::Markers);
    order.chain((0..plot.series.len()).filter(|&i| plot.series[i].mark != Mark::Markers)).collect()
}

/// The points of `s` in drawing coordinates, split into runs of plottable points (finite, and
/// positive on a log axis) so that lines break at gaps; no run is empty.
fn plottable_runs(plot: &LinePlot, s: &Series, (ax, ay): (Axis, Axis)) -> Vec<Vec<(f64, f64)>> {
    let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    for (&x, &y) in s.x.iter().zip(&s.y) {
        if kept(plot, x, y) {
            if let Some(r) = runs.last_mut() {
                r.push((ax.to(x), ay.to(y)));
            }
        } else if runs.last().is_some_and(|r| !r.is_empty()) {
            runs.push(Vec::new());
        }
    }
    runs.retain(|r| !r.is_empty());
    runs
}

/// How an axis's values are drawn: on a log axis scaled by `factor` so that its range starts at
/// 1 (plotters draws no tick below 2.2e-16 on a log axis), labelled with the values themselves.
#[derive(Clone, Copy)]
struct Axis {
    factor: f64,
    span: f64,
    scale: Scale,
}

impl Axis {
    /// The axis of `range` (padded) and its drawn range.
    fn new(range: Range<f64>, scale: Scale) -> (Self, Range<f64>) {
        let factor = if scale == Scale::Log { 1.0 / range.start } else { 1.0 };
        let axis = Axis { factor, span: range.end - range.start, scale };
        (axis, range.start * factor..range.end * factor)
    }
    fn to(self, v: f64) -> f64 {
        v * self.factor
    }
    fn label(self, v: f64) -> String {
        if self.scale == Scale::Log {
            format_tick(v / self.factor)
        } else {
            axis_tick(v, self.span)
        }
    }
}

pub(crate) fn draw_plot<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, plot: &LinePlot) -> Result<(), PlotError> {
    let (xr, yr) = ranges(plot)?;
    let ((ax, xr), (ay, yr)) = (Axis::new(xr, plot.x_scale), Axis::new(yr, plot.y_scale));
    use Scale::{Linear, Log};
    match (plot.x_scale, plot.y_scale) {
        (Linear, Linear) => draw_with(area, plot, xr, yr, (ax, ay)),
        (Log, Linear) => draw_with(area, plot, xr.log_scale(), yr, (ax, ay)),
        (Linear, Log) => draw_with(area, plot, xr, yr.log_scale(), (ax, ay)),
        (Log, Log) => draw_with(area, plot, xr.log_scale(), yr.log_scale(), (ax, ay)),
    }
}

/// Renders `draw` into an in-memory SVG of `size` pixels.
pub(crate) fn render(
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

/// The smallest `font-size` of an SVG [px] (tests of the figures).
#[cfg(test)]
pub(crate) fn smallest_text(svg: &str) -> f64 {
    svg.split("font-size=\"").skip(1).filter_map(|r| r.split('"').next()?.parse::<f64>().ok()).fold(f64::MAX, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series(label: &str, f: impl Fn(f64) -> f64) -> Series {
        let x: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        let y = x.iter().map(|&v| f(v)).collect();
        Series::new(label, x, y)
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
        p.y_scale = Scale::Log;
        p.x_scale = Scale::Log; // x = 0 is dropped
        let svg = render_svg(&p).unwrap();
        assert!(svg.contains("err") && svg.contains("with zero"));
        let all_negative = LinePlot { y_scale: Scale::Log, ..plot(vec![series("neg", |x| -1.0 - x)]) };
        assert!(matches!(render_svg(&all_negative), Err(PlotError::NoPlottablePoints { log_y: true, .. })));
    }

    #[test]
    fn bad_input_errors() {
        let empty = plot(vec![Series::new("nothing", vec![], vec![])]);
        let e = render_svg(&empty).unwrap_err();
        assert!(matches!(e, PlotError::EmptySeries { .. }));
        assert!(e.to_string().contains("'nothing'") && e.to_string().contains("empty"), "{e}");
        assert!(matches!(render_svg(&plot(vec![])), Err(PlotError::NoSeries { .. })));
        let mismatch = plot(vec![Series::new("m", vec![1.0, 2.0], vec![1.0])]);
        assert!(matches!(render_svg(&mismatch), Err(PlotError::LengthMismatch { x_len: 2, y_len: 1, .. })));
    }

    /// A y window leaves out the points outside it (the line breaks there) and the axis spans
    /// the points kept: a spike of 100 on a curve within ±1 leaves the axis at ±1.
    #[test]
    fn a_y_window_leaves_out_the_points_outside_it() {
        let mut s = series("wave", |x| (x * 2.0).sin());
        s.y[3] = 100.0;
        let mut p = plot(vec![s]);
        assert!(ranges(&p).unwrap().1.end > 100.0);
        p.y_window = Some((-1.0, 1.0));
        let (_, y) = ranges(&p).unwrap();
        assert!(y.end <= 1.0 + 2.0 * RANGE_MARGIN && y.start >= -1.0 - 2.0 * RANGE_MARGIN, "{y:?}");
        let runs = plottable_runs(
            &p,
            &p.series[0],
            (Axis::new(0.0..1.0, Scale::Linear).0, Axis::new(0.0..1.0, Scale::Linear).0),
        );
        assert_eq!(runs.iter().map(Vec::len).collect::<Vec<_>>(), [3, 46], "broken at the spike");
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
    fn ticks_without_round_off_and_text_of_readable_size() {
        assert_eq!(axis_tick(-1.39e-17, 0.02), "0");
        assert_eq!(axis_tick(-1.39e-17, 1e-15), "-1.39e-17");
        assert_eq!(nice_ticks(-2.2, 2.2, 5), vec![-2.0, -1.0, 0.0, 1.0, 2.0]);
        let labels: Vec<String> = nice_ticks(705.80, 705.85, 5).iter().map(|v| axis_tick(*v, 0.05)).collect();
        assert_eq!(labels, ["705.8", "705.82", "705.84"]);
        let svg = render_svg(&plot(vec![series("a", |x| x - 2.0)])).unwrap();
        assert!(smallest_text(&svg) >= 12.0, "{}", smallest_text(&svg));
        // a log axis far below 1e-15 still has its decades labelled
        let tiny = LinePlot { y_scale: Scale::Log, ..plot(vec![series("tiny", |x| 1e-22 * (1.0 + x))]) };
        let svg = render_svg(&tiny).unwrap();
        assert!(svg.contains("\n1e-22\n") && svg.contains("\n1e-21\n"), "decades missing");
    }
}
