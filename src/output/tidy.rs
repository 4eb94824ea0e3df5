//! What runs that ended early left in a folder of output folders (a batch's OUT, whose
//! recordings' folders are `OUT/NAME`): for each NAME, its lock file `.NAME.lock`, its staging
//! folders `.NAME.staging-PID` and the folders of an interrupted exchange (`.NAME.swap-PID`,
//! `.NAME.old-PID`); and the temporary files of atomic writes (`.summary.csv.PID.N.tmp`) at the
//! top. A run that skips NAME (its folder is complete) never claims it, so this is what clears
//! them.
//!
//! NAME's are cleared holding NAME's lock ([`super::folder_lock`]): a lock that can be taken
//! was held by no live process (the kernel releases it when its holder dies, whatever kills
//! it), and every staging folder of NAME then belongs to a run that has ended; a lock held by
//! a live run leaves NAME's files alone. The lock file goes when the lock is dropped.
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use super::folder_lock::{FolderLock, LockError};
use super::manifest::{io_err, FolderError};
use super::staging::leftovers;
use crate::io::files::is_temporary;

/// The output folders named by what runs left in `out`: `.NAME.lock`, `.NAME.staging-PID`,
/// `.NAME.swap-PID`, `.NAME.old-PID`.
fn names_left(out: &Path) -> Result<BTreeSet<String>, FolderError> {
    let mut names = BTreeSet::new();
    for entry in std::fs::read_dir(out).map_err(io_err(out))? {
        let n = entry.map_err(io_err(out))?.file_name().to_string_lossy().into_owned();
        let Some(rest) = n.strip_prefix('.') else { continue };
        if let Some(name) = rest.strip_suffix(".lock") {
            names.insert(name.to_string());
            continue;
        }
        let Some((name, tail)) = rest.rsplit_once('.') else { continue };
        let pid = ["staging-", "swap-", "old-"].iter().find_map(|k| tail.strip_prefix(k));
        if pid.is_some_and(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit())) {
            names.insert(name.to_string());
        }
    }
    Ok(names)
}

/// Remove from `out` what runs that have ended left ([`self`]); the caller holds `out`'s own
/// lock (no other process writes its top-level files). `keep_work(NAME)`: whether NAME's
/// staging folders that hold a run's work (killed, stopped by a full disk, or kept beside a
/// complete run) stay, to be continued; otherwise they go too (NAME is complete, or no longer
/// one of the batch's folders). Returns what was removed.
pub fn clear_ended(out: &Path, keep_work: impl Fn(&str) -> bool) -> Result<Vec<PathBuf>, FolderError> {
    let mut removed = Vec::new();
    for name in names_left(out)? {
        let lock_file = super::folder_lock::lock_path(out, &name);
        let had_lock_file = lock_file.exists();
        let lock = match FolderLock::acquire(out, &name) {
            Ok(lock) => lock,
            Err(LockError::Held { .. }) => continue, // a live run writes NAME
            Err(LockError::Io { path, source }) => return Err(FolderError::Io { path, source }),
        };
        let (left, others) = leftovers(out, &name)?;
        let keep = keep_work(&name);
        let gone = left.into_iter().filter(|l| !(keep && l.in_progress())).map(|l| l.dir).chain(others);
        for dir in gone {
            std::fs::remove_dir_all(&dir).map_err(io_err(&dir))?;
            removed.push(dir);
        }
        drop(lock);
        if had_lock_file {
            removed.push(lock_file);
        }
    }
    for entry in std::fs::read_dir(out).map_err(io_err(out))? {
        let entry = entry.map_err(io_err(out))?;
        let p = entry.path();
        if is_temporary(&entry.file_name().to_string_lossy()) && entry.file_type().map_err(io_err(&p))?.is_file() {
            std::fs::remove_file(&p).map_err(io_err(&p))?;
            removed.push(p);
        }
    }
    Ok(removed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_of_leftovers_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        for d in [".a.staging-12", ".b.c.swap-3", ".x.staging-", ".y.staging-1z", "z", ".d.old-4"] {
            std::fs::create_dir(dir.path().join(d)).unwrap();
        }
        for f in [".e.lock", ".summary.csv.5.0.tmp", "f.lock"] {
            std::fs::write(dir.path().join(f), "").unwrap();
        }
        let names: Vec<String> = names_left(dir.path()).unwrap().into_iter().collect();
        assert_eq!(names, ["a", "b.c", "d", "e"]);
    }
}
