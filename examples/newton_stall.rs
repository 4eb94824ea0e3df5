//! The evidence of `docs/inverse.md` I13 (Newton's Λκ stall): the fixed point of an inverse case
//! from the straight state to a relative change `FPTOL`, the certificate along the way, Newton
//! from there for `NEWTON_ITS` iterations with the certificate of every iterate, and with
//! `SVD=1` the smallest singular values of the equilibrated Jacobian at the fixed point's
//! iterate with the singular components that make up the Newton step (`SHAPE=1`: their angle
//! shapes).
//!
//! ```sh
//! cargo run --release --example newton_stall -- cases/inverse_bend_twist_newton.toml 1e-10 1e-6 60
//! SVD=1 cargo run --release --example newton_stall -- cases/inverse_bend_twist_newton.toml 1e-10 1e-6 1
//! ```
//! `LK3`: Λκ3 to set (negative: the case's), `FPTOL`: the fixed point's tolerance.
use cosserat::case::Case;
use cosserat::solve::inverse::kkt::dirichlet;

use cosserat::solve::inverse::{Frame, FrameProblem, FrameSolver, InverseMethod, Start};
use nalgebra::{DVector, Vector3};

fn big_of(case: &Case, u: &DVector<f64>, a: &DVector<f64>) -> DVector<f64> {
    case.mesh.kkt_dofs().kkt_join(u, a)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 5 {
        eprintln!("usage: newton_stall CASE.toml LK3 FPTOL NEWTON_ITS (see the top of examples/newton_stall.rs)");
        std::process::exit(2);
    }
    let case = Case::from_file(std::path::Path::new(&args[1])).expect("case");
    let lk3: f64 = args[2].parse().unwrap();
    let fptol: f64 = args[3].parse().unwrap();
    let nits: usize = args[4].parse().unwrap();
    let data = cosserat::engine::rust::forward_data(&case).expect("data");
    let p = case.problem();
    let mut params = case.inverse().unwrap().params;
    if lk3 >= 0.0 {
        params.weights.lambda_kappa[2] = lk3;
    }
    params.method = InverseMethod::FixedPoint;
    params.tolerance = fptol;
    params.max_iterations = 20000;
    let frame = Frame { index: 0, x_g: &data.x, previous: None, weight: None, fix_roll: false };
    let kd = case.mesh.kkt_dofs();
    let fixed = dirichlet(&kd, 0.0, &frame);
    let prev = vec![Vector3::zeros(); kd.nodes()];
    // the KKT certificate (C1) of a primal state and its adjoint
    let cert = |u: &DVector<f64>, a: &DVector<f64>| {
        let pt = kd.pattern();
        let mut v = vec![0.0; pt.nnz()];
        cosserat::solve::inverse::kkt::certificate(
            FrameProblem { problem: &p, params: &params, frame: &frame, alpha_prev: &prev },
            &big_of(&case, u, a),
            &pt,
            &mut v,
        )
    };
    let mut k = 0;
    let fp = FrameSolver::new(&p, params)
        .solve(&frame, &p.reference_state(), Start::Guess, |r, u, a| {
            k += 1;
            if k % 100 == 0 || k < 2 {
                let c = cert(u, a);
                eprintln!(
                    "fp {k}: change {:.3e} cert {:.3e} blocks {:?}",
                    r.rel_change,
                    c.value,
                    c.blocks.map(|b| (b * 1e3).log10().round() - 3.0)
                );
            }
        })
        .unwrap();
    let c = cert(&fp.u, &fp.adjoint);
    eprintln!(
        "fp end {} its stop {:?} change {:.3e} cert {:.3e} blocks {:?}",
        fp.history.len(),
        fp.stop,
        fp.history.last().unwrap().rel_change,
        c.value,
        c.blocks.map(|b| (b * 1e3).log10().round() - 3.0)
    );
    if std::env::var("SVD").is_ok() {
        let big = big_of(&case, &fp.u, &fp.adjoint);
        let pattern = kd.pattern();
        let mut values = vec![0.0; pattern.nnz()];
        let rows: Vec<usize> = fixed.iter().map(|f| f.0).collect();
        let r = cosserat::solve::inverse::newton::assemble_residual(
            FrameProblem { problem: &p, params: &params, frame: &frame, alpha_prev: &prev },
            &big,
            &fixed,
            Some((&pattern, &mut values, &rows)),
        );
        let (a, dr, dc) = cosserat::linalg::LinearSolver::new(&pattern).equilibrate(&values);
        let m = pattern.to_dense(&a);
        let svd = m.svd(true, true);
        let mut idx: Vec<usize> = (0..svd.singular_values.len()).collect();
        idx.sort_by(|&i, &j| svd.singular_values[i].partial_cmp(&svd.singular_values[j]).unwrap());
        let rs = DVector::from_fn(r.len(), |i, _| r[i] * dr[i]);
        eprintln!("|D_r R| {:.3e} sigma max {:.3e}", rs.norm(), svd.singular_values.max());
        let vt = svd.v_t.as_ref().unwrap();
        let uu = svd.u.as_ref().unwrap();
        // step decomposition: y = V S^-1 U^T D_r R; contribution of each singular component
        let mut contrib: Vec<(f64, f64, f64)> = idx
            .iter()
            .map(|&k| {
                let c = uu.column(k).dot(&rs) / svd.singular_values[k];
                (svd.singular_values[k], uu.column(k).dot(&rs), c)
            })
            .collect();
        let tot: f64 = contrib.iter().map(|c| c.2 * c.2).sum::<f64>().sqrt();
        eprintln!("scaled step norm {tot:.3e}");
        let mut acc = 0.0;
        for (i, c) in contrib.iter().enumerate() {
            acc += c.2 * c.2;
            if i < 40 && (c.2.abs() > 0.05 * tot || i < 12) {
                eprintln!("  #{i} sigma {:.2e} proj {:.2e} step {:.2e} cum {:.3}", c.0, c.1, c.2, (acc).sqrt() / tot);
            }
        }
        let mut order: Vec<usize> = (0..contrib.len()).collect();
        order.sort_by(|&a, &b| contrib[b].2.abs().partial_cmp(&contrib[a].2.abs()).unwrap());
        for &i in order.iter().take(8) {
            let c = contrib[i];
            eprintln!("  top #{i} sigma {:.2e} proj {:.2e} step {:.2e}", c.0, c.1, c.2);
        }
        // unscaled step from the top singular component
        let k = idx[order[0]];
        let v = vt.row(k).transpose();
        // the angle part of a singular vector, unscaled, at every 4th node
        let alpha_shape = |v: &DVector<f64>, digits: usize| -> String {
            let sh: Vec<String> = (0..kd.nodes())
                .step_by(4)
                .map(|nd| {
                    let c: Vec<String> =
                        (3..6).map(|c| format!("{:.*e}", digits, v[12 * nd + c] * dc[12 * nd + c])).collect();
                    format!("[{}]", c.join(" "))
                })
                .collect();
            sh.join(" ")
        };
        eprintln!("  top alpha shape (unscaled): {}", alpha_shape(&v, 1));
        let sh: Vec<String> = (0..kd.nodes()).step_by(4).map(|nd| format!("{:.1e}", dc[12 * nd + 3])).collect();
        eprintln!("  dc alpha: {}", sh.join(" "));
        contrib.clear();
        for &k in idx.iter().take(6) {
            let v = vt.row(k).transpose();
            let w: Vec<String> = (0..12)
                .map(|c| format!("{:.2}", (0..kd.nodes()).map(|nd| v[12 * nd + c].powi(2)).sum::<f64>().sqrt()))
                .collect();
            eprintln!("sigma {:.3e}: u·D_rR {:.3e} weights {:?}", svd.singular_values[k], uu.column(k).dot(&rs), w);
            if std::env::var("SHAPE").is_ok() {
                eprintln!("  alpha shape (unscaled): {}", alpha_shape(&v, 2));
            }
        }
    }
    let mut np = params;
    np.method = InverseMethod::Newton { warm_start_tolerance: 1e-3 };
    np.tolerance = 1e-14;
    np.max_iterations = nits;
    let mut k = 0;
    let nw = FrameSolver::new(&p, np)
        .solve(&frame, &fp.u, Start::Near, |r, u, a| {
            k += 1;
            let c = {
                let pt = kd.pattern();
                let mut v = vec![0.0; pt.nnz()];
                cosserat::solve::inverse::kkt::certificate(
                    FrameProblem { problem: &p, params: &np, frame: &frame, alpha_prev: &prev },
                    &big_of(&case, u, a),
                    &pt,
                    &mut v,
                )
            };
            if k < 30 || k % 50 == 0 {
                eprintln!(
                    "newton {k}: change {:.3e} merit {:.3e} cert {:.3e} blocks {:?}",
                    r.rel_change,
                    r.residual.unwrap_or(f64::NAN),
                    c.value,
                    c.blocks.map(|b| (b * 1e3).log10().round() - 3.0)
                );
            }
        })
        .unwrap();
    let du = &nw.u - &fp.u;
    let (dx, da) = case.mesh.dofs().split_norms_inf(&du);
    eprintln!("newton stop {:?}; |u_newton - u_fp| x {dx:.3e} alpha {da:.3e}", nw.stop);
}
