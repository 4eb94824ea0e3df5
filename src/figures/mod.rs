//! SVG figures, knowing nothing of rods: line plots with their legends and log axes
//! ([`plot`]; long ones drawn with fewer points by [`decimate`]; grids of them under a figure
//! title, [`panels`]), heatmaps with a colour bar ([`heatmap`]), postures of a rod drawn in projections
//! ([`posture`]) and the text of figures ([`figure_text`]). What a figure shows of a run is
//! chosen in `crate::output` and `crate::audit`.
pub mod decimate;
pub mod figure_text;
pub mod heatmap;
pub mod panels;
pub mod plot;
pub mod posture;
#[cfg(test)]
pub(crate) mod svg_text;
