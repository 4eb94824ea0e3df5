//! The regularisation findings (2)–(4) of §5.2 of Wang et al. (2023) for the first data set,
//! eq. (64), measured on the Rust fixed point: the sweeps of λl, λd and λf whose numbers
//! `docs/inverse.md` I10 quotes, each checked against what was measured (a panic says which
//! changed). The paper's claims themselves are judged by the quick audit (`cases/paper/
//! sec52_eq64.toml`, claims eq64-2, eq64-3, eq64-4; `tests/audit.rs`), so these sweeps are not
//! run twice by `cargo test`.
//!
//! Base parameters (the paper's first test): λg = 1e9, λf = 1, λl = 1e-10, λd = 1e-6,
//! Λκ = diag(0, 0, 1e-10), Λω = 0, w = 0.5, stop at relative change 3e-6 (reachable: the
//! iteration plateaus near 1.6e-6). Runs that do not reach it are capped at `CAP` iterations.
//!
//! ```sh
//! cargo run --release --example eq64_findings
//! ```
#[path = "../tests/common/mod.rs"]
mod common;

use std::sync::OnceLock;

use common::fixed_point::{paper, run, Data, Run};
use common::with_weights;
use cosserat::engine::metrics::curvature_error;
use cosserat::solve::inverse::InverseParams;
use rayon::prelude::*;

fn main() {
    lambda_l_sweep();
    lambda_d_sweep();
    lambda_f_sweep();
    eprintln!("the findings of docs/inverse.md I10 hold as measured");
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
