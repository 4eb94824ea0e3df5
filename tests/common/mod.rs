//! Shared helpers of the integration tests.
#![allow(dead_code)]
use std::path::{Path, PathBuf};

use cosserat::case::Case;
use cosserat::engine::freefem::{find_executable, INSTALL_HINT};
use cosserat::jobs::compare::CompareReport;
use cosserat::model::mesh::Field;
use cosserat::solve::certificate::DEFAULT_CERTIFICATE_TOLERANCE;
use cosserat::solve::inverse::{
    Frame, FrameSolver, InverseMethod, InverseParams, InverseRecord, InverseSolution, Start, Weights,
    DEFAULT_STABILISATION,
};
use cosserat::solve::{Problem, SolveError};
use nalgebra::{DVector, Vector3};

pub mod fixed_point;

pub fn cases_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("cases")
}

pub fn case_text(name: &str) -> String {
    std::fs::read_to_string(cases_dir().join(format!("{name}.toml"))).expect("case file")
}

/// The text of the case `name` with its `../data/elegansbot/` path made absolute, so that the
/// case can be written to and run from any folder.
pub fn case_text_with_data(name: &str) -> String {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/elegansbot");
    edit(&case_text(name), "file = \"../data/elegansbot/", &format!("file = \"{}/", data.display()))
}

/// `worm_roll_3d` cut to `frames` frames of `nodes` nodes, written as `dir/file`.
pub fn short_roll_case(dir: &Path, file: &str, frames: usize, nodes: usize) -> PathBuf {
    let text = edit(
        &edit(&case_text_with_data("worm_roll_3d"), "elements = 127", &format!("elements = {}", nodes - 1)),
        "clip_frames = 1160",
        &format!("clip_frames = {frames}"),
    );
    let path = dir.join(file);
    std::fs::write(&path, text).expect("case");
    path
}

/// Parse a case from (modified) TOML text.
pub fn case_from(text: &str, name: &str) -> Case {
    Case::from_toml(text, name, Path::new(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// Replace exactly one occurrence of `from` (so a silently unmatched edit fails the test).
pub fn edit(text: &str, from: &str, to: &str) -> String {
    assert_eq!(text.matches(from).count(), 1, "pattern `{from}` must occur once");
    text.replacen(from, to, 1)
}

/// A case file of `cases/` read from disk (relative paths inside it resolve against `cases/`).
pub fn case_file(name: &str) -> Case {
    Case::from_file(&cases_dir().join(format!("{name}.toml"))).unwrap_or_else(|e| panic!("{e}"))
}

/// Are the worm clips of `scripts/fetch_worm_data.sh` present? A test that needs them fails
/// without them, unless `COSSERAT_SKIP_WORM_DATA` is set (local work only; CI never sets it: a
/// test that passes without its data proves nothing), in which case it says so and returns
/// false.
pub fn worm_data_present(test: &str) -> bool {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/elegansbot");
    let ok = ["kymogram_omega-turn.npy", "kymogram_delta-turn.npy"].iter().all(|f| dir.join(f).is_file());
    if !ok && std::env::var_os("COSSERAT_SKIP_WORM_DATA").is_none() {
        panic!(
            "{test}: the worm clips are not in {} (run scripts/fetch_worm_data.sh, or set COSSERAT_SKIP_WORM_DATA=1 to \
             skip the tests that need them)",
            dir.display()
        );
    }
    if !ok {
        eprintln!("{test}: SKIPPED (COSSERAT_SKIP_WORM_DATA is set): the worm clips are not in {}", dir.display());
    }
    ok
}

/// `case` as `cosserat run` and `compare` read it (a recording's length, plane and frame
/// numbers from its data: `resolve_recording`), if its data are here. A case without a clip
/// needs none; a clip needs the elegansbot kymograms (`scripts/fetch_worm_data.sh`; `None` and a
/// notice when absent), and a case on the tracker recordings of `data/tracker/`
/// (`cases/worm_2d_recording.toml`) those too, from which they are written when absent with
/// the recordings `scripts/setup.sh` writes (`cosserat synth --tracker --out data/tracker`:
/// the same parameters, the same bytes).
pub fn with_clip_data(case: Case) -> Option<Case> {
    let Some(src) = case.clip() else { return Some(case) };
    if !worm_data_present(&case.name) {
        return None;
    }
    if !src.file.is_file() && src.file.components().any(|c| c.as_os_str() == "tracker") {
        use cosserat::engine::input::tracker::{write_tracker_corpus, TrackerParams};
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let kymograms = ["omega", "delta"].map(|t| root.join(format!("data/elegansbot/kymogram_{t}-turn.npy")));
        write_tracker_corpus(&root.join("data/tracker"), &kymograms, &TrackerParams::default())
            .unwrap_or_else(|e| panic!("the tracker recordings of {}: {e}", case.name));
    }
    let resolved = cosserat::engine::input::resolve::resolve_recording(&case);
    Some(resolved.unwrap_or_else(|e| panic!("{}: {}", case.name, error_chain(&e))))
}

/// Is this case a recorded clip (`[clip]`)?
pub fn is_clip(case: &Case) -> bool {
    case.clip().is_some()
}

/// Forward data by Newton (tolerance 1e-13) with `steps` load-continuation steps: the solution
/// and its nodal positions x_g.
pub fn forward_data(case: &Case, steps: usize) -> (nalgebra::DVector<f64>, Vec<nalgebra::Vector3<f64>>) {
    use cosserat::solve::statics::{self, Method, StaticParams};
    let p = case.problem();
    let fwd = statics::solve(
        &p,
        &StaticParams {
            method: Method::Newton,
            tolerance: 1e-13,
            max_iterations: 40,
            continuation_steps: steps,
            certificate_tolerance: DEFAULT_CERTIFICATE_TOLERANCE,
            path: None,
            buckling_modes: 0,
            vibration_modes: 0,
        },
        |_| {},
    )
    .and_then(|s| s.converged())
    .expect("forward data");
    let xg = p.dofs().field(&fwd.u, Field::X);
    (fwd.u, xg)
}

/// The paper's first inverse test (§5.2): λg = 1e9, λf = 1, λl = 1e-10, λd = 1e-6,
/// Λκ = diag(0, 0, 1e-10), Λω = 0, w = 0.5, the fixed point; stop at relative change 3e-6
/// within 1000 iterations (tests override the stopping settings as they need).
pub fn paper_params_64() -> InverseParams {
    InverseParams {
        weights: Weights {
            lambda_g: 1e9,
            lambda_f: 1.0,
            lambda_l: 1e-10,
            lambda_d: 1e-6,
            lambda_kappa: Vector3::new(0.0, 0.0, 1e-10),
            lambda_omega: Vector3::zeros(),
        },
        frame_interval_s: 1.0,
        alpha0_rad: 0.0,
        stabilisation: DEFAULT_STABILISATION,
        relaxation: 0.5,
        method: InverseMethod::FixedPoint,
        tolerance: 3e-6,
        max_iterations: 1000,
        certificate_tolerance: DEFAULT_CERTIFICATE_TOLERANCE,
    }
}

/// Every term of (41) switched on (Λω acts on a frame with a previous one), for derivative
/// checks.
pub fn all_terms_params() -> InverseParams {
    let p = paper_params_64();
    InverseParams {
        weights: Weights {
            lambda_f: 1e-2,
            lambda_l: 1e-6,
            lambda_d: 1e-3,
            lambda_kappa: Vector3::new(1e-12, 2e-12, 1e-10),
            lambda_omega: Vector3::new(1e-9, 1e-9, 1e-8),
            ..p.weights
        },
        frame_interval_s: 0.04,
        tolerance: 1e-6,
        max_iterations: 1,
        ..p
    }
}

/// `params` with other weights.
pub fn with_weights(params: &InverseParams, f: impl FnOnce(&mut Weights)) -> InverseParams {
    let mut p = *params;
    f(&mut p.weights);
    p
}

/// One frame through the one inverse entry point: the method of `params` from `u0`
/// (`Start::Guess`: Newton warm-started by the fixed point; `Start::Near`: Newton directly);
/// `previous`: the previous frame's angles (None: a first frame). An error if it did not
/// converge.
pub fn solve_frame(
    p: &Problem,
    params: &InverseParams,
    x_g: &[Vector3<f64>],
    previous: Option<&[Vector3<f64>]>,
    u0: &DVector<f64>,
    start: Start,
    on: impl FnMut(&InverseRecord),
) -> Result<InverseSolution, SolveError> {
    solve_frame_any(p, params, x_g, previous, u0, start, on)?.converged(0)
}

/// [`solve_frame`] without the convergence check: the solution whatever its stop (converged,
/// stalled or at the iteration limit), for tests of what an iteration does.
pub fn solve_frame_any(
    p: &Problem,
    params: &InverseParams,
    x_g: &[Vector3<f64>],
    previous: Option<&[Vector3<f64>]>,
    u0: &DVector<f64>,
    start: Start,
    mut on: impl FnMut(&InverseRecord),
) -> Result<InverseSolution, SolveError> {
    let frame = Frame { index: 0, x_g, previous, weight: None, fix_roll: false };
    FrameSolver::new(p, *params).solve(&frame, u0, start, |r, _, _| on(r))
}

/// A run of a case in the Rust engine that may end stalled or at its iteration limit: the
/// result (the last iterate) and, for such an end, the solver's error.
pub fn run_any(case: &Case) -> (cosserat::engine::RunResult, Option<SolveError>) {
    match cosserat::engine::rust::run_rust(case, |_, _| {}) {
        Ok(r) => (r, None),
        Err(cosserat::engine::RunError::Incomplete { source, partial }) => (*partial, Some(source)),
        Err(e) => panic!("{}: {}", case.name, error_chain(&e)),
    }
}

/// [`solve_frame`] by Newton directly from `u0` (no warm start), with `params`' stopping rule.
pub fn solve_newton(
    p: &Problem,
    params: &InverseParams,
    x_g: &[Vector3<f64>],
    previous: Option<&[Vector3<f64>]>,
    u0: &DVector<f64>,
    on: impl FnMut(&InverseRecord),
) -> Result<InverseSolution, SolveError> {
    let newton = InverseParams { method: InverseMethod::Newton { warm_start_tolerance: 1e-3 }, ..*params };
    solve_frame(p, &newton, x_g, previous, u0, Start::Near, on)
}

/// Is FreeFEM there? Panics if not, unless `COSSERAT_SKIP_FREEFEM` is set (local work only;
/// CI never sets it), in which case it says so and returns false.
pub fn freefem_required() -> bool {
    if std::env::var_os("COSSERAT_SKIP_FREEFEM").is_some() {
        eprintln!("COSSERAT_SKIP_FREEFEM is set: skipping the FreeFEM cross-check");
        return false;
    }
    if find_executable().is_err() {
        panic!("FreeFem++ is not installed; {INSTALL_HINT} (or set COSSERAT_SKIP_FREEFEM=1 for local work)");
    }
    true
}

/// Print a comparison's rows and push one line per failed row to `failures`.
pub fn report_failures(report: &CompareReport, failures: &mut Vec<String>) {
    eprintln!(
        "{}: {}; rust {:.3} s, freefem {:.3} s",
        report.case, report.what, report.rust_wall_s, report.freefem_wall_s
    );
    for row in &report.rows {
        eprintln!(
            "  {:<32} |diff| {:.3e}  tol {:.3e}  {}  {}",
            row.name,
            row.difference,
            row.tolerance,
            if row.passed() { "PASS" } else { "FAIL" },
            row.basis
        );
        if !row.passed() {
            failures
                .push(format!("{}: {} differs by {:e} > {:e}", report.case, row.name, row.difference, row.tolerance));
        }
    }
}

/// An error with its sources, for the failure list.
pub fn error_chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut src = e.source();
    while let Some(c) = src {
        s.push_str(": ");
        s.push_str(&c.to_string());
        src = c.source();
    }
    s
}

/// A clip sink that keeps every frame handed to it.
pub struct Collect(pub std::sync::Arc<std::sync::Mutex<Vec<cosserat::engine::clip::ClipFrame>>>);

impl cosserat::engine::clip::FrameSink for Collect {
    type Error = std::convert::Infallible;
    fn frame(&mut self, frame: &cosserat::engine::clip::ClipFrame) -> Result<(), Self::Error> {
        self.0.lock().expect("frames").push(frame.clone());
        Ok(())
    }
    fn finish(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// Every number of a frame that derives from its solve, as bits.
pub fn frame_bits(f: &cosserat::engine::clip::ClipFrame) -> Vec<u64> {
    let r = &f.report;
    let mut v: Vec<u64> = [
        r.convergence.last_change,
        r.misfit.x_err_rel,
        r.misfit.tangent_misfit,
        r.misfit.objective.tracking,
        r.conditioning.min_cos_beta,
    ]
    .iter()
    .map(|x| x.to_bits())
    .collect();
    v.push(r.convergence.iterations as u64);
    v.extend(f.record.state.iter().chain(f.record.adjoint.iter()).map(|x| x.to_bits()));
    v.extend(f.planar.kappa2.iter().map(|x| x.to_bits()));
    v.extend(f.truth.iter().flat_map(|t| t.bending_recovered.iter().map(|x| x.to_bits())));
    v
}
