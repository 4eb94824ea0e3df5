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
    cosserat()
        .args(["run", "--help"])
        .assert()
        .success()
        .stdout(predicate::str::contains("--engine <ENGINE>").and(predicate::str::contains("freefem")));
}

#[test]
fn list_shows_every_case_with_its_description() {
    cosserat().arg("list").assert().success().stdout(
        predicate::str::contains("timoshenko_5pct")
            .and(predicate::str::contains("timoshenko_10pct"))
            .and(predicate::str::contains("cantilever_dynamic"))
            .and(predicate::str::contains("§5.1")),
    );
}

#[test]
fn run_writes_csv_metrics_and_plot() {
    let dir = tempfile::tempdir().expect("tempdir");
    cosserat()
        .args(["run", "cases/timoshenko_5pct.toml", "--quiet", "--out"])
        .arg(dir.path())
        .assert()
        .success()
        .stdout(predicate::str::contains("timoshenko_5pct [rust]"));
    let nodes = std::fs::read_to_string(dir.path().join("nodes.csv")).expect("nodes.csv");
    assert!(nodes.starts_with("s_m,x_m,y_m,z_m,ux_m,uy_m,uz_m,alpha_rad,beta_rad,gamma_rad\n"));
    assert_eq!(nodes.lines().count(), 102);
    let m: std::collections::BTreeMap<String, f64> =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("metrics.json")).expect("metrics"))
            .expect("json");
    assert!((m["tip_y_m"] / -4.93e-5 - 1.0).abs() < 1e-3, "{m:?}");
    assert!(std::fs::read_to_string(dir.path().join("plot.svg")).expect("svg").contains("<svg"));
    assert!(dir.path().join("history.csv").is_file() && dir.path().join("curvature.csv").is_file());
}

#[test]
fn bad_case_is_a_clear_error_not_a_panic() {
    let dir = tempfile::tempdir().expect("tempdir");
    let bad = dir.path().join("bad.toml");
    std::fs::write(
        &bad,
        common::edit(&common::case_text("timoshenko_5pct"), "young_modulus_pa = 1.1e5", "young_modulus_pa = -1.1e5"),
    )
    .expect("write");
    cosserat().arg("run").arg(&bad).assert().code(1).stderr(
        predicate::str::contains("material.young_modulus_pa")
            .and(predicate::str::contains("must be > 0"))
            .and(predicate::str::contains("panicked").not()),
    );
    // A length no double-precision rod can have is blamed, not the loads that then fail.
    std::fs::write(&bad, common::edit(&common::case_text("timoshenko_5pct"), "length_m = \"L0\"", "length_m = 1e200"))
        .expect("write");
    cosserat().arg("run").arg(&bad).assert().code(1).stderr(
        predicate::str::contains("rod.length_m")
            .and(predicate::str::contains("radius of gyration"))
            .and(predicate::str::contains("loads").not()),
    );
    cosserat()
        .args(["run", "cases/does_not_exist.toml"])
        .assert()
        .code(1)
        .stderr(predicate::str::contains("cannot read case file"));
    cosserat().args(["run", "cases/timoshenko_5pct.toml", "--engine", "abaqus"]).assert().code(2);
}

#[test]
fn modes_prints_the_first_bending_frequency() {
    cosserat()
        .args(["modes", "cases/cantilever_dynamic.toml", "--count", "2"])
        .assert()
        .success()
        .stdout(predicate::str::contains("206.78"));
}

#[test]
fn compare_runs_both_engines() {
    if std::env::var_os("COSSERAT_SKIP_FREEFEM").is_some() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    cosserat().args(["compare", "cases/timoshenko_5pct.toml", "--out"]).arg(dir.path()).assert().success().stdout(
        predicate::str::contains("nodewise_rel_diff_displacement")
            .and(predicate::str::contains("PASS"))
            .and(predicate::str::contains("FAIL").not()),
    );
    assert!(dir.path().join("freefem/metrics.json").is_file() && dir.path().join("rust/metrics.json").is_file());
}

#[test]
fn inverse_run_writes_frame_controls_history_and_plot() {
    let dir = tempfile::tempdir().expect("tempdir");
    // the paper's fixed point at its stopping rule is stalled (docs/certificate.md C4): exit 1,
    // the last iterate kept, run.json saying stalled with the certificate
    let stalled_dir = tempfile::tempdir().expect("tempdir");
    let stalled = stalled_dir.path().join("stalled");
    cosserat()
        .args(["run", "cases/inverse_bend_twist.toml", "--quiet", "--out"])
        .arg(&stalled)
        .assert()
        .code(1)
        .stderr(predicate::str::contains("stalled after").and(predicate::str::contains("certificate")));
    let manifest = std::fs::read_to_string(stalled.join("run.json")).expect("run.json");
    assert!(manifest.contains("\"status\": \"stalled\"") && manifest.contains("\"tolerance\": 1e-10"), "{manifest}");
    assert!(stalled.join("inverse_nodes.csv").is_file());
    cosserat()
        .args(["run", "cases/inverse_bend_twist_newton.toml", "--quiet", "--out"])
        .arg(dir.path())
        .assert()
        .success();
    let nodes = std::fs::read_to_string(dir.path().join("inverse_nodes.csv")).expect("inverse_nodes.csv");
    let header = nodes.lines().next().expect("header");
    for col in ["alpha_rad", "d1_x", "d3_z", "f_x_n_per_m", "l_z_nm_per_m", "data_x_m"] {
        assert!(header.split(',').any(|c| c == col), "{col} missing in {header}");
    }
    assert_eq!(nodes.lines().count(), 102);
    // Directors are orthonormal: check d1·d3 = 0 and |d2| = 1 on every row.
    let cols: Vec<&str> = header.split(',').collect();
    let at = |row: &[f64], name: &str| row[cols.iter().position(|c| *c == name).expect("column")];
    for line in nodes.lines().skip(1) {
        let row: Vec<f64> = line.split(',').map(|v| v.parse().expect("number")).collect();
        let dot13 = at(&row, "d1_x") * at(&row, "d3_x")
            + at(&row, "d1_y") * at(&row, "d3_y")
            + at(&row, "d1_z") * at(&row, "d3_z");
        let n2 = at(&row, "d2_x").powi(2) + at(&row, "d2_y").powi(2) + at(&row, "d2_z").powi(2);
        assert!(dot13.abs() < 1e-14 && (n2 - 1.0).abs() < 1e-14);
    }
    let hist = std::fs::read_to_string(dir.path().join("inverse_history.csv")).expect("history");
    assert!(hist.starts_with("iteration,rel_change,x_err_rel,tangent_misfit_m05,j_tracking,j_force,j_torque,j_shear,j_bending,j_angular,j_total,newton_residual_rel,certificate,kappa_err_rel,kappa_err_rel_inner\n"));
    assert!(dir.path().join("data.csv").is_file() && dir.path().join("inverse_curvature.csv").is_file());
    let m: std::collections::BTreeMap<String, f64> =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("metrics.json")).expect("metrics"))
            .expect("json");
    assert!(m["x_err_rel"] < 2e-5 && m["kappa_err_rel_inner"] < 1e-2, "{m:?}");
    assert!(m["certificate"] <= 1e-14, "{m:?}");
    assert_eq!(m["iterations"] as usize + 1, hist.lines().count());
    assert!(std::fs::read_to_string(dir.path().join("plot.svg")).expect("svg").contains("recovered torque"));
}

#[test]
fn sweep_writes_one_folder_per_run_a_summary_and_a_convergence_plot() {
    let dir = tempfile::tempdir().expect("tempdir");
    cosserat()
        .args([
            "sweep",
            "cases/inverse_bend_twist.toml",
            "--quiet",
            "--set",
            "lambda_l=1e-6,1",
            "--set",
            "tolerance=1e-3",
            "--set",
            // a fixed point stopped at a change of 1e-3 leaves a certificate ~1e-5: held to that
            "certificate_tolerance=1e-4",
            "--out",
        ])
        .arg(dir.path())
        .assert()
        .success()
        .stdout(predicate::str::contains("2 runs, 0 failed or not converged"));
    let summary = std::fs::read_to_string(dir.path().join("summary.csv")).expect("summary");
    let lines: Vec<&str> = summary.lines().collect();
    assert!(
        lines[0].starts_with("lambda_l,tolerance,certificate_tolerance,status,iterations,certificate,x_err_rel"),
        "{}",
        lines[0]
    );
    assert_eq!(lines.len(), 3);
    assert!(lines[1].starts_with("1e-6,1e-3,1e-4,ok,") && lines[2].starts_with("1,1e-3,1e-4,ok,"), "{summary}");
    assert!(dir.path().join("lambda_l=1e-6_tolerance=1e-3_certificate_tolerance=1e-4/inverse_history.csv").is_file());
    assert!(std::fs::read_to_string(dir.path().join("convergence.svg")).expect("svg").contains("<svg"));
    // A run that hits its iteration limit is a failed row naming frame, iteration and change.
    cosserat()
        .args(["sweep", "cases/inverse_bend_twist.toml", "--quiet", "--set", "max_iterations=3", "--out"])
        .arg(dir.path().join("fail"))
        .assert()
        .code(1)
        .stderr(predicate::str::contains("frame 0 did not converge after 3 iterations"));
    let summary = std::fs::read_to_string(dir.path().join("fail/summary.csv")).expect("summary");
    assert!(summary.lines().nth(1).expect("row").starts_with("3,not_converged,3,"), "{summary}");
    // The last iterate is kept, labelled, and its history plotted.
    let manifest = std::fs::read_to_string(dir.path().join("fail/max_iterations=3/run.json")).expect("run.json");
    assert!(manifest.contains("\"status\": \"failed\"") && manifest.contains("did not converge"), "{manifest}");
    let sweep = std::fs::read_to_string(dir.path().join("fail/run.json")).expect("sweep run.json");
    assert!(sweep.contains("\"status\": \"failed\"") && sweep.contains("1 of 1 points"), "{sweep}");
    assert_eq!(
        std::fs::read_to_string(dir.path().join("fail/max_iterations=3/inverse_history.csv"))
            .expect("history")
            .lines()
            .count(),
        4
    );
    assert!(dir.path().join("fail/convergence.svg").is_file());
    cosserat()
        .args(["sweep", "cases/inverse_bend_twist.toml", "--set", "lambda_q=1"])
        .assert()
        .code(1)
        .stderr(predicate::str::contains("unknown parameter"));
}

#[test]
fn compare_on_a_clip_checks_consecutive_frames_in_both_engines() {
    if !common::worm_data_present("compare_on_a_clip_checks_consecutive_frames_in_both_engines")
        || !common::freefem_required()
    {
        return;
    }
    cosserat()
        .args(["compare", "cases/worm_roll_3d.toml", "--frames", "0"])
        .assert()
        .failure()
        .stderr(predicate::str::contains("expected a number of frames >= 1 or `all`"));
    let dir = tempfile::tempdir().expect("tempdir");
    cosserat()
        .args(["compare", "cases/worm_roll_3d.toml", "--frames", "2", "--out"])
        .arg(dir.path())
        .assert()
        .success()
        .stdout(
            predicate::str::contains("clip frames 0-1 (2 frames)")
                .and(predicate::str::contains("frames_solved"))
                .and(predicate::str::contains("per frame: rust"))
                .and(predicate::str::contains("FAIL").not()),
        )
        // FreeFEM's frames as it runs (stderr is not a terminal here: the final line)
        .stderr(predicate::str::contains("worm_roll_3d FreeFEM: 2/2 frames in"));
    let frames = std::fs::read_to_string(dir.path().join("compare_frames.csv")).expect("compare_frames.csv");
    assert_eq!(frames.lines().count(), 3, "{frames}");
    assert!(std::fs::read_to_string(dir.path().join("compare.csv")).expect("compare.csv").contains("derived"));
}

#[test]
fn compare_refuses_frames_on_a_case_without_a_clip() {
    cosserat()
        .args(["compare", "cases/timoshenko_5pct.toml", "--frames", "3", "--out"])
        .arg(tempfile::tempdir().expect("tempdir").path())
        .assert()
        .failure()
        .stderr(predicate::str::contains("`--frames` applies to clips only"));
}

/// `run --engine freefem` on a clip is refused before anything is prepared: the message names
/// `compare`, which runs FreeFEM's clip script, and no output folder (not even a failed one) is
/// left behind.
#[test]
fn run_refuses_a_clip_in_freefem_before_it_makes_a_folder() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("clip");
    cosserat()
        .args(["run", "--engine", "freefem", "cases/worm_delta_turn_ld1.toml", "--out"])
        .arg(&out)
        .assert()
        .failure()
        .stderr(
            predicate::str::contains("cosserat compare CASE --frames N")
                .and(predicate::str::contains("running FreeFEM").not()),
        );
    assert!(!out.exists(), "a refused run left {}", out.display());
    let left: Vec<_> = std::fs::read_dir(dir.path()).expect("dir").collect();
    assert!(left.is_empty(), "a refused run left {left:?}");
}

/// Without a terminal (stderr to a pipe: a log file, nohup, a Slurm task) a long command prints
/// a progress line every interval (10 s; 0.1 s here) with done/total, rate and time left, and a
/// final line; `--quiet` prints none.
#[test]
fn progress_without_a_terminal_is_a_line_every_interval_and_a_final_line() {
    if !common::worm_data_present("progress_without_a_terminal_is_a_line_every_interval_and_a_final_line") {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let out = cosserat()
        .env("COSSERAT_PROGRESS_INTERVAL_S", "0.1")
        .args(["run", "cases/worm_delta_turn_ld1.toml", "--out"])
        .arg(dir.path().join("clip"))
        .output()
        .expect("run");
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = stderr.lines().filter(|l| l.starts_with("worm_delta_turn_ld1 [rust]: ")).collect();
    assert!(lines.len() >= 3, "{stderr}");
    // a line before the first frame ends says only the time elapsed (a loaded machine)
    assert!(lines.iter().any(|l| l.contains("/300 frames (") && l.contains(" frames/s, ETA ")), "{stderr}");
    assert!(lines.last().is_some_and(|l| l.contains("300/300 frames in ")), "{stderr}");
    let quiet = cosserat()
        .env("COSSERAT_PROGRESS_INTERVAL_S", "0.1")
        .args(["run", "cases/worm_delta_turn_ld1.toml", "--quiet", "--out"])
        .arg(dir.path().join("quiet"))
        .output()
        .expect("run");
    assert!(quiet.status.success() && quiet.stderr.is_empty(), "{}", String::from_utf8_lossy(&quiet.stderr));
}

/// `run --engine freefem` shows FreeFEM's time steps as the script writes them: without a
/// terminal, a line every interval and a final line with the count.
#[test]
fn a_freefem_dynamic_run_shows_its_time_steps() {
    let dir = tempfile::tempdir().expect("tempdir");
    // the dynamic cantilever cut to its first 40 of 1000 steps (the same time step)
    let case = std::fs::read_to_string("cases/cantilever_dynamic.toml").expect("case");
    let case = case.replace("end_s = 0.06", "end_s = 0.0024").replace("steps = 1000", "steps = 40");
    assert!(case.contains("steps = 40") && case.contains("end_s = 0.0024"), "{case}");
    let path = dir.path().join("forty_steps.toml");
    std::fs::write(&path, case).expect("write case");
    let out = cosserat()
        .env("COSSERAT_PROGRESS_INTERVAL_S", "0.1")
        .args(["run", "--engine", "freefem", "--out"])
        .arg(dir.path().join("ff"))
        .arg(&path)
        .output()
        .expect("run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| l.starts_with("forty_steps [freefem]: ")).collect();
    assert!(lines.last().is_some_and(|l| l.contains("40/40 time steps in ")), "{stderr}");
}

/// The flags of a piece of README text: `--name` at the start of a word (after `[` or `(`),
/// up to `=` or the first character that cannot be in a flag's name.
fn flags_in(text: &str) -> Vec<String> {
    text.split_whitespace()
        .filter_map(|w| {
            let w = w.trim_start_matches(['[', '(']);
            let name: String =
                w.strip_prefix("--")?.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '-').collect();
            (!name.is_empty()).then(|| format!("--{name}"))
        })
        .collect()
}

/// Does the help text `text` name the flag `flag` as a whole word (`--out`, not the start of
/// `--output-format`)?
fn has_flag(text: &str, flag: &str) -> bool {
    text.match_indices(flag)
        .any(|(i, _)| !text[i + flag.len()..].starts_with(|c: char| c.is_ascii_alphanumeric() || c == '-'))
}

/// The README and the `--help` texts agree: every flag on a code line or in a code span that
/// runs `cosserat SUB` is in `cosserat SUB --help`, and every other flag the README names (in
/// prose) is in the help of some command.
#[test]
fn every_flag_the_readme_names_is_in_the_help() {
    let readme =
        std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).expect("README");
    let subs = ["run", "compare", "sweep", "audit", "batch", "batch-task", "gather", "synth", "list", "modes"];
    let help: std::collections::BTreeMap<&str, String> = subs
        .iter()
        .map(|s| {
            (*s, String::from_utf8_lossy(&cosserat().args([s, "--help"]).output().expect("help").stdout).into_owned())
        })
        .collect();
    // the lines of fenced code blocks, and the inline code spans of the prose (which may wrap)
    let (mut pieces, mut prose, mut block) = (Vec::new(), String::new(), false);
    for line in readme.lines() {
        if line.trim_start().starts_with("```") {
            block = !block;
        } else if block {
            pieces.push(line.to_string());
        } else {
            prose += line;
            prose.push('\n');
        }
    }
    pieces.extend(prose.split('`').skip(1).step_by(2).map(|s| s.replace('\n', " ")));
    let external =
        ["cargo", "bash", "sbatch", "squeue", "scripts/", "python", "pip", "ulimit", "target/release/cosserat gather"];
    let mut checked = 0;
    for piece in &pieces {
        let code = piece.split('#').next().unwrap_or("").trim(); // a shell comment is prose
        if let Some(at) = code.find("cosserat ").or_else(|| code.find("target/release/cosserat ")) {
            let rest = &code[at..];
            let rest = rest.split_once("cosserat ").map(|(_, r)| r).unwrap_or("");
            let sub = rest.split_whitespace().next().unwrap_or("");
            let Some(text) = help.get(sub) else { continue };
            for flag in flags_in(rest) {
                assert!(has_flag(text, &flag), "README: `{piece}`: `cosserat {sub} --help` has no {flag}");
                checked += 1;
            }
        } else if !external.iter().any(|e| code.starts_with(e)) {
            for flag in flags_in(code).into_iter().filter(|f| f != "--help") {
                assert!(help.values().any(|t| has_flag(t, &flag)), "README: `{piece}`: no command has {flag}");
                checked += 1;
            }
        }
    }
    assert!(checked > 30, "only {checked} flags found in the README");
}

/// `--jobs` is bounded: 0 and more than `MAX_JOBS` are refused before anything runs, with the
/// range in the message (a batch once started 5,000 threads for `--jobs 100000`).
#[test]
fn jobs_outside_one_to_the_maximum_are_refused() {
    let max = cosserat::jobs::MAX_JOBS;
    let dir = tempfile::tempdir().expect("tempdir");
    for given in ["0".to_string(), (max + 1).to_string(), "100000".into(), "many".into()] {
        for args in [
            vec!["sweep", "cases/cantilever_dynamic.toml", "--set", "solver.dt_s=[1e-3]", "--jobs", &given],
            vec!["audit", "--quick", "--jobs", &given],
            vec!["batch", "cases/batch/roll_recording.toml", "--recordings", "data", "--jobs", &given],
        ] {
            let out = dir.path().join("out");
            let mut c = cosserat();
            c.args(&args).arg("--out").arg(&out);
            c.assert().code(2).stderr(predicate::str::contains(format!(
                "expected a number of parallel runs from 1 to {max}, got `{given}`"
            )));
            assert!(!out.exists(), "{args:?}: nothing is written");
        }
    }
}

/// Messages of everyday mistakes: `-` is the standard input; a case given to `audit` or
/// `noise-study` is named a case; a tiny memory limit keeps its digits; a huge generated
/// expression gives a line, not the expression.
#[test]
fn everyday_mistakes_get_messages_that_say_what_happened() {
    let dir = tempfile::tempdir().expect("tempdir");
    let case = std::fs::read_to_string("cases/timoshenko_5pct.toml").expect("case");
    let out = dir.path().join("stdin");
    cosserat().args(["run", "-", "--quiet", "--out"]).arg(&out).write_stdin(case.clone()).assert().success();
    assert!(out.join("run.json").is_file(), "`run -` reads the case from the standard input");

    for (command, what) in [("audit", "not an audit spec"), ("noise-study", "not a noise study spec")] {
        cosserat()
            .args([command, "cases/timoshenko_5pct.toml", "--out"])
            .arg(dir.path().join(command))
            .assert()
            .failure()
            .stderr(predicate::str::contains(format!("this is a case file ([rod], [solver]), {what}")));
    }

    cosserat()
        .args(["run", "cases/cantilever_dynamic.toml", "--max-memory-gib", "0.001", "--out"])
        .arg(dir.path().join("mem"))
        .assert()
        .failure()
        .stderr(predicate::str::contains("above the limit of 1.00e-3 GiB"));

    let deep = format!("{}1{}", "(".repeat(100_000), ")".repeat(99_999));
    let text = case.replacen("[constants]\n", &format!("[constants]\nDEEP = \"{deep}\"\n"), 1);
    assert_ne!(text, case);
    let file = dir.path().join("deep.toml");
    std::fs::write(&file, text).expect("case");
    let out = cosserat().arg("run").arg(&file).arg("--out").arg(dir.path().join("deep")).output().expect("run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(stderr.contains("(an expression of 200000 characters)") && stderr.contains("nested more than"), "{stderr}");
    assert!(stderr.len() < 1000, "a line, not the expression: {} bytes", stderr.len());
}

/// `--out` given as a symbolic link is written through it (the link is kept, the folder it
/// names holds the run), and a run into the folder by its real name finds the link's run.
#[test]
fn an_output_folder_given_as_a_symlink_is_written_through_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (real, link) = (dir.path().join("real"), dir.path().join("link"));
    std::fs::create_dir(&real).expect("folder");
    std::os::unix::fs::symlink(&real, &link).expect("symlink");
    cosserat().args(["run", "cases/timoshenko_5pct.toml", "--quiet", "--out"]).arg(&link).assert().success();
    assert!(std::fs::symlink_metadata(&link).expect("link").file_type().is_symlink(), "the link is kept");
    assert!(real.join("run.json").is_file(), "the run is in the folder the link names");
    // the same folder by its other name: a run of its own, replaced as any earlier run is
    cosserat().args(["run", "cases/timoshenko_5pct.toml", "--quiet", "--out"]).arg(&real).assert().success();
    assert!(link.join("run.json").is_file());
}
