//! The claims inventory of §5–6 (`cases/paper/inventory.csv`): every sentence of §5–6 and of
//! the figure captions that states something checkable, with the rows of the audit that judge
//! it, or why it is not checkable here, or that it has no row yet. The report shows its
//! coverage ([`Coverage`]).
use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::ClaimResult;
use crate::io::files::{read_capped_text, InputError};

/// The inventory's file name, beside the specs.
pub const INVENTORY: &str = "inventory.csv";

/// Errors reading the inventory; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum InventoryError {
    #[error(transparent)]
    Input(#[from] InputError),
    #[error("{path}: {message}")]
    Invalid { path: PathBuf, message: String },
}

/// What the paper's sentence has here.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
pub enum Status {
    /// judged by the rows named
    #[serde(rename = "row")]
    Row,
    /// nothing here can check it (the note says why)
    #[serde(rename = "not checkable here")]
    NotCheckable,
    /// checkable, but the audit has no row for it yet
    #[serde(rename = "no row yet")]
    NoRowYet,
}

/// One sentence of the paper.
#[derive(Clone, Debug, Deserialize)]
pub struct Entry {
    pub id: String,
    pub section: String,
    /// the paper's words, verbatim ("..." for an elision)
    pub sentence: String,
    /// `spec/claim` ids separated by `;` (status `row`)
    pub rows: String,
    pub status: Status,
    pub note: String,
}

impl Entry {
    /// The `spec/claim` ids of the rows that judge the sentence.
    pub fn row_ids(&self) -> Vec<&str> {
        self.rows.split(';').map(str::trim).filter(|s| !s.is_empty()).collect()
    }
}

/// Read and check the inventory: unique ids, rows named exactly when the status is `row`.
pub fn read_inventory(path: &Path) -> Result<Vec<Entry>, InventoryError> {
    let text = read_capped_text(path, super::spec::SPEC_FILE_CAP_BYTES, "claims inventory")?;
    let invalid = |message: String| InventoryError::Invalid { path: path.to_path_buf(), message };
    let mut entries: Vec<Entry> = Vec::new();
    for (i, r) in csv::Reader::from_reader(text.as_bytes()).deserialize::<Entry>().enumerate() {
        let e = r.map_err(|e| invalid(format!("row {}: {e}", i + 2)))?;
        if entries.iter().any(|o| o.id == e.id) {
            return Err(invalid(format!("id `{}` given twice", e.id)));
        }
        if (e.status == Status::Row) == e.row_ids().is_empty() {
            return Err(invalid(format!("`{}`: rows are named exactly when the status is `row`", e.id)));
        }
        if e.status != Status::Row && e.note.trim().is_empty() {
            return Err(invalid(format!("`{}`: a sentence without a row says why in `note`", e.id)));
        }
        entries.push(e);
    }
    Ok(entries)
}

/// The inventory against the rows of an audit.
#[derive(Clone, Debug)]
pub struct Coverage {
    pub entries: Vec<Entry>,
    /// rows the inventory names that the audit does not have (`entry id`, `spec/claim`)
    pub dangling: Vec<(String, String)>,
    /// claims of the paper in the audit that no sentence names
    pub unlisted: Vec<String>,
}

impl Coverage {
    pub fn new(entries: Vec<Entry>, claims: &[ClaimResult]) -> Self {
        let key = |c: &ClaimResult| format!("{}/{}", c.spec, c.claim.id);
        let dangling = entries
            .iter()
            .flat_map(|e| e.row_ids().into_iter().map(move |r| (e.id.clone(), r.to_string())))
            .filter(|(_, r)| !claims.iter().any(|c| key(c) == *r))
            .collect();
        let unlisted = claims
            .iter()
            .filter(|c| !c.claim.ours)
            .map(key)
            .filter(|k| !entries.iter().any(|e| e.row_ids().contains(&k.as_str())))
            .collect();
        Coverage { entries, dangling, unlisted }
    }
    /// Sentences per status: with rows, not checkable here, no row yet.
    pub fn counts(&self) -> [usize; 3] {
        [Status::Row, Status::NotCheckable, Status::NoRowYet]
            .map(|s| self.entries.iter().filter(|e| e.status == s).count())
    }
}
