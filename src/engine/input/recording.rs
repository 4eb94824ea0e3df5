//! Reading a tracker's recording as it comes (`clip.kind = "recording"`): positions per frame
//! and node, in metres, a NaN where a node or frame was not tracked.
//!
//! | format | layout | unit |
//! |---|---|---|
//! | CSV | header `frame,node,x_U,y_U[,z_U]`, one row per frame and node, in any order | `U` of the header: `m`, `mm`, `um` (`µm`), `px` |
//! | NPY | float64 `frames × nodes × 3` or `× 2` | `clip.unit` (default `m`) |
//! | WCON | the worm community's JSON (Tracker Commons), [`wcon`] | its `units` block |
//!
//! - **2D recordings** (two coordinates) are placed at z = 0: planar data
//!   (`crate::clip::recording`).
//! - **Units.** A position in `px` needs `clip.scale_m_per_px`; a `clip.unit` that disagrees
//!   with the file's header is an error, not a silent choice.
//! - **Missing data** (`clip.missing = "nan"`): an empty cell, `nan`/`NaN` or a JSON `null` is an
//!   untracked node; a frame without rows between the first and the last (a dropped frame) is a
//!   lost frame, all of its nodes untracked. Without the key each of these is an error that
//!   names the file, the row or frame and the node.
//! - **Frame numbers** may start anywhere: the clip's frame 0 is the file's first frame
//!   ([`crate::clip::recording::RecordingInfo::first_frame`]), and every frame's time is its
//!   number times the frame interval. Node numbers run contiguously from 0 or from 1.
//! - Every index read from a file is only compared and sorted, never used to size or index an
//!   allocation: a gap of frames is filled only after its size has been checked against the
//!   positions a clip may hold ([`MAX_CLIP_POSITIONS`]).
use std::path::Path;

use nalgebra::Vector3;

pub mod wcon;

use crate::clip::missing::MissingData;
use crate::clip::recording::{constant_axis, LengthUnit, RecordingInfo, UnitSpec};
use crate::clip::MAX_CLIP_POSITIONS;
use crate::io::files::{open_capped, InputError};
use crate::io::npy::open_npy;

/// Largest CSV or WCON recording read [bytes]: 1 GiB. The paper's clip (1160 frames × 128
/// nodes) is about 11 MB as CSV; an hour at 30 frames/s with 128 nodes about 1 GB. (NPY
/// recordings and kymograms: `io::npy::NPY_FILE_CAP_BYTES`.)
pub const RECORDING_CAP_BYTES: u64 = 1 << 30;

/// How to read a recording: the case's unit and pixel scale, what marks a node that was not
/// tracked, the frame interval [s] (WCON times become frame numbers) and the worm of a WCON
/// file with several (`clip.worm_id`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReadSpec {
    pub units: UnitSpec,
    pub missing: MissingData,
    pub dt_s: f64,
    pub worm_id: Option<String>,
}

/// A recording as read: positions [m] per frame and node (NaN where untracked, with
/// [`MissingData::Nan`]) and what the file says about itself (its plane before any rotation).
#[derive(Clone, Debug, PartialEq)]
pub struct Recorded {
    pub frames: Vec<Vec<Vector3<f64>>>,
    pub info: RecordingInfo,
}

/// Read the recording `path` as `spec` says (module doc).
pub fn read_positions(path: &Path, spec: &ReadSpec) -> Result<Recorded, InputError> {
    let shape = |reason: String| InputError::Shape { path: path.to_path_buf(), reason };
    if path.is_dir() {
        return Err(shape("is a directory, not a recording file (.csv, .npy or .wcon/.json)".into()));
    }
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let table = match ext.as_deref() {
        Some("npy") => return npy_recorded(path, spec),
        Some("csv") => csv_table(path, spec)?,
        Some("wcon") | Some("json") => wcon::read(path, spec)?,
        _ => return Err(shape("unknown extension, expected .csv, .npy, .wcon or .json".into())),
    };
    table.into_recorded(path, spec.missing)
}

/// The unit of a file (`file`, `None` where it says nothing) against the case's: the one that
/// is given, an error where both are and differ; metres per unit.
pub(crate) fn resolve_unit(
    path: &Path,
    file: Option<LengthUnit>,
    spec: &UnitSpec,
    where_: &str,
) -> Result<(LengthUnit, f64), InputError> {
    let shape = |reason: String| InputError::Shape { path: path.to_path_buf(), reason };
    let unit = match (file, spec.unit) {
        (Some(f), Some(c)) if f != c => {
            return Err(shape(format!(
                "{where_} says the positions are in `{}`, but the case says clip.unit = \"{}\"; remove clip.unit or \
                 correct it",
                f.name(),
                c.name()
            )))
        }
        (Some(u), _) | (None, Some(u)) => u,
        (None, None) => LengthUnit::Metre,
    };
    let metres = unit.metres(spec.m_per_px).ok_or_else(|| {
        shape(format!(
            "positions in pixels ({where_}): give the camera's scale as clip.scale_m_per_px (metres per pixel)"
        ))
    })?;
    Ok((unit, metres))
}

/// Positions keyed by frame number before the frames are laid out: each row's frame, node and
/// position [m] (NaN where missing), sorted, and whether the file had two coordinates.
pub(crate) struct Table {
    /// `(frame, node, position, row)`: `row` names the source in errors (a CSV data row; 0
    /// where there is none)
    pub(crate) rows: Vec<(usize, usize, Vector3<f64>, usize)>,
    pub(crate) planar: bool,
    pub(crate) unit: LengthUnit,
}

impl Table {
    /// The frames of the rows: contiguous from the smallest frame number, nodes from the
    /// smallest node number; gaps of frames and missing node rows are untracked (NaN) with
    /// [`MissingData::Nan`] and errors without.
    fn into_recorded(mut self, path: &Path, missing: MissingData) -> Result<Recorded, InputError> {
        let shape = |reason: String| InputError::Shape { path: path.to_path_buf(), reason };
        if self.rows.is_empty() {
            return Err(shape("no data rows".into()));
        }
        self.rows.sort_by_key(|r| (r.0, r.1));
        if let Some(w) = self.rows.windows(2).filter(|w| (w[0].0, w[0].1) == (w[1].0, w[1].1)).min_by_key(|w| w[1].3) {
            return Err(InputError::DuplicateRow {
                path: path.to_path_buf(),
                row: w[0].3.max(w[1].3),
                first_row: w[0].3.min(w[1].3),
                frame: w[0].0,
                node: w[0].1,
            });
        }
        let node0 = self.rows.iter().map(|r| r.1).min().unwrap_or(0);
        if node0 > 1 {
            return Err(shape(format!("the smallest node number is {node0}: nodes must be numbered from 0 or 1")));
        }
        // nodes per frame: the most any frame has, at most the rows read
        let nodes = self.rows.iter().map(|r| r.1 - node0).max().unwrap_or(0).saturating_add(1);
        if nodes > self.rows.len() {
            let (frame, node) = first_missing(&self.rows, node0);
            return Err(InputError::MissingRow { path: path.to_path_buf(), frame, node });
        }
        if nodes < 3 {
            return Err(shape(format!("{nodes} nodes per frame, need at least 3")));
        }
        let (first, last) = (self.rows[0].0, self.rows[self.rows.len() - 1].0);
        let frames = (last - first).saturating_add(1);
        check_gap(path, first, last, nodes, &self.rows, missing)?;
        let nan = Vector3::repeat(f64::NAN);
        let mut out: Vec<Vec<Vector3<f64>>> = Vec::with_capacity(frames);
        let mut rows = self.rows.iter().peekable();
        for f in first..=last {
            let mut pts = vec![nan; nodes];
            let mut seen = 0;
            while let Some(r) = rows.next_if(|r| r.0 == f) {
                pts[r.1 - node0] = r.2;
                seen += 1;
            }
            if seen == 0 && missing == MissingData::Error {
                let next = rows.peek().map_or(f, |r| r.0);
                let row = rows.peek().map_or(0, |r| r.3);
                return Err(InputError::FrameGap { path: path.to_path_buf(), frame: f, next, row });
            }
            if seen != 0 && seen < nodes && missing == MissingData::Error {
                let node = (0..nodes).find(|&i| pts[i].x.is_nan() && pts[i].y.is_nan()).unwrap_or(0);
                return Err(InputError::MissingRow { path: path.to_path_buf(), frame: f, node: node + node0 });
            }
            out.push(pts);
        }
        let info = info_of(first, self.unit, if self.planar { Some(PLANE_AXIS) } else { constant_axis(&out) });
        Ok(Recorded { frames: out, info })
    }
}

/// The first (frame, node) without a row in the sorted `rows` whose nodes are numbered from
/// `node0`: a node number beyond the next one of its frame.
fn first_missing(rows: &[(usize, usize, Vector3<f64>, usize)], node0: usize) -> (usize, usize) {
    let mut expected = 0;
    for (k, r) in rows.iter().enumerate() {
        if k > 0 && rows[k - 1].0 != r.0 {
            expected = 0;
        }
        if r.1 - node0 != expected {
            return (r.0, expected + node0);
        }
        expected += 1;
    }
    rows.last().map_or((0, node0), |r| (r.0, expected + node0))
}

/// Refuse a recording whose frame numbers `first..=last` of `nodes` nodes would hold more
/// positions than a clip may, before any frame is laid out; and, without missing data, name
/// the first frame that has no rows.
fn check_gap(
    path: &Path,
    first: usize,
    last: usize,
    nodes: usize,
    rows: &[(usize, usize, Vector3<f64>, usize)],
    missing: MissingData,
) -> Result<(), InputError> {
    let frames = (last - first).saturating_add(1);
    if frames.saturating_mul(nodes) <= MAX_CLIP_POSITIONS {
        return Ok(());
    }
    // a jump in the frame numbers: the first frame after which it happens
    let gap = rows.windows(2).find(|w| w[1].0 > w[0].0 + 1);
    match (gap, missing) {
        (Some(w), MissingData::Error) => {
            Err(InputError::FrameGap { path: path.to_path_buf(), frame: w[0].0 + 1, next: w[1].0, row: w[1].3 })
        }
        _ => Err(InputError::Shape {
            path: path.to_path_buf(),
            reason: format!(
                "frames {first}–{last} × {nodes} nodes are more than the {MAX_CLIP_POSITIONS} positions a clip may hold \
                 (is the frame column a timestamp?)"
            ),
        }),
    }
}

/// A cell of a position column: a number, or NaN for an empty cell or `nan` (any case).
fn parse_coordinate(text: &str) -> Result<f64, std::num::ParseFloatError> {
    if text.is_empty() || text.eq_ignore_ascii_case("nan") {
        return Ok(f64::NAN);
    }
    text.parse::<f64>()
}

/// A position's coordinates must be finite; with [`MissingData::Nan`] a NaN (an empty cell)
/// marks an untracked node (an infinity stays an error).
pub(crate) fn check_position(
    path: &Path,
    (frame, node): (usize, usize),
    p: &Vector3<f64>,
    missing: MissingData,
) -> Result<(), InputError> {
    let marked = |v: f64| missing == MissingData::Nan && v.is_nan();
    match (0..3).find(|&k| !p[k].is_finite() && !marked(p[k])) {
        Some(k) => Err(InputError::NonFinitePosition {
            path: path.to_path_buf(),
            frame,
            node,
            axis: ['x', 'y', 'z'][k],
            value: p[k],
        }),
        None => Ok(()),
    }
}

/// The unit suffix shared by the position columns of a CSV header (`x_um, y_um` → `um`), and
/// whether there are two of them.
fn csv_header(path: &Path, header: &[String]) -> Result<(LengthUnit, bool), InputError> {
    let bad = |why: &str| InputError::Shape {
        path: path.to_path_buf(),
        reason: format!(
            "header {header:?}: {why}; expected frame,node,x_U,y_U or frame,node,x_U,y_U,z_U with U the unit (m, mm, \
             um, px), e.g. frame,node,x_um,y_um"
        ),
    };
    if header.len() < 4 || header.len() > 5 || header[0] != "frame" || header[1] != "node" {
        return Err(bad("not a recording's columns"));
    }
    let mut unit: Option<&str> = None;
    for (col, axis) in header[2..].iter().zip(["x_", "y_", "z_"]) {
        let u = col.strip_prefix(axis).ok_or_else(|| bad(&format!("column `{col}` is not `{axis}` and a unit")))?;
        if unit.is_some_and(|v| v != u) {
            return Err(bad("the position columns have different units"));
        }
        unit = Some(u);
    }
    let name = unit.unwrap_or_default();
    let u = LengthUnit::parse(name).ok_or_else(|| bad(&format!("unknown unit `{name}`")))?;
    Ok((u, header.len() == 4))
}

/// The rows of a CSV recording (module doc).
fn csv_table(path: &Path, spec: &ReadSpec) -> Result<Table, InputError> {
    // read as it goes: an hour's CSV (about 1 GB) is never held beside its rows
    let (file, _) = open_capped(path, RECORDING_CAP_BYTES, "recording")?;
    let mut rdr =
        csv::ReaderBuilder::new().trim(csv::Trim::All).flexible(true).buffer_capacity(1 << 20).from_reader(file);
    let csv_err = |source| InputError::Csv { path: path.to_path_buf(), source };
    let header: Vec<String> = rdr.headers().map_err(csv_err)?.iter().map(String::from).collect();
    let (file_unit, planar) = csv_header(path, &header)?;
    let (unit, metres) = resolve_unit(path, Some(file_unit), &spec.units, "the CSV header")?;
    let columns = header.len();
    let mut rows = Vec::new();
    for (i, rec) in rdr.records().enumerate() {
        let row = i + 1;
        let bad = |reason: String| InputError::Row { path: path.to_path_buf(), row, reason };
        let rec = rec.map_err(|e| bad(e.to_string()))?;
        if rec.len() != columns {
            return Err(bad(format!("{} columns, expected {columns}", rec.len())));
        }
        if rows.len() == MAX_CLIP_POSITIONS {
            return Err(bad(format!("more than {MAX_CLIP_POSITIONS} rows, the most positions a clip may hold")));
        }
        let index = |k: usize| {
            rec[k]
                .parse::<usize>()
                .map_err(|_| bad(format!("{} `{}` is not a non-negative integer", header[k], &rec[k])))
        };
        let (frame, node) = (index(0)?, index(1)?);
        let hint = if spec.missing == MissingData::Error {
            " (if the tracker leaves untracked nodes empty, set clip.missing = \"nan\" in the case)"
        } else {
            ""
        };
        let coord = |k: usize| match parse_coordinate(&rec[k]) {
            Ok(v) if v.is_nan() && rec[k].is_empty() && spec.missing == MissingData::Error => {
                Err(bad(format!("frame {frame}, node {node}: {} is empty{hint}", header[k])))
            }
            Ok(v) => Ok(v * metres),
            Err(e) => Err(bad(format!("{} `{}`: {e}", header[k], &rec[k]))),
        };
        let position = Vector3::new(coord(2)?, coord(3)?, if planar { 0.0 } else { coord(4)? });
        // a node untracked in one coordinate is untracked
        let position = if position.iter().any(|v| v.is_nan()) { Vector3::repeat(f64::NAN) } else { position };
        check_position(path, (frame, node), &position, spec.missing)?;
        rows.push((frame, node, position, row));
    }
    Ok(Table { rows, planar, unit })
}

/// An NPY recording, `frames × nodes × 3` or `× 2` (frames numbered from 0): a full grid, so
/// its frames are laid out as the file is read, a frame at a time (an hour of 128 nodes at 30
/// frames/s is 330 MB of positions: never held twice).
fn npy_recorded(path: &Path, spec: &ReadSpec) -> Result<Recorded, InputError> {
    let mut reader = NpyFrames::open(path, spec)?;
    let mut out = Vec::with_capacity(reader.frames());
    while let Some(pts) = reader.next_frame()? {
        out.push(pts);
    }
    let info = info_of(0, reader.unit(), if reader.planar() { Some(PLANE_AXIS) } else { constant_axis(&out) });
    Ok(Recorded { frames: out, info })
}

/// An NPY recording (`frames × nodes × 3` or `× 2`) read a frame at a time, each frame checked
/// and converted to metres as [`read_positions`] does (a 2D recording placed at z = 0, a node
/// untracked in one coordinate untracked in all): what a clip streamed from its file reads
/// (`super::recording_stream`), and the reader of [`read_positions`].
pub struct NpyFrames {
    stream: crate::io::npy::NpyStream,
    path: std::path::PathBuf,
    missing: MissingData,
    unit: LengthUnit,
    /// metres per unit of the file
    metres: f64,
    frames: usize,
    nodes: usize,
    /// coordinates per position (2 or 3)
    dims: usize,
    /// the index of the next frame
    next: usize,
    values: Vec<f64>,
}

impl NpyFrames {
    /// Open the NPY recording `path` as `spec` says: its shape, size and unit checked.
    pub fn open(path: &Path, spec: &ReadSpec) -> Result<NpyFrames, InputError> {
        let stream = open_npy(path)?;
        let shape = |reason: String| InputError::Shape { path: path.to_path_buf(), reason };
        let &[frames, nodes, dims @ (2 | 3)] = stream.shape.as_slice() else {
            return Err(shape(format!("recording of shape {:?}, expected frames × nodes × 3 (or × 2)", stream.shape)));
        };
        if frames == 0 || nodes < 3 {
            return Err(shape(format!("recording of shape {:?}: need at least 1 frame and 3 nodes", stream.shape)));
        }
        // the shape's product was checked by open_npy: it does not overflow
        if frames * nodes > MAX_CLIP_POSITIONS {
            return Err(shape(format!(
                "recording of shape {:?}: {} positions, more than the {MAX_CLIP_POSITIONS} a clip may hold",
                stream.shape,
                frames * nodes
            )));
        }
        let (unit, metres) = resolve_unit(path, None, &spec.units, "the NPY file")?;
        let values = vec![0.0; nodes * dims];
        let path = path.to_path_buf();
        Ok(NpyFrames { stream, path, missing: spec.missing, unit, metres, frames, nodes, dims, next: 0, values })
    }

    /// Frames of the recording.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Nodes per frame.
    pub fn nodes(&self) -> usize {
        self.nodes
    }

    /// The unit the positions are read in.
    pub fn unit(&self) -> LengthUnit {
        self.unit
    }

    /// Does the file hold two coordinates per position (a planar recording at z = 0)?
    pub fn planar(&self) -> bool {
        self.dims == 2
    }

    /// The next frame's positions [m] (NaN where untracked, with [`MissingData::Nan`]); `None`
    /// after the last.
    pub fn next_frame(&mut self) -> Result<Option<Vec<Vector3<f64>>>, InputError> {
        if self.next == self.frames {
            return Ok(None);
        }
        self.stream.read(&mut self.values)?;
        let pts = frame_positions(&self.path, self.next, (&self.values, self.dims), self.missing, self.metres)?;
        self.next += 1;
        Ok(Some(pts))
    }
}

/// Frame `frame` of a recording from its coordinates `values`, `dims` (2 or 3) per node, each
/// position checked and converted to metres (`metres` per unit): a 2D position placed at
/// z = 0, a node untracked (NaN) in one coordinate untracked in all. `path` names the source.
pub(crate) fn frame_positions(
    path: &Path,
    frame: usize,
    (values, dims): (&[f64], usize),
    missing: MissingData,
    metres: f64,
) -> Result<Vec<Vector3<f64>>, InputError> {
    let mut pts = Vec::with_capacity(values.len() / dims);
    for (i, c) in values.chunks_exact(dims).enumerate() {
        let p = Vector3::new(c[0], c[1], if dims == 3 { c[2] } else { 0.0 });
        check_position(path, (frame, i), &p, missing)?;
        pts.push(if p.iter().any(|v| v.is_nan()) { Vector3::repeat(f64::NAN) } else { p * metres });
    }
    Ok(pts)
}

/// A recording held in memory (frames × nodes × `dims` coordinates, frame-major, numbered from
/// 0), read as an NPY file of the same array is ([`NpyFrames`]): the same shape limits, checks,
/// unit (`spec`: the case's `clip.unit`, metres by default) and missing-data rule. `name` stands
/// for the file in messages.
pub fn memory_recorded(
    name: &Path,
    values: &[f64],
    (frames, nodes, dims): (usize, usize, usize),
    spec: &ReadSpec,
) -> Result<Recorded, InputError> {
    let shape = |reason: String| InputError::Shape { path: name.to_path_buf(), reason };
    let shape_text = format!("[{frames}, {nodes}, {dims}]");
    if !(dims == 2 || dims == 3) || frames.checked_mul(nodes).and_then(|p| p.checked_mul(dims)) != Some(values.len()) {
        return Err(shape(format!(
            "recording of shape {shape_text} with {} values, expected frames × nodes × 3 (or × 2)",
            values.len()
        )));
    }
    if frames == 0 || nodes < 3 {
        return Err(shape(format!("recording of shape {shape_text}: need at least 1 frame and 3 nodes")));
    }
    if frames * nodes > MAX_CLIP_POSITIONS {
        return Err(shape(format!(
            "recording of shape {shape_text}: {} positions, more than the {MAX_CLIP_POSITIONS} a clip may hold",
            frames * nodes
        )));
    }
    let (unit, metres) = resolve_unit(name, None, &spec.units, "the recording in memory")?;
    let out = values
        .chunks_exact(nodes * dims)
        .enumerate()
        .map(|(f, v)| frame_positions(name, f, (v, dims), spec.missing, metres))
        .collect::<Result<Vec<_>, _>>()?;
    let info = info_of(0, unit, if dims == 2 { Some(PLANE_AXIS) } else { constant_axis(&out) });
    Ok(Recorded { frames: out, info })
}

/// The axis normal to the plane z = 0 that a recording of two coordinates is placed in.
pub(crate) const PLANE_AXIS: usize = 2;

/// What a recording says about itself: its first frame number, its unit and its plane, normal
/// to `axis`, the axis along which every position is the same, if there is one:
/// [`PLANE_AXIS`] for a file of two coordinates, else found in its frames ([`constant_axis`],
/// or `crate::clip::recording::ConstantAxes` as they are read).
pub(crate) fn info_of(first_frame: usize, unit: LengthUnit, axis: Option<usize>) -> RecordingInfo {
    RecordingInfo { first_frame, unit, plane_normal: axis.map(|k| Vector3::ith(k, 1.0)) }
}

#[cfg(test)]
mod tests;
