//! Shared by `tests/batch.rs` and `tests/slurm.rs`: a small corpus of synthetic recordings with
//! one bad recording, the batch case, and summaries compared without their timing column.
#![allow(dead_code)]
use std::path::{Path, PathBuf};

use assert_cmd::Command;

/// Recordings of the test corpus (the bad one excepted) and their frames.
pub const GOOD: usize = 4;
pub const FRAMES: usize = 12;

pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

pub fn cosserat() -> Command {
    let mut c = Command::cargo_bin("cosserat").expect("binary");
    c.current_dir(root());
    c
}

/// The batch case shipped in `cases/batch/`.
pub fn case() -> PathBuf {
    root().join("cases/batch/roll_recording.toml")
}

/// `cosserat batch CASE --recordings RECS --out OUT --quiet EXTRA…` of the batch case.
pub fn batch_command(recs: &Path, out: &Path, extra: &[&str]) -> Command {
    let mut c = cosserat();
    c.arg("batch").arg(case()).arg("--recordings").arg(recs).arg("--out").arg(out).arg("--quiet").args(extra);
    c
}

/// `GOOD` synthetic recordings of `FRAMES` frames (with truth sidecars) and `bad.csv`, a
/// recording with a non-finite coordinate, in `dir`.
pub fn corpus(dir: &Path) {
    let out = cosserat()
        .args(["synth", "--count", &GOOD.to_string(), "--frames", &FRAMES.to_string(), "--seed", "3", "--out"])
        .arg(dir)
        .output()
        .expect("synth");
    assert!(out.status.success(), "synth: {}", String::from_utf8_lossy(&out.stderr));
    let mut bad = String::from("frame,node,x_m,y_m,z_m\n");
    for node in 0..33 {
        let z = if node == 7 { "nan".to_string() } else { format!("{}", node as f64 * 1e-3 / 32.0) };
        bad += &format!("0,{node},0,0,{z}\n");
    }
    std::fs::write(dir.join("bad.csv"), bad).expect("bad.csv");
}

/// `summary.csv` of `out` without its `wall_time_s` column (the only one that differs between
/// two runs of the same batch).
pub fn summary_without_time(out: &Path) -> Vec<Vec<String>> {
    let mut r = csv::Reader::from_path(out.join("summary.csv")).expect("summary.csv");
    let header: Vec<String> = r.headers().expect("header").iter().map(String::from).collect();
    let time = header.iter().position(|h| h == "wall_time_s").expect("wall_time_s column");
    let mut rows = vec![header.iter().enumerate().filter(|(i, _)| *i != time).map(|(_, h)| h.clone()).collect()];
    for rec in r.records() {
        let rec = rec.expect("row");
        rows.push(rec.iter().enumerate().filter(|(i, _)| *i != time).map(|(_, v)| v.to_string()).collect());
    }
    rows
}
