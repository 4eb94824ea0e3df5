//! An NPY recording streamed from its file into the solve, a frame at a time, so that the memory
//! of a clip run does not grow with the recording's frames (an hour at 30 frames/s of 128 nodes
//! is 330 MB of positions). What [`super::clip_files::load_clip`] needs the whole clip for is
//! found in passes over the file before the solve, each holding one frame:
//! 1. the survey: the shape, every position checked, the constant axis of a planar recording
//!    written with three columns ([`ConstantAxes`]), frame 0's polyline length;
//! 2. the frames of the case's range: each frame's length against the rod's (D18), and what the
//!    automatic weights need (N2): each frame's noise level and the first
//!    [`CALIBRATION_FRAMES`] frames;
//! 3. the solve's own pass ([`RecordingStream::frames`]), on a second thread.
//!
//! A recording with an untracked node or a lost frame (their filling needs the frames on both
//! sides), a truth sidecar, or anything [`load_clip`](super::clip_files::load_clip) refuses is
//! not streamed: it is read whole, as before, and refused with the same message. The frames a
//! stream gives are the frames `load_clip` gives, bit for bit.
use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Vector3};

use super::clip_files::{clip_source, read_spec, recording_source, ClipFileError};
use super::recording::{info_of, NpyFrames, ReadSpec, PLANE_AXIS};
use super::truth_file::truth_sidecar;
use crate::case::{Case, ClipKind, RodLength, WeightsRule};
use crate::clip::length::{BodyLength, FrameLength};
use crate::clip::recording::{ConstantAxes, RecordingInfo};
use crate::clip::{check_frame_range, polyline_length, rotate_frame, Clip, MAX_LENGTH_DEVIATION};
use crate::io::files::InputError;
use crate::recorded::fit::noise_level_in;

/// Frames of a clip the automatic weights calibrate λg on (`crate::engine::weights`, N2).
pub const CALIBRATION_FRAMES: usize = 3;

/// What the survey of an NPY recording (pass 1) found.
struct Survey {
    frames: usize,
    nodes: usize,
    info: RecordingInfo,
    /// frame 0's polyline length [m]
    length0_m: f64,
}

/// Pass 1 over the NPY recording `path`: `None` where a position is untracked (NaN, read with
/// `clip.missing = "nan"`) or frame 0 has no length, for the whole-clip reader to fill or
/// refuse; `Err` where the reader refuses the file (the same error the whole-clip reader gives).
fn survey(path: &Path, spec: &ReadSpec) -> Result<Option<Survey>, InputError> {
    let mut reader = NpyFrames::open(path, spec)?;
    let (frames, nodes) = (reader.frames(), reader.nodes());
    let mut axes = ConstantAxes::default();
    let mut length0_m = None;
    while let Some(x) = reader.next_frame()? {
        if x.iter().any(|p| p.iter().any(|v| v.is_nan())) {
            return Ok(None);
        }
        axes.push(&x);
        length0_m.get_or_insert_with(|| polyline_length(&x));
    }
    let length0_m = length0_m.filter(|&l| l > 0.0);
    let info = info_of(0, reader.unit(), if reader.planar() { Some(PLANE_AXIS) } else { axes.axis() });
    Ok(length0_m.map(|length0_m| Survey { frames, nodes, info, length0_m }))
}

/// The NPY recording of a `kind = "recording"` case without a truth sidecar (`None` for any
/// other clip), and its spec.
fn npy_recording(case: &Case) -> Result<Option<(PathBuf, ReadSpec)>, ClipFileError> {
    let Some(src) = case.clip().filter(|c| c.kind == ClipKind::Recording) else { return Ok(None) };
    let src = clip_source(case).map(|_| src)?;
    let npy = src.file.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("npy"));
    if !npy || truth_sidecar(&src.file).is_file() {
        return Ok(None);
    }
    Ok(Some((src.file.clone(), read_spec(case, src))))
}

/// The file's frames of the case's range `(first, end)` in a recording of `frames` frames
/// (`clip.frames`, numbered from 0 in an NPY file; `None` if it lies outside).
fn range(case: &Case, frames: usize) -> Option<(usize, usize)> {
    let (first, end) = case.clip()?.frames.unwrap_or((0, frames));
    check_frame_range(first, end, frames).ok().map(|_| (first, end))
}

/// The frames `first..end` of the NPY recording `path`, read one at a time.
fn frames_of(
    path: &Path,
    spec: &ReadSpec,
    (first, end): (usize, usize),
) -> Result<impl Iterator<Item = Result<Vec<Vector3<f64>>, InputError>>, InputError> {
    let mut reader = NpyFrames::open(path, spec)?;
    let (frames, path) = (reader.frames(), path.to_path_buf());
    let mut k = 0;
    Ok(std::iter::from_fn(move || loop {
        if k == end {
            return None;
        }
        let x = match reader.next_frame() {
            Ok(Some(x)) => x,
            Ok(None) => return Some(Err(ended(&path, frames, end))),
            Err(e) => return Some(Err(e)),
        };
        k += 1;
        if k > first {
            return Some(Ok(x));
        }
    }))
}

/// The error of a recording of `frames` frames that ends before the clip's frame `end` (it
/// changed since it was read through).
fn ended(path: &Path, frames: usize, end: usize) -> InputError {
    InputError::Shape {
        path: path.to_path_buf(),
        reason: format!(
            "has {frames} frames now, but the clip's frames run to {end}: was the file changed while it was read?"
        ),
    }
}

/// The body length of an NPY recording (`rod.length_m = "from_data"`) over the frames of the
/// case's range, and what the file says about itself, found a frame at a time: what
/// [`super::resolve::resolve_recording`] finds on the whole clip, for a recording
/// [`recording_stream`] would stream (`None` for any other).
pub fn streamed_body_length(case: &Case) -> Result<Option<(RecordingInfo, Option<BodyLength>)>, ClipFileError> {
    let Some((path, spec)) = npy_recording(case)? else { return Ok(None) };
    let Some(s) = survey(&path, &spec)? else { return Ok(None) };
    if case.rod.length != RodLength::FromData(None) {
        return Ok(Some((s.info, None)));
    }
    let Some(frames) = range(case, s.frames) else { return Ok(None) };
    let plane = s.info.plane_normal;
    let lengths: Vec<FrameLength> = frames_of(&path, &spec, frames)?
        .map(|x| x.map(|x| FrameLength::of_in(&x, plane.as_ref())))
        .collect::<Result<_, _>>()?;
    Ok(BodyLength::of_lengths(&lengths).map(|b| (s.info, Some(b))))
}

/// A recording's clip as a stream of its frames (module doc): everything
/// [`super::clip_files::load_clip`] gives but the frames, which [`RecordingStream::frames`] reads.
pub struct RecordingStream {
    path: PathBuf,
    spec: ReadSpec,
    /// the file's frames of the clip: `first..end`
    range: (usize, usize),
    orientation: Matrix3<f64>,
    header: Clip,
    calibration: Vec<Vec<Vector3<f64>>>,
    noise_levels: Vec<f64>,
}

impl RecordingStream {
    /// Frames of the clip (of its range).
    pub fn len(&self) -> usize {
        self.range.1 - self.range.0
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The clip without its frames: what `load_clip`'s clip holds besides them.
    pub fn header(&self) -> Clip {
        self.header.clone()
    }

    /// The clip's first [`CALIBRATION_FRAMES`] frames [m] (all of a shorter clip).
    pub fn calibration(&self) -> &[Vec<Vector3<f64>>] {
        &self.calibration
    }

    /// Each frame's noise level [m] (`solve::fit::noise_level_in` in the case's data plane), if
    /// the case's weights are `"auto"` without `noise_m`; else empty.
    pub fn noise_levels(&self) -> &[f64] {
        &self.noise_levels
    }

    /// The frames of the clip [m], in order, read from the file one at a time: the frames of
    /// `load_clip`'s clip.
    pub fn frames(&self) -> Result<impl Iterator<Item = Result<Vec<Vector3<f64>>, InputError>> + '_, InputError> {
        let frames = frames_of(&self.path, &self.spec, self.range)?;
        Ok(frames.map(|x| x.map(|x| self.placed(x))))
    }

    /// A frame of the file placed as the case says (`clip.orientation`).
    fn placed(&self, mut x: Vec<Vector3<f64>>) -> Vec<Vector3<f64>> {
        if self.orientation != Matrix3::identity() {
            rotate_frame(&mut x, &self.orientation);
        }
        x
    }
}

/// [`RecordingStream`] of a case whose clip is an NPY recording every frame of which is tracked,
/// without a truth sidecar, that [`super::clip_files::load_clip`] would take; `None` for any
/// other (read whole, and refused there with its message).
pub fn recording_stream(case: &Case) -> Result<Option<RecordingStream>, ClipFileError> {
    if case.rod.length == RodLength::FromData(None) {
        return Ok(None);
    }
    let Some((path, spec)) = npy_recording(case)? else { return Ok(None) };
    let Some(s) = survey(&path, &spec)? else { return Ok(None) };
    let (Some(range), true) = (range(case, s.frames), s.nodes == case.mesh.nodes()) else { return Ok(None) };
    let orientation = case.clip().map_or_else(Matrix3::identity, |c| c.placement.orientation);
    let header = Clip {
        frames: Vec::new(),
        dt_s: spec.dt_s,
        source: recording_source(&path, (s.frames, s.nodes), &s.info),
        length_m: s.length0_m,
        tracked: None,
        recording: RecordingInfo { plane_normal: s.info.plane_normal.map(|n| orientation * n), ..s.info.clone() },
    };
    let mut stream =
        RecordingStream { path, spec, range, orientation, header, calibration: Vec::new(), noise_levels: Vec::new() };
    let sp = case.sequence_params();
    let auto = case.inverse().is_some_and(|i| i.weights_rule == WeightsRule::Auto);
    let plane = sp.as_ref().and_then(|sp| sp.plane);
    let noise_wanted = auto && sp.as_ref().is_some_and(|sp| sp.gate.noise_m.is_none());
    let (rod_m, file_plane) = (case.mesh.length_m, s.info.plane_normal);
    for x in frames_of(&stream.path, &stream.spec, range)? {
        let x = x?;
        // a frame refused for its length: load_clip says which and why
        let ratio = FrameLength::of_in(&x, file_plane.as_ref()).corrected_m / rod_m;
        if ratio.is_nan() || (ratio - 1.0).abs() > MAX_LENGTH_DEVIATION {
            return Ok(None);
        }
        let x = stream.placed(x);
        if noise_wanted {
            stream.noise_levels.push(noise_level_in(&x, plane.as_ref()));
        }
        if auto && stream.calibration.len() < CALIBRATION_FRAMES {
            stream.calibration.push(x);
        }
    }
    Ok(Some(stream))
}
