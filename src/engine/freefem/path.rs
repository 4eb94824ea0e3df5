//! The path of an arc-length case from `freefem/arclength.idp` (D25): `ff_path.csv` (a row per
//! point: step, λ, arc length, the determinant's sign, iterations, certificate, the displacement
//! at each recorded node) and `ff_critical.csv` read into the [`PathOutput`] the Rust engine
//! gives, so that both engines write the same `path.csv` and are compared on it.

use std::path::Path;

use nalgebra::Vector3;

use super::info::FfInfo;
use super::{read_table, FreeFemError};
use crate::case::Case;
use crate::engine::common::path_record_points;
use crate::engine::common::result::{PathOutput, PathRecord};
use crate::solve::arclength::Critical;

/// The outputs `arclength.idp` writes besides `forward.edp`'s.
pub const PATH_OUTPUTS: [&str; 2] = ["ff_path.csv", "ff_critical.csv"];

/// The path in `dir` of a case followed by arc length; `info` its `ff_info.csv`.
pub(super) fn read_path(case: &Case, dir: &Path, info: &FfInfo) -> Result<PathOutput, FreeFemError> {
    let record_s_m = path_record_points(case);
    let mut header: Vec<String> =
        ["step", "load_factor", "arc_length", "determinant_sign", "iterations", "certificate"].map(String::from).into();
    for j in 0..record_s_m.len() {
        header.extend(["x", "y", "z"].map(|c| format!("u{c}_m_{j}")));
    }
    let h: Vec<&str> = header.iter().map(String::as_str).collect();
    let points = read_table(&dir.join(PATH_OUTPUTS[0]), &h)?
        .into_iter()
        .map(|r| PathRecord {
            step: r[0] as usize,
            load_factor: r[1],
            arc_length: r[2],
            determinant_sign: r[3] as i8,
            iterations: r[4] as usize,
            certificate: r[5],
            displacements: r[6..].chunks(3).map(|d| Vector3::new(d[0], d[1], d[2])).collect(),
        })
        .collect();
    let critical_path = dir.join(PATH_OUTPUTS[1]);
    let critical = read_table(
        &critical_path,
        &["kind_1limit_2bifurcation", "load_factor", "bracket_low", "bracket_high", "after_step"],
    )?
    .into_iter()
    .map(|r| match r[0] as i32 {
        1 => Ok(Critical::Limit { load_factor: r[1], after: r[4] as usize }),
        2 => Ok(Critical::Bifurcation { between: (r[2], r[3]), after: r[4] as usize }),
        k => Err(FreeFemError::BadOutput { path: critical_path.clone(), reason: format!("critical point kind {k}") }),
    })
    .collect::<Result<_, _>>()?;
    Ok(PathOutput { record_s_m, points, critical, reached_end: info.path.reached_end == Some(1.0) })
}
