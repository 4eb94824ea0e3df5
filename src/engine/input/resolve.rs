//! A case resolved against its recording before it runs (`kind = "recording"`): the body
//! length of `rod.length_m = "from_data"`, the plane of a planar recording and the file's first
//! frame number written into the case's tables ([`resolve_recording`]). An NPY recording is read
//! a frame at a time for this ([`super::recording_stream`]), any other whole.
use nalgebra::Vector3;

use super::clip_files::{clip_source, read_recording_as, read_spec, ClipFileError};
use super::recording_stream::streamed_body_length;
use crate::case::{Case, ClipKind, RodLength};
use crate::clip::length::BodyLength;
use crate::clip::recording::RecordingInfo;
use crate::clip::Clip;

/// The case resolved against its recording (`kind = "recording"`; any other case is returned
/// as it is), written into the case file's tables and validated again, so that everything
/// derived from them follows (the slenderness check, the default stabilisation, the section
/// scaled by `rod.section_length_m`, a sweep's points):
/// - `rod.length_m = "from_data"`: the body length of the recording (the frames of its range;
///   with missing data, the frames tracked whole, else every frame as filled),
///   [`BodyLength::estimate_in`]; the estimate is kept in [`Case::body_length`];
/// - a planar recording (`clip::recording`): `clip.data_plane`, its plane's normal, and, where
///   the case gives no `clip.gauge`, the gauge along that normal, so that the bending of the
///   data is κ2 with d2 along the normal (docs/rotation.md R7);
/// - a recording numbered from frame `k > 0`, without `clip.frames`: `clip.frames` from `k`,
///   so that every frame is reported under the file's number.
///
/// The clip file is written as an absolute path (a batch's recording replaces the file's).
pub fn resolve_recording(case: &Case) -> Result<Case, ClipFileError> {
    let Some(src) = case.clip().filter(|c| c.kind == ClipKind::Recording) else { return Ok(case.clone()) };
    let src = clip_source(case).map(|_| src)?;
    // an NPY recording read a frame at a time, else the whole clip
    let found = match streamed_body_length(case)? {
        Some((info, body)) => (info, None, body),
        None => whole_body_length(case, src, read_recording_as(&src.file, &read_spec(case, src))?)?,
    };
    // the clip file as an absolute path (a batch's recording replaces the file's)
    let file = std::path::absolute(&src.file).unwrap_or_else(|_| src.file.clone());
    resolve_as(case, src, found, Some(&file))
}

/// [`resolve_recording`] on the clip `clip` of a `kind = "recording"` case, read by the caller
/// (a recording held in memory, `super::recording::memory_recorded` and
/// `super::clip_files::recording_clip`) instead of from `clip.file`, which stays as it is.
pub fn resolve_recorded(case: &Case, clip: Clip) -> Result<Case, ClipFileError> {
    let Some(src) = case.clip().filter(|c| c.kind == ClipKind::Recording) else { return Ok(case.clone()) };
    let found = whole_body_length(case, src, clip)?;
    resolve_as(case, src, found, None)
}

/// The case with what was found in its recording (`info`, its frames where counted, its body
/// length where asked for) written into its tables, and its clip file replaced by `file`.
fn resolve_as(
    case: &Case,
    src: &crate::case::ClipSource,
    (info, frames, body): (RecordingInfo, Option<usize>, Option<BodyLength>),
    file: Option<&std::path::Path>,
) -> Result<Case, ClipFileError> {
    let mut overrides: Vec<(String, toml::Value)> = Vec::new();
    let array = |v: &Vector3<f64>| toml::Value::Array(v.iter().map(|c| toml::Value::Float(*c)).collect());
    if let (Some(n), None) = (&info.plane_normal, &src.recording.data_plane) {
        overrides.push(("clip.data_plane".into(), array(n)));
        let gauge_given = case.toml_table().and_then(|t| t.get("clip")).and_then(|c| c.get("gauge")).is_some();
        if !gauge_given {
            overrides.push(("clip.gauge".into(), array(n)));
        }
    }
    if let (true, None, Some(frames)) = (info.first_frame > 0, src.frames, frames) {
        let end = info.first_frame + frames;
        let range = [info.first_frame, end].map(|v| toml::Value::Integer(v as i64));
        overrides.push(("clip.frames".into(), toml::Value::Array(range.to_vec())));
    }
    if let Some(b) = &body {
        overrides.push(("rod.length_m".into(), toml::Value::Float(b.length_m)));
    }
    if overrides.is_empty() {
        return Ok(case.clone());
    }
    if let Some(file) = file {
        overrides.push(("clip.file".into(), toml::Value::String(file.display().to_string())));
    }
    let mut resolved = case.with_overrides(&overrides).map_err(|source| ClipFileError::FromData {
        path: src.file.clone(),
        length_m: body.map_or(case.mesh.length_m, |b| b.length_m),
        source,
    })?;
    if let Some(b) = body {
        resolved.rod.length = RodLength::FromData(Some(b));
    }
    resolved.origin.source_sha256.clone_from(&case.origin.source_sha256);
    Ok(resolved)
}

/// What [`resolve_recording`] finds in a recording read whole (`clip`, as read and filled):
/// what the file says about itself, its frames, and its body length where `rod.length_m =
/// "from_data"` (over the frames of the range; with missing data, the frames tracked whole,
/// else every frame as filled).
fn whole_body_length(
    case: &Case,
    src: &crate::case::ClipSource,
    mut clip: Clip,
) -> Result<(RecordingInfo, Option<usize>, Option<BodyLength>), ClipFileError> {
    let (info, frames) = (clip.recording.clone(), clip.frame_count());
    if case.rod.length != RodLength::FromData(None) {
        return Ok((info, Some(frames), None));
    }
    if let Some((a, b)) = src.frames {
        let (a0, b0) = (a.saturating_sub(info.first_frame), b.saturating_sub(info.first_frame));
        clip.select(a0, b0)?;
    }
    let whole: Vec<Vec<Vector3<f64>>> = (0..clip.frame_count())
        .filter(|&k| clip.nodes_tracked(k) == clip.node_count())
        .map(|k| clip.frames[k].clone())
        .collect();
    let body_frames = if whole.is_empty() { &clip.frames } else { &whole };
    let b = BodyLength::estimate_in(body_frames, info.plane_normal.as_ref())
        .ok_or_else(|| ClipFileError::NoBodyLength { path: src.file.clone() })?;
    Ok((info, Some(frames), Some(b)))
}
