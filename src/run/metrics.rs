//! Metrics of a run (one function for both engines), the errors against the independent
//! theory of a case's `[reference]`, and the Rust–FreeFEM comparison (D8).
use std::collections::BTreeMap;

use nalgebra::{DVector, Vector3};

use super::{NodalState, RunResult};
use crate::case::{Analysis, Case, CompareTolerances, Reference};
use crate::model::mesh::Mesh;
use crate::reference::{timoshenko_tip_deflection, tip_loaded_cantilever, PlanarRod, ReferenceError};
use crate::solve::inverse::ObjectiveTerms;
use crate::solve::statics::{Method, StaticParams};

/// Flat map metric name → value (`metrics.json`). Names carry SI units.
pub type Metrics = BTreeMap<String, f64>;

/// Physical metrics compared between engines.
pub fn physical_metrics(r: &RunResult) -> Metrics {
    let mut m = Metrics::new();
    let last = r.nodes.x.len() - 1;
    let (x, a) = (r.nodes.x[last], r.nodes.alpha[last]);
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        m.insert(format!("tip_{name}_m"), x[k]);
    }
    for (k, name) in ["alpha", "beta", "gamma"].iter().enumerate() {
        m.insert(format!("tip_{name}_rad"), a[k]);
    }
    if !r.tip.is_empty() {
        let max_abs = |k: usize| r.tip.iter().fold(0.0_f64, |acc, t| acc.max(t.position_m[k].abs()));
        m.insert("tip_max_abs_x_m".into(), max_abs(0));
        m.insert("tip_max_abs_y_m".into(), max_abs(1));
        let max_abs_a = |k: usize| r.tip.iter().fold(0.0_f64, |acc, t| acc.max(t.angles_rad[k].abs()));
        m.insert("tip_max_abs_beta_rad".into(), max_abs_a(1));
        m.insert("tip_max_abs_gamma_rad".into(), max_abs_a(2));
    }
    m
}

/// Edge elements left out of the "inner" curvature error: the ends carry the boundary layer of
/// the natural condition m = 0 (46) that the data do not satisfy exactly.
pub const INNER_SKIP_ELEMENTS: usize = 5;

/// Metrics of an inverse run (empty for forward runs): the recovery errors of §5.2 and the
/// terms of the objective (41) at the last iterate.
///
/// - `x_err_rel`: ‖x − x_g‖/‖x_g‖ (L², two-point rule, I2)
/// - `kappa_err_rel`, `kappa_err_rel_inner`: discrete ℓ² relative error of the element-midpoint
///   curvature κˡ = A ∂sα (eq. 28) against the forward data's, all elements / without
///   [`INNER_SKIP_ELEMENTS`] at each end
/// - `tangent_misfit_m05`: ‖∂s x − d3‖ [m^½]
/// - `force_l2_n_per_m05`, `torque_l2_n_m05`: ‖f‖, ‖l‖ (L², from the objective terms)
pub fn inverse_metrics(r: &RunResult) -> Metrics {
    let mut m = Metrics::new();
    let Some(inv) = &r.inverse else { return m };
    let Some(last) = inv.history.last() else { return m };
    m.insert("x_err_rel".into(), last.x_err_rel);
    m.insert("tangent_misfit_m05".into(), last.tangent_misfit);
    if inv.angles_known {
        let k: Vec<_> = r.nodes.element_curvature().into_iter().map(|(_, k)| k).collect();
        let kf: Vec<_> = inv.data.element_curvature().into_iter().map(|(_, k)| k).collect();
        m.insert("kappa_err_rel".into(), relative_error(&k, &kf, 0));
        m.insert("kappa_err_rel_inner".into(), relative_error(&k, &kf, INNER_SKIP_ELEMENTS));
    }
    for (name, v) in ObjectiveTerms::NAMES.iter().zip(last.objective.values()) {
        m.insert(name.to_string(), v);
    }
    m.insert("force_l2_n_per_m05".into(), (2.0 * last.objective.force / inv.lambda_f).sqrt());
    m.insert("torque_l2_n_m05".into(), (2.0 * last.objective.torque / inv.lambda_l).sqrt());
    m
}

/// Discrete relative ℓ² error `‖a − b‖/‖b‖` of two equally long lists of 3-vectors, skipping
/// `skip` entries at each end (at most half of them).
pub fn relative_error(a: &[Vector3<f64>], b: &[Vector3<f64>], skip: usize) -> f64 {
    let n = a.len().min(b.len());
    let range = skip.min(n / 2)..n - skip.min(n / 2);
    let num: f64 = range.clone().map(|e| (a[e] - b[e]).norm_squared()).sum();
    let den: f64 = range.map(|e| b[e].norm_squared()).sum();
    (num / den).sqrt()
}

/// `‖κ − κ_f‖/‖κ_f‖` over element midpoints of two states (forward layout) on `mesh`,
/// skipping `skip` elements at each end.
pub fn curvature_error(mesh: &Mesh, u: &DVector<f64>, truth: &DVector<f64>, skip: usize) -> f64 {
    let kappa = |u: &DVector<f64>| -> Vec<Vector3<f64>> {
        NodalState::from_vector(mesh, u).element_curvature().into_iter().map(|(_, k)| k).collect()
    };
    relative_error(&kappa(u), &kappa(truth), skip)
}

/// Add the reference values and relative errors of the tip deflection to `m`.
///
/// * `eq63_*`: linear Timoshenko beam, eq. (63) at s = L;
/// * `elastica_*`: Kirchhoff elastica (inextensible, unshearable), by shooting;
/// * `reissner_*`: planar Reissner rod with the case's kGA and EA, which is exactly the planar
///   restriction of the model solved here (the remaining error is the discretisation).
pub fn reference_metrics(case: &Case, r: &RunResult, m: &mut Metrics) -> Result<(), ReferenceError> {
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

/// All metrics written to `metrics.json`: physical ones, errors against the case's
/// `[reference]` theory, and solver statistics.
pub fn all_metrics(case: &Case, r: &RunResult) -> Result<Metrics, ReferenceError> {
    let mut m = physical_metrics(r);
    m.extend(inverse_metrics(r));
    reference_metrics(case, r, &mut m)?;
    m.insert("iterations".into(), r.stats.iterations as f64);
    if let Some(v) = r.stats.last_change {
        m.insert("last_change".into(), v);
    }
    if let Some(v) = r.stats.residual {
        m.insert("relative_residual".into(), v);
    }
    if let Some(v) = r.stats.max_newton_iterations {
        m.insert("max_newton_iterations".into(), v as f64);
    }
    m.insert("wall_time_s".into(), r.stats.wall_time_s);
    Ok(m)
}

/// One row of `cosserat compare`.
#[derive(Clone, Debug, PartialEq)]
pub struct ComparisonRow {
    pub name: String,
    /// metric values; `None` for rows that compare whole fields
    pub rust: Option<f64>,
    pub freefem: Option<f64>,
    pub difference: f64,
    pub tolerance: f64,
}

impl ComparisonRow {
    pub fn passed(&self) -> bool {
        self.difference <= self.tolerance
    }
}

/// `max_i |a_i − b_i| / max_i |a_i|` over 3-vectors (D8); 0 when both are identically zero.
pub fn max_relative_difference(a: &[nalgebra::Vector3<f64>], b: &[nalgebra::Vector3<f64>]) -> f64 {
    let scale = a.iter().fold(0.0_f64, |m, v| m.max(v.amax()));
    let diff = a.iter().zip(b).fold(0.0_f64, |m, (u, v)| m.max((u - v).amax()));
    if diff == 0.0 {
        0.0
    } else if scale == 0.0 {
        f64::INFINITY
    } else {
        diff / scale
    }
}

/// Rows comparing a Rust and a FreeFEM run of the same case.
pub fn compare(case: &Case, rust: &RunResult, ff: &RunResult) -> Vec<ComparisonRow> {
    let tol: &CompareTolerances = &case.compare;
    let mut rows = Vec::new();
    let nodes_match = rust.nodes.s.len() == ff.nodes.s.len();
    let field = |name: &str, value: f64, tolerance: f64| ComparisonRow {
        name: name.into(),
        rust: None,
        freefem: None,
        difference: value,
        tolerance,
    };
    if nodes_match {
        rows.push(field(
            "nodewise_rel_diff_displacement",
            max_relative_difference(&rust.nodes.displacement(), &ff.nodes.displacement()),
            tol.displacement_rel,
        ));
        rows.push(field(
            "nodewise_rel_diff_angles",
            max_relative_difference(&rust.nodes.alpha, &ff.nodes.alpha),
            tol.angles_rel,
        ));
    } else {
        rows.push(field("node_count", f64::INFINITY, 0.0));
    }
    let (mr, mf) = (physical_metrics(rust), physical_metrics(ff));
    for (name, &a) in &mr {
        let b = mf.get(name).copied().unwrap_or(f64::NAN);
        let d = (a - b).abs();
        rows.push(ComparisonRow {
            name: name.clone(),
            rust: Some(a),
            freefem: Some(b),
            difference: if d.is_nan() { f64::INFINITY } else { d },
            tolerance: tol.metric_rel * a.abs() + tol.metric_abs,
        });
    }
    if rust.tip.len() == ff.tip.len() && !rust.tip.is_empty() {
        let a: Vec<_> = rust.tip.iter().map(|t| t.position_m).collect();
        let b: Vec<_> = ff.tip.iter().map(|t| t.position_m).collect();
        let a0: Vec<_> = a.iter().map(|p| p - a[0]).collect();
        let b0: Vec<_> = b.iter().map(|p| p - b[0]).collect();
        rows.push(field("tip_history_rel_diff", max_relative_difference(&a0, &b0), tol.displacement_rel));
    }
    if let (Some(a), Some(b)) = (&rust.inverse, &ff.inverse) {
        if nodes_match {
            rows.push(field("nodewise_rel_diff_xhat", max_relative_difference(&a.xhat, &b.xhat), tol.adjoint_rel));
            rows.push(field("nodewise_rel_diff_ahat", max_relative_difference(&a.ahat, &b.ahat), tol.adjoint_rel));
        }
        // Recovery errors (κ amplifies angle differences by ~1/h), compared relatively.
        let (ma, mb) = (inverse_metrics(rust), inverse_metrics(ff));
        for name in ["x_err_rel", "kappa_err_rel", "kappa_err_rel_inner"].into_iter().filter(|n| ma.contains_key(*n)) {
            let (x, y) = (ma.get(name).copied().unwrap_or(f64::NAN), mb.get(name).copied().unwrap_or(f64::NAN));
            let d = (x - y).abs();
            rows.push(ComparisonRow {
                name: name.into(),
                rust: Some(x),
                freefem: Some(y),
                difference: if d.is_nan() { f64::INFINITY } else { d },
                tolerance: tol.metric_rel * x.abs(),
            });
        }
    }
    // Both engines run the identical fixed point (D5), so their iteration counts are compared.
    let fixed_point = matches!(case.analysis, Analysis::Static(StaticParams { method: Method::FixedPoint { .. }, .. }));
    if fixed_point || matches!(case.analysis, Analysis::Inverse(_)) {
        let (a, b) = (rust.stats.iterations as f64, ff.stats.iterations as f64);
        rows.push(ComparisonRow {
            name: "iterations".into(),
            rust: Some(a),
            freefem: Some(b),
            difference: (a - b).abs(),
            tolerance: tol.iterations_abs,
        });
    }
    rows
}
