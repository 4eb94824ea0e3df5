//! Conditioning probe: how far does a round-off-sized perturbation of the data move the inverse
//! result at the same iteration count? Justifies the `compare.adjoint_rel` of the inverse cases.
//! `cargo run --release --example inv_sens -- cases/inverse_bend.toml [eps]`
use anyhow::{Context, Result};
use cosserat::case::{Analysis, Case};
use cosserat::engine::metrics::max_relative_difference;
use cosserat::engine::rust::{forward_data, run_inverse};
use cosserat::engine::{NodalState, RunError, RunResult};

/// The inverse run on `data`, or its last iterate when it stopped without meeting its rule (the
/// case's certificate tolerance may not be met: the iterates are compared all the same).
fn solve(case: &Case, data: &NodalState) -> Result<RunResult> {
    match run_inverse(case, data, |_, _| {}) {
        Ok(r) => Ok(r),
        Err(RunError::Incomplete { partial, .. }) => Ok(*partial),
        Err(e) => Err(e.into()),
    }
}

fn main() -> Result<()> {
    let path = std::env::args().nth(1).context("usage: inv_sens CASE [eps]")?;
    let eps: f64 = std::env::args().nth(2).map(|a| a.parse()).transpose()?.unwrap_or(1e-15);
    let mut case = Case::from_file(std::path::Path::new(&path))?;
    let data = forward_data(&case)?;
    // Stop both runs at the same iteration: a tolerance just above the unperturbed run's last change.
    let first = solve(&case, &data)?;
    if let Analysis::Inverse(s) = &mut case.analysis {
        s.params.tolerance = first.stats.last_change.context("change")? * 1.001;
    }
    let mut pert = data.clone();
    for (i, x) in pert.x.iter_mut().enumerate() {
        *x *= 1.0 + eps * ((i as f64 * 1.7).sin());
    }
    let (a, b) = (solve(&case, &data)?, solve(&case, &pert)?);
    let (ia, ib) = (a.inverse.context("inverse")?, b.inverse.context("inverse")?);
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
    Ok(())
}
