//! Reading clips: kymograms and user recordings (`crate::clip` turns their content into
//! centrelines), and the clip of a clip case with its frame range, orientation and, for a
//! synthetic clip, its ground truth.
use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Vector3};

use super::recording::{read_positions, ReadSpec, Recorded};
use super::truth_file::{read_truth, truth_sidecar};
use crate::case::sweep::SweepError;
use crate::case::{Case, ClipKind, RodLength, FROM_DATA};
use crate::clip::length::FrameLength;
use crate::clip::missing::{fill_missing, MissingData, MIN_TRACKED};
use crate::clip::recording::RecordingInfo;
use crate::clip::synthetic::{roll_clip, FrameTruth, GroundTruth, RollClipGenerator};
use crate::clip::{
    check_frame_range, clip_from_angles, polyline_length, rotate_frame, Clip, ClipError, KymogramParams,
    MAX_CLIP_POSITIONS, MAX_LENGTH_DEVIATION,
};
use crate::io::files::InputError;
use crate::io::npy::read_npy;

/// Column names of a CSV recording in metres (the header's suffix is the unit:
/// `frame,node,x_um,y_um` is a 2D recording in micrometres, [`super::recording`]).
pub const RECORDING_HEADER: [&str; 5] = ["frame", "node", "x_m", "y_m", "z_m"];

/// The folder of the `elegansbot` kymograms that `scripts/fetch_worm_data.sh` fetches.
const FETCHED_DATA: [&str; 2] = ["data", "elegansbot"];

/// Errors of reading the clip of a clip case.
#[derive(Debug, thiserror::Error)]
pub enum ClipFileError {
    #[error(transparent)]
    Input(#[from] InputError),
    #[error(transparent)]
    Clip(#[from] ClipError),
    #[error("case `{0}` has no [clip]")]
    NotAClip(String),
    #[error("{path} does not exist (the clip.file of case `{case}`){hint}")]
    Missing { path: PathBuf, case: String, hint: &'static str },
    #[error("{path}: {nodes} nodes per frame, but the case's mesh has {expected} (rod.elements + 1)")]
    NodeCount { path: PathBuf, nodes: usize, expected: usize },
    #[error(
        "{path}, frame {frame}: the centreline is {corrected_m:.4e} m long after the noise correction (measured: \
         {polyline_m:.4e} m as the polyline of its nodes, noise level {noise_m:.2e} m per coordinate, chords of \
         {chord_nodes} node spacing(s); docs/decisions.md D18), {ratio:.3}× the rod length rod.length_m = {rod_m:e} m \
         (allowed: {:.3}× to {:.3}×, ±{:.0} %){glitch}; scale the recording to metres of this rod, or set \
         rod.length_m to the length of the recorded body (\"from_data\" estimates it)",
        1.0 - MAX_LENGTH_DEVIATION,
        1.0 + MAX_LENGTH_DEVIATION,
        100.0 * MAX_LENGTH_DEVIATION
    )]
    Length {
        path: PathBuf,
        frame: usize,
        polyline_m: f64,
        noise_m: f64,
        chord_nodes: usize,
        corrected_m: f64,
        rod_m: f64,
        ratio: f64,
        glitch: String,
    },
    #[error(
        "case `{case}`: rod.length_m = \"{FROM_DATA}\" is the body length of the recording, estimated when it is \
         read (io::clip_files::resolve_length), and this case's was not"
    )]
    LengthNotResolved { case: String },
    #[error(
        "{path}: no frame has a positive finite length to estimate the body length from (rod.length_m = \
         \"{FROM_DATA}\")"
    )]
    NoBodyLength { path: PathBuf },
    #[error("{path}: the body length {length_m:e} m estimated from the recording (rod.length_m = \"{FROM_DATA}\")")]
    FromData {
        path: PathBuf,
        length_m: f64,
        #[source]
        source: SweepError,
    },
    #[error(
        "{path}: {frames} frames × {nodes} nodes are {positions} positions, more than the {MAX_CLIP_POSITIONS} a clip \
         may hold; use a shorter clip"
    )]
    TooManyPositions { path: PathBuf, frames: usize, nodes: usize, positions: usize },
}

/// Is `path` in the folder of the fetched kymograms (`data/elegansbot`)?
fn is_fetched_data(path: &Path) -> bool {
    let parts: Vec<_> = path.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
    parts.windows(2).any(|w| w[0] == FETCHED_DATA[0] && w[1] == FETCHED_DATA[1])
}

/// Refuse a clip of `frames` frames × `nodes` nodes beyond [`MAX_CLIP_POSITIONS`], before it is built.
fn check_positions(path: &Path, frames: usize, nodes: usize) -> Result<(), ClipFileError> {
    let positions = frames.saturating_mul(nodes);
    if positions > MAX_CLIP_POSITIONS {
        return Err(ClipFileError::TooManyPositions { path: path.to_path_buf(), frames, nodes, positions });
    }
    Ok(())
}

/// Refuse a recording frame (`first` is the file's index of `frames[0]`) whose length,
/// corrected for the frame's noise ([`FrameLength`], docs/decisions.md D18), deviates from the
/// rod length by more than [`MAX_LENGTH_DEVIATION`]; frames with too few tracked nodes are
/// bridged from checked ones and not checked.
fn check_lengths(
    path: &Path,
    clip: &Clip,
    first: usize,
    (rod_m, plane): (f64, Option<&Vector3<f64>>),
) -> Result<(), ClipFileError> {
    for (k, f) in clip.frames.iter().enumerate() {
        if clip.nodes_tracked(k) < MIN_TRACKED {
            continue;
        }
        let l = FrameLength::of_in(f, plane);
        let ratio = l.corrected_m / rod_m;
        if ratio.is_nan() || (ratio - 1.0).abs() > MAX_LENGTH_DEVIATION {
            return Err(ClipFileError::Length {
                path: path.to_path_buf(),
                frame: first + k,
                polyline_m: l.polyline_m,
                noise_m: l.noise_m,
                chord_nodes: l.chord_nodes,
                corrected_m: l.corrected_m,
                rod_m,
                ratio,
                glitch: glitch(f),
            });
        }
    }
    Ok(())
}

/// A point far off its neighbours (a tracking glitch) in the frame `pts`, in words: the node
/// whose segments are both longer than 10× the median segment (or an end node's one segment),
/// with its distance; empty if there is none.
fn glitch(pts: &[Vector3<f64>]) -> String {
    let seg: Vec<f64> = pts.windows(2).map(|w| (w[1] - w[0]).norm()).collect();
    let mut sorted = seg.clone();
    sorted.sort_by(f64::total_cmp);
    let Some(&median) = sorted.get(sorted.len() / 2).filter(|&&m| m > 0.0) else { return String::new() };
    let long = |i: usize| seg.get(i).is_some_and(|&l| l > 10.0 * median);
    let Some(i) = (0..seg.len()).filter(|&i| long(i)).max_by(|&a, &b| seg[a].total_cmp(&seg[b])) else {
        return String::new();
    };
    // segment i joins nodes i and i + 1: the node shared with another long segment, else the end
    let node = if i + 1 < seg.len() && long(i + 1) {
        i + 1
    } else if i > 0 && long(i - 1) {
        i
    } else if i == 0 {
        0
    } else {
        i + 1
    };
    format!(
        "; node {node} lies {:e} m from its neighbour, {:.0}× the median segment (a tracking glitch?)",
        seg[i],
        seg[i] / median
    )
}

/// The clip of a clip case: kymograms become spline centrelines with the mesh's node count
/// and the rod's length in the case's plane; recordings must have that node count, and every
/// frame solved the rod's length within [`MAX_LENGTH_DEVIATION`] once corrected for its noise; a synthetic clip
/// (`kind = "roll_3d"`) comes with its ground truth, and so does a recording with a truth sidecar
/// ([`super::truth_file`]). The frame range and the orientation of the
/// case are applied to both.
pub fn load_clip(case: &Case) -> Result<(Clip, Option<GroundTruth>), ClipFileError> {
    if case.rod.length == RodLength::FromData(None) {
        return Err(ClipFileError::LengthNotResolved { case: case.name.clone() });
    }
    let src = clip_source(case)?;
    let (clip, truth) = match &src.kind {
        ClipKind::Kymogram => {
            let params = case.kymogram_params().ok_or_else(|| ClipFileError::NotAClip(case.name.clone()))?;
            let rows = kymogram_rows(&src.file)?;
            check_positions(&src.file, rows.len(), params.nodes)?;
            (kymogram_clip(&src.file, &rows, &params), None)
        }
        ClipKind::Recording => {
            let clip = read_recording_as(&src.file, &read_spec(case, src))?;
            // a synthetic recording's ground truth, when its sidecar lies next to it
            let sidecar = truth_sidecar(&src.file);
            let truth = if sidecar.is_file() {
                let s: Vec<f64> = (0..clip.node_count()).map(|i| case.mesh.node_s(i)).collect();
                Some(read_truth(&sidecar, clip.frame_count(), &s)?)
            } else {
                None
            };
            (clip, truth)
        }
        ClipKind::Roll3d(_) => {
            let params = case.roll_clip_params().ok_or_else(|| ClipFileError::NotAClip(case.name.clone()))?;
            let rows = kymogram_rows(&src.file)?;
            let (clip, truth) = roll_clip(&rows, None, &params)?;
            (clip, Some(truth))
        }
    };
    fit_to_case(case, src, clip, truth)
}

/// The clip of a `kind = "recording"` case from a recording already read (`recorded`, e.g. held
/// in memory by the caller, [`super::recording::memory_recorded`]) instead of its file: filled
/// as the case's `clip.missing` says ([`recording_clip`]) and fitted to the case as
/// [`load_clip`] fits a recording's file, check for check; `clip.file` only names it.
pub fn load_recorded(case: &Case, recorded: Recorded) -> Result<Clip, ClipFileError> {
    if case.rod.length == RodLength::FromData(None) {
        return Err(ClipFileError::LengthNotResolved { case: case.name.clone() });
    }
    let src = case
        .clip()
        .filter(|c| c.kind == ClipKind::Recording)
        .ok_or_else(|| ClipFileError::NotAClip(case.name.clone()))?;
    let clip = recording_clip(&src.file, recorded, &read_spec(case, src))?;
    Ok(fit_to_case(case, src, clip, None)?.0)
}

/// A clip as read fitted to its case: the mesh's node count, the frame range of the case, a
/// recording's lengths checked against the rod's, the case's orientation (of the truth too).
fn fit_to_case(
    case: &Case,
    src: &crate::case::ClipSource,
    mut clip: Clip,
    mut truth: Option<GroundTruth>,
) -> Result<(Clip, Option<GroundTruth>), ClipFileError> {
    if clip.node_count() != case.mesh.nodes() {
        return Err(ClipFileError::NodeCount {
            path: src.file.clone(),
            nodes: clip.node_count(),
            expected: case.mesh.nodes(),
        });
    }
    // the frame range in the file's numbers (a recording's may start anywhere)
    let first = clip.recording.first_frame;
    if let Some((a, b)) = src.frames {
        let (a0, b0) = (a.checked_sub(first), b.checked_sub(first));
        let (a0, b0) = a0.zip(b0).ok_or(ClipError::FrameRange { first: a, end: b, frames: first })?;
        clip.select(a0, b0)?;
        if let Some(t) = &mut truth {
            t.select(a0, b0);
        }
    }
    if src.kind == ClipKind::Recording {
        // Kymograms are scaled to the rod length by design; a recording's length is the user's.
        // (a bridged frame, too few tracked nodes, is an interpolation of checked ones)
        let plane = clip.recording.plane_normal;
        check_lengths(&src.file, &clip, src.frames.map_or(first, |f| f.0), (case.mesh.length_m, plane.as_ref()))?;
    }
    if src.placement.orientation != Matrix3::identity() {
        clip.rotate(&src.placement.orientation);
        if let Some(t) = &mut truth {
            t.rotate(&src.placement.orientation);
        }
    }
    Ok((clip, truth))
}

/// The clip section of a clip case whose file exists.
pub(super) fn clip_source(case: &Case) -> Result<&crate::case::ClipSource, ClipFileError> {
    let src = case.clip().ok_or_else(|| ClipFileError::NotAClip(case.name.clone()))?;
    if !src.file.exists() {
        let hint = if is_fetched_data(&src.file) {
            "; the elegansbot kymograms are fetched and checksum-verified by scripts/fetch_worm_data.sh"
        } else {
            ""
        };
        return Err(ClipFileError::Missing { path: src.file.clone(), case: case.name.clone(), hint });
    }
    Ok(src)
}

/// The clip of a `roll_3d` case as a generator of its frames in order: frame for frame what
/// [`load_clip`] builds at once (the case's frame range and orientation applied), for a run
/// that solves the first frames while later ones are integrated.
pub struct RollStream {
    generator: RollClipGenerator,
    first: usize,
    len: usize,
    orientation: Matrix3<f64>,
}

impl RollStream {
    /// Frames of the clip (of its range).
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The clip without its frames.
    pub fn header(&self) -> Clip {
        self.generator.header()
    }

    /// Frame `i` of the range: positions [m] and ground truth, as [`load_clip`] has them.
    pub fn frame(&self, i: usize) -> (Vec<Vector3<f64>>, FrameTruth) {
        let (mut x, mut truth) = self.generator.frame(self.first + i);
        if self.orientation != Matrix3::identity() {
            rotate_frame(&mut x, &self.orientation);
            truth.rotate(&self.orientation);
        }
        (x, truth)
    }
}

/// [`RollStream`] of a `roll_3d` case, with the checks of [`load_clip`]; `None` for the other
/// kinds of clip.
pub fn roll_stream(case: &Case) -> Result<Option<RollStream>, ClipFileError> {
    let src = clip_source(case)?;
    if !matches!(src.kind, ClipKind::Roll3d(_)) {
        return Ok(None);
    }
    let params = case.roll_clip_params().ok_or_else(|| ClipFileError::NotAClip(case.name.clone()))?;
    let rows = kymogram_rows(&src.file)?;
    let generator = RollClipGenerator::new(&rows, None, &params)?;
    if params.nodes != case.mesh.nodes() {
        return Err(ClipFileError::NodeCount {
            path: src.file.clone(),
            nodes: params.nodes,
            expected: case.mesh.nodes(),
        });
    }
    let (first, end) = src.frames.unwrap_or((0, params.frames));
    check_frame_range(first, end, params.frames)?;
    Ok(Some(RollStream { generator, first, len: end - first, orientation: src.placement.orientation }))
}

/// The rows (frames × joint angles [rad]) of a kymogram `.npy`, every angle finite.
pub fn kymogram_rows(path: &Path) -> Result<Vec<Vec<f64>>, InputError> {
    let a = read_npy(path)?;
    let shape = |reason: String| InputError::Shape { path: path.to_path_buf(), reason };
    let &[frames, joints] = a.shape.as_slice() else {
        return Err(shape(format!("kymogram of shape {:?}, expected 2 axes (frames × joint angles)", a.shape)));
    };
    if frames == 0 || joints == 0 {
        return Err(shape(format!("kymogram of shape {:?} is empty", a.shape)));
    }
    if let Some(k) = a.data.iter().position(|v| !v.is_finite()) {
        return Err(InputError::NonFiniteAngle {
            path: path.to_path_buf(),
            frame: k / joints,
            joint: k % joints,
            value: a.data[k],
        });
    }
    // A joint angle turns one segment against the next: beyond ±π it cannot be in radians.
    if let Some(k) = a.data.iter().position(|v| v.abs() > std::f64::consts::PI) {
        return Err(shape(format!(
            "frame {}, joint {}: joint angle {} is beyond ±π, so not in radians (degrees? the kymogram's angles must \
             be radians, largest |angle| {})",
            k / joints,
            k % joints,
            a.data[k],
            a.data.iter().fold(0.0f64, |m, v| m.max(v.abs()))
        )));
    }
    Ok(a.data.chunks_exact(joints).map(<[f64]>::to_vec).collect())
}

/// Read a kymogram `.npy` (frames × joints, float64, angles [rad]) into a [`Clip`].
pub fn read_kymogram(path: &Path, params: &KymogramParams) -> Result<Clip, ClipFileError> {
    let rows = kymogram_rows(path)?;
    check_positions(path, rows.len(), params.nodes)?;
    Ok(kymogram_clip(path, &rows, params))
}

/// The clip of the (non-empty) rows of the kymogram `path`.
fn kymogram_clip(path: &Path, rows: &[Vec<f64>], params: &KymogramParams) -> Clip {
    let (frames, joints) = (rows.len(), rows[0].len());
    let scaled = if params.scale_to_length { ", scaled to the body length" } else { "" };
    let source = format!(
        "{} ({frames} frames × {joints} joint angles; spline resampled to {} nodes{scaled}, {:?} plane)",
        path.display(),
        params.nodes,
        params.plane
    );
    clip_from_angles(rows, params, source)
}

/// Read a user recording in metres as its file says ([`super::recording`]; a NaN is an error):
/// CSV, NPY or WCON; `dt_s` is the time between frames [s].
pub fn read_recording(path: &Path, dt_s: f64) -> Result<Clip, InputError> {
    let spec = ReadSpec { dt_s, ..ReadSpec::default() };
    let recorded = read_positions(path, &spec)?;
    clip_of(path, recorded, dt_s, MissingData::Error)
}

/// [`read_recording`] as the case's keys say (`spec`: unit, missing data, worm): with
/// [`MissingData::Nan`], untracked nodes and lost frames are filled and recorded in
/// [`Clip::tracked`] ([`fill_missing`]).
pub fn read_recording_as(path: &Path, spec: &ReadSpec) -> Result<Clip, ClipFileError> {
    recording_clip(path, read_positions(path, spec)?, spec)
}

/// The clip of the recording `recorded` (read from `path`, or held in memory under that name)
/// as `spec` says: with [`MissingData::Nan`], untracked nodes and lost frames filled and
/// recorded in [`Clip::tracked`] ([`fill_missing`]).
pub fn recording_clip(path: &Path, recorded: Recorded, spec: &ReadSpec) -> Result<Clip, ClipFileError> {
    let mut clip = clip_of(path, recorded, spec.dt_s, spec.missing)?;
    if spec.missing == MissingData::Nan {
        let tracked = fill_missing(&mut clip.frames, clip.recording.first_frame)?;
        clip.length_m = polyline_length(&clip.frames[0]);
        if tracked.iter().any(|f| f.iter().any(|t| !t)) {
            clip.tracked = Some(tracked);
        }
    }
    Ok(clip)
}

/// How the case reads its recording `src`.
pub fn read_spec(case: &Case, src: &crate::case::ClipSource) -> ReadSpec {
    ReadSpec {
        units: src.recording.units,
        missing: src.missing,
        dt_s: case.inverse().map(|i| i.params.frame_interval_s).unwrap_or(f64::NAN),
        worm_id: src.recording.worm_id.clone(),
    }
}

/// The clip of what was read from `path`.
fn clip_of(path: &Path, recorded: Recorded, dt_s: f64, missing: MissingData) -> Result<Clip, InputError> {
    let Recorded { frames, info } = recorded;
    let length_m = polyline_length(&frames[0]);
    if length_m <= 0.0 && missing == MissingData::Error {
        return Err(InputError::Shape { path: path.to_path_buf(), reason: "frame 0 has zero length".into() });
    }
    let source = recording_source(path, (frames.len(), frames[0].len()), &info);
    Ok(Clip { frames, dt_s, source, length_m, tracked: None, recording: info })
}

/// The source of a recording's clip (`Clip::source`): its file, `frames × nodes` and what it
/// says about itself.
pub(super) fn recording_source(path: &Path, (frames, nodes): (usize, usize), info: &RecordingInfo) -> String {
    let planar = if info.plane_normal.is_some() { ", planar" } else { "" };
    format!(
        "{} ({frames} frames × {nodes} nodes from frame {}, in {}{planar})",
        path.display(),
        info.first_frame,
        info.unit.name()
    )
}

#[cfg(test)]
mod tests;
