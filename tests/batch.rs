//! `cosserat synth` and `cosserat batch` on this machine: four small synthetic recordings and a
//! bad one; the bad one fails alone with its reason in the summary, the others are scored
//! against their truth sidecars, and a second run skips the complete ones.
mod batch_common;
mod common;

use batch_common::{batch_command, corpus, cosserat, summary_without_time, FRAMES, GOOD};

#[test]
fn batch_runs_every_recording_fails_the_bad_one_alone_and_resumes() {
    if !common::worm_data_present("batch") {
        return;
    }
    let tmp = tempfile::tempdir().expect("tempdir");
    let (recs, out) = (tmp.path().join("recordings"), tmp.path().join("out"));
    corpus(&recs);
    let run = || batch_command(&recs, &out, &["--jobs", "2", "--output-format", "csv"]).output().expect("batch");
    let first = run();
    let stderr = String::from_utf8_lossy(&first.stderr);
    assert_eq!(first.status.code(), Some(1), "one bad recording: exit status 1; stderr {stderr}");
    assert!(stderr.contains(&format!("1 of {} recordings failed: bad", GOOD + 1)), "{stderr}");
    let rows = summary_without_time(&out);
    assert_eq!(
        rows[0],
        [
            "recording",
            "folder",
            "status",
            "frames",
            "newton_iterations_per_frame",
            "certificate_max",
            "fit_position_rel_length_max",
            "curvature_err_rel_max",
            "length_m",
            "length_spread_rel",
            "noise_m",
            "lambda_g",
            "reason"
        ]
    );
    assert_eq!(rows.len(), GOOD + 2, "{rows:?}");
    let bad = &rows[1];
    assert_eq!((bad[1].as_str(), bad[2].as_str()), ("bad", "failed"), "{bad:?}");
    assert!(bad[12].contains("bad.csv") && bad[12].contains("not finite"), "reason: {}", bad[12]);
    for r in &rows[2..] {
        assert_eq!(r[2], "ok", "{r:?}");
        assert_eq!(r[3], FRAMES.to_string(), "{r:?}");
        let num = |k: usize| r[k].parse::<f64>().unwrap_or_else(|_| panic!("column {k} of {r:?}"));
        assert!(num(4) >= 1.0 && num(4) < 20.0, "Newton iterations per frame: {r:?}");
        // every frame certified (docs/certificate.md)
        assert!(num(5) > 0.0 && num(5) <= 1e-10, "certificate: {r:?}");
        // in body lengths: below the fit gate's floor (1e-3, solve::fit), as the status says
        assert!(num(6) > 0.0 && num(6) < 1e-3, "fit: {r:?}");
        // the truth sidecar is read: the recovered bending of the noisy recording (noise 1e-7 m,
        // 0.3 % of an element) within 30 % of the truth's in the worst frame
        assert!(num(7) > 0.0 && num(7) < 0.3, "curvature error against the truth: {r:?}");
        // the case's rod.length_m, and no spread: the length was not estimated
        assert_eq!((num(8), r[9].as_str()), (1e-3, ""), "{r:?}");
        // weights = "auto" (the case's): the noise level estimated from the recording (1e-7 m
        // added, over the 33-node mesh's own floor of 0.06-0.09 µm, docs/noise.md N2) and a λg
        // below the case's cap of 1e9
        assert!(num(10) > 0.7e-7 && num(10) < 1.6e-7, "noise estimate: {r:?}");
        assert!(num(11) > 0.0 && num(11) <= 1e9, "λg: {r:?}");
        assert!(r[12].is_empty(), "{r:?}");
        let folder = out.join(&r[1]);
        let manifest = std::fs::read_to_string(folder.join("run.json")).expect("run.json");
        assert!(manifest.contains("\"status\": \"complete\"") && manifest.contains("\"command\": \"batch\""));
        assert!(folder.join("truth.csv").is_file(), "truth.csv in {}", folder.display());
    }
    // Resume: the complete recordings are read back, the bad one is tried (and fails) again.
    let second = run();
    let stdout = String::from_utf8_lossy(&second.stdout);
    assert_eq!(second.status.code(), Some(1));
    assert!(stdout.contains(&format!("{GOOD} already complete, skipped")), "{stdout}");
    assert_eq!(summary_without_time(&out), rows, "a resumed batch writes the same summary");
    // The compact format, a batch's default, is another output: the complete CSV runs are not
    // taken for it, every recording runs again into `fields.npz`, and the summary is the same
    // numbers.
    let compact = batch_command(&recs, &out, &["--jobs", "2"]).output().expect("batch");
    let stdout = String::from_utf8_lossy(&compact.stdout);
    assert_eq!(compact.status.code(), Some(1));
    assert!(stdout.contains("(0 already complete, skipped)"), "{stdout}");
    assert_eq!(summary_without_time(&out), rows, "the compact batch scores the same");
    for r in &rows[2..] {
        let folder = out.join(&r[1]);
        assert!(folder.join("fields.npz").is_file() && !folder.join("fields.csv").exists(), "{}", folder.display());
    }
}

#[test]
fn batch_refuses_a_foreign_output_folder_and_a_case_without_clip() {
    let tmp = tempfile::tempdir().expect("tempdir");
    std::fs::write(tmp.path().join("a.npy"), b"x").expect("write");
    std::fs::write(tmp.path().join("notes.txt"), b"mine").expect("write");
    let out = batch_command(tmp.path(), tmp.path(), &[]).output().expect("batch");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("is not the output folder of a batch"), "{stderr}");
    assert_eq!(std::fs::read(tmp.path().join("notes.txt")).expect("kept"), b"mine");
    let out = cosserat()
        .args(["batch", "cases/timoshenko_5pct.toml", "--out"])
        .arg(tmp.path().join("o"))
        .arg("--recordings")
        .arg(tmp.path())
        .output()
        .expect("batch");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("has no [clip]"), "{stderr}");
    assert!(!tmp.path().join("o").exists(), "nothing written for a refused case");
}

/// SIGINT stops the running recordings at their next frame and starts no other; the summary
/// marks each, and stderr says what was kept (exit status 130).
#[test]
fn an_interrupted_batch_stops_at_the_next_frame_and_says_what_it_kept() {
    if !common::worm_data_present("batch") {
        return;
    }
    let tmp = tempfile::tempdir().expect("tempdir");
    let (recs, out) = (tmp.path().join("recordings"), tmp.path().join("out"));
    let synth = cosserat()
        .args(["synth", "--count", "4", "--frames", "400", "--seed", "5", "--out"])
        .arg(&recs)
        .output()
        .expect("synth");
    assert!(synth.status.success());
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_cosserat"))
        .arg("batch")
        .arg(batch_common::case())
        .arg("--recordings")
        .arg(&recs)
        .arg("--out")
        .arg(&out)
        .args(["--jobs", "2"])
        // progress without a terminal: only the final line within the test's time
        .env("COSSERAT_PROGRESS_INTERVAL_S", "1000")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("batch");
    let frames = out.join(format!(".roll_000.staging-{}", child.id())).join("frames.csv");
    let start = std::time::Instant::now();
    // frames.csv: a header line, then one newline-terminated row per finished frame
    let rows_written = || std::fs::read_to_string(&frames).map(|t| t.matches('\n').count()).unwrap_or(0);
    while rows_written() < 1 + 20 {
        assert!(start.elapsed().as_secs() < 60 && child.try_wait().expect("try_wait").is_none(), "no progress");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    // while it runs, no second batch nor a gather writes into its folder, by any of its names
    let link = tmp.path().join("out-link");
    std::os::unix::fs::symlink(&out, &link).expect("symlink");
    let held = format!("being written by another cosserat process (pid {})", child.id());
    for name in [&out, &link] {
        let second = batch_command(&recs, name, &[]).output().expect("second batch");
        let e = String::from_utf8_lossy(&second.stderr);
        assert!(!second.status.success() && e.contains(&held) && e.contains("before this batch"), "{e}");
        let gather = cosserat().arg("gather").arg(name).output().expect("gather");
        let e = String::from_utf8_lossy(&gather.stderr);
        assert!(!gather.status.success() && e.contains(&held) && e.contains("before this gather"), "{e}");
    }
    assert!(std::fs::symlink_metadata(&link).expect("link").file_type().is_symlink(), "the link is kept");
    let _ = std::process::Command::new("kill").args(["-INT", &child.id().to_string()]).status();
    let o = child.wait_with_output().expect("wait");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted: 0 of 4 recordings complete, 2 stopped at their next frame"), "{stderr}");
    assert!(stderr.contains("2 not started"), "{stderr}");
    // the final progress line counts what was done, not what was stopped
    assert!(stderr.contains("roll_recording batch: 0/4 recordings in"), "{stderr}");
    let rows = summary_without_time(&out);
    let not_started = "not started: a stop was requested before its turn";
    let (waiting, stopped): (Vec<_>, Vec<_>) = rows[1..].iter().partition(|r| r[12] == not_started);
    assert_eq!((stopped.len(), waiting.len()), (2, 2), "{rows:?}");
    for r in stopped {
        assert_eq!(r[2], "interrupted", "{r:?}");
        let n: usize = r[3].parse().expect("frames");
        // the recording watched had 20 frames written; the other one started with it but may
        // still have been choosing its weights (weights = "auto", docs/noise.md N2)
        let least = if r[1] == "roll_000" { 20 } else { 0 };
        assert!((least..400).contains(&n), "{r:?}");
        let m = std::fs::read_to_string(out.join(&r[1]).join("run.json")).expect("run.json");
        assert!(m.contains("\"status\": \"interrupted\"") && m.contains(&format!("\"frames_done\": {n}")), "{m}");
    }
    for r in waiting {
        assert_eq!(r[2], "interrupted", "{r:?}");
        assert!(!out.join(&r[1]).exists(), "no folder for a recording not started");
    }
}

/// `synth` writes a corpus into a folder of its own: a folder that is not empty (an earlier
/// corpus) is refused unless --force, which replaces it whole; its default kymogram is found
/// from any working folder.
#[test]
fn synth_refuses_a_folder_that_is_not_empty_and_finds_its_kymogram_anywhere() {
    if !common::worm_data_present("synth") {
        return;
    }
    let tmp = tempfile::tempdir().expect("tempdir");
    let synth = |count: &str, extra: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_cosserat"))
            .current_dir(tmp.path()) // not the source tree: the default kymogram is found anyway
            .args(["synth", "--out", "corpus", "--frames", "4", "--count", count])
            .args(extra)
            .output()
            .expect("synth")
    };
    let first = synth("3", &[]);
    assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
    let second = synth("2", &[]);
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert_eq!(second.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("is not empty") && stderr.contains("--force"), "{stderr}");
    let forced = synth("2", &["--force"]);
    assert!(forced.status.success(), "{}", String::from_utf8_lossy(&forced.stderr));
    let mut names: Vec<String> = std::fs::read_dir(tmp.path().join("corpus"))
        .expect("corpus")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["corpus.json", "roll_000.npy", "roll_000.truth.npy", "roll_001.npy", "roll_001.truth.npy", "run.json"],
        "the earlier corpus is gone whole"
    );
    let m = std::fs::read_to_string(tmp.path().join("corpus/run.json")).expect("run.json");
    assert!(m.contains("\"command\": \"synth\"") && m.contains("kymogram_omega-turn.npy"), "{m}");
}

/// The names in `dir`, sorted.
fn names(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("dir")
        .map(|e| e.expect("e").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A pid that is no longer alive: a child that has ended (and been reaped).
fn dead_pid() -> u32 {
    let mut child = std::process::Command::new("true").spawn().expect("true");
    let pid = child.id();
    child.wait().expect("wait");
    pid
}

/// What killed runs left in OUT goes at the end of the next batch, for recordings it skips
/// too: a lock file whose holder is dead, the staging folder that held a recording's previous
/// folder after the exchange (the kill "just after a recording's folder is swapped in"), the
/// staging folder of a folder no longer in the batch, a temporary summary. A lock held by a
/// live process (this test) keeps that recording's files until it is released.
#[test]
fn a_batch_removes_what_killed_runs_left_and_nothing_of_a_live_one() {
    if !common::worm_data_present("batch") {
        return;
    }
    let tmp = tempfile::tempdir().expect("tempdir");
    let (recs, out) = (tmp.path().join("recordings"), tmp.path().join("out"));
    corpus(&recs);
    let run = || batch_command(&recs, &out, &["--jobs", "2", "--output-format", "csv"]).output().expect("batch");
    assert_eq!(run().status.code(), Some(1), "the bad recording fails");
    let clean = names(&out);
    let dead = dead_pid();
    // a killed batch's leftovers: roll_000's previous folder after the swap, its lock, a
    // folder of an earlier plan's recording, a temporary summary
    let swapped = out.join(format!(".roll_000.staging-{dead}"));
    std::fs::create_dir(&swapped).expect("mkdir");
    std::fs::copy(out.join("roll_000/run.json"), swapped.join("run.json")).expect("copy");
    std::fs::write(out.join(".roll_000.lock"), dead.to_string()).expect("lock");
    std::fs::create_dir(out.join(format!(".gone.staging-{dead}"))).expect("mkdir");
    std::fs::write(out.join(format!(".summary.csv.{dead}.0.tmp")), "recording,folder\n").expect("tmp");
    // a live process writing roll_001 (this one): its lock and staging folder stay
    let live = cosserat::output::folder_lock::FolderLock::acquire(&out, "roll_001").expect("lock");
    let live_stage = out.join(format!(".roll_001.staging-{}", std::process::id()));
    std::fs::create_dir(&live_stage).expect("mkdir");

    let second = run();
    assert!(String::from_utf8_lossy(&second.stdout).contains("4 already complete, skipped"));
    let mut expected = clean.clone();
    expected.extend([".roll_001.lock".to_string(), live_stage.file_name().unwrap().to_string_lossy().into_owned()]);
    expected.sort();
    assert_eq!(names(&out), expected, "only the live run's files are left");
    drop(live);
    std::fs::remove_dir(&live_stage).expect("rmdir"); // what its run would do at its end
    run();
    assert_eq!(names(&out), clean);
    // `gather` (the end of a Slurm batch, whose tasks clear nothing) clears the same
    std::fs::write(out.join(".roll_002.lock"), dead.to_string()).expect("lock");
    std::fs::create_dir(out.join(format!(".roll_002.staging-{dead}"))).expect("mkdir");
    std::fs::write(out.join(format!(".summary.csv.{dead}.1.tmp")), "recording,folder\n").expect("tmp");
    let gathered = cosserat().arg("gather").arg(&out).output().expect("gather");
    assert_eq!(gathered.status.code(), Some(1), "the bad recording's row: {gathered:?}");
    assert_eq!(names(&out), clean, "gather leaves only the batch's own files");
}

/// summary.csv never describes folders of another run: a batch of a changed case killed
/// after it started leaves no summary (the earlier one, of the other case, is gone) beside
/// the new plan. Then a batch of a case whose recordings now fail (one iteration per frame)
/// keeps each complete folder, its row saying where its own work is; --force replaces them.
#[test]
fn a_batch_never_leaves_a_stale_summary_nor_replaces_complete_recordings() {
    if !common::worm_data_present("batch") {
        return;
    }
    let tmp = tempfile::tempdir().expect("tempdir");
    let (recs, out) = (tmp.path().join("recordings"), tmp.path().join("out"));
    corpus(&recs);
    std::fs::remove_file(recs.join("bad.csv")).expect("rm");
    let args = ["--jobs", "2", "--output-format", "csv"];
    assert_eq!(batch_command(&recs, &out, &args).output().expect("batch").status.code(), Some(0));
    let before: Vec<_> =
        (0..4).map(|k| std::fs::read(out.join(format!("roll_00{k}/fields.csv"))).expect("f")).collect();
    // the case, its clip file (replaced by each recording) absolute so that it runs from here
    let text = std::fs::read_to_string(batch_common::case()).expect("case").replacen(
        "../../data/corpus/roll_000.npy",
        &recs.join("roll_000.npy").display().to_string(),
        1,
    );
    let changed = tmp.path().join("changed.toml");
    let edited = text.replacen("max_iterations = 300", "max_iterations = 299", 1);
    assert_ne!(edited, text);
    std::fs::write(&changed, &edited).expect("case");
    let batch = |case: &std::path::Path, extra: &[&str]| {
        let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_cosserat"));
        c.current_dir(batch_common::root()).arg("batch").arg(case).arg("--recordings").arg(&recs);
        c.arg("--out").arg(&out).arg("--quiet").args(args).args(extra);
        c
    };
    let mut child = batch(&changed, &[]).stderr(std::process::Stdio::null()).spawn().expect("batch");
    let stage = out.join(format!(".roll_000.staging-{}", child.id()));
    let start = std::time::Instant::now();
    while !stage.join("run.json").exists() {
        assert!(start.elapsed().as_secs() < 60 && child.try_wait().expect("try_wait").is_none(), "no progress");
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    child.kill().expect("kill");
    child.wait().expect("wait");
    let plan = std::fs::read_to_string(out.join("batch.json")).expect("plan");
    assert!(plan.contains("changed.toml"), "the new plan");
    assert!(!out.join("summary.csv").exists(), "no summary of the earlier case beside it");

    let failing = tmp.path().join("failing.toml");
    std::fs::write(&failing, text.replacen("max_iterations = 300", "max_iterations = 1", 1)).expect("case");
    let o = batch(&failing, &[]).output().expect("batch");
    assert_eq!(o.status.code(), Some(1), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = summary_without_time(&out);
    for (k, r) in rows[1..].iter().enumerate() {
        assert_eq!(r[2], "failed", "{r:?}");
        let folder = out.join(&r[1]);
        assert!(r[12].contains(&format!("{} keeps its complete run", folder.display())), "{r:?}");
        assert!(
            r[12]
                .contains(&format!("this run's work is kept in {}", out.join(format!(".{}.staging-", r[1])).display())),
            "{r:?}"
        );
        assert_eq!(std::fs::read(folder.join("fields.csv")).expect("fields"), before[k], "{} as it was", r[1]);
    }
    let o = batch(&failing, &["--force"]).output().expect("batch");
    assert_eq!(o.status.code(), Some(1));
    for k in 0..4 {
        let m = std::fs::read_to_string(out.join(format!("roll_00{k}/run.json"))).expect("run.json");
        assert!(m.contains("\"status\": \"failed\""), "--force replaces: {m}");
    }
    assert!(names(&out).iter().all(|n| !n.starts_with('.')), "{:?}", names(&out));
}
