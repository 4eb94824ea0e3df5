//! Posture figures of a rod (cf. Figs. 16, 21 and 22 of Wang et al., Comput. Mech. 71, 2023):
//! the 3-D centreline with its material frame, one row per frame and three orthogonal
//! projections (x–y, x–z, y–z) per row, rendered to SVG text with plotters.
//!
//! The directors `d1`, `d3` are rows of the frame matrix `Q` (eq. 2); `d3` is the cross-section
//! normal. The shear/stretch term of the objective (the `Λ`/`λ_d` weights of eq. 41) penalises
//! `∂s x − d3`, so the finite-difference tangent is drawn next to `d3` (thin red against black)
//! to make a detachment of the frame from the centreline visible, as in Fig. 21.

use super::heatmap::{draw_colour_bar, COLOUR_BAR_STRIP};
use super::panels::draw_panels;
use super::plot::{draw_err, font, title_strip, LinePlot, PlotError, PLOT_SIZE};
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

/// The angle [deg] between d3 and the centreline of each element: the element's `∂s x` (its
/// chord `x_{i+1} − x_i`, P1) against the mean of its two nodes' d3, the pair the λd term of
/// eq. (41) compares at the element's midpoint. `None` for an element whose chord or mean d3
/// has no direction.
pub fn element_angles_deg(x: &[Vector3<f64>], d3: &[Vector3<f64>]) -> Vec<Option<f64>> {
    (0..x.len().min(d3.len()).saturating_sub(1))
        .map(|i| {
            let (c, m) = (x[i + 1] - x[i], d3[i] + d3[i + 1]);
            let norms = c.norm() * m.norm();
            (norms > 0.0 && norms.is_finite()).then(|| (c.dot(&m) / norms).clamp(-1.0, 1.0).acos().to_degrees())
        })
        .collect()
}

/// The glyphs of one sampled element, at its midpoint [mm]: the unit directions of its chord
/// (`∂s x`) and of the mean of its nodes' d3 and d1.
struct Glyph {
    mid: Vector3<f64>,
    chord: Option<Vector3<f64>>,
    d3: Vector3<f64>,
    d1: Vector3<f64>,
}

/// `v` of unit length, or zero.
fn unit(v: Vector3<f64>) -> Vector3<f64> {
    let n = v.norm();
    if n > 0.0 && n.is_finite() {
        v / n
    } else {
        Vector3::zeros()
    }
}

/// What every row of a posture figure shares, so that the rows compare: positions in the lab
/// frame on the same axes (per projection one centre and half-width over all rows), one glyph
/// length and one colour range.
struct Shared {
    /// Per projection of [`PROJECTIONS`]: the centre (a, b) and the half-width [mm].
    boxes: [((f64, f64), f64); 3],
    /// Glyph length [mm].
    glyph: f64,
    /// Colour range (lo, hi) over every row.
    range: (f64, f64),
}

impl Shared {
    fn new(panels: &[PosturePanel]) -> Self {
        let nodes = || panels.iter().flat_map(|p| p.x.iter().map(|q| q * 1e3));
        let bounds =
            |k: usize| nodes().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), q| (l.min(q[k]), h.max(q[k])));
        let b = [bounds(0), bounds(1), bounds(2)];
        let extent = b.iter().map(|(lo, hi)| hi - lo).fold(0.0, f64::max);
        let glyph = GLYPH_FRACTION * if extent > 0.0 { extent } else { 1.0 };
        let boxes = PROJECTIONS.map(|(i, j, _, _)| {
            let half = 0.5 * (b[i].1 - b[i].0).max(b[j].1 - b[j].0) * 1.05 + 1.5 * glyph;
            ((0.5 * (b[i].0 + b[i].1), 0.5 * (b[j].0 + b[j].1)), if half > 0.0 { half } else { 1.0 })
        });
        let range = colour_range(panels);
        Shared { boxes, glyph, range }
    }

    fn colour_of(&self, v: f64) -> RGBColor {
        let (lo, hi) = self.range;
        viridis(if hi > lo { (v - lo) / (hi - lo) } else { 0.5 })
    }
}

/// The one colour range (lo, hi) of a posture figure: the smallest and largest colour value
/// of all its rows.
pub(crate) fn colour_range(panels: &[PosturePanel]) -> (f64, f64) {
    panels.iter().flat_map(|p| &p.colour).fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &c| (l.min(c), h.max(c)))
}

/// A panel prepared for drawing: positions in mm, the glyphs of its sampled elements.
struct Prepared<'a> {
    panel: &'a PosturePanel,
    /// Node positions [mm].
    x_mm: Vec<Vector3<f64>>,
    /// The sampled elements' glyphs.
    glyphs: Vec<Glyph>,
    /// Largest angle between d3 and ∂s x over all elements [deg] ([`element_angles_deg`]).
    max_angle_deg: f64,
}

impl<'a> Prepared<'a> {
    fn new(panel: &'a PosturePanel) -> Self {
        let x_mm: Vec<Vector3<f64>> = panel.x.iter().map(|p| p * 1e3).collect();
        let elements = x_mm.len() - 1;
        let glyphs = (0..elements)
            .step_by(sample_step(elements))
            .map(|i| {
                let c = x_mm[i + 1] - x_mm[i];
                Glyph {
                    mid: 0.5 * (x_mm[i] + x_mm[i + 1]),
                    chord: (c.norm() > 0.0).then(|| unit(c)),
                    d3: unit(panel.d3[i] + panel.d3[i + 1]),
                    d1: unit(panel.d1[i] + panel.d1[i + 1]),
                }
            })
            .collect();
        let max_angle_deg = element_angles_deg(&panel.x, &panel.d3).into_iter().flatten().fold(0.0, f64::max);
        Prepared { panel, x_mm, glyphs, max_angle_deg }
    }

    fn caption(&self) -> String {
        format!(
            "{} — ● head (s = 0); per element: black arrow d3, grey tick d1, red ∂s x — max ∠(d3, ∂s x) = {}°",
            self.panel.label,
            fmt_num(sig2(self.max_angle_deg))
        )
    }
}

type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Draws projection `k` of [`PROJECTIONS`] of `p` into `area` with equal-aspect axes, on the
/// figure's shared box.
fn draw_projection<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &Prepared,
    shared: &Shared,
    k: usize,
) -> Result<(), PlotError> {
    let (a, b, _, _) = PROJECTIONS[k];
    let mut chart = projection_chart(area, p, shared, k)?;
    draw_rod(&mut chart, p, shared, |v: &Vector3<f64>| (v[a], v[b]))
}

/// The square chart of projection `k` with its mesh drawn: the figure's box of that projection
/// (the same for every row: positions in the lab frame), the surplus pixels spread over the
/// margins.
fn projection_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    p: &Prepared,
    shared: &Shared,
    k: usize,
) -> Result<Chart<'a, DB>, PlotError> {
    let t = p.panel.label.as_str();
    let (_, _, name_a, name_b) = PROJECTIONS[k];
    // Square plotting area: spread the surplus pixels over the margins.
    let (w, h) = area.dim_in_pixel();
    let pw = w.saturating_sub(2 * MARGIN + Y_LABEL_AREA);
    let ph = h.saturating_sub(2 * MARGIN + X_LABEL_AREA);
    let side = pw.min(ph);
    let (ex, ey) = (pw - side, ph - side);
    let ((ca, cb), half) = shared.boxes[k];
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

/// The rod in `chart`, projected by `proj` [mm]: the coloured centreline, and at the sampled
/// elements' midpoints the d1 ticks, the d3 arrows and `∂s x` (the chord); the head.
fn draw_rod<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    p: &Prepared,
    shared: &Shared,
    proj: impl Fn(&Vector3<f64>) -> (f64, f64),
) -> Result<(), PlotError> {
    let t = p.panel.label.as_str();
    let n = p.x_mm.len();
    // Centreline, segment by segment, coloured by the mean of its end values.
    let segments = (0..n - 1).map(|i| {
        let c = shared.colour_of(0.5 * (p.panel.colour[i] + p.panel.colour[i + 1]));
        PathElement::new(vec![proj(&p.x_mm[i]), proj(&p.x_mm[i + 1])], c.stroke_width(3))
    });
    chart.draw_series(segments).map_err(|e| draw_err(t, e))?;
    let g = shared.glyph;
    // d1 ribbon ticks: a segment through the midpoint along ±d1 (total length g).
    let ribbons = p.glyphs.iter().map(|q| {
        PathElement::new(
            vec![proj(&(q.mid - 0.5 * g * q.d1)), proj(&(q.mid + 0.5 * g * q.d1))],
            RIBBON_COLOUR.stroke_width(2),
        )
    });
    chart.draw_series(ribbons).map_err(|e| draw_err(t, e))?;
    let d3 = d3_arrows(p, g, &proj);
    chart.draw_series(d3.arrows).map_err(|e| draw_err(t, e))?;
    chart.draw_series(d3.rings).map_err(|e| draw_err(t, e))?;
    // ∂s x of the element (unit, same length as the d3 arrows), on top of the arrows.
    let chords = p
        .glyphs
        .iter()
        .filter_map(|q| q.chord.map(|c| (q.mid, c)))
        .map(|(m, c)| PathElement::new(vec![proj(&m), proj(&(m + g * c))], TANGENT_COLOUR.stroke_width(1)));
    chart.draw_series(chords).map_err(|e| draw_err(t, e))?;
    // Head (node 0).
    let head = Circle::new(proj(&p.x_mm[0]), 5, BLACK.filled());
    chart.draw_series(std::iter::once(head)).map_err(|e| draw_err(t, e))?;
    Ok(())
}

/// The d3 arrows of a projection.
struct D3Arrows {
    /// one polyline per sampled element: shaft and head
    arrows: Vec<PathElement<(f64, f64)>>,
    /// a ring at each element whose d3 is out of the plane (projected shorter than a quarter
    /// glyph)
    rings: Vec<Circle<(f64, f64), i32>>,
}

/// The d3 arrows (length `g` [mm]) at the sampled elements' midpoints, projected by `proj`.
fn d3_arrows(p: &Prepared, g: f64, proj: &impl Fn(&Vector3<f64>) -> (f64, f64)) -> D3Arrows {
    let mut rings = Vec::new();
    let arrows = p
        .glyphs
        .iter()
        .map(|q| {
            let (x0, y0) = proj(&q.mid);
            let (x1, y1) = proj(&(q.mid + g * q.d3));
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

/// The figure's one colour bar, in the strip right of the rows, from the first row's
/// projections to the last row's.
fn draw_figure_colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    shared: &Shared,
    label: &str,
) -> Result<(), PlotError> {
    let (_, h) = area.dim_in_pixel();
    let rows = (CAPTION_H + MARGIN + 20) as i32..(h - MARGIN - X_LABEL_AREA - 20) as i32;
    let (lo, hi) = shared.range;
    let colour = |t: f64| viridis(t);
    draw_colour_bar(area, 10, rows, &colour, (lo, hi.max(lo)), label)
}

/// Render panels (one row per panel, three orthogonal projections per row: x–y, x–z, y–z,
/// each with equal aspect ratio axes in mm) to SVG text.
///
/// Every row is drawn on the same axes (per projection, one box around the nodes of all rows:
/// positions stay in the lab frame, so that a rod's motion between the frames shows) and with
/// one colour scale (the smallest to the largest `colour` of all rows, one colour bar right of
/// the rows, labelled with the first panel's `colour_label`). Per projection: the centreline
/// coloured segment by segment by `colour`, and at about 16 sampled elements' midpoints a black
/// `d3` arrow and a grey `d1` tick (the means of the element's two nodes) with a thin red `∂s x`
/// of the element (its chord; all ≈ 4 % of the rods' extent; `d3` off `∂s x` is what the λd
/// term of eq. 41 penalises, and each row's caption gives its largest angle,
/// [`element_angles_deg`]), and a filled circle at the head (node 0). A `d3` nearly normal to
/// the projection plane is marked by a ring. `extra`, if given, is drawn beneath the rows
/// (900 × 600 px high, the full width).
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
    let shared = Shared::new(panels);
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
        let (postures, bar) = postures.split_horizontally(CELL * PROJECTIONS.len() as u32);
        for (row, p) in postures.split_evenly((panels.len(), 1)).iter().zip(&prepared) {
            let (cap, cells) = row.split_vertically(CAPTION_H);
            draw_caption(&cap, p)?;
            for (k, cell) in cells.split_evenly((1, PROJECTIONS.len())).iter().enumerate() {
                draw_projection(cell, p, &shared, k)?;
            }
        }
        draw_figure_colour_bar(&bar, &shared, &panels[0].colour_label)?;
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
        let samples = (0..n - 1).step_by(sample_step(n - 1)).count();
        assert_eq!(samples, 16);
        assert_eq!(polylines(&svg, ARROW_COLOUR), 3 * samples);
        assert_eq!(polylines(&svg, RIBBON_COLOUR), 3 * samples);
        assert_eq!(polylines(&svg, TANGENT_COLOUR), 3 * samples);
        // d3 = e1 is normal to the y–z plane: one ring per sample there.
        assert_eq!(svg.split('<').filter(|t| t.starts_with("circle") && t.contains("#141414")).count(), samples);
        assert!(svg.contains("max ∠(d3, ∂s x) = 0°"));
    }

    /// An arc of a circle (radius 1 mm, a quarter turn, 21 nodes) with d3 turned by `tilt`
    /// [rad] from the exact tangent about the arc's normal e3, at every node.
    fn arc(tilt: f64) -> PosturePanel {
        let n = 21;
        let phi = |i: usize| std::f64::consts::FRAC_PI_2 * i as f64 / (n - 1) as f64;
        let x = (0..n).map(|i| 1e-3 * Vector3::new(phi(i).cos(), phi(i).sin(), 0.0)).collect();
        let d3 = (0..n).map(|i| Vector3::new(-(phi(i) + tilt).sin(), (phi(i) + tilt).cos(), 0.0)).collect();
        PosturePanel {
            label: "arc".into(),
            x,
            d1: vec![Vector3::z(); n],
            d3,
            colour: vec![1.0; n],
            colour_label: "|κ| [1/mm]".into(),
        }
    }

    /// The caption's angle is the largest of the per-element angles (the λd term's pair, the
    /// data the audit's profile draws): 0 for an arc whose d3 is its tangent (by symmetry the
    /// mean of the end tangents of an element lies along its chord; a one-sided difference at
    /// the ends would give half the angle an element subtends, 2.25°), and the tilt when d3 is
    /// turned off the tangent.
    #[test]
    fn the_caption_angle_is_the_largest_element_angle() {
        let straight_d3 = arc(0.0);
        let angles: Vec<f64> = element_angles_deg(&straight_d3.x, &straight_d3.d3).into_iter().flatten().collect();
        assert_eq!(angles.len(), 20);
        assert!(angles.iter().all(|a| *a < 1e-5), "{angles:?}");
        let tilted = arc(2f64.to_radians());
        let angles: Vec<f64> = element_angles_deg(&tilted.x, &tilted.d3).into_iter().flatten().collect();
        assert!(angles.iter().all(|a| (a - 2.0).abs() < 1e-9), "{angles:?}");
        assert_eq!(Prepared::new(&tilted).max_angle_deg, angles.iter().copied().fold(0.0, f64::max));
        let svg = render_postures_svg("arcs", &[tilted], None).unwrap();
        assert!(svg.contains("max ∠(d3, ∂s x) = 2°"), "caption");
    }

    /// Every row is drawn on the same lab-frame axes and colour scale: a rod moved by 2 mm
    /// along x and coloured 3× stronger in the second row widens the box and the range of
    /// both rows, and the figure has one colour bar.
    #[test]
    fn rows_share_the_lab_frame_and_one_colour_range() {
        let first = straight(33);
        let mut second = straight(33);
        second.x.iter_mut().for_each(|q| q.x += 2e-3);
        second.colour.iter_mut().for_each(|c| *c *= 3.0);
        let panels = [first, second];
        assert_eq!(colour_range(&panels), (0.0, 96.0));
        let shared = Shared::new(&panels);
        // x from 0 to 3 mm, y = z = 0: centre 1.5 mm, half-width 1.5 × 1.05 + 1.5 glyphs
        let ((ca, cb), half) = shared.boxes[0];
        assert!((ca - 1.5).abs() < 1e-12 && cb == 0.0, "{ca} {cb}");
        assert!((half - (1.575 + 1.5 * GLYPH_FRACTION * 3.0)).abs() < 1e-12, "{half}");
        let svg = render_postures_svg("two rows", &panels, None).unwrap();
        assert_eq!(svg.matches("|kappa| [1/m]").count(), 1, "one colour bar");
        assert_eq!(crate::figures::svg_text::overlaps(&svg), Vec::<(String, String)>::new());
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
