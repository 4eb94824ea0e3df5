//! The residual certificate of a solve (`docs/certificate.md`): how well the returned state
//! satisfies the discrete equations the solve claims to solve, as a block backward error.
//!
//! Every system here is written, at a state `u`, as a sum of terms `R(U) = K(u) U − r(u)`: the
//! frozen-coefficient form of the paper's fixed point (D5, I4), whose every row is a sum of the
//! integrals of (52)/(61) as printed (`Q_kᵀ K Q_k ∂s x`, `K33 q3`, `λg x_g`, …). For each block
//! `b` of equations (the rows tested by one field: force and moment balance of the forward
//! problem; the four row blocks `δx, δα, δx̂, δα̂` of the KKT system, I1)
//!
//! ```text
//!   η_b = max_{i∈b} |R_i(U)| / max_{i∈b} (|K(u)| |U| + |r(u)|)_i ,      η = max_b η_b
//! ```
//! with every coefficient at the returned state itself (not at the previous iterate). `η` is the
//! relative size of the smallest perturbation of the terms of each block, measured against the
//! block's largest term, that makes `U` an exact solution: a backward error. It does not depend
//! on the units or on cancellation between large terms (the K33 q3 of D10), and its floor is the
//! round-off of summing the terms, a few ulps (`docs/certificate.md` has the measured floors).
use nalgebra::DVector;

use crate::linalg::Pattern;
use crate::model::mesh::DofMap;

/// A certificate at or below this is at the round-off floor of the block sums: the largest of
/// the floors measured on the committed cases is 2e-15 (`docs/certificate.md`).
pub const CERTIFICATE_FLOOR: f64 = 1e-14;

/// Default tolerance of the certificate: a result is `converged` only with `η ≤` this. Four
/// decades above the floor, so a Newton root reaches it in one step from a quadratically
/// converging iterate, and far below what a stalled iteration leaves (1e-7 … 1e-3 measured).
pub const DEFAULT_CERTIFICATE_TOLERANCE: f64 = 1e-10;

/// The block backward error of a returned state (module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Certificate {
    /// `η = max_b η_b`
    pub value: f64,
    /// `η_b` per block, indexed by the field whose test function makes the rows
    /// (`Field as usize`: x, α, then x̂, α̂ for the KKT system); unused blocks are 0
    pub blocks: [f64; 4],
}

/// The system a certificate is of, which names its four blocks of rows: a forward problem's
/// (force and moment balance, two blocks) or the inverse problem's KKT system (eq. 61: the
/// adjoint's and the primal's rows, four blocks).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum System {
    Forward,
    Kkt,
}

impl Certificate {
    /// The certificate of a residual `r` and the term magnitudes `scale` (`|K||U| + |r|` per row),
    /// both in the layout `dofs`. A block whose terms are all zero has `η_b = 0` if its residual
    /// is zero too, else infinity; a non-finite residual gives a non-finite certificate.
    pub fn from_residual(dofs: &DofMap, r: &DVector<f64>, scale: &DVector<f64>) -> Self {
        let mut top = [(0.0_f64, 0.0_f64); 4];
        for (i, (ri, si)) in r.iter().zip(scale.iter()).enumerate() {
            let b = &mut top[dofs.field_of(i) as usize];
            // NaN-propagating maxima: a non-finite residual must not hide
            b.0 = if ri.is_nan() || b.0.is_nan() { f64::NAN } else { b.0.max(ri.abs()) };
            b.1 = b.1.max(si.abs());
        }
        let blocks = top.map(|(res, size)| match (res, size) {
            (res, _) if res.is_nan() => f64::NAN,
            (res, size) if size > 0.0 => res / size,
            (0.0, _) => 0.0,
            _ => f64::INFINITY,
        });
        let value = blocks.iter().fold(0.0_f64, |m, &b| if b.is_nan() || m.is_nan() { f64::NAN } else { m.max(b) });
        Certificate { value, blocks }
    }

    /// Is the certificate within `tolerance` (false for a non-finite one)?
    pub fn within(&self, tolerance: f64) -> bool {
        self.value.is_finite() && self.value <= tolerance
    }

    /// The block with the largest `η_b`, named by the balance its rows express.
    pub fn worst_block(&self, system: System) -> &'static str {
        let names: [&'static str; 4] = match system {
            System::Kkt => ["adjoint δx rows", "adjoint δα rows", "primal force rows (δx̂)", "primal moment rows (δα̂)"],
            System::Forward => ["force balance", "moment balance", "", ""],
        };
        let worst = (0..4).max_by(|&a, &b| self.blocks[a].total_cmp(&self.blocks[b])).unwrap_or(0);
        names[worst]
    }
}

/// The residual `K U − r` and the term magnitudes `|K| |U| + |r|` of an assembled system (the
/// values of `pattern`, Dirichlet rows already the identity with their values in `r`).
pub fn system_terms(
    pattern: &Pattern,
    values: &[f64],
    u: &DVector<f64>,
    r: &DVector<f64>,
) -> (DVector<f64>, DVector<f64>) {
    let (mut res, mut scale) = (-r, r.abs());
    let (cols, rows) = (pattern.col_ptr(), pattern.row_idx());
    for j in 0..pattern.ndofs() {
        let (uj, aj) = (u[j], u[j].abs());
        for k in cols[j]..cols[j + 1] {
            let i = rows[k];
            res[i] += values[k] * uj;
            scale[i] += values[k].abs() * aj;
        }
    }
    (res, scale)
}

/// The certificate of an assembled system at `U` ([`system_terms`], [`Certificate::from_residual`]).
pub fn of_system(dofs: &DofMap, pattern: &Pattern, values: &[f64], u: &DVector<f64>, r: &DVector<f64>) -> Certificate {
    let (res, scale) = system_terms(pattern, values, u, r);
    Certificate::from_residual(dofs, &res, &scale)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::mesh::Field;

    #[test]
    fn block_backward_error_of_a_small_system() {
        let dofs = DofMap::forward(2);
        let mut r = dofs.zeros();
        let mut s = dofs.zeros();
        // x rows: residual 1e-3 against a largest term of 10; α rows: 0 against 5
        r[0] = 1e-3;
        s[0] = 10.0;
        s[1] = 1.0;
        s[3] = 5.0;
        let c = Certificate::from_residual(&dofs, &r, &s);
        assert_eq!(c.blocks[Field::X as usize], 1e-4);
        assert_eq!(c.blocks[Field::Alpha as usize], 0.0);
        assert_eq!(c.value, 1e-4);
        assert_eq!(c.worst_block(System::Forward), "force balance");
        // a residual where every term vanishes cannot be certified, nor can a NaN
        r[3] = 1e-30;
        s[3] = 0.0;
        assert!(Certificate::from_residual(&dofs, &r, &s).value.is_infinite());
        r[4] = f64::NAN;
        assert!(!Certificate::from_residual(&dofs, &r, &s).within(1.0));
    }
}
