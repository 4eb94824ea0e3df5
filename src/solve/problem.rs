//! The discrete forward problem of D3: mesh, coefficients, quadrature and loads, and its
//! global vectors and tangents, each one pass of the element loop with a kernel of
//! `model::element`.
use nalgebra::DVector;

use crate::assemble::{assemble_new, Tangent};
use crate::model::element::{distributed_load, follower_load, internal_force, momentum, LocalMat};
use crate::model::loads::{LoadFrame, Loads};
use crate::model::material::RodProperties;
use crate::model::mesh::{DofMap, Field, Mesh, QuadratureScheme};

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
    pub fn new(mesh: Mesh, props: RodProperties, scheme: QuadratureScheme, loads: &'a Loads) -> Self {
        Problem { mesh, props, scheme, loads, load_factor: 1.0 }
    }

    /// Layout of the unknowns `(x, α)`.
    pub fn dofs(&self) -> DofMap {
        self.mesh.dofs()
    }

    /// Reference configuration: straight along e3, `x0(s) = (0, 0, s)`, `α = 0` (D1).
    pub fn reference_state(&self) -> DVector<f64> {
        let dofs = self.dofs();
        let mut u = dofs.zeros();
        for i in 0..self.mesh.nodes() {
            u[dofs.index(i, Field::X, 2)] = self.mesh.node_s(i);
        }
        u
    }

    /// Unknowns fixed by the clamp at s = 0 (D3): all six of node 0.
    pub fn clamped_dofs(&self) -> Vec<usize> {
        (0..self.dofs().block()).collect()
    }

    /// External load vector `F(t)` of D3 (distributed + end loads) for global-frame loads;
    /// follower loads are evaluated in the reference configuration (use [`Problem::loads_at`]).
    pub fn external_force(&self, t: f64) -> DVector<f64> {
        self.loads_at(&self.reference_state(), t, None)
    }

    /// External load vector `F(u, t)` of D3; follower (local-frame) distributed loads depend on
    /// `u` through `Qᵀ(α)`, and a `tangent` then receives `scale · ∂F/∂u`. Scaled by
    /// `load_factor`.
    pub fn loads_at(&self, u: &DVector<f64>, t: f64, tangent: Option<Tangent<'_>>) -> DVector<f64> {
        let h = self.mesh.h();
        let lf = self.load_factor;
        let dofs = self.dofs();
        let mut field = |s: f64| {
            let (f, l) = self.loads.distributed(s, t);
            (f * lf, l * lf)
        };
        let mut f = match (self.loads.has_distributed(), self.loads.frame) {
            (false, _) => dofs.zeros(),
            (true, LoadFrame::Global) => {
                assemble_new(&dofs, None, |e, _| distributed_load(self.scheme, h, self.mesh.node_s(e), &mut field))
            }
            (true, LoadFrame::Local) => assemble_new(&dofs, tangent, |e, t| {
                follower_load(self.scheme, h, self.mesh.node_s(e), &dofs.gather(u, e), &mut field, t)
            }),
        };
        let (fe, le) = self.loads.end(t);
        let (fe, le) = (fe * lf, le * lf);
        let last = self.mesh.nodes() - 1;
        for k in 0..3 {
            f[dofs.index(last, Field::X, k)] += fe[k];
            f[dofs.index(last, Field::Alpha, k)] += le[k];
        }
        f
    }

    /// Internal force `G(u)`; a `tangent` also receives `scale · ∂G/∂u`.
    pub fn internal_force(&self, u: &DVector<f64>, tangent: Option<Tangent<'_>>) -> DVector<f64> {
        let h = self.mesh.h();
        let dofs = self.dofs();
        assemble_new(&dofs, tangent, |e, t| internal_force(&self.props, self.scheme, h, &dofs.gather(u, e), t))
    }

    /// Momentum `P(u, u̇)` of D6; `tangent = Some((t, scale_udot))` receives
    /// `t.scale · ∂P/∂u + scale_udot · ∂P/∂u̇`.
    pub fn momentum(&self, u: &DVector<f64>, udot: &DVector<f64>, tangent: Option<(Tangent<'_>, f64)>) -> DVector<f64> {
        let h = self.mesh.h();
        let dofs = self.dofs();
        // One element matrix out of two scaled kernel tangents: `su ∂P/∂u + sv ∂P/∂u̇`, added
        // with scale 1.
        let (tangent, su, sv) = match tangent {
            Some((t, sv)) => {
                let su = t.scale;
                (Some(Tangent { scale: 1.0, ..t }), su, sv)
            }
            None => (None, 0.0, 0.0),
        };
        let mut dv = LocalMat::zeros();
        assemble_new(&dofs, tangent, |e, t| {
            let (ue, ve) = (dofs.gather(u, e), dofs.gather(udot, e));
            match t {
                Some(du) => {
                    dv.as_mut_slice().fill(0.0);
                    let r = momentum(&self.props, self.scheme, h, &ue, &ve, Some(du), Some(&mut dv));
                    *du = *du * su + dv * sv;
                    r
                }
                None => momentum(&self.props, self.scheme, h, &ue, &ve, None, None),
            }
        })
    }

    /// Infinity norm over the unknowns that are not clamped.
    pub fn free_norm_inf(&self, r: &DVector<f64>) -> f64 {
        let fixed = self.clamped_dofs();
        r.iter().enumerate().filter(|(i, _)| !fixed.contains(i)).fold(0.0, |m, (_, v)| m.max(v.abs()))
    }

    /// Newton increment measure of D5/D6: `max(‖δx‖∞ / L, ‖δα‖∞)`.
    pub fn increment_measure(&self, du: &DVector<f64>) -> f64 {
        let (dx, da) = self.dofs().split_norms_inf(du);
        (dx / self.mesh.length_m).max(da)
    }
}
