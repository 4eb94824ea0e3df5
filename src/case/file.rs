//! Reading a case file: refused unless it is a regular file (a named pipe would block its
//! open, a device never end) or the standard input a case is piped into, and above
//! [`CASE_FILE_CAP_BYTES`].
use std::path::Path;

use super::{CaseError, CASE_FILE_CAP_BYTES};

/// The message of `CaseError::TooLarge` (worded as `crate::io::InputError::TooLarge`).
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
/// end as piped): a named pipe would block the open, a device never end (`crate::file_kind`).
/// The same rule as `crate::io::files::read_capped`, which this layer cannot import
/// (`tests/architecture.rs`).
pub(super) fn read_case_file(path: &Path) -> Result<String, CaseError> {
    use crate::file_kind::{is_standard_input, kind, FileKind};
    use std::io::Read;
    let io = |source| CaseError::Io { path: path.to_path_buf(), source };
    let too_large = |size| CaseError::TooLarge { path: path.to_path_buf(), size };
    let not_regular = |kind| CaseError::NotRegular { path: path.to_path_buf(), kind };
    let piped = match kind(path).map_err(io)? {
        FileKind::Regular => false,
        FileKind::Fifo if is_standard_input(path) => true,
        other => return Err(not_regular(other)),
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    if !meta.is_file() && !piped {
        // replaced between the check and the open
        return Err(not_regular(FileKind::of(&meta)));
    }
    if meta.is_file() && meta.len() > CASE_FILE_CAP_BYTES {
        return Err(too_large(Some(meta.len())));
    }
    let mut bytes = Vec::new();
    file.take(CASE_FILE_CAP_BYTES + 1).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > CASE_FILE_CAP_BYTES {
        return Err(too_large(meta.is_file().then_some(bytes.len() as u64)));
    }
    String::from_utf8(bytes).map_err(|e| CaseError::Syntax {
        path: path.to_path_buf(),
        message: format!("not UTF-8 text (invalid byte at offset {})", e.utf8_error().valid_up_to()),
    })
}

/// SHA-256 of `bytes` (hex).
pub(super) fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::{Digest, Sha256};
    Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect()
}
