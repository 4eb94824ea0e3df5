//! Independent theory attached to a case by its `[reference]` table, reported as metrics so
//! `metrics.json` and the snapshots carry the errors against theory.
use crate::case::{Case, Reference};
use crate::metrics::Metrics;
use crate::reference::{timoshenko_tip_deflection, tip_loaded_cantilever, PlanarRod, ReferenceError};
use crate::run::RunResult;

/// Add the reference values and relative errors of the tip deflection to `m`.
///
/// * `eq63_*`: linear Timoshenko beam, eq. (63) at s = L;
/// * `elastica_*`: Kirchhoff elastica (inextensible, unshearable), by shooting;
/// * `reissner_*`: planar Reissner rod with the case's kGA and EA, which is exactly the planar
///   restriction of the model solved here (the remaining error is the discretisation).
pub fn add_reference_metrics(case: &Case, r: &RunResult, m: &mut Metrics) -> Result<(), ReferenceError> {
    let Some(Reference::TipLoadedCantilever { force_n }) = case.reference else {
        return Ok(());
    };
    let tip_y = r.nodes.x.last().map(|x| x[1]).unwrap_or(f64::NAN);
    let (l, kga, ea, ei) = (
        case.mesh.length_m,
        case.props.shear_stretch_n[0],
        case.props.shear_stretch_n[2],
        case.props.bend_twist_nm2[0],
    );
    let eq63 = timoshenko_tip_deflection(force_n, l, kga, ei);
    let rod = |shearable: bool| PlanarRod {
        length_m: l,
        bending_stiffness_nm2: ei,
        shear_stiffness_n: shearable.then_some(kga),
        axial_stiffness_n: shearable.then_some(ea),
    };
    let elastica = tip_loaded_cantilever(&rod(false), force_n)?.tip_y_m;
    let reissner = tip_loaded_cantilever(&rod(true), force_n)?.tip_y_m;
    for (name, value) in [("eq63", eq63), ("elastica", elastica), ("reissner", reissner)] {
        m.insert(format!("{name}_tip_y_m"), value);
        m.insert(format!("{name}_rel_error"), tip_y / value - 1.0);
    }
    Ok(())
}
