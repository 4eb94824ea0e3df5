//! A batch as a Slurm job array (`cosserat batch --slurm`): the job script `OUT/batch.sbatch`
//! runs `cosserat batch-task OUT --index $SLURM_ARRAY_TASK_ID` in every task (the recordings
//! of the plan's chunk, exactly as a local batch runs them: `super::batch::run_task`), `sbatch`
//! submits it, and `squeue` tells when the array has left the queue. The output folder must be
//! on a filesystem that every node sees under the same path. The Slurm clients find their
//! cluster as usual (`SLURM_CONF`, or the system's configuration).
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use super::batch::Plan;
use super::files::{write_atomic, OutputError};

/// The job script in the output folder.
pub const SCRIPT: &str = "batch.sbatch";
/// The folder of the tasks' stdout and stderr in the output folder.
pub const LOGS: &str = "slurm";

/// Errors of submitting or following a job array.
#[derive(Debug, thiserror::Error)]
pub enum SlurmError {
    #[error("cannot run `{program}` (is Slurm installed, and its client on PATH?)")]
    Spawn {
        program: &'static str,
        #[source]
        source: std::io::Error,
    },
    #[error("`{program}` failed ({status}): {stderr}")]
    Failed { program: &'static str, status: String, stderr: String },
    #[error("`sbatch` printed `{0}`, not a job id")]
    JobId(String),
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// Quote `s` for a POSIX shell.
fn shell_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// The job script of `plan` in `out` (absolute): one array task per chunk of `plan.per_task`
/// recordings, one CPU each, calling `exe`.
pub fn job_script(plan: &Plan, out: &Path, exe: &Path, partition: Option<&str>) -> String {
    let logs = out.join(LOGS);
    let mut s = String::from("#!/bin/bash\n");
    s += "#SBATCH --job-name=cosserat-batch\n";
    s += &format!("#SBATCH --array=0-{}\n", plan.tasks().saturating_sub(1));
    s += "#SBATCH --ntasks=1\n#SBATCH --cpus-per-task=1\n";
    s += &format!("#SBATCH --output={}/%A_%a.out\n", logs.display());
    if let Some(p) = partition {
        s += &format!("#SBATCH --partition={p}\n");
    }
    s += &format!(
        "# {} recordings, {} per task; results in {}/<recording>/, then `cosserat gather {}`\n",
        plan.recordings.len(),
        plan.per_task,
        out.display(),
        out.display()
    );
    s += &format!(
        "exec {} batch-task {} --index \"$SLURM_ARRAY_TASK_ID\"\n",
        shell_quote(&exe.display().to_string()),
        shell_quote(&out.display().to_string())
    );
    s
}

fn run(program: &'static str, args: &[&str]) -> Result<String, SlurmError> {
    let o = Command::new(program).args(args).output().map_err(|source| SlurmError::Spawn { program, source })?;
    if !o.status.success() {
        return Err(SlurmError::Failed {
            program,
            status: o.status.to_string(),
            stderr: String::from_utf8_lossy(&o.stderr).trim().to_string(),
        });
    }
    Ok(String::from_utf8_lossy(&o.stdout).into_owned())
}

/// Write the job script of `plan` into `out` (absolute) and submit it; returns the job id.
pub fn submit(plan: &Plan, out: &Path, exe: &Path, partition: Option<&str>) -> Result<String, SlurmError> {
    let logs = out.join(LOGS);
    std::fs::create_dir_all(&logs).map_err(|source| OutputError::Io { path: logs.clone(), source })?;
    let script: PathBuf = out.join(SCRIPT);
    write_atomic(&script, job_script(plan, out, exe, partition).as_bytes())?;
    let text = run("sbatch", &["--parsable", &script.display().to_string()])?;
    // `--parsable` prints `jobid` or `jobid;cluster`
    let id = text.trim().split(';').next().unwrap_or("").to_string();
    if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
        return Err(SlurmError::JobId(text.trim().to_string()));
    }
    Ok(id)
}

/// Tasks of job `id` still in the queue (pending or running).
pub fn queued(id: &str) -> Result<usize, SlurmError> {
    let text = run("squeue", &["--noheader", "--array", "--jobs", id, "--format=%i"])?;
    Ok(text.lines().filter(|l| !l.trim().is_empty()).count())
}

/// Block until every task of job `id` has left the queue, polling `squeue` every `poll`;
/// `tick(queued)` after each poll.
pub fn wait(id: &str, poll: Duration, mut tick: impl FnMut(usize)) -> Result<(), SlurmError> {
    loop {
        let n = match queued(id) {
            Ok(n) => n,
            // a job that has left the controller's memory is reported as an invalid id
            Err(SlurmError::Failed { stderr, .. }) if stderr.contains("Invalid job id") => 0,
            Err(e) => return Err(e),
        };
        tick(n);
        if n == 0 || crate::interrupt::requested() {
            return Ok(());
        }
        std::thread::sleep(poll);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn script_has_array_and_task_command() {
        let recs: Vec<PathBuf> = (0..5).map(|k| PathBuf::from(format!("/r/{k}.npy"))).collect();
        let plan = Plan::new(Path::new("/c.toml"), &recs, 2);
        let s = job_script(&plan, Path::new("/o u't"), Path::new("/bin/cosserat"), None);
        assert!(s.contains("#SBATCH --array=0-2\n"), "{s}");
        assert!(s.contains("exec '/bin/cosserat' batch-task '/o u'\\''t' --index \"$SLURM_ARRAY_TASK_ID\""), "{s}");
    }
}
