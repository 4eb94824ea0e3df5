//! `cosserat batch` and the body length: `rod.length_m = "from_data"` measures each
//! recording's body (worms of different sizes in one batch), and the summary's measures do
//! not depend on where a recording sits in space.
mod batch_common;
mod common;

use std::path::Path;

use batch_common::{case, cosserat, summary_without_time};
use cosserat::io::npy::{read_npy, write_npy};

/// Frames per recording of these tests.
const FRAMES: usize = 8;

/// `cosserat synth` of one recording of `length_m` [m] (default noise, 1e-7 m) into `dir`.
fn synth(dir: &Path, length_m: &str, seed: &str) {
    let out = cosserat()
        .args(["synth", "--count", "1", "--frames", &FRAMES.to_string(), "--seed", seed, "--length-m", length_m])
        .arg("--out")
        .arg(dir)
        .output()
        .expect("synth");
    assert!(out.status.success(), "synth: {}", String::from_utf8_lossy(&out.stderr));
}

/// `cosserat batch CASE --recordings RECS --out OUT --quiet`; its summary without the time.
fn batch(case: &Path, recs: &Path, out: &Path) -> Vec<Vec<String>> {
    let o =
        cosserat().arg("batch").arg(case).arg("--recordings").arg(recs).arg("--out").arg(out).arg("--quiet").output();
    let o = o.expect("batch");
    assert!(o.status.success(), "batch: {}", String::from_utf8_lossy(&o.stderr));
    summary_without_time(out)
}

/// The value of `column` in `row` of a summary with header `header`.
fn column<'a>(header: &[String], row: &'a [String], column: &str) -> &'a str {
    &row[header.iter().position(|h| h == column).unwrap_or_else(|| panic!("no column {column}"))]
}

/// Two worms, 0.8 mm and 1.3 mm, in one batch of a case with `rod.length_m = "from_data"`:
/// each is solved with its own length. The tolerance, 1e-3 of the length: the noise (1e-7 m,
/// synth's default) lengthens a chord by 2σ²/h² ≈ 3e-5 at most (0.8 mm on 33 nodes), so the
/// estimate is limited by the chord-to-arc excess of the bent body, h²κ²/24 ≈ 3e-3 of the
/// length at 33 nodes (docs/decisions.md D18), which the curvature correction removes: a third
/// of it would be missed by an estimate without that correction.
#[test]
fn from_data_measures_each_recordings_body_length() {
    if !common::worm_data_present("from_data") {
        return;
    }
    let tmp = tempfile::tempdir().expect("tempdir");
    let recs = tmp.path().join("recordings");
    for (length, seed, name) in [("8e-4", "1", "small"), ("1.3e-3", "2", "big")] {
        let dir = tmp.path().join(name);
        synth(&dir, length, seed);
        std::fs::create_dir_all(&recs).expect("recordings");
        for ext in ["npy", "truth.npy"] {
            std::fs::copy(dir.join(format!("roll_000.{ext}")), recs.join(format!("{name}.{ext}"))).expect("copy");
        }
    }
    let text = std::fs::read_to_string(case()).expect("case").replace("length_m = \"L\"", "length_m = \"from_data\"");
    assert!(text.contains("\"from_data\""), "the batch case sets rod.length_m = \"L\"");
    let from_data = tmp.path().join("from_data.toml");
    std::fs::write(&from_data, text).expect("case");
    let out = tmp.path().join("out");
    let rows = batch(&from_data, &recs, &out);
    assert_eq!(rows.len(), 3, "{rows:?}");
    for (row, truth) in rows[1..].iter().zip([1.3e-3, 8e-4]) {
        let num = |c: &str| column(&rows[0], row, c).parse::<f64>().unwrap_or_else(|_| panic!("{c} of {row:?}"));
        assert_eq!(column(&rows[0], row, "status"), "ok", "{row:?}");
        assert!((num("length_m") / truth - 1.0).abs() < 1e-3, "length {} against {truth}: {row:?}", num("length_m"));
        assert!(num("length_spread_rel") < 1e-3, "{row:?}");
        let manifest: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join(&row[1]).join("run.json")).expect("run.json"))
                .expect("json");
        let b = &manifest["body_length"];
        // the summary's 10 significant digits
        let estimate = b["length_m"].as_f64().expect("length_m");
        assert!((estimate / num("length_m") - 1.0).abs() < 1e-9, "{manifest}");
        assert_eq!(b["frames"].as_u64(), Some(FRAMES as u64), "{manifest}");
        let (lo, hi) = (b["min_m"].as_f64().expect("min_m"), b["max_m"].as_f64().expect("max_m"));
        assert!(lo <= estimate && estimate <= hi && (hi - lo) / truth < 3e-3, "{manifest}");
        println!("{}: estimated {estimate:e} m, truth {truth:e} m, frames {lo:e} … {hi:e} m", row[1]);
    }
}

/// A copy of a recording translated by 1 cm along every axis (ten body lengths) is solved and
/// scored as the original: the summary's measures agree to the solver's tolerance. The fit
/// measure is in body lengths; the solves differ by round-off of the translated coordinates
/// (ε · 1.7 cm ≈ 4e-18 m) amplified by at most the solver's stop tolerance 1e-9 on the relative
/// change of (x, α): 1e-9 of |x| ≈ 2e-11 m, 2e-8 body lengths. (The paper's ‖x − x_g‖/‖x_g‖ of
/// frames.csv changes with the position.)
#[test]
fn a_translated_recording_scores_the_same() {
    if !common::worm_data_present("translated") {
        return;
    }
    let tmp = tempfile::tempdir().expect("tempdir");
    let recs = tmp.path().join("recordings");
    synth(&recs, "1e-3", "7");
    let a = read_npy(&recs.join("roll_000.npy")).expect("recording");
    let moved: Vec<f64> = a.data.iter().map(|v| v + 1e-2).collect();
    write_npy(&recs.join("roll_moved.npy"), &a.shape, &moved).expect("translated copy");
    std::fs::copy(recs.join("roll_000.truth.npy"), recs.join("roll_moved.truth.npy")).expect("truth");
    let out = tmp.path().join("out");
    let rows = batch(&case(), &recs, &out);
    assert_eq!(rows.len(), 3, "{rows:?}");
    let (h, here, there) = (&rows[0], &rows[1], &rows[2]);
    for c in ["status", "frames", "length_m", "length_spread_rel", "reason"] {
        assert_eq!(column(h, here, c), column(h, there, c), "{c}: {rows:?}");
    }
    let num = |row: &[String], c: &str| column(h, row, c).parse::<f64>().unwrap_or_else(|_| panic!("{c} of {row:?}"));
    let fit = num(here, "fit_position_rel_length_max");
    println!("fit {fit:e} and {:e} body lengths", num(there, "fit_position_rel_length_max"));
    assert!((fit - num(there, "fit_position_rel_length_max")).abs() < 2e-8, "{rows:?}");
    let bending = num(here, "curvature_err_rel_max");
    assert!((bending / num(there, "curvature_err_rel_max") - 1.0).abs() < 1e-6, "{rows:?}");
    // frames.csv keeps the paper's measure, which does depend on the position
    let x_err_rel_max = |dir: &str| {
        let mut r = csv::Reader::from_path(out.join(dir).join("frames.csv")).expect("frames.csv");
        let k = r.headers().expect("header").iter().position(|c| c == "x_err_rel").expect("x_err_rel");
        r.records().map(|rec| rec.expect("row")[k].parse::<f64>().expect("x_err_rel")).fold(0.0, f64::max)
    };
    assert!(x_err_rel_max("roll_000") / x_err_rel_max("roll_moved") > 10.0, "‖x − x_g‖/‖x_g‖ moves with the clip");
}
