//! The resume journal of a clip run, `resume.jsonl`: one JSON line per converged frame, written
//! after the frame's rows and VTK file, holding what the frame is derived from exactly
//! ([`FrameRecord`], floats that round-trip bit for bit) and the length of every streamed CSV
//! after it. A run that stopped (signal, failure, or a kill between two lines) is resumed from
//! the last complete line: the CSVs are cut back to that line's lengths, VTK files of later
//! frames are removed, and the solve continues from the two last records
//! (`solve::sequence::ResumeFrom`), so the resumed CSVs are byte for byte those of an
//! uninterrupted run. A complete run removes its journal.
use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};

use crate::engine::rust::clip::FrameRecord;
use crate::io::files::{JournalError, OutputError};

/// File name of the journal in a clip's output folder.
pub const JOURNAL: &str = "resume.jsonl";

/// Lengths [bytes] of the streamed CSVs after a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Offsets {
    pub frames: u64,
    pub fields: u64,
    pub curvature: u64,
    /// `truth.csv` of a synthetic clip
    pub truth: Option<u64>,
}

/// One line of the journal.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Entry {
    /// the frame's time [s] (its `clip.pvd` entry)
    pub time_s: f64,
    pub offsets: Offsets,
    pub record: FrameRecord,
}

/// The journal being appended to.
pub struct Journal {
    path: PathBuf,
    file: std::fs::File,
}

impl Journal {
    /// A new, empty journal in `dir`.
    pub fn create(dir: &Path) -> Result<Self, OutputError> {
        let path = dir.join(JOURNAL);
        let file = std::fs::File::create(&path).map_err(|source| OutputError::Io { path: path.clone(), source })?;
        Ok(Journal { path, file })
    }

    /// The journal of `dir` cut to its first `bytes` (its complete lines), to append to.
    pub fn reopen(dir: &Path, bytes: u64) -> Result<Self, OutputError> {
        let path = dir.join(JOURNAL);
        let err = |source| OutputError::Io { path: path.clone(), source };
        let file = std::fs::OpenOptions::new().append(true).open(&path).map_err(err)?;
        file.set_len(bytes).map_err(err)?;
        Ok(Journal { path, file })
    }

    /// Append one frame's line and flush it.
    pub fn append(&mut self, entry: &Entry) -> Result<(), OutputError> {
        let err = |source| OutputError::Io { path: self.path.clone(), source };
        let mut line = serde_json::to_vec(entry)
            .map_err(|e| OutputError::Invalid { path: self.path.clone(), reason: e.to_string() })?;
        line.push(b'\n');
        self.file.write_all(&line).map_err(err)?;
        self.file.flush().map_err(err)
    }
}

/// The complete lines of the journal of `dir`, in order, and their length [bytes]; reading
/// stops at the first line that is not a complete entry (a kill while it was written).
pub fn read_journal(dir: &Path) -> Result<(Vec<Entry>, u64), JournalError> {
    let path = dir.join(JOURNAL);
    let file = match std::fs::File::open(&path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Err(JournalError::Missing { path }),
        Err(source) => return Err(JournalError::Io { path, source }),
    };
    let mut reader = std::io::BufReader::new(file);
    let (mut entries, mut bytes) = (Vec::new(), 0u64);
    let mut line = Vec::new();
    loop {
        line.clear();
        let n =
            reader.read_until(b'\n', &mut line).map_err(|source| JournalError::Io { path: path.clone(), source })?;
        if n == 0 || line.last() != Some(&b'\n') {
            break;
        }
        match serde_json::from_slice::<Entry>(&line) {
            Ok(e) => entries.push(e),
            Err(_) => break,
        }
        bytes += n as u64;
    }
    Ok((entries, bytes))
}

/// Remove the journal of `dir` (a complete run), if any.
pub fn remove_journal(dir: &Path) -> Result<(), OutputError> {
    let path = dir.join(JOURNAL);
    match std::fs::remove_file(&path) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(source) => Err(OutputError::Io { path, source }),
    }
}
