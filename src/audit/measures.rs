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
//!   `√(κ1² + κ2²)` over frames and inner elements [1/m] (Figs. 17, 23, 25), and the lag in
//!   frames of the bending wave between s = L/4 and 3L/4 (> 0: from s = 0 towards s = L), with
//!   the coherence of the bending and of the twist at their best lag (`bending_wave_coherence`,
//!   `twist_wave_coherence`: a wave that keeps its shape, 1, none, 0), and `x_err_rel_jitter`:
//!   the largest frame-to-frame oscillation of ‖x − x_g‖/‖x_g‖ over its median (Fig. 20 (i)).
use nalgebra::{DVector, Vector3};

use crate::case::{Analysis, Case, Reference};
use crate::engine::clip::ClipFrame;
use crate::engine::metrics::{Metric, Metrics, INNER_SKIP_ELEMENTS};
use crate::engine::RunResult;
use crate::model::mesh::Field;
use crate::reference::timoshenko_deflection;
use crate::solve::modes::modal_model;

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
            if let Some(inv) = r.inverse.as_ref() {
                let a = inv.ahat.iter().map(|a| a.norm()).fold(0.0, f64::max);
                m.insert_named("adjoint_alpha_max_abs", a);
                m.insert_named("adjoint_alpha_orders_from_paper", (a / (1e7 * inv.lambda_l)).log10().abs());
            }
        }
    }
    if let Some(s) = series {
        m.extend(clip_series_metrics(s));
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
    let (fd, ld) = (rms(&mut inner.clone().map(|i| design(i).0.norm())), rms(&mut inner.map(|i| design(i).1.norm())));
    if fd > 0.0 && ld > 0.0 {
        m.insert_named("force_to_design_orders_inner", (f / fd).log10().abs());
        m.insert_named("torque_to_design_orders_inner", (l / ld).log10().abs());
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

/// RMS of the recovered curvature components over the frames and the inner elements, and the
/// lag of the bending wave (see the module documentation).
fn clip_series_metrics(s: &ClipSeries) -> Metrics {
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
    if let Some((lag, coherence)) = wave_lag(s, &|k| (k[0], k[1]), false) {
        m.insert_named("bending_wave_lag_frames", lag as f64);
        m.insert_named("bending_wave_coherence", coherence);
    }
    if let Some((_, coherence)) = wave_lag(s, &|k| (k[2], 0.0), true) {
        m.insert_named("twist_wave_coherence", coherence);
    }
    if let Some(j) = x_err_jitter(&s.x_err_rel) {
        m.insert_named("x_err_rel_jitter", j);
    }
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

/// The lag τ (frames) maximising `|Σ_t z_a(t) conj(z_b(t + τ))|` with `z` a complex signal of
/// κ (`κ1 + i κ2` for the bending, `κ3` for the twist) at the elements nearest s = L/4 (a)
/// and 3L/4 (b), |τ| ≤ a quarter of the clip: positive when the wave travels from s = 0
/// towards s = L. A roll of the material frame multiplies both bending signals by the same
/// phase and does not change the magnitude. With it, the coherence at that lag,
/// `|Σ z_a conj(z_b)| / √(Σ|z_a|² Σ|z_b|²)` over the overlap, in [0, 1]: 1 for a wave that
/// keeps its shape between the probes, near 0 when there is no such wave. `centred`: each
/// probe's mean over the frames is taken out first (the twist: a steady κ3 is no wave).
fn wave_lag(s: &ClipSeries, signal: &dyn Fn(&Vector3<f64>) -> (f64, f64), centred: bool) -> Option<(i64, f64)> {
    let nf = s.kappa.len();
    if nf < 8 {
        return None;
    }
    let ne = s.s_mid.len();
    let (a, b) = (ne / 4, 3 * ne / 4);
    let mean = |e: usize| {
        let sum = (0..nf).map(|f| signal(&s.kappa[f][e])).fold((0.0, 0.0), |m, v| (m.0 + v.0, m.1 + v.1));
        if centred {
            (sum.0 / nf as f64, sum.1 / nf as f64)
        } else {
            (0.0, 0.0)
        }
    };
    let (ma, mb) = (mean(a), mean(b));
    let z = |f: usize, e: usize| {
        let (v, m) = (signal(&s.kappa[f][e]), if e == a { ma } else { mb });
        (v.0 - m.0, v.1 - m.1)
    };
    let max_lag = (nf / 4) as i64;
    let mut best = (0i64, -1.0f64, 0.0f64);
    for tau in -max_lag..=max_lag {
        let (mut re, mut im, mut pa, mut pb) = (0.0, 0.0, 0.0, 0.0);
        for t in 0..nf as i64 {
            let u = t + tau;
            if u < 0 || u >= nf as i64 {
                continue;
            }
            let (x, y) = (z(t as usize, a), z(u as usize, b));
            // x · conj(y)
            re += x.0 * y.0 + x.1 * y.1;
            im += x.1 * y.0 - x.0 * y.1;
            pa += x.0 * x.0 + x.1 * x.1;
            pb += y.0 * y.0 + y.1 * y.1;
        }
        let cross = (re * re + im * im).sqrt();
        let mag = cross / (nf as i64 - tau.abs()) as f64;
        if mag > best.1 {
            let coherence = if pa > 0.0 && pb > 0.0 { cross / (pa * pb).sqrt() } else { 0.0 };
            best = (tau, mag, coherence);
        }
    }
    Some((best.0, best.2))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pulse of bending travels towards s = L at 0.01 body lengths per frame: the probes at
    /// L/4 and 3L/4 see it 50 frames apart; played backwards, −50.
    #[test]
    fn wave_lag_sign_and_size() {
        let (ne, nf) = (100, 400);
        let s_mid: Vec<f64> = (0..ne).map(|e| (e as f64 + 0.5) / ne as f64).collect();
        let kappa: Vec<Vec<Vector3<f64>>> = (0..nf)
            .map(|t| {
                s_mid
                    .iter()
                    .map(|s| {
                        let u = (s - 0.01 * t as f64 + 1.0) / 0.1;
                        Vector3::new((-u * u).exp(), 0.5 * (-u * u).exp(), 3.0)
                    })
                    .collect()
            })
            .collect();
        let series = ClipSeries { frames: (0..nf).collect(), s_mid, kappa, ..Default::default() };
        assert_eq!(wave_lag(&series, &|k| (k[0], k[1]), false).map(|w| w.0), Some(50));
        let back = ClipSeries { kappa: series.kappa.iter().rev().cloned().collect(), ..series.clone() };
        assert_eq!(wave_lag(&back, &|k| (k[0], k[1]), false).map(|w| w.0), Some(-50));
    }
}
