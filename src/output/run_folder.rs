//! The output-folder contract. Every command that writes results (`run`, `sweep`, `compare`,
//! `audit`, each recording of `batch`) writes them into a staging folder beside its output
//! folder, `.NAME.staging-PID`, and `run.json` there says what the folder is: the command, the
//! case and the SHA-256 of its file and inputs, the engine, the program version, the status
//! (`running`, `complete`, `failed`, `interrupted`), the frames done and the files written.
//! When the run ends — complete, failed or interrupted — the staging folder takes the output
//! folder's place in one exchange of names, so a folder never mixes two runs, never holds stale
//! files, and a run killed at any moment leaves the output folder either as it was or whole and
//! new. One run writes a folder at a time ([`super::folder_lock`]); what a killed run left is
//! removed, or resumed, by the next run. `--resume` continues in a staging folder of its own (a
//! copy of the output folder, or the staging folder of a killed run), so the previous folder
//! stays in place until the resumed run ends. A folder holding files but no `run.json` is not
//! replaced unless `--force`. A run that fails or is interrupted is not put in place of a
//! folder holding a complete run: that folder stays, and the run stays beside it in its
//! staging folder ([`Placed::Beside`]), unless `--force`.
use std::path::{Path, PathBuf};

use super::folder_lock::{real_folder, FolderLock, LockError};
use super::manifest::io_err;
pub use super::manifest::{
    input_file, input_file_as, list_files, sha256_file, CertificateSummary, FolderError, InputFile, Manifest, Status,
    MANIFEST,
};
use super::staging::{
    copy_run, journal_frames, leftovers, put_in_place, remove_temporaries, resume_source, Leftover, ResumeSource,
};

/// How a run treats its output folder.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// a new run; `force`: also replace a folder that holds files but no `run.json`, and a
    /// complete run with one that failed or was interrupted ([`RunFolder::finish`])
    Fresh { force: bool },
    /// continue the interrupted or failed run of the folder (same case and inputs)
    Resume,
}

/// An output folder being written: the run writes into [`RunFolder::dir`] (the staging folder)
/// and [`RunFolder::finish`] puts it in place. The folder's lock ([`super::folder_lock`]) is
/// held from [`RunFolder::begin`] until the `RunFolder` is dropped.
#[derive(Debug)]
pub struct RunFolder {
    target: PathBuf,
    staging: PathBuf,
    pub manifest: Manifest,
    /// the manifest of the run being resumed
    pub resumed: Option<Manifest>,
    /// what was done to the folder's surroundings (stale staging folders removed), for the user
    pub notes: Vec<String>,
    /// `--force`: the run replaces a complete run even if it ends worse
    force: bool,
    /// one writer per folder
    _lock: FolderLock,
}

/// Is `path` the working folder, one of its parents, or the root?
fn dangerous(path: &Path) -> bool {
    let Ok(abs) = std::fs::canonicalize(path) else { return false };
    let cwd = std::env::current_dir().ok().and_then(|c| std::fs::canonicalize(c).ok());
    abs.parent().is_none() || cwd.is_some_and(|c| c.starts_with(&abs))
}

/// The output folder `target` as it is written: a symbolic link resolved to the folder it names
/// (written through, and locked as that folder), its parent and its name.
fn locate(target: &Path) -> Result<(PathBuf, PathBuf, String), FolderError> {
    let real = real_folder(target).map_err(|e| match e {
        LockError::Io { path, source } => FolderError::Io { path, source },
        LockError::Held { pid } => FolderError::Busy { path: target.to_path_buf(), pid },
    })?;
    let name = real
        .file_name()
        .filter(|n| !n.is_empty() && *n != "..")
        .ok_or_else(|| FolderError::Dangerous { path: real.clone() })?
        .to_string_lossy()
        .into_owned();
    let parent = match real.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    Ok((real, parent, name))
}

impl RunFolder {
    /// Start a run whose results go to `target`, described by `manifest` (status running):
    /// take the folder's lock (refused at once if another run holds it), clear what runs that
    /// ended early left beside it, and make the staging folder: empty, or for `--resume` the
    /// run being continued (a killed run's staging folder taken over, or a copy of the output
    /// folder, which stays in place until this run ends).
    pub fn begin(target: &Path, mut manifest: Manifest, mode: Mode) -> Result<RunFolder, FolderError> {
        let (real, parent, name) = locate(target)?;
        let target = real.as_path();
        // the folder, or the first of its parents that exists, must be a folder
        if let Some(existing) = target.ancestors().find(|a| !a.as_os_str().is_empty() && a.exists()) {
            if !existing.is_dir() {
                return Err(FolderError::NotAFolder { path: existing.to_path_buf() });
            }
        }
        std::fs::create_dir_all(&parent).map_err(io_err(&parent))?;
        let lock = FolderLock::acquire(&parent, &name).map_err(|e| match e {
            LockError::Held { pid } => FolderError::Busy { path: target.to_path_buf(), pid },
            LockError::Io { path, source } => FolderError::Io { path, source },
        })?;
        let staging = parent.join(format!(".{name}.staging-{}", std::process::id()));
        let mut notes = Vec::new();
        // Holding the lock, every staging folder of NAME is a run's that has ended. What holds
        // no run's work goes at once; a killed run's work stays until it is resumed or replaced.
        let (left, others) = leftovers(&parent, &name)?;
        let (mut left, garbage): (Vec<_>, Vec<_>) = left.into_iter().partition(Leftover::in_progress);
        for dir in garbage.into_iter().map(|l| l.dir).chain(others) {
            std::fs::remove_dir_all(&dir).map_err(io_err(&dir))?;
        }
        let old = Manifest::read(target)?;
        let resumed = match mode {
            Mode::Fresh { force } => {
                let files = if target.is_dir() { list_entries(target)? } else { Vec::new() };
                if old.is_none() && !files.is_empty() {
                    if !force {
                        let examples = files.iter().take(3).cloned().collect::<Vec<_>>().join(", ");
                        return Err(FolderError::Foreign { path: target.to_path_buf(), examples });
                    }
                    if dangerous(target) {
                        return Err(FolderError::Dangerous { path: target.to_path_buf() });
                    }
                }
                None
            }
            Mode::Resume => {
                let previous = adopt(target, old.as_ref(), &mut left, &manifest, &staging, &mut notes)?;
                manifest.process.started_unix_s = previous.process.started_unix_s;
                Some(previous)
            }
        };
        for dir in left.into_iter().map(|l| l.dir) {
            std::fs::remove_dir_all(&dir).map_err(io_err(&dir))?;
            notes.push(format!("removed {}, left by a run that ended before its folder was in place", dir.display()));
        }
        if resumed.is_none() {
            std::fs::create_dir_all(&staging).map_err(io_err(&staging))?;
        }
        manifest.status = Status::Running;
        if let Err(e) = manifest.write(&staging) {
            if resumed.is_none() {
                let _ = std::fs::remove_dir_all(&staging);
            }
            return Err(e);
        }
        let force = mode == Mode::Fresh { force: true };
        Ok(RunFolder { target: target.to_path_buf(), staging, manifest, resumed, notes, force, _lock: lock })
    }

    /// Where the run writes (the staging folder).
    pub fn dir(&self) -> &Path {
        &self.staging
    }

    /// The output folder (where the results will be once the run ends).
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// End a run that the disk could not hold without touching the output folder: the staging
    /// folder stays where it is, to be resumed (its `run.json` says `status` with `message` and
    /// the frames done where there is room to write it; otherwise it still says running, which
    /// `--resume` takes the same way). Returns the staging folder.
    pub fn keep_staging(mut self, status: Status, message: Option<String>) -> PathBuf {
        let _ = self.manifest.finish(&self.staging, status, message);
        self.staging.clone()
    }

    /// End a run whose staging folder holds nothing worth keeping (a full disk before any
    /// result): it is removed, and the output folder is left as it was.
    pub fn abandon(self) {
        let _ = std::fs::remove_dir_all(&self.staging);
    }

    /// End the run as `status`: `run.json` written with the files, then the staging folder put
    /// in place of the output folder in one step ([`put_in_place`]), the previous one removed
    /// after; or, where the run did not complete and the output folder holds a complete run
    /// (and not `--force`), that folder left as it was and this run's kept beside it
    /// ([`Placed::Beside`]), where `--resume` finds it.
    pub fn finish(self, status: Status, message: Option<String>) -> Result<Placed, FolderError> {
        self.finish_keeping(status, message, Beside::Kept)
    }

    /// [`RunFolder::finish`]; `beside`: whether a run that is not put in place (it would have
    /// replaced a complete run) is kept beside it, or removed (it holds nothing to continue:
    /// a single run's `run.json` alone).
    pub fn finish_keeping(
        mut self,
        status: Status,
        message: Option<String>,
        beside: Beside,
    ) -> Result<Placed, FolderError> {
        let previous = Manifest::read(&self.target).ok().flatten().map(|m| m.status);
        if !status.is_complete() && !self.force && previous.is_some_and(Status::is_complete) {
            if beside == Beside::Removed {
                std::fs::remove_dir_all(&self.staging).map_err(io_err(&self.staging))?;
                return Ok(Placed::Beside { target: self.target.clone(), kept: None });
            }
            self.manifest.finish(&self.staging, status, message)?;
            return Ok(Placed::Beside { target: self.target.clone(), kept: Some(self.staging.clone()) });
        }
        self.manifest.finish(&self.staging, status, message)?;
        put_in_place(&self.staging, &self.target)?;
        Ok(Placed::InPlace(self.target.clone()))
    }
}

/// What [`RunFolder::finish_keeping`] does with a run that is not put in place because the
/// output folder holds a complete one: keeps it beside that folder, or removes it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Beside {
    /// kept in its staging folder, where `--resume` (or the next batch) continues it
    Kept,
    /// removed: it holds nothing to continue
    Removed,
}

/// Where [`RunFolder::finish`] left a run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Placed {
    /// in the output folder
    InPlace(PathBuf),
    /// not in the output folder `target`, which keeps the complete run it held: this run (it
    /// failed or was interrupted) is kept beside it in its staging folder `kept`, to be
    /// continued by `--resume` (or by the next batch) or replaced by the next run (`None`:
    /// removed, it held nothing to continue)
    Beside { target: PathBuf, kept: Option<PathBuf> },
}

impl Placed {
    /// The output folder.
    pub fn target(&self) -> &Path {
        match self {
            Placed::InPlace(t) | Placed::Beside { target: t, .. } => t,
        }
    }

    /// The words that say where the run is when it was not put in place ("" when it was):
    /// "; OUT keeps its complete run (…); this run's work is kept in STAGING {then}".
    pub fn kept_text(&self, then: &str) -> String {
        match self {
            Placed::InPlace(_) => String::new(),
            Placed::Beside { target, kept } => {
                let this = match kept {
                    Some(k) => format!("this run's work is kept in {} {then}", k.display()),
                    None => "nothing of this run was kept (it had no partial result)".into(),
                };
                format!(
                    "; {} keeps its complete run, which a run that failed or was interrupted does not replace \
                     (--force does); {this}",
                    target.display()
                )
            }
        }
    }
}

/// Is there beside the output folder `target` a staging folder that a run described by
/// `manifest` can continue ([`Mode::Resume`]): a run that was killed, stopped by a full disk,
/// or failed or was interrupted beside a complete run ([`Placed::Beside`])? Read without the
/// folder's lock; [`RunFolder::begin`] decides again under it.
pub fn resumable_beside(target: &Path, manifest: &Manifest) -> bool {
    let Ok((_, parent, name)) = locate(target) else { return false };
    let Ok((left, _)) = leftovers(&parent, &name) else { return false };
    left.iter()
        .filter(|l| l.in_progress())
        .any(|l| l.manifest.as_ref().is_some_and(|m| super::manifest::check_resumable(m, manifest).is_ok()))
}

/// `--resume`: make the staging folder `staging` the run to continue ([`resume_source`]): a
/// left staging folder taken over (renamed), or a copy of the output folder. Returns the
/// manifest of the run continued. A full disk on the way leaves the run's frames where they
/// were (a taken-over folder gets its name back) and says so ([`FolderError::ResumeDiskFull`]).
fn adopt(
    target: &Path,
    old: Option<&Manifest>,
    left: &mut Vec<Leftover>,
    manifest: &Manifest,
    staging: &Path,
    notes: &mut Vec<String>,
) -> Result<Manifest, FolderError> {
    let (source, previous) = resume_source(target, old, left, manifest)?;
    // the folder that holds the frames, and whether it is a copy (what it needs on disk)
    let (from, copied) = match source {
        ResumeSource::Leftover(i) => {
            let dir = left.remove(i).dir;
            if dir != staging {
                std::fs::rename(&dir, staging).map_err(io_err(&dir))?;
            }
            notes.push(format!("resuming the run that was stopped while writing {}", dir.display()));
            (dir, false)
        }
        ResumeSource::Target => {
            if let Some(i) = left.iter().position(|l| l.dir == staging) {
                let dir = left.remove(i).dir;
                std::fs::remove_dir_all(&dir).map_err(io_err(&dir))?;
            }
            (target.to_path_buf(), true)
        }
    };
    let prepared = if copied { copy_run(target, staging) } else { Ok(()) };
    let prepared = prepared.and_then(|()| remove_temporaries(staging)).and_then(|()| {
        // run.json says running from here on: written now, so a full disk is found before
        // the run starts (and the taken-over folder keeps its own until then)
        let mut running = manifest.clone();
        running.status = Status::Running;
        running.write(staging)
    });
    match prepared {
        Ok(()) => Ok(previous),
        Err(e) if crate::io::disk::is_full(&e) => {
            if !copied && from != staging {
                let _ = std::fs::rename(staging, &from);
            }
            let need = if copied {
                format!(
                    "; the copy that --resume works in needs {}",
                    crate::io::disk::bytes_text(crate::io::files::folder_bytes(target))
                )
            } else {
                String::new()
            };
            Err(FolderError::ResumeDiskFull {
                space: crate::io::disk::full_text(target),
                path: target.to_path_buf(),
                frames: journal_frames(&from),
                kept: from,
                need,
                source: Box::new(e),
            })
        }
        Err(e) => Err(e),
    }
}

/// The names in a folder.
fn list_entries(dir: &Path) -> Result<Vec<String>, FolderError> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io_err(dir))? {
        out.push(entry.map_err(io_err(dir))?.file_name().to_string_lossy().into_owned());
    }
    out.sort();
    Ok(out)
}
