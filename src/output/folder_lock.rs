//! One writer per output folder: a run holds an exclusive `flock` on `.NAME.lock` beside its
//! output folder `NAME` from the moment it claims the folder until the folder is in place. A
//! second run into the same folder finds the lock taken and is refused at once, naming the
//! process that holds it (its pid is the lock file's content).
//!
//! The kernel releases the lock when its holder dies, whatever kills it: a process killed
//! with SIGKILL and not yet reaped (a zombie) holds no lock, and neither does a process on
//! another node of a cluster that has gone (NFS leases expire). So holding the lock also proves
//! that every staging folder of `NAME` left beside it belongs to a run that has ended: no
//! process id is ever tested for life.
//!
//! The lock file is removed by its holder when it releases it. A run that takes the lock checks
//! that the file it locked is still the one at the path (a run that was finishing may have
//! removed it meanwhile) and tries again if not, so two runs never hold locks on two different
//! files of the same name.
use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// Why a folder could not be locked.
#[derive(Debug)]
pub enum LockError {
    /// another process holds the lock (its pid, if it has written it yet)
    Held {
        pid: Option<u32>,
    },
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// The lock of an output folder, held until dropped (which removes the lock file).
#[derive(Debug)]
pub struct FolderLock {
    path: PathBuf,
    file: File,
}

/// The output folder `target` as its lock knows it: a symbolic link (its last component)
/// resolved to the folder it names, so that two names of one folder take one lock and the
/// folder is written through the link, never replacing it; any other path as given (a link
/// among its parents names the same lock file already).
pub fn real_folder(target: &Path) -> Result<PathBuf, LockError> {
    match std::fs::symlink_metadata(target) {
        Ok(m) if m.file_type().is_symlink() => {
            std::fs::canonicalize(target).map_err(|source| LockError::Io { path: target.to_path_buf(), source })
        }
        _ => Ok(target.to_path_buf()),
    }
}

/// The lock file of the output folder `name` in `parent`.
pub fn lock_path(parent: &Path, name: &str) -> PathBuf {
    parent.join(format!(".{name}.lock"))
}

impl FolderLock {
    /// Take the lock of the output folder `name` in `parent`, or say who holds it.
    pub fn acquire(parent: &Path, name: &str) -> Result<FolderLock, LockError> {
        let path = lock_path(parent, name);
        let io = |source| LockError::Io { path: path.clone(), source };
        loop {
            let mut file =
                OpenOptions::new().read(true).write(true).create(true).truncate(false).open(&path).map_err(io)?;
            match file.try_lock() {
                Ok(()) => {}
                Err(TryLockError::WouldBlock) => return Err(LockError::Held { pid: holder(&mut file) }),
                Err(TryLockError::Error(e)) => return Err(io(e)),
            }
            if !still_at(&file, &path) {
                continue; // removed by the run that held it before us: lock the new file
            }
            // the pid is for the message of a refused run; a full disk may refuse it: no matter
            let _ = file.set_len(0).and_then(|_| file.write_all(std::process::id().to_string().as_bytes()));
            return Ok(FolderLock { path, file });
        }
    }
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        // removed while held, so that no other run can have opened it and lock it after us
        // without noticing (`still_at`)
        let _ = std::fs::remove_file(&self.path);
        let _ = self.file.unlock();
    }
}

/// Is `file` (open) the file at `path`?
fn still_at(file: &File, path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (file.metadata(), std::fs::metadata(path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = (file, path);
        true
    }
}

/// The pid written in a lock file held by another process (it writes it just after it locks
/// the file: retried briefly).
fn holder(file: &mut File) -> Option<u32> {
    for _ in 0..20 {
        let mut text = String::new();
        if file.read_to_string(&mut text).is_ok() {
            if let Ok(pid) = text.trim().parse::<u32>() {
                return Some(pid);
            }
        }
        let _ = std::io::Seek::rewind(file);
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_is_refused_naming_the_holder_and_released_on_drop() {
        let dir = tempfile::tempdir().unwrap();
        let lock = FolderLock::acquire(dir.path(), "out").unwrap();
        assert!(lock_path(dir.path(), "out").is_file());
        match FolderLock::acquire(dir.path(), "out") {
            Err(LockError::Held { pid }) => assert_eq!(pid, Some(std::process::id())),
            other => panic!("expected the lock to be held, got {other:?}"),
        }
        drop(lock);
        assert!(!lock_path(dir.path(), "out").exists(), "the lock file goes with the lock");
        // a lock file left by a process that died (unlocked) is taken over
        std::fs::write(lock_path(dir.path(), "out"), "12345").unwrap();
        let lock = FolderLock::acquire(dir.path(), "out").unwrap();
        assert_eq!(std::fs::read_to_string(&lock.path).unwrap(), std::process::id().to_string());
    }
}
