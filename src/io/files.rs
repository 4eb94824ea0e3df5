//! Writing files atomically, CSV text with SI units in the column names, and the errors of
//! reading and writing files. Every output of the crate goes through [`write_atomic`]: it is
//! written to a temporary name in the target directory and renamed into place, so a failure
//! never leaves a half-written file; files are created with the process's umask (readable by
//! others where the umask says so). Every input file is read through [`read_capped`], which
//! refuses a file larger than its reader's cap before reading it, and stops reading a device or
//! pipe that never ends at the cap.
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::figures::plot::PlotError;

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
    #[error("cannot write {path}: {reason}")]
    Zip { path: PathBuf, reason: ZipError },
    /// a part of the output (a sweep's point) could not be written for want of space
    #[error("{path}: {message}")]
    DiskFull { path: PathBuf, message: String },
}

/// Errors of reading the resume journal of a clip run (`crate::output::journal`). (Here, not in
/// `journal`, so that the engines' error can name it without importing the output folder.)
#[derive(Debug, thiserror::Error)]
pub enum JournalError {
    #[error("{path} does not exist: this folder holds no clip run that can be resumed")]
    Missing { path: PathBuf },
    #[error("cannot read {path}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
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
    Npy { path: PathBuf, reason: Box<NpyError> },
    #[error("{path}: {reason}")]
    Shape { path: PathBuf, reason: String },
    #[error("{path}: {reason}")]
    Compact { path: PathBuf, reason: Box<CompactError> },
    #[error("{path}, frame {frame}, joint {joint}: angle {value} is not finite")]
    NonFiniteAngle { path: PathBuf, frame: usize, joint: usize, value: f64 },
    #[error(
        "{path}, frame {frame}, node {node}: {axis} = {value} is not finite{}",
        if value.is_nan() { " (if the tracker marks untracked nodes with NaN, set clip.missing = \"nan\" in the case)" } else { "" }
    )]
    NonFinitePosition { path: PathBuf, frame: usize, node: usize, axis: char, value: f64 },
    #[error("{path}, frame {frame}: {nodes} nodes, but frame 0 has {expected}")]
    NodeCount { path: PathBuf, frame: usize, nodes: usize, expected: usize },
    #[error(
        "{path}, frame {frame}, node {node}: no row (nodes are numbered contiguously from 0 or 1; if the tracker \
         leaves untracked nodes out, set clip.missing = \"nan\" in the case)"
    )]
    MissingRow { path: PathBuf, frame: usize, node: usize },
    #[error(
        "{path}, row {row}: frame {next} comes where frame {frame} was expected: frame {frame} has no rows (a \
         dropped frame? with clip.missing = \"nan\" it is a lost frame, bridged from its neighbours; or is the \
         frame column a timestamp, or a -1 written unsigned?)"
    )]
    FrameGap { path: PathBuf, frame: usize, next: usize, row: usize },
    #[error("{path}, row {row}: frame {frame}, node {node} already given in row {first_row}")]
    DuplicateRow { path: PathBuf, row: usize, first_row: usize, frame: usize, node: usize },
    #[error("{}", too_large_text(path, what, *.size, *.cap))]
    TooLarge {
        path: PathBuf,
        what: &'static str,
        /// the size of a regular file; `None`: more than `cap` bytes were read from a stream
        size: Option<u64>,
        cap: u64,
    },
    #[error("{}", crate::file_kind::not_regular_text(path, what, *kind))]
    NotRegular { path: PathBuf, what: &'static str, kind: crate::file_kind::FileKind },
    #[error("{path}: {what} is not UTF-8 text (invalid byte at offset {offset})")]
    NotText { path: PathBuf, what: &'static str, offset: usize },
}

/// Why the bytes of an `.npy` file are not a C-order array [`super::npy`] takes; the file's
/// name is the caller's ([`InputError::Npy`]). Text from the file is shown by its first 40
/// characters. (Here, not in `npy`, so that `npy` imports `files` and not the other way.)
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NpyError {
    #[error("missing the magic string \\x93NUMPY (not an .npy file, or truncated)")]
    NoMagic,
    #[error("truncated in the header length")]
    TruncatedHeaderLength,
    #[error("format version {major}.x is not supported (1.0, 2.0 or 3.0)")]
    Version { major: u8 },
    #[error("truncated: the header is {header_len} bytes, the file ends before it does")]
    TruncatedHeader { header_len: usize },
    #[error("the header is not text")]
    HeaderNotText,
    #[error("Fortran-order array (fortran_order: True); expected C order")]
    FortranOrder,
    #[error("dtype '{descr}', expected little-endian float64 '<f8'")]
    Dtype { descr: String },
    #[error("shape overflows")]
    ShapeOverflow,
    #[error("truncated: shape {shape:?} needs {expected} data bytes, the file has {found}")]
    TruncatedData { shape: Vec<usize>, expected: usize, found: usize },
    #[error("{extra} bytes after the data of shape {shape:?} ({expected} bytes)")]
    TrailingBytes { extra: usize, shape: Vec<usize>, expected: usize },
    #[error("header {header:?} is not a dictionary")]
    NotDictionary { header: String },
    #[error("header {header:?}: expected a quoted key at {at:?}")]
    ExpectedKey { header: String, at: String },
    #[error("header: key '{key}' given twice")]
    DuplicateKey { key: String },
    #[error("header: expected ':' after '{key}'")]
    ExpectedColon { key: String },
    #[error("header: 'descr' is not a quoted string (structured dtypes are not supported)")]
    DescrNotString,
    #[error("header: 'fortran_order' is neither True nor False at {at:?}")]
    FortranNotBool { at: String },
    #[error("header: 'shape' is not a tuple")]
    ShapeNotTuple,
    #[error("header: 'shape' tuple is not closed")]
    ShapeNotClosed,
    #[error("header: shape has more than {MAX_AXES} axes, the most an array has")]
    TooManyAxes,
    #[error("header: shape entry '{entry}' is not a non-negative integer")]
    ShapeEntry { entry: String },
    #[error("header: unknown key '{key}'")]
    UnknownKey { key: String },
    #[error("header has no '{key}'")]
    MissingKey { key: &'static str },
}

/// Most axes of an array (NumPy 2's `NPY_MAXDIMS`).
pub(super) const MAX_AXES: usize = 64;

/// Why `fields.npz` could not be made; the file's name is the caller's ([`OutputError::Zip`]).
#[derive(Debug, thiserror::Error)]
pub enum ZipError {
    #[error("deflate: {0}")]
    Deflate(flate2::CompressError),
    /// `what`: a member's name, "the archive" or "the directory"
    #[error("{what} exceeds 4 GiB (zip without Zip64)")]
    TooLarge { what: String },
    #[error("more than 65535 members ({count})")]
    TooManyMembers { count: usize },
}

/// Why the bytes of a `fields.npz` are not a compact clip; the file's name is the caller's
/// ([`InputError::Compact`]), the member's is in the variant.
#[derive(Debug, thiserror::Error)]
pub enum CompactError {
    #[error("not a zip archive (no end of central directory)")]
    NotZip,
    #[error("truncated zip")]
    Truncated,
    #[error("corrupt zip central directory")]
    CorruptDirectory,
    #[error("{name}: truncated")]
    MemberTruncated { name: String },
    #[error("{name}: {error}")]
    Inflate { name: String, error: std::io::Error },
    #[error("{name}: compression method {method} (expected deflate)")]
    Method { name: String, method: usize },
    #[error("{name}: size or CRC does not match (corrupt archive)")]
    Corrupt { name: String },
    #[error("{name}: {reason}")]
    Npy { name: String, reason: NpyError },
    #[error("{name}: unexpected array {descr} {shape:?}")]
    UnexpectedArray { name: String, descr: String, shape: Vec<usize> },
}

/// The message of `InputError::TooLarge`.
fn too_large_text(path: &Path, what: &str, size: Option<u64>, cap: u64) -> String {
    let cap_text = format!("{cap} bytes ({}), the cap for {what}s", human_bytes(cap));
    match size {
        Some(n) => format!("{}: {what} of {n} bytes is larger than {cap_text}", path.display()),
        None => format!(
            "{}: {what} is not a regular file and did not end within {cap_text}: reading stopped there",
            path.display()
        ),
    }
}

/// `n` bytes in the largest binary unit that divides it (`1 MiB`, `256 MiB`, `1 GiB`).
pub fn human_bytes(n: u64) -> String {
    match [(30, "GiB"), (20, "MiB"), (10, "KiB")]
        .iter()
        .find(|(shift, _)| n >= 1 << shift && n.is_multiple_of(1 << shift))
    {
        Some(&(shift, unit)) => format!("{} {unit}", n >> shift),
        None => format!("{n} bytes"),
    }
}

/// The whole content of the input file `path` (`what` names its kind in messages: "recording",
/// "kymogram", …), refused if it holds more than `cap` bytes. Anything but a regular file (a
/// pipe, whose open blocks until a writer comes; a device such as `/dev/zero`, which never
/// ends; a folder) is refused before it is opened ([`check_regular`]); a regular file is
/// refused by its size before it is read, and read through `Read::take(cap + 1)` in case it
/// grows meanwhile. The caps are chosen per reader, far above any real input of its kind.
pub fn read_capped(path: &Path, cap: u64, what: &'static str) -> Result<Vec<u8>, InputError> {
    let (file, size) = open_capped(path, cap, what)?;
    read_to_cap(path, file, Some(size), (cap, what))
}

/// [`read_capped`] that also takes the pipe of this process's standard input
/// (`cosserat run /dev/stdin < case.toml`), read to its end as piped, within the same cap: a
/// named pipe would still block its open, a device never end, so both are refused.
pub fn read_capped_or_stdin(path: &Path, cap: u64, what: &'static str) -> Result<Vec<u8>, InputError> {
    use crate::file_kind::{is_standard_input, kind, FileKind};
    match kind(path) {
        Ok(FileKind::Regular) => read_capped(path, cap, what),
        Ok(FileKind::Fifo) if is_standard_input(path) => {
            let file =
                std::fs::File::open(path).map_err(|source| InputError::Open { path: path.to_path_buf(), source })?;
            read_to_cap(path, file, None, (cap, what))
        }
        Ok(kind) => Err(InputError::NotRegular { path: path.to_path_buf(), what, kind }),
        Err(source) => Err(InputError::Open { path: path.to_path_buf(), source }),
    }
}

/// Read the opened `file` (`path`; `size` [bytes] of a regular file, `None` for the standard
/// input's pipe) to its end through `Read::take(cap + 1)`: refused if it holds more than `cap`
/// bytes (a regular file that grew while it was read).
fn read_to_cap(
    path: &Path,
    file: std::fs::File,
    size: Option<u64>,
    (cap, what): (u64, &'static str),
) -> Result<Vec<u8>, InputError> {
    let mut bytes = Vec::with_capacity(usize::try_from(size.unwrap_or(0).min(cap)).unwrap_or(0));
    file.take(cap.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|source| InputError::Open { path: path.to_path_buf(), source })?;
    if bytes.len() as u64 > cap {
        // A regular file that grew while it was read has at least this many bytes.
        let size = size.map(|_| bytes.len() as u64);
        return Err(InputError::TooLarge { path: path.to_path_buf(), what, size, cap });
    }
    Ok(bytes)
}

/// Open the regular file `path` to be read as it goes (not held whole) if it has at most `cap`
/// bytes: refused before it is opened if it is not a regular file ([`check_regular`]), and by
/// its size. Returns the file and its size [bytes].
pub fn open_capped(path: &Path, cap: u64, what: &'static str) -> Result<(std::fs::File, u64), InputError> {
    check_regular(path, what)?;
    let open = |source| InputError::Open { path: path.to_path_buf(), source };
    let file = std::fs::File::open(path).map_err(open)?;
    let meta = file.metadata().map_err(open)?;
    if !meta.is_file() {
        // replaced between the check and the open
        let kind = crate::file_kind::FileKind::of(&meta);
        return Err(InputError::NotRegular { path: path.to_path_buf(), what, kind });
    }
    if meta.len() > cap {
        return Err(InputError::TooLarge { path: path.to_path_buf(), what, size: Some(meta.len()), cap });
    }
    Ok((file, meta.len()))
}

/// `Ok` if `path` is a regular file (symbolic links followed), found without opening it
/// (`crate::file_kind`); the error names the input (`what`) and what the path is instead.
pub fn check_regular(path: &Path, what: &'static str) -> Result<(), InputError> {
    use crate::file_kind::{kind, FileKind};
    match kind(path) {
        Ok(FileKind::Regular) => Ok(()),
        Ok(kind) => Err(InputError::NotRegular { path: path.to_path_buf(), what, kind }),
        Err(source) => Err(InputError::Open { path: path.to_path_buf(), source }),
    }
}

/// [`read_capped`] for a text file: its content must be UTF-8.
pub fn read_capped_text(path: &Path, cap: u64, what: &'static str) -> Result<String, InputError> {
    String::from_utf8(read_capped(path, cap, what)?).map_err(|e| InputError::NotText {
        path: path.to_path_buf(),
        what,
        offset: e.utf8_error().valid_up_to(),
    })
}

static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Bytes of the files under `dir` [bytes], its sub-folders included; what cannot be read counts 0
/// (an output folder's size: the audit's REPORT.md, the copy `--resume` needs).
pub fn folder_bytes(dir: &Path) -> u64 {
    std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| match e.file_type() {
            Ok(t) if t.is_dir() => folder_bytes(&e.path()),
            Ok(_) => e.metadata().map(|m| m.len()).unwrap_or(0),
            Err(_) => 0,
        })
        .sum()
}

/// Is `name` the temporary file of an atomic write ([`write_atomic`])? A run killed while it
/// wrote one leaves it behind.
pub fn is_temporary(name: &str) -> bool {
    name.starts_with('.') && name.ends_with(".tmp")
}

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

/// Write an SVG rendered by `crate::figures::plot`; a rendering error names the file.
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
    csv_text_int(header, &[], rows)
}

/// [`csv_text_opt`] with the columns named in `integers` (iteration counts, indices, flags)
/// written as integers (`12`, not `1.20000000000000000e1`).
pub fn csv_text_int(header: &[&str], integers: &[&str], rows: impl Iterator<Item = Vec<Option<f64>>>) -> String {
    let integer: Vec<bool> = header.iter().map(|h| integers.contains(h)).collect();
    let mut s = header.join(",");
    s.push('\n');
    for r in rows {
        for (k, v) in r.iter().enumerate() {
            if k > 0 {
                s.push(',');
            }
            match v {
                Some(v) if integer.get(k).copied().unwrap_or(false) => super::number::push_integer(&mut s, *v, 17),
                Some(v) => s.push_str(&format!("{v:.17e}")),
                None => {}
            }
        }
        s.push('\n');
    }
    s
}

/// A CSV reader of `path` whose header must be `expected` (fields trimmed).
pub fn csv_reader(path: &Path, expected: &[&str]) -> Result<csv::Reader<std::fs::File>, InputError> {
    let csv_err = |source| InputError::Csv { path: path.to_path_buf(), source };
    let rdr = csv::ReaderBuilder::new().trim(csv::Trim::All).from_path(path).map_err(csv_err)?;
    with_header(path, rdr, expected)
}

/// A CSV reader of the input file `path`, read whole through [`read_capped`], whose header
/// must be `expected` (fields trimmed).
pub fn csv_reader_capped(
    path: &Path,
    cap: u64,
    what: &'static str,
    expected: &[&str],
) -> Result<csv::Reader<std::io::Cursor<Vec<u8>>>, InputError> {
    let bytes = read_capped(path, cap, what)?;
    let rdr = csv::ReaderBuilder::new().trim(csv::Trim::All).from_reader(std::io::Cursor::new(bytes));
    with_header(path, rdr, expected)
}

/// `rdr` if its header is `expected`.
fn with_header<R: Read>(path: &Path, mut rdr: csv::Reader<R>, expected: &[&str]) -> Result<csv::Reader<R>, InputError> {
    let csv_err = |source| InputError::Csv { path: path.to_path_buf(), source };
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

    /// A file over the cap is refused by its size, a stream that never ends after cap + 1
    /// bytes; at the cap it is read.
    #[test]
    fn capped_reads_refuse_large_files_and_endless_streams() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.csv");
        std::fs::write(&p, vec![b'x'; 1024]).unwrap();
        assert_eq!(read_capped(&p, 1024, "recording").unwrap().len(), 1024);
        let e = read_capped(&p, 1023, "recording").unwrap_err().to_string();
        assert_eq!(
            e,
            format!(
                "{}: recording of 1024 bytes is larger than 1023 bytes (1023 bytes), the cap for recordings",
                p.display()
            )
        );
        std::fs::write(&p, [0xff, 0xfe]).unwrap();
        let e = read_capped_text(&p, 1024, "audit spec").unwrap_err().to_string();
        assert_eq!(e, format!("{}: audit spec is not UTF-8 text (invalid byte at offset 0)", p.display()));
        let e = read_capped(&dir.path().join("none"), 1024, "recording").unwrap_err();
        assert!(matches!(e, InputError::Open { .. }), "{e}");
        assert_eq!(
            (human_bytes(1 << 20), human_bytes(256 << 20), human_bytes(1 << 30)),
            ("1 MiB".into(), "256 MiB".into(), "1 GiB".into())
        );
    }

    /// Devices, pipes and folders are refused before they are opened: `/dev/zero` would never
    /// end, and the open of a pipe without a writer would never return.
    #[cfg(unix)]
    #[test]
    fn devices_pipes_and_folders_are_refused_unopened() {
        let e = read_capped(Path::new("/dev/zero"), 1 << 20, "recording").unwrap_err().to_string();
        assert!(e.starts_with("/dev/zero: the recording is a character device, not a regular file"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let e = read_capped(dir.path(), 1 << 20, "kymogram").unwrap_err().to_string();
        assert!(e.contains("the kymogram is a folder, not a regular file"), "{e}");
        let fifo = dir.path().join("p.npy");
        if std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success()) {
            let start = std::time::Instant::now();
            let e = read_capped(&fifo, 1 << 20, "recording").unwrap_err().to_string();
            assert!(e.contains("is a named pipe (FIFO), not a regular file"), "{e}");
            assert!(start.elapsed().as_secs() < 5);
        }
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
