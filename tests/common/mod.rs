//! Shared helpers of the integration tests.
#![allow(dead_code)]
use std::path::{Path, PathBuf};

use cosserat::case::Case;

pub fn cases_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("cases")
}

pub fn case_text(name: &str) -> String {
    std::fs::read_to_string(cases_dir().join(format!("{name}.toml"))).expect("case file")
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

/// Round to `digits` significant digits (stable snapshot values across machines).
pub fn sig(v: f64, digits: i32) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let p = digits - 1 - v.abs().log10().floor() as i32;
    let f = 10f64.powi(p);
    (v * f).round() / f
}

/// A case file of `cases/` read from disk (relative paths inside it resolve against `cases/`).
pub fn case_file(name: &str) -> Case {
    Case::from_file(&cases_dir().join(format!("{name}.toml"))).unwrap_or_else(|e| panic!("{e}"))
}

/// Are the worm clips of `scripts/fetch_worm_data.sh` present? Prints a notice when not.
pub fn worm_data_present(test: &str) -> bool {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/elegansbot");
    let ok = ["kymogram_omega-turn.npy", "kymogram_delta-turn.npy"].iter().all(|f| dir.join(f).is_file());
    if !ok {
        eprintln!("{test}: SKIPPED: the worm clips are not in {} (run scripts/fetch_worm_data.sh)", dir.display());
    }
    ok
}

/// Is this case a recorded clip (`[clip]`)?
pub fn is_clip(case: &Case) -> bool {
    matches!(case.inverse().map(|i| &i.data), Some(cosserat::case::DataSource::Clip(_)))
}

/// Forward data by Newton (tolerance 1e-13) with `steps` load-continuation steps: the solution
/// and its nodal positions x_g.
pub fn forward_data(case: &Case, steps: usize) -> (nalgebra::DVector<f64>, Vec<nalgebra::Vector3<f64>>) {
    use cosserat::solve::statics::{self, Method, StaticParams};
    let p = cosserat::solve::Problem::from_case(case);
    let fwd = statics::solve(
        &p,
        &StaticParams { method: Method::Newton, tolerance: 1e-13, max_iterations: 40, continuation_steps: steps },
        |_| {},
    )
    .expect("forward data");
    let xg = (0..case.mesh.nodes()).map(|i| cosserat::solve::node_values(&fwd.u, i).0).collect();
    (fwd.u, xg)
}

/// The paper's first inverse test (§5.2): λg = 1e9, λf = 1, λl = 1e-10, λd = 1e-6,
/// Λκ = diag(0, 0, 1e-10), Λω = 0, w = 0.5, first frame; stop at relative change 3e-6 within
/// 1000 iterations (tests override the stopping settings as they need).
pub fn paper_params_64() -> cosserat::solve::inverse::InverseParams {
    cosserat::solve::inverse::InverseParams {
        lambda_g: 1e9,
        lambda_f: 1.0,
        lambda_l: 1e-10,
        lambda_d: 1e-6,
        lambda_kappa: nalgebra::Vector3::new(0.0, 0.0, 1e-10),
        lambda_omega: nalgebra::Vector3::zeros(),
        dt: 1.0,
        first_frame: true,
        alpha0: 0.0,
        frame: 0,
        stabilisation: 0.0,
        relaxation: 0.5,
        tolerance: 3e-6,
        max_iterations: 1000,
    }
}

/// Every term of (41) switched on, a frame after the first (Λω active), for derivative checks.
pub fn all_terms_params() -> cosserat::solve::inverse::InverseParams {
    cosserat::solve::inverse::InverseParams {
        lambda_f: 1e-2,
        lambda_l: 1e-6,
        lambda_d: 1e-3,
        lambda_kappa: nalgebra::Vector3::new(1e-12, 2e-12, 1e-10),
        lambda_omega: nalgebra::Vector3::new(1e-9, 1e-9, 1e-8),
        dt: 0.04,
        first_frame: false,
        tolerance: 1e-6,
        max_iterations: 1,
        ..paper_params_64()
    }
}
