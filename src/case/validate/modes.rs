//! `solver.vibration_modes`: the lowest natural frequencies of the rod about its rest state
//! (`docs/decisions.md`, D28), computed by `run` after a static solve in both engines.
use super::super::raw::{RawAnalysis, RawCase, RawQuadrature};
use super::{CaseError, Validator};
use crate::model::mesh::Mesh;

impl Validator<'_> {
    /// `solver.vibration_modes` (0 when not given): at least 1, at most half the free unknowns
    /// (`3 × elements`); only for a static analysis of the paper's rod (straight, clamped at
    /// s = 0, free at s = L: the pencil of `solve::modes` removes node 0 and symmetrises the
    /// angle rows with `A(0)ᵀ`, eqs. 27–30), with the density given (ω ∝ 1/√ρ) and a mass
    /// matrix that is not singular (not `quadrature = "midpoint"`, §5.2).
    pub(super) fn vibration_modes(
        &self,
        raw: &RawCase,
        mesh: &Mesh,
        density_given: bool,
        general: bool,
    ) -> Result<usize, CaseError> {
        let Some(n) = raw.solver.vibration_modes else { return Ok(0) };
        let key = "solver.vibration_modes";
        let refuse = |reason: &str| Err(self.err(key, reason));
        if raw.solver.analysis != RawAnalysis::Static {
            return refuse("only for a static analysis: the frequencies of the rod about its rest state are computed after the static solve (D28; `cosserat modes` takes any case)");
        }
        if n == 0 {
            return refuse("must be at least 1 (leave it out for no natural frequencies)");
        }
        let most = 3 * mesh.elements;
        if n > most {
            return Err(self.err(
                key,
                format!("at most {most} (half the unknowns not held) on {} elements, got {n}", mesh.elements),
            ));
        }
        if general {
            return refuse("the natural frequencies are computed for the paper's rod only: straight along e3, clamped at s = 0 and free at s = L (no rod.start_*, intrinsic curvature, chart axis or [ends], D28)");
        }
        if !density_given {
            return refuse("needs material.density_kg_m3 [kg/m^3] (the natural frequencies scale as 1/sqrt(density))");
        }
        if matches!(raw.solver.quadrature, RawQuadrature::Midpoint) {
            return Err(self.err(
                "solver.quadrature",
                "\"midpoint\" integrates the mass matrix with one point, which is singular for P1 elements: solver.vibration_modes needs \"selective\", \"full\", \"reduced\" or \"gauss2\"",
            ));
        }
        Ok(n)
    }
}
