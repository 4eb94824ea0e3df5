//! The stability of a static result, the case's linearised buckling (D27) and the rod's natural
//! frequencies about its rest state (D28) as a run's output.
use nalgebra::DVector;

use super::RunError;
use crate::case::{Analysis, Case};
use crate::engine::common::result::{BucklingRecord, StabilityOutput};
use crate::model::mesh::Field;
use crate::solve::modes::lowest_modes;
use crate::solve::stability::{buckling, stability, StabilityError};
use crate::solve::Problem;

/// The stability of the static state `u` of `problem` (at its load factor) and, with
/// `solver.buckling_modes`, the case's lowest critical load factors and modes. Above the dense
/// limit the stability is `None` (buckling is refused there when the case is read). With
/// `solver.vibration_modes`, the lowest natural frequencies about the rest state by
/// shift-invert block Lanczos (`solve::modes::lowest_modes`, D28), whatever the loads.
pub fn output(case: &Case, problem: &Problem, u: &DVector<f64>) -> Result<StabilityOutput, RunError> {
    let (modes, vibration) = match &case.analysis {
        Analysis::Static(p) => (p.buckling_modes, p.vibration_modes),
        _ => (0, 0),
    };
    let (smallest_eigenvalue_per_s2, conservative) = match stability(problem, u) {
        Ok(s) => (Some(s.smallest_eigenvalue_per_s2), s.conservative),
        Err(StabilityError::TooLarge { .. }) => (None, false),
        Err(e) => return Err(e.into()),
    };
    let modes = if modes > 0 { buckling(problem, modes)? } else { Vec::new() };
    let omegas_rad_per_s = if vibration > 0 { lowest_modes(problem, vibration)?.omegas } else { Vec::new() };
    let dofs = problem.dofs();
    let chart = problem.chart();
    let modes = modes
        .into_iter()
        .map(|m| BucklingRecord {
            load_factor: m.load_factor,
            displacement: (0..dofs.nodes()).map(|i| chart.to_space(&dofs.get(&m.shape, i, Field::X))).collect(),
        })
        .collect();
    Ok(StabilityOutput { smallest_eigenvalue_per_s2, conservative, modes, omegas_rad_per_s })
}
