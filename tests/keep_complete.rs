//! A complete result is never replaced by a worse one (`output::run_folder`, `RunFolder::finish`):
//! a run, a clip, a sweep or a batch recording that is interrupted (a real SIGINT) or fails
//! into a folder holding a complete run leaves that folder byte for byte as it was, keeps its
//! own work beside it where `--resume` (or the next batch) continues it, and says so;
//! `--force` replaces.
mod batch_common;
mod common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn cosserat(args: &[&str], out: &Path) -> (Option<i32>, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_cosserat"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .expect("run cosserat");
    (o.status.code(), String::from_utf8_lossy(&o.stderr).into_owned())
}

fn spawn(args: &[&str], out: &Path) -> Child {
    Command::new(env!("CARGO_BIN_EXE_cosserat"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .arg("--out")
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn cosserat")
}

/// SIGINT, then the exit status and stderr.
fn interrupt(child: Child) -> (Option<i32>, String) {
    let ok = Command::new("kill").args(["-INT", &child.id().to_string()]).status().expect("kill").success();
    assert!(ok, "kill -INT");
    let o = child.wait_with_output().expect("wait");
    (o.status.code(), String::from_utf8_lossy(&o.stderr).into_owned())
}

/// Wait until `file` has at least `lines` newline-terminated lines (written by `child`).
fn wait_for_lines(child: &mut Child, file: &Path, lines: usize) {
    let start = Instant::now();
    while std::fs::read_to_string(file).map(|t| t.matches('\n').count()).unwrap_or(0) < lines {
        assert!(child.try_wait().expect("try_wait").is_none(), "ended before it was interrupted");
        assert!(start.elapsed() < Duration::from_secs(120), "no progress in {}", file.display());
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn staging(target: &Path, pid: u32) -> PathBuf {
    let name = target.file_name().expect("name").to_string_lossy().into_owned();
    target.with_file_name(format!(".{name}.staging-{pid}"))
}

/// Every file under `dir` with its bytes.
fn tree(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let p = e.expect("entry").path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((p.strip_prefix(dir).expect("under").to_path_buf(), std::fs::read(&p).expect("read")));
            }
        }
    }
    out.sort();
    out
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap_or_default()).unwrap_or_default()
}

/// The names in `dir`.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("dir")
        .map(|e| e.expect("e").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

const CLIP: &str = "cases/worm_delta_turn_ld1.toml";

/// A single run (the dynamic cantilever) interrupted over its own complete run: the folder is
/// as it was, nothing is left beside it (a single run keeps no partial result); a failed run
/// (3 iterations of an inverse case) likewise, and with --force it replaces the folder.
#[test]
fn a_single_run_interrupted_or_failing_leaves_the_complete_folder() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("dyn");
    assert_eq!(cosserat(&["run", "cases/cantilever_dynamic.toml", "--quiet"], &out).0, Some(0));
    let before = tree(&out);
    let mut child = spawn(&["run", "cases/cantilever_dynamic.toml", "--quiet"], &out);
    let stage = staging(&out, child.id());
    wait_for_lines(&mut child, &stage.join("run.json"), 2);
    let (code, err) = interrupt(child);
    assert_eq!(code, Some(130), "{err}");
    assert!(err.contains(&format!("{} keeps its complete run", out.display())), "{err}");
    assert!(err.contains("nothing of this run was kept"), "{err}");
    assert_eq!(tree(&out), before, "the complete run, byte for byte");
    assert_eq!(names(tmp.path()), ["dyn"], "nothing left beside it");

    let inv = tmp.path().join("inv");
    assert_eq!(cosserat(&["run", "cases/inverse_bend_twist_newton.toml", "--quiet"], &inv).0, Some(0));
    let before = tree(&inv);
    let text = common::edit(&common::case_text("inverse_bend_twist"), "max_iterations = 1000", "max_iterations = 3");
    let short = tmp.path().join("short.toml");
    std::fs::write(&short, text).expect("case");
    let short = short.to_string_lossy().into_owned();
    let (code, err) = cosserat(&["run", &short, "--quiet"], &inv);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("did not converge after 3 iterations") && err.contains("keeps its complete run"), "{err}");
    assert_eq!(tree(&inv), before);
    assert_eq!(names(tmp.path()), ["dyn", "inv", "short.toml"]);
    let (code, err) = cosserat(&["run", &short, "--quiet", "--force"], &inv);
    assert_eq!(code, Some(1), "{err}");
    assert_eq!(json(&inv.join("run.json"))["status"], "failed", "--force replaces");
    let history = std::fs::read_to_string(inv.join("inverse_history.csv")).expect("history");
    assert_eq!(history.lines().count(), 4, "3 iterations of the failed run");
}

/// A clip interrupted over its own complete run: the folder is as it was; the converged frames
/// stay in the staging folder (run.json there: interrupted), which --resume continues to the
/// same files; the message says where they are.
#[test]
fn an_interrupted_clip_keeps_the_complete_folder_and_resumes_beside_it() {
    if !common::worm_data_present("keep_complete") {
        return;
    }
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("clip");
    assert_eq!(cosserat(&["run", CLIP, "--quiet"], &out).0, Some(0));
    let before = tree(&out);
    let mut child = spawn(&["run", CLIP, "--quiet"], &out);
    let stage = staging(&out, child.id());
    wait_for_lines(&mut child, &stage.join("frames.csv"), 1 + 20);
    let (code, err) = interrupt(child);
    assert_eq!(code, Some(130), "{err}");
    assert_eq!(tree(&out), before, "the complete clip, byte for byte");
    let m = json(&stage.join("run.json"));
    let done = m["frames_done"].as_u64().expect("frames_done");
    assert!(m["status"] == "interrupted" && done >= 20, "{m}");
    assert!(
        err.contains(&format!("this run's work is kept in {}", stage.display())) && err.contains("--resume"),
        "{err}"
    );
    let (code, err) = cosserat(&["run", CLIP, "--quiet", "--resume"], &out);
    assert_eq!(code, Some(0), "{err}");
    assert!(err.contains("resuming the run that was stopped"), "{err}");
    assert!(!stage.exists());
    let after = tree(&out);
    for f in ["frames.csv", "fields.csv", "curvature.csv", "clip.pvd"] {
        let get = |t: &[(PathBuf, Vec<u8>)]| t.iter().find(|(p, _)| p == Path::new(f)).map(|(_, b)| b.clone());
        assert!(get(&after) == get(&before), "{f}: the resumed clip is the uninterrupted one");
    }
}

/// A sweep whose points now fail (1 iteration) into the folder of a complete sweep: the folder
/// stays, the new sweep's points and summary are beside it and the message says where;
/// --force replaces.
#[test]
fn a_failing_sweep_keeps_the_complete_sweep() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("sweep");
    let case = "cases/timoshenko_5pct.toml";
    let (code, err) = cosserat(&["sweep", case, "--quiet", "--set", "elements=10,20"], &out);
    assert_eq!(code, Some(0), "{err}");
    let before = tree(&out);
    let (code, err) = cosserat(&["sweep", case, "--quiet", "--set", "max_iterations=1,2"], &out);
    assert_eq!(code, Some(1), "{err}");
    assert_eq!(tree(&out), before, "the complete sweep, byte for byte");
    let beside: Vec<String> = names(tmp.path()).into_iter().filter(|n| n.starts_with(".sweep.staging-")).collect();
    assert_eq!(beside.len(), 1, "{beside:?}");
    let kept = tmp.path().join(&beside[0]);
    assert!(err.contains(&format!("this run's work is kept in {}", kept.display())), "{err}");
    assert_eq!(json(&kept.join("run.json"))["status"], "failed");
    let summary = std::fs::read_to_string(kept.join("summary.csv")).expect("the new sweep's summary");
    assert!(summary.starts_with("max_iterations,status"), "{summary}");
    let (code, _) = cosserat(&["sweep", case, "--quiet", "--force", "--set", "max_iterations=1,2"], &out);
    assert_eq!(code, Some(1));
    assert_eq!(json(&out.join("run.json"))["status"], "failed", "--force replaces");
    assert_eq!(names(tmp.path()), ["sweep"], "and the kept sweep is gone with the run that replaced it");
}
