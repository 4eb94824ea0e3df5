//! The discrete forward problem of D3: mesh, coefficients, quadrature, loads and the rod's
//! reference and ends (D20–D23), and its global vectors and tangents, each one pass of the element
//! loop with a kernel of `model::element`.
use nalgebra::DVector;

use crate::assemble::{assemble_new, Tangent};
use crate::model::balance::{element_balance, Balance};
use crate::model::chart::Chart;
use crate::model::element::{
    distributed_load, follower_load, internal_force, momentum, point_shape, ElementRest, LocalMat, MomentumDerivatives,
};
use crate::model::ends::{EndKind, Ends, MotionAt};
use crate::model::geometry::Rod;
use crate::model::loads::{LoadFrame, Loads};
use crate::model::material::RodProperties;
use crate::model::mesh::{DofMap, Field, Mesh, QuadratureScheme};
use crate::model::rotation::rotation_derivatives;

/// The discrete forward problem: mesh, coefficients, quadrature and loads.
#[derive(Clone, Copy)]
pub struct Problem<'a> {
    pub mesh: Mesh,
    pub props: RodProperties,
    pub scheme: QuadratureScheme,
    pub loads: &'a Loads,
    /// factor applied to every load (load continuation), 1 by default
    pub load_factor: f64,
    /// the rod's reference configuration in its chart and its ends (D20–D22); `None`: the
    /// paper's rod, straight along e3 from the origin, clamped at s = 0 and free at s = L
    pub rod: Option<&'a Rod>,
}

/// The held unknowns of a problem (Dirichlet rows, D22) and their values.
#[derive(Clone, Debug, PartialEq)]
pub struct Held {
    /// indices of the held unknowns, ascending
    pub dofs: Vec<usize>,
    /// their values, in the same order
    pub values: Vec<f64>,
    /// nodes of pinned ends whose twist is held: their moment rows are combined with the frame
    /// before the α row is replaced ([`Problem::apply_held`])
    pub twist_nodes: Vec<usize>,
}

/// How the held rows enter a system ([`Problem::apply_held`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HeldRows<'a> {
    /// Newton's residual of a static step at the state `u`: `u_d − value_d`
    Residual(&'a DVector<f64>),
    /// a time step's residual, whose held unknowns already hold their values: 0
    Zero,
    /// the right-hand side of the fixed point's frozen system: `value_d`
    Values,
}

/// The combination of a twist-held pin's three moment rows at angles `a` (D22,
/// [`Problem::apply_held`]): `t` (row 0 `e_c`, replaced by the held α; rows 1, 2
/// `e_r − (d3_r/d3_c) e_c`), the component `c` of largest `|d3_c|` and the other two.
pub struct TwistRows {
    pub t: [[f64; 3]; 3],
    pub c: usize,
    pub others: [usize; 2],
}

/// [`TwistRows`] at the angles `a`.
pub fn twist_rows(a: &crate::model::rotation::Angles) -> TwistRows {
    let d3 = crate::model::rotation::d3(a);
    let c = d3.iamax();
    let others = [(c + 1) % 3, (c + 2) % 3];
    let others = [others[0].min(others[1]), others[0].max(others[1])];
    let mut t = [[0.0; 3]; 3];
    t[0][c] = 1.0;
    for (j, &rk) in others.iter().enumerate() {
        t[j + 1][rk] = 1.0;
        t[j + 1][c] = -d3[rk] / d3[c];
    }
    TwistRows { t, c, others }
}

/// The state whose frame combines the moment rows of a twist-held pin, and its derivative with
/// respect to the unknowns (1 for the state itself, ½ for a time step's midpoint state).
#[derive(Clone, Copy, Debug)]
pub struct FrameAt<'a> {
    pub state: &'a DVector<f64>,
    pub rate: f64,
}

impl<'a> FrameAt<'a> {
    /// The state itself.
    pub fn of(state: &'a DVector<f64>) -> Self {
        FrameAt { state, rate: 1.0 }
    }
}

impl Held {
    /// Write the held values into `u`.
    pub fn impose(&self, u: &mut DVector<f64>) {
        for (&d, &v) in self.dofs.iter().zip(&self.values) {
            u[d] = v;
        }
    }
}

impl<'a> Problem<'a> {
    pub fn new(mesh: Mesh, props: RodProperties, scheme: QuadratureScheme, loads: &'a Loads) -> Self {
        Problem { mesh, props, scheme, loads, load_factor: 1.0, rod: None }
    }

    /// The same problem on a rod with a reference and ends of its own (D20–D22).
    pub fn on_rod(self, rod: Option<&'a Rod>) -> Self {
        Problem { rod, ..self }
    }

    /// The chart the problem is posed in (D21): the paper's unless the rod has its own.
    pub fn chart(&self) -> Chart {
        self.rod.map(|r| r.rest.chart).unwrap_or_default()
    }

    /// The ends (D22).
    pub fn ends(&self) -> &Ends {
        self.rod.map(|r| &r.ends).unwrap_or(&Ends::CLAMPED_FREE)
    }

    /// The reference strains of element `e` (D20).
    pub fn rest(&self, e: usize) -> &ElementRest {
        self.rod.map(|r| &r.rest.strains[e]).unwrap_or(&ElementRest::ZERO)
    }

    /// Layout of the unknowns `(x, α)`.
    pub fn dofs(&self) -> DofMap {
        self.mesh.dofs()
    }

    /// Reference configuration in the problem's chart: the rod's (D20), or the paper's straight
    /// rod along e3, `x0(s) = (0, 0, s)`, `α = 0` (D1).
    pub fn reference_state(&self) -> DVector<f64> {
        if let Some(rod) = self.rod {
            return rod.rest.state.clone();
        }
        let dofs = self.dofs();
        let mut u = dofs.zeros();
        for i in 0..self.mesh.nodes() {
            u[dofs.index(i, Field::X, 2)] = self.mesh.node_s(i);
        }
        u
    }

    /// The held unknowns of both ends (D22), ascending: all six of node 0 for the paper's clamp.
    pub fn clamped_dofs(&self) -> Vec<usize> {
        let dofs = self.dofs();
        let mut held = Vec::new();
        for (end, node) in self.ends().with_nodes(self.mesh.nodes()) {
            for (c, on) in end.kind.held().iter().enumerate() {
                if *on {
                    held.push(dofs.block() * node + c);
                }
            }
        }
        held
    }

    /// The held unknowns and their values at `at` (D22): the reference's, or a moving end's
    /// prescribed position and angles. `prev`: the state of the previous time step (its held
    /// angles guide the unwrapping of a dynamic rotation); the reference if `None`.
    pub fn held(&self, at: MotionAt, prev: Option<&DVector<f64>>) -> Held {
        let dofs = self.dofs();
        let reference = self.reference_state();
        let mut values_of = reference.clone();
        if let Some(rod) = self.rod {
            for (end, node) in rod.ends.with_nodes(self.mesh.nodes()) {
                let Some(motion) = &end.motion else { continue };
                let r = rod.rest.end_reference(&self.mesh, node);
                let near = prev.map(|p| dofs.get(p, node, Field::Alpha)).unwrap_or(r.angles);
                let (x, a) = motion.target(&r, &rod.rest.chart, at, &near);
                dofs.set(&mut values_of, node, Field::X, &x);
                dofs.set(&mut values_of, node, Field::Alpha, &a);
            }
        }
        let held = self.clamped_dofs();
        let values = held.iter().map(|&d| values_of[d]).collect();
        let twist_nodes = self
            .ends()
            .with_nodes(self.mesh.nodes())
            .into_iter()
            .filter(|(e, _)| e.kind == EndKind::Pinned { twist_held: true })
            .map(|(_, node)| node)
            .collect();
        Held { dofs: held, values, twist_nodes }
    }

    /// The held unknowns applied to a system (D22): `r` is a residual or a right-hand side
    /// (`rows` says which, with the state of a residual) and `values`, if given, its matrix in
    /// `pattern`; `frame` is the state whose d3 combines the rows of a twist-held pin.
    ///
    /// The paper tests the moment balance with δα (D9): row c of a node is the global (chart)
    /// component c of its moment balance `M`, as an end torque enters `δα·L`. A clamp replaces
    /// all three rows, which pairs them correctly. Holding α of a pin (the roll about d3) adds a
    /// reaction torque `μ d3` to all three rows, so with `c*` the component of largest `|d3_c|`
    /// they become `α = target`, `M_r1 − (d3_r1/d3_c*) M_c*`, `M_r2 − (d3_r2/d3_c*) M_c*` (the
    /// reaction eliminated, `r1 < r2` the other two components) in the rows of α, β, γ. A Newton
    /// matrix (`Residual`, `Zero`) also gets the derivative of the coefficients, times `M_c*`.
    pub fn apply_held(
        &self,
        pattern: &crate::linalg::Pattern,
        mut values: Option<&mut [f64]>,
        r: &mut DVector<f64>,
        held: &Held,
        rows: HeldRows,
        frame: FrameAt,
    ) {
        let dofs = self.dofs();
        for &node in &held.twist_nodes {
            let i0 = dofs.index(node, Field::Alpha, 0);
            let a = dofs.get(frame.state, node, Field::Alpha);
            let d3 = crate::model::rotation::d3(&a);
            let TwistRows { t, c, others } = twist_rows(&a);
            let m = [r[i0], r[i0 + 1], r[i0 + 2]];
            for k in 0..3 {
                r[i0 + k] = t[k][0] * m[0] + t[k][1] * m[1] + t[k][2] * m[2];
            }
            if let Some(v) = values.as_deref_mut() {
                pattern.combine_rows(v, [i0, i0 + 1, i0 + 2], &t);
                if rows != HeldRows::Values {
                    let dq = rotation_derivatives(&a);
                    for (kk, dqk) in dq.iter().enumerate() {
                        let dd = dqk.row(2).transpose();
                        for (j, &rk) in others.iter().enumerate() {
                            // ∂(−d3_r/d3_c)/∂α_k · M_c
                            let coef = -(dd[rk] * d3[c] - d3[rk] * dd[c]) / (d3[c] * d3[c]);
                            let pos = pattern.position(i0 + j + 1, i0 + kk).expect("a node's own block");
                            v[pos] += frame.rate * coef * m[c];
                        }
                    }
                }
            }
        }
        for (&d, &v) in held.dofs.iter().zip(&held.values) {
            r[d] = match rows {
                HeldRows::Residual(u) => u[d] - v,
                HeldRows::Zero => 0.0,
                HeldRows::Values => v,
            };
        }
        if let Some(v) = values {
            pattern.set_identity_rows(v, &held.dofs);
        }
    }

    /// The held unknowns of a static problem at its load factor.
    pub fn held_static(&self) -> Held {
        self.held(MotionAt::Static { load_factor: self.load_factor }, None)
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
        let mut tangent = tangent;
        let h = self.mesh.h();
        let lf = self.load_factor;
        let dofs = self.dofs();
        let chart = self.chart();
        let rotate = !chart.is_identity() && self.loads.frame == LoadFrame::Global;
        let mut field = |s: f64| {
            let (f, l) = self.loads.distributed(s, t);
            if rotate {
                (chart.to_chart(&f) * lf, chart.to_chart(&l) * lf)
            } else {
                (f * lf, l * lf)
            }
        };
        let mut f = match (self.loads.has_distributed(), self.loads.frame) {
            (false, _) => dofs.zeros(),
            (true, LoadFrame::Global) => {
                assemble_new(&dofs, None, |e, _| distributed_load(self.scheme, h, self.mesh.node_s(e), &mut field))
            }
            (true, LoadFrame::Local) => assemble_new(&dofs, tangent.as_mut().map(Tangent::reborrow), |e, t| {
                follower_load(self.scheme, h, self.mesh.node_s(e), &dofs.gather(u, e), &mut field, t)
            }),
        };
        let (fe, le) = self.loads.end(t);
        let (fe, le) = if chart.is_identity() { (fe, le) } else { (chart.to_chart(&fe), chart.to_chart(&le)) };
        let (fe, le) = (fe * lf, le * lf);
        let last = self.mesh.nodes() - 1;
        for k in 0..3 {
            f[dofs.index(last, Field::X, k)] += fe[k];
            f[dofs.index(last, Field::Alpha, k)] += le[k];
        }
        self.add_point_loads(&mut f, u, t, tangent);
        f
    }

    /// The point loads of D23 at time `t` into `f` (scaled by the load factor); follower ones at
    /// the state `u`, their derivative into `tangent` if given.
    fn add_point_loads(&self, f: &mut DVector<f64>, u: &DVector<f64>, t: f64, mut tangent: Option<Tangent<'_>>) {
        let (dofs, lf, chart) = (self.dofs(), self.load_factor, self.chart());
        for p in &self.loads.point {
            let (e, xi) = self.mesh.locate(p.s_m);
            let (force, torque) = (p.force.at(p.s_m, t) * lf, p.torque.at(p.s_m, t) * lf);
            let (local, mut mat) = match p.frame {
                LoadFrame::Global => (point_shape(xi, &chart.to_chart(&force), &chart.to_chart(&torque)), None),
                LoadFrame::Local => {
                    let mut m = LocalMat::zeros();
                    let want = tangent.is_some();
                    let v = crate::model::element::follower_point_load(
                        xi,
                        &dofs.gather(u, e),
                        &force,
                        &torque,
                        want.then_some(&mut m),
                    );
                    (v, want.then_some(m))
                }
            };
            dofs.add_element(f, e, &local);
            if let (Some(t), Some(m)) = (tangent.as_mut(), mat.as_mut()) {
                if t.scale != 1.0 {
                    *m *= t.scale;
                }
                t.pattern.scatter(t.values, e, m);
            }
        }
    }

    /// Internal force `G(u)`; a `tangent` also receives `scale · ∂G/∂u`.
    pub fn internal_force(&self, u: &DVector<f64>, tangent: Option<Tangent<'_>>) -> DVector<f64> {
        let h = self.mesh.h();
        let dofs = self.dofs();
        assemble_new(&dofs, tangent, |e, t| {
            internal_force(&self.props, self.scheme, h, &dofs.gather(u, e), self.rest(e), t)
        })
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
                    let both = MomentumDerivatives { d_u: Some(&mut *du), d_udot: Some(&mut dv) };
                    let r = momentum(&self.props, self.scheme, h, &ue, &ve, both);
                    *du = *du * su + dv * sv;
                    r
                }
                None => momentum(&self.props, self.scheme, h, &ue, &ve, MomentumDerivatives::default()),
            }
        })
    }

    /// The energy and the momenta of the state `u` with rates `udot` (both in the problem's
    /// chart), the momenta in space coordinates (D21; [`crate::model::balance`]).
    pub fn balance(&self, u: &DVector<f64>, udot: &DVector<f64>) -> Balance {
        let h = self.mesh.h();
        let dofs = self.dofs();
        let mut sum = Balance::default();
        for e in 0..self.mesh.elements {
            let (ue, ve) = (dofs.gather(u, e), dofs.gather(udot, e));
            sum += element_balance(&self.props, self.scheme, h, (&ue, &ve), self.rest(e));
        }
        let chart = self.chart();
        if chart.is_identity() {
            sum
        } else {
            sum.rotated(&chart.base.transpose())
        }
    }

    /// Infinity norm over the unknowns that are not held.
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::Expr;
    use crate::model::ends::End;
    use crate::model::geometry::{RestShape, RestSpec};
    use crate::model::loads::VectorExpr;
    use crate::model::material::Stiffnesses;
    use nalgebra::{Matrix3, Vector3};
    use std::collections::BTreeMap;

    /// The Newton system of a static step with a twist-held pinned end (D22): its matrix is the
    /// derivative of its residual, the frame's derivative included (central differences).
    #[test]
    fn the_held_rows_of_a_twisted_pin_are_differentiated_exactly() {
        let mesh = Mesh::new(2.0, 5);
        let z = || Expr::parse("0").unwrap();
        let spec = RestSpec {
            start_position_m: Vector3::zeros(),
            start_frame: Matrix3::identity(),
            curvature: VectorExpr::new([z(), Expr::parse("0.4").unwrap(), z()], &BTreeMap::new()).unwrap(),
        };
        let ends = Ends {
            start: End { kind: EndKind::Clamped, motion: None },
            end: End { kind: EndKind::Pinned { twist_held: true }, motion: None },
        };
        let rod = Rod { rest: RestShape::new(&mesh, &spec, None), ends };
        let s = Stiffnesses {
            ea_n: 50.0,
            ga_n: [20.0, 30.0],
            ei_nm2: [1.0, 2.0],
            gj_nm2: 0.7,
            rho_a_kg_per_m: None,
            rho_i_kg_m: None,
        };
        let loads = Loads::new(
            LoadFrame::Global,
            [z(), z(), z()],
            [z(), z(), z()],
            [z(), z(), z()],
            [z(), z(), z()],
            &BTreeMap::new(),
        )
        .unwrap();
        let p = Problem::new(mesh, RodProperties::from_stiffnesses(&s), QuadratureScheme::Selective, &loads)
            .on_rod(Some(&rod));
        let held = p.held_static();
        assert_eq!(held.twist_nodes, vec![5]);
        // a state far from the reference, so that the end node carries a moment
        let mut u = p.reference_state();
        for (i, v) in u.iter_mut().enumerate() {
            *v += 0.1 * ((i as f64) * 0.7).sin();
        }
        let pattern = p.dofs().pattern();
        let residual = |u: &DVector<f64>, values: Option<&mut [f64]>| {
            let mut values = values;
            let mut r = p.internal_force(u, values.as_deref_mut().map(|v| Tangent::new(&pattern, v, 1.0)));
            p.apply_held(&pattern, values, &mut r, &held, HeldRows::Residual(u), FrameAt::of(u));
            r
        };
        let mut values = vec![0.0; pattern.nnz()];
        let r0 = residual(&u, Some(&mut values));
        assert!(r0.amax() > 1e-2, "a loaded state");
        let k = pattern.to_dense(&values);
        let eps = 1e-6;
        for j in 0..u.len() {
            let (mut up, mut um) = (u.clone(), u.clone());
            up[j] += eps;
            um[j] -= eps;
            let col = (residual(&up, None) - residual(&um, None)) / (2.0 * eps);
            let err = (col - k.column(j)).amax();
            assert!(err < 1e-6 * k.amax(), "column {j}: {err:e}");
        }
    }
}
