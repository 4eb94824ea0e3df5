//! The KKT system of the fixed point (`docs/inverse.md`, I4) element by element, and the
//! boundary conditions of I5. Element vectors and matrices have the KKT layout of two nodes,
//! `[x, α, x̂, α̂]` per node (24 unknowns).
use nalgebra::{DVector, Matrix3, SMatrix, SVector, Vector3};

use super::tracking::weight_at;
use super::{Frame, FrameProblem, InverseParams};
use crate::assemble::{assemble, Tangent};
use crate::linalg::Pattern;
use crate::model::element::{frozen_operator, interpolate, ElementRest, LocalMat, LocalVec};
use crate::model::mesh::{DofMap, Field, GAUSS2};
use crate::model::rotation::{a_matrix, d3, rotation_derivatives};
use crate::solve::certificate::{of_system, Certificate};
use crate::solve::Problem;

/// Element matrix of the KKT system (24 × 24).
pub type KktMat = SMatrix<f64, 24, 24>;
/// Element vector of the KKT system (24).
pub type KktVec = SVector<f64, 24>;

/// Layout of a KKT element vector and of a forward element vector.
pub(crate) const LOCAL: DofMap = DofMap::kkt(2);
const FORWARD: DofMap = DofMap::forward(2);
/// Offsets of the fields of the element's two nodes in a KKT element vector.
pub(crate) const X: [usize; 2] = [LOCAL.local(0, Field::X, 0), LOCAL.local(1, Field::X, 0)];
pub(crate) const AL: [usize; 2] = [LOCAL.local(0, Field::Alpha, 0), LOCAL.local(1, Field::Alpha, 0)];
const XH: [usize; 2] = [LOCAL.local(0, Field::XHat, 0), LOCAL.local(1, Field::XHat, 0)];
const ALH: [usize; 2] = [LOCAL.local(0, Field::AlphaHat, 0), LOCAL.local(1, Field::AlphaHat, 0)];

/// Which half of the KKT unknowns (eq. 61): the state `(x, α)` or its adjoint `(x̂, α̂)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    State,
    Adjoint,
}

/// The KKT element index of forward element index `i` (`[x_a, α_a, x_b, α_b]`) in `part`
/// (the adjoint's copy: x → x̂, α → α̂).
#[inline]
pub(crate) fn kkt(i: usize, part: Part) -> usize {
    match part {
        Part::State => KKT_STATE[i],
        Part::Adjoint => KKT_HAT[i],
    }
}

const fn kkt_index(i: usize, part: Part) -> usize {
    let position = i % FORWARD.block() < 3;
    let field = match (position, part) {
        (true, Part::State) => Field::X,
        (true, Part::Adjoint) => Field::XHat,
        (false, Part::State) => Field::Alpha,
        (false, Part::Adjoint) => Field::AlphaHat,
    };
    LOCAL.local(i / FORWARD.block(), field, i % 3)
}

const fn kkt_table(part: Part) -> [usize; 12] {
    let mut t = [0; 12];
    let mut i = 0;
    while i < 12 {
        t[i] = kkt_index(i, part);
        i += 1;
    }
    t
}

const KKT_STATE: [usize; 12] = kkt_table(Part::State);
const KKT_HAT: [usize; 12] = kkt_table(Part::Adjoint);
// `add_operator_blocks` relies on this layout: forward unknown i of node a at 12 a + i % 6,
// its adjoint 6 further
const _: () = {
    let mut i = 0;
    while i < 12 {
        assert!(KKT_STATE[i] == 12 * (i / 6) + i % 6 && KKT_HAT[i] == KKT_STATE[i] + 6);
        i += 1;
    }
};

/// The state or the adjoint `part` of a KKT element vector, in the forward element layout.
pub(crate) fn element_part(ue: &KktVec, part: Part) -> LocalVec {
    LocalVec::from_fn(|i, _| ue[kkt(i, part)])
}

/// Points `(ξ, w)` of the λd term's rule (I11): `(1 − ε)` times the stretch–shear rule of the
/// scheme plus `ε` times 2-point Gauss (at most 2 + 2 points, no allocation). A one-rule scheme
/// (`QuadratureScheme::is_one_rule`) has its one rule here and no blend (its ε is 0, checked
/// when a case is read).
#[derive(Clone, Copy, Debug)]
pub struct PointRule {
    points: [(f64, f64); 4],
    len: usize,
}

impl PointRule {
    /// The λd rule of `problem`'s scheme with stabilisation `eps`.
    pub fn tangent(problem: &Problem, eps: f64) -> Self {
        let base = problem.scheme.stretch_shear();
        let mut rule = PointRule { points: [(0.0, 0.0); 4], len: 0 };
        let mut push = |x: f64, w: f64| {
            if w != 0.0 {
                rule.points[rule.len] = (x, w);
                rule.len += 1;
            }
        };
        for (x, w) in base.iter() {
            push(x, w * (1.0 - eps));
        }
        if eps > 0.0 && !problem.scheme.is_one_rule() {
            for (x, w) in GAUSS2.iter() {
                push(x, w * eps);
            }
        }
        rule
    }

    pub fn iter(&self) -> impl Iterator<Item = (f64, f64)> + Clone + '_ {
        self.points[..self.len].iter().copied()
    }
}

/// `∂d3/∂α = [0 | d_β | d_γ]` (eqs. 56–58).
pub(crate) fn d3_jacobian(alpha: &Vector3<f64>) -> Matrix3<f64> {
    let dq = rotation_derivatives(alpha);
    Matrix3::from_columns(&[dq[0].row(2).transpose(), dq[1].row(2).transpose(), dq[2].row(2).transpose()])
}

/// Where [`add_operator_blocks`] adds a forward-layout element matrix.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Blocks {
    /// the adjoint rows × state columns only (a Jacobian's linearised operator)
    AdjointRows,
    /// those and the transpose into the state rows × adjoint columns (the symmetric KKT matrix)
    WithTranspose,
}

/// Add a forward-layout element matrix `l` (12 × 12) into the adjoint rows × state columns of a
/// KKT element matrix, `m[kkt(i, Adjoint), kkt(j, State)] += l[i, j]`, and, with
/// [`Blocks::WithTranspose`], its transpose into the state rows × adjoint columns: 6 × 6 blocks
/// per pair of nodes (a node's forward unknowns `[x, α]` are the first six of its KKT block, the
/// adjoint's the last six).
pub(crate) fn add_operator_blocks(m: &mut KktMat, l: &LocalMat, blocks: Blocks) {
    const B: usize = 6;
    for a in 0..2 {
        for c in 0..2 {
            let blk = l.fixed_view::<B, B>(B * a, B * c);
            let mut adj_rows = m.fixed_view_mut::<B, B>(2 * B * a + B, 2 * B * c);
            adj_rows += blk;
            if blocks == Blocks::WithTranspose {
                let mut state_rows = m.fixed_view_mut::<B, B>(2 * B * c, 2 * B * a + B);
                state_rows += blk.transpose();
            }
        }
    }
}

/// Add a 3 × 3 block at `(ro, co)`.
#[inline]
pub(crate) fn add3(m: &mut KktMat, ro: usize, co: usize, blk: &Matrix3<f64>) {
    let mut v = m.fixed_view_mut::<3, 3>(ro, co);
    v += blk;
}

/// Add `s I` (3 × 3) at `(ro, co)`: the diagonal only.
#[inline]
fn add_diagonal3(m: &mut KktMat, ro: usize, co: usize, s: f64) {
    for i in 0..3 {
        m[(ro + i, co + i)] += s;
    }
}

/// Local KKT matrix (added into `m`, which the caller zeroes) and right-hand side (returned)
/// of element `e` of eq. (61) (`docs/inverse.md`, I4) in the frame's problem `fp`,
/// coefficients frozen at the element's state `uk`; from `fp` at the element's nodes: the data
/// `x_g`, the previous frame's angles (no Λω term on a first frame) and the nodal weights of
/// the tracking term (I14: `λg ∫ w δx·(x − x_g)`, w P1). Also returns the frozen operator `L(u)` of the element
/// (`element::frozen_operator`), which the Newton Jacobian needs again. The terms are added in
/// this order: the frozen operator, the objective rule's terms ([`objective_terms`]), the λd
/// term ([`lambda_d_term`], I11), the Λκ term ([`lambda_kappa_term`], I12).
pub(crate) fn element_system(fp: &FrameProblem<'_>, e: usize, uk: &LocalVec, m: &mut KktMat) -> (KktVec, LocalMat) {
    let FrameProblem { problem, params: p, frame, alpha_prev } = *fp;
    let (xg, wg) = frame.tracking().element(e);
    let h = problem.mesh.h();
    let mut r = KktVec::zeros();
    // Frozen operator: primal rows (hat test) × state columns, and its transpose.
    // (the inverse problem keeps the straight reference, D20)
    let (l, b) = frozen_operator(&problem.props, problem.scheme, h, uk, &ElementRest::ZERO);
    for i in 0..12 {
        r[kkt(i, Part::Adjoint)] += b[i];
    }
    add_operator_blocks(m, &l, Blocks::WithTranspose);
    let nodal = NodalData { xg, wg, alpha_prev: [alpha_prev[e], alpha_prev[e + 1]] };
    objective_terms(fp, uk, &nodal, m, &mut r);
    lambda_d_term(problem, p, uk, m, &mut r);
    lambda_kappa_term(problem, p, uk, m);
    (r, l)
}

/// What an element's terms of eq. (61) know of the frame at its two nodes.
struct NodalData {
    /// the data x_g [m]
    xg: [Vector3<f64>; 2],
    /// the weights w of the tracking term (I14, dimensionless)
    wg: [f64; 2],
    /// the previous frame's angles α_{n−1} [rad] (the Λω term)
    alpha_prev: [Vector3<f64>; 2],
}

/// Mass-type terms of eq. (61) on the objective rule: the tracking term
/// `λg ∫ w δx·(x − x_g)` (I14), the control costs `−∫ δx̂·x̂ / λf` and `−∫ δα̂·α̂ / λl`, and the
/// Λω term `∫ δα·AᵀΛωA (α − α_{n−1}) / Δt²` (none on the first frame of `fp`).
#[allow(non_snake_case)] // paper symbols W, A
fn objective_terms(fp: &FrameProblem<'_>, uk: &LocalVec, nodal: &NodalData, m: &mut KktMat, r: &mut KktVec) {
    let FrameProblem { problem, params: p, frame, .. } = *fp;
    let first_frame = frame.is_first();
    let h = problem.mesh.h();
    let w8 = &p.weights;
    let NodalData { xg, wg, alpha_prev } = nodal;
    let omega_on = !first_frame && w8.lambda_omega.amax() > 0.0;
    let dt = p.frame_interval_s;
    for (xi, w) in problem.scheme.objective().iter() {
        let q = interpolate(uk, h, xi);
        let n = q.n;
        let wh = w * h;
        let xg_q = xg[0] * n[0] + xg[1] * n[1];
        // λg w at the point: the one place the tracking weight enters (I14)
        let lg = w8.lambda_g * weight_at(*wg, n);
        let ap_q = alpha_prev[0] * n[0] + alpha_prev[1] * n[1];
        let W = if omega_on {
            let A = a_matrix(&q.alpha);
            A.transpose() * Matrix3::from_diagonal(&w8.lambda_omega) * A / (dt * dt)
        } else {
            Matrix3::zeros()
        };
        for a in 0..2 {
            for i in 0..3 {
                r[X[a] + i] += wh * n[a] * lg * xg_q[i];
            }
            let wa = W * ap_q * (wh * n[a]);
            for i in 0..3 {
                r[AL[a] + i] += wa[i];
            }
            for c in 0..2 {
                let nn = wh * n[a] * n[c];
                add_diagonal3(m, X[a], X[c], lg * nn);
                add_diagonal3(m, XH[a], XH[c], -nn / w8.lambda_f);
                add_diagonal3(m, ALH[a], ALH[c], -nn / w8.lambda_l);
            }
        }
        // the (α, α) blocks W · wh n_a n_c
        add_node_pairs(m, (AL, AL), &W, wh, (&n, &n));
    }
}

/// λd term of eq. (61) on its rule (I11): `λd ∫ (∂sδx − D δα)·(∂s x − D α − d3^k + D α_k)`,
/// `D = ∂d3/∂α` frozen at the element's state.
#[allow(non_snake_case)] // paper symbol D
fn lambda_d_term(problem: &Problem, p: &InverseParams, uk: &LocalVec, m: &mut KktMat, r: &mut KktVec) {
    let h = problem.mesh.h();
    for (xi, w) in PointRule::tangent(problem, p.stabilisation).iter() {
        let q = interpolate(uk, h, xi);
        let wh = w * h * p.weights.lambda_d;
        let D = d3_jacobian(&q.alpha);
        let c = d3(&q.alpha) - D * q.alpha;
        // test operator of node a: (∂sδx, −D δα) = (dn_a I, −n_a D) applied to (δx, δα)
        let t_alpha = [-D * q.n[0], -D * q.n[1]];
        for a in 0..2 {
            let ta = &t_alpha[a];
            let tac = ta.transpose() * c;
            for i in 0..3 {
                r[X[a] + i] += wh * (q.dn[a] * c[i]);
                r[AL[a] + i] += wh * tac[i];
            }
            for cc in 0..2 {
                let tc = &t_alpha[cc];
                // the blocks (x, x), (x, α), (α, x), (α, α) of ta_rᵀ tc_c
                add_diagonal3(m, X[a], X[cc], q.dn[a] * q.dn[cc] * wh);
                add3(m, X[a], AL[cc], &(tc * q.dn[a] * wh));
                add3(m, AL[a], X[cc], &(ta.transpose() * q.dn[cc] * wh));
                add3(m, AL[a], AL[cc], &(ta.transpose() * tc * wh));
            }
        }
    }
}

/// Λκ term of eq. (61) on its rule (I12): `∫ ∂sδα · Aᵀ Λκ A ∂sα` (none when Λκ = 0).
#[allow(non_snake_case)] // paper symbols A, Kk
fn lambda_kappa_term(problem: &Problem, p: &InverseParams, uk: &LocalVec, m: &mut KktMat) {
    let lambda_kappa = &p.weights.lambda_kappa;
    if lambda_kappa.amax() > 0.0 {
        let h = problem.mesh.h();
        for (xi, w) in problem.scheme.kappa().iter() {
            let q = interpolate(uk, h, xi);
            let A = a_matrix(&q.alpha);
            let Kk = A.transpose() * Matrix3::from_diagonal(lambda_kappa) * A * (w * h);
            // Kk carries the weight w h: the blocks Kk · dn_a dn_c
            add_node_pairs(m, (AL, AL), &Kk, 1.0, (&q.dn, &q.dn));
        }
    }
}

/// `m[rows[c], cols[b]] += blk · (wh f_c g_b)` for the element's two nodes c and b (`rows`,
/// `cols`: the local offsets of a field at the two nodes; `f`, `g`: shape functions or their
/// derivatives at the point).
pub(crate) fn add_node_pairs(
    m: &mut KktMat,
    (rows, cols): ([usize; 2], [usize; 2]),
    blk: &Matrix3<f64>,
    wh: f64,
    (f, g): (&[f64; 2], &[f64; 2]),
) {
    for c in 0..2 {
        for b in 0..2 {
            add3(m, rows[c], cols[b], &(blk * (wh * f[c] * g[b])));
        }
    }
}

/// Dirichlet unknowns of I5 (KKT layout) with their values: `x = x_g` and `x̂ = α̂ = 0` at
/// both ends, and on the first frame `α(0) = α0` (first angle only, Remark 6; on every frame of
/// a planar recording, [`Frame::fix_roll`]).
pub fn dirichlet(dofs: &DofMap, alpha0: f64, frame: &Frame) -> Vec<(usize, f64)> {
    let mut fixed = Vec::new();
    dirichlet_into(dofs, alpha0, frame, &mut fixed);
    fixed
}

/// [`dirichlet`] into a reused vector (cleared first).
pub(crate) fn dirichlet_into(dofs: &DofMap, alpha0: f64, frame: &Frame, fixed: &mut Vec<(usize, f64)>) {
    fixed.clear();
    let last = frame.x_g.len() - 1;
    for node in [0, last] {
        for k in 0..3 {
            fixed.push((dofs.index(node, Field::X, k), frame.x_g[node][k]));
        }
        for field in [Field::XHat, Field::AlphaHat] {
            for k in 0..3 {
                fixed.push((dofs.index(node, field, k), 0.0));
            }
        }
    }
    if frame.fixes_alpha0() {
        fixed.push((dofs.index(0, Field::Alpha, 0), alpha0));
    }
}

/// Assemble the KKT matrix (replacing `values`) and right-hand side of I4 with the
/// coefficients frozen at the state `u` (forward layout); boundary conditions not applied.
pub fn assemble_system(fp: FrameProblem<'_>, pattern: &Pattern, values: &mut [f64], u: &DVector<f64>) -> DVector<f64> {
    let problem = fp.problem;
    let fwd = problem.dofs();
    let kkt_dofs = problem.mesh.kkt_dofs();

    let mut rhs = kkt_dofs.zeros();
    let mut scratch = KktMat::zeros();
    assemble(&kkt_dofs, &mut rhs, Some(Tangent::overwriting(pattern, values, 1.0)), |e, t| {
        let uk: LocalVec = fwd.gather(u, e);
        let m = t.unwrap_or(&mut scratch);
        element_system(&fp, e, &uk, m).0
    });
    rhs
}

/// The residual certificate (`solve::certificate`, `docs/certificate.md`) of the KKT vector
/// `big` for `frame`: the block backward error of `R(U) = K(u) U − r(u)` of I4/I8 with every
/// coefficient at the state of `big` itself, against `|K(u)| |U| + |r(u)|`, positions measured
/// from the data's first node (so that a translation of the data leaves it unchanged).
/// `values`: scratch of `pattern`'s size.
pub fn certificate(fp: FrameProblem<'_>, big: &DVector<f64>, pattern: &Pattern, values: &mut [f64]) -> Certificate {
    let FrameProblem { problem, params: p, frame, .. } = fp;
    let kd = problem.mesh.kkt_dofs();
    let origin = frame.x_g[0];
    let x_g: Vec<Vector3<f64>> = frame.x_g.iter().map(|x| x - origin).collect();
    let mut big = big.clone();
    for node in 0..kd.nodes() {
        let x = kd.get(&big, node, Field::X) - origin;
        kd.set(&mut big, node, Field::X, &x);
    }
    let shifted = Frame { x_g: &x_g, ..*frame };
    let u = kd.kkt_state(&big);
    let shifted_fp = FrameProblem { frame: &shifted, ..fp };
    let mut rhs = assemble_system(shifted_fp, pattern, values, &u);
    let fixed = dirichlet(&kd, p.alpha0_rad, &shifted);
    for &(d, v) in &fixed {
        rhs[d] = v;
    }
    let rows: Vec<usize> = fixed.iter().map(|f| f.0).collect();
    pattern.set_identity_rows(values, &rows);
    of_system(&kd, pattern, values, &big, &rhs)
}
