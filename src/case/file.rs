//! Reading a case file: refused unless it is a regular file (a named pipe would block its
//! open, a device never end) or the standard input a case is piped into, and above
//! [`CASE_FILE_CAP_BYTES`].
use std::path::Path;

use super::{CaseError, CASE_FILE_CAP_BYTES};
use crate::io::files::{read_capped_or_stdin, InputError};

/// The message of `CaseError::TooLarge` (worded as `crate::io::InputError::TooLarge` of a
/// "case file").
pub(super) fn too_large_text(size: Option<u64>) -> String {
    let cap = format!("{CASE_FILE_CAP_BYTES} bytes (1 MiB), the cap for case files");
    match size {
        Some(n) => format!("of {n} bytes is larger than {cap}"),
        None => format!("is not a regular file and did not end within {cap}: reading stopped there"),
    }
}

/// The text of a case file, refused above [`CASE_FILE_CAP_BYTES`] (a regular file by its size,
/// a pipe after one byte more), and refused before it is opened unless it is a regular file or
/// the pipe of this process's standard input (`cosserat run /dev/stdin < case.toml`, read to its
/// end as piped): a named pipe would block the open, a device never end
/// (`crate::io::files::read_capped_or_stdin`).
pub(super) fn read_case_file(path: &Path) -> Result<String, CaseError> {
    let bytes = read_capped_or_stdin(path, CASE_FILE_CAP_BYTES, "case file").map_err(|e| case_error(path, e))?;
    String::from_utf8(bytes).map_err(|e| CaseError::Syntax {
        path: path.to_path_buf(),
        message: format!("not UTF-8 text (invalid byte at offset {})", e.utf8_error().valid_up_to()),
    })
}

/// A capped read's error as the case file's (the same causes, worded for a case file).
fn case_error(path: &Path, e: InputError) -> CaseError {
    let path = path.to_path_buf();
    match e {
        InputError::TooLarge { size, .. } => CaseError::TooLarge { path, size },
        InputError::NotRegular { kind, .. } => CaseError::NotRegular { path, kind },
        InputError::Open { source, .. } => CaseError::Io { path, source },
        // a capped read fails in no other way
        other => CaseError::Io { path, source: std::io::Error::other(other) },
    }
}

/// SHA-256 of `bytes` (hex).
pub(super) fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::{Digest, Sha256};
    Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect()
}
