//! Writing files atomically, CSV text with SI units in the column names, and the errors of
//! reading and writing files. Every output of the crate goes through [`write_atomic`]: it is
//! written to a temporary name in the target directory and renamed into place, so a failure
//! never leaves a half-written file; files are created with the process's umask (readable by
//! others where the umask says so).
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::plot::PlotError;

/// Errors while writing outputs; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot write {path}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot write plot {path}")]
    Plot {
        path: PathBuf,
        #[source]
        source: PlotError,
    },
    #[error("cannot write {path}: {reason}")]
    Invalid { path: PathBuf, reason: String },
}

/// Errors reading an input file; each names the file and, where it applies, the row, frame,
/// node or joint.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    #[error("cannot read {path}")]
    Open {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot read {path}")]
    Csv {
        path: PathBuf,
        #[source]
        source: csv::Error,
    },
    #[error("{path}: header {found:?}, expected {expected:?}")]
    Header { path: PathBuf, found: Vec<String>, expected: Vec<String> },
    #[error("{path}, row {row}: {reason}")]
    Row { path: PathBuf, row: usize, reason: String },
    #[error("{path}: not a little-endian float64 C-order .npy file: {reason}")]
    Npy { path: PathBuf, reason: String },
    #[error("{path}: {reason}")]
    Shape { path: PathBuf, reason: String },
    #[error("{path}, frame {frame}, joint {joint}: angle {value} is not finite")]
    NonFiniteAngle { path: PathBuf, frame: usize, joint: usize, value: f64 },
    #[error("{path}, frame {frame}, node {node}: {axis} = {value} is not finite")]
    NonFinitePosition { path: PathBuf, frame: usize, node: usize, axis: char, value: f64 },
    #[error("{path}, frame {frame}: {nodes} nodes, but frame 0 has {expected}")]
    NodeCount { path: PathBuf, frame: usize, nodes: usize, expected: usize },
    #[error("{path}, frame {frame}, node {node}: no row (frames and nodes must be contiguous from 0)")]
    MissingRow { path: PathBuf, frame: usize, node: usize },
    #[error("{path}, row {row}: frame {frame}, node {node} already given in row {first_row}")]
    DuplicateRow { path: PathBuf, row: usize, first_row: usize, frame: usize, node: usize },
}

static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Write `bytes` to `path` atomically: a temporary file next to it (created with the umask's
/// permissions), then a rename; the temporary file is removed on failure. Creates the
/// directory if needed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let err = |source| OutputError::Io { path: path.to_path_buf(), source };
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(err)?;
    let name = path
        .file_name()
        .ok_or_else(|| err(std::io::Error::new(std::io::ErrorKind::InvalidInput, "path has no file name")))?;
    let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp = dir.join(format!(".{}.{}.{n}.tmp", name.to_string_lossy(), std::process::id()));
    let result = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)
        .and_then(|mut f| f.write_all(bytes))
        .and_then(|_| std::fs::rename(&tmp, path));
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(err(e));
    }
    Ok(())
}

/// Write an SVG rendered by `crate::io::plot`; a rendering error names the file.
pub fn write_plot(path: &Path, svg: Result<String, PlotError>) -> Result<(), OutputError> {
    let svg = svg.map_err(|source| OutputError::Plot { path: path.to_path_buf(), source })?;
    write_atomic(path, svg.as_bytes())
}

/// CSV text: the header, then one line per row, every value with 17 significant digits.
pub fn csv_text(header: &[&str], rows: impl Iterator<Item = Vec<f64>>) -> String {
    csv_text_opt(header, rows.map(|r| r.into_iter().map(Some).collect()))
}

/// CSV with empty fields where a value does not apply.
pub fn csv_text_opt(header: &[&str], rows: impl Iterator<Item = Vec<Option<f64>>>) -> String {
    let mut s = header.join(",");
    s.push('\n');
    for r in rows {
        let line: Vec<String> = r.iter().map(|v| v.map(|v| format!("{v:.17e}")).unwrap_or_default()).collect();
        s.push_str(&line.join(","));
        s.push('\n');
    }
    s
}

/// A CSV reader of `path` whose header must be `expected` (fields trimmed).
pub fn csv_reader(path: &Path, expected: &[&str]) -> Result<csv::Reader<std::fs::File>, InputError> {
    let csv_err = |source| InputError::Csv { path: path.to_path_buf(), source };
    let mut rdr = csv::ReaderBuilder::new().trim(csv::Trim::All).from_path(path).map_err(csv_err)?;
    let found: Vec<String> = rdr.headers().map_err(csv_err)?.iter().map(String::from).collect();
    if found != expected {
        return Err(InputError::Header {
            path: path.to_path_buf(),
            found,
            expected: expected.iter().map(|s| s.to_string()).collect(),
        });
    }
    Ok(rdr)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_writes_replace_files_and_leave_no_temporaries() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("sub/a.csv");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        let left: Vec<_> = std::fs::read_dir(p.parent().unwrap()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(left, vec![std::ffi::OsString::from("a.csv")]);
        // A directory in the way: the error names the path and nothing is left behind.
        std::fs::create_dir(dir.path().join("d")).unwrap();
        let e = write_atomic(&dir.path().join("d"), b"x").unwrap_err();
        assert!(e.to_string().contains("/d"), "{e}");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }

    #[cfg(unix)]
    #[test]
    fn files_follow_the_umask() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.csv");
        write_atomic(&p, b"x").unwrap();
        let direct = dir.path().join("direct");
        std::fs::write(&direct, b"x").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&p), mode(&direct), "same permissions as a plainly created file");
    }
}
