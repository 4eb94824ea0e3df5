//! WCON, the Worm tracker Commons Object Notation of the OpenWorm Tracker Commons
//! (`WCON_format.md` of openworm/tracker-commons): a JSON object with a `units` block and a
//! `data` block of records, each one worm (`id`) at one or more times `t`, its midline as
//! `x` and `y` arrays per time.
//!
//! What is read (a minimal reader's duties, and what a centreline needs):
//! - `units`: `t` in seconds (`s`, `sec`, `second(s)`, `ms`, `min`, or a factor such as
//!   `0.04*s`), `x`, `y` (and `ox`, `oy`) in lengths with SI prefixes (`m`, `mm`, `um`, `µm`,
//!   `μm`, `micron`, `nm`, `cm`, `metre(s)`, `millimetre(s)`, …, `inch`) or a factor such as
//!   `0.0125*mm` (pixels of 12.5 µm);
//! - `data`: one record or an array of them; records of the same `id` are merged by time. A
//!   file with several worms needs `clip.worm_id`;
//! - per record `t` (a number or an array), `x`, `y` (an array of numbers per time; `null`
//!   marks an untracked point), the origin `ox`, `oy` (added to every point, arrays of the
//!   length of `t` or one number) and `head` (`"R"`: the head is the last point, the midline is
//!   reversed so that node 0 is the head);
//! - anything else (metadata, perimeters, custom `@` blocks) is ignored, as the format asks.
//!
//! Each time `t` becomes the frame `round(t/Δt)` (Δt = `clip.frame_interval_s`); a time more
//! than a quarter of Δt from a frame is an error, and the frames that no time reaches are
//! dropped frames (lost, with `clip.missing = "nan"`). Every time must have the same number of
//! points.
use std::collections::BTreeSet;
use std::path::Path;

use nalgebra::Vector3;
use serde_json::Value;

use super::{check_position, resolve_unit, ReadSpec, Table, RECORDING_CAP_BYTES};
use crate::clip::recording::{LengthUnit, UnitSpec};
use crate::io::files::{read_capped, InputError};

/// Largest distance of a time from its frame, in frame intervals.
const FRAME_TIME_TOLERANCE: f64 = 0.25;

/// The value of an SI prefix (module doc), `None` for an unknown one.
fn prefix(p: &str) -> Option<f64> {
    Some(match p {
        "" => 1.0,
        "c" | "centi" => 1e-2,
        "m" | "milli" => 1e-3,
        "u" | "µ" | "μ" | "micro" => 1e-6,
        "n" | "nano" => 1e-9,
        "k" | "kilo" => 1e3,
        _ => return None,
    })
}

/// A unit atom as `bases` (names and their value in SI) with an SI prefix: its value.
fn atom(text: &str, bases: &[(&str, f64)]) -> Option<f64> {
    bases.iter().find_map(|&(b, v)| text.strip_suffix(b).and_then(prefix).map(|p| p * v))
}

/// A unit expression of factors joined by `*` (numbers, or atoms of `bases`): its value in SI.
fn unit_value(text: &str, bases: &[(&str, f64)]) -> Option<f64> {
    let text = text.trim();
    if text.is_empty() {
        return None;
    }
    text.split('*')
        .map(str::trim)
        .try_fold(1.0, |acc, f| f.parse::<f64>().ok().or_else(|| atom(f, bases)).map(|v| acc * v))
}

/// Metres per unit of a WCON length unit.
fn length_unit(text: &str) -> Option<f64> {
    const BASES: [(&str, f64); 12] = [
        ("metres", 1.0),
        ("meters", 1.0),
        ("metre", 1.0),
        ("meter", 1.0),
        ("microns", 1e-6),
        ("micron", 1e-6),
        ("inches", 0.0254),
        ("inch", 0.0254),
        ("in", 0.0254),
        ("m", 1.0),
        ("mm", 1e-3),
        ("um", 1e-6),
    ];
    match text.trim() {
        "micron" | "microns" => Some(1e-6),
        t => unit_value(t, &BASES),
    }
}

/// Seconds per unit of a WCON time unit.
fn time_unit(text: &str) -> Option<f64> {
    const BASES: [(&str, f64); 10] = [
        ("seconds", 1.0),
        ("second", 1.0),
        ("sec", 1.0),
        ("s", 1.0),
        ("minutes", 60.0),
        ("minute", 60.0),
        ("min", 60.0),
        ("hours", 3600.0),
        ("hour", 3600.0),
        ("h", 3600.0),
    ];
    unit_value(text, &BASES)
}

/// One worm at one time: its time [s], midline [m] (NaN where untracked) and where it came
/// from (the record's index in `data`).
struct Sample {
    t_s: f64,
    points: Vec<Vector3<f64>>,
    record: usize,
}

/// Read the WCON file `path` into the rows of its worm (module doc).
pub(crate) fn read(path: &Path, spec: &ReadSpec) -> Result<Table, InputError> {
    let shape = |reason: String| InputError::Shape { path: path.to_path_buf(), reason };
    let bytes = read_capped(path, RECORDING_CAP_BYTES, "recording")?;
    let root: Value = serde_json::from_slice(&bytes).map_err(|e| shape(format!("not WCON: not JSON: {e}")))?;
    let units =
        root.get("units").and_then(Value::as_object).ok_or_else(|| shape("WCON without a `units` object".into()))?;
    let unit_of = |key: &str| units.get(key).and_then(Value::as_str);
    let t_unit = unit_of("t").ok_or_else(|| shape("WCON units: no unit for `t`".into()))?;
    let seconds = time_unit(t_unit).ok_or_else(|| shape(format!("WCON units: t = \"{t_unit}\" is not a time unit")))?;
    let x_unit = unit_of("x").ok_or_else(|| shape("WCON units: no unit for `x`".into()))?;
    if unit_of("y") != Some(x_unit) {
        return Err(shape(format!("WCON units: y = {:?} differs from x = \"{x_unit}\"", unit_of("y"))));
    }
    let per_unit =
        length_unit(x_unit).ok_or_else(|| shape(format!("WCON units: x = \"{x_unit}\" is not a length unit")))?;
    // the file states its unit: a clip.unit that disagrees is an error, pixels need no scale
    let named = LengthUnit::parse(x_unit.trim()).filter(|u| *u != LengthUnit::Pixel);
    let (unit, _) = match named {
        Some(u) => resolve_unit(path, Some(u), &spec.units, "the WCON units")?,
        None => resolve_unit(path, None, &UnitSpec { unit: None, m_per_px: None }, "the WCON units")?,
    };
    let origin_per_unit = match unit_of("ox") {
        Some(u) => length_unit(u).ok_or_else(|| shape(format!("WCON units: ox = \"{u}\" is not a length unit")))?,
        None => per_unit,
    };
    let records: Vec<&Value> = match root.get("data") {
        Some(Value::Array(a)) => a.iter().collect(),
        Some(v @ Value::Object(_)) => vec![v],
        _ => return Err(shape("WCON without a `data` record or array".into())),
    };
    let id = worm(path, &records, spec.worm_id.as_deref())?;
    let mut samples = Vec::new();
    for (k, r) in records.iter().enumerate().filter(|(_, r)| record_id(r).as_deref() == Some(id.as_str())) {
        samples.extend(record_samples(path, k, r, (seconds, per_unit, origin_per_unit))?);
    }
    frame_rows(path, spec, &id, samples, unit)
}

/// A record's `id` as text (a number is accepted as its text).
fn record_id(r: &Value) -> Option<String> {
    match r.get("id")? {
        Value::String(s) => Some(s.clone()),
        Value::Number(n) => Some(n.to_string()),
        _ => None,
    }
}

/// The worm to read: `wanted`, or the only one.
fn worm(path: &Path, records: &[&Value], wanted: Option<&str>) -> Result<String, InputError> {
    let ids: BTreeSet<String> = records.iter().filter_map(|r| record_id(r)).collect();
    let shape = |reason: String| InputError::Shape { path: path.to_path_buf(), reason };
    match wanted {
        Some(w) if ids.contains(w) => Ok(w.to_string()),
        Some(w) => Err(shape(format!("WCON: no worm with id \"{w}\" (clip.worm_id); the file has {ids:?}"))),
        None if ids.len() == 1 => Ok(ids.into_iter().next().unwrap_or_default()),
        None if ids.is_empty() => Err(shape("WCON: no data record with an `id`".into())),
        None => Err(shape(format!("WCON: {} worms ({ids:?}); choose one with clip.worm_id", ids.len()))),
    }
}

/// A per-time quantity of a record: an array with one entry per time, or one value for all.
fn per_time(v: &Value, times: usize) -> Option<Vec<&Value>> {
    match v {
        Value::Array(a) if a.len() == times => Some(a.iter().collect()),
        Value::Array(_) => None,
        v => Some(vec![v; times]),
    }
}

/// The samples of record `k` (`scales`: seconds per time unit, metres per length unit of the
/// midline and of the origin).
fn record_samples(path: &Path, k: usize, r: &Value, scales: (f64, f64, f64)) -> Result<Vec<Sample>, InputError> {
    let (seconds, per_unit, origin_per_unit) = scales;
    let shape = |reason: String| InputError::Shape {
        path: path.to_path_buf(),
        reason: format!("WCON data record {k}: {reason}"),
    };
    let t: Vec<f64> = match r.get("t") {
        Some(Value::Array(a)) => a
            .iter()
            .map(|v| v.as_f64().ok_or_else(|| shape(format!("time {v} is not a number"))))
            .collect::<Result<_, _>>()?,
        Some(v) => vec![v.as_f64().ok_or_else(|| shape(format!("time {v} is not a number")))?],
        None => return Err(shape("no `t`".into())),
    };
    let single = !matches!(r.get("t"), Some(Value::Array(_)));
    let coords = |key: &str| -> Result<Vec<Vec<f64>>, InputError> {
        let v = r.get(key).ok_or_else(|| shape(format!("no `{key}`")))?;
        let per: Vec<&Value> = match (single, v) {
            (true, v) => vec![v],
            (false, Value::Array(a)) if a.len() == t.len() => a.iter().collect(),
            _ => return Err(shape(format!("`{key}` does not have one entry per time ({} times)", t.len()))),
        };
        per.iter()
            .map(|p| match p {
                Value::Array(a) => Ok(a.iter().map(|c| c.as_f64().unwrap_or(f64::NAN)).collect()),
                Value::Number(n) => Ok(vec![n.as_f64().unwrap_or(f64::NAN)]),
                Value::Null => Ok(Vec::new()),
                v => Err(shape(format!("`{key}` entry {v} is not an array of numbers"))),
            })
            .collect()
    };
    let (xs, ys) = (coords("x")?, coords("y")?);
    let origin = |key: &str| -> Result<Vec<f64>, InputError> {
        match r.get(key) {
            None => Ok(vec![0.0; t.len()]),
            Some(v) => per_time(v, t.len())
                .map(|vs| vs.iter().map(|v| v.as_f64().unwrap_or(f64::NAN)).collect())
                .ok_or_else(|| shape(format!("`{key}` does not have one entry per time"))),
        }
    };
    let (ox, oy) = (origin("ox")?, origin("oy")?);
    let heads: Vec<bool> = match r.get("head") {
        None => vec![false; t.len()],
        Some(v) => per_time(v, t.len())
            .ok_or_else(|| shape("`head` does not have one entry per time".into()))?
            .iter()
            .map(|h| h.as_str() == Some("R"))
            .collect(),
    };
    let mut out = Vec::with_capacity(t.len());
    for (i, &ti) in t.iter().enumerate() {
        let (x, y) = (&xs[i], &ys[i]);
        if x.len() != y.len() {
            return Err(shape(format!("at t = {ti}: {} x and {} y values", x.len(), y.len())));
        }
        let mut points: Vec<Vector3<f64>> = x
            .iter()
            .zip(y)
            .map(|(a, b)| {
                Vector3::new(a * per_unit + ox[i] * origin_per_unit, b * per_unit + oy[i] * origin_per_unit, 0.0)
            })
            .map(|p| if p.x.is_nan() || p.y.is_nan() { Vector3::repeat(f64::NAN) } else { p })
            .collect();
        if heads[i] {
            points.reverse();
        }
        out.push(Sample { t_s: ti * seconds, points, record: k });
    }
    Ok(out)
}

/// The table of the samples of worm `id`: times to frames (module doc).
fn frame_rows(
    path: &Path,
    spec: &ReadSpec,
    id: &str,
    samples: Vec<Sample>,
    unit: LengthUnit,
) -> Result<Table, InputError> {
    let shape = |reason: String| InputError::Shape {
        path: path.to_path_buf(),
        reason: format!("WCON worm \"{id}\": {reason}"),
    };
    let dt = spec.dt_s;
    if !(dt.is_finite() && dt > 0.0) {
        return Err(shape("the frame interval clip.frame_interval_s is needed to number its times".into()));
    }
    let nodes = samples.first().map_or(0, |s| s.points.len());
    let mut rows = Vec::new();
    for s in &samples {
        if s.points.len() != nodes {
            return Err(shape(format!(
                "t = {} s has {} points, t = {} s has {nodes}: every time needs the same number of midline points",
                s.t_s,
                s.points.len(),
                samples[0].t_s
            )));
        }
        let q = s.t_s / dt;
        if !q.is_finite() || q < -0.5 || (q - q.round()).abs() > FRAME_TIME_TOLERANCE || q.round() > usize::MAX as f64 {
            return Err(shape(format!(
                "t = {} s is {:.3} frame intervals of {dt} s (clip.frame_interval_s): not within {FRAME_TIME_TOLERANCE} of a frame",
                s.t_s, q
            )));
        }
        let frame = q.round() as usize;
        for (i, p) in s.points.iter().enumerate() {
            check_position(path, (frame, i), p, spec.missing)?;
            rows.push((frame, i, *p, s.record));
        }
    }
    Ok(Table { rows, planar: true, unit })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_of_the_format_are_understood() {
        for (u, m) in [("mm", 1e-3), ("um", 1e-6), ("µm", 1e-6), ("micron", 1e-6), ("m", 1.0), ("millimetres", 1e-3)] {
            assert_eq!(length_unit(u), Some(m), "{u}");
        }
        assert!((length_unit("0.0125*mm").unwrap() - 1.25e-5).abs() < 1e-20);
        assert_eq!(length_unit("parsec"), None);
        assert_eq!(time_unit("seconds"), Some(1.0));
        assert_eq!(time_unit("ms"), Some(1e-3));
        assert!((time_unit("0.04*s").unwrap() - 0.04).abs() < 1e-18);
        assert_eq!(time_unit("min"), Some(60.0));
    }
}
