//! The data of the tracking term `λg/2 ∫ w |x − x_g|²` of (41) with its nodal weight `w`
//! (`docs/inverse.md`, I14): 1 at a tracked node, [`FILL_WEIGHT`] at a node the recording did not
//! track, whose data are filled (`clip::missing`, `docs/decisions.md` D18).
use nalgebra::Vector3;

/// Fewest tracked nodes of a frame that `clip::missing` fills along the body; a frame with
/// fewer is bridged in time.
pub const MIN_TRACKED: usize = 2;

/// Tracking weight of an untracked node, whose data are filled. Reduced against a tracked
/// node's 1, so that tracked data win where they and the fill disagree; not zero, since nothing
/// else holds the shape there (`clip::missing`). The results hardly depend on it: on the three
/// patterns of `tests/missing_data.rs`, 1e-5, 1e-3 and 1e-1 give untracked position errors
/// within 10 % of each other (D18).
pub const FILL_WEIGHT: f64 = 1e-3;

/// The tracking weight `w_i` of every node of a frame with the tracked nodes `tracked` (module
/// doc): 1 tracked, [`FILL_WEIGHT`] untracked.
pub fn tracking_weights(tracked: &[bool]) -> Vec<f64> {
    tracked.iter().map(|&t| if t { 1.0 } else { FILL_WEIGHT }).collect()
}

/// The data of the tracking term `λg/2 ∫ w |x − x_g|²` of (41) (I14): the positions `x_g` per
/// node [m] and the nodal weight `w` (P1), `None` for w ≡ 1 (every node tracked).
#[derive(Clone, Copy, Debug)]
pub struct Tracking<'a> {
    pub x_g: &'a [Vector3<f64>],
    pub weight: Option<&'a [f64]>,
}

impl Tracking<'_> {
    /// The data and the weights at the two nodes of element `e`.
    pub fn element(&self, e: usize) -> ([Vector3<f64>; 2], [f64; 2]) {
        let w = self.weight.map_or([1.0; 2], |w| [w[e], w[e + 1]]);
        ([self.x_g[e], self.x_g[e + 1]], w)
    }
}

/// The weight at the point with shape function values `n` of an element with nodal weights
/// `w`: exactly 1 where both are 1 (`(1 − ξ) + ξ` need not round to 1), so that a clip without
/// missing data gives the same bits as the unweighted term.
pub fn weight_at(w: [f64; 2], n: [f64; 2]) -> f64 {
    if w == [1.0, 1.0] {
        1.0
    } else {
        w[0] * n[0] + w[1] * n[1]
    }
}

impl<'a> From<&'a [Vector3<f64>]> for Tracking<'a> {
    fn from(x_g: &'a [Vector3<f64>]) -> Self {
        Tracking { x_g, weight: None }
    }
}

impl<'a> From<&'a Vec<Vector3<f64>>> for Tracking<'a> {
    fn from(x_g: &'a Vec<Vector3<f64>>) -> Self {
        Tracking { x_g, weight: None }
    }
}
