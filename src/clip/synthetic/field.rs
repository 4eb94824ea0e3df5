//! The kymogram as a smooth field in time and along the body (module doc, steps 1–2).
use super::{RollClipParams, TimeMapping};
use crate::clip::ClipError;

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
    pub(super) k: Vec<f64>,
    /// Second derivatives [1/m³].
    pub(super) m: Vec<f64>,
    pub(super) segment_m: f64,
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
