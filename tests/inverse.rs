//! Inverse problem (Problem 2, eq. 61) in the Rust engine on forward data of eq. (64).
mod common;

use common::{case_from, case_text};
use cosserat::engine::metrics::curvature_error;
use cosserat::model::mesh::Field;
use cosserat::solve::inverse::{FrameProblem, InverseRecord, Start};

/// Paper §5.2, first test: λf = 1, λl = 1e-10, λd = 1e-6, Λκ = diag(0, 0, 1e-10), Λω = 0.
/// The printed fixed point converges sublinearly: an independent re-implementation
/// (PAPER-NOTES) measured a relative change of 3.6e-5 after 50 iterations and 5.8e-6 after
/// 200; ours must follow the same history. Stopping at 3e-6 (reachable, above the ~1.6e-6
/// plateau; docs/certificate.md C4: 5 iterations within it), the position and the curvature
/// away from the ends are recovered, but the iterate is not a solution: its certificate is
/// stalled a thousand times above the tolerance.
#[test]
fn recovers_eq64_frames_from_the_centreline() {
    let case = case_from(&case_text("follower_bend_64"), "f64");
    let p = case.problem();
    let (fwd_u, xg) = common::forward_data(&case, 5);
    let n = case.mesh.nodes();
    let params = common::paper_params_64();
    let mut hist: Vec<InverseRecord> = Vec::new();
    let sol = common::solve_frame_any(&p, &params, &xg, None, &p.reference_state(), Start::Guess, |r| hist.push(*r))
        .expect("inverse");
    eprintln!("eq. 64 fixed point at 3e-6: {:?}, certificate {:.2e}", sol.stop, sol.certificate.value);
    assert_eq!(sol.stop, cosserat::solve::Stop::Stalled);
    assert!(sol.certificate.value > 1e3 * sol.certificate_tolerance);
    let at = |k: usize| hist[k - 1].rel_change;
    let last = sol.history.last().expect("history");
    let (k_all, k_inner) =
        (curvature_error(&case.mesh, &sol.u, &fwd_u, 0), curvature_error(&case.mesh, &sol.u, &fwd_u, 5));
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
    let dofs = p.dofs();
    let off_plane =
        (0..n).map(|i| dofs.get(&sol.u, i, Field::Alpha)).map(|a| a[0].abs().max(a[2].abs())).fold(0.0, f64::max);
    assert!(off_plane < 1e-10, "{off_plane}");
}

/// Consistency of the discrete adjoint on a frozen iterate (coefficients at `u_k`).
/// Reduced objective `j(c, ξ) = ½ uᵀHu − hᵀu + ½ Σ λ cᵀ M c`, with `u` solving the primal rows
/// `L u = b + M c` for given controls `c` (nodal f, l on the interior) and boundary angles `ξ`
/// (the square reading I5 leaves the end angles to the optimality system). The gradient from
/// the *assembled* adjoint block must equal central finite differences, and the solution of the
/// full KKT system must be a stationary point of `j`.
#[test]
fn adjoint_gradient_matches_finite_differences() {
    use cosserat::solve::inverse::kkt::{assemble_system, dirichlet};
    use cosserat::solve::inverse::Frame;
    use nalgebra::{DMatrix, DVector, Vector3};

    let text = common::edit(&case_text("follower_bend_64"), "elements = 100", "elements = 10");
    let case = case_from(&text, "f64_10");
    let p = case.problem();
    let (fwd_u, xg) = common::forward_data(&case, 5);
    let nodes = case.mesh.nodes();
    let (fwd, kd) = (case.mesh.dofs(), case.mesh.kkt_dofs());
    let prev: Vec<Vector3<f64>> = fwd.field(&fwd_u, Field::Alpha).iter().map(|a| a * 0.9).collect();
    // A frozen iterate near, not at, the data; every term of (41) switched on.
    let uk = DVector::from_fn(fwd.len(), |i, _| {
        fwd_u[i] + if fwd.field_of(i) == Field::Alpha { 0.05 * ((i as f64) * 0.7).sin() } else { 0.0 }
    });
    let params = common::all_terms_params();
    let pattern = kd.pattern();
    let mut values = vec![0.0; pattern.nnz()];
    // a frame after the first: the Λω term against `prev` is on
    let frame = Frame { index: 1, x_g: &xg, previous: Some(&prev), weight: None, fix_roll: false };
    let fp = FrameProblem { problem: &p, params: &params, frame: &frame, alpha_prev: &prev };
    let rhs = assemble_system(fp, &pattern, &mut values, &uk);
    let k = pattern.to_dense(&values);
    // Index sets (KKT layout).
    let set = |nodes: &[usize], fields: &[Field]| -> Vec<usize> {
        nodes.iter().flat_map(|&n| fields.iter().flat_map(move |&f| (0..3).map(move |c| kd.index(n, f, c)))).collect()
    };
    let (all, ends, interior): (Vec<usize>, Vec<usize>, Vec<usize>) =
        ((0..nodes).collect(), vec![0, nodes - 1], (1..nodes - 1).collect());
    let state = set(&all, &[Field::X, Field::Alpha]);
    let x_fixed = set(&ends, &[Field::X]);
    let xi = set(&ends, &[Field::Alpha]);
    let inner = set(&interior, &[Field::X, Field::Alpha]);
    let hats = set(&interior, &[Field::XHat, Field::AlphaHat]);
    let sub = |rows: &[usize], cols: &[usize]| DMatrix::from_fn(rows.len(), cols.len(), |i, j| k[(rows[i], cols[j])]);
    let subv = |rows: &[usize]| DVector::from_fn(rows.len(), |i, _| rhs[rows[i]]);
    let pos = |set: &[usize], d: usize| set.iter().position(|&s| s == d).expect("index");
    let h_mat = sub(&state, &state);
    let h_vec = subv(&state);
    let b = subv(&hats);
    let w8 = params.weights;
    let lam = |d: usize| if kd.field_of(d) == Field::XHat { w8.lambda_f } else { w8.lambda_l };
    // Control mass M = λ C with C = −(hat–hat block).
    let mass = DMatrix::from_fn(hats.len(), hats.len(), |i, j| -k[(hats[i], hats[j])] * lam(hats[i]));
    let cost = DMatrix::from_fn(hats.len(), hats.len(), |i, j| mass[(i, j)] * lam(hats[i]));
    let (l_in, l_xi, l_fix) = (sub(&hats, &inner), sub(&hats, &xi), sub(&hats, &x_fixed));
    let u_fix = DVector::from_fn(x_fixed.len(), |i, _| xg[if i < 3 { 0 } else { nodes - 1 }][i % 3]);
    let lu = l_in.clone().lu();
    let state_of = |c: &DVector<f64>, x: &DVector<f64>| -> DVector<f64> {
        let u_in = lu.solve(&(&b + &mass * c - &l_fix * &u_fix - &l_xi * x)).expect("primal");
        let mut u = DVector::zeros(state.len());
        for (i, &d) in inner.iter().enumerate() {
            u[pos(&state, d)] = u_in[i];
        }
        for (i, &d) in xi.iter().enumerate() {
            u[pos(&state, d)] = x[i];
        }
        for (i, &d) in x_fixed.iter().enumerate() {
            u[pos(&state, d)] = u_fix[i];
        }
        u
    };
    let j = |c: &DVector<f64>, x: &DVector<f64>| -> f64 {
        let u = state_of(c, x);
        0.5 * u.dot(&(&h_mat * &u)) - h_vec.dot(&u) + 0.5 * c.dot(&(&cost * c))
    };
    // Adjoint-based gradient with the assembled adjoint block K[inner, hats].
    let adj_block = sub(&inner, &hats);
    let grad = |c: &DVector<f64>, x: &DVector<f64>| -> (DVector<f64>, DVector<f64>) {
        let u = state_of(c, x);
        let g_u = &h_mat * &u - &h_vec;
        let g_in = DVector::from_fn(inner.len(), |i, _| g_u[pos(&state, inner[i])]);
        let g_xi = DVector::from_fn(xi.len(), |i, _| g_u[pos(&state, xi[i])]);
        // KKT adjoint rows: H u − h + K[state, hats] û = 0, so p = −û solves adj_block p = g_in.
        let p_adj = adj_block.clone().lu().solve(&g_in).expect("adjoint");
        (&cost * c + mass.transpose() * &p_adj, g_xi - sub(&xi, &hats) * &p_adj)
    };
    let c0 = DVector::from_fn(hats.len(), |i, _| 1e-3 * ((i as f64) * 1.3).cos() / lam(hats[i]).sqrt());
    let x0 = DVector::from_fn(xi.len(), |i, _| 0.1 * (i as f64 + 1.0).sin());
    let (gc, gx) = grad(&c0, &x0);
    let mut worst: f64 = 0.0;
    for trial in 0..6 {
        let dc = DVector::from_fn(c0.len(), |i, _| ((i * 7 + trial * 13) as f64).sin() * c0.amax());
        let dx = DVector::from_fn(x0.len(), |i, _| ((i * 5 + trial * 3) as f64).cos() * 1e-2);
        let eps = 1e-4;
        let fd = (j(&(&c0 + &dc * eps), &(&x0 + &dx * eps)) - j(&(&c0 - &dc * eps), &(&x0 - &dx * eps))) / (2.0 * eps);
        let an = gc.dot(&dc) + gx.dot(&dx);
        worst = worst.max((fd - an).abs() / an.abs().max(1e-300));
    }
    eprintln!("adjoint gradient vs central FD: worst relative difference {worst:.2e}");
    assert!(worst < 1e-6, "{worst}");
    // The KKT solution is a stationary point of the reduced objective.
    let mut kb = k.clone();
    let mut rb = rhs.clone();
    for (d, v) in dirichlet(
        &kd,
        params.alpha0_rad,
        &Frame { index: 1, x_g: &xg, previous: Some(&prev), weight: None, fix_roll: false },
    ) {
        kb.row_mut(d).fill(0.0);
        kb[(d, d)] = 1.0;
        rb[d] = v;
    }
    let sol = kb.lu().solve(&rb).expect("kkt");
    let c_star = DVector::from_fn(hats.len(), |i, _| sol[hats[i]] / lam(hats[i]));
    let x_star = DVector::from_fn(xi.len(), |i, _| sol[xi[i]]);
    let (gc, gx) = grad(&c_star, &x_star);
    let (gc0, _) = grad(&c0, &x0);
    let stationarity = gc.amax().max(gx.amax()) / gc0.amax();
    eprintln!("gradient at the KKT solution / gradient at a random control: {stationarity:.2e}");
    assert!(stationarity < 1e-6, "{stationarity}");
}

/// Paper §5.2, second test (Figs. 12–15), through the case file `inverse_bend_twist`: data of
/// eq. (65) (bend and twist, Newton with 10 load steps), λf = 1e-2, λl = 1e-6, λd = 1e-6,
/// Λκ = 1e-20, the λd blend of I13 (ε = 0.034). Measured at the fixed point's stop (108
/// iterations, stalled: certificate 5.0e-7): ‖x − x_g‖/‖x_g‖ = 9.9e-6, κ error 0.108 over
/// all elements and 0.0071 without 5 at each end (PAPER-NOTES' re-implementation: 3.5e-6,
/// 0.066 / 0.005). Asserted with a margin of about 1.5×.
#[test]
fn recovers_eq65_bend_and_twist_from_the_case_file() {
    use cosserat::engine::metrics::{inverse_metrics, Metric};
    let case = case_from(&case_text("inverse_bend_twist"), "inverse_bend_twist");
    let (r, stop) = common::run_any(&case);
    assert!(matches!(stop, Some(cosserat::solve::SolveError::Stalled(_))), "{stop:?}");
    let m = inverse_metrics(&r);
    eprintln!("eq. 65 inverse: {m:?}");
    assert!(m[Metric::XErrRel] < 1.5e-5, "{m:?}");
    assert!(m[Metric::KappaErrRel] < 0.2 && m[Metric::KappaErrRelInner] < 0.011, "{m:?}");
    // 3.7e-5: the λd blend of I13 (ε = 0.034 against 1e-3 before) weighs the within-element
    // variation of ∂s x − d3 more, and the misfit is measured by that blended rule
    assert!(m[Metric::TangentMisfit] < 5e-5, "{m:?}");
    // Each curvature component separately, away from the ends: the twist is recovered as well
    // as the bend. Measured max errors (fraction of max |κ_f|): see the printed line.
    let inv = r.inverse.as_ref().expect("inverse output");
    let (k, kf) = (r.nodes.element_curvature(), inv.data.element_curvature());
    for c in 0..3 {
        let a: Vec<_> = k[5..95].iter().map(|p| p.1[c]).collect();
        let b: Vec<_> = kf[5..95].iter().map(|p| p.1[c]).collect();
        let scale = kf.iter().fold(0.0_f64, |m, p| m.max(p.1.amax()));
        let err = a.iter().zip(&b).fold(0.0_f64, |m, (x, y)| m.max((x - y).abs())) / scale;
        eprintln!("component {}: max error {err:.3e} of the curvature scale", c + 1);
        assert!(err < 0.05, "component {c}: max error {err:.3e} of the curvature scale");
    }
}
