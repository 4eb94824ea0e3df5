//! Micro-benchmark of the operations of the inverse Newton on a frame of the 3D clip
//! `cases/worm_roll_3d.toml` (frame 29, after solving frames 0–29): KKT system assembly,
//! residual assembly with and without the Jacobian, the equilibrated and the rescaled banded
//! LU solve, and a solve with the last factorisation; µs per call, wall time. Needs the worm
//! data (scripts/fetch_worm_data.sh). Run with
//! `cargo run --release --example bench_ops [reps] [name prefix]`.
use std::time::Instant;

use anyhow::{Context, Result};
use cosserat::case::Case;
use cosserat::engine::input::clip_files::load_clip;
use cosserat::linalg::LinearSolver;
use cosserat::solve::inverse::{kkt, measures, newton, Frame, FrameProblem};
use cosserat::solve::sequence::{solve_sequence, FirstStart, FrameSolution};
use nalgebra::{DVector, Vector3};

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let reps: usize = args.next().map(|a| a.parse()).transpose().context("reps")?.unwrap_or(2000);
    let only = args.next();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/worm_roll_3d.toml");
    let case = Case::from_file(&path)?;
    let (clip, _) = load_clip(&case)?;
    let problem = case.problem();
    let sp = case.sequence_params().context("a clip case")?;
    let frames = clip.frames[..30].to_vec();
    let mut state = None;
    solve_sequence(
        &problem,
        &sp,
        &frames,
        FirstStart::DataGuess,
        |_, _| {},
        |_, f: &FrameSolution| {
            state = Some(f.state.clone());
            Ok(())
        },
    )?;
    let u = state.context("a solved frame")?;
    let params = sp.inverse;
    let dofs = problem.mesh.kkt_dofs();
    let pattern = dofs.pattern();
    let mut values = vec![0.0; pattern.nnz()];
    let x_g = &frames[29];
    let prev = vec![Vector3::zeros(); problem.mesh.nodes()];
    let frame = Frame { index: 29, x_g, previous: Some(&prev), weight: None, fix_roll: false };
    let fixed = kkt::dirichlet(&dofs, 0.0, &frame);
    let rows: Vec<usize> = fixed.iter().map(|f| f.0).collect();
    let time = |name: &str, f: &mut dyn FnMut()| {
        if only.as_deref().is_some_and(|o| !name.starts_with(o)) {
            return;
        }
        f();
        let t = Instant::now();
        for _ in 0..reps {
            f();
        }
        println!("{name:32} {:8.1} µs", t.elapsed().as_secs_f64() * 1e6 / reps as f64);
    };
    let fp = FrameProblem { problem: &problem, params: &params, frame: &frame, alpha_prev: &prev };
    let rhs = kkt::assemble_system(fp, &pattern, &mut values, &u);
    pattern.set_identity_rows(&mut values, &rows);
    let mut solver = LinearSolver::new(&pattern);
    let big: DVector<f64> = solver.solve_equilibrated(&values, &rhs)?;
    time("KKT system", &mut || {
        std::hint::black_box(kkt::assemble_system(fp, &pattern, &mut values, &u));
    });
    time("residual", &mut || {
        std::hint::black_box(newton::assemble_residual(fp, &big, &fixed, None));
    });
    let jacobian = |values: &mut [f64]| newton::assemble_residual(fp, &big, &fixed, Some((&pattern, values, &rows)));
    time("residual + Jacobian", &mut || {
        std::hint::black_box(jacobian(&mut values));
    });
    let r = jacobian(&mut values);
    time("Ruiz + LU + solve", &mut || {
        std::hint::black_box(solver.solve_equilibrated(&values, &r).expect("solve"));
    });
    time("LU + solve (rescaled)", &mut || {
        std::hint::black_box(solver.solve_rescaled(&values, &r).expect("solve"));
    });
    time("solve (last factorisation)", &mut || {
        std::hint::black_box(solver.solve_factored(&r).expect("solve"));
    });
    let fwd = problem.dofs();
    let (us, adj) = (dofs.kkt_state(&big), dofs.kkt_adjoint(&big));
    time("iteration record (measures)", &mut || {
        std::hint::black_box(measures::measures(&fp, &us, &adj));
    });
    time("relative change", &mut || {
        std::hint::black_box(cosserat::solve::statics::relative_change(&fwd, &us, &adj));
    });
    Ok(())
}
