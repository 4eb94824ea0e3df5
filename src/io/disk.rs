//! A full disk (or an exhausted quota): recognised in an error's chain of causes, and described
//! with the folder and the space left, so that a run stopped by it can say where space is
//! needed and how much there is.
use std::error::Error;
use std::path::Path;

/// `errno` values of a full disk: ENOSPC (no space left on device), EDQUOT (disk quota
/// exceeded).
const FULL: [i32; 2] = [28, 122];

/// Was `e`, or any of its causes, a write refused because the disk (or the quota) is full?
pub fn is_full(e: &(dyn Error + 'static)) -> bool {
    let mut cause = Some(e);
    while let Some(c) = cause {
        if matches!(c.downcast_ref::<super::files::OutputError>(), Some(super::files::OutputError::DiskFull { .. })) {
            return true;
        }
        if let Some(io) = c.downcast_ref::<std::io::Error>() {
            if io.raw_os_error().is_some_and(|code| FULL.contains(&code))
                || matches!(io.kind(), std::io::ErrorKind::StorageFull | std::io::ErrorKind::QuotaExceeded)
            {
                return true;
            }
        }
        cause = c.source();
    }
    false
}

/// Bytes available to this user on the file system holding `path`, and its size.
pub fn free_bytes(path: &Path) -> Option<(u64, u64)> {
    #[cfg(unix)]
    {
        let s = rustix::fs::statvfs(path).ok()?;
        Some((s.f_bavail.saturating_mul(s.f_frsize), s.f_blocks.saturating_mul(s.f_frsize)))
    }
    #[cfg(not(unix))]
    {
        let _ = path;
        None
    }
}

/// "the disk holding FOLDER is full (12 KiB free of 2 MiB)".
pub fn full_text(folder: &Path) -> String {
    let space = match free_bytes(folder.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."))) {
        Some((free, size)) => format!("{} free of {}", bytes_text(free), bytes_text(size)),
        None => "free space unknown".into(),
    };
    format!("the disk holding {} is full ({space})", folder.display())
}

/// A size for people: `2 MiB`, `1.5 MiB`, `48 KiB`, `700 bytes`.
pub fn bytes_text(n: u64) -> String {
    match [(30, "GiB"), (20, "MiB"), (10, "KiB")].into_iter().find(|(shift, _)| n >= 1 << shift) {
        Some((shift, unit)) if n.is_multiple_of(1 << shift) => format!("{} {unit}", n >> shift),
        Some((shift, unit)) => format!("{:.1} {unit}", n as f64 / (1u64 << shift) as f64),
        None => format!("{n} bytes"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("writing the clip")]
    struct Outer(#[source] std::io::Error);

    #[test]
    fn a_full_disk_is_found_among_the_causes() {
        let full = Outer(std::io::Error::from_raw_os_error(28));
        assert!(is_full(&full));
        assert!(!is_full(&Outer(std::io::Error::from_raw_os_error(13))));
        assert_eq!(
            (bytes_text(2 << 20), bytes_text(1536 << 10), bytes_text(700)),
            ("2 MiB".into(), "1.5 MiB".into(), "700 bytes".into())
        );
        assert!(free_bytes(Path::new("/")).is_some_and(|(free, size)| free <= size));
    }
}
