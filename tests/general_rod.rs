//! The general rod of D20–D24 in the Rust engine, against exact solutions and invariances: a
//! curved reference is stress free, an end moment rolls a cantilever into a closed polygon, a
//! pinned–pinned beam under a point load meets the beam formula at second order, a twisted clamp
//! gives uniform torsion, a rigidly rotated case gives the rotated answer, and the ends that leave a
//! rigid motion free are refused by name.
mod common;

use common::case_from;
use cosserat::case::Case;
use cosserat::model::mesh::Field;
use cosserat::solve::statics;
use nalgebra::{DVector, Matrix3, Rotation3, Vector3};
use std::f64::consts::PI;

/// A static case with the stiffnesses EA = GA = 1e7, EI = GJ = 1e7/12 (the 45° bend's) and the
/// given `[rod]` extras, ends, loads; Newton with `steps` continuation steps.
fn case(rod_extra: &str, rest: &str, elements: usize, length: f64, steps: usize) -> Case {
    let text = format!(
        r#"description = "general rod test"
[rod]
length_m = {length}
elements = {elements}
{rod_extra}
[cross_section]
shape = "stiffness"
ea_n = 1e7
ga1_n = 1e7
ga2_n = 1e7
ei1_nm2 = "1e7/12"
ei2_nm2 = "1e7/12"
gj_nm2 = "1e7/12"
{rest}
[solver]
analysis = "static"
method = "newton"
tolerance = 1e-12
max_iterations = 40
continuation_steps = {steps}
"#
    );
    case_from(&text, "general")
}

fn solve(case: &Case) -> DVector<f64> {
    let cosserat::case::Analysis::Static(params) = &case.analysis else { panic!("static") };
    let sol = statics::solve(&case.problem(), params, |_| {}).and_then(|s| s.converged()).expect("static solve");
    assert!(sol.certificate.value < 1e-13, "certificate {}", sol.certificate.value);
    sol.u
}

/// Positions in space of a solved state.
fn positions(case: &Case, u: &DVector<f64>) -> Vec<Vector3<f64>> {
    cosserat::engine::NodalState::of_forward(case, u).x
}

#[test]
fn an_unloaded_arc_stays_where_it_is() {
    // a quarter circle of radius 100 in the x–z plane, and one tilted out of every plane
    for extra in [
        "intrinsic_curvature_per_m = [0, 0.01, 0]",
        "intrinsic_curvature_per_m = [0.004, 0.01, \"0.002*s\"]\nstart_d3 = [0.3, 0.5, 0.8]\nstart_d1 = [1, 0, 0]\nstart_position_m = [5, -2, 1]",
    ] {
        let c = case(extra, "", 16, 50.0 * PI, 1);
        let u = solve(&c);
        let rest = &c.rod.general.as_ref().expect("a general rod").rest;
        let moved = (&u - &rest.state).amax();
        assert!(moved < 1e-12 * 100.0, "{extra}: moved by {moved:e}");
    }
}

#[test]
fn an_end_moment_rolls_the_cantilever_into_a_closed_polygon() {
    // M = 2π EI/L about e2: κ2 = 2π/L uniform; with the stretch–shear integrand at the
    // midpoint each element's chord has length h along d3 there, so the nodes are a regular
    // polygon of `elements` sides that closes exactly (the tip returns to the clamp)
    let (l, ei) = (10.0, 1e7 / 12.0);
    for (elements, frame) in [(10, "global"), (24, "local")] {
        let loads =
            format!("[[loads.point]]\ns_m = {l}\ntorque_nm = [0, {}, 0]\nframe = \"{frame}\"", 2.0 * PI * ei / l);
        let c = case("", &loads, elements, l, 8);
        let x = positions(&c, &solve(&c));
        let tip = x[elements];
        assert!(tip.norm() < 1e-10 * l, "{elements} elements ({frame}): tip at {tip}");
        // every node on the circumscribed circle of the polygon, radius h / (2 sin(π/n))
        let r = (l / elements as f64) / (2.0 * (PI / elements as f64).sin());
        let centre = Vector3::new(r, 0.0, 0.0);
        for (i, xi) in x.iter().enumerate() {
            assert!(((xi - centre).norm() - r).abs() < 1e-10 * l, "node {i}: {}", (xi - centre).norm() - r);
            assert!(xi[1].abs() < 1e-12, "planar");
        }
    }
}

#[test]
fn a_pinned_beam_under_a_midspan_load_meets_the_beam_formula_at_second_order() {
    // simply supported (twist held at one end), P at L/2 along −e1: δ = P L³/(48 EI) + P L/(4 GA)
    let (l, p, ei, ga): (f64, f64, f64, f64) = (10.0, 1.0, 1e7 / 12.0, 1e7);
    let exact = p * l.powi(3) / (48.0 * ei) + p * l / (4.0 * ga);
    let mut errors = Vec::new();
    for elements in [8, 16, 32] {
        let rest = format!(
            "[ends.start]\nkind = \"pinned\"\ntwist = \"held\"\n[ends.end]\nkind = \"pinned\"\n[[loads.point]]\ns_m = {}\nforce_n = [{}, 0, 0]",
            l / 2.0,
            -p
        );
        let c = case("", &rest, elements, l, 1);
        let x = positions(&c, &solve(&c));
        let delta = -x[elements / 2][0];
        errors.push((delta - exact).abs() / exact);
    }
    // the linear answer is matched up to the (tiny, (δ/L)² ~ 1e-11) geometric nonlinearity and
    // O(h²): measured 1.5e-2, 3.9e-3, 9.7e-4
    assert!(errors[2] < 1.5e-3, "{errors:?}");
    for w in errors.windows(2) {
        let order = (w[0] / w[1]).log2();
        assert!((1.9..2.1).contains(&order), "order {order} ({errors:?})");
    }
}

#[test]
fn a_twisted_clamp_gives_uniform_torsion() {
    // clamped at both ends, the end at s = L turned by φ about its axis e3: α(s) = −φ s/L and
    // the reaction torque GJ φ/L; P1 holds the linear twist exactly
    let phi = 0.8;
    let rest = format!("[ends.end]\nkind = \"clamped\"\nrotation_rad = [0, 0, {phi}]");
    let c = case("", &rest, 7, 2.0, 1);
    let u = solve(&c);
    let dofs = c.mesh.dofs();
    for i in 0..c.mesh.nodes() {
        let a = dofs.get(&u, i, Field::Alpha);
        let s = c.mesh.node_s(i);
        assert!((a[0] + phi * s / 2.0).abs() < 1e-12 && a[1].abs() < 1e-12 && a[2].abs() < 1e-12, "node {i}: {a}");
        let x = dofs.get(&u, i, Field::X);
        assert!((x - Vector3::new(0.0, 0.0, s)).amax() < 1e-12);
    }
}

#[test]
fn a_rigidly_rotated_case_gives_the_rotated_answer() {
    // the same curved cantilever under a dead tip force, posed in rotated space coordinates
    // (start frame, load and chart axis rotated by R): positions rotate by R
    let r = Rotation3::new(Vector3::new(0.7, -0.4, 1.1)).into_inner();
    let v = |x: Vector3<f64>| format!("[{:.17e}, {:.17e}, {:.17e}]", x[0], x[1], x[2]);
    let pose = |rot: &Matrix3<f64>| {
        let extra = format!(
            "intrinsic_curvature_per_m = [0, 0.01, 0.002]\nstart_d3 = {}\nstart_d1 = {}\nchart_axis = {}",
            v(rot * Vector3::z()),
            v(rot * Vector3::x()),
            v(rot * Vector3::y())
        );
        let loads = format!("[loads]\nend_force_n = {}", v(rot * Vector3::new(0.0, 300.0, 100.0)));
        case(&extra, &loads, 16, 25.0 * PI, 4)
    };
    let (a, b) = (pose(&Matrix3::identity()), pose(&r));
    let (xa, xb) = (positions(&a, &solve(&a)), positions(&b, &solve(&b)));
    let span = xa.iter().map(|x| x.norm()).fold(0.0, f64::max);
    for (p, q) in xa.iter().zip(&xb) {
        assert!((r * p - q).norm() < 1e-9 * span, "{}", (r * p - q).norm());
    }
    // and the deflection is large: a real test of the nonlinear problem
    assert!((xa[16] - a.rod.general.as_ref().unwrap().rest.positions[16]).norm() > 5.0);
}

#[test]
fn ends_that_leave_a_rigid_motion_free_are_refused_by_name() {
    let err = |rest: &str| {
        let text = format!(
            "description = \"x\"\n[rod]\nlength_m = 1\nelements = 4\n[cross_section]\nshape = \"stiffness\"\nea_n = 1\nga1_n = 1\nga2_n = 1\nei1_nm2 = 1\nei2_nm2 = 1\ngj_nm2 = 1\n{rest}\n[solver]\nanalysis = \"static\"\nmethod = \"newton\"\ntolerance = 1e-10\nmax_iterations = 5\n"
        );
        Case::from_toml(&text, "x", std::path::Path::new("x.toml")).expect_err("refused").to_string()
    };
    let e = err("[ends.start]\nkind = \"pinned\"\n[ends.end]\nkind = \"pinned\"");
    assert!(
        e.contains("a rotation about the axis through (0.000, 0.000, 0.000) m along (0.000, 0.000, 1.000)")
            && e.contains("twist = \"held\""),
        "{e}"
    );
    let e = err("[ends.start]\nkind = \"free\"");
    assert!(e.contains("translation") || e.contains("rotation"), "{e}");
    let e = err("[ends.start]\nkind = \"free\"\ntwist = \"held\"");
    assert!(e.contains("ends.start.twist"), "{e}");
}
