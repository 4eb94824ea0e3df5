//! The rigid-motion equivariance of the inverse scheme (`docs/inverse.md` I10), measured on the
//! Rust fixed point with the eq. (64) data of §5.2 of Wang et al. (2023). Where our numbers
//! differ from the paper's text, the test asserts what we measured and its doc comment says so.
//! The regularisation findings (2)–(4) of §5.2 are judged by the quick audit (claims eq64-2,
//! eq64-3, eq64-4 of `cases/paper/sec52_eq64.toml`, `tests/audit.rs`); their sweeps as first
//! measured are `examples/eq64_findings.rs`.
mod common;

use common::fixed_point::{paper, run, Data};
use cosserat::engine::NodalState;
use cosserat::model::mesh::{DofMap, Field};
use cosserat::model::rotation::{angles_from_rotation, rotation};
use cosserat::solve::inverse::InverseParams;
use cosserat::solve::Problem;
use nalgebra::{DVector, Matrix3, Rotation3, Unit, Vector3};
use rayon::prelude::*;

/// Transform a state rigidly: `x → R x + c` and `Q → L Q Rᵀ` (directors are the rows of Q, so
/// a spatial rotation R acts on the right; L rotates the material frame about d3).
fn transform(u: &DVector<f64>, r: &Matrix3<f64>, l: &Matrix3<f64>, c: &Vector3<f64>) -> DVector<f64> {
    let mut v = u.clone();
    let dofs = DofMap::forward(u.len() / 6);
    for i in 0..dofs.nodes() {
        let (x, a) = (dofs.get(u, i, Field::X), dofs.get(u, i, Field::Alpha));
        dofs.set(&mut v, i, Field::X, &(r * x + c));
        dofs.set(&mut v, i, Field::Alpha, &angles_from_rotation(&(l * rotation(&a) * r.transpose())));
    }
    v
}

/// `(x, Q, κ, angles)` differences between `a` and the transform of `b`: max |x−(Rx_b+c)|/max|x_b|,
/// max |Q−L Q_b Rᵀ|, max |κ − L κ_b|/max |κ_b| (local curvature: Q′∂sQ′ᵀ = L Q∂sQᵀ Lᵀ), max |α−α_b|.
fn equivariance_error(
    p: &Problem,
    a: &DVector<f64>,
    b: &DVector<f64>,
    r: &Matrix3<f64>,
    l: &Matrix3<f64>,
    c: &Vector3<f64>,
) -> [f64; 4] {
    let mut e = [0.0f64; 4];
    let mut nx = 0.0f64;
    let dofs = p.dofs();
    for i in 0..dofs.nodes() {
        let (xa, aa) = (dofs.get(a, i, Field::X), dofs.get(a, i, Field::Alpha));
        let (xb, ab) = (dofs.get(b, i, Field::X), dofs.get(b, i, Field::Alpha));
        e[0] = e[0].max((xa - (r * xb + c)).norm());
        nx = nx.max(xb.norm());
        e[1] = e[1].max((rotation(&aa) - l * rotation(&ab) * r.transpose()).amax());
        e[3] = e[3].max((aa - ab).amax());
    }
    let kappa = |u: &DVector<f64>| -> Vec<Vector3<f64>> {
        NodalState::from_vector(&p.mesh, u).element_curvature().into_iter().map(|(_, k)| k).collect()
    };
    let (ka, kb) = (kappa(a), kappa(b));
    let nk = kb.iter().map(|k| k.norm()).fold(0.0, f64::max);
    e[2] = ka.iter().zip(&kb).map(|(x, y)| (x - l * y).norm()).fold(0.0, f64::max) / nk;
    e[0] /= nx;
    e
}

/// Rigid motions of the data (50 elements, 20 iterations from the transformed straight state).
///
/// With directors the rows of `Q = Rz(α) Rx(β) Ry(γ)` (`e = Q ∂s x − e3`), a spatial rotation R
/// maps `Q → Q Rᵀ`, and a constant rotation of the cross-section frame about d3 maps
/// `Q → Rz(θ) Q`. The chart turns exactly two of these into shifts of one angle:
/// `Rz(θ) Q(α, β, γ) = Q(α + θ, β, γ)` (frame relabelling; positions unchanged, with
/// α(0) = θ) and `Q(α, β, γ) Ry(φ)ᵀ = Q(α, β, γ − φ)` (spatial rotation about **e2**). With
/// translations these are exact symmetries of the discrete scheme (isotropic section,
/// Λκ1 = Λκ2). A spatial rotation about **e3** is *not* one: `Q Rz(θ)ᵀ` mixes all three angles,
/// although it is the obvious candidate.
///
/// Measured (x rel., max |Q′ − L Q Rᵀ|, κ rel., max angle change), after 1 | 20 iterations:
/// - translation c:           8.2e-16, 6.5e-13, 4.7e-11 | 6.5e-7, 6.6e-5, 1.2e-3
/// - relabelling Rz(0.7) + c: 7.7e-16, 7.2e-13, 4.3e-11 | 3.5e-7, 2.4e-5, 4.4e-4 (α + 0.7)
/// - spatial Ry(0.6) + c:     1.0e-15, 2.0e-13, 1.4e-11 | 4.2e-6, 1.8e-4, 3.4e-3 (γ − 0.6)
/// - spatial Rz(0.7) + c:     9.3e-16, 4.4e-2, 0.16     | 4.2e-4, 8.9e-3, 7.1e-2
/// - general R + c:           2.1e-15, 4.2e-2, 0.12     | 2.2e-2, 1.7, 1.0e3
///
/// (general R: axis (1, 2, 3), 0.5 rad; α0 from the chart of `Q(α_orig(0)) Rᵀ` — the product
/// `R Q` is the relabelling, not a spatial rotation, in this convention.) After one iteration
/// the symmetric cases agree to round-off; over 20 iterations the round-off differences grow
/// (the near-null β zig-zag of I8, now held by the stabilised λd rule at ε = 1e-3: with ε = 0
/// they were 3.5e-6 in Q after one iteration). The rotated non-symmetric runs are 20–1e4 times
/// further apart: this is not discretisation error — the Euler chart makes the scheme
/// orientation dependent.
#[test]
fn rigid_motions() {
    let d = Data::new(50);
    let p = d.problem();
    let u0 = p.reference_state();
    let i3 = Matrix3::identity();
    let c = Vector3::new(3e-4, -2e-4, 5e-4);
    let rz = *Rotation3::from_axis_angle(&Vector3::z_axis(), 0.7).matrix();
    let ry = *Rotation3::from_axis_angle(&Vector3::y_axis(), 0.6).matrix();
    let rg = *Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::new(1.0, 2.0, 3.0)), 0.5).matrix();
    let cases = [
        ("translation", i3, i3),
        ("relabel Rz(0.7)", i3, rz),
        ("spatial Ry(0.6)", ry, i3),
        ("spatial Rz(0.7)", rz, i3),
        ("general R", rg, i3),
    ];
    let errors = |iterations: usize| -> Vec<[f64; 4]> {
        let params = InverseParams { tolerance: 0.0, max_iterations: iterations, ..paper() };
        let orig = run(&d, &params, &d.xg, &u0, false);
        assert_eq!(orig.iterations(), iterations);
        let errs: Vec<[f64; 4]> = cases
            .par_iter()
            .map(|(_, r, l)| {
                let xg: Vec<Vector3<f64>> = d.xg.iter().map(|x| r * x + c).collect();
                let a0 = p.dofs().get(&orig.u, 0, Field::Alpha);
                let alpha0_rad = angles_from_rotation(&(l * rotation(&a0) * r.transpose()))[0];
                let s = run(&d, &InverseParams { alpha0_rad, ..params }, &xg, &transform(&u0, r, l, &c), false);
                assert_eq!(s.iterations(), iterations);
                equivariance_error(&p, &s.u, &orig.u, r, l, &c)
            })
            .collect();
        for ((name, _, _), e) in cases.iter().zip(&errs) {
            eprintln!(
                "after {iterations:2} iterations, {name}: x {:.2e}, Q {:.2e}, kappa {:.2e}, angles {:.2e}",
                e[0], e[1], e[2], e[3]
            );
        }
        errs
    };
    // One iteration from the straight state: x is linear in the data for all five; the
    // frames agree to round-off for the symmetries and to 4e-2 otherwise.
    let errs = errors(1);
    for e in &errs {
        assert!(e[0] < 1e-14, "{e:?}");
    }
    for e in &errs[..3] {
        assert!(e[1] < 1e-10 && e[2] < 1e-8, "{e:?}");
    }
    for e in &errs[3..] {
        assert!(e[1] > 1e-2 && e[2] > 0.05, "{e:?}");
    }
    let errs = errors(20);
    // Exact in exact arithmetic: the round-off differences have grown, x most for the rotations.
    // How far they grow depends on the round-off of the data themselves (the forward solve's):
    // rewriting the forward kernels' products as matrix-vector chains moved κ of Ry(0.6) from
    // 1.7e-3 to 3.4e-3 with the fixed point unchanged. The claim is the gap to the rotations
    // that are not symmetries (κ ≥ 7e-2, 20 times and more), so κ is bounded at 1e-2.
    for e in &errs[..3] {
        assert!(e[0] < 1e-5 && e[1] < 3e-4 && e[2] < 1e-2, "{e:?}");
    }
    // Not exact: 20 times the symmetric differences and more.
    for e in &errs[3..] {
        assert!(e[0] > 1e-4 && e[1] > 5e-3 && e[2] > 0.05, "{e:?}");
    }
}
