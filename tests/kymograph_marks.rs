//! Lost and flagged frames are marked on a clip's kymographs: a recording (`cosserat synth`, 60
//! frames of 33 nodes) with three frames lost whole (every coordinate NaN, `clip.missing =
//! "nan"`: `frames.csv` says `nodes_tracked = 0`) and one frame with a tracking glitch (four
//! nodes thrown 40 µm sideways: the rod cannot follow, the frame is over the fit-quality gate,
//! `flagged = 1`). Each such frame's column is hatched (lost) or barred (flagged) on every
//! kymograph of the run, and a legend under each title says what the marks mean and how many
//! frames they stand for; a clip with neither has no legend.
use std::path::{Path, PathBuf};

use assert_cmd::Command;
use cosserat::io::npy::{read_npy, write_npy};

const NODES: usize = 33;
const LOST: std::ops::Range<usize> = 20..23;
const GLITCH: usize = 40;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn cosserat() -> Command {
    let mut c = Command::cargo_bin("cosserat").expect("binary");
    c.current_dir(root());
    c
}

/// The batch case on `recording` with `clip.missing = "nan"`, as `dir/NAME.toml`.
fn case_file(dir: &Path, recording: &Path, name: &str) -> PathBuf {
    let text = std::fs::read_to_string(root().join("cases/batch/roll_recording.toml")).expect("batch case");
    let key = format!("file = {:?}\nmissing = \"nan\"", recording.display().to_string());
    let text: String = text
        .lines()
        .map(|l| if l.starts_with("file = ") { key.clone() } else { l.to_string() })
        .collect::<Vec<_>>()
        .join("\n");
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).expect("case");
    path
}

/// Run `case` into `dir/out`; the rows of `frames.csv` as (nodes_tracked, flagged).
fn run(case: &Path, out: &Path) -> Vec<(usize, usize)> {
    let o = cosserat().args(["run", "--quiet", "--out"]).arg(out).arg(case).output().expect("run");
    assert!(o.status.success(), "run: {}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("frames.csv")).expect("frames.csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).expect("column");
    let (tracked, flagged) = (col("nodes_tracked"), col("flagged"));
    lines
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (c[tracked].parse().expect("integer"), c[flagged].parse().expect("integer"))
        })
        .collect()
}

/// The `<polyline>` and `<line>` elements of an SVG drawn in the marks' colour.
fn marks_drawn(svg: &str) -> usize {
    svg.matches("stroke=\"#282828\"").count()
}

#[test]
fn lost_and_flagged_frames_are_marked_on_every_kymograph() {
    let dir = tempfile::tempdir().expect("tempdir");
    let corpus = dir.path().join("corpus");
    let o = cosserat()
        .args(["synth", "--count", "1", "--frames", "60", "--seed", "1", "--out"])
        .arg(&corpus)
        .output()
        .expect("synth");
    assert!(o.status.success(), "synth: {}", String::from_utf8_lossy(&o.stderr));
    let clean = corpus.join("roll_000.npy");
    let mut a = read_npy(&clean).expect("recording");
    for f in LOST {
        a.data[3 * NODES * f..3 * NODES * (f + 1)].fill(f64::NAN);
    }
    for i in 14..18 {
        a.data[3 * (NODES * GLITCH + i)] += 4e-5;
    }
    let marked = dir.path().join("marked.npy");
    write_npy(&marked, &a.shape, &a.data).expect("write");
    std::fs::copy(corpus.join("roll_000.truth.npy"), dir.path().join("marked.truth.npy")).expect("truth sidecar");

    let rows = run(&case_file(dir.path(), &marked, "marked"), &dir.path().join("marked"));
    assert_eq!(rows.len(), 60);
    let lost: Vec<usize> = (0..60).filter(|&f| rows[f].0 == 0).collect();
    let flagged: Vec<usize> = (0..60).filter(|&f| rows[f].1 == 1).collect();
    assert_eq!(lost, LOST.collect::<Vec<_>>(), "frames without a tracked node");
    assert!(flagged.contains(&GLITCH), "the glitch is over the fit gate: flagged {flagged:?}");
    let plural = |n: usize| if n == 1 { "1 frame".to_string() } else { format!("{n} frames") };
    for name in ["kymograph.svg", "omega.svg", "truth.svg"] {
        let svg = std::fs::read_to_string(dir.path().join("marked").join(name)).expect(name);
        assert!(
            svg.contains(&format!("lost: {} without a tracked node", plural(LOST.len()))),
            "{name}: legend of the lost frames"
        );
        assert!(
            svg.contains(&format!("flagged: {} over the fit-quality gate", plural(flagged.len()))),
            "{name}: legend of the flagged"
        );
        // hatching: several lines per lost column and panel (60 frames: one column per frame)
        let panels = if name == "omega.svg" { 3 } else { 2 };
        assert!(marks_drawn(&svg) >= panels * (2 * LOST.len() + 1), "{name}: {} marks", marks_drawn(&svg));
    }

    // the same recording unmarked: no legend, no marks
    let rows = run(&case_file(dir.path(), &clean, "clean"), &dir.path().join("clean"));
    assert!(rows.iter().all(|r| r.0 == NODES && r.1 == 0), "the clean recording is tracked and unflagged");
    let svg = std::fs::read_to_string(dir.path().join("clean/kymograph.svg")).expect("kymograph");
    assert!(!svg.contains("lost:") && !svg.contains("flagged:") && marks_drawn(&svg) == 0);
    if let Ok(keep) = std::env::var("COSSERAT_KEEP_FIGURES") {
        for name in ["kymograph.svg", "omega.svg", "truth.svg"] {
            std::fs::copy(dir.path().join("marked").join(name), Path::new(&keep).join(name)).expect("copy");
        }
    }
}
