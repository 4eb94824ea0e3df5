//! Micro-benchmark of one Newton iteration of the inverse problem at 128 nodes (the worm clip
//! `cases/worm_omega_turn_ld1.toml`, frame 1 after frame 0): KKT Jacobian assembly, the
//! equilibrated banded LU solve, and whole Newton iterations in a reused workspace.
//! Needs the worm data (scripts/fetch_worm_data.sh). Run with
//! `cargo run --release --example bench_kkt [reps]`.
use std::time::Instant;

use anyhow::{Context, Result};
use cosserat::case::Case;
use cosserat::engine::input::clip_files::load_clip;
use cosserat::linalg::LinearSolver;
use cosserat::model::mesh::Field;
use cosserat::solve::inverse::kkt::dirichlet;
use cosserat::solve::inverse::newton::assemble_residual;
use cosserat::solve::inverse::{Frame, FrameProblem, FrameSolver, InverseMethod, InverseParams, Start};
use cosserat::solve::sequence::data_frame_guess;
use nalgebra::DVector;

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
    let (clip, _) = load_clip(&case).context("clip (scripts/fetch_worm_data.sh)")?;
    let problem = case.problem();
    let base = case.inverse().context("inverse case")?.params;
    let warm = 1e-3;
    let n = problem.mesh.nodes();
    let (fwd, kd) = (problem.dofs(), problem.mesh.kkt_dofs());

    // Frame 0, then frame 1 up to the warm start: a realistic Newton start.
    let mut solver0 = FrameSolver::new(&problem, base);
    let f0_frame = Frame { index: 0, x_g: &clip.frames[0], previous: None, weight: None, fix_roll: false };
    let f0 = solver0.solve(&f0_frame, &data_frame_guess(&clip.frames[0]), Start::Guess, |_, _, _| {})?.converged(0)?;
    let prev = fwd.field(&f0.u, Field::Alpha);
    let x_g = &clip.frames[1];
    let frame = Frame { index: 1, x_g, previous: Some(&prev), weight: None, fix_roll: false };
    let warm_params = InverseParams { method: InverseMethod::FixedPoint, tolerance: warm, ..base };
    let start =
        FrameSolver::new(&problem, warm_params).solve(&frame, &data_frame_guess(x_g), Start::Guess, |_, _, _| {})?;

    // The KKT vector at the start (state and adjoint of the last fixed-point solve).
    let mut big = kd.zeros();
    for i in 0..n {
        for (field, hat) in [(Field::X, Field::XHat), (Field::Alpha, Field::AlphaHat)] {
            kd.set(&mut big, i, field, &fwd.get(&start.u, i, field));
            kd.set(&mut big, i, hat, &fwd.get(&start.adjoint, i, field));
        }
    }
    let fixed = dirichlet(&kd, base.alpha0_rad, &frame);
    let rows: Vec<usize> = fixed.iter().map(|f| f.0).collect();
    let pattern = kd.pattern();
    let mut solver = LinearSolver::new(&pattern);
    let mut values = vec![0.0; pattern.nnz()];
    let t = Clock::now();
    let mut r = DVector::zeros(0);
    for _ in 0..reps {
        r = assemble_residual(
            FrameProblem { problem: &problem, params: &base, frame: &frame, alpha_prev: &prev },
            &big,
            &fixed,
            Some((&pattern, &mut values, &rows)),
        );
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
    let mut newton_solver = FrameSolver::new(&problem, base);
    for _ in 0..runs {
        let sol = newton_solver.solve(&frame, &start.u, Start::Near, |_, _, _| {})?;
        iterations += sol.history.len();
    }
    let newton = elapsed(&t) / iterations as f64;
    println!("(CPU time of the thread where /proc/thread-self/schedstat exists, else wall time)");
    println!("{} nodes, {} unknowns, {} stored entries", n, kd.len(), pattern.nnz());
    println!("Newton Jacobian + residual assembly: {:8.3} ms", assemble * 1e3);
    println!("equilibrated banded LU solve:       {:8.3} ms (relative residual {res:.1e})", solve * 1e3);
    println!(
        "whole Newton iteration:             {:8.3} ms ({} iterations per frame)",
        newton * 1e3,
        iterations / runs
    );
    Ok(())
}
