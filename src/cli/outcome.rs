//! What a command that ended early kept, in words for stderr: a run stopped by a full disk,
//! an interrupted sweep or audit (the batch's is `super::interrupted_summary`); and what the
//! progress of a run counts.
use std::path::Path;

use cosserat::case::Case;
use cosserat::engine::metrics::Metric;
use cosserat::engine::Engine;
use cosserat::output::run_folder::{Manifest, Status};
use cosserat::solve::Outcome;

/// What a run stopped by a full disk left, and how to go on.
pub fn full_disk_note(end: &cosserat::jobs::job::JobEnd, case: &Path, dir: &Path) -> String {
    let previous = format!("\n{} is left as it was", dir.display());
    match (&end.disk_full, end.frames) {
        (Some(Some(staging)), Some((n, _))) => format!(
            "{previous}. The {n} converged frames are kept in {}: free some space, then `cosserat run {} --out {} --resume` continues from them (or remove that folder to free its space)",
            staging.display(),
            case.display(),
            dir.display()
        ),
        _ => format!("{previous}; nothing of this run was kept (its staging folder is removed)"),
    }
}

/// What an interrupted sweep kept: every point counted once by how it ended (complete, stalled,
/// failed or not converged, stopped at its next iteration or frame with a clip's converged
/// frames, not started).
pub fn sweep_interrupted_summary(rows: &[cosserat::jobs::sweep::SummaryRow], target: &Path) -> String {
    use cosserat::jobs::sweep::NOT_STARTED;
    let not_started = rows.iter().filter(|r| r.error.as_deref() == Some(NOT_STARTED)).count();
    let stopped: Vec<_> =
        rows.iter().filter(|r| r.status == Outcome::Interrupted && r.error.as_deref() != Some(NOT_STARTED)).collect();
    let frames: Vec<String> = stopped
        .iter()
        .filter_map(|r| {
            r.metrics.as_ref().and_then(|m| m.get(Metric::Frames)).map(|f| format!("{} {f} frames", r.name))
        })
        .collect();
    let count = |f: fn(Outcome) -> bool| rows.iter().filter(|r| f(r.status)).count();
    let complete = count(Outcome::is_complete);
    let stalled = count(|s| s == Outcome::Stalled);
    let failed = count(|s| matches!(s, Outcome::Failed | Outcome::IterationLimit));
    format!(
        "interrupted: of {} points {complete} complete, {stalled} stalled, {failed} failed or not converged, {} stopped at their next iteration or frame{}, {not_started} not started; {} marks each, and {} holds run.json saying interrupted",
        rows.len(),
        stopped.len(),
        if frames.is_empty() { String::new() } else { format!(" (kept: {})", frames.join(", ")) },
        target.join("summary.csv").display(),
        target.display()
    )
}

/// What the points of an interrupted audit in `dir` kept, from their `run.json`: complete,
/// stopped at their next iteration or frame, failed, and (of `total`) not started.
pub fn audit_points_kept(dir: &Path, total: usize) -> String {
    fn walk(dir: &Path, depth: usize, out: &mut Vec<Status>) {
        if let Ok(Some(m)) = Manifest::read(dir) {
            if m.writer.command == "audit point" {
                out.push(m.status);
                return;
            }
        }
        if depth == 0 {
            return;
        }
        for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
            if e.path().is_dir() {
                walk(&e.path(), depth - 1, out);
            }
        }
    }
    let mut statuses = Vec::new();
    walk(dir, 3, &mut statuses);
    let count = |s: Status| statuses.iter().filter(|x| **x == s).count();
    let (complete, stopped) = (count(Status::Complete), count(Status::Interrupted));
    format!(
        "of {total} points {complete} complete, {stopped} stopped at their next iteration or frame, {} failed or stalled, {} not started",
        statuses.len() - complete - stopped,
        total.saturating_sub(statuses.len())
    )
}

/// What the progress of a run of `case` in `engine` counts: clip frames, time steps or
/// iterations ("" for FreeFEM: its clip frames and time steps are shown by `FreefemProgress`, its
/// other runs the time elapsed).
pub fn progress_unit(case: &Case, engine: Engine) -> &'static str {
    use cosserat::case::Analysis;
    match (&case.analysis, engine) {
        (_, Engine::Freefem) => "",
        _ if case.clip().is_some() => "frames",
        (Analysis::Dynamic(_), _) => "time steps",
        _ => "iterations",
    }
}

/// The error of a command (`what`: "sweep") stopped by a full disk, which keeps nothing and
/// leaves its output folder `target` as it was.
pub fn disk_full_text(e: &(dyn std::error::Error + 'static), target: &Path, what: &str) -> String {
    format!(
        "{}: {}\n{} is left as it was; nothing of this {what} was kept (its staging folder is removed)",
        cosserat::io::disk::full_text(target),
        cosserat::jobs::sweep::chain(e),
        target.display()
    )
}

/// What a missed published value or a clip's frames over the fit-quality gate do to the exit
/// status of `run`: a warning (status 0), or, with `--strict`, an error (status 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Strictness {
    Warn,
    Fail,
}

/// How `cosserat run` ends, by the status of its folder: the summary on stdout, its published
/// values on stderr, a warning or a missed published value (`--strict`: exit 1), the interrupt's exit status 130 with what was kept, or the error with
/// what the folder holds.
pub fn run_end(
    end: cosserat::jobs::job::JobEnd,
    (case, engine): (&Case, Engine),
    path: &Path,
    dir: &Path,
    strictness: Strictness,
) -> anyhow::Result<std::process::ExitCode> {
    let strict = strictness == Strictness::Fail;
    match end.status {
        Status::Complete => {
            print!("{}", end.summary(&case.name, engine));
            if published_values(&end, (case, engine), strictness) > 0 && strict {
                return Ok(std::process::ExitCode::from(1));
            }
        }
        Status::CompleteWithWarnings => {
            print!("{}", end.summary(&case.name, engine));
            eprintln!("warning: {}", end.message.unwrap_or_default());
            if strict {
                return Ok(std::process::ExitCode::from(1));
            }
        }
        Status::Interrupted => {
            let resume = format!("(`cosserat run {} --out {} --resume` continues it)", path.display(), dir.display());
            let kept = match (&end.beside, end.frames) {
                (Some(beside), _) => {
                    eprintln!("{}: interrupted{}", case.name, beside.kept_text(&resume));
                    return Ok(std::process::ExitCode::from(crate::EXIT_INTERRUPTED));
                }
                (None, Some((n, _))) => format!(
                    "kept {n} converged frames (the folder's files and figures cover exactly them); continue with `cosserat run {} --out {} --resume`",
                    path.display(),
                    dir.display()
                ),
                (None, None) => "a single run keeps no partial result".into(),
            };
            eprintln!("{}: interrupted; {kept}; run.json in {} says interrupted", case.name, dir.display());
            return Ok(std::process::ExitCode::from(crate::EXIT_INTERRUPTED));
        }
        Status::Stalled | Status::Failed if end.beside.is_some() => {
            let resume = format!(
                "(after a fix that does not change the case, `cosserat run {} --out {} --resume` continues it)",
                path.display(),
                dir.display()
            );
            let beside = end.beside.as_ref().map(|b| b.kept_text(&resume)).unwrap_or_default();
            anyhow::bail!("{}{beside}", end.message.unwrap_or_default())
        }
        Status::Stalled => anyhow::bail!(
            "{}\n{} holds the last iterate, with its certificate (run.json says stalled; docs/certificate.md)",
            end.message.unwrap_or_default(),
            dir.display()
        ),
        Status::Failed | Status::Running if end.disk_full.is_some() => {
            anyhow::bail!("{}{}", end.message.clone().unwrap_or_default(), full_disk_note(&end, path, dir))
        }
        Status::Failed | Status::Running => {
            let kept = match end.frames {
                Some((n, _)) if n > 0 => format!(
                    "\nThe {n} converged frames before it are in {} (run.json says failed); after a fix that does not change the case, `--resume` continues from them",
                    dir.display()
                ),
                _ => format!("\n{} holds run.json saying failed", dir.display()),
            };
            anyhow::bail!("{}{kept}", end.message.unwrap_or_default());
        }
    }
    Ok(std::process::ExitCode::SUCCESS)
}

/// The published values (`[[reference.values]]`) of a complete single run on stderr, one line
/// each, and a line with the number missed; returns that number.
fn published_values(
    end: &cosserat::jobs::job::JobEnd,
    (case, engine): (&Case, Engine),
    strictness: Strictness,
) -> usize {
    let strict = strictness == Strictness::Fail;
    use cosserat::engine::{metrics::all_metrics, published::evaluate};
    let Some(r) = &end.single else { return 0 };
    let rows = match all_metrics(case, r) {
        Ok(m) => evaluate(case, r, &m),
        Err(_) => return 0,
    };
    for row in &rows {
        eprintln!("{} [{engine}] published {}", case.name, row.summary());
    }
    for s in cosserat::engine::published::sources(&rows) {
        eprintln!("  source: {s}");
    }
    let missed = rows.iter().filter(|r| !r.pass).count();
    if missed > 0 {
        eprintln!(
            "{}{}: {missed} of {} published values missed (reference.csv in {}){}",
            if strict { "error: " } else { "warning: " },
            case.name,
            rows.len(),
            end.dir.display(),
            if strict { "" } else { "; `--strict` makes this exit status 1" }
        );
    }
    missed
}
