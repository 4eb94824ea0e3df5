//! A comparison that cannot fail proves nothing: copies of the FreeFEM scripts with one sign
//! flipped in one term (through the test-only script directory `COSSERAT_FREEFEM_DIR`) must make
//! `compare` fail, by rows beyond their derived tolerances or by a FreeFEM failure, while the
//! intact scripts pass the same comparison (`cross_engine.rs`).
//!
//! One test function: the script directory is process-wide state.
mod common;

use std::path::Path;

use cosserat::case::Case;
use cosserat::engine::freefem::{script_dir, SCRIPT_DIR_ENV};
use cosserat::jobs::compare::{compare_case, CompareOptions, Horizon};

/// One mutation: a script of `freefem/`, the exact text replaced (at each of its `occurrences`),
/// its replacement, the case and horizon it is run on, and the rows that must fail.
struct Mutation {
    what: &'static str,
    file: &'static str,
    from: &'static str,
    occurrences: usize,
    to: &'static str,
    case: &'static str,
    horizon: Horizon,
    /// rows that must fail when FreeFEM still converges
    rows: &'static [&'static str],
}

const MUTATIONS: &[Mutation] = &[
    Mutation {
        what: "inverse: the lambda_d right-hand side (linearised d3 of eq. 60) with the wrong sign",
        file: "inverse_core.idp",
        from: "+ (1. - stab)*lambdaD*(TMS1(uc,te)*TMR1(uc)",
        occurrences: 1,
        to: "- (1. - stab)*lambdaD*(TMS1(uc,te)*TMR1(uc)",
        case: "inverse_bend_twist",
        horizon: Horizon::Short,
        rows: &["nodewise_rel_diff_angles", "nodewise_rel_diff_xhat", "x_err_rel"],
    },
    Mutation {
        what: "forward: the follower load's f2 term (f^g = Q^T f^l) with the wrong sign",
        file: "forward.edp",
        from: "macro FLG2(P,T) (Qp(12,P)*F1(x,T) + Qp(22,P)*F2(x,T)",
        occurrences: 1,
        to: "macro FLG2(P,T) (Qp(12,P)*F1(x,T) - Qp(22,P)*F2(x,T)",
        case: "follower_bend_64",
        horizon: Horizon::Full,
        rows: &["nodewise_rel_diff_displacement", "tip_y_m"],
    },
    // kinematics.idp's XN3F as scripts/freefem_coefficients.py writes it into coefficients.idp
    // (array statements; the script FreeFEM runs), in COEFUPDATE and in COEFUPDATET
    Mutation {
        what: "forward: the third component of d_s x cross n (eq. 35) with the wrong sign",
        file: "coefficients.idp",
        from: "cqcXN3[] = cqcD1[] .* cqcNG2[]; coefW = cqcD2[] .* cqcNG1[]; cqcXN3[] -= coefW;",
        occurrences: 2,
        to: "cqcXN3[] = cqcD1[] .* cqcNG2[]; coefW = cqcD2[] .* cqcNG1[]; cqcXN3[] += coefW;",
        case: "follower_bend_twist_65",
        horizon: Horizon::Full,
        rows: &["nodewise_rel_diff_displacement"],
    },
];

fn copy_scripts(to: &Path) {
    for e in std::fs::read_dir(script_dir()).expect("freefem/") {
        let p = e.expect("entry").path();
        if p.is_file() {
            std::fs::copy(&p, to.join(p.file_name().expect("name"))).expect("copy");
        }
    }
}

#[test]
fn broken_freefem_scripts_make_compare_fail() {
    if !common::freefem_required() {
        return;
    }
    let mut survived = Vec::new();
    for m in MUTATIONS {
        let dir = tempfile::tempdir().expect("tempdir");
        copy_scripts(dir.path());
        let path = dir.path().join(m.file);
        let text = std::fs::read_to_string(&path).expect("script");
        let found = text.matches(m.from).count();
        assert_eq!(found, m.occurrences, "{}: `{}` must occur {} times in {}", m.what, m.from, m.occurrences, m.file);
        std::fs::write(&path, text.replace(m.from, m.to)).expect("write");
        std::env::set_var(SCRIPT_DIR_ENV, dir.path());
        let case = Case::from_file(&common::cases_dir().join(format!("{}.toml", m.case))).expect("case");
        let out = tempfile::tempdir().expect("tempdir");
        let result = compare_case(&case, out.path(), &CompareOptions { horizon: m.horizon, frames: None });
        std::env::remove_var(SCRIPT_DIR_ENV);
        match result {
            Err(e) => eprintln!("{} on {}: compare FAILED with an error: {}", m.what, m.case, common::error_chain(&e)),
            Ok(report) => {
                let failed: Vec<&str> = report.rows.iter().filter(|r| !r.passed()).map(|r| r.name.as_str()).collect();
                eprintln!(
                    "{} on {}: {} of {} rows FAILED: {failed:?}",
                    m.what,
                    m.case,
                    failed.len(),
                    report.rows.len()
                );
                for r in &report.rows {
                    eprintln!("  {:<32} |diff| {:.3e}  tol {:.3e}", r.name, r.difference, r.tolerance);
                }
                let missing: Vec<_> = m.rows.iter().filter(|n| !failed.contains(n)).collect();
                if !missing.is_empty() {
                    survived.push(format!("{} on {}: rows {missing:?} passed", m.what, m.case));
                }
            }
        }
    }
    assert!(survived.is_empty(), "mutations the comparison did not catch: {survived:#?}");
}

/// The generated `coefficients.idp` (the state quantities of `kinematics.idp` as array
/// statements) is what its generator writes from the committed formulas: a formula changed
/// without running the generator would not reach FreeFEM.
#[test]
fn the_generated_coefficients_are_up_to_date() {
    let out = std::process::Command::new("python3")
        .arg("scripts/freefem_coefficients.py")
        .arg("--check")
        .output()
        .expect("python3");
    assert!(out.status.success(), "{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
}
