//! Conditioning probe: how far does a round-off-sized perturbation of the data move the inverse
//! result at the same iteration count? Justifies the `compare.adjoint_rel` of the inverse cases.
use cosserat::metrics::max_relative_difference;
use cosserat::run::{generate_data, run_rust_inverse};

fn main() {
    let path = std::env::args().nth(1).expect("case");
    let eps: f64 = std::env::args().nth(2).and_then(|a| a.parse().ok()).unwrap_or(1e-15);
    let mut case = cosserat::case::Case::from_file(std::path::Path::new(&path)).expect("case");
    let data = generate_data(&case).expect("data");
    // Stop both runs at the same iteration: a tolerance just above the unperturbed run's last change.
    let first = run_rust_inverse(&case, &data, |_, _| {}).expect("first");
    if let cosserat::case::Analysis::Inverse(s) = &mut case.analysis {
        s.tolerance = first.stats.last_change.expect("change") * 1.001;
    }
    let mut pert = data.clone();
    for (i, x) in pert.x.iter_mut().enumerate() {
        *x *= 1.0 + eps * ((i as f64 * 1.7).sin());
    }
    let a = run_rust_inverse(&case, &data, |_, _| {}).expect("a");
    let b = run_rust_inverse(&case, &pert, |_, _| {}).expect("b");
    let (ia, ib) = (a.inverse.unwrap(), b.inverse.unwrap());
    for k in [1usize, 10, 100, 300, 362] {
        if k < ia.history.len() && k < ib.history.len() {
            println!("iteration {}: change {:.6e} / {:.6e}", k + 1, ia.history[k].rel_change, ib.history[k].rel_change);
        }
    }
    println!(
        "eps {eps:e}: iterations {} / {}; x {:.3e} alpha {:.3e} xhat {:.3e} ahat {:.3e}",
        a.stats.iterations,
        b.stats.iterations,
        max_relative_difference(&a.nodes.displacement(), &b.nodes.displacement()),
        max_relative_difference(&a.nodes.alpha, &b.nodes.alpha),
        max_relative_difference(&ia.xhat, &ib.xhat),
        max_relative_difference(&ia.ahat, &ib.ahat)
    );
}
