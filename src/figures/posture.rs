//! Posture figures of a rod (cf. Figs. 16, 21 and 22 of Wang et al., Comput. Mech. 71, 2023):
//! the 3-D centreline with its material frame, one row per frame and three orthogonal
//! projections (x–y, x–z, y–z) per row, rendered to SVG text with plotters.
//!
//! The directors `d1`, `d3` are rows of the frame matrix `Q` (eq. 2); `d3` is the cross-section
//! normal. The shear/stretch term of the objective (the `Λ`/`λ_d` weights of eq. 41) penalises
//! `∂s x − d3`, so the finite-difference tangent is drawn next to `d3` (thin red against black)
//! to make a detachment of the frame from the centreline visible, as in Fig. 21.

use super::heatmap::{draw_colour_bar, COLOUR_BAR_STRIP};
use super::plot::{draw_err, draw_panels, font, title_strip, LinePlot, PlotError, PLOT_SIZE};
use nalgebra::Vector3;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// One panel: one frame of a rod.
#[derive(Debug, Clone, PartialEq)]
pub struct PosturePanel {
    /// panel title, e.g. "frame 700"
    pub label: String,
    /// centreline node positions [m]
    pub x: Vec<Vector3<f64>>,
    /// director d1 per node (unit; a row of Q, eq. 2)
    pub d1: Vec<Vector3<f64>>,
    /// director d3 per node (unit, the cross-section normal; a row of Q, eq. 2)
    pub d3: Vec<Vector3<f64>>,
    /// colour value per node, e.g. |κ| [1/m]; colours the centreline (viridis-like scale)
    pub colour: Vec<f64>,
    /// label of the colour quantity, e.g. "|kappa| [1/m]"
    pub colour_label: String,
}

/// Side of one (square) projection cell [px].
const CELL: u32 = 480;
/// Height of the figure title strip [px].
const TITLE_H: u32 = 40;
/// Height of the caption strip above each row [px].
const CAPTION_H: u32 = 34;
/// Outer margin of each projection chart [px].
const MARGIN: u32 = 10;
/// Label area below (x axis) and left of (y axis) each chart [px].
const X_LABEL_AREA: u32 = 40;
const Y_LABEL_AREA: u32 = 62;
/// About this many frame glyphs are drawn along a rod.
const SAMPLES_PER_ROD: f64 = 16.0;
/// Length of the frame glyphs as a fraction of the rod's extent.
const GLYPH_FRACTION: f64 = 0.04;
/// Stroke colour of the `d3` arrows (visually black, distinct from the axes' pure black).
const ARROW_COLOUR: RGBColor = RGBColor(0x14, 0x14, 0x14);
/// Stroke colour of the `d1` ribbon ticks.
const RIBBON_COLOUR: RGBColor = RGBColor(0x8c, 0x8c, 0x8c);
/// Stroke colour of the finite-difference tangent.
const TANGENT_COLOUR: RGBColor = RGBColor(0xe0, 0x10, 0x10);
/// The projections: (first coordinate, second coordinate, their names).
const PROJECTIONS: [(usize, usize, &str, &str); 3] = [(0, 1, "x", "y"), (0, 2, "x", "z"), (1, 2, "y", "z")];
/// Viridis sampled at 0, 1/8, …, 1 (linearly interpolated in between).
const VIRIDIS: [(u8, u8, u8); 9] = [
    (68, 1, 84),
    (71, 44, 122),
    (59, 81, 139),
    (44, 113, 142),
    (33, 144, 141),
    (39, 173, 129),
    (92, 200, 99),
    (170, 220, 50),
    (253, 231, 37),
];

/// Viridis-like colour for `t` in [0, 1] (clamped; non-finite → the middle of the scale).
fn viridis(t: f64) -> RGBColor {
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.5 };
    let f = t * (VIRIDIS.len() - 1) as f64;
    let i = (f.floor() as usize).min(VIRIDIS.len() - 2);
    let w = f - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let mix = |p: u8, q: u8| (p as f64 + w * (q as f64 - p as f64)).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Step between the nodes that carry frame glyphs (about [`SAMPLES_PER_ROD`] per rod).
fn sample_step(n: usize) -> usize {
    ((n as f64 / SAMPLES_PER_ROD).round() as usize).max(1)
}

/// Compact number for captions and tick labels (the line plots' tick format).
fn fmt_num(v: f64) -> String {
    super::plot::format_tick(v)
}

/// `v` rounded to two significant digits (a caption's measure).
fn sig2(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let p = 10f64.powi(1 - v.abs().log10().floor() as i32);
    (v * p).round() / p
}

/// Tick label on an axis of half-width `half`: round-off next to 0 shows as "0".
fn tick(v: f64, half: f64) -> String {
    fmt_num(if v.abs() < 1e-9 * half { 0.0 } else { v })
}

/// Checks lengths (equal, at least 2 nodes) and finiteness of one panel.
fn validate(p: &PosturePanel) -> Result<(), PlotError> {
    let t = p.label.as_str();
    let n = p.x.len();
    if n == 0 {
        return Err(PlotError::EmptySeries { title: t.into(), series: "x".into() });
    }
    for (name, len) in [("d1", p.d1.len()), ("d3", p.d3.len()), ("colour", p.colour.len())] {
        if len != n {
            return Err(PlotError::LengthMismatch { title: t.into(), series: name.into(), x_len: n, y_len: len });
        }
    }
    if n < 2 {
        return Err(draw_err(t, format!("a posture needs at least 2 nodes, got {n}")));
    }
    for (name, v) in [("x", &p.x), ("d1", &p.d1), ("d3", &p.d3)] {
        if let Some(i) = v.iter().position(|w| w.iter().any(|c| !c.is_finite())) {
            return Err(draw_err(t, format!("non-finite {name} at node {i}")));
        }
    }
    if let Some(i) = p.colour.iter().position(|c| !c.is_finite()) {
        return Err(draw_err(t, format!("non-finite colour value at node {i}")));
    }
    Ok(())
}

/// Finite-difference unit tangent `∂s x / |∂s x|` per node (central inside, one-sided at the
/// ends); `None` where neighbouring nodes coincide.
pub(crate) fn tangents(x: &[Vector3<f64>]) -> Vec<Option<Vector3<f64>>> {
    let n = x.len();
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let d = x[b] - x[a];
            let l = d.norm();
            (l > 0.0 && l.is_finite()).then(|| d / l)
        })
        .collect()
}

/// A panel prepared for drawing: positions in mm, glyph length, colour range.
struct Prepared<'a> {
    panel: &'a PosturePanel,
    /// Node positions [mm].
    x_mm: Vec<Vector3<f64>>,
    tangent: Vec<Option<Vector3<f64>>>,
    /// Glyph length [mm].
    glyph: f64,
    /// Colour range (lo, hi).
    range: (f64, f64),
    /// Nodes carrying frame glyphs.
    samples: Vec<usize>,
    /// Largest angle between d3 and the tangent over all nodes [deg].
    max_angle_deg: f64,
}

impl<'a> Prepared<'a> {
    fn new(panel: &'a PosturePanel) -> Self {
        let x_mm: Vec<Vector3<f64>> = panel.x.iter().map(|p| p * 1e3).collect();
        let extent = (0..3)
            .map(|k| {
                let (lo, hi) =
                    x_mm.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p[k]), h.max(p[k])));
                hi - lo
            })
            .fold(0.0, f64::max);
        let glyph = GLYPH_FRACTION * if extent > 0.0 { extent } else { 1.0 };
        let range = panel.colour.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &c| (l.min(c), h.max(c)));
        let tangent = tangents(&x_mm);
        let max_angle_deg = tangent
            .iter()
            .zip(&panel.d3)
            .filter_map(|(t, d)| t.map(|t| (t, d)))
            .filter(|(_, d)| d.norm() > 0.0)
            .map(|(t, d)| (t.dot(d) / d.norm()).clamp(-1.0, 1.0).acos().to_degrees())
            .fold(0.0, f64::max);
        let samples = (0..x_mm.len()).step_by(sample_step(x_mm.len())).collect();
        Prepared { panel, x_mm, tangent, glyph, range, samples, max_angle_deg }
    }

    fn colour_of(&self, v: f64) -> RGBColor {
        let (lo, hi) = self.range;
        viridis(if hi > lo { (v - lo) / (hi - lo) } else { 0.5 })
    }

    fn caption(&self) -> String {
        format!(
            "{} — ● head (s = 0); black arrows d3, grey ticks d1, red: tangent ∂s x — max ∠(d3, ∂s x) = {}°",
            self.panel.label,
            fmt_num(sig2(self.max_angle_deg))
        )
    }
}

type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Draws one projection (coordinates `a`, `b`) of `p` into `area` with equal-aspect axes.
fn draw_projection<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &Prepared,
    (a, b, name_a, name_b): (usize, usize, &str, &str),
) -> Result<(), PlotError> {
    let mut chart = projection_chart(area, p, (a, b, name_a, name_b))?;
    draw_rod(&mut chart, p, |v: &Vector3<f64>| (v[a], v[b]))
}

/// The square chart of one projection (axes `a`, `b` of the positions, named `name_a`,
/// `name_b`) with its mesh drawn: the data's bounds in both coordinates with a common half-width
/// (and room for the glyphs), the surplus pixels spread over the margins.
fn projection_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    p: &Prepared,
    (a, b, name_a, name_b): (usize, usize, &str, &str),
) -> Result<Chart<'a, DB>, PlotError> {
    let t = p.panel.label.as_str();
    // Square plotting area: spread the surplus pixels over the margins.
    let (w, h) = area.dim_in_pixel();
    let pw = w.saturating_sub(2 * MARGIN + Y_LABEL_AREA);
    let ph = h.saturating_sub(2 * MARGIN + X_LABEL_AREA);
    let side = pw.min(ph);
    let (ex, ey) = (pw - side, ph - side);
    // Common half-width from the data bounds in both projected coordinates (+ room for glyphs).
    let bounds =
        |k: usize| p.x_mm.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, hi), q| (l.min(q[k]), hi.max(q[k])));
    let ((a0, a1), (b0, b1)) = (bounds(a), bounds(b));
    let half = 0.5 * (a1 - a0).max(b1 - b0) * 1.05 + 1.5 * p.glyph;
    let half = if half > 0.0 { half } else { 1.0 };
    let (ca, cb) = (0.5 * (a0 + a1), 0.5 * (b0 + b1));
    let mut chart: Chart<DB> = ChartBuilder::on(area)
        .margin_left(MARGIN + ex / 2)
        .margin_right(MARGIN + ex - ex / 2)
        .margin_top(MARGIN + ey / 2)
        .margin_bottom(MARGIN + ey - ey / 2)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d((ca - half)..(ca + half), (cb - half)..(cb + half))
        .map_err(|e| draw_err(t, e))?;
    let (desc_a, desc_b) = (format!("{name_a} [mm]"), format!("{name_b} [mm]"));
    chart
        .configure_mesh()
        .x_desc(desc_a.as_str())
        .y_desc(desc_b.as_str())
        .x_labels(6)
        .y_labels(6)
        .label_style(font(14))
        .axis_desc_style(font(15))
        .x_label_formatter(&|v| tick(*v, half))
        .y_label_formatter(&|v| tick(*v, half))
        .light_line_style(WHITE)
        .bold_line_style(BLACK.mix(0.08))
        .draw()
        .map_err(|e| draw_err(t, e))?;
    Ok(chart)
}

/// The rod in `chart`, projected by `proj` [mm]: the coloured centreline, the d1 ribbon ticks,
/// the d3 arrows, the finite-difference tangents and the head.
fn draw_rod<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    p: &Prepared,
    proj: impl Fn(&Vector3<f64>) -> (f64, f64),
) -> Result<(), PlotError> {
    let t = p.panel.label.as_str();
    let n = p.x_mm.len();
    // Centreline, segment by segment, coloured by the mean of its end values.
    let segments = (0..n - 1).map(|i| {
        let c = p.colour_of(0.5 * (p.panel.colour[i] + p.panel.colour[i + 1]));
        PathElement::new(vec![proj(&p.x_mm[i]), proj(&p.x_mm[i + 1])], c.stroke_width(3))
    });
    chart.draw_series(segments).map_err(|e| draw_err(t, e))?;
    let g = p.glyph;
    // d1 ribbon ticks: a segment through the node along ±d1 (total length g).
    let ribbons = p.samples.iter().map(|&i| {
        let (x, d1) = (p.x_mm[i], p.panel.d1[i]);
        PathElement::new(vec![proj(&(x - 0.5 * g * d1)), proj(&(x + 0.5 * g * d1))], RIBBON_COLOUR.stroke_width(2))
    });
    chart.draw_series(ribbons).map_err(|e| draw_err(t, e))?;
    let d3 = d3_arrows(p, &proj);
    chart.draw_series(d3.arrows).map_err(|e| draw_err(t, e))?;
    chart.draw_series(d3.rings).map_err(|e| draw_err(t, e))?;
    // Finite-difference tangent (unit, same length as the d3 arrows), on top of the arrows.
    let tangents = p.samples.iter().filter_map(|&i| p.tangent[i].map(|tv| (i, tv))).map(|(i, tv)| {
        let x = p.x_mm[i];
        PathElement::new(vec![proj(&x), proj(&(x + g * tv))], TANGENT_COLOUR.stroke_width(1))
    });
    chart.draw_series(tangents).map_err(|e| draw_err(t, e))?;
    // Head (node 0).
    let head = Circle::new(proj(&p.x_mm[0]), 5, BLACK.filled());
    chart.draw_series(std::iter::once(head)).map_err(|e| draw_err(t, e))?;
    Ok(())
}

/// The d3 arrows of a projection.
struct D3Arrows {
    /// one polyline per sampled node: shaft and head
    arrows: Vec<PathElement<(f64, f64)>>,
    /// a ring at each node whose d3 is out of the plane (projected shorter than a quarter glyph)
    rings: Vec<Circle<(f64, f64), i32>>,
}

/// The d3 arrows at the sampled nodes, projected by `proj`.
fn d3_arrows(p: &Prepared, proj: &impl Fn(&Vector3<f64>) -> (f64, f64)) -> D3Arrows {
    let g = p.glyph;
    let mut rings = Vec::new();
    let arrows = p
        .samples
        .iter()
        .map(|&i| {
            let (x, d3) = (p.x_mm[i], p.panel.d3[i]);
            let (x0, y0) = proj(&x);
            let (x1, y1) = proj(&(x + g * d3));
            let (dx, dy) = (x1 - x0, y1 - y0);
            let len = dx.hypot(dy);
            let mut pts = vec![(x0, y0), (x1, y1)];
            if len > 0.25 * g {
                let (ux, uy) = (dx / len, dy / len);
                let (hl, hw) = (0.3 * len, 0.15 * len);
                pts.push((x1 - hl * ux + hw * uy, y1 - hl * uy - hw * ux));
                pts.push((x1, y1));
                pts.push((x1 - hl * ux - hw * uy, y1 - hl * uy + hw * ux));
            } else {
                rings.push(Circle::new((x0, y0), 4, ARROW_COLOUR.stroke_width(1)));
            }
            PathElement::new(pts, ARROW_COLOUR.stroke_width(2))
        })
        .collect();
    D3Arrows { arrows, rings }
}

/// Caption strip of one row.
fn draw_caption<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Prepared) -> Result<(), PlotError> {
    let (_, h) = area.dim_in_pixel();
    let style = TextStyle::from(font(15)).pos(Pos::new(HPos::Left, VPos::Center));
    area.draw_text(&p.caption(), &style, (12, h as i32 / 2)).map_err(|e| draw_err(&p.panel.label, e))
}

/// The colour bar of one row, in the strip right of its projections, as tall as a projection.
fn draw_row_colour_bar<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Prepared) -> Result<(), PlotError> {
    let (_, h) = area.dim_in_pixel();
    let rows = (MARGIN + 20) as i32..(h - MARGIN - X_LABEL_AREA - 20) as i32;
    let (lo, hi) = p.range;
    let colour = |t: f64| viridis(t);
    draw_colour_bar(area, 10, rows, &colour, (lo, hi.max(lo)), &p.panel.colour_label)
}

/// Render panels (one row per panel, three orthogonal projections per row: x–y, x–z, y–z,
/// each with equal aspect ratio axes in mm) to SVG text.
///
/// Per projection: the centreline coloured segment by segment by `colour` (one scale per panel,
/// its colour bar right of the row), at about 16 sampled nodes a black `d3` arrow, a grey `d1` tick
/// through the node and a thin red finite-difference tangent (all ≈ 4 % of the rod's extent;
/// `d3` off the tangent is what the `Λ`/`λ_d` term of eq. 41 penalises), and a filled circle at
/// the head (node 0). A `d3` nearly normal to the projection plane is marked by a ring.
/// `extra`, if given, is drawn beneath the rows (900 × 600 px high, the full width).
///
/// Errors: no panels ([`PlotError::InvalidGrid`]), a panel without nodes
/// ([`PlotError::EmptySeries`]), `d1`/`d3`/`colour` lengths differing from `x`
/// ([`PlotError::LengthMismatch`]), fewer than 2 nodes or a non-finite value
/// ([`PlotError::Draw`]).
pub fn render_postures_svg(
    title: &str,
    panels: &[PosturePanel],
    extra: Option<&LinePlot>,
) -> Result<String, PlotError> {
    if panels.is_empty() {
        return Err(PlotError::InvalidGrid { panels: 0, cols: PROJECTIONS.len() });
    }
    for p in panels {
        validate(p)?;
    }
    let prepared: Vec<Prepared> = panels.iter().map(Prepared::new).collect();
    let rows = panels.len() as u32;
    let width = CELL * PROJECTIONS.len() as u32 + COLOUR_BAR_STRIP;
    let extra_h = if extra.is_some() { PLOT_SIZE.1 } else { 0 };
    let size = (width, TITLE_H + rows * (CAPTION_H + CELL) + extra_h);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| draw_err(title, e))?;
        let body = title_strip(&root, title, TITLE_H, 20)?;
        let (postures, below) = body.split_vertically(rows * (CAPTION_H + CELL));
        for (row, p) in postures.split_evenly((panels.len(), 1)).iter().zip(&prepared) {
            let (cap, cells) = row.split_vertically(CAPTION_H);
            draw_caption(&cap, p)?;
            let (cells, bar) = cells.split_horizontally(CELL * PROJECTIONS.len() as u32);
            for (cell, pr) in cells.split_evenly((1, PROJECTIONS.len())).iter().zip(PROJECTIONS) {
                draw_projection(cell, p, pr)?;
            }
            draw_row_colour_bar(&bar, p)?;
        }
        if let Some(plot) = extra {
            draw_panels(&below, std::slice::from_ref(plot), 1)?;
        }
        root.present().map_err(|e| draw_err(title, e))?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight(n: usize) -> PosturePanel {
        PosturePanel {
            label: "frame 7".into(),
            x: (0..n).map(|i| Vector3::new(1e-3 * i as f64 / (n - 1) as f64, 0.0, 0.0)).collect(),
            d1: vec![Vector3::y(); n],
            d3: vec![Vector3::x(); n],
            colour: (0..n).map(|i| i as f64).collect(),
            colour_label: "|kappa| [1/m]".into(),
        }
    }

    /// Polylines (not circles or text) stroked with `colour`.
    fn polylines(svg: &str, colour: RGBColor) -> usize {
        let c = format!("stroke=\"#{:02X}{:02X}{:02X}\"", colour.0, colour.1, colour.2);
        svg.split('<').filter(|tag| tag.starts_with("polyline") && tag.contains(&c)).count()
    }

    #[test]
    fn straight_rod_draws_one_glyph_of_each_kind_per_sample_and_projection() {
        let n = 33;
        let svg = render_postures_svg("Straight rod", &[straight(n)], None).expect("renders");
        assert!(svg.contains("Straight rod") && svg.contains("frame 7") && svg.contains("|kappa| [1/m]"));
        let samples = (0..n).step_by(sample_step(n)).count();
        assert_eq!(samples, 17);
        assert_eq!(polylines(&svg, ARROW_COLOUR), 3 * samples);
        assert_eq!(polylines(&svg, RIBBON_COLOUR), 3 * samples);
        assert_eq!(polylines(&svg, TANGENT_COLOUR), 3 * samples);
        // d3 = e1 is normal to the y–z plane: one ring per sample there.
        assert_eq!(svg.split('<').filter(|t| t.starts_with("circle") && t.contains("#141414")).count(), samples);
        assert!(svg.contains("max ∠(d3, ∂s x) = 0°"));
    }

    #[test]
    fn bad_input_is_an_error() {
        let mut p = straight(10);
        p.d3.pop();
        assert!(matches!(
            render_postures_svg("t", &[p], None),
            Err(PlotError::LengthMismatch { x_len: 10, y_len: 9, .. })
        ));
        assert!(matches!(render_postures_svg("t", &[], None), Err(PlotError::InvalidGrid { .. })));
        let mut p = straight(10);
        p.x[3].y = f64::NAN;
        assert!(matches!(render_postures_svg("t", &[p], None), Err(PlotError::Draw { .. })));
    }
}
