//! Missing data in recordings, as trackers write it (`clip.missing = "nan"`): a node with a NaN
//! coordinate was not tracked in that frame (the head or tail lost, an occlusion); a frame
//! whose nodes are all NaN is a missing frame.
//!
//! The tracking term of the objective (41) carries a nodal weight `w_i` (P1) in its integrand
//! (`docs/inverse.md`, I14; `docs/decisions.md`, D19):
//!
//! ```text
//!   λg/2 ∫ w |x − x_g|²,    w_i = 1 (node i tracked),  FILL_WEIGHT (not tracked: x_g filled)
//! ```
//!
//! Every untracked position is filled before anything else sees the clip, so that no NaN
//! reaches the length check, the chart, the start guess or the solve ([`fill_missing`]):
//! - in a frame with at least [`MIN_TRACKED`] tracked nodes, along the body: an interior gap by
//!   a cubic between its tracked neighbours, an end gap by continuing the end's last turn;
//! - a frame with fewer is *bridged* in time: each node linear in time between the nearest
//!   frames with [`MIN_TRACKED`] tracked nodes (held constant beyond the first or last one).
//!
//! Why not `w = 0` there: then nothing holds the untracked part. The controls that bend it cost
//! almost nothing (λl = 1e-6 against a bending stiffness of 1e-14 N m²) and the clip cases' Λκ
//! and Λω are 0 and 1e-20. A tail of 4 untracked nodes (of 33) made Newton stall at a
//! certificate of 3e-9 (measured, D19); a frame with `w ≡ 0` leaves even its position to the two
//! end conditions. So the filled data are tracked with a reduced weight: an untracked node is
//! placed by the rod (the λd term, ∂s x = d3 at unit stretch, from its tracked neighbours) and
//! pulled weakly towards its fill.
use nalgebra::{Rotation3, Vector3};

use super::ClipError;
pub use crate::solve::inverse::tracking::{tracking_weights, FILL_WEIGHT, MIN_TRACKED};

/// How a recording marks nodes that were not tracked (`clip.missing`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MissingData {
    /// a non-finite coordinate is an error naming its frame and node (the default)
    #[default]
    Error,
    /// NaN marks an untracked node (any coordinate NaN), all nodes NaN a missing frame
    Nan,
}

/// Is every coordinate of `p` finite?
fn finite(p: &Vector3<f64>) -> bool {
    p.iter().all(|c| c.is_finite())
}

/// Fill every untracked node of `frames` (a node with a NaN coordinate) as the module doc says,
/// and return which nodes were tracked, frame by frame. `first`: the file's index of
/// `frames[0]` (for the error). An error if no frame has [`MIN_TRACKED`] tracked nodes.
pub fn fill_missing(frames: &mut [Vec<Vector3<f64>>], first: usize) -> Result<Vec<Vec<bool>>, ClipError> {
    let tracked: Vec<Vec<bool>> = frames.iter().map(|f| f.iter().map(finite).collect()).collect();
    let fillable: Vec<usize> =
        (0..frames.len()).filter(|&k| tracked[k].iter().filter(|t| **t).count() >= MIN_TRACKED).collect();
    if fillable.is_empty() {
        return Err(ClipError::NothingTracked { first, frames: frames.len(), minimum: MIN_TRACKED });
    }
    for &k in &fillable {
        fill_along_body(&mut frames[k], &tracked[k]);
    }
    for k in 0..frames.len() {
        if fillable.binary_search(&k).is_ok() {
            continue;
        }
        let after = fillable.partition_point(|&j| j < k);
        let (a, b) = match (after.checked_sub(1).map(|i| fillable[i]), fillable.get(after)) {
            (Some(a), Some(&b)) => (a, b),
            (Some(a), None) => (a, a),
            (None, Some(&b)) => (b, b),
            (None, None) => unreachable!("fillable is not empty"),
        };
        let t = if a == b { 0.0 } else { (k - a) as f64 / (b - a) as f64 };
        for i in 0..frames[k].len() {
            if !tracked[k][i] {
                frames[k][i] = frames[a][i] * (1.0 - t) + frames[b][i] * t;
            }
        }
    }
    Ok(tracked)
}

/// Fill the untracked nodes of one frame with at least [`MIN_TRACKED`] tracked nodes: interior
/// gaps by the cubic Hermite curve between their tracked neighbours, with the tangents of the
/// tracked nodes beyond them (Catmull–Rom in the node index); end gaps by continuing the end's
/// last turn (the rotation between its last two segments, a circle for a planar end) at the
/// frame's median spacing of neighbouring tracked nodes.
fn fill_along_body(x: &mut [Vector3<f64>], tracked: &[bool]) {
    let known: Vec<usize> = (0..x.len()).filter(|&i| tracked[i]).collect();
    let (head, tail) = (known[0], known[known.len() - 1]);
    for (k, w) in known.windows(2).enumerate() {
        let (a, b) = (w[0], w[1]);
        if b == a + 1 {
            continue;
        }
        let (before, after) = (known[k.saturating_sub(1)], known.get(k + 2).copied().unwrap_or(b));
        let span = (b - a) as f64;
        // tangents per unit of the gap's parameter u = (i − a)/(b − a)
        let ta = (x[b] - x[before]) * (span / (b - before) as f64);
        let tb = (x[after] - x[a]) * (span / (after - a) as f64);
        for i in a + 1..b {
            let u = (i - a) as f64 / span;
            let (u2, u3) = (u * u, u * u * u);
            x[i] = x[a] * (2.0 * u3 - 3.0 * u2 + 1.0)
                + ta * (u3 - 2.0 * u2 + u)
                + x[b] * (-2.0 * u3 + 3.0 * u2)
                + tb * (u3 - u2);
        }
    }
    let mut steps: Vec<f64> =
        known.windows(2).filter(|w| w[1] == w[0] + 1).map(|w| (x[w[1]] - x[w[0]]).norm()).collect();
    steps.sort_by(f64::total_cmp);
    let spacing = steps.get(steps.len() / 2).copied().unwrap_or((x[tail] - x[head]).norm() / (tail - head) as f64);
    let n = x.len();
    continue_end(x, tail, (tail + 1..n).collect(), spacing, -1);
    continue_end(x, head, (0..head).rev().collect(), spacing, 1);
}

/// Continue the body beyond its last known node `end` into the nodes `out` (in order away from
/// it), each `spacing` [m] from the one before, turning each segment by the turn between the
/// last two known segments; `inward` (±1) is the step from a node towards the body.
fn continue_end(x: &mut [Vector3<f64>], end: usize, out: Vec<usize>, spacing: f64, inward: isize) {
    let step = |i: usize| i.checked_add_signed(inward).filter(|&j| j < x.len());
    let Some(p1) = step(end).filter(|_| !out.is_empty()) else { return };
    let last = x[end] - x[p1];
    // the turn between the last two segments; straight where there is one segment only
    let turn = step(p1)
        .and_then(|p2| Rotation3::rotation_between(&(x[p1] - x[p2]), &last))
        .unwrap_or_else(Rotation3::identity);
    let mut dir = last.try_normalize(0.0).unwrap_or_else(Vector3::zeros);
    let mut from = x[end];
    for i in out {
        dir = turn * dir;
        from += dir * spacing;
        x[i] = from;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arc(n: usize) -> Vec<Vector3<f64>> {
        (0..n).map(|i| Vector3::new((i as f64 * 0.1).sin(), 0.0, (i as f64 * 0.1).cos())).collect()
    }

    /// A straight frame is filled exactly: interior gaps on the line, ends continued at the
    /// node spacing; the weights are 1 and 0.
    #[test]
    fn straight_frame_is_filled_exactly() {
        let line: Vec<Vector3<f64>> = (0..8).map(|i| Vector3::new(0.0, 0.0, 0.5 * i as f64)).collect();
        let mut x = vec![line.clone()];
        for i in [0, 1, 3, 4, 7] {
            x[0][i] = Vector3::new(f64::NAN, 0.0, 0.0);
        }
        let tracked = fill_missing(&mut x, 0).expect("two tracked nodes");
        for (a, b) in x[0].iter().zip(&line) {
            assert!((a - b).norm() < 1e-15, "{a} vs {b}");
        }
        let f = FILL_WEIGHT;
        assert_eq!(tracking_weights(&tracked[0]), vec![f, f, 1.0, f, f, 1.0, 1.0, f]);
    }

    /// A missing frame is the linear interpolation in time of its neighbours, its weights
    /// reduced; a missing frame at the end holds the last tracked one.
    #[test]
    fn missing_frames_are_bridged_in_time() {
        let a = arc(6);
        let b: Vec<Vector3<f64>> = a.iter().map(|p| p + Vector3::new(3.0, 0.0, 0.0)).collect();
        let nan = vec![Vector3::new(f64::NAN, f64::NAN, f64::NAN); 6];
        let mut x = vec![a.clone(), nan.clone(), nan.clone(), b.clone(), nan];
        let tracked = fill_missing(&mut x, 0).expect("tracked frames");
        assert!((x[1][2] - (a[2] + Vector3::new(1.0, 0.0, 0.0))).norm() < 1e-15);
        assert!((x[2][5] - (a[5] + Vector3::new(2.0, 0.0, 0.0))).norm() < 1e-15);
        assert_eq!(x[4], b);
        assert_eq!(tracking_weights(&tracked[1]), vec![FILL_WEIGHT; 6]);
        assert_eq!(tracking_weights(&tracked[3]), vec![1.0; 6]);
    }

    #[test]
    fn a_clip_without_two_tracked_nodes_in_any_frame_is_an_error() {
        let mut x = vec![vec![Vector3::new(f64::NAN, 0.0, 0.0); 4]; 3];
        x[1][2] = Vector3::zeros();
        let e = fill_missing(&mut x, 10).unwrap_err().to_string();
        assert!(e.contains("frames 10–12") && e.contains("2 tracked nodes"), "{e}");
    }
}
