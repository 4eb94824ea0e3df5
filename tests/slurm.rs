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
    // A resubmission submits only the task of the unfinished (bad) recording, and says so.
    let r = batch(&slurm, &["--slurm", "--per-task", "2", "--wait"]);
    let (stderr, stdout) = (String::from_utf8_lossy(&r.stderr), String::from_utf8_lossy(&r.stdout));
    assert_eq!(r.status.code(), Some(1), "{stderr}");
    let counts =
        format!("1 of {} recordings to run ({GOOD} already complete, skipped) in 1 of 3 array tasks", GOOD + 1);
    assert!(stderr.contains(&counts), "{stderr}");
    assert!(stdout.contains(&format!("({GOOD} already complete, skipped)")), "{stdout}");
    let script = std::fs::read_to_string(slurm.join("batch.sbatch")).expect("script");
    assert!(script.contains("#SBATCH --array=0\n"), "{script}");
    assert_eq!(summary_without_time(&slurm), gathered);
}

/// `--dry-run` writes the job script with the options and set-up lines and submits nothing.
#[test]
fn dry_run_writes_the_job_script_with_its_options() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let recs = tmp.path().join("recs");
    std::fs::create_dir(&recs).expect("mkdir");
    for k in 0..3 {
        std::fs::write(recs.join(format!("r{k}.csv")), "frame,node,x_m,y_m,z_m\n").expect("recording");
    }
    let setup = tmp.path().join("setup.sh");
    std::fs::write(&setup, "module load gcc/12\nexport OMP_NUM_THREADS=1\n").expect("setup");
    let out = tmp.path().join("out");
    let o =
        batch_command(&recs, &out, &["--slurm", "--dry-run", "--per-task", "2", "--time", "0:20:00", "--mem", "2G"])
            .args(["--account", "lab", "--sbatch-arg=--qos=long", "--sbatch-arg", "--constraint=avx2", "--setup"])
            .arg(&setup)
            .env("SLURM_CONF", "/nonexistent/slurm.conf")
            .output()
            .expect("batch");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("3 of 3 recordings to run (0 already complete, skipped) in 2 of 2 array tasks"),
        "{stderr}"
    );
    assert!(stderr.contains("not submitted"), "{stderr}");
    let script = std::fs::read_to_string(out.join("batch.sbatch")).expect("script");
    for line in [
        "#SBATCH --array=0-1\n",
        "#SBATCH --time=0:20:00\n",
        "#SBATCH --mem=2G\n",
        "#SBATCH --account=lab\n",
        "#SBATCH --qos=long\n",
        "#SBATCH --constraint=avx2\n",
        "module load gcc/12\nexport OMP_NUM_THREADS=1\n",
    ] {
        assert!(script.contains(line), "{line:?} in {script}");
    }
    assert!(script.find("module load").expect("setup") < script.find("exec ").expect("exec"));
    assert!(!out.join("slurm").read_dir().is_ok_and(|mut d| d.next().is_some()), "nothing ran");
}

/// Without a controller to reach, `sbatch`'s error comes with a hint on SLURM_CONF.
#[test]
fn sbatch_without_a_controller_gets_a_hint() {
    if Path::new("/etc/slurm/slurm.conf").exists() || Command::new("sbatch").arg("--version").output().is_err() {
        return; // a configured or absent client: nothing to show
    }
    let tmp = tempfile::tempdir().expect("tempdir");
    let recs = tmp.path().join("recs");
    std::fs::create_dir(&recs).expect("mkdir");
    std::fs::write(recs.join("r.csv"), "frame,node,x_m,y_m,z_m\n").expect("recording");
    let o =
        batch_command(&recs, &tmp.path().join("out"), &["--slurm"]).env_remove("SLURM_CONF").output().expect("batch");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("cannot reach a Slurm controller") && stderr.contains("hint: SLURM_CONF is not set"),
        "{stderr}"
    );
}
