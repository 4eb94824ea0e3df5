//! The regularisation findings (2)–(4) of §5.2 of Wang et al. (2023) for the first data set,
//! eq. (64), and the rigid-motion equivariance of the scheme (`docs/inverse.md`), measured on
//! the Rust fixed point. Where our numbers differ from the paper's text, the test asserts what
//! we measured and its doc comment says so.
//!
//! Base parameters (the paper's first test): λg = 1e9, λf = 1, λl = 1e-10, λd = 1e-6,
//! Λκ = diag(0, 0, 1e-10), Λω = 0, w = 0.5, stop at relative change 3e-6 (reachable: the
//! iteration plateaus near 1.6e-6). Runs that do not reach it are capped at `CAP` iterations.
mod common;

use std::sync::OnceLock;

use common::{case_from, case_text, edit, with_weights};
use cosserat::case::Case;
use cosserat::model::mesh::{DofMap, Field};
use cosserat::model::rotation::{angles_from_rotation, rotation};
use cosserat::run::metrics::curvature_error;
use cosserat::run::NodalState;
use cosserat::solve::inverse::{InverseParams, InverseRecord, Start};
use cosserat::solve::Problem;
use nalgebra::{DVector, Matrix3, Rotation3, Unit, Vector3};
use rayon::prelude::*;

/// Iteration cap of the sweeps: the base run stops after 361 iterations.
const CAP: usize = 600;

/// Forward data of eq. (64): the Newton solution (truth) and its nodal positions x_g.
struct Data {
    case: Case,
    truth: DVector<f64>,
    xg: Vec<Vector3<f64>>,
}

impl Data {
    fn new(elements: usize) -> Self {
        let text = case_text("follower_bend_64");
        let text =
            if elements == 100 { text } else { edit(&text, "elements = 100", &format!("elements = {elements}")) };
        let case = case_from(&text, "f64");
        let (truth, xg) = common::forward_data(&case, 5);
        Data { case, truth, xg }
    }
    fn problem(&self) -> Problem<'_> {
        self.case.problem()
    }
}

fn paper() -> InverseParams {
    InverseParams { max_iterations: CAP, ..common::paper_params_64() }
}

/// One run of the fixed point with the state after every iteration.
struct Run {
    history: Vec<InverseRecord>,
    /// `(‖κ − κ_f‖/‖κ_f‖` all elements, without 5 end elements) per iteration (if tracked)
    kappa: Vec<(f64, f64)>,
    converged: bool,
    u: DVector<f64>,
}

impl Run {
    fn last(&self) -> &InverseRecord {
        self.history.last().expect("at least one iteration")
    }
    fn iterations(&self) -> usize {
        self.history.len()
    }
    /// ‖l‖ [L² norm] from λl/2 ∫|l|² (l = α̂/λl of the last solve).
    fn torque_norm(&self, lambda_l: f64) -> f64 {
        (2.0 * self.last().objective.torque / lambda_l).sqrt()
    }
}

/// The fixed point one iteration per `solve_frame` call (max_iterations 1, tolerance ∞). An
/// iteration depends on the state `(x, α)` only (the adjoint is solved afresh), so this is the
/// same sequence as one call, with the state available after every iteration. Stops at
/// `params.tolerance`, after `params.max_iterations` or at the first solver error.
fn run(d: &Data, params: &InverseParams, xg: &[Vector3<f64>], u0: &DVector<f64>, track_kappa: bool) -> Run {
    let p = d.problem();
    let one = InverseParams { max_iterations: 1, tolerance: f64::INFINITY, ..*params };
    let mut u = u0.clone();
    let (mut history, mut kappa, mut converged) = (Vec::new(), Vec::new(), false);
    for k in 1..=params.max_iterations {
        let Ok(sol) = common::solve_frame_any(&p, &one, xg, None, &u, Start::Guess, |_| {}) else { break };
        u = sol.u;
        let rec = InverseRecord { iteration: k, ..sol.history[0] };
        history.push(rec);
        if track_kappa {
            kappa.push((curvature_error(&p.mesh, &u, &d.truth, 0), curvature_error(&p.mesh, &u, &d.truth, 5)));
        }
        if rec.rel_change <= params.tolerance {
            converged = true;
            break;
        }
    }
    Run { history, kappa, converged, u }
}

/// Eq. (64) data on 100 elements and the run with the base parameters (shared by the sweeps).
fn base() -> &'static (Data, Run) {
    static BASE: OnceLock<(Data, Run)> = OnceLock::new();
    BASE.get_or_init(|| {
        let d = Data::new(100);
        let r = run(&d, &paper(), &d.xg, &d.problem().reference_state(), true);
        (d, r)
    })
}

/// Run `params` for each value in parallel; the base value reuses the shared run.
fn sweep(
    values: &[f64],
    set: impl Fn(f64) -> InverseParams + Sync,
    base_value: f64,
    track_kappa: bool,
) -> Vec<(f64, Option<Run>)> {
    let (d, _) = base();
    let u0 = d.problem().reference_state();
    values.par_iter().map(|&v| (v, (v != base_value).then(|| run(d, &set(v), &d.xg, &u0, track_kappa)))).collect()
}

fn line(name: &str, v: f64, r: &Run, lambda_l: f64) {
    let (d, _) = base();
    let p = d.problem();
    let (last, o) = (r.last(), r.last().objective);
    eprintln!(
        "{name} {v:e}: converged {} after {} its (change {:.2e}); |x-xg|/|xg| {:.3e}; kappa err {:.4} (inner {:.4}); |l| {:.3e}; J tracking {:.3e} force {:.3e} torque {:.3e} shear {:.3e} bending {:.3e} total {:.3e}",
        r.converged,
        r.iterations(),
        last.rel_change,
        last.x_err_rel,
        curvature_error(&p.mesh, &r.u, &d.truth, 0),
        curvature_error(&p.mesh, &r.u, &d.truth, 5),
        r.torque_norm(lambda_l),
        o.tracking,
        o.force,
        o.torque,
        o.shear,
        o.bending,
        o.total()
    );
}

/// Largest relative difference between two histories over their common iterations.
fn spread(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs() / y.abs()).fold(0.0, f64::max)
}

/// Finding (2): "vary λl from 1e-20 to 1e3 … these convergence curves are exactly the same …
/// l = α̂/λl always has a magnitude of 1e-7".
///
/// **Reproduced for λl ∈ [1e-20, 1e-3]; not at 1 or 1e3** (Λκ3 = 1e-10 here, the paper's Fig. 9
/// used 1e-20). Measured (100 elements, stop 3e-6, cap 600; κ error: all elements (without 5
/// end elements)):
///
/// | λl    | its  | ‖x−x_g‖/‖x_g‖ | κ error         | ‖l‖ [L²]   |
/// |-------|------|---------------|-----------------|------------|
/// | 1e-20 | 361  | 8.20e-5       | 0.086 (0.018)   | 2.28e-8    |
/// | 1e-12 | 361  | 8.20e-5       | 0.086 (0.018)   | 2.28e-8    |
/// | 1e-10 | 361  | 8.20e-5       | 0.086 (0.018)   | 2.28e-8    |
/// | 1e-6  | 361  | 8.20e-5       | 0.086 (0.018)   | 2.28e-8    |
/// | 1e-3  | 373  | 8.07e-5       | 0.080 (0.018)   | 2.12e-8    |
/// | 1     | 551  | 7.17e-5       | 0.027 (0.009)   | 7.5e-9     |
/// | 1e3   | 600✗ | 1.81e-2       | 6.6 (6.1)       | 1.28e-7    |
///
/// Max relative spread of the histories against λl = 1e-10 (common iterations): 1e-20 and
/// 1e-12: x 1.1e-10, κ 3.0e-8; 1e-6: x 1.0e-6, κ 3.0e-4; 1e-3: x 1.6e-3, κ 0.63 (transient;
/// 6.3e-2 from iteration 100). So "exactly the same curves" and ‖l‖ ≈ 2.3e-8 constant (the
/// paper: ~1e-7) hold for 1e-20 … 1e-6. λl = 1 converges more slowly to a *better* κ; at 1e3
/// the torque is too costly and x is not fitted. (With the one-point λd rule and the 2-point Λκ
/// rule, 1e-20 did not converge: change O(1), κ error 278; docs/audit.md.)
#[test]
fn lambda_l_sweep() {
    let (_, b) = base();
    let set = |l: f64| with_weights(&paper(), |w| w.lambda_l = l);
    let runs = sweep(&[1e-20, 1e-12, 1e-10, 1e-6, 1e-3, 1.0, 1e3], set, 1e-10, true);
    let get = |l: f64| runs.iter().find(|(v, _)| *v == l).map(|(_, r)| r.as_ref().unwrap_or(b)).expect("value");
    let xh = |r: &Run| r.history.iter().map(|h| h.x_err_rel).collect::<Vec<_>>();
    let kh = |r: &Run, inner: bool| r.kappa.iter().map(|k| if inner { k.1 } else { k.0 }).collect::<Vec<_>>();
    for (l, _) in &runs {
        line("lambda_l", *l, get(*l), *l);
    }
    // 1e-12 and 1e-6: the same curves as 1e-10, and the same ‖l‖.
    for l in [1e-20, 1e-12, 1e-6, 1e-3] {
        let r = get(l);
        let (sx, sk, ski) =
            (spread(&xh(r), &xh(b)), spread(&kh(r, false), &kh(b, false)), spread(&kh(r, true), &kh(b, true)));
        let late = spread(&kh(r, false)[100..], &kh(b, false)[100..]);
        let ln = r.torque_norm(l) / b.torque_norm(1e-10);
        eprintln!("  lambda_l {l:e} vs 1e-10: spread x {sx:.2e}, kappa {sk:.2e} (from iteration 100: {late:.2e}), inner kappa {ski:.2e}; |l| ratio {ln:.3}");
        // 361–373 iterations
        assert!(r.converged && r.iterations() <= 400, "{l}: {}", r.iterations());
        assert!((ln - 1.0).abs() < 0.1, "{l}: {ln}");
        if l < 1e-3 {
            // measured: x ≤ 1.0e-6, κ ≤ 3.0e-4, inner κ ≤ 6.3e-4
            assert!(sx < 1e-5 && sk < 3e-3 && ski < 6e-3, "{l}: {sx} {sk} {ski}");
        } else {
            // 1e-3: x still the same curve; κ differs in the transient, agrees later.
            assert!(sx < 5e-3 && sk > 0.3 && late < 0.1, "{l}: {sx} {sk} {late}");
        }
    }
    assert!(b.converged && (b.torque_norm(1e-10) - 2.28e-8).abs() < 0.1e-8, "{}", b.torque_norm(1e-10));
    // 1: converges, later, to a smaller curvature error.
    let r = get(1.0);
    assert!(r.converged && (500..=600).contains(&r.iterations()), "{}", r.iterations());
    assert!(r.kappa.last().unwrap().0 < 0.5 * b.kappa.last().unwrap().0);
    assert!(r.torque_norm(1.0) < 0.5 * b.torque_norm(1e-10));
    // 1e3: no convergence, x not fitted.
    let r = get(1e3);
    assert!(!r.converged && r.last().x_err_rel > 1e-2, "{}", r.last().x_err_rel);
}

/// Finding (3): "converge stably with λd varying from 1e1 to 1e-10".
///
/// **Reproduced** with the stabilised λd rule (ε = 1e-3, I11) and the midpoint rule for the Λκ
/// term (I12). Measured (stop 3e-6; κ error all elements (without 5 end elements)):
///
/// | λd    | its | ‖x−x_g‖/‖x_g‖ | κ error       | J tracking / shear / total   |
/// |-------|-----|---------------|---------------|------------------------------|
/// | 1e1   | 375 | 1.42e-4       | 0.086 (0.019) | 1.6e-9 / 4.0e-9 / 6.0e-9     |
/// | 1e-2  | 361 | 8.20e-5       | 0.086 (0.018) | 5.4e-10 / 5.6e-12 / 1.1e-9   |
/// | 1e-6  | 361 | 8.20e-5       | 0.086 (0.018) | 5.4e-10 / 5.6e-16 / 1.1e-9   |
/// | 1e-10 | 361 | 8.20e-5       | 0.086 (0.018) | 5.4e-10 / 5.6e-20 / 1.1e-9   |
///
/// With the one-point λd rule (ε = 0, the selective element's stretch–shear rule) 1e-2 needed
/// 2827 iterations and 1e1 did not converge (change 0.05–0.6, κ error 369): the one-point rule
/// cannot see the nodal zig-zag of the angles (docs/audit.md).
#[test]
fn lambda_d_sweep() {
    let (d, b) = base();
    let p = d.problem();
    let set = |l: f64| with_weights(&paper(), |w| w.lambda_d = l);
    let runs = sweep(&[1e1, 1e-2, 1e-6, 1e-10], set, 1e-6, false);
    let get = |l: f64| runs.iter().find(|(v, _)| *v == l).map(|(_, r)| r.as_ref().unwrap_or(b)).expect("value");
    for (l, _) in &runs {
        line("lambda_d", *l, get(*l), 1e-10);
    }
    let kappa = |r: &Run| curvature_error(&p.mesh, &r.u, &d.truth, 0);
    for l in [1e-2, 1e-10] {
        let r = get(l);
        assert!(r.converged && r.iterations().abs_diff(b.iterations()) <= 3, "{l}: {}", r.iterations());
        assert!(
            (kappa(r) / kappa(b) - 1.0).abs() < 0.01 && (r.last().x_err_rel / b.last().x_err_rel - 1.0).abs() < 0.01
        );
    }
    // 1e1: converges a few iterations later; x is fitted less tightly (the λd term pulls ∂s x
    // towards d3), κ as well as at 1e-6.
    let r = get(1e1);
    assert!(r.converged && r.iterations() <= b.iterations() + 30, "{}", r.iterations());
    assert!(r.last().x_err_rel < 2e-4 && r.last().x_err_rel > 1.5 * b.last().x_err_rel, "{}", r.last().x_err_rel);
    assert!((kappa(r) / kappa(b) - 1.0).abs() < 0.05, "{}", kappa(r));
}

/// Finding (4): "converges for λf from 1e-10 to 1e6 … λf must be sufficiently small for the
/// objectives to be sufficiently reduced" (Fig. 11).
///
/// **The objective part is reproduced; convergence at 1e6 is not** (to our stopping rule).
/// Measured (stop 3e-6; tracking term at iteration 1 ≈ 5.8e-2 (5.2e-2 for 1e6)):
///
/// | λf    | its  | ‖x−x_g‖/‖x_g‖ | κ error         | ‖l‖    | J tracking | J total | tracking/total |
/// |-------|------|---------------|-----------------|--------|------------|---------|----------------|
/// | 1e-10 | 23   | 2.03e-7       | 0.0026 (0.0025) | 7.5e-9 | 3.3e-15    | 3.9e-15 | 0.85           |
/// | 1e-4  | 45   | 2.98e-7       | 0.011 (0.0029)  | 1.3e-8 | 7.1e-15    | 8.7e-14 | 0.08           |
/// | 1     | 363  | 8.17e-5       | 0.086 (0.018)   | 2.3e-8 | 5.4e-10    | 1.1e-9  | 0.49           |
/// | 1e6   | 600✗ | 0.117         | 0.44 (0.40)     | 1.1e-8 | 1.1e-3     | 1.1e-3  | 1.00           |
///
/// At 1e6 the relative change stalls at 1.4–1.7e-5 from iteration ~200 on (still at 1500 in a
/// side run, x 0.10, tracking 8.6e-4). Small λf is also much *faster* and recovers κ best.
#[test]
fn lambda_f_sweep() {
    let (d, b) = base();
    let p = d.problem();
    let set = |l: f64| with_weights(&paper(), |w| w.lambda_f = l);
    let runs = sweep(&[1e-10, 1e-4, 1.0, 1e6], set, 1.0, false);
    let get = |l: f64| runs.iter().find(|(v, _)| *v == l).map(|(_, r)| r.as_ref().unwrap_or(b)).expect("value");
    for (l, _) in &runs {
        line("lambda_f", *l, get(*l), 1e-10);
        let r = get(*l);
        eprintln!(
            "  tracking reduction {:.2e}, tracking/total {:.3}",
            r.last().objective.tracking / r.history[0].objective.tracking,
            r.last().objective.tracking / r.last().objective.total()
        );
    }
    let (r10, r4, r6) = (get(1e-10), get(1e-4), get(1e6));
    let track = |r: &Run| r.last().objective.tracking;
    assert!(
        r10.converged && r10.iterations() <= 30 && r4.converged && r4.iterations() <= 60,
        "{} {}",
        r10.iterations(),
        r4.iterations()
    );
    assert!(r10.last().x_err_rel < 5e-7 && r4.last().x_err_rel < 5e-7);
    assert!(
        curvature_error(&p.mesh, &r10.u, &d.truth, 0) < 0.01 && curvature_error(&p.mesh, &r4.u, &d.truth, 5) < 0.01
    );
    // Ordering of the final tracking term: 1e-10 < 1e-4 ≪ 1 ≪ 1e6.
    assert!(track(r10) < track(r4) && track(r4) < 1e-4 * track(b) && track(b) < 1e-5 * track(r6));
    assert!(track(r10) / r10.history[0].objective.tracking < 1e-12);
    assert!(track(r6) / r6.history[0].objective.tracking > 1e-2 && r6.last().x_err_rel > 0.05);
    assert!(!r6.converged && r6.last().rel_change > 1e-5, "{}", r6.last().rel_change);
}

/// Transform a state rigidly: `x → R x + c` and `Q → L Q Rᵀ` (directors are the rows of Q, so
/// a spatial rotation R acts on the right; L rotates the material frame about d3).
fn transform(u: &DVector<f64>, r: &Matrix3<f64>, l: &Matrix3<f64>, c: &Vector3<f64>) -> DVector<f64> {
    let mut v = u.clone();
    let dofs = DofMap::forward(u.len() / 6);
    for i in 0..dofs.nodes() {
        let (x, a) = (dofs.get(u, i, Field::X), dofs.get(u, i, Field::Alpha));
        dofs.set(&mut v, i, Field::X, &(r * x + c));
        dofs.set(&mut v, i, Field::Alpha, &angles_from_rotation(&(l * rotation(&a) * r.transpose())));
    }
    v
}

/// `(x, Q, κ, angles)` differences between `a` and the transform of `b`: max |x−(Rx_b+c)|/max|x_b|,
/// max |Q−L Q_b Rᵀ|, max |κ − L κ_b|/max |κ_b| (local curvature: Q′∂sQ′ᵀ = L Q∂sQᵀ Lᵀ), max |α−α_b|.
fn equivariance_error(
    p: &Problem,
    a: &DVector<f64>,
    b: &DVector<f64>,
    r: &Matrix3<f64>,
    l: &Matrix3<f64>,
    c: &Vector3<f64>,
) -> [f64; 4] {
    let mut e = [0.0f64; 4];
    let mut nx = 0.0f64;
    let dofs = p.dofs();
    for i in 0..dofs.nodes() {
        let (xa, aa) = (dofs.get(a, i, Field::X), dofs.get(a, i, Field::Alpha));
        let (xb, ab) = (dofs.get(b, i, Field::X), dofs.get(b, i, Field::Alpha));
        e[0] = e[0].max((xa - (r * xb + c)).norm());
        nx = nx.max(xb.norm());
        e[1] = e[1].max((rotation(&aa) - l * rotation(&ab) * r.transpose()).amax());
        e[3] = e[3].max((aa - ab).amax());
    }
    let kappa = |u: &DVector<f64>| -> Vec<Vector3<f64>> {
        NodalState::from_vector(&p.mesh, u).element_curvature().into_iter().map(|(_, k)| k).collect()
    };
    let (ka, kb) = (kappa(a), kappa(b));
    let nk = kb.iter().map(|k| k.norm()).fold(0.0, f64::max);
    e[2] = ka.iter().zip(&kb).map(|(x, y)| (x - l * y).norm()).fold(0.0, f64::max) / nk;
    e[0] /= nx;
    e
}

/// Rigid motions of the data (50 elements, 20 iterations from the transformed straight state).
///
/// With directors the rows of `Q = Rz(α) Rx(β) Ry(γ)` (`e = Q ∂s x − e3`), a spatial rotation R
/// maps `Q → Q Rᵀ`, and a constant rotation of the cross-section frame about d3 maps
/// `Q → Rz(θ) Q`. The chart turns exactly two of these into shifts of one angle:
/// `Rz(θ) Q(α, β, γ) = Q(α + θ, β, γ)` (frame relabelling; positions unchanged, with
/// α(0) = θ) and `Q(α, β, γ) Ry(φ)ᵀ = Q(α, β, γ − φ)` (spatial rotation about **e2**). With
/// translations these are exact symmetries of the discrete scheme (isotropic section,
/// Λκ1 = Λκ2). A spatial rotation about **e3** is *not* one: `Q Rz(θ)ᵀ` mixes all three angles,
/// although it is the obvious candidate.
///
/// Measured (x rel., max |Q′ − L Q Rᵀ|, κ rel., max angle change), after 1 | 20 iterations:
/// - translation c:           8.2e-16, 6.5e-13, 4.7e-11 | 6.5e-7, 6.6e-5, 1.2e-3
/// - relabelling Rz(0.7) + c: 7.7e-16, 7.2e-13, 4.3e-11 | 3.5e-7, 2.4e-5, 4.4e-4 (α + 0.7)
/// - spatial Ry(0.6) + c:     1.0e-15, 2.0e-13, 1.4e-11 | 4.2e-6, 1.8e-4, 3.4e-3 (γ − 0.6)
/// - spatial Rz(0.7) + c:     9.3e-16, 4.4e-2, 0.16     | 4.2e-4, 8.9e-3, 7.1e-2
/// - general R + c:           2.1e-15, 4.2e-2, 0.12     | 2.2e-2, 1.7, 1.0e3
///
/// (general R: axis (1, 2, 3), 0.5 rad; α0 from the chart of `Q(α_orig(0)) Rᵀ` — the product
/// `R Q` is the relabelling, not a spatial rotation, in this convention.) After one iteration
/// the symmetric cases agree to round-off; over 20 iterations the round-off differences grow
/// (the near-null β zig-zag of I8, now held by the stabilised λd rule at ε = 1e-3: with ε = 0
/// they were 3.5e-6 in Q after one iteration). The rotated non-symmetric runs are 20–1e4 times
/// further apart: this is not discretisation error — the Euler chart makes the scheme
/// orientation dependent.
#[test]
fn rigid_motions() {
    let d = Data::new(50);
    let p = d.problem();
    let u0 = p.reference_state();
    let i3 = Matrix3::identity();
    let c = Vector3::new(3e-4, -2e-4, 5e-4);
    let rz = *Rotation3::from_axis_angle(&Vector3::z_axis(), 0.7).matrix();
    let ry = *Rotation3::from_axis_angle(&Vector3::y_axis(), 0.6).matrix();
    let rg = *Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::new(1.0, 2.0, 3.0)), 0.5).matrix();
    let cases = [
        ("translation", i3, i3),
        ("relabel Rz(0.7)", i3, rz),
        ("spatial Ry(0.6)", ry, i3),
        ("spatial Rz(0.7)", rz, i3),
        ("general R", rg, i3),
    ];
    let errors = |iterations: usize| -> Vec<[f64; 4]> {
        let params = InverseParams { tolerance: 0.0, max_iterations: iterations, ..paper() };
        let orig = run(&d, &params, &d.xg, &u0, false);
        assert_eq!(orig.iterations(), iterations);
        let errs: Vec<[f64; 4]> = cases
            .par_iter()
            .map(|(_, r, l)| {
                let xg: Vec<Vector3<f64>> = d.xg.iter().map(|x| r * x + c).collect();
                let a0 = p.dofs().get(&orig.u, 0, Field::Alpha);
                let alpha0_rad = angles_from_rotation(&(l * rotation(&a0) * r.transpose()))[0];
                let s = run(&d, &InverseParams { alpha0_rad, ..params }, &xg, &transform(&u0, r, l, &c), false);
                assert_eq!(s.iterations(), iterations);
                equivariance_error(&p, &s.u, &orig.u, r, l, &c)
            })
            .collect();
        for ((name, _, _), e) in cases.iter().zip(&errs) {
            eprintln!(
                "after {iterations:2} iterations, {name}: x {:.2e}, Q {:.2e}, kappa {:.2e}, angles {:.2e}",
                e[0], e[1], e[2], e[3]
            );
        }
        errs
    };
    // One iteration from the straight state: x is linear in the data for all five; the
    // frames agree to round-off for the symmetries and to 4e-2 otherwise.
    let errs = errors(1);
    for e in &errs {
        assert!(e[0] < 1e-14, "{e:?}");
    }
    for e in &errs[..3] {
        assert!(e[1] < 1e-10 && e[2] < 1e-8, "{e:?}");
    }
    for e in &errs[3..] {
        assert!(e[1] > 1e-2 && e[2] > 0.05, "{e:?}");
    }
    let errs = errors(20);
    // Exact in exact arithmetic: the round-off differences have grown, x most for the rotations.
    // How far they grow depends on the round-off of the data themselves (the forward solve's):
    // rewriting the forward kernels' products as matrix-vector chains moved κ of Ry(0.6) from
    // 1.7e-3 to 3.4e-3 with the fixed point unchanged. The claim is the gap to the rotations
    // that are not symmetries (κ ≥ 7e-2, 20 times and more), so κ is bounded at 1e-2.
    for e in &errs[..3] {
        assert!(e[0] < 1e-5 && e[1] < 3e-4 && e[2] < 1e-2, "{e:?}");
    }
    // Not exact: 20 times the symmetric differences and more.
    for e in &errs[3..] {
        assert!(e[0] > 1e-4 && e[1] > 5e-3 && e[2] > 0.05, "{e:?}");
    }
}
