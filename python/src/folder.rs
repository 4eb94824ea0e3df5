//! `run_case(..., out=PATH)`: a case run into an output folder as `cosserat run --out PATH`
//! writes it (`cosserat::jobs::job::run_into`: a staging folder beside it, the folder's lock,
//! `run.json` whatever the end), with the result handed back as well (a clip's frames collected
//! as they are written).
use std::path::Path;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::case::case_label;
use crate::clip::clip_dict;
use crate::errors::BindError;
use crate::sink::Collected;
use crate::watch::{self, Cancel};
use cosserat::case::Case;
use cosserat::engine::clip::FrameSink;
use cosserat::engine::Engine;
use cosserat::io::compact::OutputFormat;
use cosserat::jobs::job::{run_into_observed, JobEnd};
use cosserat::output::run_folder::{Mode, Status};

/// How the folder is written: replace a folder of an earlier run (`force`, as `--force`) and
/// the clip fields' format (`"csv"` or `"compact"`, as `--output-format`).
pub struct FolderOptions<'a> {
    pub out: &'a str,
    pub force: bool,
    pub format: &'a str,
}

/// The clip fields' format of `name`.
fn format_of(name: &str) -> Result<OutputFormat, BindError> {
    match name {
        "csv" => Ok(OutputFormat::Csv),
        "compact" => Ok(OutputFormat::Compact),
        other => Err(BindError::Unsupported(format!("output_format `{other}`: expected \"csv\" or \"compact\""))),
    }
}

/// The result dict of a run that ended in its folder: the clip's or the single run's, with
/// `out` (the folder) and its status as `run.json` says it; a run that stopped or produced
/// nothing is an exception whose message names the folder.
fn end_dict<'py>(
    py: Python<'py>,
    case: &Case,
    engine: Engine,
    end: JobEnd,
    frames: Collected,
) -> PyResult<Bound<'py, PyDict>> {
    let said = serde_json::to_string(&end.status).unwrap_or_default();
    let where_ = format!("{} holds run.json saying {}", end.dir.display(), said.trim_matches('"'));
    let message = || format!("{}; {where_}", end.message.clone().unwrap_or_else(|| case_label(case)));
    if end.status == Status::Interrupted {
        return Err(BindError::Interrupted(message()).into());
    }
    let status = match (&end.status, end.clip.is_some()) {
        (Status::Complete, _) => "ok",
        (Status::CompleteWithWarnings, _) => "warnings",
        (Status::Stalled, false) => "stalled",
        (Status::Failed, true) if end.frames.is_some_and(|(done, _)| done > 0) => "failed",
        (Status::Failed, false) if end.single.is_some() => "not_converged",
        _ => return Err(BindError::RunFailed(message()).into()),
    };
    let d = match (&end.clip, &end.single) {
        (Some(run), _) => {
            let total = end.frames.map_or(0, |f| f.1);
            clip_dict(py, case, (status, end.message.clone()), (run, total), frames)?
        }
        (None, Some(r)) => {
            let d = PyDict::new(py);
            d.set_item("status", status)?;
            d.set_item("error", end.message.clone())?;
            d.set_item("case", case.name.clone())?;
            d.set_item("engine", engine.to_string())?;
            crate::result_dict(py, case, r, &d)?;
            d
        }
        (None, None) => return Err(BindError::RunFailed(message()).into()),
    };
    d.set_item("out", end.dir.display().to_string())?;
    Ok(d)
}

/// Run `case` in `engine` into the folder `opts.out`, watched; see `cosserat.run_case`.
pub fn run_into_folder<'py>(
    py: Python<'py>,
    case: &Case,
    engine: Engine,
    opts: FolderOptions<'_>,
    progress: Option<Bound<'py, PyAny>>,
    cancel: Option<&Bound<'py, Cancel>>,
) -> PyResult<Bound<'py, PyDict>> {
    let mode = (Mode::Fresh { force: opts.force }, format_of(opts.format)?);
    let out = Path::new(opts.out);
    let token = watch::token_of(cancel);
    let solved = watch::run_watched(py, progress.as_ref(), token, |tx| {
        let mut frames = Collected::default();
        let end = run_into_observed(
            case,
            engine,
            out,
            mode,
            |f| {
                let Ok(()) = frames.frame(f);
            },
            |done, total| {
                let _ = tx.send((done, total));
            },
        );
        end.map(|end| (end, frames))
    })?;
    let (end, frames) =
        solved.map_err(|source| BindError::Folder { path: out.display().to_string(), source: Box::new(source) })?;
    end_dict(py, case, engine, end, frames)
}
