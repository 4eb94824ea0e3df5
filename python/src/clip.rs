//! Clip cases: the frames of a case's clip (its file, or a recording held in numpy memory) in the
//! Rust engine, every converged frame collected ([`Collected`]), and the result dict of a clip.
use numpy::{PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyDict};

use crate::case::{case_label, load_case, parse_case};
use crate::errors::{chain, BindError};
use crate::json_to_py;
use crate::sink::Collected;
use crate::watch::{self, Cancel};
use cosserat::case::Case;
use cosserat::engine::clip::{ClipOutcome, ClipRun, FrameRecord, FrameSink};
use cosserat::engine::{clip_metrics, run_clip_into, ClipInput, EngineError};
use cosserat::io::files::JournalError;

/// A [`FrameSink`] into a [`Collected`] the caller keeps.
struct Collecting<'a>(&'a mut Collected);

impl FrameSink for Collecting<'_> {
    type Error = std::convert::Infallible;
    fn frame(&mut self, f: &cosserat::engine::clip::ClipFrame) -> Result<(), Self::Error> {
        self.0.frame(f)
    }
    fn finish(&mut self) -> Result<(), Self::Error> {
        self.0.finish()
    }
}

/// The clip case and its frames `input()` gives, in the Rust engine, every converged frame
/// collected.
fn solve_clip(
    input: impl FnOnce() -> Result<(Case, ClipInput), EngineError>,
    progress: watch::Progress,
) -> Result<(Case, ClipOutcome, Collected), EngineError> {
    let (case, input) = input()?;
    let mut frames = Collected::default();
    let mut none = std::iter::empty::<Result<FrameRecord, JournalError>>();
    let out = run_clip_into(&case, input, &mut none, Collecting(&mut frames), |done, total| {
        let _ = progress.send((done, total));
    })?;
    Ok((case, out, frames))
}

/// Status and message of a clip run that started, as the CLI's `run.json` says them.
fn clip_status(case: &Case, out: &ClipOutcome) -> Result<(&'static str, Option<String>), BindError> {
    let flagged = out.run.reports.iter().filter(|r| r.fit.flagged).count();
    Ok(match &out.stopped {
        None if flagged > 0 => (
            "warnings",
            Some(format!(
                "{}: {flagged} of {} frames are over the fit-quality gate (`flagged` in frames): each is certified, but \
                 does not follow its data",
                case_label(case),
                out.run.reports.len()
            )),
        ),
        None => ("ok", None),
        Some(e) if e.is_interrupted() => return Err(BindError::Interrupted(format!("{}: {}", case_label(case), chain(e)))),
        Some(e) => (
            "failed",
            Some(format!("{}: {}; the converged frames before it are in the result", case_label(case), chain(e))),
        ),
    })
}

/// The result dict of a clip run: status, counts, weights, metrics (of a run that did not
/// fail), and the collected frames' arrays.
pub fn clip_dict<'py>(
    py: Python<'py>,
    case: &Case,
    (status, error): (&str, Option<String>),
    (run, total): (&ClipRun, usize),
    frames: Collected,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("status", status)?;
    d.set_item("error", error)?;
    d.set_item("frames_done", frames.len())?;
    d.set_item("frames_total", total)?;
    d.set_item("case", case.name.clone())?;
    d.set_item("body_length_m", case.mesh.length_m)?;
    d.set_item("frame_interval_s", case.inverse().map(|i| i.params.frame_interval_s))?;
    let weights = run.weights.map(serde_json::to_value).transpose().map_err(|e| BindError::Type(e.to_string()))?;
    d.set_item("weights", weights.map(|w| json_to_py(py, &w)).transpose()?)?;
    let metrics = (status != "failed").then(|| clip_metrics::clip_metrics(case, run));
    d.set_item("metrics", metrics.map(|m| m.into_iter().collect::<Vec<_>>().into_py_dict(py)).transpose()?)?;
    d.set_item("wall_time_s", run.wall_time_s)?;
    frames.into_dict(&d)?;
    Ok(d)
}

/// Solve the clip `input()` gives (on the worker thread: reading it and choosing its weights
/// are part of the solve), watched, and give its result dict; `label` names the case in errors.
fn run_input<'py>(
    py: Python<'py>,
    label: String,
    input: impl FnOnce() -> Result<(Case, ClipInput), EngineError> + Send,
    progress: Option<Bound<'py, PyAny>>,
    cancel: Option<&Bound<'py, Cancel>>,
) -> PyResult<Bound<'py, PyDict>> {
    let solved = watch::run_watched(py, progress.as_ref(), watch::token_of(cancel), |tx| solve_clip(input, tx))?;
    let (case, out, frames) = solved.map_err(|source| BindError::Engine { label, source: Box::new(source) })?;
    let status = clip_status(&case, &out)?;
    clip_dict(py, &case, status, (&out.run, out.total), frames)
}

/// Run the clip case of the file `case_path` (or of `case_text`, named by `case_path`) with
/// `overrides` in the Rust engine; see `cosserat.run_case`.
#[pyfunction]
#[pyo3(signature = (case_text, case_path, overrides, progress=None, cancel=None))]
pub fn run_clip<'py>(
    py: Python<'py>,
    case_text: Option<&str>,
    case_path: &str,
    overrides: Vec<(String, Bound<'py, PyAny>)>,
    progress: Option<Bound<'py, PyAny>>,
    cancel: Option<Bound<'py, Cancel>>,
) -> PyResult<Bound<'py, PyDict>> {
    let o = crate::case::overrides(&overrides)?;
    let case = py.detach(|| load_case(case_text, case_path, &o))?;
    if case.clip().is_none() {
        return Err(BindError::Unsupported(format!(
            "{}: not a clip case (it has no [clip]); use run_case",
            case_label(&case)
        ))
        .into());
    }
    run_input(py, case_label(&case), || Ok((case.clone(), ClipInput::of(&case)?)), progress, cancel.as_ref())
}

/// Run the recording case `case_text` (named by `case_path`; its `clip.file` names the
/// recording in messages) on `positions`, frames × nodes × 3 (or × 2) held in memory, read as
/// the same array in an NPY file would be; see `cosserat.reconstruct`.
#[pyfunction]
#[pyo3(signature = (case_text, case_path, positions, progress=None, cancel=None))]
pub fn run_recording<'py>(
    py: Python<'py>,
    case_text: &str,
    case_path: &str,
    positions: PyReadonlyArray3<'py, f64>,
    progress: Option<Bound<'py, PyAny>>,
    cancel: Option<Bound<'py, Cancel>>,
) -> PyResult<Bound<'py, PyDict>> {
    let case = parse_case(case_text, case_path)?;
    let shape = match *positions.shape() {
        [f, n, d] => (f, n, d),
        _ => return Err(BindError::Type("positions: expected a 3-dimensional array".into()).into()),
    };
    // the array as it is when C-contiguous (no copy), else copied in C order
    let owned;
    let values = match positions.as_slice() {
        Ok(v) => v,
        Err(_) => {
            owned = positions.as_array().iter().copied().collect::<Vec<f64>>();
            &owned[..]
        }
    };
    run_input(py, case_label(&case), || ClipInput::in_memory(&case, values, shape), progress, cancel.as_ref())
}
