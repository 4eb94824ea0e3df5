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
//! `engine::input::clip_files::read_recording`: CSV with header `frame,node,x_m,y_m,z_m` (0-based,
//! contiguous frames and nodes, rows in any order, every frame with the same node count ≥ 3)
//! or NPY of shape `frames × nodes × 3` [m]. Positions are used as given (no resampling, no
//! rigid motion). This module holds the clips and their geometry; the files are read in
//! `crate::engine::input`.
//!
//! ## Stretch
//! Remark 9 of [R1]: the data give the current arc length, so `j = ∂_s̃ s` is known. Per frame,
//! [`Clip::stretch`] is the polyline length of the nodes divided by [`Clip::length_m`].
use nalgebra::{Matrix3, Vector2, Vector3};

pub mod length;
pub mod missing;
pub mod recording;
mod spline;
pub mod synthetic;

pub use spline::Spline;

/// Body length of the kymogram clips, L [m].
pub const WORM_LENGTH_M: f64 = 1e-3;
/// Frame rate of the elegansbot kymograms [1/s] (`examples/example03.py`).
pub const KYMOGRAM_FPS: f64 = 32.0;
/// Nodes per frame in [R1] §6.
pub const PAPER_NODES: usize = 128;

/// Elements left out at each end by the measures of a clip run: the inner curvature errors
/// (`engine::metrics::INNER_SKIP_ELEMENTS`) and the ground-truth scores (`engine::clip::TRUTH_SKIP_NODES`
/// nodes); equal to both (tested in `engine::input::clip_files`).
pub const CLIP_SKIP_ELEMENTS: usize = 5;
/// Fewest elements of a clip case's mesh: the measures leave out [`CLIP_SKIP_ELEMENTS`] at
/// each end and must keep one, and the roughness (`engine::clip::sign_alternation`) of the data's
/// curvature at the `elements − 1` interior nodes needs 3 values. A smaller mesh would run and
/// write results without these measures.
pub const MIN_CLIP_ELEMENTS: usize = 2 * CLIP_SKIP_ELEMENTS + 1;
/// Most positions (frames × nodes) a clip may hold: 2²⁵ ≈ 3.4·10⁷ (768 MiB of positions). The
/// paper's clip is 1160 × 128 = 1.5·10⁵; an hour of a recording at 30 frames/s with 128 nodes
/// is 1.4·10⁷. A kymogram's frames and a synthetic clip's `clip_frames` are multiplied by the
/// mesh's node count before anything is allocated.
pub const MAX_CLIP_POSITIONS: usize = 1 << 25;
/// Largest deviation of a recorded frame's length from the rod length, `|L_frame / rod.length_m
/// − 1|`, accepted when a recording is loaded (kymograms are scaled to the rod length by design
/// and not checked). `L_frame` is the frame's length corrected for its own noise
/// ([`length::FrameLength`], docs/decisions.md D18): noise of σ per coordinate lengthens a
/// polyline of node spacing h by about 2σ²/h², 20 % for 10 µm at 33 nodes on 1 mm.
///
/// Measured, max over all frames of every clip case of `cases/` on its own mesh (`engine::input::clip_files`
/// test `length_ratios_of_the_clip_cases`, polyline lengths: these clips have no noise):
///
/// | clip | frames | max deviation | without `scale_to_length` |
/// |---|---|---|---|
/// | worm_omega_turn(_ld1) | 600 | 3.3e-4 | 8.2e-3 |
/// | worm_delta_turn(_ld1) | 300 | 3.6e-4 | 8.8e-3 |
/// | worm_roll_3d (synthetic, j = 1) | 1160 | 3.1e-4 | – |
/// | worm_2d_recording (1 µm of noise, 49 nodes; fully tracked frames) | 300 | 4.9e-3 | – |
///
/// and over the 400 frames of `cosserat synth --count 4 --frames 100 --seed 11` (1 mm body),
/// polyline → corrected:
///
/// | σ [µm] | 33 nodes | 128 nodes |
/// |---|---|---|
/// | 0 | 3.2e-3 → 5.7e-5 | 2.0e-4 → 1.7e-7 |
/// | 0.3 | 3.4e-3 → 1.8e-3 | 4.6e-3 → 2.1e-3 |
/// | 1 | 6.5e-3 → 6.8e-3 | 4.8e-2 → 1.5e-2 |
/// | 3 | 3.9e-2 → 2.1e-2 | 3.9e-1 → 2.0e-2 |
/// | 10 | 3.5e-1 → 4.9e-2 | 2.4 → 3.2e-2 |
///
/// The band is 10 %: 2× the largest corrected deviation measured (4.9 %, 10 µm of noise on 33
/// nodes, where one frame's length has a spread of 1.6 %: `clip::length` tests), far below the
/// errors it is there to name (a recording in mm read as m is 1000×, a wrong `rod.length_m`
/// 0.5× or 1.2×). It is not a convergence bound: frames 100–103 of the omega turn scaled by k
/// about the head converge for k = 1 … 1.2 with λd = 1 and Newton (`worm_omega_turn_ld1`), but
/// not for k = 0.95 or 1.05 with Table 1's λd = 1e2.
pub const MAX_LENGTH_DEVIATION: f64 = 0.10;

/// Errors of building, cutting and scoring clips (reading their files is `crate::engine::input`'s).
#[derive(Debug, thiserror::Error)]
pub enum ClipError {
    #[error("clip.frames = [{first}, {end}) but the clip has {frames} frames")]
    FrameRange { first: usize, end: usize, frames: usize },
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
    #[error(
        "clip.missing = \"nan\": none of the frames {first}–{} has {minimum} tracked nodes (a node is untracked where a coordinate is NaN); there is nothing to reconstruct",
        first + frames - 1
    )]
    NothingTracked { first: usize, frames: usize, minimum: usize },
    #[error("frame comparison: {what} has {len} nodes, truth has {expected}")]
    ComparisonSize { what: &'static str, len: usize, expected: usize },
    #[error("frame comparison: skipping {skip} nodes at each end of {nodes} leaves none")]
    ComparisonSkip { skip: usize, nodes: usize },
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
    /// which nodes were tracked, frames × nodes (`clip.missing = "nan"`, [`missing`]); `None`:
    /// every node of every frame. The untracked positions in `frames` are filled
    /// ([`missing::fill_missing`]).
    pub tracked: Option<Vec<Vec<bool>>>,
    /// what a recording says about itself: its first frame's number, its unit, its plane
    /// ([`recording`]); the default for kymograms and synthetic clips
    pub recording: recording::RecordingInfo,
}

impl Clip {
    /// A clip of `frames` [m] at `dt_s` [s] from `source`, of reference length `length_m` [m],
    /// every node tracked and nothing known of a recording (a kymogram, a synthetic clip).
    pub fn new(frames: Vec<Vec<Vector3<f64>>>, dt_s: f64, source: String, length_m: f64) -> Clip {
        Clip { frames, dt_s, source, length_m, tracked: None, recording: Default::default() }
    }

    /// Nodes per frame.
    pub fn node_count(&self) -> usize {
        self.frames.first().map_or(0, Vec::len)
    }

    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.frames.len()
    }

    /// The tracking weights `w_i` of frame `frame` ([`missing::tracking_weights`]); `None`
    /// where every node was tracked (w ≡ 1).
    pub fn tracking_weights(&self, frame: usize) -> Option<Vec<f64>> {
        self.tracked.as_ref().map(|t| missing::tracking_weights(&t[frame]))
    }

    /// Tracked nodes of frame `frame`.
    pub fn nodes_tracked(&self, frame: usize) -> usize {
        self.tracked.as_ref().map_or(self.node_count(), |t| t[frame].iter().filter(|x| **x).count())
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

    /// Keep the frames `[first, end)` (the case's `clip.frames`).
    pub fn select(&mut self, first: usize, end: usize) -> Result<(), ClipError> {
        check_frame_range(first, end, self.frame_count())?;
        self.frames = self.frames[first..end].to_vec();
        if let Some(t) = &mut self.tracked {
            *t = t[first..end].to_vec();
        }
        Ok(())
    }

    /// Rotate every frame rigidly by `r` (the case's `clip.orientation`).
    pub fn rotate(&mut self, r: &Matrix3<f64>) {
        for frame in &mut self.frames {
            rotate_frame(frame, r);
        }
        if let Some(n) = &mut self.recording.plane_normal {
            *n = r * *n;
        }
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

/// The frame range `[first, end)` of a clip of `frames` frames: non-empty and inside the clip.
pub fn check_frame_range(first: usize, end: usize, frames: usize) -> Result<(), ClipError> {
    if first >= end || end > frames {
        return Err(ClipError::FrameRange { first, end, frames });
    }
    Ok(())
}

/// Rotate the positions of one frame rigidly by `r` (as [`Clip::rotate`]).
pub fn rotate_frame(frame: &mut [Vector3<f64>], r: &Matrix3<f64>) {
    frame.iter_mut().for_each(|x| *x = r * *x);
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
        return Clip::new(Vec::new(), params.dt_s, source, params.length_m);
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
    // frames are independent: resampled in parallel, collected in order
    use rayon::prelude::*;
    let frames = joints
        .par_iter()
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
    Clip::new(frames, params.dt_s, source, params.length_m)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The elegansbot kymogram `file` of `scripts/fetch_worm_data.sh`, if it is there. A test
    /// that needs it fails without it, unless `COSSERAT_SKIP_WORM_DATA` is set (local work only;
    /// CI never sets it: a test that passes without its data would prove nothing), in which case
    /// it says so and is skipped (`None`). The integration tests' `common::worm_data_present`
    /// follows the same rule.
    pub(crate) fn worm_data(file: &str) -> Option<std::path::PathBuf> {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/elegansbot").join(file);
        if path.is_file() {
            return Some(path);
        }
        if std::env::var_os("COSSERAT_SKIP_WORM_DATA").is_none() {
            panic!("{} is missing: run scripts/fetch_worm_data.sh (or set COSSERAT_SKIP_WORM_DATA=1)", path.display());
        }
        eprintln!("SKIPPED (COSSERAT_SKIP_WORM_DATA is set): {} is missing", path.display());
        None
    }

    /// Discrete (Menger) curvature at the interior nodes [1/m].
    pub(crate) fn menger_curvature(p: &[Vector3<f64>]) -> Vec<f64> {
        p.windows(3)
            .map(|w| {
                let (a, b) = (w[1] - w[0], w[2] - w[1]);
                2.0 * a.cross(&b).norm() / (a.norm() * b.norm() * (a + b).norm())
            })
            .collect()
    }

    pub(crate) fn planar(joints: &[Vector2<f64>]) -> Vec<Vector3<f64>> {
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

    pub(crate) fn wave(phase: f64) -> Vec<f64> {
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
        let clip = Clip::new(vec![straight, bent], 0.1, "test".into(), 1e-3);
        assert!((clip.stretch(0) - 1.0).abs() < 1e-15);
        let (frame, dev) = clip.max_stretch_deviation();
        assert_eq!(frame, 1);
        assert!((dev - 0.04).abs() < 1e-12);
        assert_eq!(clip.frames_with_tangent_near(&Vector3::y(), 1e-3), vec![1]);
        assert_eq!(clip.frames_with_tangent_near(&Vector3::z(), 1e-3), vec![0]);
    }
}
