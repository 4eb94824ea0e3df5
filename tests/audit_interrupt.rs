//! An unfinished audit gives no verdict on what did not finish. `cosserat audit` stopped by
//! SIGINT while a point of a `does_not_converge` claim is running must not read that point's
//! "stopped" as "the scheme does not converge": REPORT.md is headed "interrupted: N of M
//! claims judged", the claim is *not judged* and counted apart, and run.json says interrupted.
//! (Issue 30: before, such a run reported eq64-1 "reproduced" from "failed: interrupted by a
//! signal".) `--resume` then keeps the spec judged whole and runs the other again.
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Two specs of one claim each on the data of eq. (64): `a` (the paper's set, about 1 s) and
/// `b` (finding (1), 1/λl → 0: 3000 iterations without converging, several seconds).
fn two_specs(dir: &Path) -> [PathBuf; 2] {
    let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/inverse_bend.toml");
    let a = format!(
        r#"title = "interrupt test, fast"
section = "§5.2"

[runs.a_fast]
case = "{case}"

[[claims]]
id = "fast"
where = "§5.2 (64), Fig. 8 left"
statement = "both the position and the curvature can be recovered accurately"
paper = "recovered x on the data"
check = {{ kind = "below", run = "a_fast", metric = "x_err_rel", limit = 1e-3 }}
expect = "reproduced"
"#,
        case = case.display()
    );
    let b = format!(
        r#"title = "interrupt test, slow"
section = "§5.2"

[runs.b_slow]
case = "{case}"
set = {{ "inverse.lambda_l" = 1e30, "solver.max_iterations" = 3000 }}

[[claims]]
id = "slow"
where = "§5.2 (64), finding (1)"
statement = "the proposed algorithm struggles to converge"
paper = "does not converge without the l-term"
check = {{ kind = "does_not_converge", run = "b_slow" }}
expect = "reproduced"
"#,
        case = case.display()
    );
    let paths = [dir.join("a.toml"), dir.join("b.toml")];
    std::fs::write(&paths[0], a).expect("spec a");
    std::fs::write(&paths[1], b).expect("spec b");
    paths
}

/// The first file named `name` under `dir` (any depth).
fn find(dir: &Path, name: &str) -> Option<PathBuf> {
    for e in std::fs::read_dir(dir).ok()?.flatten() {
        let p = e.path();
        if p.is_dir() {
            if let Some(f) = find(&p, name) {
                return Some(f);
            }
        } else if p.file_name().is_some_and(|f| f == name) && p.parent().is_some_and(|d| d.ends_with("a_fast/run")) {
            return Some(p);
        }
    }
    None
}

#[test]
fn an_interrupted_audit_judges_only_what_finished() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let specs = two_specs(tmp.path());
    let out = tmp.path().join("out");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_cosserat"))
        .arg("audit")
        .args(&specs)
        .arg("--out")
        .arg(&out)
        .args(["--quiet", "--jobs", "1"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("audit");
    // the fast point finished (its metrics are written); the slow one is running
    let start = Instant::now();
    while find(tmp.path(), "metrics.json").is_none() {
        assert!(start.elapsed().as_secs() < 120 && child.try_wait().expect("try_wait").is_none(), "no progress");
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(300));
    let _ = std::process::Command::new("kill").args(["-INT", &child.id().to_string()]).status();
    let o = child.wait_with_output().expect("wait");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{stderr}");

    let md = std::fs::read_to_string(out.join("REPORT.md")).expect("REPORT.md");
    let title = md.lines().next().unwrap_or_default();
    assert!(title.ends_with("— interrupted: 1 of 2 claims judged"), "{title}");
    assert!(md.contains("**1 are not judged**"), "{md}");
    let row = |id: &str| md.lines().find(|l| l.starts_with(&format!("| {id} |"))).unwrap_or_default().to_string();
    // the slow point was stopped: its claim is not judged, whatever its status says
    assert!(row("slow").contains("*not judged*"), "{}", row("slow"));
    assert!(!row("slow").contains("reproduced"), "{}", row("slow"));
    assert!(row("slow").contains("1 of 1 points of run `b_slow` stopped"), "{}", row("slow"));
    // the fast point finished: its claim is judged on its own number
    assert!(row("fast").contains("**reproduced**"), "{}", row("fast"));
    let csv = std::fs::read_to_string(out.join("report.csv")).expect("report.csv");
    let slow = csv.lines().find(|l| l.contains(",slow,")).expect("slow row");
    assert!(slow.contains(",not judged,"), "{slow}");
    let manifest = std::fs::read_to_string(out.join("run.json")).expect("run.json");
    assert!(manifest.contains("\"status\": \"interrupted\""), "{manifest}");

    // --resume: spec a was judged whole and is kept (its point is not run again); spec b runs
    assert!(out.join("a/judged.json").is_file() && !out.join("b/judged.json").exists());
    let fast = out.join("a/a_fast/run/metrics.json");
    // (its metrics hold its wall time: a run again would not write the same bytes)
    let before = std::fs::read_to_string(&fast).expect("metrics");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_cosserat"))
        .arg("audit")
        .args(&specs)
        .arg("--out")
        .arg(&out)
        .args(["--quiet", "--jobs", "1", "--resume"])
        .output()
        .expect("resume");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let md = std::fs::read_to_string(out.join("REPORT.md")).expect("REPORT.md");
    assert!(!md.lines().next().unwrap_or_default().contains("interrupted"), "{md}");
    let row = |id: &str| md.lines().find(|l| l.starts_with(&format!("| {id} |"))).unwrap_or_default().to_string();
    assert!(
        row("slow").contains("**reproduced**") && row("slow").contains("not converged after 3000"),
        "{}",
        row("slow")
    );
    assert!(row("fast").contains("**reproduced**"), "{}", row("fast"));
    assert_eq!(std::fs::read_to_string(&fast).expect("metrics"), before, "spec a ran again");
    let manifest = std::fs::read_to_string(out.join("run.json")).expect("run.json");
    assert!(manifest.contains("\"status\": \"complete\""), "{manifest}");
}
