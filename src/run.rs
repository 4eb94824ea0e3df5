//! Running a case in either engine, producing one engine-agnostic [`RunResult`].
use std::path::Path;
use std::time::Instant;

use nalgebra::{DVector, Vector3};

use crate::case::{Analysis, Case, StaticMethod};
use crate::freefem::{self, FreeFemError};
use crate::solve::dynamics::{self, DynamicParams, TipRecord};
use crate::solve::statics::{self, IterationRecord, Method, StaticParams};
use crate::solve::{node_values, Problem, SolveError};

/// Which implementation produced a result.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Engine {
    Rust,
    Freefem,
}

impl std::fmt::Display for Engine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Engine::Rust => "rust",
            Engine::Freefem => "freefem",
        })
    }
}

/// Nodal fields of the final state.
#[derive(Clone, Debug, PartialEq)]
pub struct NodalState {
    /// reference arc length [m]
    pub s: Vec<f64>,
    /// position [m]
    pub x: Vec<Vector3<f64>>,
    /// angles (α, β, γ) [rad]
    pub alpha: Vec<Vector3<f64>>,
}

impl NodalState {
    pub fn from_vector(case: &Case, u: &DVector<f64>) -> Self {
        let n = case.mesh.nodes();
        let (x, alpha) = (0..n).map(|i| node_values(u, i)).unzip();
        NodalState { s: (0..n).map(|i| case.mesh.node_s(i)).collect(), x, alpha }
    }
    /// Displacement from the reference configuration `(0, 0, s)` [m].
    pub fn displacement(&self) -> Vec<Vector3<f64>> {
        self.x.iter().zip(&self.s).map(|(x, s)| x - Vector3::new(0.0, 0.0, *s)).collect()
    }
}

/// Solver statistics.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SolverStats {
    /// static: iterations of the nonlinear solver; dynamic: total Newton iterations
    pub iterations: usize,
    /// static: last relative change (fixed point) or increment (Newton)
    pub last_change: Option<f64>,
    /// static: ‖R‖∞/‖F‖∞ at the solution
    pub residual: Option<f64>,
    /// dynamic: largest Newton iteration count of a step
    pub max_newton_iterations: Option<usize>,
    /// wall-clock time of the solve (engine-internal) [s]
    pub wall_time_s: f64,
}

/// Result of running a case in one engine.
#[derive(Clone, Debug)]
pub struct RunResult {
    pub engine: Engine,
    pub nodes: NodalState,
    /// static iteration history
    pub history: Vec<IterationRecord>,
    /// dynamic tip history (including t = 0)
    pub tip: Vec<TipRecord>,
    pub stats: SolverStats,
}

/// Errors of running a case.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("rust engine")]
    Solve(#[from] SolveError),
    #[error("freefem engine")]
    FreeFem(#[from] FreeFemError),
}

/// Run `case` in the Rust engine. `progress(done, total)` is called per step/iteration.
pub fn run_rust(case: &Case, mut progress: impl FnMut(usize, usize)) -> Result<RunResult, RunError> {
    let problem = Problem::from_case(case);
    let start = Instant::now();
    match case.analysis {
        Analysis::Static { method, tolerance, max_iterations, continuation_steps } => {
            let method = match method {
                StaticMethod::FixedPoint { relaxation } => Method::FixedPoint { relaxation },
                StaticMethod::Newton => Method::Newton,
            };
            let params = StaticParams { method, tolerance, max_iterations, continuation_steps };
            let sol = statics::solve(&problem, &params, |r| progress(r.iteration, max_iterations))?;
            Ok(RunResult {
                engine: Engine::Rust,
                nodes: NodalState::from_vector(case, &sol.u),
                history: sol.history,
                tip: Vec::new(),
                stats: SolverStats {
                    iterations: sol.iterations,
                    last_change: Some(sol.last_change),
                    residual: Some(sol.residual),
                    max_newton_iterations: None,
                    wall_time_s: start.elapsed().as_secs_f64(),
                },
            })
        }
        Analysis::Dynamic { end_time_s, steps, tolerance, max_iterations } => {
            let params = DynamicParams { end_time_s, steps, newton_tolerance: tolerance, newton_max_iterations: max_iterations };
            let sol = dynamics::solve(&problem, &params, &mut progress)?;
            Ok(RunResult {
                engine: Engine::Rust,
                nodes: NodalState::from_vector(case, &sol.u),
                history: Vec::new(),
                tip: sol.tip,
                stats: SolverStats {
                    iterations: sol.total_newton_iterations,
                    last_change: None,
                    residual: None,
                    max_newton_iterations: Some(sol.max_newton_iterations),
                    wall_time_s: start.elapsed().as_secs_f64(),
                },
            })
        }
    }
}

/// Run `case` in the chosen engine; FreeFEM works in `workdir`.
pub fn run(case: &Case, engine: Engine, workdir: &Path, progress: impl FnMut(usize, usize)) -> Result<RunResult, RunError> {
    match engine {
        Engine::Rust => run_rust(case, progress),
        Engine::Freefem => Ok(freefem::run(case, workdir)?),
    }
}
