//! A Slurm array task of a batch (`cosserat batch-task`, [`super::slurm`]): its recordings run
//! one after the other exactly as a local batch runs them ([`super::batch::run_recording`]),
//! each row left in its recording's folder for [`super::batch::gather`].
use std::path::Path;

use super::batch::{plan_case, run_recording, BatchError, BatchRow, Plan, Ran, RecordingOptions, ROW};
use crate::io::files::{write_atomic, OutputError};
use crate::solve::Outcome;

/// Run the recordings of Slurm array task `index` of the plan in `out`, one after the other;
/// `progress(done, total)` after each.
pub fn run_task(out: &Path, index: usize, mut progress: impl FnMut(usize, usize)) -> Result<Vec<Ran>, BatchError> {
    let plan = Plan::read(out)?;
    let entries = plan.task(index)?;
    let (case, case_file) = plan_case(&plan)?;
    let mut ran = Vec::with_capacity(entries.len());
    for e in entries {
        let r = run_recording(&case, &case_file, e, out, RecordingOptions { format: plan.format, force: false });
        // a recording that fails before its folder is begun (unreadable, bad values) has its
        // row only here: `gather` reads rows from the folders, so it goes there too
        if r.row.status == Some(Outcome::Failed) {
            write_failed_row(&out.join(&e.folder), &r.row)?;
        }
        ran.push(r);
        progress(ran.len(), entries.len());
    }
    Ok(ran)
}

/// Write the row of a failed recording to its folder `dir` (created if needed) for [`gather`].
fn write_failed_row(dir: &Path, row: &BatchRow) -> Result<(), BatchError> {
    let path = dir.join(ROW);
    std::fs::create_dir_all(dir)
        .map_err(|source| OutputError::Io { path: dir.to_path_buf(), source })
        .and_then(|_| {
            serde_json::to_vec_pretty(row)
                .map_err(|e| OutputError::Invalid { path: path.clone(), reason: e.to_string() })
        })
        .and_then(|bytes| write_atomic(&path, &bytes))?;
    Ok(())
}
