//! Scoring a recovered frame against the ground truth.
use std::f64::consts::PI;

use nalgebra::{Matrix3, Vector3};

use super::FrameTruth;
use crate::clip::ClipError;

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
