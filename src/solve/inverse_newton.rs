//! Newton mode of the inverse problem (issue 3): Newton on the discrete equations of Problem 2,
//! eq. (61), whose fixed point `inverse::solve_frame` seeks. Work in progress.
use nalgebra::{DVector, Vector3};

use super::inverse::{InverseParams, InverseRecord, InverseSolution};
use super::{Problem, SolveError};

/// Not available yet: an error, never a silent substitute.
pub fn solve_frame_newton(_problem: &Problem, _p: &InverseParams, _x_g: &[Vector3<f64>], _alpha_prev: &[Vector3<f64>], _u0: &DVector<f64>, _progress: impl FnMut(&InverseRecord)) -> Result<InverseSolution, SolveError> {
    Err(SolveError::Unsupported("solver.method = \"newton\" for inverse cases is not implemented yet"))
}
