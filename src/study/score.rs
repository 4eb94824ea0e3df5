//! Scoring a reconstruction of a synthetic recording against its truth: the bending-curvature
//! error per frame (`docs/noise.md`, N5).
//!
//! Per frame, with `b_e = √(κ1² + κ2²)` on element `e` (the roll-invariant bending curvature;
//! the recovered `κ` is element-wise, the truth's nodal `κ1, κ2` are averaged to the element
//! midpoints), over the elements without `skip` at each end:
//!
//! ```text
//!   error = ( Σ_e (b_e − b_e^true)² / Σ_e (b_e^true)² )^½
//! ```
use std::path::Path;

use nalgebra::Vector3;

use crate::clip::synthetic::FrameTruth;
use crate::io::{InputError, OutputError};
use crate::recorded::smoothing::SmoothingSpline;

/// Errors of scoring a run.
#[derive(Debug, thiserror::Error)]
pub enum ScoreError {
    #[error(transparent)]
    Input(#[from] InputError),
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error("{path}: {reason}")]
    Curvature { path: String, reason: String },
}

/// The truth's bending curvature on each element [1/m] (nodal `κ1, κ2` averaged to the
/// element's midpoint).
pub fn truth_bending(truth: &FrameTruth) -> Vec<f64> {
    truth.kappa.windows(2).map(|w| (0.5 * (w[0].x + w[1].x)).hypot(0.5 * (w[0].y + w[1].y))).collect()
}

/// The relative L² error of `b` against `truth` over the elements without `skip` at each end
/// (the module doc); NaN when `b` is missing or the truth is zero there.
pub fn bending_error(b: &[f64], truth: &[f64], skip: usize) -> f64 {
    if b.len() != truth.len() || 2 * skip >= truth.len() {
        return f64::NAN;
    }
    let kept = skip..truth.len() - skip;
    let num: f64 = kept.clone().map(|e| (b[e] - truth[e]).powi(2)).sum();
    let den: f64 = kept.map(|e| truth[e].powi(2)).sum();
    if den > 0.0 {
        (num / den).sqrt()
    } else {
        f64::NAN
    }
}

/// The smoothing-spline baseline's bending curvature per element of a noisy frame of a body of
/// length `length_m` [m] (nodes equally spaced in arc length), NaN where no spline can be
/// fitted.
pub fn spline_bending(frame: &[Vector3<f64>], length_m: f64) -> Vec<f64> {
    let elements = frame.len().saturating_sub(1);
    SmoothingSpline::fit_uniform(frame, length_m)
        .map_or_else(|| vec![f64::NAN; elements], |s| s.element_curvatures(elements))
}

/// The recovered bending curvature per frame and element from a run's `curvature.csv`
/// (columns `frame, s_mid_m, kappa1_per_m, kappa2_per_m, kappa3_per_m`); frames that were not
/// written (the run stopped) are absent.
pub fn read_curvature(path: &Path) -> Result<Vec<Vec<f64>>, ScoreError> {
    read_frames(path, |num| Ok(num(2)?.hypot(num(3)?)))
}

/// One value per row of the CSV file `path` whose first column is the frame, gathered per frame
/// in row order: `value` reads a row through its number of column `i`. Frames without rows are
/// empty.
fn read_frames<T>(
    path: &Path,
    value: impl Fn(&dyn Fn(usize) -> Result<f64, ScoreError>) -> Result<T, ScoreError>,
) -> Result<Vec<Vec<T>>, ScoreError> {
    let bad = |reason: String| ScoreError::Curvature { path: path.display().to_string(), reason };
    let mut reader = csv::Reader::from_path(path).map_err(|e| bad(e.to_string()))?;
    let mut frames: Vec<Vec<T>> = Vec::new();
    for record in reader.records() {
        let r = record.map_err(|e| bad(e.to_string()))?;
        let num = |i: usize| -> Result<f64, ScoreError> {
            r.get(i).and_then(|v| v.parse::<f64>().ok()).ok_or_else(|| bad(format!("column {i} of {r:?}")))
        };
        let frame = num(0)? as usize;
        while frames.len() <= frame {
            frames.push(Vec::new());
        }
        frames[frame].push(value(&num)?);
    }
    Ok(frames)
}

/// The nodal bending curvature recovered from element values `b` (a patch recovery): each
/// interior node takes the mean of its two elements, an end node its element's. For a smooth
/// curvature sampled at element midpoints this is second order at the interior nodes
/// (`b(s_i) + h² b''/8`), and it averages the noise of two elements.
pub fn recovered_nodal(b: &[f64]) -> Vec<f64> {
    let n = b.len();
    (0..=n)
        .map(|i| match i {
            0 => b[0],
            i if i == n => b[n - 1],
            i => 0.5 * (b[i - 1] + b[i]),
        })
        .collect()
}

/// The bending curvature per element of a reconstructed centreline `x` (the rod's nodes [m]),
/// not of its frame: the Menger curvature `2|a × b| / (|a| |b| |a + b|)` of each interior node's
/// two chords (exact on a circle), an end node taking its neighbour's, each element the mean of
/// its two nodes [1/m]. Beside the frame's `√(κ1² + κ2²)` it shows how far the frame's
/// curvature is from its centreline's (`docs/noise.md` N13).
pub fn centreline_bending(x: &[Vector3<f64>]) -> Vec<f64> {
    if x.len() < 3 {
        return vec![f64::NAN; x.len().saturating_sub(1)];
    }
    let mut nodal: Vec<f64> = x
        .windows(3)
        .map(|w| {
            let (a, b) = (w[1] - w[0], w[2] - w[1]);
            2.0 * a.cross(&b).norm() / (a.norm() * b.norm() * (a + b).norm())
        })
        .collect();
    nodal.insert(0, nodal[0]);
    nodal.push(nodal[nodal.len() - 1]);
    nodal.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect()
}

/// The reconstructed node positions per frame [m] from a run's `fields.csv` (columns `frame`,
/// `node`, `s_m`, `x_m`, `y_m`, `z_m`, …); frames that were not written are absent.
pub fn read_positions(path: &Path) -> Result<Vec<Vec<Vector3<f64>>>, ScoreError> {
    read_frames(path, |num| Ok(Vector3::new(num(3)?, num(4)?, num(5)?)))
}

/// The truth's bending curvature at the nodes [1/m].
pub fn truth_bending_nodal(truth: &FrameTruth) -> Vec<f64> {
    truth.kappa.iter().map(|k| k.x.hypot(k.y)).collect()
}

/// Median and largest of a set of per-frame errors (NaN entries are frames not reconstructed
/// and are left out); `(NaN, NaN)` when none is finite.
pub fn median_and_worst(errors: &[f64]) -> (f64, f64) {
    let mut v: Vec<f64> = errors.iter().copied().filter(|e| e.is_finite()).collect();
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let median = if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) };
    (median, v[n - 1])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bending_error_is_relative_and_skips_the_ends() {
        let truth = vec![100.0, 1.0, 2.0, 2.0, 1.0, 100.0];
        let mut b = truth.clone();
        b[0] = 0.0;
        b[5] = 0.0;
        assert_eq!(bending_error(&b, &truth, 1), 0.0);
        b[2] = 3.0; // error 1 against a norm of √10
        assert!((bending_error(&b, &truth, 1) - (0.1f64).sqrt()).abs() < 1e-15);
        assert!(bending_error(&b, &truth, 3).is_nan());
    }

    /// Linear curvature sampled as element means is recovered exactly at the interior nodes.
    #[test]
    fn nodal_recovery_is_exact_for_linear_curvature() {
        let h = 0.1;
        let means: Vec<f64> = (0..8).map(|e| 2.0 + 3.0 * (e as f64 + 0.5) * h).collect();
        let r = recovered_nodal(&means);
        assert_eq!(r.len(), 9);
        for (i, v) in r.iter().enumerate().take(8).skip(1) {
            assert!((v - (2.0 + 3.0 * i as f64 * h)).abs() < 1e-14, "node {i}: {v}");
        }
    }

    /// Nodes on a circle of radius 2 mm, unevenly spaced: every element has curvature 1/R.
    #[test]
    fn centreline_bending_is_exact_on_a_circle() {
        let r = 2e-3;
        let x: Vec<Vector3<f64>> = [0.0, 0.1, 0.25, 0.3, 0.5, 0.55, 0.8]
            .iter()
            .map(|t: &f64| Vector3::new(r * t.cos(), r * t.sin(), 0.0))
            .collect();
        let b = centreline_bending(&x);
        assert_eq!(b.len(), 6);
        for v in b {
            assert!((v * r - 1.0).abs() < 1e-12, "{v}");
        }
    }

    #[test]
    fn median_and_worst_leave_out_missing_frames() {
        assert_eq!(median_and_worst(&[3.0, f64::NAN, 1.0, 2.0]), (2.0, 3.0));
        assert_eq!(median_and_worst(&[4.0, 1.0]), (2.5, 4.0));
        assert!(median_and_worst(&[f64::NAN]).0.is_nan());
    }
}
