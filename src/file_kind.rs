//! What kind of file an input path names, found without opening it. Opening a FIFO for reading
//! blocks until a writer appears (forever, when none does), and a device or a folder is no
//! input at all, so every input file (case file, clip file, recording, audit spec) is checked
//! with [`kind`] (a `stat`, which never blocks) and refused unless it is a regular file.
use std::path::Path;

/// The kind of a file system entry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    Regular,
    Directory,
    /// a named pipe
    Fifo,
    CharDevice,
    BlockDevice,
    Socket,
    Other,
}

impl FileKind {
    /// The kind in words, for messages ("a named pipe (FIFO)").
    pub fn describe(self) -> &'static str {
        match self {
            FileKind::Regular => "a regular file",
            FileKind::Directory => "a folder",
            FileKind::Fifo => "a named pipe (FIFO)",
            FileKind::CharDevice => "a character device",
            FileKind::BlockDevice => "a block device",
            FileKind::Socket => "a socket",
            FileKind::Other => "not a regular file",
        }
    }

    /// The kind of the entry `meta` describes.
    pub fn of(meta: &std::fs::Metadata) -> FileKind {
        let t = meta.file_type();
        if t.is_file() {
            return FileKind::Regular;
        }
        if t.is_dir() {
            return FileKind::Directory;
        }
        #[cfg(unix)]
        {
            use std::os::unix::fs::FileTypeExt;
            if t.is_fifo() {
                return FileKind::Fifo;
            }
            if t.is_char_device() {
                return FileKind::CharDevice;
            }
            if t.is_block_device() {
                return FileKind::BlockDevice;
            }
            if t.is_socket() {
                return FileKind::Socket;
            }
        }
        FileKind::Other
    }
}

/// The kind of the file `path` names (symbolic links followed), without opening it.
pub fn kind(path: &Path) -> std::io::Result<FileKind> {
    std::fs::metadata(path).map(|m| FileKind::of(&m))
}

/// Is `path` this process's standard input (the file of descriptor 0: `/dev/stdin`, or the
/// pipe a case is piped through)? A pipe read there blocks only on what the user piped in.
pub fn is_standard_input(path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::fd::AsFd;
        use std::os::unix::fs::MetadataExt;
        let stdin = std::io::stdin();
        let Ok(fd) = stdin.as_fd().try_clone_to_owned() else { return false };
        match (std::fs::File::from(fd).metadata(), std::fs::metadata(path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = path;
        false
    }
}

/// The sentence of an error refusing `path` of kind `kind` as `what` (an input file).
pub fn not_regular_text(path: &Path, what: &str, kind: FileKind) -> String {
    format!(
        "{}: the {what} is {}, not a regular file; give the path of a file (a pipe or device is not read, as it may never end)",
        path.display(),
        kind.describe()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(unix)]
    #[test]
    fn kinds_are_found_without_opening() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("f");
        std::fs::write(&file, "x").unwrap();
        assert_eq!(kind(&file).unwrap(), FileKind::Regular);
        assert_eq!(kind(dir.path()).unwrap(), FileKind::Directory);
        assert_eq!(kind(Path::new("/dev/null")).unwrap(), FileKind::CharDevice);
        let fifo = dir.path().join("p");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|s| s.success()) {
            // no reader or writer: opening would block; the stat does not
            assert_eq!(kind(&fifo).unwrap(), FileKind::Fifo);
        }
        assert!(kind(&dir.path().join("none")).is_err());
    }
}
