//! Real C. elegans clips for the inverse problem of §6 of [R1] (issue 4): centreline sequences
//! `x_g(s, t_n)` read from a joint-angle kymogram or from a user recording.
//!
//! ## Kymograms (`elegansbot`)
//! `scripts/fetch_worm_data.sh` puts the omega-turn (600 frames) and delta-turn (300 frames)
//! kymograms of the `elegansbot` package, derived from Broekmans et al., eLife 5 (2016), into
//! `data/elegansbot/` (32 frames/s, the package's `examples/example03.py`). Row `n` holds the
//! `M = 24` joint angles `a_j` [rad] between the `M + 1 = 25` rigid segments of the body, head to
//! tail. A kymogram holds the body's *shape* only; its position and heading are not recorded
//! (elegansbot recovers them by simulating friction). Frame by frame ([`kymogram_joints`]):
//!
//! ```text
//! θ_0 = 0,  θ_{j+1} = θ_j + a_j,     p_0 = 0,  p_{j+1} = p_j + (L/(M+1)) (cos θ_j, sin θ_j),   j = 0 … M
//! ```
//!
//! gives `M + 2 = 26` joints in the body plane `(u, v)`, `L` = 1 mm. The points are then
//! resampled to `N` nodes (128 in [R1]) equally spaced in arc length along a not-a-knot cubic
//! spline through the joints ([`Spline`]); linear resampling would put all curvature in 24
//! corners.
//!
//! **Placement.** Node 0 is the head: `s = 0` at the head, `s = L` at the tail, as in Figs.
//! 16–17 of [R1]. The code's reference configuration is `x0(s) = (0, 0, s)`, so one rigid motion,
//! computed from frame 0 and applied to every frame, maps the body plane to the x–z plane:
//! frame 0's head to the origin and its head→tail chord onto +e3; the in-plane normal direction
//! `v` (rotated) goes to +e1, the plane normal to +e2, and `y = 0` for every node. The x–z
//! plane keeps every tangent away from ±e2, where `β = ±π/2` makes `det A = 0`
//! (PAPER-NOTES, worm clip: in the x–y plane the omega turn has tangents along ±e2 in many frames).
//! Since all frames have `θ_0 = 0` at `p_0 = 0` before the motion, every frame's head sits at the
//! origin with the same head-segment direction.
//!
//! ## User recordings
//! [`read_recording`]: CSV with header `frame,node,x_m,y_m,z_m` (0-based, contiguous frames and
//! nodes, rows in any order, every frame with the same node count ≥ 3) or NPY of shape
//! `frames × nodes × 3` [m]. Positions are used as given (no resampling, no rigid motion).
//!
//! ## Stretch
//! Remark 9 of [R1]: the data give the current arc length, so `j = ∂_s̃ s` is known. Per frame,
//! [`Clip::stretch`] is the polyline length of the nodes divided by [`Clip::length_m`].
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::{Vector2, Vector3};

use crate::output::OutputError;

mod npy;
mod spline;
pub mod synthetic;

pub use npy::{npy_bytes, read_npy, write_npy, NpyArray};
pub use spline::Spline;

/// Body length of the kymogram clips, L [m].
pub const WORM_LENGTH_M: f64 = 1e-3;
/// Frame rate of the elegansbot kymograms [1/s] (`examples/example03.py`).
pub const KYMOGRAM_FPS: f64 = 32.0;
/// Nodes per frame in [R1] §6.
pub const PAPER_NODES: usize = 128;
/// Column names of a CSV recording.
pub const RECORDING_HEADER: [&str; 5] = ["frame", "node", "x_m", "y_m", "z_m"];

/// Errors reading clips; each names the file and, where it applies, the frame, node or row.
#[derive(Debug, thiserror::Error)]
pub enum ClipError {
    #[error("cannot read clip file {path}: {reason}")]
    Read { path: PathBuf, reason: String },
    #[error("clip file {path}: not a little-endian float64 C-order .npy file: {reason}")]
    Npy { path: PathBuf, reason: String },
    #[error("clip file {path}: {reason}")]
    Shape { path: PathBuf, reason: String },
    #[error("clip file {path}, frame {frame}, joint {joint}: angle {value} is not finite")]
    NonFiniteAngle { path: PathBuf, frame: usize, joint: usize, value: f64 },
    #[error("clip file {path}, frame {frame}, node {node}: {axis} = {value} is not finite")]
    NonFinitePosition { path: PathBuf, frame: usize, node: usize, axis: char, value: f64 },
    #[error("clip file {path}, frame {frame}: {nodes} nodes, but frame 0 has {expected}")]
    NodeCount { path: PathBuf, frame: usize, nodes: usize, expected: usize },
    #[error("clip file {path}, frame {frame}, node {node}: no row (frames and nodes must be contiguous from 0)")]
    MissingRow { path: PathBuf, frame: usize, node: usize },
    #[error("clip file {path}, row {row}: frame {frame}, node {node} already given in row {first_row}")]
    DuplicateRow { path: PathBuf, row: usize, first_row: usize, frame: usize, node: usize },
    #[error("clip file {path}, row {row}: {reason}")]
    Row { path: PathBuf, row: usize, reason: String },
    #[error("synthetic clip: kymogram {which} has {frames} frames, need at least {minimum}")]
    SyntheticTooFewFrames { which: &'static str, frames: usize, minimum: usize },
    #[error("synthetic clip: kymogram {which}, frame {frame}: {joints} joint angles, but frame 0 has {expected}")]
    SyntheticRowLength { which: &'static str, frame: usize, joints: usize, expected: usize },
    #[error("synthetic clip: kymogram {which}, frame 0: 0 joint angles, need at least 1")]
    SyntheticNoJoints { which: &'static str },
    #[error("synthetic clip: kymogram {which}, frame {frame}, joint {joint}: angle {value} is not finite")]
    SyntheticNonFiniteAngle { which: &'static str, frame: usize, joint: usize, value: f64 },
    #[error("synthetic clip: parameter {name} = {value} is invalid, must be {requirement}")]
    SyntheticParameter { name: &'static str, value: f64, requirement: &'static str },
    #[error("synthetic clip: time mapping OmegaThenDelta needs the delta-turn kymogram")]
    SyntheticMissingDelta,
    #[error("frame comparison: {what} has {len} nodes, truth has {expected}")]
    ComparisonSize { what: &'static str, len: usize, expected: usize },
    #[error("frame comparison: skipping {skip} nodes at each end of {nodes} leaves none")]
    ComparisonSkip { skip: usize, nodes: usize },
    #[error(transparent)]
    Write(#[from] OutputError),
}

/// A sequence of centrelines sampled at the same nodes, head (`s = 0`) first.
#[derive(Debug, Clone, PartialEq)]
pub struct Clip {
    /// Node positions, frames × nodes [m].
    pub frames: Vec<Vec<Vector3<f64>>>,
    /// Time between frames [s].
    pub dt_s: f64,
    /// Where the clip came from (file and processing).
    pub source: String,
    /// Reference body length L used for the stretch j [m]: the kymogram's body length, or the
    /// polyline length of frame 0 for a recording.
    pub length_m: f64,
}

impl Clip {
    /// Nodes per frame.
    pub fn node_count(&self) -> usize {
        self.frames.first().map_or(0, Vec::len)
    }

    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.frames.len()
    }

    /// Stretch `j` of a frame: polyline length of its nodes / `length_m` (Remark 9 of [R1]).
    pub fn stretch(&self, frame: usize) -> f64 {
        polyline_length(&self.frames[frame]) / self.length_m
    }

    /// `max |j − 1|` over the frames, and the frame where it occurs.
    pub fn max_stretch_deviation(&self) -> (usize, f64) {
        (0..self.frame_count()).map(|f| (f, (self.stretch(f) - 1.0).abs())).fold((0, 0.0), |a, b| {
            if b.1 > a.1 {
                b
            } else {
                a
            }
        })
    }

    /// Frames in which some segment's unit tangent is within `tol` of `±direction` (a unit
    /// vector). With `direction = e2` these are the frames that touch `β = ±π/2`.
    pub fn frames_with_tangent_near(&self, direction: &Vector3<f64>, tol: f64) -> Vec<usize> {
        let near = |t: Vector3<f64>| (t - direction).norm() < tol || (t + direction).norm() < tol;
        (0..self.frame_count())
            .filter(|&f| self.frames[f].windows(2).any(|w| near((w[1] - w[0]).normalize())))
            .collect()
    }
}

/// Length of the polyline through `points` [m].
pub fn polyline_length(points: &[Vector3<f64>]) -> f64 {
    points.windows(2).map(|w| (w[1] - w[0]).norm()).sum()
}

/// Plane the kymogram's body plane is mapped to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ClipPlane {
    /// x–z plane, frame-0 chord along +e3 (the reference configuration `x0 = (0, 0, s)`).
    #[default]
    Xz,
    /// x–y plane, frame-0 chord along +e1 (for comparison only: tangents can reach ±e2).
    Xy,
}

/// How a kymogram becomes a [`Clip`].
#[derive(Debug, Clone, PartialEq)]
pub struct KymogramParams {
    /// Body length L [m].
    pub length_m: f64,
    /// Nodes per frame after resampling (≥ 2).
    pub nodes: usize,
    /// Time between frames [s].
    pub dt_s: f64,
    /// Target plane of the rigid placement.
    pub plane: ClipPlane,
    /// Scale each frame about its head so that the spline's arc length is `length_m`. The
    /// spline through the joints is longer than the joint polygon (by up to ~0.8 % on the
    /// elegansbot clips, the chord-vs-arc excess of bent segments); with this, `j ≈ 1`, but the
    /// nodes no longer pass through the joints.
    pub scale_to_length: bool,
}

impl Default for KymogramParams {
    fn default() -> Self {
        KymogramParams {
            length_m: WORM_LENGTH_M,
            nodes: PAPER_NODES,
            dt_s: 1.0 / KYMOGRAM_FPS,
            plane: ClipPlane::Xz,
            scale_to_length: false,
        }
    }
}

/// Joints of one kymogram row in the body plane: `angles.len() + 2` points, segment length
/// `length_m / (angles.len() + 1)` [m] (see the module doc).
pub fn kymogram_joints(angles: &[f64], length_m: f64) -> Vec<Vector2<f64>> {
    let ds = length_m / (angles.len() + 1) as f64;
    let mut joints = Vec::with_capacity(angles.len() + 2);
    let (mut p, mut theta) = (Vector2::zeros(), 0.0f64);
    joints.push(p);
    for j in 0..=angles.len() {
        p += Vector2::new(theta.cos(), theta.sin()) * ds;
        joints.push(p);
        if j < angles.len() {
            theta += angles[j];
        }
    }
    joints
}

/// Clip from kymogram rows (frames × joint angles [rad]): joints, rigid placement from frame 0,
/// spline resampling to `params.nodes` nodes equally spaced in arc length.
pub fn clip_from_angles(rows: &[Vec<f64>], params: &KymogramParams, source: String) -> Clip {
    assert!(params.nodes >= 2, "at least two nodes");
    let joints: Vec<Vec<Vector2<f64>>> = rows.iter().map(|a| kymogram_joints(a, params.length_m)).collect();
    let Some(first) = joints.first() else {
        return Clip { frames: Vec::new(), dt_s: params.dt_s, source, length_m: params.length_m };
    };
    let (head, chord) = (first[0], first[first.len() - 1] - first[0]);
    let (c, s) = (chord.x / chord.norm(), chord.y / chord.norm());
    // Rotate by −φ so the chord lies along the first in-plane axis, then embed.
    let place = |p: &Vector2<f64>| {
        let q = p - head;
        let (along, across) = (c * q.x + s * q.y, -s * q.x + c * q.y);
        match params.plane {
            ClipPlane::Xz => Vector3::new(across, 0.0, along),
            ClipPlane::Xy => Vector3::new(along, across, 0.0),
        }
    };
    let frames = joints
        .iter()
        .map(|frame| {
            let placed: Vec<Vector3<f64>> = frame.iter().map(place).collect();
            let (nodes, arc) = Spline::through(&placed).resample_by_arc_length(params.nodes);
            if params.scale_to_length {
                let (origin, k) = (nodes[0], params.length_m / arc);
                nodes.iter().map(|p| origin + (p - origin) * k).collect()
            } else {
                nodes
            }
        })
        .collect();
    Clip { frames, dt_s: params.dt_s, source, length_m: params.length_m }
}

/// Read a kymogram `.npy` (frames × joints, float64, angles [rad]) into a [`Clip`].
pub fn read_kymogram(path: &Path, params: &KymogramParams) -> Result<Clip, ClipError> {
    let a = read_npy(path)?;
    let shape = |reason: String| ClipError::Shape { path: path.to_path_buf(), reason };
    let &[frames, joints] = a.shape.as_slice() else {
        return Err(shape(format!("kymogram of shape {:?}, expected 2 axes (frames × joint angles)", a.shape)));
    };
    if frames == 0 || joints == 0 {
        return Err(shape(format!("kymogram of shape {:?} is empty", a.shape)));
    }
    if let Some(k) = a.data.iter().position(|v| !v.is_finite()) {
        return Err(ClipError::NonFiniteAngle {
            path: path.to_path_buf(),
            frame: k / joints,
            joint: k % joints,
            value: a.data[k],
        });
    }
    let rows: Vec<Vec<f64>> = a.data.chunks_exact(joints).map(<[f64]>::to_vec).collect();
    let scaled = if params.scale_to_length { ", scaled to the body length" } else { "" };
    let source = format!(
        "{} ({frames} frames × {joints} joint angles; spline resampled to {} nodes{scaled}, {:?} plane)",
        path.display(),
        params.nodes,
        params.plane
    );
    Ok(clip_from_angles(&rows, params, source))
}

/// Read a user recording: `.csv` (header `frame,node,x_m,y_m,z_m`) or `.npy` (frames × nodes × 3,
/// float64) [m]; `dt_s` is the time between frames [s].
pub fn read_recording(path: &Path, dt_s: f64) -> Result<Clip, ClipError> {
    let frames = match path.extension().and_then(|e| e.to_str()) {
        Some("npy") => recording_npy(path)?,
        Some("csv") => recording_csv(path)?,
        _ => {
            return Err(ClipError::Read {
                path: path.to_path_buf(),
                reason: "unknown extension, expected .csv or .npy".into(),
            })
        }
    };
    let length_m = polyline_length(&frames[0]);
    if length_m <= 0.0 {
        return Err(ClipError::Shape { path: path.to_path_buf(), reason: "frame 0 has zero length".into() });
    }
    let source = format!("{} ({} frames × {} nodes)", path.display(), frames.len(), frames[0].len());
    Ok(Clip { frames, dt_s, source, length_m })
}

fn check_position(path: &Path, frame: usize, node: usize, p: &Vector3<f64>) -> Result<(), ClipError> {
    match (0..3).find(|&k| !p[k].is_finite()) {
        Some(k) => Err(ClipError::NonFinitePosition {
            path: path.to_path_buf(),
            frame,
            node,
            axis: ['x', 'y', 'z'][k],
            value: p[k],
        }),
        None => Ok(()),
    }
}

fn recording_npy(path: &Path) -> Result<Vec<Vec<Vector3<f64>>>, ClipError> {
    let a = read_npy(path)?;
    let shape = |reason: String| ClipError::Shape { path: path.to_path_buf(), reason };
    let &[frames, nodes, 3] = a.shape.as_slice() else {
        return Err(shape(format!("recording of shape {:?}, expected frames × nodes × 3", a.shape)));
    };
    if frames == 0 || nodes < 3 {
        return Err(shape(format!("recording of shape {:?}: need at least 1 frame and 3 nodes", a.shape)));
    }
    let mut out = Vec::with_capacity(frames);
    for (f, frame) in a.data.chunks_exact(3 * nodes).enumerate() {
        let pts: Vec<Vector3<f64>> = frame.chunks_exact(3).map(|c| Vector3::new(c[0], c[1], c[2])).collect();
        for (i, p) in pts.iter().enumerate() {
            check_position(path, f, i, p)?;
        }
        out.push(pts);
    }
    Ok(out)
}

fn recording_csv(path: &Path) -> Result<Vec<Vec<Vector3<f64>>>, ClipError> {
    let read = |reason: String| ClipError::Read { path: path.to_path_buf(), reason };
    let mut rdr = csv::ReaderBuilder::new().trim(csv::Trim::All).from_path(path).map_err(|e| read(e.to_string()))?;
    let headers: Vec<String> = rdr.headers().map_err(|e| read(e.to_string()))?.iter().map(String::from).collect();
    if headers != RECORDING_HEADER {
        return Err(read(format!("header {headers:?}, expected {RECORDING_HEADER:?}")));
    }
    // (frame, node) → (row, position)
    let mut rows: BTreeMap<(usize, usize), (usize, Vector3<f64>)> = BTreeMap::new();
    for (i, rec) in rdr.records().enumerate() {
        let row = i + 1;
        let bad = |reason: String| ClipError::Row { path: path.to_path_buf(), row, reason };
        let rec = rec.map_err(|e| bad(e.to_string()))?;
        if rec.len() != 5 {
            return Err(bad(format!("{} columns, expected 5", rec.len())));
        }
        let index = |k: usize| {
            rec[k]
                .parse::<usize>()
                .map_err(|_| bad(format!("{} `{}` is not a non-negative integer", RECORDING_HEADER[k], &rec[k])))
        };
        let (frame, node) = (index(0)?, index(1)?);
        let coord =
            |k: usize| rec[k].parse::<f64>().map_err(|e| bad(format!("{} `{}`: {e}", RECORDING_HEADER[k], &rec[k])));
        let p = Vector3::new(coord(2)?, coord(3)?, coord(4)?);
        check_position(path, frame, node, &p)?;
        if let Some(&(first_row, _)) = rows.get(&(frame, node)) {
            return Err(ClipError::DuplicateRow { path: path.to_path_buf(), row, first_row, frame, node });
        }
        rows.insert((frame, node), (row, p));
    }
    let Some(&(last_frame, _)) = rows.keys().next_back() else {
        return Err(ClipError::Shape { path: path.to_path_buf(), reason: "no data rows".into() });
    };
    let mut frames: Vec<Vec<Vector3<f64>>> = vec![Vec::new(); last_frame + 1];
    for (&(frame, node), &(_, p)) in &rows {
        if node != frames[frame].len() {
            return Err(ClipError::MissingRow { path: path.to_path_buf(), frame, node: frames[frame].len() });
        }
        frames[frame].push(p);
    }
    let expected = frames[0].len();
    for (frame, pts) in frames.iter().enumerate() {
        if pts.is_empty() {
            return Err(ClipError::MissingRow { path: path.to_path_buf(), frame, node: 0 });
        }
        if pts.len() != expected {
            return Err(ClipError::NodeCount { path: path.to_path_buf(), frame, nodes: pts.len(), expected });
        }
    }
    if expected < 3 {
        return Err(ClipError::Shape {
            path: path.to_path_buf(),
            reason: format!("{expected} nodes per frame, need at least 3"),
        });
    }
    Ok(frames)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Discrete (Menger) curvature at the interior nodes [1/m].
    fn menger_curvature(p: &[Vector3<f64>]) -> Vec<f64> {
        p.windows(3)
            .map(|w| {
                let (a, b) = (w[1] - w[0], w[2] - w[1]);
                2.0 * a.cross(&b).norm() / (a.norm() * b.norm() * (a + b).norm())
            })
            .collect()
    }

    fn planar(joints: &[Vector2<f64>]) -> Vec<Vector3<f64>> {
        joints.iter().map(|p| Vector3::new(p.x, p.y, 0.0)).collect()
    }

    /// Constant joint angles `a_j = c`: the joints lie on a circle; the spline through them stays
    /// near it. Measured, 26 joints → 128 nodes:
    ///
    /// | c [rad] | radius err / R | spline length / arc − 1 | chord spacing vs h | κ max/mean | max abs(κR − 1) | linear: κ max/mean |
    /// |---|---|---|---|---|---|---|
    /// | 0.05 | 1.8e-7 | 1.2e-9 | 4.1e-6 | 1.0012 | 1.2e-3 | 5.0 |
    /// | 0.25 | 1.1e-4 | 8.5e-7 | 1.1e-4 | 1.028 | 2.9e-2 | 5.0 |
    ///
    /// The curvature ripple of the cubic interpolant is about c²/2 (period: one joint spacing);
    /// linear resampling puts the curvature in the 24 corners (ratio 5).
    #[test]
    fn constant_joint_angles_give_a_circular_arc() {
        let (l, n) = (WORM_LENGTH_M, PAPER_NODES);
        for c in [0.05, 0.25] {
            let joints = kymogram_joints(&[c; 24], l);
            assert_eq!(joints.len(), 26);
            // The joints are a chord polygon of the circle of radius R = ds / (2 sin(c/2)): each
            // chord ds subtends c. The head chord runs from (0, 0) to (ds, 0) and the body turns
            // towards +v, so the centre is (ds/2, R cos(c/2)).
            let ds = l / 25.0;
            let r = ds / (2.0 * (c / 2.0).sin());
            let centre = Vector3::new(ds / 2.0, r * (c / 2.0).cos(), 0.0);
            for p in planar(&joints) {
                assert!(((p - centre).norm() - r).abs() < 1e-12 * r, "joint off the circle");
            }
            let (nodes, spline_len) = Spline::through(&planar(&joints)).resample_by_arc_length(n);
            assert_eq!(nodes.len(), n);
            let radius_err = nodes.iter().map(|p| ((p - centre).norm() - r).abs() / r).fold(0.0, f64::max);
            // Arc length of the circle through the joints: 25 c R.
            let arc_err = (spline_len / (25.0 * c * r) - 1.0).abs();
            let h = (25.0 * c * r) / (n - 1) as f64;
            let spacing_err = nodes.windows(2).map(|w| ((w[1] - w[0]).norm() / h - 1.0).abs()).fold(0.0, f64::max);
            let kappa = menger_curvature(&nodes);
            let mean = kappa.iter().sum::<f64>() / kappa.len() as f64;
            let peak = kappa.iter().cloned().fold(0.0, f64::max);
            let kappa_err = kappa.iter().map(|k| (k * r - 1.0).abs()).fold(0.0, f64::max);
            // The same with linear resampling along the joint polygon, for contrast.
            let linear = linear_resample(&planar(&joints), n);
            let kl = menger_curvature(&linear);
            let linear_ratio = kl.iter().cloned().fold(0.0, f64::max) / (kl.iter().sum::<f64>() / kl.len() as f64);
            println!(
                "c = {c}: radius err {radius_err:.2e} R, spline/arc length − 1 {arc_err:.2e}, chord spacing err {spacing_err:.2e}, \
                 κ max/mean {:.6}, max |κR − 1| {kappa_err:.2e}; linear resampling max/mean {linear_ratio:.2}",
                peak / mean
            );
            assert!(radius_err < 0.05 * c.powi(4), "radius error {radius_err:e}");
            assert!(arc_err < 1e-5, "arc length error {arc_err:e}");
            assert!(spacing_err < 3e-3 * c * c, "spacing error {spacing_err:e}");
            assert!(
                peak / mean < 1.0 + 0.6 * c * c && kappa_err < 0.6 * c * c,
                "curvature max/mean {}, max |κR − 1| {kappa_err:e}",
                peak / mean
            );
            assert!(linear_ratio > 2.0, "linear resampling concentrates curvature: {linear_ratio}");
        }
    }

    /// Linear interpolation along a polyline at equal arc-length steps (test contrast only).
    fn linear_resample(p: &[Vector3<f64>], n: usize) -> Vec<Vector3<f64>> {
        let total = polyline_length(p);
        let mut out = vec![p[0]];
        let (mut seg, mut start) = (0, 0.0);
        for k in 1..n - 1 {
            let target = total * k as f64 / (n - 1) as f64;
            while start + (p[seg + 1] - p[seg]).norm() < target {
                start += (p[seg + 1] - p[seg]).norm();
                seg += 1;
            }
            let d = p[seg + 1] - p[seg];
            out.push(p[seg] + d * ((target - start) / d.norm()));
        }
        out.push(p[p.len() - 1]);
        out
    }

    fn wave(phase: f64) -> Vec<f64> {
        (0..24).map(|j| 0.05 + 0.3 * (2.0 * std::f64::consts::PI * j as f64 / 24.0 + phase).sin()).collect()
    }

    #[test]
    fn placement_is_one_rigid_motion_into_the_xz_plane() {
        let rows = vec![wave(0.0), wave(1.0), wave(2.5)];
        let params = KymogramParams::default();
        let clip = clip_from_angles(&rows, &params, "test".into());
        assert_eq!((clip.frame_count(), clip.node_count()), (3, 128));
        assert_eq!(clip.dt_s, 1.0 / 32.0);
        let f0 = &clip.frames[0];
        assert_eq!(f0[0], Vector3::zeros(), "s = 0 (head) at the origin");
        let tail = f0[127];
        assert!(tail.x.abs() < 1e-18 && tail.z > 0.0, "frame-0 chord along +e3: {tail}");
        assert!(clip.frames.iter().flatten().all(|p| p.y == 0.0), "y = 0");
        // Same motion for every frame: all distances between nodes of any two frames are those
        // of the unplaced, resampled body-plane curves.
        let raw: Vec<Vec<Vector3<f64>>> = rows
            .iter()
            .map(|a| Spline::through(&planar(&kymogram_joints(a, params.length_m))).resample_by_arc_length(128).0)
            .collect();
        let mut worst: f64 = 0.0;
        for (f, g) in [(0, 1), (0, 2), (1, 2)] {
            for i in (0..128).step_by(7) {
                for k in (0..128).step_by(5) {
                    let d = (clip.frames[f][i] - clip.frames[g][k]).norm() - (raw[f][i] - raw[g][k]).norm();
                    worst = worst.max(d.abs());
                }
            }
        }
        assert!(worst < 1e-15, "placement is not one rigid motion: {worst:e} m");
        // The x–y placement puts the chord along +e1 with z = 0.
        let xy = clip_from_angles(&rows, &KymogramParams { plane: ClipPlane::Xy, ..params }, "test".into());
        assert!(xy.frames[0][127].y.abs() < 1e-18 && xy.frames[0][127].x > 0.0);
        assert!(xy.frames.iter().flatten().all(|p| p.z == 0.0));
        for (a, b) in clip.frames.iter().flatten().zip(xy.frames.iter().flatten()) {
            assert_eq!((a.z, a.x), (b.x, b.y));
        }
    }

    #[test]
    fn stretch_and_tangent_diagnostics() {
        let straight: Vec<Vector3<f64>> = (0..5).map(|i| Vector3::new(0.0, 0.0, i as f64 * 0.25e-3)).collect();
        let bent: Vec<Vector3<f64>> = (0..5).map(|i| Vector3::new(0.0, i as f64 * 0.26e-3, 0.0)).collect();
        let clip = Clip { frames: vec![straight, bent], dt_s: 0.1, source: "test".into(), length_m: 1e-3 };
        assert!((clip.stretch(0) - 1.0).abs() < 1e-15);
        let (frame, dev) = clip.max_stretch_deviation();
        assert_eq!(frame, 1);
        assert!((dev - 0.04).abs() < 1e-12);
        assert_eq!(clip.frames_with_tangent_near(&Vector3::y(), 1e-3), vec![1]);
        assert_eq!(clip.frames_with_tangent_near(&Vector3::z(), 1e-3), vec![0]);
    }

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn kymogram_npy_reads_and_malformed_ones_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("k.npy");
        let rows = [wave(0.0), wave(0.7)];
        write_npy(&p, &[2, 24], &rows.concat()).unwrap();
        let clip = read_kymogram(&p, &KymogramParams::default()).unwrap();
        assert_eq!(clip, clip_from_angles(&rows, &KymogramParams::default(), clip.source.clone()));
        assert!(clip.source.contains("2 frames × 24 joint angles"), "{}", clip.source);
        let err = |shape: &[usize], data: &[f64]| {
            write_npy(&p, shape, data).unwrap();
            let e = read_kymogram(&p, &KymogramParams::default()).unwrap_err().to_string();
            assert!(e.contains("k.npy"), "{e}");
            e
        };
        let mut bad = rows.concat();
        bad[24 + 5] = f64::NAN;
        assert!(err(&[2, 24], &bad).contains("frame 1, joint 5: angle NaN is not finite"));
        bad[24 + 5] = f64::NEG_INFINITY;
        assert!(err(&[2, 24], &bad).contains("frame 1, joint 5: angle -inf"));
        assert!(err(&[2, 4, 6], &rows.concat()).contains("shape [2, 4, 6], expected 2 axes"));
        assert!(err(&[0, 24], &[]).contains("empty"));
        std::fs::write(&p, npy_bytes(&[2, 24], &rows.concat()).replace_f8_with(">f8")).unwrap();
        let e = read_kymogram(&p, &KymogramParams::default()).unwrap_err().to_string();
        assert!(e.contains("k.npy") && e.contains("dtype '>f8'"), "{e}");
        let full = npy_bytes(&[2, 24], &rows.concat());
        std::fs::write(&p, &full[..full.len() - 8]).unwrap();
        let e = read_kymogram(&p, &KymogramParams::default()).unwrap_err().to_string();
        assert!(e.contains("k.npy") && e.contains("truncated"), "{e}");
        let e = read_kymogram(&dir.path().join("missing.npy"), &KymogramParams::default()).unwrap_err();
        assert!(matches!(e, ClipError::Read { .. }), "{e}");
    }

    trait ReplaceDescr {
        fn replace_f8_with(self, descr: &str) -> Vec<u8>;
    }
    impl ReplaceDescr for Vec<u8> {
        fn replace_f8_with(mut self, descr: &str) -> Vec<u8> {
            let at = self.windows(3).position(|w| w == b"<f8").unwrap();
            self.splice(at..at + 3, descr.bytes());
            self
        }
    }

    fn csv_text(frames: &[Vec<Vector3<f64>>]) -> String {
        let mut s = RECORDING_HEADER.join(",") + "\n";
        for (f, pts) in frames.iter().enumerate() {
            for (i, p) in pts.iter().enumerate() {
                s += &format!("{f},{i},{:e},{:e},{:e}\n", p.x, p.y, p.z);
            }
        }
        s
    }

    fn sample_frames() -> Vec<Vec<Vector3<f64>>> {
        (0..3)
            .map(|f| (0..4).map(|i| Vector3::new(1e-5 * f as f64, 2e-5 * (i as f64).sin(), 3e-4 * i as f64)).collect())
            .collect()
    }

    #[test]
    fn recordings_read_from_csv_and_npy() {
        let dir = tempfile::tempdir().unwrap();
        let frames = sample_frames();
        let p = write(dir.path(), "rec.csv", &csv_text(&frames));
        let clip = read_recording(&p, 0.04).unwrap();
        assert_eq!(
            (clip.frames.clone(), clip.dt_s, clip.frame_count(), clip.node_count()),
            (frames.clone(), 0.04, 3, 4)
        );
        assert!((clip.length_m - polyline_length(&frames[0])).abs() == 0.0);
        // Rows in any order.
        let text = csv_text(&frames);
        let mut lines: Vec<&str> = text.lines().collect();
        lines[1..].reverse();
        let p = write(dir.path(), "rev.csv", &lines.join("\n"));
        assert_eq!(read_recording(&p, 0.04).unwrap().frames, frames);
        let p = dir.path().join("rec.npy");
        let flat: Vec<f64> = frames.iter().flatten().flat_map(|v| [v.x, v.y, v.z]).collect();
        write_npy(&p, &[3, 4, 3], &flat).unwrap();
        assert_eq!(read_recording(&p, 0.04).unwrap().frames, frames);
    }

    #[test]
    fn malformed_recordings_name_file_frame_node_and_row() {
        let dir = tempfile::tempdir().unwrap();
        let good = csv_text(&sample_frames());
        let check = |name: &str, text: &str, wanted: &str| {
            let p = write(dir.path(), name, text);
            let e = read_recording(&p, 0.04).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains(wanted), "expected `{wanted}` in: {e}");
        };
        let lines: Vec<&str> = good.lines().collect();
        // line k + 1 of the file is data row k; row 6 is frame 1, node 1.
        check("nan.csv", &good.replace("1,1,1e-5,", "1,1,NaN,"), "frame 1, node 1: x = NaN is not finite");
        check("inf.csv", &good.replacen(",0e0\n", ",inf\n", 1), "frame 0, node 0: z = inf is not finite");
        check("header.csv", &good.replace("x_m", "x"), "expected [\"frame\", \"node\", \"x_m\", \"y_m\", \"z_m\"]");
        check("missing.csv", &[&lines[..6], &lines[7..]].concat().join("\n"), "frame 1, node 1: no row");
        check(
            "dup.csv",
            &[&lines[..], &[lines[6]]].concat().join("\n"),
            "row 13: frame 1, node 1 already given in row 6",
        );
        check("count.csv", &[&lines[..], &["1,4,0,0,0"]].concat().join("\n"), "frame 1: 5 nodes, but frame 0 has 4");
        check("gap.csv", &good.replace("\n2,", "\n3,"), "frame 2, node 0: no row");
        check("few.csv", "frame,node,x_m,y_m,z_m\n0,0,0,0,0\n0,1,0,0,1\n", "2 nodes per frame, need at least 3");
        check("text.csv", &good.replace("\n1,2,", "\n1,two,"), "row 7: node `two` is not a non-negative integer");
        check("cols.csv", &good.replace("\n1,2,", "\n1,2,9,"), "row 7: ");
        check("empty.csv", "frame,node,x_m,y_m,z_m\n", "no data rows");
        check("rec.txt", &good, "unknown extension");
        let npy = |name: &str, shape: &[usize], data: &[f64], wanted: &str| {
            let p = dir.path().join(name);
            write_npy(&p, shape, data).unwrap();
            let e = read_recording(&p, 0.04).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains(wanted), "expected `{wanted}` in: {e}");
        };
        npy("two.npy", &[3, 4, 2], &[0.0; 24], "shape [3, 4, 2], expected frames × nodes × 3");
        npy("flat.npy", &[12, 3], &[0.0; 36], "expected frames × nodes × 3");
        npy("short.npy", &[3, 2, 3], &[0.0; 18], "need at least 1 frame and 3 nodes");
        let mut data = vec![0.0; 36];
        data[3 * 4 + 3 * 2 + 1] = f64::NAN;
        npy("nan.npy", &[3, 4, 3], &data, "frame 1, node 2: y = NaN is not finite");
        let p = dir.path().join("fortran.npy");
        let mut b = npy_bytes(&[3, 4, 3], &[0.0; 36]);
        let at = b.windows(5).position(|w| w == b"False").unwrap();
        b.splice(at..at + 5, b"True ".iter().copied());
        std::fs::write(&p, b).unwrap();
        let e = read_recording(&p, 0.04).unwrap_err().to_string();
        assert!(e.contains("fortran.npy") && e.contains("Fortran-order"), "{e}");
    }

    /// The real clips of `scripts/fetch_worm_data.sh`; skipped with a notice when absent.
    #[test]
    fn elegansbot_clips_load_when_fetched() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/elegansbot");
        if !dir.is_dir() {
            println!("SKIPPED: {} is absent (run scripts/fetch_worm_data.sh)", dir.display());
            return;
        }
        for (name, frames) in [("kymogram_omega-turn.npy", 600), ("kymogram_delta-turn.npy", 300)] {
            let path = dir.join(name);
            let raw = read_npy(&path).unwrap();
            assert_eq!(raw.shape, vec![frames, 24], "{name}");
            let max_angle = raw.data.iter().fold(0.0f64, |m, a| m.max(a.abs()));
            let clip = read_kymogram(&path, &KymogramParams::default()).unwrap();
            assert_eq!((clip.frame_count(), clip.node_count(), clip.dt_s), (frames, 128, 1.0 / 32.0));
            assert!(clip.frames.iter().flatten().all(|p| p.iter().all(|v| v.is_finite()) && p.y == 0.0));
            let (jf, jdev) = clip.max_stretch_deviation();
            let xz = clip.frames_with_tangent_near(&Vector3::y(), 1e-3).len();
            let xy =
                read_kymogram(&path, &KymogramParams { plane: ClipPlane::Xy, ..KymogramParams::default() }).unwrap();
            let xy_near = xy.frames_with_tangent_near(&Vector3::y(), 1e-3).len();
            // elegansbot's own orientation: head segment along +e1 in every frame, no rotation.
            let unrotated = Clip {
                frames: raw
                    .data
                    .chunks_exact(24)
                    .map(|a| Spline::through(&planar(&kymogram_joints(a, WORM_LENGTH_M))).resample_by_arc_length(128).0)
                    .collect(),
                ..clip.clone()
            };
            let unrotated_near = unrotated.frames_with_tangent_near(&Vector3::y(), 1e-3).len();
            // Frames whose continuous tangent passes through ±e2 somewhere: the x-component of
            // the segment tangents changes sign (x–y placements).
            let crossing = |c: &Clip| {
                c.frames.iter().filter(|f| f.windows(3).any(|w| (w[1].x - w[0].x) * (w[2].x - w[1].x) <= 0.0)).count()
            };
            println!(
                "{name}: frames whose tangent passes through ±e2: x–y chord along +e1 {}, x–y head along +e1 {}",
                crossing(&xy),
                crossing(&unrotated)
            );
            let kappa_max = clip.frames.iter().flat_map(|f| menger_curvature(f)).fold(0.0, f64::max);
            let scaled =
                read_kymogram(&path, &KymogramParams { scale_to_length: true, ..KymogramParams::default() }).unwrap();
            let (sf, sdev) = scaled.max_stretch_deviation();
            println!("{name}: scaled to the body length: max |j − 1| {sdev:.3e} (frame {sf})");
            assert!(sdev < 1e-3, "{name}: scaled max |j − 1| = {sdev}");
            println!(
                "{name}: {frames} × 24, max |a_j| {max_angle:.3} rad, max |j − 1| {jdev:.3e} (frame {jf}), max κ {kappa_max:.4e} 1/m; \
                 frames with a tangent within 1e-3 of ±e2: x–z {xz}, x–y chord along +e1 {xy_near}, x–y head along +e1 {unrotated_near}"
            );
            assert_eq!(xz, 0, "{name}: x–z placement keeps tangents off ±e2");
            assert!(jdev < 0.02, "{name}: max |j − 1| = {jdev}");
        }
    }
}
