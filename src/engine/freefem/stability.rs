//! The buckling modes of a static case from `freefem/stability.idp` (D27): `ff_buckling.csv` (a
//! row per mode and node: the mode, its critical load factor, the node, the mode's displacement
//! in space) read into the [`StabilityOutput`] the Rust engine gives, with the natural
//! frequencies of `modes.idp` ([`super::modes`], D28). FreeFEM has no mass-matrix
//! eigen-analysis of a static state: its stability is the Rust engine's alone.
use std::path::Path;

use nalgebra::Vector3;

use super::{read_table, FreeFemError};
use crate::case::{Analysis, Case};
use crate::engine::common::result::{BucklingRecord, StabilityOutput};

/// The output `stability.idp` writes besides `forward.edp`'s.
pub const BUCKLING_OUTPUT: &str = "ff_buckling.csv";

/// The buckling modes of a static case's result in `dir` (`solver.buckling_modes`) and its
/// natural frequencies (`solver.vibration_modes`, [`super::modes`]): `None` for other analyses,
/// for a case without either and for a result that did not converge (`stability.idp` and
/// `modes.idp` run only for a converged one).
pub(super) fn read_stability(case: &Case, dir: &Path) -> Result<Option<StabilityOutput>, FreeFemError> {
    let Analysis::Static(params) = &case.analysis else { return Ok(None) };
    let omegas = super::modes::read_modes(dir, params.vibration_modes)?;
    let path = dir.join(BUCKLING_OUTPUT);
    let buckling = params.buckling_modes > 0 && path.exists();
    if !buckling && omegas.is_none() {
        return Ok(None);
    }
    let mut modes: Vec<BucklingRecord> = Vec::new();
    if buckling {
        let nodes = case.mesh.nodes();
        for r in read_table(&path, &["mode", "load_factor", "node", "ux", "uy", "uz"])? {
            let k = r[0] as usize;
            if k == modes.len() + 1 {
                modes.push(BucklingRecord { load_factor: r[1], displacement: Vec::with_capacity(nodes) });
            }
            let count = modes.len();
            match modes.last_mut() {
                Some(m) if k == count && r[2] as usize == m.displacement.len() => {
                    m.displacement.push(Vector3::new(r[3], r[4], r[5]))
                }
                _ => {
                    return Err(FreeFemError::BadOutput {
                        path,
                        reason: format!("row of mode {k}, node {} out of order", r[2]),
                    })
                }
            }
        }
        if modes.iter().any(|m| m.displacement.len() != nodes) {
            return Err(FreeFemError::BadOutput { path, reason: format!("a mode without {nodes} nodes") });
        }
    }
    Ok(Some(StabilityOutput {
        smallest_eigenvalue_per_s2: None,
        conservative: case.loads.conservative(),
        modes,
        omegas_rad_per_s: omegas.unwrap_or_default(),
    }))
}
