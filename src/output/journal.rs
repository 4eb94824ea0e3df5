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

use crate::engine::clip::FrameRecord;
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

/// The journal of `dir` opened for reading.
fn open(dir: &Path) -> Result<(std::io::BufReader<std::fs::File>, PathBuf), JournalError> {
    let path = dir.join(JOURNAL);
    match std::fs::File::open(&path) {
        Ok(f) => Ok((std::io::BufReader::new(f), path)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(JournalError::Missing { path }),
        Err(source) => Err(JournalError::Io { path, source }),
    }
}

/// The next complete line of a journal and its length [bytes]; `None` at its end or at the
/// first line that is not a complete entry (a kill while it was written). `line`: a buffer.
fn next_entry(
    reader: &mut std::io::BufReader<std::fs::File>,
    path: &Path,
    line: &mut Vec<u8>,
) -> Result<Option<(Entry, u64)>, JournalError> {
    line.clear();
    let n = reader.read_until(b'\n', line).map_err(|source| JournalError::Io { path: path.to_path_buf(), source })?;
    if n == 0 || line.last() != Some(&b'\n') {
        return Ok(None);
    }
    Ok(serde_json::from_slice::<Entry>(line).ok().map(|e| (e, n as u64)))
}

/// What the complete lines of a journal say, without their records (a record holds a frame's
/// whole state: an hour of frames would not fit in memory).
#[derive(Clone, Debug, Default)]
pub struct JournalScan {
    /// per complete line: the frame's number and time [s]
    pub frames: Vec<(usize, f64)>,
    /// the streamed files' lengths after the last complete line
    pub last: Option<Offsets>,
    /// the length of the complete lines [bytes]
    pub bytes: u64,
}

/// Read the journal of `dir` line by line up to its first incomplete line ([`JournalScan`]).
pub fn scan_journal(dir: &Path) -> Result<JournalScan, JournalError> {
    let (mut reader, path) = open(dir)?;
    let (mut scan, mut line) = (JournalScan::default(), Vec::new());
    while let Some((e, n)) = next_entry(&mut reader, &path, &mut line)? {
        scan.frames.push((e.record.report.frame, e.time_s));
        scan.last = Some(e.offsets);
        scan.bytes += n;
    }
    Ok(scan)
}

/// The records of the first `count` lines of a journal, read one at a time
/// ([`journal_records`]).
pub struct JournalRecords {
    reader: std::io::BufReader<std::fs::File>,
    path: PathBuf,
    line: Vec<u8>,
    left: usize,
}

impl Iterator for JournalRecords {
    type Item = Result<FrameRecord, JournalError>;
    fn next(&mut self) -> Option<Self::Item> {
        if self.left == 0 {
            return None;
        }
        self.left -= 1;
        match next_entry(&mut self.reader, &self.path, &mut self.line) {
            Ok(Some((e, _))) => Some(Ok(e.record)),
            // the scan saw this line whole: the file changed under the run
            Ok(None) => Some(Err(JournalError::Io {
                path: self.path.clone(),
                source: std::io::Error::new(std::io::ErrorKind::UnexpectedEof, "the journal ended early"),
            })),
            Err(e) => Some(Err(e)),
        }
    }
}

/// The records of the first `count` complete lines of the journal of `dir` (its
/// [`JournalScan`]'s), in order, one at a time.
pub fn journal_records(dir: &Path, count: usize) -> Result<JournalRecords, JournalError> {
    let (reader, path) = open(dir)?;
    Ok(JournalRecords { reader, path, line: Vec::new(), left: count })
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
