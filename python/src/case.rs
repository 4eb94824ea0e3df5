//! A case from a file or TOML text with overrides (dotted keys of the case file, as
//! `Case::with_overrides` takes them), resolved against its recording as `cosserat run` resolves
//! it (`rod.length_m = "from_data"`, a planar recording's plane).
use std::path::Path;

use pyo3::prelude::*;
use pyo3::types::{PyBool, PyFloat, PyInt, PyList, PyString, PyTuple};

use crate::errors::BindError;
use cosserat::case::Case;
use cosserat::engine::input::resolve::resolve_recording;

/// A Python value as a TOML value: bool, int, float, str, or a list/tuple of them.
pub fn to_toml(key: &str, v: &Bound<'_, PyAny>) -> Result<toml::Value, BindError> {
    let refuse = || {
        let kind = v.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "?".into());
        BindError::Type(format!("override `{key}`: a value of type {kind}; expected bool, int, float, str or a list"))
    };
    if v.is_instance_of::<PyBool>() {
        return v.extract::<bool>().map(toml::Value::Boolean).map_err(|_| refuse());
    }
    if v.is_instance_of::<PyInt>() {
        return v.extract::<i64>().map(toml::Value::Integer).map_err(|_| refuse());
    }
    if v.is_instance_of::<PyFloat>() {
        return v.extract::<f64>().map(toml::Value::Float).map_err(|_| refuse());
    }
    if v.is_instance_of::<PyString>() {
        return v.extract::<String>().map(toml::Value::String).map_err(|_| refuse());
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items: Vec<Bound<'_, PyAny>> =
            v.try_iter().map_err(|_| refuse())?.collect::<PyResult<_>>().map_err(|_| refuse())?;
        return items.iter().map(|x| to_toml(key, x)).collect::<Result<_, _>>().map(toml::Value::Array);
    }
    // numpy scalars: an integer type has __index__, a floating one converts to float
    if let Ok(i) = v.call_method0("__index__").and_then(|i| i.extract::<i64>()) {
        return Ok(toml::Value::Integer(i));
    }
    v.extract::<f64>().map(toml::Value::Float).map_err(|_| refuse())
}

/// The case of the file `path`, or of `text` (then `path` names it in messages and resolves its
/// relative clip file), with `overrides` applied and resolved against its recording.
pub fn load_case(text: Option<&str>, path: &str, overrides: &[(String, toml::Value)]) -> Result<Case, BindError> {
    let case = match text {
        Some(t) => parse_case(t, path)?,
        None => Case::from_file(Path::new(path))?,
    };
    let case = if overrides.is_empty() { case } else { case.with_overrides(overrides)? };
    Ok(resolve_recording(&case)?)
}

/// The case of the TOML text `text`, named by `path` (its stem is the case's name, its folder
/// resolves a relative clip file), not resolved against its recording.
pub fn parse_case(text: &str, path: &str) -> Result<Case, BindError> {
    let p = Path::new(path);
    let name = p.file_stem().and_then(|s| s.to_str()).unwrap_or("case");
    Ok(Case::from_toml(text, name, p)?)
}

/// The overrides of a Python call as TOML values.
pub fn overrides(items: &[(String, Bound<'_, PyAny>)]) -> Result<Vec<(String, toml::Value)>, BindError> {
    items.iter().map(|(k, v)| Ok((k.clone(), to_toml(k, v)?))).collect()
}

/// The case's name and file, for messages (as the CLI names it).
pub fn case_label(case: &Case) -> String {
    match &case.origin.source {
        Some(p) => format!("case {} ({})", case.name, p.display()),
        None => format!("case {}", case.name),
    }
}
