//! Reading a case file: refused unless it is a regular file (a pipe would block its open, a
//! device never end), and above [`CASE_FILE_CAP_BYTES`] by its size.
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

/// The text of a case file, refused above [`CASE_FILE_CAP_BYTES`] by its size, and refused
/// before it is opened unless it is a regular file (a pipe would block the open, a device
/// never end: `crate::file_kind`). The same rule as `crate::io::files::read_capped`, which
/// this layer cannot import (`tests/architecture.rs`).
pub(super) fn read_case_file(path: &Path) -> Result<String, CaseError> {
    use crate::file_kind::{kind, FileKind};
    use std::io::Read;
    let io = |source| CaseError::Io { path: path.to_path_buf(), source };
    let too_large = |size| CaseError::TooLarge { path: path.to_path_buf(), size };
    let not_regular = |kind| CaseError::NotRegular { path: path.to_path_buf(), kind };
    match kind(path).map_err(io)? {
        FileKind::Regular => {}
        other => return Err(not_regular(other)),
    }
    let file = std::fs::File::open(path).map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    if !meta.is_file() {
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
