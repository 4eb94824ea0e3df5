//! `--output-format compact`: the one `fields.npz` of a clip holds every per-node field of the
//! default output (`fields.csv`, `curvature.csv`, the `.vtp` files) at full precision: each
//! number the CSV and VTK files print is the decoded f64 printed as they print it, and the
//! tables (`frames.csv`, `truth.csv`) are the same bytes. A compact clip resumes to the same
//! file. On a 20-frame `worm_roll_3d` with 16 nodes; needs the omega-turn kymogram.
mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use assert_cmd::Command;
use common::{short_roll_case, worm_data_present};
use cosserat::engine::clip::nodal_curvature;
use cosserat::io::compact::{read_compact, CompactClip, OutputFormat, COMPACT_FILE, CURVATURE_COLUMNS, RAW_FIELDS};
use cosserat::jobs::clip_run::{run_clip_to, ClipOptions};
use cosserat::output::clip_output::CLIP_FIELD_COLUMNS;
use cosserat::output::journal::JOURNAL;
use nalgebra::Vector3;

const FRAMES: usize = 20;
const NODES: usize = 16;

/// The short clip as a case file in `dir`.
fn case_file(dir: &Path) -> PathBuf {
    short_roll_case(dir, "roll_short.toml", FRAMES, NODES)
}

fn run(case: &Path, out: &Path, extra: &[&str]) {
    Command::cargo_bin("cosserat")
        .expect("bin")
        .args(["run", "--quiet", "--out"])
        .arg(out)
        .arg(case)
        .args(extra)
        .assert()
        .success();
}

/// Column `name` of the compact file at (frame index, position).
fn value(c: &CompactClip, name: &str, frame: usize, at: usize) -> f64 {
    let (per, v) = &c.columns[name];
    v[frame * per + at]
}

/// The numbers of every `DataArray` of a `.vtp` file, by name.
fn vtp_arrays(text: &str) -> BTreeMap<String, Vec<String>> {
    let mut out = BTreeMap::new();
    for part in text.split("<DataArray").skip(1) {
        let name = part.split("Name=\"").nth(1).and_then(|s| s.split('"').next()).expect("name");
        let body = part.split_once('>').expect(">").1.split("</DataArray>").next().expect("end");
        out.insert(name.to_string(), body.split_whitespace().map(String::from).collect());
    }
    out
}

#[test]
fn the_compact_file_holds_every_field_of_the_default_output_exactly() {
    if !worm_data_present("the_compact_file_holds_every_field_of_the_default_output_exactly") {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let case = case_file(dir.path());
    let (csv, compact) = (dir.path().join("csv"), dir.path().join("compact"));
    run(&case, &csv, &[]);
    run(&case, &compact, &["--output-format", "compact"]);
    for f in ["frames.csv", "truth.csv"] {
        assert_eq!(std::fs::read(csv.join(f)).expect(f), std::fs::read(compact.join(f)).expect(f), "{f}");
    }
    for gone in ["fields.csv", "curvature.csv", "vtk", "clip.pvd", RAW_FIELDS, JOURNAL] {
        assert!(!compact.join(gone).exists(), "{gone} in a compact run");
    }
    let c = read_compact(&compact.join(COMPACT_FILE)).expect("fields.npz");
    assert_eq!(c.frame, (0..FRAMES as i64).collect::<Vec<_>>());
    let e = |v: f64| format!("{v:.10e}");

    // fields.csv: frame, node, then the columns, each the decoded value printed as {:.10e}
    let fields = std::fs::read_to_string(csv.join("fields.csv")).expect("fields.csv");
    let mut rows = 0;
    for (k, line) in fields.lines().skip(1).enumerate() {
        let (f, n) = (k / NODES, k % NODES);
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!((cells[0], cells[1]), (f.to_string().as_str(), n.to_string().as_str()));
        for (name, cell) in CLIP_FIELD_COLUMNS[2..].iter().zip(&cells[2..]) {
            assert_eq!(e(value(&c, name, f, n)), *cell, "fields.csv frame {f} node {n} {name}");
        }
        rows += 1;
    }
    assert_eq!(rows, FRAMES * NODES);

    // curvature.csv: frame, then s and κ at the element midpoints
    let curvature = std::fs::read_to_string(csv.join("curvature.csv")).expect("curvature.csv");
    for (k, line) in curvature.lines().skip(1).enumerate() {
        let (f, m) = (k / (NODES - 1), k % (NODES - 1));
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells[0], f.to_string());
        for (name, cell) in CURVATURE_COLUMNS.iter().zip(&cells[1..]) {
            assert_eq!(e(value(&c, name, f, m)), *cell, "curvature.csv frame {f} element {m} {name}");
        }
    }
    assert_eq!(curvature.lines().count() - 1, FRAMES * (NODES - 1));

    // the .vtp files: every array, printed as {:.9e}; κ per node from the element κ
    let vectors = [
        ("position_m", ["x_m", "y_m", "z_m"]),
        ("d1", ["d1_x", "d1_y", "d1_z"]),
        ("d2", ["d2_x", "d2_y", "d2_z"]),
        ("d3", ["d3_x", "d3_y", "d3_z"]),
        ("f_n_per_m", ["f_x_n_per_m", "f_y_n_per_m", "f_z_n_per_m"]),
        ("l_nm_per_m", ["l_x_nm_per_m", "l_y_nm_per_m", "l_z_nm_per_m"]),
        ("data_position_m", ["data_x_m", "data_y_m", "data_z_m"]),
        ("omega_rad_per_s", ["omega1_rad_per_s", "omega2_rad_per_s", "omega3_rad_per_s"]),
    ];
    for f in 0..FRAMES {
        let text = std::fs::read_to_string(csv.join(format!("vtk/frame_{f:05}.vtp"))).expect("vtp");
        let arrays = vtp_arrays(&text);
        // per element: κ from columns 1–3, n from 4–6, m from 7–9 (CURVATURE_COLUMNS), each
        // written per node as the mean of the adjacent elements
        let element = |first: usize| -> Vec<(f64, Vector3<f64>)> {
            (0..NODES - 1)
                .map(|m| {
                    let k = |i: usize| value(&c, CURVATURE_COLUMNS[i], f, m);
                    (k(0), Vector3::new(k(first), k(first + 1), k(first + 2)))
                })
                .collect()
        };
        let kn = nodal_curvature(&element(1));
        for (array, cols) in vectors {
            let expected: Vec<String> = (0..NODES)
                .flat_map(|n| cols.iter().map(move |col| (n, col)))
                .map(|(n, col)| format!("{:.9e}", value(&c, col, f, n)))
                .collect();
            assert_eq!(arrays[array], expected, "frame {f} {array}");
        }
        let printed = |v: &[Vector3<f64>]| -> Vec<String> {
            v.iter().flat_map(|k| k.iter().map(|v| format!("{v:.9e}")).collect::<Vec<_>>()).collect()
        };
        assert_eq!(arrays["kappa_per_m"], printed(&kn), "frame {f} kappa_per_m");
        assert_eq!(arrays["n_n"], printed(&nodal_curvature(&element(4))), "frame {f} n_n");
        assert_eq!(arrays["m_nm"], printed(&nodal_curvature(&element(7))), "frame {f} m_nm");
        assert_eq!(arrays.len(), vectors.len() + 5, "frame {f}: arrays {:?}", arrays.keys());
    }
}

/// A compact clip cut after 8 frames (its journal's later lines gone, `fields.npz` not yet
/// written, as after a kill) resumes to the same `fields.npz`, byte for byte.
#[test]
fn a_compact_clip_resumes_to_the_same_file() {
    if !worm_data_present("a_compact_clip_resumes_to_the_same_file") {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let case = cosserat::case::Case::from_file(&case_file(dir.path())).expect("case");
    let (whole, cut) = (dir.path().join("whole"), dir.path().join("cut"));
    std::fs::create_dir_all(&whole).expect("dir");
    let opts = ClipOptions { journal: true, resume: false, format: OutputFormat::Compact };
    let out = run_clip_to(&case, &whole, opts, |_| {}, |_, _| {}).expect("clip");
    assert!(out.stopped.is_none());
    std::fs::create_dir_all(&cut).expect("dir");
    for entry in std::fs::read_dir(&whole).expect("whole") {
        let p = entry.expect("entry").path();
        std::fs::copy(&p, cut.join(p.file_name().expect("name"))).expect("copy");
    }
    std::fs::remove_file(cut.join(COMPACT_FILE)).expect("npz");
    let journal = std::fs::read_to_string(cut.join(JOURNAL)).expect("journal");
    let head: String = journal.lines().take(8).map(|l| format!("{l}\n")).collect();
    std::fs::write(cut.join(JOURNAL), head + "{\"half a line").expect("journal");
    let resumed = ClipOptions { resume: true, ..opts };
    let out = run_clip_to(&case, &cut, resumed, |_| {}, |_, _| {}).expect("resumed clip");
    assert!(out.stopped.is_none());
    assert_eq!(out.run.reports.len(), FRAMES);
    let read = |d: &Path| std::fs::read(d.join(COMPACT_FILE)).expect("npz");
    assert!(read(&whole) == read(&cut), "the resumed fields.npz differs");
    // A compact run is not resumed as a CSV one.
    let csv = ClipOptions { format: OutputFormat::Csv, ..resumed };
    let Err(e) = run_clip_to(&case, &cut, csv, |_| {}, |_, _| {}) else { panic!("a compact run resumed as CSV") };
    assert!(common::error_chain(&e).contains("--output-format"), "{}", common::error_chain(&e));
}
