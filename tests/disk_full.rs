//! A run on a full disk (a 2 MiB tmpfs mounted for the test): the error names the folder and the
//! free space, the previous result stays in place, a clip's converged frames are kept in its
//! staging folder with `run.json` saying how many, and `--resume` completes the clip byte for
//! byte once there is space; a run with nothing to keep removes its staging folder.
//!
//! Mounting needs root: elsewhere the test prints `DISK-FULL TEST NOT AVAILABLE: <reason>` and
//! returns (with `CI=true` it fails).
mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

fn cosserat(case: &Path, out: &Path, extra: &[&str]) -> (Option<i32>, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_cosserat"))
        .arg("run")
        .arg(case)
        .args(["--quiet", "--out"])
        .arg(out)
        .args(extra)
        .output()
        .expect("run cosserat");
    (o.status.code(), String::from_utf8_lossy(&o.stderr).into_owned())
}

/// A tmpfs of `size` mounted on a fresh folder; unmounted when dropped.
struct Tmpfs {
    dir: PathBuf,
}

impl Tmpfs {
    fn mount(dir: &Path, size: &str) -> Result<Tmpfs, String> {
        std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
        let o = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(dir)
            .output()
            .map_err(|e| format!("cannot run mount: {e}"))?;
        if !o.status.success() {
            return Err(format!("mount -t tmpfs failed: {}", String::from_utf8_lossy(&o.stderr).trim()));
        }
        Ok(Tmpfs { dir: dir.to_path_buf() })
    }

    fn resize(&self, size: &str) {
        let ok = Command::new("mount")
            .args(["-o", &format!("remount,size={size}")])
            .arg(&self.dir)
            .status()
            .is_ok_and(|s| s.success());
        assert!(ok, "remount {size}");
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.dir).status();
    }
}

fn unavailable(reason: &str) {
    eprintln!("DISK-FULL TEST NOT AVAILABLE: {reason}");
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("DISK-FULL TEST NOT AVAILABLE: {reason} (CI=true)");
    }
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap_or_default()).unwrap_or_default()
}

fn lines(path: &Path) -> usize {
    std::fs::read_to_string(path).map(|t| t.lines().count()).unwrap_or(0)
}

/// The staging folders beside `out`.
fn stagings(out: &Path) -> Vec<PathBuf> {
    let name = out.file_name().expect("name").to_string_lossy().into_owned();
    let mut v: Vec<PathBuf> = std::fs::read_dir(out.parent().expect("parent"))
        .expect("dir")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.file_name().is_some_and(|n| n.to_string_lossy().starts_with(&format!(".{name}.staging-"))))
        .collect();
    v.sort();
    v
}

#[test]
fn a_full_disk_keeps_the_previous_folder_and_the_clip_resumes_once_there_is_space() {
    if !common::worm_data_present("disk_full") {
        return;
    }
    let tmp = tempfile::tempdir().expect("tempdir");
    let disk = match Tmpfs::mount(&tmp.path().join("disk"), "2m") {
        Ok(d) => d,
        Err(reason) => return unavailable(&reason),
    };
    let case = tmp.path().join("delta150.toml");
    let text = common::edit(
        &common::case_text_with_data("worm_delta_turn_ld1"),
        "frame_interval_s = \"1/32\"",
        "frame_interval_s = \"1/32\"\nframes = [0, 150]",
    );
    std::fs::write(&case, text).expect("case");
    let whole = tmp.path().join("whole");
    assert_eq!(cosserat(&case, &whole, &[]).0, Some(0));

    // The previous result: a complete run of another case.
    let out = disk.dir.join("o");
    let forward = common::cases_dir().join("timoshenko_5pct.toml");
    assert_eq!(cosserat(&forward, &out, &[]).0, Some(0));
    let before = std::fs::read(out.join("nodes.csv")).expect("nodes");
    // The clip (about 20 MB of CSV and VTK) fills the 2 MiB disk.
    let (code, err) = cosserat(&case, &out, &[]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains(&format!("the disk holding {} is full (", out.display())) && err.contains(" free of 2 MiB)"),
        "{err}"
    );
    assert!(err.contains("No space left on device") && err.contains("is left as it was"), "{err}");
    assert!(err.contains("--resume"), "{err}");
    assert_eq!(json(&out.join("run.json"))["case_name"], "timoshenko_5pct", "the previous folder is in place");
    assert_eq!(std::fs::read(out.join("nodes.csv")).expect("nodes"), before);
    // The staging folder keeps the whole frames; run.json says how many (the journal's lines).
    let kept = stagings(&out);
    assert_eq!(kept.len(), 1, "{kept:?}");
    let m = json(&kept[0].join("run.json"));
    let done = m["frames_done"].as_u64().expect("frames_done") as usize;
    assert_eq!(m["status"], "failed");
    assert!(done > 0 && done == lines(&kept[0].join("resume.jsonl")), "frames_done {done}");
    assert!(lines(&kept[0].join("frames.csv")) > done, "frames.csv holds at least the kept frames");
    assert!(err.contains(&format!("The {done} converged frames are kept in {}", kept[0].display())), "{err}");

    // --resume on the disk still full (not a byte free): it says the space and that the
    // frames already written are kept, and where; it changes nothing.
    let filler = disk.dir.join("filler");
    let (free, _) = cosserat::io::disk::free_bytes(&disk.dir).expect("statvfs");
    let _ = std::fs::write(&filler, vec![1u8; free as usize + (64 << 10)]); // ENOSPC at the end
    let journal = std::fs::read(kept[0].join("resume.jsonl")).expect("journal");
    let (code, err) = cosserat(&case, &out, &["--resume"]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains(&format!("the disk holding {} is full (", out.display())), "{err}");
    assert!(err.contains(" free of 2 MiB)"), "{err}");
    assert!(err.contains(&format!("the {done} frames already written are kept in {}", kept[0].display())), "{err}");
    assert_eq!(stagings(&out), kept, "the frames stay where they were");
    assert_eq!(std::fs::read(kept[0].join("resume.jsonl")).expect("journal"), journal);
    std::fs::remove_file(&filler).expect("rm filler");

    // Space freed: --resume completes the clip, byte for byte the uninterrupted run's files.
    disk.resize("64m");
    let (code, err) = cosserat(&case, &out, &["--resume"]);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(json(&out.join("run.json"))["status"], "complete");
    for f in ["frames.csv", "fields.csv", "curvature.csv", "clip.pvd", "plot.svg", "kymograph.svg"] {
        assert!(std::fs::read(out.join(f)).ok() == std::fs::read(whole.join(f)).ok(), "{f} differs");
    }
    assert!(stagings(&out).is_empty());

    // A run with nothing to keep (a forward case) on a full disk: its staging folder goes.
    let (free, _) = cosserat::io::disk::free_bytes(&disk.dir).expect("statvfs");
    // all but 12 KiB: room for the lock, the staging folder and its run.json, not the results
    std::fs::write(&filler, vec![1u8; free as usize - (12 << 10)]).expect("filler");
    let single = disk.dir.join("s");
    let (code, err) = cosserat(&forward, &single, &[]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("is full") && err.contains("nothing of this run was kept"), "{err}");
    assert!(!single.exists() && stagings(&single).is_empty(), "nothing left behind");
}

/// A batch recording stopped by a full disk: its row says where its converged frames are (its
/// staging folder, which is there), and once there is space the next batch continues them.
#[test]
fn a_batch_on_a_full_disk_says_where_the_frames_are_and_continues_them() {
    if !common::worm_data_present("disk_full") {
        return;
    }
    let tmp = tempfile::tempdir().expect("tempdir");
    let recs = tmp.path().join("recordings");
    let root = env!("CARGO_MANIFEST_DIR");
    let synth = Command::new(env!("CARGO_BIN_EXE_cosserat"))
        .current_dir(root)
        .args(["synth", "--count", "1", "--frames", "200", "--seed", "3", "--out"])
        .arg(&recs)
        .output()
        .expect("synth");
    assert!(synth.status.success(), "{}", String::from_utf8_lossy(&synth.stderr));
    let disk = match Tmpfs::mount(&tmp.path().join("disk"), "2m") {
        Ok(d) => d,
        Err(reason) => return unavailable(&reason),
    };
    let out = disk.dir.join("b");
    let batch = || {
        Command::new(env!("CARGO_BIN_EXE_cosserat"))
            .current_dir(root)
            .args(["batch", "cases/batch/roll_recording.toml", "--quiet", "--output-format", "csv", "--recordings"])
            .arg(&recs)
            .arg("--out")
            .arg(&out)
            .output()
            .expect("batch")
    };
    assert_eq!(batch().status.code(), Some(1));
    let summary = std::fs::read_to_string(out.join("summary.csv")).expect("summary");
    let kept: Vec<PathBuf> = stagings(&out.join("roll_000"));
    assert_eq!(kept.len(), 1, "{summary}");
    let done = json(&kept[0].join("run.json"))["frames_done"].as_u64().expect("frames_done");
    assert!(done > 0 && done as usize == lines(&kept[0].join("resume.jsonl")), "{done}");
    assert!(summary.contains(" free of 2 MiB)"), "{summary}");
    let said = format!("the {done} converged frames are kept in {}: the next batch continues", kept[0].display());
    assert!(summary.contains(&said), "{summary}");
    assert!(!summary.contains("in this folder"), "{summary}");
    disk.resize("64m");
    let o = batch();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(json(&out.join("roll_000/run.json"))["frames_done"], 200);
    let frames = std::fs::read_to_string(out.join("roll_000/frames.csv")).expect("frames");
    assert_eq!(frames.lines().count(), 1 + 200, "the kept frames and the rest, once each");
    assert!(stagings(&out.join("roll_000")).is_empty());
}
