//! `worm_roll_3d`: a deterministic 3D ground-truth clip of the size of clip 1 in §6 of [R1]
//! (1160 frames × 128 nodes, Δt = 0.04 s, L = 1 mm), built from a lab kymogram, with known
//! frames `Q`, curvatures `κˡ` and roll angle, for scoring the inverse solver.
//!
//! ## Construction
//! 1. **Bending magnitude `k(s, t)` [1/m].** Kymogram joint `j = 0 … M−1` (`M = 24`) sits at
//!    `s_j = (j + 1) L/(M + 1)` and bends by `a_j` [rad], so `k(s_j) = a_j / (L/(M + 1))`. Along
//!    the body, `k` is the natural cubic spline through these values and `k = 0` at the head
//!    `s = 0` and tail `s = L` (free ends carry no moment, eq. (46) with the linear law (15)),
//!    on the uniform knots `s = i L/(M + 1)`, `i = 0 … M + 1`. In time, each `a_j` is the natural
//!    cubic spline through the kymogram rows (knots at the row indices), so clip frames that
//!    fall on a row reproduce it exactly.
//! 2. **Time mapping** ([`TimeMapping`]). The clip spans `T = (frames − 1) Δt` = 46.36 s. With
//!    [`TimeMapping::StretchOmega`] (default) the omega turn (600 rows, 18.7 s at 32 frames/s)
//!    is played once, slowed uniformly (×2.48) so that its first and last rows fall on the
//!    clip's first and last frames: clip frame `n` reads kymogram row
//!    `u_n = n (K − 1)/(frames − 1)`. [`TimeMapping::OmegaThenDelta`] does the same with the
//!    900 rows of the omega turn followed by the delta turn (the shapes jump between the last
//!    omega row and the first delta row; the time spline bridges the jump within one row
//!    interval; ×1.65 slower than the recording).
//! 3. **Rolling bending plane and twist.** Local curvature, eq. (28)'s `κˡ`:
//!
//!    ```text
//!    κˡ(s, t) = ( −k sin ψ(t),  k cos ψ(t),  τ ),     ψ(t) = ψ_tot (1 − cos(π t/T))/2
//!    ```
//!
//!    i.e. the bending vector `(0, k, 0)` rolled by `ψ` about `d3`. With `ψ = 0` the bending is
//!    about `d2`, which keeps `d2 = e2` and the curve in the x–z plane, like the placement of
//!    [`crate::clip::clip_from_angles`] (tangents away from `±e2`, where `det A = −cos β = 0`);
//!    `ψ_tot = π/2` ends with bending about `−d1`, in the y–z plane, where the tangent of a
//!    strongly bent worm passes through `±e2`. `ψ` has zero rate at both ends. `τ` [rad/m] is
//!    a constant twist.
//! 4. **Framed curve.** With the directors the rows of `Q` (eq. (2)), eq. (19) and eq. (4)
//!    give `κᵍ = ½ Σ d_i × ∂s d_i = Σ κˡ_k d_k`, `∂s d_i = κᵍ × d_i`, i.e.
//!    `∂s Q = −[κˡ]× Q`, and `∂s x = d3` (unshearable, inextensible, `j = 1`). At the head:
//!    `x = 0`, `Q = I` (the reference configuration `x0 = (0, 0, s)`), every frame. Each
//!    element `[s_i, s_{i+1}]`, `s_i = i L/(N − 1)`, is split into `substeps` steps of length
//!    `h` (a step that contains a knot of `k(s)` is split there, so that every piece sees one
//!    cubic: `k` is only C² across knots); each step (piece) is two half steps of the fourth-order Magnus method (two Gauss points,
//!    exact exponential by Rodrigues, so `Q` stays orthonormal to rounding):
//!
//!    ```text
//!    Q ← exp(−[ω]×) Q,   ω = (η/2)(κ_a + κ_b) + (√3/12) η² κ_a × κ_b,   η = h/2,
//!    κ_{a,b} = κˡ(s + (1/2 ∓ √3/6) η)
//!    ```
//!
//!    and `x` advances by Simpson's rule on the three `d3` of the step. Both are fourth order:
//!    the error falls 16× when `substeps` doubles (tested).
//!
//! ## Scoring
//! [`compare_frame`] measures a recovered frame against the truth ([`FrameComparison`]).
//!
//! ## References
//! [R1] of the crate docs: eqs. (1), (2), (4), (19), (28), (46); §6 for the clip size.
use std::f64::consts::PI;

use nalgebra::{Matrix3, Vector3};

use super::{Clip, ClipError, KYMOGRAM_FPS, PAPER_NODES, WORM_LENGTH_M};

mod compare;
mod field;
#[cfg(test)]
mod tests;

pub use compare::{compare_frame, FrameComparison, RecoveredFrame};
pub use field::{BendingProfile, KymogramField};

/// Frames of clip 1 in §6 of [R1].
pub const PAPER_FRAMES: usize = 1160;
/// Sampling interval of clip 1 in §6 of [R1] [s].
pub const PAPER_DT_S: f64 = 0.04;
/// A knot of `k(s)` closer than this fraction of a step to the step's ends does not split it.
const KNOT_TOL: f64 = 1e-9;
/// Below this rotation angle [rad] the Rodrigues coefficients use their Taylor series
/// (truncation error ~θ⁴/120 < 1e-18).
const SMALL_ANGLE_RAD: f64 = 1e-4;

/// Which kymogram rows the clip plays, and how clip time maps to them (module doc, step 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TimeMapping {
    /// The omega turn once, stretched uniformly over the clip.
    #[default]
    StretchOmega,
    /// The omega turn followed by the delta turn, stretched uniformly over the clip.
    OmegaThenDelta,
}

/// Parameters of [`roll_clip`]; `Default` is the §6 size with a quarter-turn roll.
#[derive(Debug, Clone, PartialEq)]
pub struct RollClipParams {
    /// Body length L [m].
    pub length_m: f64,
    /// Nodes per frame N (≥ 2), at `s_i = i L/(N − 1)`.
    pub nodes: usize,
    /// Number of frames (≥ 1).
    pub frames: usize,
    /// Time between frames Δt [s].
    pub dt_s: f64,
    /// Total roll `ψ_tot` of the bending plane over the clip [rad].
    pub roll_total_rad: f64,
    /// Constant twist `τ = κ3ˡ` [rad/m].
    pub twist_per_m: f64,
    /// Kymogram rows played and their timing.
    pub time_mapping: TimeMapping,
    /// Integration steps per element (≥ 1).
    pub substeps: usize,
}

impl Default for RollClipParams {
    fn default() -> Self {
        RollClipParams {
            length_m: WORM_LENGTH_M,
            nodes: PAPER_NODES,
            frames: PAPER_FRAMES,
            dt_s: PAPER_DT_S,
            roll_total_rad: PI / 2.0,
            // 0.5 rad per body length.
            twist_per_m: 0.5 / WORM_LENGTH_M,
            time_mapping: TimeMapping::StretchOmega,
            substeps: 8,
        }
    }
}

/// Ground truth of one frame, per node (head first).
#[derive(Debug, Clone, PartialEq)]
pub struct FrameTruth {
    /// Frame `Q` with rows `d1, d2, d3` (eq. (2)) per node.
    pub q: Vec<Matrix3<f64>>,
    /// Local curvature `κˡ` (eq. (28)) per node [1/m].
    pub kappa: Vec<Vector3<f64>>,
    /// Roll angle `ψ` of the bending plane [rad].
    pub roll_rad: f64,
}

impl FrameTruth {
    /// Rotate rigidly by `r` (as [`GroundTruth::rotate`]).
    pub fn rotate(&mut self, r: &Matrix3<f64>) {
        self.q.iter_mut().for_each(|q| *q *= r.transpose());
    }
}

/// Ground truth of a whole clip.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundTruth {
    /// One entry per clip frame.
    pub frames: Vec<FrameTruth>,
    /// Arc length of each node `s_i` [m].
    pub node_s_m: Vec<f64>,
}

impl GroundTruth {
    /// Keep the frames `[first, end)` (as [`Clip::select`] on the positions).
    pub fn select(&mut self, first: usize, end: usize) {
        self.frames = self.frames[first..end].to_vec();
    }

    /// Rotate rigidly by `r`, as [`Clip::rotate`] the positions: the directors rotate with the
    /// data, `Q → Q Rᵀ` (rows are the directors).
    pub fn rotate(&mut self, r: &Matrix3<f64>) {
        for f in &mut self.frames {
            f.rotate(r);
        }
    }

    /// Per frame, `max_i |d3(s_i) · axis|` (`axis` a unit vector). With `axis = e2` this
    /// measures how close the tangent gets to the singular set `β = ±π/2` of eq. (1).
    pub fn max_tangent_alignment(&self, axis: &Vector3<f64>) -> Vec<f64> {
        self.frames
            .iter()
            .map(|f| f.q.iter().map(|q| q.row(2).transpose().dot(axis).abs()).fold(0.0, f64::max))
            .collect()
    }
}

fn check_param(name: &'static str, value: f64, ok: bool, requirement: &'static str) -> Result<(), ClipError> {
    if ok {
        Ok(())
    } else {
        Err(ClipError::SyntheticParameter { name, value, requirement })
    }
}

impl RollClipParams {
    /// Every parameter in range, or the first one that is not.
    pub fn validate(&self) -> Result<(), ClipError> {
        check_param("length_m", self.length_m, self.length_m.is_finite() && self.length_m > 0.0, "finite and > 0")?;
        check_param("nodes", self.nodes as f64, self.nodes >= 2, ">= 2")?;
        check_param("frames", self.frames as f64, self.frames >= 1, ">= 1")?;
        check_param("dt_s", self.dt_s, self.dt_s.is_finite() && self.dt_s > 0.0, "finite and > 0")?;
        check_param("roll_total_rad", self.roll_total_rad, self.roll_total_rad.is_finite(), "finite")?;
        check_param("twist_per_m", self.twist_per_m, self.twist_per_m.is_finite(), "finite")?;
        check_param("substeps", self.substeps as f64, self.substeps >= 1, ">= 1")
    }

    /// Roll angle `ψ` of clip frame `n` [rad]: `ψ_tot (1 − cos(π n/(frames − 1)))/2`.
    pub fn roll_at_frame(&self, n: usize) -> f64 {
        if self.frames < 2 {
            return 0.0;
        }
        let u = n as f64 / (self.frames - 1) as f64;
        self.roll_total_rad * 0.5 * (1.0 - (PI * u).cos())
    }
}

/// `κˡ` [1/m] of the module doc, step 3.
/// (`roll` = `roll_rad.sin_cos()`, computed once per frame.)
fn local_curvature(k: f64, roll: (f64, f64), twist_per_m: f64) -> Vector3<f64> {
    let (s, c) = roll;
    Vector3::new(-k * s, k * c, twist_per_m)
}

/// `exp([v]×)` by Rodrigues' formula, with the Taylor series below [`SMALL_ANGLE_RAD`].
fn exp_so3(v: &Vector3<f64>) -> Matrix3<f64> {
    let theta2 = v.norm_squared();
    let (a, b) = if theta2 < SMALL_ANGLE_RAD * SMALL_ANGLE_RAD {
        (1.0 - theta2 / 6.0, 0.5 - theta2 / 24.0)
    } else {
        let theta = theta2.sqrt();
        (theta.sin() / theta, (1.0 - theta.cos()) / theta2)
    };
    let k = crate::model::rotation::skew(v);
    Matrix3::identity() + k * a + k * k * b
}

/// One fourth-order Magnus step of `∂s Q = −[κˡ]× Q` from `s` over `eta` [m] (module doc).
fn magnus_step(q: &Matrix3<f64>, kappa: &impl Fn(f64) -> Vector3<f64>, s: f64, eta: f64) -> Matrix3<f64> {
    let c = 3f64.sqrt() / 6.0;
    let (ka, kb) = (kappa(s + (0.5 - c) * eta), kappa(s + (0.5 + c) * eta));
    let omega = (ka + kb) * (eta / 2.0) + ka.cross(&kb) * (3f64.sqrt() / 12.0 * eta * eta);
    exp_so3(&-omega) * q
}

/// One frame: positions, `Q` and `κˡ` at the nodes for bending profile `profile`.
fn integrate_frame(
    profile: &BendingProfile,
    roll_rad: f64,
    params: &RollClipParams,
) -> (Vec<Vector3<f64>>, FrameTruth) {
    let n = params.nodes;
    let element = params.length_m / (n - 1) as f64;
    let h = element / params.substeps as f64;
    let roll = roll_rad.sin_cos();
    let kappa = |s: f64| local_curvature(profile.at(s), roll, params.twist_per_m);
    let d3 = |q: &Matrix3<f64>| -> Vector3<f64> { q.row(2).transpose() };
    let (mut x, mut q) = (Vector3::zeros(), Matrix3::identity());
    let mut xs = Vec::with_capacity(n);
    let mut qs = Vec::with_capacity(n);
    xs.push(x);
    qs.push(q);
    for i in 0..n - 1 {
        let s_i = i as f64 * element;
        for k in 0..params.substeps {
            let s = s_i + k as f64 * h;
            // Split the step at a knot of k(s) inside it, so each piece sees one cubic.
            let knot = ((s / profile.segment_m).floor() + 1.0) * profile.segment_m;
            let split = knot - s > KNOT_TOL * h && s + h - knot > KNOT_TOL * h;
            let pieces = if split { [(s, knot - s), (knot, s + h - knot)] } else { [(s, h), (s + h, 0.0)] };
            for (a, eta) in pieces.into_iter().filter(|p| p.1 > 0.0) {
                let q_mid = magnus_step(&q, &kappa, a, eta / 2.0);
                let q_end = magnus_step(&q_mid, &kappa, a + eta / 2.0, eta / 2.0);
                x += (d3(&q) + d3(&q_mid) * 4.0 + d3(&q_end)) * (eta / 6.0);
                q = q_end;
            }
        }
        xs.push(x);
        qs.push(q);
    }
    let kappas = (0..n).map(|i| kappa(i as f64 * element)).collect();
    (xs, FrameTruth { q: qs, kappa: kappas, roll_rad })
}

/// The `worm_roll_3d` clip and its ground truth (module doc). `omega_rows` (and `delta_rows`
/// for [`TimeMapping::OmegaThenDelta`]; ignored otherwise) are kymogram rows × joint angles
/// [rad], e.g. read by `crate::io::npy::read_npy` from `data/elegansbot/kymogram_*.npy`.
pub fn roll_clip(
    omega_rows: &[Vec<f64>],
    delta_rows: Option<&[Vec<f64>]>,
    params: &RollClipParams,
) -> Result<(Clip, GroundTruth), ClipError> {
    let generator = RollClipGenerator::new(omega_rows, delta_rows, params)?;
    // Frames are independent: integrated in parallel (rayon), collected in order, so the
    // result does not depend on the thread count.
    use rayon::prelude::*;
    let (positions, truth): (Vec<_>, Vec<_>) = (0..params.frames).into_par_iter().map(|n| generator.frame(n)).unzip();
    let clip = Clip { frames: positions, ..generator.header() };
    Ok((clip, GroundTruth { frames: truth, node_s_m: generator.node_s_m() }))
}

/// The frames of a `worm_roll_3d` clip one at a time, each exactly as [`roll_clip`] computes it:
/// for a consumer that solves the first frames while later ones are still being integrated.
pub struct RollClipGenerator {
    field: KymogramField,
    params: RollClipParams,
}

impl RollClipGenerator {
    /// The clip's kymogram field (as [`roll_clip`] takes its rows) and parameters.
    pub fn new(
        omega_rows: &[Vec<f64>],
        delta_rows: Option<&[Vec<f64>]>,
        params: &RollClipParams,
    ) -> Result<Self, ClipError> {
        Ok(RollClipGenerator { field: KymogramField::new(omega_rows, delta_rows, params)?, params: params.clone() })
    }

    /// Frames of the clip.
    pub fn frame_count(&self) -> usize {
        self.params.frames
    }

    /// Frame `n`: node positions [m] and its ground truth.
    pub fn frame(&self, n: usize) -> (Vec<Vector3<f64>>, FrameTruth) {
        let p = &self.params;
        integrate_frame(&self.field.profile(self.field.row_at_frame(n)), p.roll_at_frame(n), p)
    }

    /// The clip without its frames: time step, description and body length.
    pub fn header(&self) -> Clip {
        let params = &self.params;
        let clip_s = (params.frames.saturating_sub(1)) as f64 * params.dt_s;
        let kymo_s = (self.field.row_count() - 1) as f64 / KYMOGRAM_FPS;
        let source = format!(
            "synthetic worm_roll_3d: {:?}, {} kymogram rows over {clip_s} s (×{:.3} slower than {KYMOGRAM_FPS} frames/s), \
             roll 0 → {} rad, twist {} rad/m, {} frames × {} nodes, {} substeps per element",
            params.time_mapping,
            self.field.row_count(),
            clip_s / kymo_s,
            params.roll_total_rad,
            params.twist_per_m,
            params.frames,
            params.nodes,
            params.substeps
        );
        Clip::new(Vec::new(), params.dt_s, source, params.length_m)
    }

    /// Arc length of each node `s_i` [m] (as [`GroundTruth::node_s_m`]).
    pub fn node_s_m(&self) -> Vec<f64> {
        let p = &self.params;
        (0..p.nodes).map(|i| i as f64 * p.length_m / (p.nodes - 1) as f64).collect()
    }
}
