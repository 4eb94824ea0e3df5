//! Development driver: inverse of the eq. (64) data with the paper's §5.2 parameters.
use cosserat::case::Case;
use cosserat::solve::inverse::{solve_frame, InverseParams};
use cosserat::solve::statics::{self, Method, StaticParams};
use cosserat::solve::{node_values, Problem};
use nalgebra::Vector3;

fn main() {
    let case = Case::from_file(std::path::Path::new("cases/follower_bend_64.toml")).expect("case");
    let p = Problem::from_case(&case);
    let fwd = statics::solve(
        &p,
        &StaticParams { method: Method::Newton, tolerance: 1e-13, max_iterations: 40, continuation_steps: 5 },
        |_| {},
    )
    .expect("forward");
    let n = case.mesh.nodes();
    let xg: Vec<Vector3<f64>> = (0..n).map(|i| node_values(&fwd.u, i).0).collect();
    let prev = vec![Vector3::zeros(); n];
    let maxit: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(300);
    let params = InverseParams {
        lambda_g: 1e9,
        lambda_f: 1.0,
        lambda_l: 1e-10,
        lambda_d: 1e-6,
        lambda_kappa: Vector3::new(0.0, 0.0, 1e-10),
        lambda_omega: Vector3::zeros(),
        dt: 1.0,
        first_frame: true,
        alpha0: 0.0,
        frame: 0,
        stabilisation: 0.0,
        relaxation: 0.5,
        tolerance: std::env::args().nth(2).and_then(|a| a.parse().ok()).unwrap_or(1e-12),
        max_iterations: maxit,
    };
    let t0 = std::time::Instant::now();
    let r = solve_frame(&p, &params, &xg, &prev, &p.reference_state(), |rec| {
        if [1, 2, 5, 10, 50, 100, 200, 300, 600, 1000].contains(&rec.iteration) {
            eprintln!(
                "it {:4} change {:.3e} xerr {:.3e} misfit {:.3e}",
                rec.iteration, rec.rel_change, rec.x_err_rel, rec.tangent_misfit
            );
        }
    });
    eprintln!("{:?} in {:.3} s", r.as_ref().err().map(|e| e.to_string()), t0.elapsed().as_secs_f64());
    if let Ok(sol) = r {
        use cosserat::solve::inverse::curvature_error;
        eprintln!(
            "kappa err {:.3e}, without 5 end elements {:.3e}",
            curvature_error(&p, &sol.u, &fwd.u, 0),
            curvature_error(&p, &sol.u, &fwd.u, 5)
        );
    }
}
