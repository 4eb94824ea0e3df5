//! A batch as a Slurm job array (`cosserat batch --slurm`): the job script `OUT/batch.sbatch`
//! runs `cosserat batch-task OUT --index $SLURM_ARRAY_TASK_ID` in every task (the recordings
//! of the plan's chunk, exactly as a local batch runs them: `super::batch_task::run_task`), `sbatch`
//! submits it, and `squeue` tells when the array has left the queue. The output folder must be
//! on a filesystem that every node sees under the same path. The Slurm clients find their
//! cluster as usual (`SLURM_CONF`, or the system's configuration).
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use super::batch::Plan;
use crate::io::files::{write_atomic, OutputError};

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
    #[error("`{program}` cannot reach a Slurm controller ({status}): {stderr}\nhint: {}", no_controller_hint())]
    NoController { program: &'static str, status: String, stderr: String },
    #[error("--sbatch-arg `{0}`: give one sbatch option per --sbatch-arg, starting with `-` and on one line (e.g. --sbatch-arg=--qos=long)")]
    BadOption(String),
    #[error("`sbatch` printed `{0}`, not a job id")]
    JobId(String),
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// What to do when the Slurm clients find no controller: where they look for it.
fn no_controller_hint() -> String {
    match std::env::var_os("SLURM_CONF") {
        Some(conf) => format!(
            "SLURM_CONF is {}: is its slurmctld running and reachable from here? (`scontrol ping`; a cluster started by scripts/slurm_cluster.sh: `bash scripts/slurm_cluster.sh status`)",
            std::path::Path::new(&conf).display()
        ),
        None => "SLURM_CONF is not set, and there is no /etc/slurm/slurm.conf nor a DNS SRV record (_slurmctld._tcp) naming a controller: set SLURM_CONF to your cluster's slurm.conf (`bash scripts/slurm_cluster.sh start` prints it for the cluster on this machine), or submit from the cluster's login node".into(),
    }
}

/// Does this client error say that no controller could be found or reached?
fn unreachable_controller(stderr: &str) -> bool {
    [
        "Could not establish a configuration source",
        "DNS SRV lookup failed",
        "Unable to contact slurm controller",
        "Zero Bytes were transmitted or received",
        "Connection refused",
    ]
    .iter()
    .any(|m| stderr.contains(m))
}

/// The `#SBATCH` options and set-up of a job script beyond the array itself.
#[derive(Clone, Debug, Default)]
pub struct JobOptions {
    /// `--partition`
    pub partition: Option<String>,
    /// `--time` (Slurm's formats: `MM`, `HH:MM:SS`, `D-HH`, …)
    pub time: Option<String>,
    /// `--mem` per node (`4G`, `500M`)
    pub mem: Option<String>,
    /// `--account`
    pub account: Option<String>,
    /// further options, each an `#SBATCH` line as given (`--qos=long`)
    pub sbatch_args: Vec<String>,
    /// lines run before the task (`module load …`, `export …`)
    pub setup: Option<String>,
}

impl JobOptions {
    /// The `#SBATCH` lines of these options.
    fn lines(&self) -> Result<String, SlurmError> {
        let mut s = String::new();
        for (name, value) in
            [("partition", &self.partition), ("time", &self.time), ("mem", &self.mem), ("account", &self.account)]
        {
            if let Some(v) = value {
                if v.contains('\n') {
                    return Err(SlurmError::BadOption(format!("--{name}={v}")));
                }
                s += &format!("#SBATCH --{name}={v}\n");
            }
        }
        for a in &self.sbatch_args {
            if !a.starts_with('-') || a.contains('\n') {
                return Err(SlurmError::BadOption(a.clone()));
            }
            s += &format!("#SBATCH {a}\n");
        }
        Ok(s)
    }
}

/// `0-3,5,8-9`: the indices (sorted) as Slurm's `--array` list.
pub fn array_list(indices: &[usize]) -> String {
    let mut parts = Vec::new();
    let mut i = 0;
    while i < indices.len() {
        let mut j = i;
        while j + 1 < indices.len() && indices[j + 1] == indices[j] + 1 {
            j += 1;
        }
        parts.push(if j > i { format!("{}-{}", indices[i], indices[j]) } else { indices[i].to_string() });
        i = j + 1;
    }
    parts.join(",")
}

/// Quote `s` for a POSIX shell.
fn shell_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// The job script of `plan` in `out` (absolute): one array task per chunk of `plan.per_task`
/// recordings, of the chunks `tasks` (those with a recording to run), one CPU each, with the
/// options and set-up of `opts`, calling `exe`.
pub fn job_script(
    plan: &Plan,
    tasks: &[usize],
    out: &Path,
    exe: &Path,
    opts: &JobOptions,
) -> Result<String, SlurmError> {
    let logs = out.join(LOGS);
    let mut s = String::from("#!/bin/bash\n");
    s += "#SBATCH --job-name=cosserat-batch\n";
    s += &format!("#SBATCH --array={}\n", array_list(tasks));
    s += "#SBATCH --ntasks=1\n#SBATCH --cpus-per-task=1\n";
    s += &format!("#SBATCH --output={}/%A_%a.out\n", logs.display());
    s += &opts.lines()?;
    s += &format!(
        "# {} recordings, {} per task, {} of the {} tasks to run; results in {}/<recording>/, then `cosserat gather {}`\n",
        plan.recordings.len(),
        plan.per_task,
        tasks.len(),
        plan.tasks(),
        out.display(),
        out.display()
    );
    if let Some(setup) = &opts.setup {
        s += "# set-up (--setup)\n";
        s += setup.trim_end();
        s += "\n";
    }
    s += &format!(
        "exec {} batch-task {} --index \"$SLURM_ARRAY_TASK_ID\"\n",
        shell_quote(&exe.display().to_string()),
        shell_quote(&out.display().to_string())
    );
    Ok(s)
}

fn run(program: &'static str, args: &[&str]) -> Result<String, SlurmError> {
    let o = Command::new(program).args(args).output().map_err(|source| SlurmError::Spawn { program, source })?;
    if !o.status.success() {
        let (status, stderr) = (o.status.to_string(), String::from_utf8_lossy(&o.stderr).trim().to_string());
        if unreachable_controller(&stderr) {
            return Err(SlurmError::NoController { program, status, stderr });
        }
        return Err(SlurmError::Failed { program, status, stderr });
    }
    Ok(String::from_utf8_lossy(&o.stdout).into_owned())
}

/// Write the job script of `plan`'s array tasks `tasks` into `out` (absolute); returns its path.
pub fn write_script(
    plan: &Plan,
    tasks: &[usize],
    out: &Path,
    exe: &Path,
    opts: &JobOptions,
) -> Result<PathBuf, SlurmError> {
    let logs = out.join(LOGS);
    std::fs::create_dir_all(&logs).map_err(|source| OutputError::Io { path: logs.clone(), source })?;
    let script: PathBuf = out.join(SCRIPT);
    write_atomic(&script, job_script(plan, tasks, out, exe, opts)?.as_bytes())?;
    Ok(script)
}

/// Submit the job script `script`; returns the job id.
pub fn submit(script: &Path) -> Result<String, SlurmError> {
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
        let s = job_script(&plan, &[0, 1, 2], Path::new("/o u't"), Path::new("/bin/cosserat"), &JobOptions::default())
            .unwrap();
        assert!(s.contains("#SBATCH --array=0-2\n"), "{s}");
        assert!(s.contains("exec '/bin/cosserat' batch-task '/o u'\\''t' --index \"$SLURM_ARRAY_TASK_ID\""), "{s}");
        let opts = JobOptions {
            time: Some("0:30:00".into()),
            mem: Some("2G".into()),
            account: Some("lab".into()),
            sbatch_args: vec!["--qos=long".into()],
            setup: Some("module load gcc\nexport OMP_NUM_THREADS=1\n".into()),
            ..JobOptions::default()
        };
        let s = job_script(&plan, &[0, 2], Path::new("/o"), Path::new("/bin/cosserat"), &opts).unwrap();
        for line in
            ["#SBATCH --array=0,2\n", "#SBATCH --time=0:30:00\n", "#SBATCH --mem=2G\n", "#SBATCH --account=lab\n"]
        {
            assert!(s.contains(line), "{line} in {s}");
        }
        let setup = s.find("module load gcc\nexport OMP_NUM_THREADS=1\n").expect("set-up");
        assert!(s.contains("#SBATCH --qos=long\n") && setup < s.find("exec ").expect("exec"), "{s}");
        let bad = JobOptions { sbatch_args: vec!["qos".into()], ..JobOptions::default() };
        assert!(job_script(&plan, &[0], Path::new("/o"), Path::new("/c"), &bad).is_err());
        assert_eq!(array_list(&[0, 1, 2, 5, 7, 8]), "0-2,5,7-8");
    }
}
