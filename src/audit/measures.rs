//! Numbers a claim of the paper needs beyond a run's own metrics, each from an independent
//! reference or a definition written here:
//! - `eq63_curve_rel_error` (tip-loaded cantilevers, Fig. 7): `max_s |y(s) − y₆₃(s)| / |y₆₃(L)|`
//!   against eq. (63) along the whole rod;
//! - `modal_tip_rel_error` (dynamic runs, Fig. 5): the tip history against the exact-in-time
//!   response of the linearised discrete model (`solve::modes`) to the same load, sampled
//!   twice per time step and linear in between;
//!   `modal_tip_angle_rel_error`: the same for the tip's angles α, β, γ relative to their
//!   largest, and `modal_tip_worst_rel_error` the larger of the two (Fig. 5: "the displacement
//!   and rotation"); `first_frequency_rad_per_s`: the lowest natural frequency of the discrete
//!   rod (§5.1: "the natural frequency of the system ω0");
//! - `tip_deflection_rel_length` (tip-loaded cantilevers): |y(L)| / L (Fig. 7: "5% deflection");
//! - `adjoint_alpha_max_abs` (inverse runs): max |α̂| over the nodes, the paper's δα, and
//!   `adjoint_alpha_orders_from_paper`: its orders of magnitude from the paper's line
//!   δα = 10⁷ λl (eq. 64, finding (2): "from 10⁻¹³ to 10¹⁰" as λl goes from 10⁻²⁰ to 10³);
//! - `kappa3_max_abs_per_m` (inverse runs): max |κ3| without the end elements (eq. 65,
//!   finding (4): "a too large κ3 could be generated");
//! - `force_to_design_l2`, `torque_to_design_l2` (synthetic inverse runs, Fig. 15): ‖f‖/‖f_design‖
//!   and ‖l‖/‖l_design‖, L² norms over the rod, the design the loads of the `[data]` solve, and
//!   `force_to_design_orders`, `torque_to_design_orders`: |log10| of those ratios (orders of
//!   magnitude apart);
//! - `force_to_design_orders_inner`, `torque_to_design_orders_inner`: the same over the nodes
//!   without [`INNER_SKIP_ELEMENTS`] at each end, the rule of the curvature rows (the clamp's
//!   spike in the first elements is not the distribution of Fig. 15), RMS over those nodes;
//! - `torque_max_abs_inner_n_m_per_m`: max |l| = |α̂|/λl over the same nodes (eq. 64,
//!   finding (2): "the control torque l = δα/λl always has a magnitude of 10⁻⁷");
//! - `frame_err_max_rad` (synthetic inverse runs): the largest rotation angle between the
//!   recovered frame and the forward one over the nodes, `acos((Σᵢ dᵢ·dᵢᶠ − 1)/2)` (eq. 2;
//!   chart-free), Remark 11: "converging to the same position vector x and rotation α";
//! - `other_components_rel` (synthetic inverse runs): max |x₁| over max |x − (0, 0, s)| and
//!   max(|κ2|, |κ3|) over max |κ1|, the larger (eq. 64: "all the other components of the
//!   position vector and generalised curvature are zero");
//! - clip runs ([`ClipSeries`]): RMS of the recovered κ1, κ2, κ3 and of the bending
//!   `√(κ1² + κ2²)` over frames and inner elements [1/m] (Figs. 17, 23, 25);
//!   `kappa_rate_rms_per_m_per_s`: the RMS of `(κ(t) − κ(t − Δt))/Δt` over frames, inner
//!   elements and components (§6: "the curvature along the worm's body does not change
//!   significantly in time"); and `x_err_rel_jitter`: the largest frame-to-frame oscillation of
//!   ‖x − x_g‖/‖x_g‖ over its median (Fig. 20 (i));
//! - the curvature waves of a clip run (`super::wave`, in time windows): of the bending
//!   `√(κ1² + κ2²)` (`bending_wave_head_to_tail_share`, `bending_wave_tail_to_head_share`, their
//!   `bending_wave_speed_body_per_s` and `bending_wave_clarity`), of the components κ1 and κ2
//!   as Figs. 17 and 23 draw them (`kappa12_wave_clarity`, the mean of the two clarities) and of
//!   the twist κ3 (`twist_wave_clarity`);
//! - `kappa3_head_peak_frame`, `kappa3_head_peak_ratio_elsewhere`, `kappa3_head_peak_ratio_other_frames`
//!   (§6, Fig. 22: "κ3 is much larger near the worm's head at frame 700 than elsewhere or any
//!   other frames"): the frame where the largest |κ3| over the head's elements ([`HEAD_FRACTION`]
//!   of the body after the end elements) peaks, that peak over the largest |κ3| of the other
//!   inner elements at that frame, and over the largest |κ3| of the inner elements at the frames
//!   more than [`PEAK_FRAMES_APART`] away;
//! - synthetic clips, against their ground truth: `super::truth`;
//! - synthetic inverse runs, the data the test makes (§5.2): `data_rotation_max_rad`, the
//!   largest rotation of the forward frames from the straight reference, `acos((Σᵢ dᵢ·eᵢ − 1)/2)`
//!   (eq. 2); `data_kappa1_extent`, the share of the inner elements where the forward |κ1| is at
//!   least a tenth of its largest (eq. 64: "a curvature κ1 ... is also generated along the
//!   rod"); `data_torsion_to_bending_rms`, the RMS of the forward centreline's torsion over
//!   that of its curvature over the inner elements (eq. 65: "both curvature and torsion",
//!   [`torsion_to_bending`]);
//! - `force_distribution_diff`, `torque_distribution_diff` (synthetic inverse runs, Fig. 15:
//!   "the distribution is different"): `‖ |f|/‖f‖ − |f_d|/‖f_d‖ ‖` over the inner nodes, the
//!   magnitudes along the rod of the control and of the design each scaled to norm 1 (0: the
//!   same distribution, √2: disjoint), frame-free as [`inner_control_metrics`].
use nalgebra::{DVector, Vector3};

use crate::case::{Analysis, Case, Reference};
use crate::engine::clip::ClipFrame;
use crate::engine::metrics::{Metric, Metrics, INNER_SKIP_ELEMENTS};
use crate::engine::RunResult;
use crate::model::mesh::Field;
use crate::reference::timoshenko_deflection;
use crate::solve::modes::modal_model;

use super::truth::{truth_metrics, TruthSeries};
use super::wave::{propagation, Direction};

/// Per-frame series of a clip run kept for the audit's measures and figures.
#[derive(Clone, Debug, Default)]
pub struct ClipSeries {
    /// frame numbers
    pub frames: Vec<usize>,
    /// element midpoints [m]
    pub s_mid: Vec<f64>,
    /// per frame: element-midpoint curvature κ = A ∂sα [1/m] (eq. 28)
    pub kappa: Vec<Vec<Vector3<f64>>>,
    /// per frame: max over the nodes of |ω| [rad/s] (eq. 27 between frames; 0 on the first)
    pub omega_max: Vec<f64>,
    /// per frame: the real objective ‖x − x_g‖/‖x_g‖
    pub x_err_rel: Vec<f64>,
    /// the frames asked for (posture figures)
    pub kept: Vec<ClipFrame>,
    /// the last frame solved
    pub last: Option<ClipFrame>,
    /// synthetic clips: the frames against their ground truth
    pub truth: Option<TruthSeries>,
}

/// Collects a [`ClipSeries`] frame by frame (the observer of a clip run).
pub struct ClipRecorder {
    keep: Vec<usize>,
    series: ClipSeries,
}

impl ClipRecorder {
    pub fn new(keep: &[usize]) -> Self {
        ClipRecorder { keep: keep.to_vec(), series: ClipSeries::default() }
    }
    pub fn record(&mut self, frame: &ClipFrame) {
        if self.series.s_mid.is_empty() {
            self.series.s_mid = frame.elements.kappa.iter().map(|(s, _)| *s).collect();
        }
        self.series.frames.push(frame.report.frame);
        self.series.kappa.push(frame.elements.kappa.iter().map(|(_, k)| *k).collect());
        self.series
            .omega_max
            .push(frame.omega.as_ref().map_or(0.0, |w| w.iter().map(|v| v.norm()).fold(0.0, f64::max)));
        self.series.x_err_rel.push(frame.report.misfit.x_err_rel);
        if let Some(t) = &frame.truth {
            let ts = self.series.truth.get_or_insert_with(TruthSeries::default);
            ts.bending_true.push(t.bending_true.clone());
            ts.bending_recovered.push(t.bending_recovered.clone());
            ts.comparisons.push(t.comparison);
            ts.twist_per_m.push(t.twist_per_m);
        }
        if self.keep.contains(&frame.report.frame) {
            self.series.kept.push(frame.clone());
        }
        self.series.last = Some(frame.clone());
    }
    pub fn finish(self) -> ClipSeries {
        self.series
    }
}

/// The derived metrics of a point (see the module documentation); absent where they do not
/// apply.
pub fn derived_metrics(case: &Case, run: Option<&RunResult>, series: Option<&ClipSeries>) -> Metrics {
    let mut m = Metrics::new();
    if let Some(r) = run {
        if let Some(Reference::TipLoadedCantilever { force_n }) = case.checks.reference {
            let (l, kga, ei) = (case.mesh.length_m, case.props.shear_stretch_n[0], case.props.bend_twist_nm2[0]);
            let tip = timoshenko_deflection(l, force_n, l, kga, ei).abs();
            let worst = r
                .nodes
                .s
                .iter()
                .zip(&r.nodes.x)
                .map(|(s, x)| (x[1] - timoshenko_deflection(*s, force_n, l, kga, ei)).abs())
                .fold(0.0, f64::max);
            m.insert_named("eq63_curve_rel_error", worst / tip);
            if let Some(x) = r.nodes.x.last() {
                m.insert_named("tip_deflection_rel_length", x[1].abs() / l);
            }
        }
        if let Some((x, a)) = modal_tip_errors(case, r) {
            m.insert_named("modal_tip_rel_error", x);
            m.insert_named("modal_tip_angle_rel_error", a);
            m.insert_named("modal_tip_worst_rel_error", x.max(a));
        }
        if matches!(case.analysis, Analysis::Dynamic(_)) {
            if let Some(w) = modal_model(&case.problem()).ok().and_then(|m| m.omegas.first().copied()) {
                m.insert_named("first_frequency_rad_per_s", w);
            }
        }
        if r.inverse.is_some() {
            let k = r.nodes.element_curvature();
            let n = k.len();
            let inner = k.iter().skip(INNER_SKIP_ELEMENTS).take(n.saturating_sub(2 * INNER_SKIP_ELEMENTS));
            m.insert_named("kappa3_max_abs_per_m", inner.map(|(_, k)| k[2].abs()).fold(0.0, f64::max));
            let own = crate::engine::metrics::inverse_metrics(r);
            let (fc, lc) = (own.get(Metric::ForceL2), own.get(Metric::TorqueL2));
            if let (Some((f, l)), Some(fc), Some(lc)) = (design_norms(case), fc, lc) {
                m.insert_named("force_to_design_l2", fc / f);
                m.insert_named("torque_to_design_l2", lc / l);
                m.insert_named("force_to_design_orders", (fc / f).log10().abs());
                m.insert_named("torque_to_design_orders", (lc / l).log10().abs());
            }
            m.extend(inner_control_metrics(case, r));
            m.extend(frame_metrics(r));
            m.extend(data_metrics(r));
            if let Some(inv) = r.inverse.as_ref() {
                let a = inv.ahat.iter().map(|a| a.norm()).fold(0.0, f64::max);
                m.insert_named("adjoint_alpha_max_abs", a);
                m.insert_named("adjoint_alpha_orders_from_paper", (a / (1e7 * inv.lambda_l)).log10().abs());
            }
        }
    }
    if let Some(s) = series {
        // the time between frames [s]; a clip case always has one
        let dt_s = case.inverse().map_or(1.0, |i| i.params.frame_interval_s);
        m.extend(clip_series_metrics(s, dt_s));
        if let Some(t) = &s.truth {
            m.extend(truth_metrics(t, dt_s));
        }
    }
    m
}

/// The recovered frames against the forward ones, and the components the planar test of
/// eq. (64) leaves at zero (see the module documentation); none for a recording.
fn frame_metrics(r: &RunResult) -> Metrics {
    let mut m = Metrics::new();
    let Some(inv) = r.inverse.as_ref().filter(|i| i.angles_known) else { return m };
    let angle = |d: &[Vector3<f64>; 3], f: &[Vector3<f64>; 3]| {
        let trace: f64 = (0..3).map(|i| d[i].dot(&f[i])).sum();
        ((trace - 1.0) / 2.0).clamp(-1.0, 1.0).acos()
    };
    let worst = r.nodes.directors().iter().zip(inv.data.directors()).map(|(d, f)| angle(d, &f)).fold(0.0, f64::max);
    m.insert_named("frame_err_max_rad", worst);
    let max = |v: &mut dyn Iterator<Item = f64>| v.fold(0.0, f64::max);
    let disp = max(&mut r.nodes.displacement().iter().map(|d| d.norm()));
    let x1 = max(&mut r.nodes.x.iter().map(|x| x[0].abs()));
    let k = r.nodes.element_curvature();
    let k1 = max(&mut k.iter().map(|(_, k)| k[0].abs()));
    let k23 = max(&mut k.iter().map(|(_, k)| k[1].abs().max(k[2].abs())));
    if disp > 0.0 && k1 > 0.0 {
        m.insert_named("other_components_rel", (x1 / disp).max(k23 / k1));
    }
    m
}

/// The data a synthetic inverse test makes (see the module documentation); none for a
/// recording.
fn data_metrics(r: &RunResult) -> Metrics {
    let mut m = Metrics::new();
    let Some(inv) = r.inverse.as_ref().filter(|i| i.angles_known) else { return m };
    let angle = |d: &[Vector3<f64>; 3]| {
        let trace: f64 = (0..3).map(|i| d[i][i]).sum();
        ((trace - 1.0) / 2.0).clamp(-1.0, 1.0).acos()
    };
    m.insert_named("data_rotation_max_rad", inv.data.directors().iter().map(angle).fold(0.0, f64::max));
    let k = inv.data.element_curvature();
    let n = k.len();
    if n <= 2 * INNER_SKIP_ELEMENTS {
        return m;
    }
    let inner: Vec<Vector3<f64>> = k[INNER_SKIP_ELEMENTS..n - INNER_SKIP_ELEMENTS].iter().map(|(_, k)| *k).collect();
    let k1_max = inner.iter().map(|k| k[0].abs()).fold(0.0, f64::max);
    if k1_max > 0.0 {
        let extent = inner.iter().filter(|k| k[0].abs() >= 0.1 * k1_max).count();
        m.insert_named("data_kappa1_extent", extent as f64 / inner.len() as f64);
    }
    if let Some(r) = torsion_to_bending(&k[INNER_SKIP_ELEMENTS..n - INNER_SKIP_ELEMENTS]) {
        m.insert_named("data_torsion_to_bending_rms", r);
    }
    m
}

/// The RMS of the torsion of the centreline, `τ = κ3 + ∂sφ` with `φ = atan2(κ2, κ1)` the
/// direction of the bending about d3 (between neighbouring elements, where both bend by at
/// least 5 % of the largest bending: elsewhere φ has no direction), over the RMS of the
/// curvature `√(κ1² + κ2²)` there; `kappa`: `(s [m], κ [1/m])` per element.
fn torsion_to_bending(kappa: &[(f64, Vector3<f64>)]) -> Option<f64> {
    let bend = |k: &Vector3<f64>| (k[0] * k[0] + k[1] * k[1]).sqrt();
    let most = kappa.iter().map(|(_, k)| bend(k)).fold(0.0, f64::max);
    let (mut tau2, mut bend2) = (0.0, 0.0);
    for w in kappa.windows(2) {
        let ((s0, k0), (s1, k1)) = (w[0], w[1]);
        if bend(&k0) < 0.05 * most || bend(&k1) < 0.05 * most || s1 <= s0 {
            continue;
        }
        let turn = k1[1].atan2(k1[0]) - k0[1].atan2(k0[0]);
        // wrapped into (−π, π]
        let turn = turn - 2.0 * std::f64::consts::PI * (turn / (2.0 * std::f64::consts::PI)).round();
        let tau = 0.5 * (k0[2] + k1[2]) + turn / (s1 - s0);
        tau2 += tau * tau;
        bend2 += (0.5 * (bend(&k0) + bend(&k1))).powi(2);
    }
    (bend2 > 0.0).then(|| (tau2 / bend2).sqrt())
}

/// The controls f = x̂/λf, l = α̂/λl of an inverse run at the nodes without
/// [`INNER_SKIP_ELEMENTS`] at each end (eq. 61): max |l|, and against the design loads of a
/// synthetic case's `[data]` solve the orders of magnitude of the RMS ratios (Fig. 15).
fn inner_control_metrics(case: &Case, r: &RunResult) -> Metrics {
    let mut m = Metrics::new();
    let Some(inv) = r.inverse.as_ref() else { return m };
    let n = r.nodes.s.len();
    if n <= 2 * INNER_SKIP_ELEMENTS + 1 {
        return m;
    }
    let inner = INNER_SKIP_ELEMENTS..n - INNER_SKIP_ELEMENTS;
    let l_max = inv.ahat[inner.clone()].iter().map(|a| a.norm() / inv.lambda_l).fold(0.0, f64::max);
    m.insert_named("torque_max_abs_inner_n_m_per_m", l_max);
    let Some(data) = case.data_case() else { return m };
    let rms = |v: &mut dyn Iterator<Item = f64>| {
        let (sum, count) = v.fold((0.0, 0usize), |(a, c), x| (a + x * x, c + 1));
        (sum / count.max(1) as f64).sqrt()
    };
    let design = |i: usize| data.loads.distributed(r.nodes.s[i], 0.0);
    let f = rms(&mut inner.clone().map(|i| inv.xhat[i].norm() / inv.lambda_f));
    let l = rms(&mut inner.clone().map(|i| inv.ahat[i].norm() / inv.lambda_l));
    let (fd, ld) =
        (rms(&mut inner.clone().map(|i| design(i).0.norm())), rms(&mut inner.clone().map(|i| design(i).1.norm())));
    if fd > 0.0 && ld > 0.0 {
        m.insert_named("force_to_design_orders_inner", (f / fd).log10().abs());
        m.insert_named("torque_to_design_orders_inner", (l / ld).log10().abs());
    }
    let shape = |ours: &dyn Fn(usize) -> f64, design: &dyn Fn(usize) -> f64| {
        let norm = |g: &dyn Fn(usize) -> f64| inner.clone().map(|i| g(i) * g(i)).sum::<f64>().sqrt();
        let (a, b) = (norm(ours), norm(design));
        (a > 0.0 && b > 0.0).then(|| inner.clone().map(|i| (ours(i) / a - design(i) / b).powi(2)).sum::<f64>().sqrt())
    };
    if let Some(d) = shape(&|i| inv.xhat[i].norm(), &|i| design(i).0.norm()) {
        m.insert_named("force_distribution_diff", d);
    }
    if let Some(d) = shape(&|i| inv.ahat[i].norm(), &|i| design(i).1.norm()) {
        m.insert_named("torque_distribution_diff", d);
    }
    m
}

/// `(‖f_design‖, ‖l_design‖)` [N/m · m^½, N m/m · m^½]: L² norms over the rod of the
/// distributed loads of a synthetic inverse case's `[data]` solve (|f| does not depend on the
/// frame the load is given in), by the 2-point rule per element.
fn design_norms(case: &Case) -> Option<(f64, f64)> {
    let data = case.data_case()?;
    let h = data.mesh.h();
    let (mut f2, mut l2) = (0.0, 0.0);
    for e in 0..data.mesh.elements {
        for (xi, w) in crate::model::mesh::GAUSS2.iter() {
            let s = (e as f64 + xi) * h;
            let (f, l) = data.loads.distributed(s, 0.0);
            f2 += w * h * f.norm_squared();
            l2 += w * h * l.norm_squared();
        }
    }
    Some((f2.sqrt(), l2.sqrt()))
}

/// Max over the time steps of the tip's gap to the modal solution, relative to the modal
/// solution's largest value: of the displacement (x, y) and of the rotation (α, β, γ);
/// `None` for other runs or when the modal model cannot be built.
fn modal_tip_errors(case: &Case, r: &RunResult) -> Option<(f64, f64)> {
    let modal = modal_tip_history(case, r)?;
    let gap = |rec: &dyn Fn(usize) -> [f64; 3], m: &dyn Fn(usize) -> [f64; 3], comps: usize| {
        let (mut err, mut scale) = (0.0f64, 0.0f64);
        for i in 0..modal.len().min(r.tip.len()) {
            let (a, b) = (rec(i), m(i));
            for c in 0..comps {
                scale = scale.max(b[c].abs());
                err = err.max((a[c] - b[c]).abs());
            }
        }
        (scale > 0.0).then_some(err / scale)
    };
    let x = gap(
        &|i| [r.tip[i].position_m[0], r.tip[i].position_m[1], 0.0],
        &|i| [modal[i].position_m[0], modal[i].position_m[1], 0.0],
        2,
    )?;
    let a = gap(&|i| r.tip[i].angles_rad.into(), &|i| modal[i].angles_rad, 3)?;
    Some((x, a))
}

/// The tip of the linearised discrete model at one record of a dynamic run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModalTip {
    /// the tip's x, y [m]
    pub position_m: [f64; 2],
    /// the tip's angles α, β, γ [rad] (the increments about the straight reference)
    pub angles_rad: [f64; 3],
}

/// The tip at the times of a dynamic run's tip records, from the exact-in-time
/// response of the linearised discrete model (all modes) to the case's load, sampled twice per
/// time step and linear in between; `None` for other runs.
pub fn modal_tip_history(case: &Case, r: &RunResult) -> Option<Vec<ModalTip>> {
    let Analysis::Dynamic(p) = &case.analysis else { return None };
    if r.tip.is_empty() {
        return None;
    }
    let problem = case.problem();
    let model = modal_model(&problem).ok()?;
    let dt = p.end_time_s / p.steps as f64;
    const SUB: usize = 2;
    let ds = dt / SUB as f64;
    let nm = model.omegas.len();
    let last = case.mesh.nodes() - 1;
    let dofs = case.mesh.dofs();
    let (mut q, mut v) = (DVector::<f64>::zeros(nm), DVector::<f64>::zeros(nm));
    let mut g0 = model.project(&problem.external_force(0.0));
    let mut out = Vec::with_capacity(r.tip.len());
    let mut step = 0usize;
    for rec in &r.tip {
        // the record's step number (records at t = 0 included)
        let target = (rec.time_s / dt).round();
        if target < step as f64 || (rec.time_s - target * dt).abs() > 1e-9 * dt.max(rec.time_s) {
            return None;
        }
        for n in step..target as usize {
            for k in 0..SUB {
                let t1 = (n * SUB + k + 1) as f64 * ds;
                let g1 = model.project(&problem.external_force(t1));
                for i in 0..nm {
                    // q'' + ω² q = g0 + (g1 − g0) τ/ds on [0, ds], exactly.
                    let w = model.omegas[i];
                    let rate = (g1[i] - g0[i]) / ds;
                    let (c, s) = ((w * ds).cos(), (w * ds).sin());
                    let a = q[i] - g0[i] / (w * w);
                    let b = (v[i] - rate / (w * w)) / w;
                    q[i] = g1[i] / (w * w) + a * c + b * s;
                    v[i] = rate / (w * w) - a * w * s + b * w * c;
                }
                g0 = g1;
            }
        }
        step = target as usize;
        out.push(ModalTip {
            position_m: [0, 1].map(|comp| model.displacement(dofs.index(last, Field::X, comp), &q)),
            angles_rad: [0, 1, 2].map(|comp| model.displacement(dofs.index(last, Field::Alpha, comp), &q)),
        });
    }
    Some(out)
}

/// RMS of the recovered curvature components over the frames and the inner elements, their
/// rate, the curvature waves and the head's twist peak (see the module documentation); `dt_s`
/// the time between frames [s].
fn clip_series_metrics(s: &ClipSeries, dt_s: f64) -> Metrics {
    let mut m = Metrics::new();
    let ne = s.s_mid.len();
    if s.kappa.is_empty() || ne <= 2 * INNER_SKIP_ELEMENTS {
        return m;
    }
    let inner = INNER_SKIP_ELEMENTS..ne - INNER_SKIP_ELEMENTS;
    let count = (s.kappa.len() * inner.len()) as f64;
    let rms = |f: &dyn Fn(&Vector3<f64>) -> f64| {
        (s.kappa.iter().flat_map(|k| k[inner.clone()].iter().map(f)).sum::<f64>() / count).sqrt()
    };
    m.insert_named("kappa1_rms_per_m", rms(&|k| k[0] * k[0]));
    m.insert_named("kappa2_rms_per_m", rms(&|k| k[1] * k[1]));
    m.insert_named("kappa3_rms_per_m", rms(&|k| k[2] * k[2]));
    m.insert_named("bending_rms_per_m", rms(&|k| k[0] * k[0] + k[1] * k[1]));
    m.insert_named("omega_max_rad_per_s", s.omega_max.iter().copied().fold(0.0, f64::max));
    if s.kappa.len() > 1 {
        let steps = ((s.kappa.len() - 1) * inner.len()) as f64;
        let sum: f64 =
            s.kappa.windows(2).flat_map(|w| inner.clone().map(move |e| (w[1][e] - w[0][e]).norm_squared())).sum();
        m.insert_named("kappa_rate_rms_per_m_per_s", (sum / steps).sqrt() / dt_s);
    }
    m.extend(wave_metrics(s, dt_s));
    m.extend(head_twist_metrics(s));
    if let Some(j) = x_err_jitter(&s.x_err_rel) {
        m.insert_named("x_err_rel_jitter", j);
    }
    m
}

/// The curvature waves of a clip run (`super::wave`): the bending, κ1 and κ2, the twist.
fn wave_metrics(s: &ClipSeries, dt_s: f64) -> Metrics {
    let mut m = Metrics::new();
    let length = s.s_mid.last().copied().unwrap_or(0.0) + s.s_mid.first().copied().unwrap_or(0.0);
    if length <= 0.0 {
        return m;
    }
    let pos: Vec<f64> = s.s_mid.iter().map(|x| x / length).collect();
    let kymo = |f: &dyn Fn(&Vector3<f64>) -> f64| -> Vec<Vec<f64>> {
        s.kappa.iter().map(|row| row.iter().map(f).collect()).collect()
    };
    let bending = propagation(&kymo(&|k| (k[0] * k[0] + k[1] * k[1]).sqrt()), &pos);
    if bending.windows.is_empty() {
        return m;
    }
    m.insert_named("bending_wave_head_to_tail_share", bending.share(Direction::HeadToTail));
    m.insert_named("bending_wave_tail_to_head_share", bending.share(Direction::TailToHead));
    m.insert_named("bending_wave_clarity", bending.clarity());
    if let Some(v) = bending.median_speed_body_per_frame() {
        m.insert_named("bending_wave_speed_body_per_s", v / dt_s);
    }
    let (k1, k2) = (propagation(&kymo(&|k| k[0]), &pos), propagation(&kymo(&|k| k[1]), &pos));
    m.insert_named("kappa12_wave_clarity", 0.5 * (k1.clarity() + k2.clarity()));
    m.insert_named("twist_wave_clarity", propagation(&kymo(&|k| k[2]), &pos).clarity());
    m
}

/// Share of the inner elements, after the end elements, that is the head's (§6, Fig. 22).
pub const HEAD_FRACTION: f64 = 0.1;
/// Frames from the head's twist peak beyond which a frame is "another frame" (Fig. 22).
pub const PEAK_FRAMES_APART: usize = 20;

/// Where and how far the head's |κ3| peaks (see the module documentation); none without frames
/// more than [`PEAK_FRAMES_APART`] from the peak.
fn head_twist_metrics(s: &ClipSeries) -> Metrics {
    let mut m = Metrics::new();
    let ne = s.s_mid.len();
    let inner = INNER_SKIP_ELEMENTS..ne - INNER_SKIP_ELEMENTS;
    let head = INNER_SKIP_ELEMENTS..INNER_SKIP_ELEMENTS + ((HEAD_FRACTION * inner.len() as f64).ceil() as usize).max(1);
    let max3 = |row: &[Vector3<f64>], r: std::ops::Range<usize>| row[r].iter().map(|k| k[2].abs()).fold(0.0, f64::max);
    let heads: Vec<f64> = s.kappa.iter().map(|row| max3(row, head.clone())).collect();
    let Some((at, peak)) = heads.iter().copied().enumerate().max_by(|a, b| a.1.total_cmp(&b.1)) else { return m };
    let rest = max3(&s.kappa[at], head.end..inner.end);
    let others = (0..s.kappa.len()).filter(|&f| f.abs_diff(at) > PEAK_FRAMES_APART);
    let other = others.map(|f| max3(&s.kappa[f], inner.clone())).fold(f64::NAN, f64::max);
    if other.is_nan() || rest <= 0.0 || other <= 0.0 {
        return m;
    }
    m.insert_named("kappa3_head_peak_frame", s.frames[at] as f64);
    m.insert_named("kappa3_head_peak_ratio_elsewhere", peak / rest);
    m.insert_named("kappa3_head_peak_ratio_other_frames", peak / other);
    m
}

/// The frame-to-frame oscillation of the real objective e = ‖x − x_g‖/‖x_g‖ (Fig. 20 (i)):
/// `max_n |e_n − (e_{n−1} + e_{n+1})/2|` over the median of e; `None` below 3 frames.
fn x_err_jitter(e: &[f64]) -> Option<f64> {
    if e.len() < 3 {
        return None;
    }
    let mut sorted = e.to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let worst = e.windows(3).map(|w| (w[1] - 0.5 * (w[0] + w[2])).abs()).fold(0.0, f64::max);
    (median > 0.0).then_some(worst / median)
}
