//! Solvers. Each stage has its own file: [`statics`] (the paper's relaxed fixed point of §4 and
//! Newton), [`dynamics`] (Appendix A time stepping, D6), [`modes`] (linearised natural
//! frequencies about the rest state). All of them assemble through [`Problem`], which owns the
//! one element loop of the crate.
pub mod dynamics;
pub mod inverse;
pub mod inverse_newton;
pub mod modes;
pub mod sequence;
pub mod statics;

use nalgebra::{DVector, Vector3};

use crate::assembly::{assemble_vector, gather, LinearError, Pattern};
use crate::case::Case;
use crate::element::{distributed_load, follower_load, internal_force, momentum, LocalMat, LocalVec};
use crate::loads::{LoadFrame, Loads};
use crate::material::RodProperties;
use crate::mesh::{Dof, Mesh, QuadratureScheme};

/// Errors of the solvers; each variant carries the numbers needed to act on it.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    #[error("fixed point did not converge after {iterations} iterations in continuation step {step} (last relative change {rel_change:e})")]
    FixedPointNotConverged { step: usize, iterations: usize, rel_change: f64 },
    #[error("Newton did not converge after {iterations} iterations (last increment {increment:e}){}", step_text(*.step))]
    /// `step`: time step (dynamic) or continuation step (static)
    NewtonNotConverged { step: Option<usize>, iterations: usize, increment: f64 },
    #[error("non-finite value in iteration {iteration}{}", step_text(*.step))]
    NonFinite { step: Option<usize>, iteration: usize },
    #[error("inverse fixed point of frame {frame} did not converge after {iterations} iterations (last relative change of (x, α) {rel_change:e})")]
    InverseNotConverged { frame: usize, iterations: usize, rel_change: f64 },
    #[error("inverse Newton of frame {frame} did not converge after {iterations} iterations (last residual ‖R‖/‖R₀‖ {residual:e})")]
    InverseNewtonNotConverged { frame: usize, iterations: usize, residual: f64 },
    #[error("non-finite value in iteration {iteration} of inverse frame {frame}")]
    InverseNonFinite { frame: usize, iteration: usize },
    #[error("{0}")]
    Unsupported(&'static str),
    #[error("case `{0}` is not an inverse case")]
    NotInverse(String),
    #[error(transparent)]
    Linear(#[from] LinearError),
}

fn step_text(step: Option<usize>) -> String {
    step.map(|s| format!(" at time step {s}")).unwrap_or_default()
}

/// The discrete forward problem: mesh, coefficients, quadrature and loads.
#[derive(Clone, Copy)]
pub struct Problem<'a> {
    pub mesh: Mesh,
    pub props: RodProperties,
    pub scheme: QuadratureScheme,
    pub loads: &'a Loads,
    /// factor applied to every load (load continuation), 1 by default
    pub load_factor: f64,
}

impl<'a> Problem<'a> {
    pub fn from_case(case: &'a Case) -> Self {
        Problem { mesh: case.mesh, props: case.props, scheme: case.quadrature, loads: &case.loads, load_factor: 1.0 }
    }

    /// Reference configuration: straight along e3, `x0(s) = (0, 0, s)`, `α = 0` (D1).
    pub fn reference_state(&self) -> DVector<f64> {
        let mut u = DVector::zeros(self.mesh.ndofs());
        for i in 0..self.mesh.nodes() {
            u[self.mesh.dof(i, Dof::Z)] = self.mesh.node_s(i);
        }
        u
    }

    /// Unknowns fixed by the clamp at s = 0 (D3): all six of node 0.
    pub fn clamped_dofs(&self) -> Vec<usize> {
        (0..6).collect()
    }

    /// External load vector `F(t)` of D3 (distributed + end loads) for global-frame loads;
    /// follower loads are evaluated in the reference configuration (use [`Problem::loads_at`]).
    pub fn external_force(&self, t: f64) -> DVector<f64> {
        self.loads_at(&self.reference_state(), t, None)
    }

    /// External load vector `F(u, t)` of D3; follower (local-frame) distributed loads depend on
    /// `u` through `Qᵀ(α)`, and `tangent = Some((pattern, values, scale))` then adds
    /// `scale · ∂F/∂u` into `values`. Scaled by `load_factor`.
    pub fn loads_at(&self, u: &DVector<f64>, t: f64, tangent: Option<(&Pattern, &mut [f64], f64)>) -> DVector<f64> {
        let h = self.mesh.h();
        let lf = self.load_factor;
        let mut field = |s: f64| {
            let (f, l) = self.loads.distributed(s, t);
            (f * lf, l * lf)
        };
        let mut f = match (self.loads.has_distributed(), self.loads.frame) {
            (false, _) => DVector::zeros(self.mesh.ndofs()),
            (true, LoadFrame::Global) => {
                assemble_vector(&self.mesh, |_, s0| distributed_load(self.scheme, h, s0, &mut field))
            }
            (true, LoadFrame::Local) => self.assemble_with_tangent(tangent, |e, s0, t| {
                follower_load(self.scheme, h, s0, &gather(u, e), &mut field, t)
            }),
        };
        let (fe, le) = self.loads.end(t);
        let (fe, le) = (fe * lf, le * lf);
        let last = self.mesh.nodes() - 1;
        for k in 0..3 {
            f[self.mesh.dof(last, Dof::X) + k] += fe[k];
            f[self.mesh.dof(last, Dof::Alpha) + k] += le[k];
        }
        f
    }

    /// Internal force `G(u)`; with `tangent = Some((pattern, values, scale))` also adds
    /// `scale · ∂G/∂u` into `values`.
    pub fn internal_force(&self, u: &DVector<f64>, tangent: Option<(&Pattern, &mut [f64], f64)>) -> DVector<f64> {
        let h = self.mesh.h();
        self.assemble_with_tangent(tangent, |e, _, t| internal_force(&self.props, self.scheme, h, &gather(u, e), t))
    }

    /// Momentum `P(u, u̇)` of D6; optionally adds `scale_u · ∂P/∂u + scale_v · ∂P/∂u̇`.
    pub fn momentum(
        &self,
        u: &DVector<f64>,
        udot: &DVector<f64>,
        tangent: Option<(&Pattern, &mut [f64], f64, f64)>,
    ) -> DVector<f64> {
        let h = self.mesh.h();
        // One tangent out of two scaled kernel tangents: `su ∂P/∂u + sv ∂P/∂u̇`.
        let (su, sv) = tangent.as_ref().map(|t| (t.2, t.3)).unwrap_or((0.0, 0.0));
        let mut dv = LocalMat::zeros();
        self.assemble_with_tangent(tangent.map(|(p, v, _, _)| (p, v, 1.0)), |e, _, t| {
            let (ue, ve) = (gather(u, e), gather(udot, e));
            match t {
                Some(du) => {
                    dv.fill(0.0);
                    let r = momentum(&self.props, self.scheme, h, &ue, &ve, Some(du), Some(&mut dv));
                    *du = *du * su + dv * sv;
                    r
                }
                None => momentum(&self.props, self.scheme, h, &ue, &ve, None, None),
            }
        })
    }

    /// The one gather → kernel → scatter loop with an optional tangent: `kernel(e, s0, t)`
    /// returns the element vector and, when `t` is given, fills the element tangent (zeroed
    /// before the call), which is added as `scale · t` into `values`.
    fn assemble_with_tangent(
        &self,
        mut tangent: Option<(&Pattern, &mut [f64], f64)>,
        mut kernel: impl FnMut(usize, f64, Option<&mut LocalMat>) -> LocalVec,
    ) -> DVector<f64> {
        let mut local_t = LocalMat::zeros();
        assemble_vector(&self.mesh, |e, s0| match tangent.as_mut() {
            Some((pattern, values, scale)) => {
                local_t.fill(0.0);
                let r = kernel(e, s0, Some(&mut local_t));
                local_t *= *scale;
                pattern.scatter_mat(values, e, &local_t);
                r
            }
            None => kernel(e, s0, None),
        })
    }

    /// Infinity norm over the unknowns that are not clamped.
    pub fn free_norm_inf(&self, r: &DVector<f64>) -> f64 {
        let fixed = self.clamped_dofs();
        r.iter().enumerate().filter(|(i, _)| !fixed.contains(i)).fold(0.0, |m, (_, v)| m.max(v.abs()))
    }

    /// Newton increment measure of D5/D6: `max(‖δx‖∞ / L, ‖δα‖∞)`.
    pub fn increment_measure(&self, du: &DVector<f64>) -> f64 {
        let (dx, da) = split_norms_inf(du);
        (dx / self.mesh.length_m).max(da)
    }
}

/// `(‖x‖∞, ‖α‖∞)` of a nodal vector.
pub fn split_norms_inf(u: &DVector<f64>) -> (f64, f64) {
    let mut nx: f64 = 0.0;
    let mut na: f64 = 0.0;
    for (i, v) in u.iter().enumerate() {
        if i % 6 < 3 {
            nx = nx.max(v.abs());
        } else {
            na = na.max(v.abs());
        }
    }
    (nx, na)
}

/// `(‖x‖₂, ‖α‖₂)` of a nodal vector.
pub fn split_norms_2(u: &DVector<f64>) -> (f64, f64) {
    let mut nx = 0.0;
    let mut na = 0.0;
    for (i, v) in u.iter().enumerate() {
        if i % 6 < 3 {
            nx += v * v;
        } else {
            na += v * v;
        }
    }
    (f64::sqrt(nx), f64::sqrt(na))
}

/// Node `i` position and angles of a nodal vector.
pub fn node_values(u: &DVector<f64>, i: usize) -> (Vector3<f64>, Vector3<f64>) {
    (Vector3::new(u[6 * i], u[6 * i + 1], u[6 * i + 2]), Vector3::new(u[6 * i + 3], u[6 * i + 4], u[6 * i + 5]))
}
