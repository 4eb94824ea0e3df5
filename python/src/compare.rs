//! `cosserat.compare`: a case in both engines as `cosserat compare` runs it
//! (`cosserat::jobs::compare`), its rows as records with the columns of `compare.csv`.
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::case::{case_label, load_case};
use crate::errors::{chain, BindError};
use crate::watch::{self, Cancel};
use cosserat::jobs::compare::{compare_case, CompareError, CompareOptions, CompareReport, Horizon};

/// The comparison's rows as dicts with the columns of `compare.csv`: `quantity`, `rust`,
/// `freefem` (None for a row that compares whole fields), `difference`, `tolerance`, `result`
/// (`"pass"` or `"FAIL"`, as the CLI writes it) and `basis` (how the tolerance was found).
fn rows<'py>(py: Python<'py>, report: &CompareReport) -> PyResult<Vec<Bound<'py, PyDict>>> {
    report
        .rows
        .iter()
        .map(|r| {
            let d = PyDict::new(py);
            d.set_item("quantity", &r.name)?;
            d.set_item("rust", r.rust)?;
            d.set_item("freefem", r.freefem)?;
            d.set_item("difference", r.difference)?;
            d.set_item("tolerance", r.tolerance)?;
            d.set_item("result", if r.passed() { "pass" } else { "FAIL" })?;
            d.set_item("basis", &r.basis)?;
            Ok(d)
        })
        .collect()
}

/// Did the comparison stop because a stop was requested?
fn interrupted(e: &CompareError) -> bool {
    use cosserat::engine::EngineError;
    let engine = match e {
        CompareError::Engine(e) | CompareError::Perturbed(e) => e,
        CompareError::FramesWithoutClip(_) => return false,
    };
    match engine {
        EngineError::Run(r) => r.is_interrupted(),
        EngineError::FreeFem(f) => f.is_interrupted(),
        _ => false,
    }
}

/// The keywords of `cosserat.compare` after the case, as the package's wrapper passes them (a
/// dict with every key).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct CompareSettings<'py> {
    /// the short horizon (`--short`)
    short: bool,
    /// a clip's frames to compare (`--frames`; `usize::MAX`: all)
    frames: Option<usize>,
    cancel: Option<Bound<'py, Cancel>>,
}

/// Compare the case of the file `case_path` (or of `case_text`) with `overrides` in both
/// engines as `settings` say; see `cosserat.compare`. FreeFEM works in a temporary folder,
/// removed afterwards.
#[pyfunction]
pub fn compare<'py>(
    py: Python<'py>,
    case_text: Option<&str>,
    case_path: &str,
    overrides: Vec<(String, Bound<'py, PyAny>)>,
    settings: CompareSettings<'py>,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let CompareSettings { short, frames, cancel } = settings;
    let o = crate::case::overrides(&overrides)?;
    let case = py.detach(|| load_case(case_text, case_path, &o))?;
    if let Some(why) = cosserat::engine::published::unavailable(&case) {
        return Err(BindError::Unsupported(why).into());
    }
    let opts = CompareOptions { horizon: if short { Horizon::Short } else { Horizon::Full }, frames };
    let work = crate::tempfile_dir()?;
    let dir = work.clone();
    let token = watch::token_of(cancel.as_ref());
    let report = watch::run_watched(py, None, token, |_| compare_case(&case, &dir, &opts).map_err(Box::new));
    let _ = std::fs::remove_dir_all(&work);
    let report = report?.map_err(|e| match interrupted(&e) {
        true => BindError::Interrupted(format!("{}: {}", case_label(&case), chain(&e))),
        false => BindError::Compare { label: case_label(&case), source: e },
    })?;
    rows(py, &report)
}
