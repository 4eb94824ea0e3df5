//! Grids of line plots in one SVG: [`render_panels_svg`] (each panel with its own title), and
//! [`render_figure_svg`], the same grid under a figure title in a strip of its own above the
//! panels, so that a long figure title never runs into the first panel's title.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::plot::{draw_plot, ranges, render, title_strip, LinePlot, PlotError, PLOT_SIZE};

/// Height of the strip of a figure title above its panels [px].
pub const FIGURE_TITLE_STRIP: u32 = 46;
/// A figure title at most this size [px] (smaller for a long one, down to the smallest text).
const FIGURE_TITLE_PX: u32 = 22;

/// Checks the grid and every panel; returns the number of columns and rows.
fn grid(panels: &[LinePlot], cols: usize) -> Result<(usize, usize), PlotError> {
    if panels.is_empty() || cols == 0 {
        return Err(PlotError::InvalidGrid { panels: panels.len(), cols });
    }
    for p in panels {
        ranges(p)?;
    }
    let cols = cols.min(panels.len());
    Ok((cols, panels.len().div_ceil(cols)))
}

/// `panels` as a grid with `cols` columns (rows as needed) in one SVG; each panel is 900×600
/// (text keeps its size in px). Errors if any panel is invalid, `panels` is empty or `cols`
/// is 0.
pub fn render_panels_svg(panels: &[LinePlot], cols: usize) -> Result<String, PlotError> {
    let (cols, rows) = grid(panels, cols)?;
    let (pw, ph) = PLOT_SIZE;
    let size = (pw * cols as u32, ph * rows as u32);
    let title = panels.first().map_or("", |p| p.title.as_str());
    render(size, title, |root| draw_panels(root, panels, cols))
}

/// [`render_panels_svg`] under `title`, written centred in a strip [`FIGURE_TITLE_STRIP`] px
/// high above the grid (the SVG is that much taller); each panel keeps its own title.
pub fn render_figure_svg(title: &str, panels: &[LinePlot], cols: usize) -> Result<String, PlotError> {
    let (cols, rows) = grid(panels, cols)?;
    let (pw, ph) = PLOT_SIZE;
    let size = (pw * cols as u32, ph * rows as u32 + FIGURE_TITLE_STRIP);
    render(size, title, |root| {
        let body = title_strip(root, title, FIGURE_TITLE_STRIP, FIGURE_TITLE_PX)?;
        draw_panels(&body, panels, cols)
    })
}

/// `panels` in a grid of `cols` columns filling `area`.
pub(crate) fn draw_panels<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panels: &[LinePlot],
    cols: usize,
) -> Result<(), PlotError> {
    let rows = panels.len().div_ceil(cols);
    for (a, plot) in area.split_evenly((rows, cols)).iter().zip(panels) {
        draw_plot(a, plot)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::figures::plot::{Legend, Scale, Series};
    use crate::figures::svg_text::{overlaps, texts};

    fn panel(title: &str, x_scale: Scale, legend: Legend) -> LinePlot {
        let x: Vec<f64> = (1..=60).map(f64::from).collect();
        LinePlot {
            title: title.into(),
            x_label: "iteration".into(),
            y_label: "relative change [–]".into(),
            series: vec![Series::new("a run", x.clone(), x.iter().map(|k| 1.0 / k).collect())],
            x_scale,
            y_scale: Scale::Log,
            legend,
            ..Default::default()
        }
    }

    /// The figure title has a strip of its own: no text of the figure overlaps another, the
    /// title lies above every panel's, and the SVG is the strip taller than the bare grid.
    #[test]
    fn the_figure_title_runs_into_no_panel_title() {
        let title = "Fig. 5: the cantilever's tip, Cosserat rod against the modal solution of the linearised rod";
        let panels =
            [panel("displacement", Scale::Linear, Legend::Right), panel("rotation", Scale::Linear, Legend::Right)];
        let svg = render_figure_svg(title, &panels, 2).unwrap();
        assert!(svg.contains(&format!("height=\"{}\"", PLOT_SIZE.1 + FIGURE_TITLE_STRIP)), "height");
        assert_eq!(overlaps(&svg), Vec::<(String, String)>::new());
        let all = texts(&svg);
        let top = |t: &str| all.iter().find(|b| b.text == t).map(|b| b.y.1).expect(t);
        let bottom = all.iter().find(|b| b.text == title).map(|b| b.y.1).expect("title");
        assert!(bottom <= top("displacement").min(top("rotation")), "the figure title is above the panels'");
    }

    #[test]
    fn panels_grid() {
        let names = ["position", "kappa_1", "kappa_2", "kappa_3"];
        let panels: Vec<LinePlot> = names
            .iter()
            .map(|n| LinePlot {
                title: n.to_string(),
                y_label: format!("{n} [1/m]"),
                ..panel("", Scale::Linear, Legend::Right)
            })
            .collect();
        let svg = render_panels_svg(&panels, 2).unwrap();
        for n in names {
            assert!(svg.contains(&format!("\n{n}\n")) && svg.contains(&format!("{n} [1/m]")), "{n}");
        }
        assert!(svg.contains("width=\"1800\"") && svg.contains("height=\"1200\""));
        assert!(matches!(render_panels_svg(&[], 2), Err(PlotError::InvalidGrid { .. })));
        assert!(matches!(render_figure_svg("t", &panels, 0), Err(PlotError::InvalidGrid { .. })));
    }

    /// Without a legend strip, the last tick label of the x axis stays inside the figure.
    #[test]
    fn the_last_x_tick_label_is_inside_the_figure() {
        let svg = render_panels_svg(&[panel("no legend", Scale::Log, Legend::Hidden)], 1).unwrap();
        let last = texts(&svg).into_iter().find(|b| b.text == "100").expect("the tick 100");
        assert!(last.x.1 <= PLOT_SIZE.0 as f64, "the tick label ends at {} px", last.x.1);
    }
}
