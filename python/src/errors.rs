//! The errors of the bindings and the Python exception each becomes, with the message the CLI
//! prints for it (the error and its causes, `: `-separated).
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyRuntimeError, PyTypeError, PyValueError};
use pyo3::PyErr;

use cosserat::case::sweep::SweepError;
use cosserat::case::CaseError;
use cosserat::engine::input::clip_files::ClipFileError;
use cosserat::engine::EngineError;
pub use cosserat::jobs::solved::chain;

/// Why a call could not give a result.
#[derive(Debug, thiserror::Error)]
pub enum BindError {
    /// the case file or text (syntax, an invalid key, an unreadable file)
    #[error(transparent)]
    Case(Box<CaseError>),
    /// an override (`key = value`) the case does not take
    #[error(transparent)]
    Override(Box<SweepError>),
    /// the clip of the case (a missing file, a recording that does not fit the case)
    #[error(transparent)]
    Clip(Box<ClipFileError>),
    /// the engine could not start or stopped (a frame's failure is a status, not this)
    #[error("{label}: {source}")]
    Engine {
        label: String,
        #[source]
        source: Box<EngineError>,
    },
    /// a comparison of the engines that could not be made (FreeFEM missing or failed, …)
    #[error("{label}: {source}")]
    Compare {
        label: String,
        #[source]
        source: Box<cosserat::jobs::compare::CompareError>,
    },
    /// an output folder that could not be claimed or finished (`cosserat::output::run_folder`)
    #[error("output folder {path}")]
    Folder {
        path: String,
        #[source]
        source: Box<cosserat::output::run_folder::FolderError>,
    },
    /// a run into an output folder that ended without a result; the folder's `run.json` says so
    #[error("{0}")]
    RunFailed(String),
    /// a request the engine does not serve (a clip in FreeFEM, an unknown engine)
    #[error("{0}")]
    Unsupported(String),
    /// an argument of the wrong type
    #[error("{0}")]
    Type(String),
    /// a temporary folder for the engine's files
    #[error("a temporary folder for the engine: {0}")]
    Io(#[from] std::io::Error),
    /// the call's stop was requested (`cosserat.Cancel.set()`; `cosserat::interrupt`)
    #[error("{0}")]
    Interrupted(String),
}

pyo3::create_exception!(
    cosserat,
    Cancelled,
    pyo3::exceptions::PyException,
    "A call stopped by its `cosserat.Cancel` (set from another thread)."
);

impl From<CaseError> for BindError {
    fn from(e: CaseError) -> Self {
        BindError::Case(Box::new(e))
    }
}

impl From<SweepError> for BindError {
    fn from(e: SweepError) -> Self {
        BindError::Override(Box::new(e))
    }
}

impl From<ClipFileError> for BindError {
    fn from(e: ClipFileError) -> Self {
        BindError::Clip(Box::new(e))
    }
}

impl From<BindError> for PyErr {
    fn from(e: BindError) -> PyErr {
        let message = chain(&e);
        let not_found = |io: &std::io::Error| io.kind() == std::io::ErrorKind::NotFound;
        let clip = |c: &ClipFileError| match c {
            ClipFileError::Missing { .. } => PyFileNotFoundError::new_err(message.clone()),
            _ => PyValueError::new_err(message.clone()),
        };
        match &e {
            BindError::Case(c) => match &**c {
                CaseError::Io { source, .. } if not_found(source) => PyFileNotFoundError::new_err(message),
                CaseError::Io { .. } => PyOSError::new_err(message),
                _ => PyValueError::new_err(message),
            },
            BindError::Io(_) => PyOSError::new_err(message),
            BindError::Clip(c) => clip(c),
            BindError::Engine { source, .. } => match &**source {
                EngineError::Clip(c) => clip(c),
                _ => PyRuntimeError::new_err(message),
            },
            BindError::Override(_) | BindError::Unsupported(_) => PyValueError::new_err(message),
            BindError::Type(_) => PyTypeError::new_err(message),
            BindError::Compare { .. } | BindError::RunFailed(_) => PyRuntimeError::new_err(message),
            BindError::Folder { .. } => PyOSError::new_err(message),
            BindError::Interrupted(_) => Cancelled::new_err(message),
        }
    }
}
