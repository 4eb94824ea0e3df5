//! Linear algebra of the block-tridiagonal systems every solver of the crate produces: their
//! sparsity [`Pattern`], a banded LU with partial pivoting ([`BandLu`]) and the direct solver
//! with Ruiz equilibration ([`LinearSolver`]), and block Krylov subspaces for the extreme
//! eigenpairs of an operator ([`Krylov`]). Knows matrices, not meshes.
mod band;
mod cpu;
mod krylov;
mod pattern;
mod solver;

pub use band::BandLu;
pub use krylov::{largest_real_positive, largest_symmetric, Krylov};
pub use pattern::Pattern;
pub use solver::LinearSolver;

/// Errors of the linear algebra layer.
#[derive(Debug, thiserror::Error)]
pub enum LinearError {
    #[error("singular matrix: zero or non-finite pivot {pivot:e} in column {column} of the band LU")]
    ZeroPivot { column: usize, pivot: f64 },
    #[error("linear solve produced a non-finite value at unknown {index}")]
    NonFinite { index: usize },
}
