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

/// Ground truth of a whole clip.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundTruth {
    /// One entry per clip frame.
    pub frames: Vec<FrameTruth>,
    /// Arc length of each node `s_i` [m].
    pub node_s_m: Vec<f64>,
}

impl GroundTruth {
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

/// Second derivatives of the natural cubic spline through `y` on knots spaced `h` apart
/// (`M_0 = M_{n−1} = 0`, `M_{i−1} + 4 M_i + M_{i+1} = 6 (y_{i+1} − 2 y_i + y_{i−1})/h²`,
/// Thomas algorithm). `y.len() ≥ 2`.
fn natural_second_derivatives(y: &[f64], h: f64) -> Vec<f64> {
    let n = y.len();
    let mut m = vec![0.0; n];
    if n < 3 {
        return m;
    }
    // Forward elimination on the interior unknowns 1 … n−2 (diagonal 4, off-diagonals 1).
    let mut diag = vec![0.0; n];
    let mut rhs = vec![0.0; n];
    for i in 1..n - 1 {
        let r = 6.0 * (y[i + 1] - 2.0 * y[i] + y[i - 1]) / (h * h);
        if i == 1 {
            diag[i] = 4.0;
            rhs[i] = r;
        } else {
            let w = 1.0 / diag[i - 1];
            diag[i] = 4.0 - w;
            rhs[i] = r - w * rhs[i - 1];
        }
    }
    for i in (1..n - 1).rev() {
        m[i] = (rhs[i] - m[i + 1]) / diag[i];
    }
    m
}

/// Value at `x` (in knot units, `0 ≤ x ≤ n − 1`, clamped) of the cubic spline with values `y`,
/// second derivatives `m` and knot spacing `h`.
fn spline_value(y: &[f64], m: &[f64], h: f64, x: f64) -> f64 {
    let last = y.len() - 1;
    if last == 0 {
        return y[0];
    }
    let x = x.clamp(0.0, last as f64);
    let i = (x.floor() as usize).min(last - 1);
    let b = x - i as f64;
    let a = 1.0 - b;
    a * y[i] + b * y[i + 1] + ((a * a * a - a) * m[i] + (b * b * b - b) * m[i + 1]) * (h * h / 6.0)
}

/// The kymogram as a smooth field: joint angles in time, curvature along the body (module
/// doc, steps 1–2).
#[derive(Debug, Clone)]
pub struct KymogramField {
    /// Rows played (omega, then delta if mapped), rows × joints [rad].
    rows: Vec<Vec<f64>>,
    /// Time-spline second derivatives per row and joint [rad/row²].
    m_time: Vec<Vec<f64>>,
    length_m: f64,
    frames: usize,
}

/// Check one kymogram: at least 2 rows, every row of `expected` (or row 0's) length ≥ 1,
/// all finite.
fn check_rows(which: &'static str, rows: &[Vec<f64>], expected: Option<usize>) -> Result<(), ClipError> {
    if rows.len() < 2 {
        return Err(ClipError::SyntheticTooFewFrames { which, frames: rows.len(), minimum: 2 });
    }
    let joints = expected.unwrap_or(rows[0].len());
    if joints == 0 {
        return Err(ClipError::SyntheticNoJoints { which });
    }
    for (frame, row) in rows.iter().enumerate() {
        if row.len() != joints {
            return Err(ClipError::SyntheticRowLength { which, frame, joints: row.len(), expected: joints });
        }
        if let Some(joint) = row.iter().position(|a| !a.is_finite()) {
            return Err(ClipError::SyntheticNonFiniteAngle { which, frame, joint, value: row[joint] });
        }
    }
    Ok(())
}

impl KymogramField {
    /// Field from the omega rows (and the delta rows for [`TimeMapping::OmegaThenDelta`]);
    /// rows × joint angles [rad], at least 2 rows of equal length ≥ 1, finite.
    pub fn new(
        omega_rows: &[Vec<f64>],
        delta_rows: Option<&[Vec<f64>]>,
        params: &RollClipParams,
    ) -> Result<Self, ClipError> {
        params.validate()?;
        check_rows("omega", omega_rows, None)?;
        let mut rows = omega_rows.to_vec();
        if params.time_mapping == TimeMapping::OmegaThenDelta {
            let delta = delta_rows.ok_or(ClipError::SyntheticMissingDelta)?;
            check_rows("delta", delta, Some(omega_rows[0].len()))?;
            rows.extend_from_slice(delta);
        }
        let joints = rows[0].len();
        let mut m_time = vec![vec![0.0; joints]; rows.len()];
        for j in 0..joints {
            let column: Vec<f64> = rows.iter().map(|r| r[j]).collect();
            for (r, m) in natural_second_derivatives(&column, 1.0).into_iter().enumerate() {
                m_time[r][j] = m;
            }
        }
        Ok(KymogramField { rows, m_time, length_m: params.length_m, frames: params.frames })
    }

    /// Number of kymogram rows played.
    pub fn row_count(&self) -> usize {
        self.rows.len()
    }

    /// Kymogram position (fractional row index) read by clip frame `n`:
    /// `n (K − 1)/(frames − 1)`.
    pub fn row_at_frame(&self, n: usize) -> f64 {
        if self.frames < 2 {
            return 0.0;
        }
        (n * (self.rows.len() - 1)) as f64 / (self.frames - 1) as f64
    }

    /// Joint angles `a_j` [rad] at fractional row `u` (time spline; exact at integer `u`).
    pub fn joint_angles(&self, u: f64) -> Vec<f64> {
        let joints = self.rows[0].len();
        let last = self.rows.len() - 1;
        let u = u.clamp(0.0, last as f64);
        let i = (u.floor() as usize).min(last - 1);
        let b = u - i as f64;
        let a = 1.0 - b;
        (0..joints)
            .map(|j| {
                let (y0, y1, m0, m1) = (self.rows[i][j], self.rows[i + 1][j], self.m_time[i][j], self.m_time[i + 1][j]);
                a * y0 + b * y1 + ((a * a * a - a) * m0 + (b * b * b - b) * m1) / 6.0
            })
            .collect()
    }

    /// Bending profile `k(s)` at fractional row `u` (module doc, step 1).
    pub fn profile(&self, u: f64) -> BendingProfile {
        let angles = self.joint_angles(u);
        let segment = self.length_m / (angles.len() + 1) as f64;
        let mut k = Vec::with_capacity(angles.len() + 2);
        k.push(0.0);
        k.extend(angles.iter().map(|a| a / segment));
        k.push(0.0);
        let m = natural_second_derivatives(&k, segment);
        BendingProfile { k, m, segment_m: segment }
    }
}

/// Bending magnitude `k(s)` [1/m] of one instant: natural cubic spline on uniform knots.
#[derive(Debug, Clone)]
pub struct BendingProfile {
    /// Knot values [1/m] at `s = i · segment_m`.
    k: Vec<f64>,
    /// Second derivatives [1/m³].
    m: Vec<f64>,
    segment_m: f64,
}

impl BendingProfile {
    /// `k(s)` [1/m] at arc length `s` [m] (clamped to the body).
    pub fn at(&self, s_m: f64) -> f64 {
        spline_value(&self.k, &self.m, self.segment_m, s_m / self.segment_m)
    }

    /// `∫₀ᴸ k ds` [rad], exact for the spline: `Σ h (k_i + k_{i+1})/2 − h³ (M_i + M_{i+1})/24`.
    pub fn integral(&self) -> f64 {
        let h = self.segment_m;
        self.k
            .windows(2)
            .zip(self.m.windows(2))
            .map(|(k, m)| h * (k[0] + k[1]) / 2.0 - h * h * h * (m[0] + m[1]) / 24.0)
            .sum()
    }
}

/// `κˡ` [1/m] of the module doc, step 3.
fn local_curvature(k: f64, roll_rad: f64, twist_per_m: f64) -> Vector3<f64> {
    let (s, c) = roll_rad.sin_cos();
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
    let k = crate::rotation::skew(v);
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
    let kappa = |s: f64| local_curvature(profile.at(s), roll_rad, params.twist_per_m);
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
/// [rad], e.g. from [`crate::clip::read_npy`] of `data/elegansbot/kymogram_*.npy`.
pub fn roll_clip(
    omega_rows: &[Vec<f64>],
    delta_rows: Option<&[Vec<f64>]>,
    params: &RollClipParams,
) -> Result<(Clip, GroundTruth), ClipError> {
    let field = KymogramField::new(omega_rows, delta_rows, params)?;
    // Frames are independent: integrated in parallel (rayon), collected in order, so the
    // result does not depend on the thread count.
    use rayon::prelude::*;
    let (positions, truth): (Vec<_>, Vec<_>) = (0..params.frames)
        .into_par_iter()
        .map(|n| integrate_frame(&field.profile(field.row_at_frame(n)), params.roll_at_frame(n), params))
        .unzip();
    let clip_s = (params.frames.saturating_sub(1)) as f64 * params.dt_s;
    let kymo_s = (field.row_count() - 1) as f64 / KYMOGRAM_FPS;
    let source = format!(
        "synthetic worm_roll_3d: {:?}, {} kymogram rows over {clip_s} s (×{:.3} slower than {KYMOGRAM_FPS} frames/s), \
         roll 0 → {} rad, twist {} rad/m, {} frames × {} nodes, {} substeps per element",
        params.time_mapping,
        field.row_count(),
        clip_s / kymo_s,
        params.roll_total_rad,
        params.twist_per_m,
        params.frames,
        params.nodes,
        params.substeps
    );
    let node_s_m = (0..params.nodes).map(|i| i as f64 * params.length_m / (params.nodes - 1) as f64).collect();
    let clip = Clip { frames: positions, dt_s: params.dt_s, source, length_m: params.length_m };
    Ok((clip, GroundTruth { frames: truth, node_s_m }))
}

/// A recovered frame, per node (head first), as the inverse solver returns it.
#[derive(Debug, Clone, Copy)]
pub struct RecoveredFrame<'a> {
    /// Positions [m].
    pub x: &'a [Vector3<f64>],
    /// Frames `Q` (rows `d1, d2, d3`).
    pub q: &'a [Matrix3<f64>],
    /// Local curvature `κˡ` [1/m].
    pub kappa: &'a [Vector3<f64>],
}

/// Errors of a recovered frame against the truth ([`compare_frame`]). Relative errors are
/// NaN when the truth's norm is zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameComparison {
    /// `‖x − x_true‖ / ‖x_true‖` over all nodes (discrete L2) [–].
    pub position_rel_l2: f64,
    /// `‖b − b_true‖ / ‖b_true‖`, `b = κ1² + κ2²` (roll-invariant bending), over the nodes
    /// kept [–].
    pub bending_rel_l2: f64,
    /// `max_i ∠(d3, d3_true)` over all nodes [rad].
    pub max_tangent_angle_rad: f64,
    /// Mean of the recovered `κ3` over the nodes kept [rad/m].
    pub twist_mean_per_m: f64,
    /// RMS of `κ3 − κ3_true` over the nodes kept [rad/m].
    pub twist_rms_error_per_m: f64,
    /// Circular mean over all nodes of the angle from `d1_true` to `d1` about `d3_true`,
    /// in (−π, π] [rad]. A rigid roll of the recovered frames about their tangents by `φ`
    /// gives `φ`.
    pub roll_offset_rad: f64,
}

fn check_len(what: &'static str, len: usize, expected: usize) -> Result<(), ClipError> {
    if len == expected {
        Ok(())
    } else {
        Err(ClipError::ComparisonSize { what, len, expected })
    }
}

/// Compare a recovered frame with the truth: `truth_x` are the clip positions of the frame [m],
/// `truth` its [`FrameTruth`]; the bending and twist errors skip `skip_end_nodes` nodes at
/// each end (the curvature of the inverse solution is least reliable there).
pub fn compare_frame(
    truth_x: &[Vector3<f64>],
    truth: &FrameTruth,
    recovered: &RecoveredFrame<'_>,
    skip_end_nodes: usize,
) -> Result<FrameComparison, ClipError> {
    let n = truth_x.len();
    check_len("truth q", truth.q.len(), n)?;
    check_len("truth kappa", truth.kappa.len(), n)?;
    check_len("recovered x", recovered.x.len(), n)?;
    check_len("recovered q", recovered.q.len(), n)?;
    check_len("recovered kappa", recovered.kappa.len(), n)?;
    if n == 0 || 2 * skip_end_nodes >= n {
        return Err(ClipError::ComparisonSkip { skip: skip_end_nodes, nodes: n });
    }
    let rel = |num: f64, den: f64| if den > 0.0 { (num / den).sqrt() } else { f64::NAN };
    let (mut dx, mut xx) = (0.0, 0.0);
    for (a, b) in recovered.x.iter().zip(truth_x) {
        dx += (a - b).norm_squared();
        xx += b.norm_squared();
    }
    let kept = skip_end_nodes..n - skip_end_nodes;
    let bend = |k: &Vector3<f64>| k.x * k.x + k.y * k.y;
    let (mut db, mut bb, mut t_sum, mut t_err) = (0.0, 0.0, 0.0, 0.0);
    for i in kept.clone() {
        let (r, t) = (&recovered.kappa[i], &truth.kappa[i]);
        db += (bend(r) - bend(t)).powi(2);
        bb += bend(t).powi(2);
        t_sum += r.z;
        t_err += (r.z - t.z).powi(2);
    }
    let count = kept.len() as f64;
    let (mut max_angle, mut sin_sum, mut cos_sum) = (0.0f64, 0.0, 0.0);
    for (qr, qt) in recovered.q.iter().zip(&truth.q) {
        let (d1r, d3r): (Vector3<f64>, Vector3<f64>) = (qr.row(0).transpose(), qr.row(2).transpose());
        let (d1t, d3t): (Vector3<f64>, Vector3<f64>) = (qt.row(0).transpose(), qt.row(2).transpose());
        max_angle = max_angle.max(d3r.cross(&d3t).norm().atan2(d3r.dot(&d3t)));
        let phi = d1t.cross(&d1r).dot(&d3t).atan2(d1t.dot(&d1r));
        sin_sum += phi.sin();
        cos_sum += phi.cos();
    }
    let mut roll = sin_sum.atan2(cos_sum);
    if roll <= -PI {
        roll = PI;
    }
    Ok(FrameComparison {
        position_rel_l2: rel(dx, xx),
        bending_rel_l2: rel(db, bb),
        max_tangent_angle_rad: max_angle,
        twist_mean_per_m: t_sum / count,
        twist_rms_error_per_m: (t_err / count).sqrt(),
        roll_offset_rad: roll,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// Synthetic kymogram: a travelling bending wave with a slowly growing offset, `rows × 24`.
    fn wave_rows(rows: usize) -> Vec<Vec<f64>> {
        (0..rows)
            .map(|n| {
                let t = n as f64 / rows as f64;
                (0..24).map(|j| 0.05 + 0.1 * t + 0.3 * (2.0 * PI * (j as f64 / 24.0 - 2.0 * t)).sin()).collect()
            })
            .collect()
    }

    fn small(frames: usize) -> RollClipParams {
        RollClipParams { frames, ..RollClipParams::default() }
    }

    fn row(q: &Matrix3<f64>, i: usize) -> Vector3<f64> {
        q.row(i).transpose()
    }

    #[test]
    fn frames_are_orthonormal_and_proper() {
        let (clip, truth) = roll_clip(&wave_rows(40), None, &small(9)).unwrap();
        assert_eq!((clip.frame_count(), clip.node_count(), truth.frames.len()), (9, 128, 9));
        let mut worst: f64 = 0.0;
        for q in truth.frames.iter().flat_map(|f| &f.q) {
            worst = worst.max((q * q.transpose() - Matrix3::identity()).amax()).max((q.determinant() - 1.0).abs());
        }
        println!("max |QQᵀ − I|, |det Q − 1|: {worst:.2e}");
        assert!(worst < 1e-13, "{worst:e}");
        assert!(clip.frames.iter().all(|f| f[0] == Vector3::zeros()));
        assert!(truth.frames.iter().all(|f| f.q[0] == Matrix3::identity()));
    }

    /// `∂s x = d3` and `κˡ = Q κᵍ`, `κᵍ = ½ Σ d_i × ∂s d_i` (eqs. (19), (4)) by central
    /// differences on a fine node grid reproduce the prescribed field.
    #[test]
    fn finite_differences_of_the_frames_give_the_prescribed_curvature() {
        let nodes = 2001;
        let params = RollClipParams {
            nodes,
            frames: 3,
            substeps: 2,
            roll_total_rad: 1.1,
            twist_per_m: 700.0,
            ..RollClipParams::default()
        };
        let (clip, truth) = roll_clip(&wave_rows(30), None, &params).unwrap();
        let h = params.length_m / (nodes - 1) as f64;
        let (mut tangent_err, mut kappa_err, mut kappa_max): (f64, f64, f64) = (0.0, 0.0, 0.0);
        for (x, t) in clip.frames.iter().zip(&truth.frames) {
            for i in 1..nodes - 1 {
                let dx = (x[i + 1] - x[i - 1]) / (2.0 * h);
                tangent_err = tangent_err.max((dx - row(&t.q[i], 2)).norm());
                let dq = (t.q[i + 1] - t.q[i - 1]) / (2.0 * h);
                let kappa_g: Vector3<f64> = (0..3).map(|k| row(&t.q[i], k).cross(&row(&dq, k)) * 0.5).sum();
                let kappa_l = t.q[i] * kappa_g;
                kappa_err = kappa_err.max((kappa_l - t.kappa[i]).amax());
                kappa_max = kappa_max.max(t.kappa[i].amax());
            }
        }
        println!(
            "FD: max |∂s x − d3| {tangent_err:.2e}, max |κˡ_FD − κˡ| {kappa_err:.2e} 1/m of max {kappa_max:.1} 1/m"
        );
        // Central differences are second order: error ~ h² (κ² + κ'') / 6 ≈ 1e-6 here.
        assert!(tangent_err < 1e-5, "{tangent_err:e}");
        assert!(kappa_err < 1e-4 * kappa_max, "{kappa_err:e}");
    }

    /// Fourth order: errors against a 64-substep reference fall ~16× per doubling.
    #[test]
    fn integration_converges_at_fourth_order() {
        let rows = wave_rows(20);
        let run = |substeps| {
            roll_clip(
                &rows,
                None,
                &RollClipParams { frames: 3, substeps, roll_total_rad: 1.0, ..RollClipParams::default() },
            )
            .unwrap()
        };
        let (reference, reference_truth) = run(64);
        let err = |substeps| {
            let (clip, truth) = run(substeps);
            let ex = clip
                .frames
                .iter()
                .flatten()
                .zip(reference.frames.iter().flatten())
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max);
            let eq = truth
                .frames
                .iter()
                .flat_map(|f| &f.q)
                .zip(reference_truth.frames.iter().flat_map(|f| &f.q))
                .map(|(a, b)| (a - b).amax())
                .fold(0.0, f64::max);
            (ex / WORM_LENGTH_M, eq)
        };
        let e: Vec<(f64, f64)> = [1, 2, 4, 8].into_iter().map(err).collect();
        for (k, ((x0, q0), (x1, q1))) in e.iter().zip(&e[1..]).enumerate() {
            println!("substeps {} → {}: max |Δx|/L {x0:.2e} → {x1:.2e} (ratio {:.2}), max |ΔQ| {q0:.2e} → {q1:.2e} (ratio {:.2})", 1 << k, 2 << k, x0 / x1, q0 / q1);
            assert!((12.0..20.0).contains(&(x0 / x1)), "position ratio {}", x0 / x1);
            assert!((12.0..20.0).contains(&(q0 / q1)), "frame ratio {}", q0 / q1);
        }
        let default = err(RollClipParams::default().substeps);
        println!(
            "default substeps {}: max |Δx|/L {:.2e}, max |ΔQ| {:.2e}",
            RollClipParams::default().substeps,
            default.0,
            default.1
        );
        assert!(default.0 < 1e-10 && default.1 < 1e-9, "{default:?}");
    }

    /// ψ = 0, τ = 0: bending about d2 only, so y ≡ 0 and d2 ≡ e2; the tangent's turning angle
    /// is `∫ k ds` (at the knots, every 5th node with 126 nodes).
    #[test]
    fn planar_case_lies_in_the_xz_plane_and_turns_by_the_integral_of_k() {
        let params = RollClipParams {
            nodes: 126,
            frames: 4,
            roll_total_rad: 0.0,
            twist_per_m: 0.0,
            ..RollClipParams::default()
        };
        let rows = wave_rows(12);
        let (clip, truth) = roll_clip(&rows, None, &params).unwrap();
        let field = KymogramField::new(&rows, None, &params).unwrap();
        let mut worst: f64 = 0.0;
        for (n, (x, t)) in clip.frames.iter().zip(&truth.frames).enumerate() {
            assert!(x.iter().all(|p| p.y == 0.0), "frame {n}: y ≠ 0");
            assert!(t.q.iter().all(|q| row(q, 1) == Vector3::y()), "frame {n}: d2 ≠ e2");
            let profile = field.profile(field.row_at_frame(n));
            // Unwrapped tangent angle from +e3 towards +e1.
            let (mut theta, mut prev) = (0.0, Vector3::z());
            for (i, q) in t.q.iter().enumerate() {
                let d3 = row(q, 2);
                theta += prev.cross(&d3).y.atan2(prev.dot(&d3));
                prev = d3;
                if i % 5 == 0 {
                    let knot = BendingProfile {
                        k: profile.k[..=i / 5].to_vec(),
                        m: profile.m[..=i / 5].to_vec(),
                        segment_m: profile.segment_m,
                    };
                    worst = worst.max((theta - knot.integral()).abs());
                }
            }
            assert!((theta - profile.integral()).abs() < 1e-11, "frame {n}: {theta} vs {}", profile.integral());
        }
        println!("planar: max |θ(s_knot) − ∫k ds| {worst:.2e} rad");
        assert!(worst < 1e-11, "{worst:e}");
        // Rolled by π/2 (bending about −d1): the last frame lies in the y–z plane, d1 = e1.
        let rolled = RollClipParams { roll_total_rad: PI / 2.0, ..params };
        let (clip, truth) = roll_clip(&rows, None, &rolled).unwrap();
        let last = clip.frames.len() - 1;
        let off_plane = clip.frames[last].iter().map(|p| p.x.abs()).fold(0.0, f64::max);
        assert!(off_plane < 1e-15 * rolled.length_m, "{off_plane:e}");
        assert!(truth.frames[last].q.iter().all(|q| (row(q, 0) - Vector3::x()).amax() < 1e-14));
        assert!(clip.frames[last].iter().any(|p| p.y.abs() > 0.1 * rolled.length_m), "bent in y");
    }

    /// Clip frames that fall on kymogram rows reproduce them; joints carry `a_j (M + 1)/L`.
    #[test]
    fn time_and_space_splines_interpolate_the_kymogram() {
        let rows = wave_rows(25);
        let params = small(2 * 25 - 1);
        let field = KymogramField::new(&rows, None, &params).unwrap();
        let segment = params.length_m / 25.0;
        let mut worst: f64 = 0.0;
        for (r, row) in rows.iter().enumerate() {
            assert_eq!(field.row_at_frame(2 * r), r as f64);
            let angles = field.joint_angles(field.row_at_frame(2 * r));
            let profile = field.profile(r as f64);
            for j in 0..24 {
                worst = worst
                    .max((angles[j] - row[j]).abs())
                    .max((profile.at((j + 1) as f64 * segment) * segment - row[j]).abs());
            }
            assert_eq!((profile.at(0.0), profile.at(params.length_m)), (0.0, 0.0), "k = 0 at head and tail");
        }
        assert!(worst < 1e-13, "{worst:e}");
        // Between rows the spline is smooth: the half-row value is near the linear mean.
        let mid = field.joint_angles(10.5);
        assert!((mid[3] - 0.5 * (rows[10][3] + rows[11][3])).abs() < 0.01);
        // Omega then delta plays both, stretched together.
        let both = KymogramField::new(
            &rows,
            Some(&wave_rows(7)),
            &RollClipParams { time_mapping: TimeMapping::OmegaThenDelta, ..small(32) },
        )
        .unwrap();
        assert_eq!(both.row_count(), 32);
        assert_eq!(both.joint_angles(both.row_at_frame(31)), wave_rows(7)[6]);
        // Roll: 0 at the start, ψ_tot at the end, zero rate at both ends.
        let p = small(101);
        assert_eq!(p.roll_at_frame(0), 0.0);
        assert!((p.roll_at_frame(100) - PI / 2.0).abs() < 1e-15);
        assert!(p.roll_at_frame(1) < 1e-3 && (p.roll_at_frame(50) - PI / 4.0).abs() < 1e-15);
    }

    #[test]
    fn output_is_deterministic() {
        let rows = wave_rows(15);
        let params = small(5);
        let (c1, t1) = roll_clip(&rows, None, &params).unwrap();
        let (c2, t2) = roll_clip(&rows, None, &params).unwrap();
        let bits = |c: &Clip| {
            c.frames
                .iter()
                .flatten()
                .flat_map(|p| p.iter().map(|v| v.to_bits()).collect::<Vec<_>>())
                .collect::<Vec<u64>>()
        };
        let qbits = |t: &GroundTruth| {
            t.frames
                .iter()
                .flat_map(|f| f.q.iter())
                .flat_map(|q| q.iter().map(|v| v.to_bits()).collect::<Vec<_>>())
                .collect::<Vec<u64>>()
        };
        assert_eq!(bits(&c1), bits(&c2));
        assert_eq!(qbits(&t1), qbits(&t2));
        assert_eq!((c1, t1), (c2, t2));
    }

    #[test]
    fn bad_input_gives_clear_errors() {
        let rows = wave_rows(10);
        let e = |r: Result<(Clip, GroundTruth), ClipError>| r.unwrap_err().to_string();
        let p = small(3);
        assert!(e(roll_clip(&[], None, &p)).contains("omega has 0 frames, need at least 2"));
        assert!(e(roll_clip(&rows[..1], None, &p)).contains("omega has 1 frames"));
        assert!(e(roll_clip(&[vec![], vec![]], None, &p)).contains("frame 0: 0 joint angles"));
        let mut ragged = rows.clone();
        ragged[4].pop();
        assert!(e(roll_clip(&ragged, None, &p)).contains("omega, frame 4: 23 joint angles, but frame 0 has 24"));
        let mut nan = rows.clone();
        nan[6][2] = f64::NAN;
        assert!(e(roll_clip(&nan, None, &p)).contains("omega, frame 6, joint 2: angle NaN is not finite"));
        let both = RollClipParams { time_mapping: TimeMapping::OmegaThenDelta, ..p.clone() };
        assert!(e(roll_clip(&rows, None, &both)).contains("needs the delta-turn kymogram"));
        let short: Vec<Vec<f64>> = rows.iter().map(|r| r[..20].to_vec()).collect();
        assert!(
            e(roll_clip(&rows, Some(&short), &both)).contains("delta, frame 0: 20 joint angles, but frame 0 has 24")
        );
        // Delta rows are ignored by the omega-only mapping.
        assert!(roll_clip(&rows, Some(&short), &p).is_ok());
        for (params, name) in [
            (RollClipParams { length_m: 0.0, ..p.clone() }, "length_m = 0"),
            (RollClipParams { length_m: f64::NAN, ..p.clone() }, "length_m = NaN"),
            (RollClipParams { nodes: 1, ..p.clone() }, "nodes = 1"),
            (RollClipParams { frames: 0, ..p.clone() }, "frames = 0"),
            (RollClipParams { dt_s: -0.04, ..p.clone() }, "dt_s = -0.04"),
            (RollClipParams { roll_total_rad: f64::INFINITY, ..p.clone() }, "roll_total_rad = inf"),
            (RollClipParams { twist_per_m: f64::NAN, ..p.clone() }, "twist_per_m = NaN"),
            (RollClipParams { substeps: 0, ..p.clone() }, "substeps = 0"),
        ] {
            let msg = e(roll_clip(&rows, None, &params));
            assert!(msg.contains(name), "expected `{name}` in: {msg}");
        }
        // One frame is allowed: the first kymogram row, no roll.
        let (clip, truth) = roll_clip(&rows, None, &small(1)).unwrap();
        assert_eq!((clip.frame_count(), truth.frames[0].roll_rad), (1, 0.0));
    }

    #[test]
    fn comparison_of_the_truth_with_itself_and_with_a_rolled_copy() {
        let (clip, truth) = roll_clip(&wave_rows(10), None, &small(3)).unwrap();
        let (x, t) = (&clip.frames[1], &truth.frames[1]);
        let same = compare_frame(x, t, &RecoveredFrame { x, q: &t.q, kappa: &t.kappa }, 3).unwrap();
        assert_eq!(
            (same.position_rel_l2, same.bending_rel_l2, same.max_tangent_angle_rad, same.roll_offset_rad),
            (0.0, 0.0, 0.0, 0.0)
        );
        assert_eq!(same.twist_rms_error_per_m, 0.0);
        assert!((same.twist_mean_per_m - 500.0).abs() < 1e-9);
        // Roll every frame by φ about its own d3: rows d1, d2 rotate, κˡ rotates about e3.
        for phi in [0.3, -2.0, PI] {
            let r = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), phi).into_inner();
            let q: Vec<Matrix3<f64>> = t.q.iter().map(|q| r.transpose() * q).collect();
            assert!((row(&q[5], 0) - (row(&t.q[5], 0) * phi.cos() + row(&t.q[5], 1) * phi.sin())).amax() < 1e-15);
            let kappa: Vec<Vector3<f64>> = t.kappa.iter().map(|k| r.transpose() * k).collect();
            let c = compare_frame(x, t, &RecoveredFrame { x, q: &q, kappa: &kappa }, 0).unwrap();
            assert!((c.roll_offset_rad - phi).abs() < 1e-12, "φ = {phi}: {}", c.roll_offset_rad);
            assert!(c.max_tangent_angle_rad < 1e-15 && c.bending_rel_l2 < 1e-14, "{c:?}");
        }
        // Shifted positions, tilted tangents, doubled twist.
        let shifted: Vec<Vector3<f64>> = x.iter().map(|p| p * 1.01).collect();
        let tilt = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), 0.1).into_inner();
        let q: Vec<Matrix3<f64>> = t.q.iter().map(|q| q * tilt).collect();
        let kappa: Vec<Vector3<f64>> = t.kappa.iter().map(|k| Vector3::new(k.x * 2.0, k.y * 2.0, 2.0 * k.z)).collect();
        let c = compare_frame(x, t, &RecoveredFrame { x: &shifted, q: &q, kappa: &kappa }, 2).unwrap();
        assert!((c.position_rel_l2 - 0.01).abs() < 1e-12);
        assert!((c.bending_rel_l2 - 3.0).abs() < 1e-12, "b → 4b");
        assert!((c.max_tangent_angle_rad - 0.1).abs() < 1e-12);
        assert!((c.twist_mean_per_m - 1000.0).abs() < 1e-9 && (c.twist_rms_error_per_m - 500.0).abs() < 1e-9);
        // Size mismatches and too many skipped nodes are errors.
        let e =
            compare_frame(x, t, &RecoveredFrame { x: &x[1..], q: &t.q, kappa: &t.kappa }, 0).unwrap_err().to_string();
        assert!(e.contains("recovered x has 127 nodes, truth has 128"), "{e}");
        let e = compare_frame(x, t, &RecoveredFrame { x, q: &t.q, kappa: &t.kappa }, 64).unwrap_err().to_string();
        assert!(e.contains("skipping 64 nodes at each end of 128"), "{e}");
    }

    /// The default clip from the real omega turn; skipped with a notice when absent.
    #[test]
    fn default_clip_from_the_omega_turn() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/elegansbot");
        let omega_path = dir.join("kymogram_omega-turn.npy");
        if !omega_path.is_file() {
            println!("SKIPPED: {} is absent (run scripts/fetch_worm_data.sh)", omega_path.display());
            return;
        }
        let to_rows = |p: &Path| {
            let a = crate::clip::read_npy(p).unwrap();
            a.data.chunks_exact(a.shape[1]).map(<[f64]>::to_vec).collect::<Vec<_>>()
        };
        let omega = to_rows(&omega_path);
        let delta = to_rows(&dir.join("kymogram_delta-turn.npy"));
        for mapping in [TimeMapping::StretchOmega, TimeMapping::OmegaThenDelta] {
            let params = RollClipParams { time_mapping: mapping, ..RollClipParams::default() };
            let start = std::time::Instant::now();
            let (clip, truth) = roll_clip(&omega, Some(&delta), &params).unwrap();
            let wall = start.elapsed().as_secs_f64();
            assert_eq!((clip.frame_count(), clip.node_count(), clip.dt_s), (1160, 128, 0.04));
            let align = truth.max_tangent_alignment(&Vector3::y());
            let max_align = align.iter().cloned().fold(0.0, f64::max);
            let near = align.iter().filter(|&&a| a > 0.99).count();
            let first_near = align.iter().position(|&a| a > 0.99);
            let kmax = truth.frames.iter().flat_map(|f| &f.kappa).map(|k| k.x.hypot(k.y)).fold(0.0, f64::max);
            let (jf, jdev) = clip.max_stretch_deviation();
            println!(
                "{mapping:?}: {wall:.3} s; max |d3·e2| {max_align:.6}; frames with |d3·e2| > 0.99: {near}/1160 ({:.1} %), first {first_near:?}; \
                 max bending {kmax:.0} 1/m; max |j − 1| {jdev:.2e} (frame {jf})\n  {}",
                100.0 * near as f64 / 1160.0,
                clip.source
            );
            assert!(clip.frames.iter().flatten().all(|p| p.iter().all(|v| v.is_finite())));
            if mapping == TimeMapping::StretchOmega {
                for roll in [PI / 6.0, PI / 4.0, PI / 3.0] {
                    let (_, t) =
                        roll_clip(&omega, None, &RollClipParams { roll_total_rad: roll, ..params.clone() }).unwrap();
                    let a = t.max_tangent_alignment(&Vector3::y());
                    let near = a.iter().filter(|&&v| v > 0.99).count();
                    println!(
                        "  roll_total {roll:.4} rad: max |d3·e2| {:.4}, frames with |d3·e2| > 0.99: {near}/1160",
                        a.iter().cloned().fold(0.0, f64::max)
                    );
                }
                let (fine, fine_truth) =
                    roll_clip(&omega, None, &RollClipParams { substeps: 32, ..params.clone() }).unwrap();
                let ex = clip
                    .frames
                    .iter()
                    .flatten()
                    .zip(fine.frames.iter().flatten())
                    .map(|(a, b)| (a - b).norm())
                    .fold(0.0, f64::max)
                    / params.length_m;
                let eq = truth
                    .frames
                    .iter()
                    .flat_map(|f| &f.q)
                    .zip(fine_truth.frames.iter().flat_map(|f| &f.q))
                    .map(|(a, b)| (a - b).amax())
                    .fold(0.0, f64::max);
                println!("  substeps {} vs 32: max |Δx|/L {ex:.2e}, max |ΔQ| {eq:.2e}", params.substeps);
                assert!(ex < 1e-10, "{ex:e}");
            }
        }
    }
}
