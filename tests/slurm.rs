//! `cosserat batch --slurm` on a real single-node Slurm cluster (Debian's slurmctld, slurmd and
//! munge, started by `scripts/slurm_cluster.sh` in a temporary folder): the batch of the test
//! corpus submitted as a job array (two recordings per task), waited for, gathered, and its
//! summary compared with the local batch's (timing excepted).
//!
//! Where the cluster cannot start (not root, packages missing), the test prints
//! `SLURM NOT AVAILABLE: <reason>` and returns; with `CI=true` it fails instead.
mod batch_common;
mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use batch_common::{batch_command, corpus, cosserat, root, summary_without_time, GOOD};

/// A cluster started by the script; stopped when dropped.
struct Cluster {
    dir: PathBuf,
    port: u16,
    conf: PathBuf,
}

impl Cluster {
    fn script(dir: &Path, port: u16, action: &str) -> std::io::Result<std::process::Output> {
        Command::new("bash")
            .arg(root().join("scripts/slurm_cluster.sh"))
            .arg(action)
            .env("COSSERAT_SLURM_DIR", dir)
            .env("COSSERAT_SLURM_PORT", port.to_string())
            .output()
    }

    fn start(dir: &Path) -> Result<Cluster, String> {
        // a port of its own, away from a cluster started by hand on the default 6817
        let port = 7100 + (std::process::id() % 400) as u16 * 2;
        let out = Self::script(dir, port, "start").map_err(|e| format!("cannot run bash: {e}"))?;
        if !out.status.success() {
            let stderr = String::from_utf8_lossy(&out.stderr);
            return Err(stderr.lines().last().unwrap_or("scripts/slurm_cluster.sh start failed").to_string());
        }
        Ok(Cluster { dir: dir.to_path_buf(), port, conf: dir.join("slurm.conf") })
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Self::script(&self.dir, self.port, "stop");
    }
}

fn unavailable(reason: &str) {
    eprintln!("SLURM NOT AVAILABLE: {reason}");
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("SLURM NOT AVAILABLE: {reason} (CI=true: the Slurm test must run in CI)");
    }
}

#[test]
fn slurm_job_array_gathers_the_same_summary_as_the_local_batch() {
    if !common::worm_data_present("slurm") {
        return;
    }
    let tmp = tempfile::tempdir().expect("tempdir");
    let cluster = match Cluster::start(&tmp.path().join("cluster")) {
        Ok(c) => c,
        Err(reason) => return unavailable(&reason),
    };
    let recs = tmp.path().join("recordings");
    corpus(&recs);
    let (local, slurm) = (tmp.path().join("local"), tmp.path().join("slurm"));
    let batch = |out: &Path, extra: &[&str]| {
        batch_command(&recs, out, extra).env("SLURM_CONF", &cluster.conf).output().expect("batch")
    };
    let l = batch(&local, &["--jobs", "2"]);
    assert_eq!(l.status.code(), Some(1), "local: {}", String::from_utf8_lossy(&l.stderr));
    let s = batch(&slurm, &["--slurm", "--per-task", "2", "--wait"]);
    let stderr = String::from_utf8_lossy(&s.stderr);
    assert_eq!(s.status.code(), Some(1), "slurm: the bad recording fails there too: {stderr}");
    assert!(stderr.contains("submitted Slurm job") && stderr.contains("3 array tasks"), "{stderr}");
    let tasks = std::fs::read_dir(slurm.join("slurm")).expect("task logs").count();
    assert_eq!(tasks, 3, "one log per array task");
    let gathered = summary_without_time(&slurm);
    assert_eq!(gathered.len(), GOOD + 2);
    assert_eq!(gathered, summary_without_time(&local), "gathered summary = local batch's");
    // `gather` again, by hand, writes the same summary
    let g = cosserat().arg("gather").arg(&slurm).output().expect("gather");
    assert_eq!(g.status.code(), Some(1));
    assert_eq!(summary_without_time(&slurm), gathered);
}
