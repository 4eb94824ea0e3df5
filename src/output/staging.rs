//! What runs leave beside an output folder and how the next run deals with it
//! (`super::run_folder`): the staging folders of runs that ended early, the choice of the run
//! that `--resume` continues and its copy, and the exchange that puts a finished staging folder
//! in place.
use std::path::{Path, PathBuf};

use super::manifest::{check_resumable, io_err, FolderError, Manifest, ResumeRefusal, Status, MANIFEST};
use crate::io::files::is_temporary;

/// A staging folder `.NAME.staging-PID` left beside an output folder by a run that ended
/// before it put it in place (killed, or stopped by a full disk).
#[derive(Debug)]
pub(super) struct Leftover {
    pub(super) dir: PathBuf,
    pub(super) pid: u32,
    pub(super) manifest: Option<Manifest>,
}

impl Leftover {
    /// Does it hold the work of a run that did not end normally? Its `run.json` says running
    /// (killed while it ran), or was written by the process of its name (ended by a full disk:
    /// kept to be resumed). A folder that replaced the output folder in the swap at the end of
    /// a run holds the previous output folder (finished, written by another process) for an
    /// instant, and is no run's work.
    pub(super) fn in_progress(&self) -> bool {
        self.manifest.as_ref().is_some_and(|m| m.status == Status::Running || m.process.pid == self.pid)
    }
}

/// What runs that ended before putting `NAME` in place left in `parent`: their staging folders,
/// and the folders of an interrupted swap (`.NAME.swap-PID`, `.NAME.old-PID`), which hold
/// nothing to keep.
pub(super) fn leftovers(parent: &Path, name: &str) -> Result<(Vec<Leftover>, Vec<PathBuf>), FolderError> {
    let (staging, others) = (format!(".{name}.staging-"), [format!(".{name}.swap-"), format!(".{name}.old-")]);
    let pid_after = |n: &str, prefix: &str| n.strip_prefix(prefix).and_then(|p| p.parse::<u32>().ok());
    let (mut stagings, mut rest) = (Vec::new(), Vec::new());
    for entry in std::fs::read_dir(parent).map_err(io_err(parent))? {
        let entry = entry.map_err(io_err(parent))?;
        let n = entry.file_name().to_string_lossy().into_owned();
        if let Some(pid) = pid_after(&n, &staging) {
            // an unreadable run.json is no run's work
            let manifest = Manifest::read(&entry.path()).ok().flatten();
            stagings.push(Leftover { dir: entry.path(), pid, manifest });
        } else if others.iter().any(|p| pid_after(&n, p).is_some()) {
            rest.push(entry.path());
        }
    }
    stagings.sort_by(|a, b| a.dir.cmp(&b.dir));
    Ok((stagings, rest))
}

/// Converged frames in the resume journal of `dir` (0 without one).
pub(super) fn journal_frames(dir: &Path) -> usize {
    super::journal::scan_journal(dir).map(|scan| scan.frames.len()).unwrap_or(0)
}

/// Where a resumed run continues from.
pub(super) enum ResumeSource {
    /// a staging folder left by a run that was killed (or stopped by a full disk): adopted
    Leftover(usize),
    /// the output folder itself: copied, so that it stays in place until the resumed run ends
    Target,
}

/// The run that `--resume` continues: among the left staging folders in progress and the
/// output folder, those that `new` may continue ([`check_resumable`]), the one with the most
/// converged frames (a left folder on a tie: it is taken over, not copied).
pub(super) fn resume_source(
    target: &Path,
    old: Option<&Manifest>,
    left: &[Leftover],
    new: &Manifest,
) -> Result<(ResumeSource, Manifest), FolderError> {
    let cannot = |reason: ResumeRefusal| FolderError::CannotResume { path: target.to_path_buf(), reason };
    let mut best: Option<(usize, ResumeSource, Manifest)> = None;
    for (i, l) in left.iter().enumerate() {
        let m = l.manifest.clone().unwrap_or_else(|| new.clone());
        if check_resumable(&m, new).is_ok() {
            let frames = journal_frames(&l.dir);
            if best.as_ref().is_none_or(|b| frames > b.0) {
                best = Some((frames, ResumeSource::Leftover(i), m));
            }
        }
    }
    let target_reason = match old {
        None => Some(ResumeRefusal::NoManifest),
        Some(m) => match check_resumable(m, new) {
            Ok(()) => {
                let frames = journal_frames(target);
                if best.as_ref().is_none_or(|b| frames > b.0) {
                    best = Some((frames, ResumeSource::Target, m.clone()));
                }
                None
            }
            Err(reason) => Some(reason),
        },
    };
    // `best` is set when the target is resumable, so a missing `best` has a target reason
    best.map(|(_, source, m)| (source, m)).ok_or_else(|| cannot(target_reason.unwrap_or(ResumeRefusal::NoManifest)))
}

/// Remove the temporary files of atomic writes under `dir`: a run killed while it wrote one
/// leaves it, and the run that takes its folder over writes that file anew.
pub(super) fn remove_temporaries(dir: &Path) -> Result<(), FolderError> {
    for entry in std::fs::read_dir(dir).map_err(io_err(dir))? {
        let entry = entry.map_err(io_err(dir))?;
        let p = entry.path();
        if entry.file_type().map_err(io_err(&p))?.is_dir() {
            remove_temporaries(&p)?;
        } else if is_temporary(&entry.file_name().to_string_lossy()) {
            std::fs::remove_file(&p).map_err(io_err(&p))?;
        }
    }
    Ok(())
}

/// Copy the folder `from` into the new folder `to` (files and subfolders; `run.json` at the
/// top excepted: the run writes its own).
pub(super) fn copy_run(from: &Path, to: &Path) -> Result<(), FolderError> {
    // `skipped`: the name of a file not copied (the top folder's `run.json`)
    fn copy(from: &Path, to: &Path, skipped: Option<&str>) -> Result<(), FolderError> {
        std::fs::create_dir(to).map_err(io_err(to))?;
        for entry in std::fs::read_dir(from).map_err(io_err(from))? {
            let entry = entry.map_err(io_err(from))?;
            let (src, dst) = (entry.path(), to.join(entry.file_name()));
            if entry.file_type().map_err(io_err(&src))?.is_dir() {
                copy(&src, &dst, None)?;
            } else if skipped.is_none_or(|s| entry.file_name() != s) {
                std::fs::copy(&src, &dst).map_err(io_err(&dst))?;
            }
        }
        Ok(())
    }
    copy(from, to, Some(MANIFEST)).inspect_err(|_| {
        let _ = std::fs::remove_dir_all(to);
    })
}

/// Put the folder `staging` in place of `target`. Where `target` exists, the two are exchanged
/// in one system call (`renameat2(RENAME_EXCHANGE)`, Linux 3.15; so a kill at any moment leaves
/// `target` either the previous folder or the new one) and the previous folder, now at
/// `staging`, is removed. Where the file system cannot exchange (NFS), it takes two renames,
/// between which `target` is briefly absent.
pub(super) fn put_in_place(staging: &Path, target: &Path) -> Result<(), FolderError> {
    if std::fs::symlink_metadata(target).is_err() {
        return std::fs::rename(staging, target).map_err(io_err(staging));
    }
    match exchange(staging, target) {
        Ok(()) => {
            // the previous folder; a failure here leaves it to the next run (a leftover)
            let _ = std::fs::remove_dir_all(staging);
            Ok(())
        }
        Err(e) if matches!(e.raw_os_error(), Some(code) if EXCHANGE_UNSUPPORTED.contains(&code)) => {
            let name = target.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
            let parent = staging.parent().unwrap_or(Path::new("."));
            let old = parent.join(format!(".{name}.swap-{}", std::process::id()));
            std::fs::rename(target, &old).map_err(io_err(target))?;
            if let Err(source) = std::fs::rename(staging, target) {
                let _ = std::fs::rename(&old, target);
                return Err(FolderError::Io { path: staging.to_path_buf(), source });
            }
            let _ = std::fs::remove_dir_all(&old);
            Ok(())
        }
        Err(source) => Err(FolderError::Io { path: target.to_path_buf(), source }),
    }
}

/// `errno` of a file system or kernel that cannot exchange two names: EINVAL, ENOSYS,
/// EOPNOTSUPP.
const EXCHANGE_UNSUPPORTED: [i32; 3] = [22, 38, 95];

/// Exchange the names `a` and `b` atomically.
#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use rustix::fs::{renameat_with, RenameFlags, CWD};
    renameat_with(CWD, a, CWD, b, RenameFlags::EXCHANGE).map_err(std::io::Error::from)
}

#[cfg(not(target_os = "linux"))]
fn exchange(_: &Path, _: &Path) -> std::io::Result<()> {
    Err(std::io::Error::from_raw_os_error(EXCHANGE_UNSUPPORTED[1]))
}
