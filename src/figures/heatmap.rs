//! Heatmaps (kymographs) and the colour bar every colour-coded figure carries: the quantity and
//! its unit beside a bar of the colour scale with round ticks ([`draw_colour_bar`], also used by
//! the posture figures of [`super::posture`]).

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::ops::Range;

use super::panels::FIGURE_TITLE_STRIP;
use super::plot::{
    axis_tick, draw_err, fit_font, font, nice_ticks, render, text_style, title_strip, PlotError, CHAR_WIDTH, DESC_PX,
    LEGEND_PX, TICK_PX, TITLE_PX, TITLE_STRIP,
};

/// Width of the strip right of a heatmap: head/tail labels, colour bar, its ticks and label [px].
pub(crate) const COLOUR_BAR_STRIP: u32 = 170;

/// How values map to colours on a heatmap.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ColourScale {
    /// Symmetric about 0: blue < 0 < red, clipped at ± the limit.
    #[default]
    Diverging,
    /// From 0 (white) to the limit (dark red), for values ≥ 0.
    Sequential,
}

impl ColourScale {
    /// The colour of `v` on this scale clipped at `limit`.
    fn colour(self, v: f64, limit: f64) -> RGBColor {
        let t = if limit > 0.0 && v.is_finite() { v / limit } else { 0.0 };
        match self {
            ColourScale::Diverging => diverging(t.clamp(-1.0, 1.0)),
            ColourScale::Sequential => diverging(t.clamp(0.0, 1.0)),
        }
    }
    /// The range the colour bar shows.
    fn range(self, limit: f64) -> (f64, f64) {
        match self {
            ColourScale::Diverging => (-limit, limit),
            ColourScale::Sequential => (0.0, limit),
        }
    }
}

/// Blue (−1) through white (0) to dark red (+1); on [0, 1] the sequential scale.
fn diverging(t: f64) -> RGBColor {
    let (r, g, b) = if t >= 0.0 { (1.0 - 0.3 * t, 1.0 - t, 1.0 - t) } else { (1.0 + t, 1.0 + 0.7 * t, 1.0 - 0.3 * t) };
    RGBColor((r * 255.0) as u8, (g * 255.0) as u8, (b * 255.0) as u8)
}

/// A value field over a regular grid drawn as coloured cells (a kymograph): `values[i][j]` at
/// `(x[i], y[j])`, on `scale` clipped at `limit`, with a colour bar labelled `colour_label`.
#[derive(Debug, Clone, PartialEq)]
pub struct Heatmap {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub values: Vec<Vec<f64>>,
    /// The colour scale ends at ± this (a diverging scale) or at this (a sequential one).
    pub limit: f64,
    /// The colour bar's label: the quantity and its unit, e.g. `"κ2 [1/m]"`.
    pub colour_label: String,
    pub scale: ColourScale,
    /// Labels of the bottom and top ends of the y axis (e.g. head and tail).
    pub y_ends: Option<(String, String)>,
}

impl Heatmap {
    /// A kymograph: time `t` [s] along x, arc length `s` [mm] along y from the head (s = 0) to
    /// the tail; diverging colours about 0.
    pub fn kymograph(
        title: String,
        times_s: Vec<f64>,
        s_mm: Vec<f64>,
        values: Vec<Vec<f64>>,
        limit: f64,
        colour_label: String,
    ) -> Self {
        Heatmap {
            title,
            x_label: "t [s]".into(),
            y_label: "arc length s [mm]".into(),
            x: times_s,
            y: s_mm,
            values,
            limit,
            colour_label,
            scale: ColourScale::Diverging,
            y_ends: Some(("head".into(), "tail".into())),
        }
    }
}

/// A vertical colour bar in `area` (coordinates relative to it) at `x`, spanning the pixel
/// rows `y` (top to bottom: `hi` to `lo`), with round ticks and `label` (the quantity and its
/// unit) written upwards beside them. `colour(t)` gives the colour of `t` in [0, 1].
pub(crate) fn draw_colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    x: i32,
    y: Range<i32>,
    colour: &dyn Fn(f64) -> RGBColor,
    (lo, hi): (f64, f64),
    label: &str,
) -> Result<(), PlotError> {
    let (bar_w, h) = (22, (y.end - y.start).max(1));
    let steps = 64;
    for k in 0..steps {
        let (ya, yb) = (y.end - k * h / steps, y.end - (k + 1) * h / steps);
        let c = colour((k as f64 + 0.5) / steps as f64);
        area.draw(&Rectangle::new([(x, ya), (x + bar_w, yb)], c.filled())).map_err(|e| draw_err(label, e))?;
    }
    area.draw(&Rectangle::new([(x, y.start), (x + bar_w, y.end)], BLACK.stroke_width(1)))
        .map_err(|e| draw_err(label, e))?;
    let span = hi - lo;
    let mut widest = 0;
    for v in nice_ticks(lo, hi, 5) {
        let py = if span > 0.0 { y.end - ((v - lo) / span * h as f64).round() as i32 } else { (y.start + y.end) / 2 };
        area.draw(&PathElement::new(vec![(x + bar_w, py), (x + bar_w + 5, py)], BLACK.stroke_width(1)))
            .map_err(|e| draw_err(label, e))?;
        let s = axis_tick(v, span);
        widest = widest.max(s.chars().count());
        area.draw_text(&s, &text_style(TICK_PX), (x + bar_w + 8, py)).map_err(|e| draw_err(label, e))?;
    }
    let lx = x + bar_w + 14 + (widest as f64 * CHAR_WIDTH * TICK_PX as f64) as i32 + DESC_PX as i32 / 2;
    let style = TextStyle::from(font(fit_font(label, h as u32, DESC_PX)).transform(FontTransform::Rotate270))
        .pos(Pos::new(HPos::Center, VPos::Center));
    area.draw_text(label, &style, (lx, (y.start + y.end) / 2)).map_err(|e| draw_err(label, e))
}

/// Columns of the heatmaps of one figure marked for what happened in the frames they stand
/// for: `hatched` columns are drawn over with diagonal lines, `barred` ones get a black bar
/// above the plotting area; a legend row under each title names both (drawn only if any
/// column is marked).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ColumnMarks {
    /// indices into the maps' `x` of the hatched columns
    pub hatched: Vec<usize>,
    pub hatched_label: String,
    /// indices into the maps' `x` of the barred columns
    pub barred: Vec<usize>,
    pub barred_label: String,
}

impl ColumnMarks {
    fn is_empty(&self) -> bool {
        self.hatched.is_empty() && self.barred.is_empty()
    }
}

/// Height of the legend row of [`ColumnMarks`] [px].
const MARKS_ROW: u32 = 24;
/// Spacing of the hatching of a marked column [px].
const HATCH_PX: i32 = 6;
/// The colour of the marks.
const MARK_COLOUR: RGBColor = RGBColor(40, 40, 40);

/// Diagonal lines (`x + y = c`, `c` on a grid of [`HATCH_PX`], so that adjacent columns join)
/// over the pixel rectangle `[x0, x1] × [y0, y1]` of `area`.
fn hatch<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (x0, x1): (i32, i32),
    (y0, y1): (i32, i32),
) -> Result<(), PlotError> {
    let first = (x0 + y0).div_euclid(HATCH_PX) * HATCH_PX;
    for c in (first..=x1 + y1).step_by(HATCH_PX as usize) {
        let (lo, hi) = ((c - y1).max(x0), (c - y0).min(x1));
        if lo < hi {
            area.draw(&PathElement::new(vec![(lo, c - lo), (hi, c - hi)], MARK_COLOUR.stroke_width(1)))
                .map_err(|e| draw_err("marks", e))?;
        }
    }
    Ok(())
}

/// The legend of `marks` in `row`, from `left` [px]: a sample of each mark and its label.
fn draw_marks_legend<DB: DrawingBackend>(
    row: &DrawingArea<DB, Shift>,
    marks: &ColumnMarks,
    left: i32,
) -> Result<(), PlotError> {
    let mid = MARKS_ROW as i32 / 2;
    let style = text_style(LEGEND_PX).pos(Pos::new(HPos::Left, VPos::Center));
    let mut x = left;
    for (hatched, label) in [(true, &marks.hatched_label), (false, &marks.barred_label)] {
        if (hatched && marks.hatched.is_empty()) || (!hatched && marks.barred.is_empty()) {
            continue;
        }
        if hatched {
            row.draw(&Rectangle::new([(x, mid - 7), (x + 14, mid + 7)], MARK_COLOUR.stroke_width(1)))
                .map_err(|e| draw_err(label, e))?;
            hatch(row, (x, x + 14), (mid - 7, mid + 7))?;
        } else {
            row.draw(&Rectangle::new([(x, mid - 3), (x + 14, mid + 3)], MARK_COLOUR.filled()))
                .map_err(|e| draw_err(label, e))?;
        }
        row.draw_text(label, &style, (x + 20, mid)).map_err(|e| draw_err(label, e))?;
        x += 20 + (label.chars().count() as f64 * CHAR_WIDTH * LEGEND_PX as f64) as i32 + 28;
    }
    Ok(())
}

/// The marks of `marks` on the heatmap `m` drawn in `area`; `px` maps a point of the map to
/// the pixels of `area`.
fn draw_marks<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    px: &dyn Fn(f64, f64) -> (i32, i32),
    m: &Heatmap,
    marks: &ColumnMarks,
) -> Result<(), PlotError> {
    let (y0, y1) = (m.y[0], m.y[m.y.len() - 1]);
    let column = |i: usize| {
        let lo = if i == 0 { m.x[0] } else { 0.5 * (m.x[i - 1] + m.x[i]) };
        let hi = if i + 1 == m.x.len() { m.x[i] } else { 0.5 * (m.x[i] + m.x[i + 1]) };
        let ((a, top), (b, bottom)) = (px(lo, y1), px(hi, y0));
        // at least 2 px wide, so that a lone marked column stays visible
        ((a.min(b), a.max(b).max(a.min(b) + 2)), (top.min(bottom), top.max(bottom)))
    };
    for &i in marks.hatched.iter().filter(|&&i| i < m.x.len()) {
        let (xs, ys) = column(i);
        hatch(area, xs, ys)?;
    }
    for &i in marks.barred.iter().filter(|&&i| i < m.x.len()) {
        let ((a, b), (top, _)) = column(i);
        let (a, b) = (a.min(b - 4), b);
        area.draw(&Rectangle::new([(a, top - 9), (b, top - 1)], MARK_COLOUR.filled()))
            .map_err(|e| draw_err("marks", e))?;
    }
    Ok(())
}

/// Checks the grid of every map.
fn validate_maps(maps: &[Heatmap]) -> Result<(), PlotError> {
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
    Ok(())
}

/// One heatmap in `area`: title strip (and the legend row of `marks`), cells, the marks, the y
/// ends' labels and the colour bar.
fn draw_heatmap<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    m: &Heatmap,
    marks: &ColumnMarks,
) -> Result<(), PlotError> {
    let t = m.title.as_str();
    let (w, _) = area.dim_in_pixel();
    let body = title_strip(area, t, TITLE_STRIP, TITLE_PX)?;
    let body = if marks.is_empty() {
        body
    } else {
        let (row, body) = body.split_vertically(MARKS_ROW);
        draw_marks_legend(&row, marks, 90)?;
        body
    };
    let (chart_area, _) = body.split_horizontally(w - COLOUR_BAR_STRIP);
    let (x0, x1) = (m.x[0], m.x[m.x.len() - 1]);
    let (y0, y1) = (m.y[0], m.y[m.y.len() - 1]);
    let mut chart = ChartBuilder::on(&chart_area)
        .margin(10)
        .x_label_area_size(58)
        .y_label_area_size(80)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| draw_err(t, e))?;
    let (sx, sy) = (x1 - x0, y1 - y0);
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(m.x_label.as_str())
        .y_desc(m.y_label.as_str())
        .label_style(font(TICK_PX))
        .axis_desc_style(font(DESC_PX))
        .x_label_formatter(&|v| axis_tick(*v, sx))
        .y_label_formatter(&|v| axis_tick(*v, sy))
        .draw()
        .map_err(|e| draw_err(t, e))?;
    let half = |v: &[f64], i: usize| -> (f64, f64) {
        let lo = if i == 0 { v[0] } else { 0.5 * (v[i - 1] + v[i]) };
        let hi = if i + 1 == v.len() { v[i] } else { 0.5 * (v[i] + v[i + 1]) };
        (lo, hi)
    };
    let cells = (0..m.x.len()).flat_map(|i| (0..m.y.len()).map(move |j| (i, j))).map(|(i, j)| {
        let (xa, xb) = half(&m.x, i);
        let (ya, yb) = half(&m.y, j);
        Rectangle::new([(xa, ya), (xb, yb)], m.scale.colour(m.values[i][j], m.limit).filled())
    });
    chart.draw_series(cells).map_err(|e| draw_err(t, e))?;
    let base = area.get_base_pixel();
    let to_area = |x: f64, y: f64| {
        let (a, b) = chart.backend_coord(&(x, y));
        (a - base.0, b - base.1)
    };
    draw_marks(area, &to_area, m, marks)?;
    // the plotting area in the pixels of `area`
    let (px, py) = chart.plotting_area().get_pixel_range();
    let (right, rows) = (px.end - base.0, (py.start - base.1)..(py.end - base.1));
    if let Some((bottom, top)) = &m.y_ends {
        area.draw_text(top, &text_style(LEGEND_PX).pos(Pos::new(HPos::Left, VPos::Top)), (right + 6, rows.start))
            .map_err(|e| draw_err(t, e))?;
        area.draw_text(bottom, &text_style(LEGEND_PX).pos(Pos::new(HPos::Left, VPos::Bottom)), (right + 6, rows.end))
            .map_err(|e| draw_err(t, e))?;
    }
    let (scale, limit) = (m.scale, m.limit);
    let (lo, hi) = scale.range(limit);
    let colour = move |u: f64| scale.colour(lo + u * (hi - lo), limit);
    draw_colour_bar(area, right + 50, rows, &colour, (lo, hi), &m.colour_label)
}

/// Size of one heatmap [px]: wide, for a long time axis.
pub const HEATMAP_SIZE: (u32, u32) = (1200, 440);

/// Heatmaps from top to bottom (one column, as the paper's kymographs) in one SVG, each with its
/// colour bar.
pub fn render_heatmaps_svg(maps: &[Heatmap]) -> Result<String, PlotError> {
    render_marked_heatmaps_svg(maps, &ColumnMarks::default())
}

/// [`render_heatmaps_svg`] with the columns of `marks` marked on every map (maps of one time
/// axis), and its legend under each title.
pub fn render_marked_heatmaps_svg(maps: &[Heatmap], marks: &ColumnMarks) -> Result<String, PlotError> {
    render_maps(None, maps, marks)
}

/// [`render_heatmaps_svg`] under `title`, in a strip of its own above the maps (as
/// [`super::panels::render_figure_svg`]); each map keeps its own title.
pub fn render_figure_heatmaps_svg(title: &str, maps: &[Heatmap]) -> Result<String, PlotError> {
    render_maps(Some(title), maps, &ColumnMarks::default())
}

/// The maps from top to bottom, under the figure title `title` if given.
fn render_maps(title: Option<&str>, maps: &[Heatmap], marks: &ColumnMarks) -> Result<String, PlotError> {
    validate_maps(maps)?;
    let strip = if title.is_some() { FIGURE_TITLE_STRIP } else { 0 };
    let size = (HEATMAP_SIZE.0, HEATMAP_SIZE.1 * maps.len() as u32 + strip);
    let name = title.map_or_else(|| maps[0].title.clone(), str::to_string);
    render(size, &name, |root| {
        let body = match title {
            Some(t) => title_strip(root, t, FIGURE_TITLE_STRIP, TITLE_PX + 3)?,
            None => root.clone(),
        };
        for (m, area) in maps.iter().zip(body.split_evenly((maps.len(), 1))) {
            draw_heatmap(&area, m, marks)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::figures::plot::smallest_text;

    #[test]
    fn heatmap_has_a_colour_bar_with_its_unit_and_the_ends_labelled() {
        let x = vec![0.0, 0.04, 0.08];
        let y = vec![0.0, 0.5, 1.0];
        let values = vec![vec![-1.0, 0.0, 1.0]; 3];
        let m = Heatmap::kymograph("k".into(), x, y, values, 1.0, "κ2 [1/mm]".into());
        let svg = render_heatmaps_svg(&[m]).unwrap();
        for text in ["κ2 [1/mm]", "t [s]", "\nhead\n", "\ntail\n", "\n-1\n", "\n0\n", "\n1\n"] {
            assert!(svg.contains(text), "missing {text}");
        }
        assert!(smallest_text(&svg) >= 12.0);
    }

    /// Under a figure title, each map keeps its own title and no text runs into another.
    #[test]
    fn a_figure_title_has_a_strip_of_its_own() {
        let x: Vec<f64> = (0..40).map(|i| i as f64 * 1.2).collect();
        let y: Vec<f64> = (0..20).map(|j| j as f64 * 0.05).collect();
        let map = |c: usize| {
            let v = vec![vec![0.5; y.len()]; x.len()];
            Heatmap::kymograph(format!("κ{c}"), x.clone(), y.clone(), v, 1.0, format!("κ{c} [1/mm]"))
        };
        let title = "Fig. 25: κ with Λκ = diag(0, 0, 1e-20), Λω = diag(0, 0, 1e-10), the caption's set";
        let svg = render_figure_heatmaps_svg(title, &[map(1), map(2), map(3)]).unwrap();
        assert!(svg.contains(&format!("height=\"{}\"", 3 * HEATMAP_SIZE.1 + FIGURE_TITLE_STRIP)));
        let texts = crate::figures::svg_text::texts(&svg);
        assert!(texts.iter().any(|t| t.text == title) && texts.iter().any(|t| t.text == "κ1"));
        assert_eq!(crate::figures::svg_text::overlaps(&svg), Vec::<(String, String)>::new());
    }

    /// Marked columns are hatched or barred on every map, with a legend under each title;
    /// without marks there is neither.
    #[test]
    fn marked_columns_are_hatched_or_barred_with_a_legend() {
        let x: Vec<f64> = (0..20).map(|i| i as f64 * 0.04).collect();
        let y = vec![0.0, 0.5, 1.0];
        let m = Heatmap::kymograph("k".into(), x.clone(), y, vec![vec![0.5; 3]; 20], 1.0, "κ [1/mm]".into());
        let plain = render_heatmaps_svg(&[m.clone(), m.clone()]).unwrap();
        let marks = ColumnMarks {
            hatched: vec![3, 4],
            hatched_label: "lost frames".into(),
            barred: vec![10],
            barred_label: "flagged frames".into(),
        };
        let marked = render_marked_heatmaps_svg(&[m.clone(), m], &marks).unwrap();
        let lines = |svg: &str| svg.matches("stroke=\"#282828\"").count();
        let bars = |svg: &str| svg.matches("fill=\"#282828\"").count();
        assert_eq!((lines(&plain), bars(&plain)), (0, 0));
        assert!(!plain.contains("lost frames"));
        assert_eq!(marked.matches("lost frames").count(), 2);
        assert_eq!(marked.matches("flagged frames").count(), 2);
        // two columns of ~45 px × ~300 px: dozens of hatch lines per map; one bar per map and
        // one in each legend
        assert!(lines(&marked) > 2 * 20, "{}", lines(&marked));
        assert_eq!(bars(&marked), 4);
    }
}
