//! The paper's scheme as printed read with one rule (`quadrature = "midpoint"` and `"gauss2"`,
//! D4) on the eq. (64) data at λd = 0.3, in both engines (`docs/inverse.md`, I15).
//!
//! An independent implementation of the printed scheme (`scripts/midpoint_reading.py`, written
//! from the paper) reproduces both engines term for term; what set it apart was its stopping
//! rule, the first relative change ≤ 3e-6, against ours, 5 consecutive ones (D5). These tests
//! hold the two facts that explain the disagreement:
//! - gauss2: the change falls steadily, so our stop is exactly 4 iterations after the first
//!   change within the tolerance (the independent implementation's 144 against our 148);
//! - midpoint: the change dips under the tolerance once (near 400 iterations) and then rises
//!   again above 1e-5: the iterates do not settle, and no stopping rule on the change makes
//!   that dip a solution.
mod common;

use std::path::Path;

use common::{case_text, edit, freefem_required};

/// The relative change of every iteration in `inverse_history.csv` of a run folder.
fn changes(out: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(out.join("inverse_history.csv")).expect("inverse_history.csv");
    let mut lines = text.lines();
    let header = lines.next().expect("header");
    let col = header.split(',').position(|c| c == "rel_change").expect("rel_change column");
    lines.map(|l| l.split(',').nth(col).and_then(|v| v.parse().ok()).expect("a number")).collect()
}

/// `inverse_bend` (eq. 64, the paper's weights) read with `rule`, λd = 0.3, at most `cap`
/// iterations, run by the binary in `engine` into a folder of `dir`; its changes.
fn run(dir: &Path, rule: &str, engine: &str, cap: usize) -> Vec<f64> {
    let text = edit(&case_text("inverse_bend"), "lambda_d = 1e-6", "lambda_d = 0.3");
    let text = edit(&text, "analysis = \"inverse\"", &format!("analysis = \"inverse\"\nquadrature = \"{rule}\""));
    let text = edit(&text, "max_iterations = 1000", &format!("max_iterations = {cap}"));
    let case = dir.join(format!("{rule}.toml"));
    std::fs::write(&case, text).unwrap();
    let out = dir.join(format!("{rule}_{engine}"));
    let run = std::process::Command::new(assert_cmd::cargo::cargo_bin("cosserat"))
        .args(["run", case.to_str().unwrap(), "--engine", engine, "--quiet", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    // every run here ends stalled or not converged (the certificate, docs/certificate.md)
    assert_eq!(run.status.code(), Some(1), "{rule} {engine}: {}", String::from_utf8_lossy(&run.stderr));
    changes(&out)
}

const TOL: f64 = 3e-6;

/// The first iteration (1-based) whose change is within the tolerance.
fn first_dip(ch: &[f64]) -> Option<usize> {
    ch.iter().position(|&c| c <= TOL).map(|k| k + 1)
}

fn engines() -> Vec<&'static str> {
    if freefem_required() {
        vec!["rust", "freefem"]
    } else {
        vec!["rust"]
    }
}

/// gauss2: the fixed point stops (5 consecutive changes within 3e-6) exactly 4 iterations after
/// its first change within 3e-6, between 100 and 200 iterations (148 and 144 measured).
#[test]
fn gauss2_stops_four_after_its_first_dip() {
    let dir = tempfile::tempdir().unwrap();
    for engine in engines() {
        let ch = run(dir.path(), "gauss2", engine, 400);
        let dip = first_dip(&ch).expect("a change within the tolerance");
        eprintln!("gauss2, {engine}: first change ≤ 3e-6 at {dip}, stop at {}", ch.len());
        assert!((100..200).contains(&dip), "{engine}: {dip}");
        assert_eq!(ch.len(), dip + 4, "{engine}");
    }
}

/// midpoint: the first change within 3e-6 comes between 300 and 600 iterations (391 Rust, 430
/// FreeFEM, 379 the independent implementation), and within the next 400 the change rises to
/// over 1e-5 again (1.4e-4, 2.5e-4): no 5 consecutive changes within the tolerance.
#[test]
fn midpoint_dips_once_and_does_not_settle() {
    let dir = tempfile::tempdir().unwrap();
    for engine in engines() {
        let ch = run(dir.path(), "midpoint", engine, 1000);
        assert_eq!(ch.len(), 1000, "{engine}: the iteration limit");
        let dip = first_dip(&ch).expect("a change within the tolerance");
        let after = ch[dip..(dip + 400).min(ch.len())].iter().cloned().fold(0.0, f64::max);
        eprintln!("midpoint, {engine}: first change ≤ 3e-6 at {dip}, then up to {after:.2e}");
        assert!((300..600).contains(&dip), "{engine}: {dip}");
        assert!(after > 1e-5, "{engine}: {after:e}");
    }
}
