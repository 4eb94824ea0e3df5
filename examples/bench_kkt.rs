//! Micro-benchmark of one Newton iteration of the inverse problem at 128 nodes (the worm clip
//! `cases/worm_omega_turn_ld1.toml`, frame 1 after frame 0): KKT Jacobian assembly, the
//! equilibrated banded LU solve, and whole Newton iterations in a reused workspace.
//! Needs the worm data (scripts/fetch_worm_data.sh). Run with
//! `cargo run --release --example bench_kkt [reps]`.
use std::time::Instant;

use anyhow::{Context, Result};
use cosserat::assembly::{LinearSolver, Pattern};
use cosserat::case::Case;
use cosserat::run::{inverse_params, load_clip};
use cosserat::solve::inverse::{InverseParams, InverseWorkspace, BLOCK};
use cosserat::solve::inverse_newton::{assemble_newton, solve_frame_newton_observed_in, solve_frame_warm_in};
use cosserat::solve::sequence::data_frame_guess;
use cosserat::solve::{node_values, Problem};
use nalgebra::{DVector, Vector3};

/// CPU time of this thread [s] (Linux `schedstat`: immune to other processes on a shared
/// machine), or wall time elsewhere.
struct Clock(Instant);
impl Clock {
    fn cpu() -> Option<f64> {
        let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
        Some(text.split_whitespace().next()?.parse::<f64>().ok()? * 1e-9)
    }
    fn now() -> (Clock, Option<f64>) {
        (Clock(Instant::now()), Self::cpu())
    }
}
fn elapsed(start: &(Clock, Option<f64>)) -> f64 {
    match (start.1, Clock::cpu()) {
        (Some(a), Some(b)) => b - a,
        _ => start.0 .0.elapsed().as_secs_f64(),
    }
}

fn main() -> Result<()> {
    let reps: usize = std::env::args().nth(1).map(|s| s.parse()).transpose()?.unwrap_or(200);
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/worm_omega_turn_ld1.toml");
    let case = Case::from_file(std::path::Path::new(path)).context("case")?;
    let clip = load_clip(&case).context("clip (scripts/fetch_worm_data.sh)")?;
    let settings = case.inverse().context("inverse case")?;
    let problem = Problem::from_case(&case);
    let base = InverseParams { dt: clip.dt_s, ..inverse_params(settings) };
    let warm = 1e-3;
    let n = problem.mesh.nodes();
    let mut ws = InverseWorkspace::new(&problem)?;

    // Frame 0, then frame 1 up to the warm start: a realistic Newton start.
    let p0 = InverseParams { first_frame: true, frame: 0, ..base };
    let zero = vec![Vector3::zeros(); n];
    let f0 = solve_frame_warm_in(
        &mut ws,
        &problem,
        &p0,
        warm,
        &clip.frames[0],
        &zero,
        &data_frame_guess(&clip.frames[0]),
        |_, _, _| {},
    )?;
    let prev: Vec<Vector3<f64>> = (0..n).map(|i| node_values(&f0.u, i).1).collect();
    let p1 = InverseParams { first_frame: false, frame: 1, ..base };
    let x_g = &clip.frames[1];
    let start = cosserat::solve::inverse::solve_frame_observed_in(
        &mut ws,
        &problem,
        &InverseParams { tolerance: warm, ..p1 },
        x_g,
        &prev,
        &data_frame_guess(x_g),
        |_, _, _| {},
    )?;

    // The KKT vector at the start (state and adjoint of the last fixed-point solve).
    let mut big = DVector::zeros(BLOCK * n);
    for i in 0..n {
        for k in 0..6 {
            big[BLOCK * i + k] = start.u[6 * i + k];
            big[BLOCK * i + 6 + k] = start.adjoint[6 * i + k];
        }
    }
    let pattern = Pattern::with_block(&problem.mesh, BLOCK);
    let mut solver = LinearSolver::new(&pattern)?;
    let mut values = vec![0.0; pattern.nnz()];
    let t = Clock::now();
    let mut r = DVector::zeros(0);
    for _ in 0..reps {
        r = assemble_newton(&problem, &p1, &pattern, &mut values, &big, x_g, &prev);
    }
    let assemble = elapsed(&t) / reps as f64;
    let t = Clock::now();
    let mut delta = DVector::zeros(0);
    for _ in 0..reps {
        delta = solver.solve_equilibrated(&values, &r)?;
    }
    let solve = elapsed(&t) / reps as f64;
    let mut dense = pattern.to_dense(&values);
    let res = (&dense * &delta - &r).norm() / r.norm();
    dense.fill(0.0);

    // Whole Newton solves from the warm start (line search, records included).
    let t = Clock::now();
    let mut iterations = 0;
    let runs = (reps / 20).max(1);
    for _ in 0..runs {
        let sol = solve_frame_newton_observed_in(&mut ws, &problem, &p1, x_g, &prev, &start.u, |_, _, _| {})?;
        iterations += sol.history.len();
    }
    let newton = elapsed(&t) / iterations as f64;
    println!("(CPU time of the thread where /proc/thread-self/schedstat exists, else wall time)");
    println!("{} nodes, {} unknowns, {} stored entries", n, BLOCK * n, pattern.nnz());
    println!("Newton Jacobian + residual assembly: {:8.3} ms", assemble * 1e3);
    println!("equilibrated banded LU solve:       {:8.3} ms (relative residual {res:.1e})", solve * 1e3);
    println!(
        "whole Newton iteration:             {:8.3} ms ({} iterations per frame)",
        newton * 1e3,
        iterations / runs
    );
    Ok(())
}
