//! Metrics of a run (one function for both engines), the errors against the independent
//! theory of a case's `[reference]`, and the Rust–FreeFEM comparison (D8).
use nalgebra::{DVector, Vector3};

use super::result::InverseOutput;
use super::result::{NodalState, PathOutput, RunResult};
use crate::case::{Case, Reference};
use crate::model::mesh::Mesh;
use crate::reference::{timoshenko_tip_deflection, tip_loaded_cantilever, PlanarRod, ReferenceError};
use crate::solve::dynamics::TipRecord;

pub use super::metric::{Metric, Metrics};

/// Physical metrics compared between engines.
pub fn physical_metrics(r: &RunResult) -> Metrics {
    let mut m = Metrics::new();
    let last = r.nodes.x.len() - 1;
    let (x, a) = (r.nodes.x[last], r.nodes.alpha[last]);
    for (k, key) in Metric::TIP_POSITION.into_iter().enumerate() {
        m.insert(key, x[k]);
    }
    for (k, key) in Metric::TIP_ANGLES.into_iter().enumerate() {
        m.insert(key, a[k]);
    }
    if !r.tip.is_empty() {
        let max_abs = |k: usize| r.tip.iter().fold(0.0_f64, |acc, t| acc.max(t.position_m[k].abs()));
        m.insert(Metric::TipMaxAbsX, max_abs(0));
        m.insert(Metric::TipMaxAbsY, max_abs(1));
        let max_abs_a = |k: usize| r.tip.iter().fold(0.0_f64, |acc, t| acc.max(t.angles_rad[k].abs()));
        m.insert(Metric::TipMaxAbsBeta, max_abs_a(1));
        m.insert(Metric::TipMaxAbsGamma, max_abs_a(2));
    }
    if r.tip.len() > 1 {
        balance_metrics(&r.tip, &mut m);
    }
    if let Some(p) = &r.path {
        path_metrics(p, &mut m);
    }
    if let Some(st) = &r.stability {
        stability_metrics(st, &mut m);
    }
    for (key, c) in Metric::CENTROID.into_iter().zip(centroid(&r.nodes.s, &r.nodes.x).iter()) {
        m.insert(key, *c);
    }
    m
}

/// A dynamic run's energy and momenta at its end time, and their largest change over its
/// trailing unloaded steps (no load, no moving end: the energy is conserved by the continuous
/// problem, and the momenta too where no end is held; `model::balance`).
fn balance_metrics(tip: &[TipRecord], m: &mut Metrics) {
    let end = &tip[tip.len() - 1].balance;
    m.insert(Metric::KineticEnergy, end.kinetic_j);
    m.insert(Metric::ElasticEnergy, end.elastic_j);
    for k in 0..3 {
        m.insert(Metric::MOMENTUM[k], end.momentum_n_s[k]);
        m.insert(Metric::ANGULAR_MOMENTUM[k], end.angular_momentum_n_m_s[k]);
    }
    // the trailing records whose steps are unloaded, and the state before the first of them
    let loaded = tip.iter().rposition(|t| t.loaded).map_or(0, |i| i + 1);
    let first = loaded.saturating_sub(1).min(tip.len() - 1);
    if tip.len() - first < 2 {
        return;
    }
    let (start, window) = (&tip[first], &tip[first..]);
    let e0 = start.balance.energy_j();
    let change = |f: &dyn Fn(&TipRecord) -> f64| window.iter().map(f).fold(0.0_f64, f64::max);
    m.insert(Metric::UnloadedFrom, start.time_s);
    if e0 > 0.0 {
        m.insert(Metric::UnloadedEnergyChangeRel, change(&|t| (t.balance.energy_j() - e0).abs() / e0));
    }
    let (p0, h0) = (start.balance.momentum_n_s, start.balance.angular_momentum_n_m_s);
    m.insert(Metric::UnloadedMomentumChange, change(&|t| (t.balance.momentum_n_s - p0).norm()));
    m.insert(Metric::UnloadedAngularMomentumChange, change(&|t| (t.balance.angular_momentum_n_m_s - h0).norm()));
}

/// The centreline's mean position `∫ x ds / L` [m] of the P1 interpolant (exact: the
/// trapezoidal rule per element); the centre of mass where ρA is uniform.
pub fn centroid(s: &[f64], x: &[Vector3<f64>]) -> Vector3<f64> {
    let mut sum = Vector3::zeros();
    for i in 1..s.len() {
        sum += (x[i] + x[i - 1]) * (0.5 * (s[i] - s[i - 1]));
    }
    sum / (s[s.len() - 1] - s[0])
}

/// A static result's stability and its buckling load factors (D27):
/// `tangent_smallest_eigenvalue_per_s2` (`min Re ω²`), `stable` (conservative loads only: 1
/// when it is positive, else 0), `buckling_{k}_load_factor` (k = 1, 2, …, ascending), and the
/// natural frequencies about the rest state `omega_{k}_rad_per_s` (D28, k = 1, 2, …).
fn stability_metrics(st: &super::result::StabilityOutput, m: &mut Metrics) {
    if let Some(mu) = st.smallest_eigenvalue_per_s2 {
        m.insert(Metric::TangentSmallestEigenvalue, mu);
        if st.conservative {
            m.insert(Metric::Stable, if mu > 0.0 { 1.0 } else { 0.0 });
        }
    }
    for (k, mode) in st.modes.iter().enumerate() {
        m.insert_named(format!("buckling_{}_load_factor", k + 1), mode.load_factor);
    }
    for (k, w) in st.omegas_rad_per_s.iter().enumerate() {
        m.insert_named(format!("omega_{}_rad_per_s", k + 1), *w);
    }
}

/// An arc-length path's metrics (D25): the load factor where it ended, the first limit and
/// bifurcation points' load factors, its points.
fn path_metrics(p: &PathOutput, m: &mut Metrics) {
    use crate::solve::arclength::Critical;
    if let Some(last) = p.points.last() {
        m.insert(Metric::FinalLoadFactor, last.load_factor);
    }
    m.insert(Metric::PathPoints, p.points.len() as f64);
    if let Some(c) = p.critical.iter().find(|c| matches!(c, Critical::Limit { .. })) {
        m.insert(Metric::LimitLoadFactor, c.load_factor());
    }
    if let Some(c) = p.critical.iter().find(|c| matches!(c, Critical::Bifurcation { .. })) {
        m.insert(Metric::BifurcationLoadFactor, c.load_factor());
    }
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
    m.insert(Metric::XErrRel, last.x_err_rel);
    m.insert(Metric::TangentMisfit, last.tangent_misfit);
    if inv.angles_known {
        let k: Vec<_> = r.nodes.element_curvature().into_iter().map(|(_, k)| k).collect();
        let kf: Vec<_> = inv.data.element_curvature().into_iter().map(|(_, k)| k).collect();
        m.insert(Metric::KappaErrRel, relative_error(&k, &kf, 0));
        m.insert(Metric::KappaErrRelInner, relative_error(&k, &kf, INNER_SKIP_ELEMENTS));
    }
    for (key, v) in Metric::OBJECTIVE.into_iter().zip(last.objective.values()) {
        m.insert(key, v);
    }
    m.insert(Metric::ForceL2, (2.0 * last.objective.force / inv.lambda_f).sqrt());
    m.insert(Metric::TorqueL2, (2.0 * last.objective.torque / inv.lambda_l).sqrt());
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
    let Some(Reference::TipLoadedCantilever { force_n }) = case.checks.reference else {
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
    for (tip, error, value) in [
        (Metric::Eq63TipY, Metric::Eq63RelError, eq63),
        (Metric::ElasticaTipY, Metric::ElasticaRelError, elastica),
        (Metric::ReissnerTipY, Metric::ReissnerRelError, reissner),
    ] {
        m.insert(tip, value);
        m.insert(error, tip_y / value - 1.0);
    }
    Ok(())
}

/// All metrics written to `metrics.json`: physical ones, errors against the case's
/// `[reference]` theory, solver statistics, and its published values (`reference.*`,
/// `super::published`).
pub fn all_metrics(case: &Case, r: &RunResult) -> Result<Metrics, ReferenceError> {
    let mut m = physical_metrics(r);
    m.extend(inverse_metrics(r));
    reference_metrics(case, r, &mut m)?;
    m.insert(Metric::Iterations, r.stats.iterations as f64);
    if let Some(v) = r.stats.last_change {
        m.insert(Metric::LastChange, v);
    }
    if let Some(v) = r.stats.residual {
        m.insert(Metric::RelativeResidual, v);
    }
    if let Some(v) = r.stats.max_newton_iterations {
        m.insert(Metric::MaxNewtonIterations, v as f64);
    }
    if let Some(v) = r.stats.certificate {
        m.insert(Metric::Certificate, v);
    }
    m.insert(Metric::WallTime, r.stats.wall_time_s);
    let published = super::published::evaluate(case, r, &m);
    m.extend(super::published::metric_entries(&published));
    Ok(m)
}

/// Which tolerance of a case's `[compare]` table a comparison row falls under (overrides,
/// docs/decisions.md D14).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Group {
    /// node-wise displacement and the tip history (`displacement_rel`)
    Displacement,
    /// node-wise angles (`angles_rel`)
    Angles,
    /// node-wise adjoints x̂, α̂ (`adjoint_rel`)
    Adjoint,
    /// scalar metrics (`metric_rel`, `metric_abs`)
    Metric,
    /// iteration counts (`iterations_abs`)
    Iterations,
    /// the residual certificates of the two results (`docs/certificate.md`): equal to their
    /// sensitivity, or both at the round-off floor
    Certificate,
}

/// One compared quantity of two runs: a field difference (relative, D8), a scalar metric of
/// each (absolute difference) or an iteration count.
#[derive(Clone, Debug, PartialEq)]
pub struct Difference {
    pub name: String,
    pub group: Group,
    /// the two runs' values (`None` for field rows)
    pub a: Option<f64>,
    pub b: Option<f64>,
    /// field rows: max node-wise |Δ| / max |field|; metrics and counts: |a − b| (∞ if either
    /// is missing or not finite)
    pub difference: f64,
    /// scalar metrics: the field row (group) whose relative difference σ bounds this metric's,
    /// `|Δq| ≲ σ · scale`: a tip position by the displacement (scale max |x − x0|), a tip angle
    /// by the angles (max |α|), the recovery errors by the state they are computed from
    pub bound: Option<(Group, f64)>,
}

/// Metrics the FreeFEM engine does not compute (the mass-matrix eigen-analysis of a static
/// state, D27): compared only when both runs have them.
pub const RUST_ONLY_METRICS: [Metric; 2] = [Metric::TangentSmallestEigenvalue, Metric::Stable];

/// Whether [`differences`] compares the runs' iteration counts: where both engines run the same
/// algorithm to the same rule (not where they run an equal count by construction).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Iterations {
    Compared,
    Ignored,
}

/// The quantities two runs of the same case are compared on: node-wise displacement, angles
/// and (inverse) adjoints, the tip history of a dynamic run, the physical metrics, the recovery
/// errors and, as `iterations` says, the iteration counts.
pub fn differences(a: &RunResult, b: &RunResult, iterations: Iterations) -> Vec<Difference> {
    let mut rows = Vec::new();
    let amax = |v: &[Vector3<f64>]| v.iter().fold(0.0_f64, |m, v| m.max(v.amax()));
    let disp_scale = amax(&a.nodes.displacement()).max(amax(&a.tip.iter().map(|t| t.position_m).collect::<Vec<_>>()));
    let angle_scale = amax(&a.nodes.alpha).max(amax(&a.tip.iter().map(|t| t.angles_rad).collect::<Vec<_>>()));
    let nodes_match = a.nodes.s.len() == b.nodes.s.len();
    if nodes_match {
        rows.push(Difference::field(
            "nodewise_rel_diff_displacement",
            Group::Displacement,
            max_relative_difference(&a.nodes.displacement(), &b.nodes.displacement()),
        ));
        rows.push(Difference::field(
            "nodewise_rel_diff_angles",
            Group::Angles,
            max_relative_difference(&a.nodes.alpha, &b.nodes.alpha),
        ));
    } else {
        rows.push(Difference::field("node_count", Group::Displacement, f64::INFINITY));
    }
    let (ma, mb) = (physical_metrics(a), physical_metrics(b));
    for (name, x) in ma.iter() {
        if RUST_ONLY_METRICS.iter().any(|k| k.as_str() == name) && mb.named(name).is_none() {
            continue;
        }
        let bound = if name.ends_with("_rad") {
            Some((Group::Angles, angle_scale))
        } else if name.ends_with("load_factor") || name.ends_with("_rad_per_s") {
            // a load factor on the path moves with the state it balances, R(u, λ) = 0: relatively;
            // a natural frequency (D28) is a relative quantity of the same matrices
            Some((Group::Displacement, x.abs()))
        } else if name == Metric::PathPoints.as_str() || name == Metric::Stable.as_str() {
            None // a count or a verdict: equal, or the runs differ
        } else if name == Metric::TangentSmallestEigenvalue.as_str() {
            Some((Group::Displacement, x.abs()))
        } else {
            Some((Group::Displacement, disp_scale))
        };
        rows.push(Difference::scalar(name, Group::Metric, Some(x), mb.named(name), bound));
    }
    if let (Some(p), Some(q)) = (&a.path, &b.path) {
        rows.extend(path_differences(p, q));
    }
    if a.tip.len() == b.tip.len() && !a.tip.is_empty() {
        let p: Vec<_> = a.tip.iter().map(|t| t.position_m - a.tip[0].position_m).collect();
        let q: Vec<_> = b.tip.iter().map(|t| t.position_m - b.tip[0].position_m).collect();
        rows.push(Difference::field("tip_history_rel_diff", Group::Displacement, max_relative_difference(&p, &q)));
    } else if a.tip.len() != b.tip.len() {
        rows.push(Difference::field("tip_history_length", Group::Displacement, f64::INFINITY));
    }
    if let (Some(x), Some(y)) = (&a.inverse, &b.inverse) {
        if nodes_match {
            rows.push(Difference::field(
                "nodewise_rel_diff_xhat",
                Group::Adjoint,
                max_relative_difference(&x.xhat, &y.xhat),
            ));
            rows.push(Difference::field(
                "nodewise_rel_diff_ahat",
                Group::Adjoint,
                max_relative_difference(&x.ahat, &y.ahat),
            ));
        }
        rows.extend(recovery_differences(a, b, x, angle_scale));
    }
    if a.stats.certificate.is_some() || b.stats.certificate.is_some() {
        rows.push(Difference::scalar(
            "certificate",
            Group::Certificate,
            a.stats.certificate,
            b.stats.certificate,
            None,
        ));
    }
    if iterations == Iterations::Compared {
        let (x, y) = (a.stats.iterations as f64, b.stats.iterations as f64);
        rows.push(Difference::scalar("iterations", Group::Iterations, Some(x), Some(y), None));
    }
    rows
}

/// Two arc-length paths (D25): the number of critical points and, over paths of as many points,
/// the load factors and the recorded displacements point by point (relative to their largest).
fn path_differences(p: &PathOutput, q: &PathOutput) -> Vec<Difference> {
    let count = |p: &PathOutput| Some(p.critical.len() as f64);
    let mut rows = vec![Difference::scalar("critical_points", Group::Metric, count(p), count(q), None)];
    if p.points.len() == q.points.len() {
        let lambda = |p: &PathOutput| p.points.iter().map(|r| Vector3::new(r.load_factor, 0.0, 0.0)).collect();
        let disp = |p: &PathOutput| p.points.iter().flat_map(|r| r.displacements.clone()).collect::<Vec<_>>();
        let (lp, lq): (Vec<_>, Vec<_>) = (lambda(p), lambda(q));
        rows.push(Difference::field(
            "path_rel_diff_load_factor",
            Group::Displacement,
            max_relative_difference(&lp, &lq),
        ));
        rows.push(Difference::field(
            "path_rel_diff_displacement",
            Group::Displacement,
            max_relative_difference(&disp(p), &disp(q)),
        ));
    }
    rows
}

/// The recovery errors of two inverse runs (`x`: the first run's inverse output), each judged
/// against its own scale.
fn recovery_differences(a: &RunResult, b: &RunResult, x: &InverseOutput, angle_scale: f64) -> Vec<Difference> {
    let mut rows = Vec::new();
    // Recovery errors (κ amplifies angle differences by ~1/h).
    // x_err_rel moves with the displacement relative to the data's size (scale 1); the
    // curvature errors with ∂sα: 2 max|Δα|/h against the data's rms curvature.
    let (ma, mb) = (inverse_metrics(a), inverse_metrics(b));
    let kf: Vec<f64> = x.data.element_curvature().iter().map(|(_, k)| k.norm_squared()).collect();
    let k_rms = (kf.iter().sum::<f64>() / kf.len().max(1) as f64).sqrt();
    let h = a.nodes.s.get(1).copied().unwrap_or(1.0) - a.nodes.s.first().copied().unwrap_or(0.0);
    for key in [Metric::XErrRel, Metric::KappaErrRel, Metric::KappaErrRelInner].into_iter().filter(|k| ma.contains(*k))
    {
        let bound = if key == Metric::XErrRel {
            (Group::Displacement, 1.0)
        } else {
            (Group::Angles, 2.0 * angle_scale / (h * k_rms))
        };
        rows.push(Difference::scalar(key.as_str(), Group::Metric, ma.get(key), mb.get(key), Some(bound)));
    }
    rows
}

impl Difference {
    /// A node-wise or history difference without values of its own (NaN counts as infinite).
    fn field(name: &str, group: Group, difference: f64) -> Difference {
        Difference {
            name: name.into(),
            group,
            a: None,
            b: None,
            difference: if difference.is_nan() { f64::INFINITY } else { difference },
            bound: None,
        }
    }

    /// The difference `|x − y|` of a scalar of both runs (infinite if either lacks it or it is
    /// NaN), with the scale `bound` it is judged against.
    fn scalar(name: &str, group: Group, x: Option<f64>, y: Option<f64>, bound: Option<(Group, f64)>) -> Difference {
        let d = match (x, y) {
            (Some(x), Some(y)) => (x - y).abs(),
            _ => f64::INFINITY,
        };
        Difference {
            name: name.into(),
            group,
            a: x,
            b: y,
            difference: if d.is_nan() { f64::INFINITY } else { d },
            bound,
        }
    }
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
    /// how the tolerance was found (derived from the perturbed run, or the case's override)
    pub basis: String,
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
    if a.len() != b.len() {
        f64::INFINITY
    } else if diff == 0.0 {
        0.0
    } else if scale == 0.0 {
        f64::INFINITY
    } else {
        diff / scale
    }
}
