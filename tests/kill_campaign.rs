//! Every kill point survivable (`output::run_folder`, `output::folder_lock`): a clip run, and a
//! `--resume` of an interrupted clip, each killed with SIGKILL at 20 moments drawn at random
//! (seeded) over its duration. After every kill the output folder is either the previous one,
//! byte for byte, or the new one, whole; and `--resume` then completes the clip with the CSVs,
//! VTK files and figures byte for byte those of an uninterrupted run. The counts are printed
//! (`cargo test --release --test kill_campaign -- --nocapture`) and recorded in
//! `docs/results.md`.
mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use cosserat::output::run_folder::sha256_file;

/// Kills per campaign.
const KILLS: usize = 20;
/// The moments are drawn in [0, SPAN × the longest of three runs]: some fall after its end,
/// also when the machine is busier during the campaign than while it was timed.
const SPAN: f64 = 1.3;

/// The tests of this file run one at a time (the campaign's moments are scaled by measured
/// durations, which a second test on the same cores would stretch).
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// The longest wall time of three runs of `make` (which prepares and runs one).
fn longest_duration(mut make: impl FnMut(usize) -> Duration) -> Duration {
    (0..3).map(&mut make).max().unwrap_or_default()
}
/// Frames of the clip: the delta turn cut to its first 150 (a run takes about half a second).
const FRAMES: usize = 150;

fn cosserat(args: &[&str], case: &Path, out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_cosserat"));
    c.arg("run").arg(case).args(["--quiet", "--out"]).arg(out).args(args);
    c.stdout(Stdio::null()).stderr(Stdio::piped());
    c
}

/// Run to the end; the exit status and stderr.
fn run(args: &[&str], case: &Path, out: &Path) -> (Option<i32>, String) {
    let o = cosserat(args, case, out).output().expect("run cosserat");
    (o.status.code(), String::from_utf8_lossy(&o.stderr).into_owned())
}

/// Every file under `dir` (relative path → SHA-256), `run.json` excepted when `manifest` is
/// false; empty if `dir` does not exist.
fn tree(dir: &Path, manifest: bool) -> BTreeMap<String, String> {
    fn walk(root: &Path, dir: &Path, manifest: bool, out: &mut BTreeMap<String, String>) {
        let Ok(entries) = std::fs::read_dir(dir) else { return };
        for e in entries {
            let p = e.expect("entry").path();
            if p.is_dir() {
                walk(root, &p, manifest, out);
            } else {
                let rel = p.strip_prefix(root).expect("under root").display().to_string();
                if manifest || rel != "run.json" {
                    out.insert(rel, sha256_file(&p).expect("hash"));
                }
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, manifest, &mut out);
    out
}

fn status(dir: &Path) -> String {
    let text = std::fs::read_to_string(dir.join("run.json")).unwrap_or_default();
    let m: serde_json::Value = serde_json::from_str(&text).unwrap_or_default();
    m["status"].as_str().unwrap_or_default().to_string()
}

/// What a kill left as the output folder.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Left {
    Previous,
    New,
}

/// The output folder after a kill: the previous one (every file, `run.json` included, as
/// before) or the new one (complete, every file but `run.json` the uninterrupted run's).
fn classify(out: &Path, previous: &BTreeMap<String, String>, whole: &BTreeMap<String, String>, when: &str) -> Left {
    let now = tree(out, true);
    if &now == previous {
        return Left::Previous;
    }
    let mut new = now.clone();
    new.remove("run.json");
    assert!(
        status(out) == "complete" && &new == whole,
        "{when}: {} is neither the previous folder nor the new one whole: status {:?}, {} files (previous {}, whole {})",
        out.display(),
        status(out),
        now.len(),
        previous.len(),
        whole.len()
    );
    Left::New
}

/// Uniform numbers in [0, 1) (splitmix64), seeded.
struct Moments(u64);

impl Moments {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Start `cosserat run` and SIGKILL it after `after`; whether it had ended by itself before.
fn kill_after(args: &[&str], case: &Path, out: &Path, after: Duration) -> bool {
    let mut child = cosserat(args, case, out).stderr(Stdio::null()).spawn().expect("spawn");
    let start = Instant::now();
    while start.elapsed() < after {
        if child.try_wait().expect("try_wait").is_some() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(2).min(after.saturating_sub(start.elapsed())));
    }
    let ended = child.try_wait().expect("try_wait").is_some();
    let _ = child.kill();
    child.wait().expect("wait");
    ended
}

/// Copy the folder `from` to `to` (a fresh previous folder for each kill).
fn copy_dir(from: &Path, to: &Path) {
    let ok = Command::new("cp").arg("-a").arg(from).arg(to).status().expect("cp").success();
    assert!(ok, "cp -a {} {}", from.display(), to.display());
}

/// Nothing but the output folder is left in `parent` for it (no staging folder, no lock).
fn assert_no_leftovers(parent: &Path, name: &str) {
    let left: Vec<String> = std::fs::read_dir(parent)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(&format!(".{name}.")))
        .collect();
    assert!(left.is_empty(), "left beside {name}: {left:?}");
}

#[derive(Default, Debug)]
struct Counts {
    previous: usize,
    new: usize,
    ended_before_kill: usize,
    resumed_identical: usize,
    nothing_to_resume: usize,
}

#[test]
fn sigkill_at_twenty_random_moments_of_a_run_and_of_a_resume() {
    if !common::worm_data_present("kill_campaign") {
        return;
    }
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().expect("tempdir");
    let case = tmp.path().join("delta150.toml");
    let text = common::edit(
        &common::case_text_with_data("worm_delta_turn_ld1"),
        "frame_interval_s = \"1/32\"",
        &format!("frame_interval_s = \"1/32\"\nframes = [0, {FRAMES}]"),
    );
    std::fs::write(&case, text).expect("case");
    // The uninterrupted run, and its duration.
    let whole_dir = tmp.path().join("whole");
    let t_run = longest_duration(|k| {
        let dir = tmp.path().join(format!("whole{k}"));
        let start = Instant::now();
        let (code, err) = run(&[], &case, &dir);
        assert_eq!(code, Some(0), "{err}");
        start.elapsed()
    });
    std::fs::rename(tmp.path().join("whole0"), &whole_dir).expect("rename");
    let whole = tree(&whole_dir, false);
    assert_eq!(tree(&tmp.path().join("whole1"), false), whole, "two uninterrupted runs write the same files");
    // An interrupted run (SIGINT after some frames): the previous folder of the resumes.
    let base = tmp.path().join("base");
    let mut child = cosserat(&[], &case, &base).spawn().expect("spawn");
    let stage = tmp.path().join(format!(".base.staging-{}", child.id()));
    let t0 = Instant::now();
    while std::fs::read_to_string(stage.join("frames.csv")).map(|t| t.lines().count()).unwrap_or(0) < FRAMES / 3 {
        assert!(t0.elapsed() < Duration::from_secs(60), "no progress");
        std::thread::sleep(Duration::from_millis(2));
    }
    let _ = Command::new("kill").args(["-INT", &child.id().to_string()]).status();
    assert_eq!(child.wait().expect("wait").code(), Some(130));
    assert_eq!(status(&base), "interrupted");
    // A complete run of another case: the previous folder of the runs.
    let other = tmp.path().join("other");
    let (code, err) = run(&[], &common::cases_dir().join("timoshenko_5pct.toml"), &other);
    assert_eq!(code, Some(0), "{err}");
    // How long a resume of the interrupted run takes.
    let t_resume = longest_duration(|k| {
        let probe = tmp.path().join(format!("probe{k}"));
        copy_dir(&base, &probe);
        let start = Instant::now();
        assert_eq!(run(&["--resume"], &case, &probe).0, Some(0));
        start.elapsed()
    });

    // another seed for a longer search: COSSERAT_KILL_SEED=7 cargo test --release --test kill_campaign
    let seed = std::env::var("COSSERAT_KILL_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(31);
    let mut moments = Moments(seed);
    let mut report = Vec::new();
    for (what, previous_dir, args, t) in
        [("run", &other, &[][..], t_run), ("resume", &base, &["--resume"][..], t_resume)]
    {
        let mut counts = Counts::default();
        for k in 0..KILLS {
            let name = format!("{what}{k:02}");
            let out = tmp.path().join(&name);
            copy_dir(previous_dir, &out);
            let previous = tree(&out, true);
            let after = t.mul_f64(SPAN * moments.next());
            let when = format!("{what} killed after {:.0} ms", after.as_secs_f64() * 1e3);
            if kill_after(args, &case, &out, after) {
                counts.ended_before_kill += 1;
            }
            match classify(&out, &previous, &whole, &when) {
                Left::Previous => counts.previous += 1,
                Left::New => counts.new += 1,
            }
            let (code, err) = run(&["--resume"], &case, &out);
            match code {
                Some(0) => {
                    assert_eq!(classify(&out, &BTreeMap::new(), &whole, &format!("{when}, resumed")), Left::New);
                    counts.resumed_identical += 1;
                }
                _ if err.contains("complete; nothing to resume") && status(&out) == "complete" => {}
                // killed before the run had written its run.json: the previous folder (another
                // case's) holds nothing to resume, and the refusal leaves it as it was
                _ if err.contains("cannot resume") && what == "run" => {
                    assert_eq!(tree(&out, true), previous, "{when}: a refused resume changes nothing");
                    counts.nothing_to_resume += 1;
                }
                _ => panic!("{when}: --resume failed: {err}"),
            }
            assert_no_leftovers(tmp.path(), &name);
            std::fs::remove_dir_all(&out).expect("clean");
        }
        assert_eq!(counts.previous + counts.new, KILLS, "{what}: {counts:?}");
        report.push(format!(
            "{what} ({:.2} s uninterrupted, longest of 3): {KILLS} SIGKILLs: the previous folder left {}, the new one {} ({} had ended before the kill); --resume then byte-identical {}, nothing to resume {}",
            t.as_secs_f64(),
            counts.previous,
            counts.new,
            counts.ended_before_kill,
            counts.resumed_identical,
            counts.nothing_to_resume
        ));
    }
    eprintln!("SIGKILL campaign, clip of {FRAMES} frames, seed {seed}:\n  {}", report.join("\n  "));
}

/// A second run into a folder being written is refused at once, naming the process; a run
/// killed outright and not yet reaped (a zombie) holds no lock, so `--resume` goes ahead.
#[test]
fn one_writer_per_folder_and_a_zombie_does_not_count() {
    if !common::worm_data_present("kill_campaign") {
        return;
    }
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().expect("tempdir");
    let case = common::cases_dir().join("worm_delta_turn_ld1.toml");
    let out: PathBuf = tmp.path().join("k");
    let mut first = cosserat(&[], &case, &out).spawn().expect("spawn");
    let stage = tmp.path().join(format!(".k.staging-{}", first.id()));
    let t0 = Instant::now();
    while std::fs::read_to_string(stage.join("frames.csv")).map(|t| t.lines().count()).unwrap_or(0) < 10 {
        assert!(t0.elapsed() < Duration::from_secs(60), "no progress");
        std::thread::sleep(Duration::from_millis(2));
    }
    let start = Instant::now();
    let (code, err) = run(&[], &case, &out);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains(&format!("being written by another cosserat process (pid {})", first.id())), "{err}");
    assert!(start.elapsed() < Duration::from_secs(5), "refused at once");
    // SIGKILL, not reaped: the process is a zombie while --resume runs.
    let ok = Command::new("kill").args(["-KILL", &first.id().to_string()]).status().expect("kill").success();
    assert!(ok);
    let zombie =
        |pid: u32| std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|s| s.split(' ').nth(2) == Some("Z"));
    let t0 = Instant::now();
    while !zombie(first.id()) {
        assert!(t0.elapsed() < Duration::from_secs(10), "the killed run did not become a zombie");
        std::thread::sleep(Duration::from_millis(1));
    }
    let (code, err) = run(&["--resume"], &case, &out);
    assert_eq!(code, Some(0), "resume beside a zombie: {err}");
    assert!(err.contains("resuming the run that was stopped"), "{err}");
    assert_eq!(status(&out), "complete");
    first.wait().expect("reap");
}
