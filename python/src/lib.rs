//! `cosserat._native`: the Rust engine behind the Python package `cosserat`
//! (`cosserat/__init__.py` is its documented face). A case is read as `cosserat run` reads it,
//! solved on a worker thread with the GIL released ([`watch`]), and its result handed back as
//! numpy arrays and dicts; nothing is written unless the caller asks for an output folder
//! (`out=`, [`folder`]: what `cosserat run --out` writes) or the engine needs a working folder
//! (a temporary one, removed afterwards). A recording held in numpy memory is read from there
//! ([`clip::run_recording`]); a comparison of the engines gives the rows of `compare.csv`
//! ([`compare`]). Each call has its own stop token ([`watch`]).
mod case;
mod clip;
mod compare;
mod errors;
mod folder;
mod sink;
mod watch;

use nalgebra::Vector3;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyDict, PyList};

use crate::case::{case_label, load_case};
use crate::errors::{chain, BindError};
use crate::watch::Cancel;
use cosserat::case::Case;
use cosserat::engine::{metrics, run_case as engine_run_case};
use cosserat::engine::{Engine, EngineError, RunError, RunResult};

/// A JSON value as a Python object (numbers, strings, bools, null, arrays, objects).
pub(crate) fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value;
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Number(n) => match n.as_i64() {
            Some(i) => i.into_pyobject(py)?.into_any(),
            None => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Array(a) => {
            PyList::new(py, a.iter().map(|x| json_to_py(py, x)).collect::<PyResult<Vec<_>>>()?)?.into_any()
        }
        Value::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// Three components per node as a `nodes × 3` array.
fn vectors<'py>(py: Python<'py>, v: &[Vector3<f64>]) -> PyResult<Bound<'py, PyAny>> {
    let flat: Vec<f64> = v.iter().flat_map(|x| x.iter().copied()).collect();
    Ok(PyArray1::from_vec(py, flat).reshape([v.len(), 3])?.into_any())
}

/// The arrays and metrics of a single-frame result.
pub(crate) fn result_dict<'py>(py: Python<'py>, case: &Case, r: &RunResult, d: &Bound<'py, PyDict>) -> PyResult<()> {
    let n = &r.nodes;
    d.set_item("s_m", PyArray1::from_vec(py, n.s.clone()))?;
    d.set_item("x_m", vectors(py, &n.x)?)?;
    d.set_item("angles_rad", vectors(py, &n.alpha)?)?;
    let dir = n.directors();
    for (k, name) in ["d1", "d2", "d3"].iter().enumerate() {
        d.set_item(name, vectors(py, &dir.iter().map(|di| di[k]).collect::<Vec<_>>())?)?;
    }
    let kappa = n.element_curvature();
    d.set_item("s_mid_m", PyArray1::from_vec(py, kappa.iter().map(|k| k.0).collect()))?;
    d.set_item("kappa_per_m", vectors(py, &kappa.iter().map(|k| k.1).collect::<Vec<_>>())?)?;
    if let Some(inv) = &r.inverse {
        d.set_item("f_n_per_m", vectors(py, &inv.force())?)?;
        d.set_item("l_nm_per_m", vectors(py, &inv.torque())?)?;
        d.set_item("data_m", vectors(py, &inv.data.x)?)?;
    }
    let m = metrics::all_metrics(case, r).map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(chain(&e)))?;
    d.set_item("metrics", m.into_iter().collect::<Vec<_>>().into_py_dict(py)?)?;
    Ok(())
}

/// The keywords of `cosserat.run_case` after the case, as the package's wrapper passes them
/// (a dict with every key).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct RunSettings<'py> {
    /// `"rust"` or `"freefem"`
    engine: String,
    /// called as `progress(done, total)`
    progress: Option<Bound<'py, PyAny>>,
    cancel: Option<Bound<'py, Cancel>>,
    /// the output folder, if the run writes one
    out: Option<String>,
    /// `--force` for `out`
    force: bool,
    /// `"csv"` or `"compact"`, for `out`
    output_format: String,
}

/// Run the case of the file `case_path` (or of `case_text`) with `overrides` as `settings`
/// say, in their engine (`"rust"` or `"freefem"`); see `cosserat.run_case`. A clip case runs
/// as [`clip::run_clip`]; with `out`, into that folder ([`folder::run_into_folder`]).
#[pyfunction]
fn run_case<'py>(
    py: Python<'py>,
    case_text: Option<&str>,
    case_path: &str,
    overrides: Vec<(String, Bound<'py, PyAny>)>,
    settings: RunSettings<'py>,
) -> PyResult<Bound<'py, PyDict>> {
    let RunSettings { engine, progress, cancel, out, force, output_format } = settings;
    let engine = match engine.as_str() {
        "rust" => Engine::Rust,
        "freefem" => Engine::Freefem,
        other => {
            return Err(BindError::Unsupported(format!("engine `{other}`: expected \"rust\" or \"freefem\"")).into())
        }
    };
    let o = case::overrides(&overrides)?;
    let case = py.detach(|| load_case(case_text, case_path, &o))?;
    if let Some(why) = cosserat::jobs::solved::unsupported(&case, engine) {
        return Err(BindError::Unsupported(why).into());
    }
    if let Some(out) = out.as_deref() {
        let opts = folder::FolderOptions { out, force, format: &output_format };
        return folder::run_into_folder(py, &case, engine, opts, progress, cancel.as_ref());
    }
    if case.clip().is_some() {
        return clip::run_clip(py, case_text, case_path, overrides, progress, cancel);
    }
    let work = tempfile_dir()?;
    let path = work.clone();
    let solved = watch::run_watched(py, progress.as_ref(), watch::token_of(cancel.as_ref()), |tx| {
        engine_run_case(&case, engine, &path, |done, total| {
            let _ = tx.send((done, total));
        })
    })?;
    let _ = std::fs::remove_dir_all(&work);
    let d = PyDict::new(py);
    let (status, error, r) = match solved {
        Ok(r) => ("ok", None, r),
        Err(EngineError::Run(RunError::Incomplete { source, partial })) => {
            let status =
                if matches!(source, cosserat::solve::SolveError::Stalled(_)) { "stalled" } else { "not_converged" };
            (status, Some(format!("{}: {source}; the result holds the last iterate", case_label(&case))), *partial)
        }
        Err(e) if interrupted(&e) => {
            return Err(BindError::Interrupted(format!("{}: {}", case_label(&case), chain(&e))).into())
        }
        Err(source) => return Err(BindError::Engine { label: case_label(&case), source: Box::new(source) }.into()),
    };
    d.set_item("status", status)?;
    d.set_item("error", error)?;
    d.set_item("case", case.name.clone())?;
    d.set_item("engine", engine.to_string())?;
    result_dict(py, &case, &r, &d)?;
    Ok(d)
}

/// Did the engine stop because a stop was requested (`cosserat::interrupt`)?
fn interrupted(e: &EngineError) -> bool {
    match e {
        EngineError::Run(r) => r.is_interrupted(),
        EngineError::FreeFem(f) => f.is_interrupted(),
        _ => false,
    }
}

/// A fresh private folder for the engine's files (an inverse case's `data.csv`, FreeFEM's).
pub(crate) fn tempfile_dir() -> Result<std::path::PathBuf, BindError> {
    let base = std::env::temp_dir();
    for k in 0..1000u32 {
        let p = base.join(format!("cosserat-py-{}-{k}", std::process::id()));
        match std::fs::create_dir(&p) {
            Ok(()) => return Ok(p),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e.into()),
        }
    }
    Err(std::io::Error::other("no free name for a temporary folder").into())
}

/// Read a clip's `fields.npz` (`cosserat run --output-format compact`): `frame` and every
/// column as a `frames × values` array.
#[pyfunction]
fn read_compact<'py>(py: Python<'py>, path: &str) -> PyResult<Bound<'py, PyDict>> {
    let c = cosserat::io::compact::read_compact(std::path::Path::new(path))
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(chain(&e)))?;
    let d = PyDict::new(py);
    let frames = c.frame.len();
    d.set_item("frame", PyArray1::from_vec(py, c.frame))?;
    for (name, (per, values)) in c.columns {
        d.set_item(name, PyArray1::from_vec(py, values).reshape([frames, per])?)?;
    }
    Ok(d)
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(clip::run_clip, m)?)?;
    m.add_function(wrap_pyfunction!(clip::run_recording, m)?)?;
    m.add_function(wrap_pyfunction!(run_case, m)?)?;
    m.add_function(wrap_pyfunction!(compare::compare, m)?)?;
    m.add_class::<Cancel>()?;
    m.add("Cancelled", m.py().get_type::<errors::Cancelled>())?;
    m.add_function(wrap_pyfunction!(read_compact, m)?)?;
    m.add_function(wrap_pyfunction!(write_corpus, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}

/// The keywords of `cosserat.synth` but the kymogram, as the package's wrapper passes them (a
/// dict with every key; units as `cosserat.synth` documents them).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct CorpusSettings {
    count: usize,
    frames: usize,
    nodes: usize,
    /// [m]
    length_m: f64,
    /// [s]
    frame_interval_s: f64,
    /// [m]
    noise_m: f64,
    seed: u64,
    /// [rad]
    max_roll_rad: f64,
    /// [rad/m]
    max_twist_per_m: f64,
}

/// Write a corpus of synthetic recordings of `settings` into `dir` from the kymogram
/// `kymogram` (as `cosserat synth`); see `cosserat.synth`.
#[pyfunction]
fn write_corpus<'py>(
    py: Python<'py>,
    dir: &str,
    kymogram: &str,
    settings: CorpusSettings,
) -> PyResult<Bound<'py, PyAny>> {
    use cosserat::engine::input::corpus::{write_corpus as write, CorpusParams};
    let CorpusSettings {
        count,
        frames,
        nodes,
        length_m,
        frame_interval_s,
        noise_m,
        seed,
        max_roll_rad,
        max_twist_per_m,
    } = settings;
    let params = CorpusParams {
        count,
        frames,
        nodes,
        length_m,
        dt_s: frame_interval_s,
        noise_m,
        shape_noise_m: 0.0,
        seed,
        max_roll_rad,
        max_twist_per_m,
    };
    let (dir, kymogram) = (std::path::Path::new(dir), std::path::Path::new(kymogram));
    let entries =
        py.detach(|| write(dir, kymogram, &params)).map_err(|e| pyo3::exceptions::PyValueError::new_err(chain(&e)))?;
    let v = serde_json::to_value(entries).map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
    json_to_py(py, &v)
}
