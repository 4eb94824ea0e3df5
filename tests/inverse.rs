//! Inverse problem (Problem 2, eq. 61) in the Rust engine on forward data of eq. (64).
mod common;

use common::{case_from, case_text};
use cosserat::solve::inverse::{curvature_error, solve_frame, InverseParams, InverseRecord};
use cosserat::solve::statics::{self, Method, StaticParams};
use cosserat::solve::{node_values, Problem};
use nalgebra::Vector3;

/// Paper §5.2, first test: λf = 1, λl = 1e-10, λd = 1e-6, Λκ = diag(0, 0, 1e-10), Λω = 0.
/// The printed fixed point converges sublinearly: an independent re-implementation
/// (PAPER-NOTES) measured a relative change of 3.6e-5 after 50 iterations and 5.8e-6 after
/// 200; ours must follow the same history. Stopping at 3e-6 (reachable, above the ~1.6e-6
/// plateau), the position and the curvature away from the ends are recovered.
#[test]
fn recovers_eq64_frames_from_the_centreline() {
    let case = case_from(&case_text("follower_bend_64"), "f64");
    let p = Problem::from_case(&case);
    let fwd = statics::solve(&p, &StaticParams { method: Method::Newton, tolerance: 1e-13, max_iterations: 40, continuation_steps: 5 }, |_| {}).expect("forward data");
    let n = case.mesh.nodes();
    let xg: Vec<Vector3<f64>> = (0..n).map(|i| node_values(&fwd.u, i).0).collect();
    let params = InverseParams {
        lambda_g: 1e9,
        lambda_f: 1.0,
        lambda_l: 1e-10,
        lambda_d: 1e-6,
        lambda_kappa: Vector3::new(0.0, 0.0, 1e-10),
        lambda_omega: Vector3::zeros(),
        dt: 1.0,
        first_frame: true,
        relaxation: 0.5,
        tolerance: 3e-6,
        max_iterations: 1000,
    };
    let mut hist: Vec<InverseRecord> = Vec::new();
    let sol = solve_frame(&p, &params, &xg, &vec![Vector3::zeros(); n], &p.reference_state(), |r| hist.push(*r)).expect("inverse");
    let at = |k: usize| hist[k - 1].rel_change;
    let last = sol.history.last().expect("history");
    let (k_all, k_inner) = (curvature_error(&p, &sol.u, &fwd.u, 0), curvature_error(&p, &sol.u, &fwd.u, 5));
    eprintln!(
        "eq. 64 inverse: change {:.2e} @50, {:.2e} @200; stopped after {} iterations; |x-xg|/|xg| {:.2e}; |x'-d3| {:.2e}; kappa error {k_all:.3} (without 5 end elements {k_inner:.3})",
        at(50),
        at(200),
        last.iteration,
        last.x_err_rel,
        last.tangent_misfit
    );
    assert!((at(50) / 3.6e-5 - 1.0).abs() < 0.05, "{}", at(50));
    assert!((at(200) / 5.8e-6 - 1.0).abs() < 0.05, "{}", at(200));
    assert!(last.x_err_rel < 2e-4);
    assert!(k_all < 0.12 && k_inner < 0.03, "{k_all} {k_inner}");
    // Planar data: the recovered frame stays planar (α = γ = 0 up to round-off).
    let off_plane = (0..n).map(|i| sol.u[6 * i + 3].abs().max(sol.u[6 * i + 5].abs())).fold(0.0, f64::max);
    assert!(off_plane < 1e-10, "{off_plane}");
}
