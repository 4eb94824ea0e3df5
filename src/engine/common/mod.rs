//! What both engines give and everything above them reads, engine-neutral: a run's result
//! ([`result::RunResult`]), its metrics and published values, a clip's frames
//! ([`clip_frame::ClipFrame`], [`clip_frame::FrameSink`]) and summary, and a clip's frames for
//! a comparison ([`frames::SolvedFrame`]). `engine/rust/` and `engine/freefem/` import this and
//! not each other (`tests/architecture.rs`, `SUBLAYERS`).
pub mod clip_frame;
pub mod clip_metrics;
pub mod clip_summary;
pub mod frames;
pub mod metric;
pub mod metrics;
pub mod published;
pub mod result;

use crate::case::{Case, DataSource};

/// The arc lengths [m] a path records: each point load's and s = L, ascending.
pub fn path_record_points(case: &Case) -> Vec<f64> {
    let mut s: Vec<f64> = case.loads.point.iter().map(|p| p.s_m).chain([case.mesh.length_m]).collect();
    s.sort_by(f64::total_cmp);
    s.dedup();
    s
}

/// Does the data source of an inverse case carry the true angles (synthetic forward data)?
pub fn angles_known(case: &Case) -> bool {
    matches!(case.inverse().map(|i| &i.data), Some(DataSource::Forward(_)))
}

/// Whether a static case's dense eigen-analyses (stability and buckling, D27) fit: its unknowns
/// at most `crate::solve::stability::DENSE_LIMIT`.
pub fn dense_analyses_fit(case: &Case) -> bool {
    case.problem().dofs().len() <= crate::solve::stability::DENSE_LIMIT
}
