//! The `cosserat` binary: help text, listing, running, errors on bad input, modes, compare.
mod common;

use assert_cmd::Command;
use predicates::prelude::*;

fn cosserat() -> Command {
    let mut c = Command::cargo_bin("cosserat").expect("binary");
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

#[test]
fn help_lists_the_subcommands() {
    let out = cosserat().arg("--help").assert().success().get_output().stdout.clone();
    insta::assert_snapshot!("help", String::from_utf8_lossy(&out));
    cosserat().args(["run", "--help"]).assert().success().stdout(predicate::str::contains("--engine <ENGINE>").and(predicate::str::contains("freefem")));
}

#[test]
fn list_shows_every_case_with_its_description() {
    cosserat()
        .arg("list")
        .assert()
        .success()
        .stdout(predicate::str::contains("timoshenko_5pct").and(predicate::str::contains("timoshenko_10pct")).and(predicate::str::contains("cantilever_dynamic")).and(predicate::str::contains("§5.1")));
}

#[test]
fn run_writes_csv_metrics_and_plot() {
    let dir = tempfile::tempdir().expect("tempdir");
    cosserat().args(["run", "cases/timoshenko_5pct.toml", "--quiet", "--out"]).arg(dir.path()).assert().success().stdout(predicate::str::contains("timoshenko_5pct [rust]"));
    let nodes = std::fs::read_to_string(dir.path().join("nodes.csv")).expect("nodes.csv");
    assert!(nodes.starts_with("s_m,x_m,y_m,z_m,ux_m,uy_m,uz_m,alpha_rad,beta_rad,gamma_rad\n"));
    assert_eq!(nodes.lines().count(), 102);
    let m: std::collections::BTreeMap<String, f64> = serde_json::from_str(&std::fs::read_to_string(dir.path().join("metrics.json")).expect("metrics")).expect("json");
    assert!((m["tip_y_m"] / -4.93e-5 - 1.0).abs() < 1e-3, "{m:?}");
    assert!(std::fs::read_to_string(dir.path().join("plot.svg")).expect("svg").contains("<svg"));
    assert!(dir.path().join("history.csv").is_file() && dir.path().join("curvature.csv").is_file());
}

#[test]
fn bad_case_is_a_clear_error_not_a_panic() {
    let dir = tempfile::tempdir().expect("tempdir");
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, common::edit(&common::case_text("timoshenko_5pct"), "young_modulus_pa = 1.1e5", "young_modulus_pa = -1.1e5")).expect("write");
    cosserat()
        .arg("run")
        .arg(&bad)
        .assert()
        .code(1)
        .stderr(predicate::str::contains("material.young_modulus_pa").and(predicate::str::contains("must be > 0")).and(predicate::str::contains("panicked").not()));
    cosserat().args(["run", "cases/does_not_exist.toml"]).assert().code(1).stderr(predicate::str::contains("cannot read case file"));
    cosserat().args(["run", "cases/timoshenko_5pct.toml", "--engine", "abaqus"]).assert().code(2);
}

#[test]
fn modes_prints_the_first_bending_frequency() {
    cosserat().args(["modes", "cases/cantilever_dynamic.toml", "--count", "2"]).assert().success().stdout(predicate::str::contains("206.78"));
}

#[test]
fn compare_runs_both_engines() {
    if std::env::var_os("COSSERAT_SKIP_FREEFEM").is_some() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    cosserat()
        .args(["compare", "cases/timoshenko_5pct.toml", "--out"])
        .arg(dir.path())
        .assert()
        .success()
        .stdout(predicate::str::contains("nodewise_rel_diff_displacement").and(predicate::str::contains("PASS")).and(predicate::str::contains("FAIL").not()));
    assert!(dir.path().join("freefem/metrics.json").is_file() && dir.path().join("rust/metrics.json").is_file());
}
