//! The internal force `n = Qᵀ K (Q ∂s x − e3)` [N] and moment `m = Qᵀ J A ∂s α` [N m] of every
//! element (eqs. 13, 15, 28; `model::resultants::resultants`) against solutions known without the
//! code: a cantilever under an end force carries that force along its whole length and the
//! moment of its lever arm; an end moment bends a rod into a circle of curvature M/EI under a
//! constant moment and no force; and every solved state, forward or inverse (a single frame, a
//! frame of a clip in its rebased chart), balances its loads discretely, node by node:
//! `∂s n + f = 0` and `∂s m + ∂s x × n + l = 0`, with the controls f, l of eq. (41) as the
//! loads of an inverse solution.
mod common;

use std::sync::{Arc, Mutex};

use common::{case_from, case_text, edit, short_roll_case, worm_data_present, Collect};
use cosserat::case::Case;
use cosserat::engine::rust::clip::{run_clip, ClipFrames};
use cosserat::engine::rust::run_rust;
use cosserat::engine::RunResult;
use cosserat::io::compact::CURVATURE_COLUMNS;
use cosserat::model::resultants::Resultants;
use nalgebra::Vector3;

/// The Timoshenko cantilever of `cases/` with its tip force set to `force` [N] along −e2,
/// solved by Newton to round-off.
fn cantilever(force: &str) -> Case {
    let text = edit(&case_text("timoshenko_10pct"), "F = 1e-8 ", &format!("F = {force} "));
    case_from(&newton(&text), "cantilever")
}

/// The static case `text` solved by Newton to round-off instead of the fixed point.
fn newton(text: &str) -> String {
    let text = edit(text, "method = \"fixed_point\"", "method = \"newton\"");
    edit(&edit(&text, "relaxation = 0.5\n", ""), "tolerance = 1e-9", "tolerance = 1e-13")
}

fn resultants(case: &Case, r: &RunResult) -> Vec<Resultants> {
    r.nodes.resultants(&case.props, case.quadrature, None)
}

/// Largest |component| of `v` over a set of vectors.
fn amax<'a>(v: impl Iterator<Item = &'a Vector3<f64>>) -> f64 {
    v.fold(0.0, |m, x| m.max(x.amax()))
}

/// A dead tip force F carries through the rod unchanged, n = F on every element, and the
/// moment about each element's midpoint is that of the lever arm from there to the tip,
/// m = (x(L) − x_mid) × F, both exactly (the discrete equations balance them element by
/// element, at any deflection); the linear beam's m = (L − s) e3 × F is off by the arm's
/// foreshortening, second order in the deflection.
#[test]
fn a_cantilever_under_an_end_force_carries_it_and_its_lever_arm() {
    for (force, deflection) in [("1e-8", 0.1), ("1e-10", 1e-3)] {
        let case = cantilever(force);
        let r = run_rust(&case, |_, _| {}).expect("cantilever converges");
        let f: f64 = force.parse().expect("number");
        let big_f = Vector3::new(0.0, -f, 0.0);
        let res = resultants(&case, &r);
        assert_eq!(res.len(), case.mesh.elements);
        // Newton stops at an increment of 1e-13: the strains, and so n = K × strain, are
        // known to about 1e-13 of the stiffness
        let tol = 1e-12 * case.props.shear_stretch_n.amax();
        let n_err = amax(res.iter().map(|e| e.n - big_f).collect::<Vec<_>>().iter());
        assert!(n_err < tol, "F = {force}: max |n − F| = {n_err:e} N");
        let tip = r.nodes.x[r.nodes.x.len() - 1];
        let length = case.mesh.length_m;
        let lever = res
            .iter()
            .enumerate()
            .map(|(e, el)| (el.m - (tip - (r.nodes.x[e] + r.nodes.x[e + 1]) * 0.5).cross(&big_f)).amax())
            .fold(0.0, f64::max);
        let linear = linear_error(&res, &r, big_f, length);
        let m0 = f * length;
        eprintln!(
            "F = {force} N: max |n − F| = {n_err:.2e} N, max |m − (x(L) − x_mid) × F| = {lever:.2e} N m, \
             max |m − (L − s) e3 × F| = {:.2e} FL",
            linear / m0
        );
        assert!(lever < tol * length, "F = {force}: max |m − (x(L) − x_mid) × F| = {lever:e} N m against FL = {m0:e}");
        // the linear lever arm (L − s) e3 misses the arm's foreshortening, of second order in
        // the tip's deflection δ/L
        let second = deflection * deflection * m0;
        assert!(linear < second && linear > 0.1 * second, "F = {force}: max |m − (L − s) e3 × F| = {linear:e} N m");
        // in the directors: the root element's bending moment about d1 is F (L − h/2), its
        // shear force F along −d2
        let root = &res[0];
        let arm = length - 0.5 * case.mesh.h();
        assert!((root.m_local.x / (f * arm) - 1.0).abs() < deflection, "{:?}", root.m_local);
        assert!((root.n_local.y / -f - 1.0).abs() < 2.0 * deflection, "{:?}", root.n_local);
    }
}

/// max |m − (L − s_mid) e3 × F| over the elements [N m].
fn linear_error(res: &[Resultants], r: &RunResult, big_f: Vector3<f64>, length: f64) -> f64 {
    res.iter()
        .enumerate()
        .map(|(e, el)| {
            let s = (r.nodes.s[e] + r.nodes.s[e + 1]) * 0.5;
            (el.m - Vector3::z().cross(&big_f) * (length - s)).amax()
        })
        .fold(0.0, f64::max)
}

/// An end moment M about e1 bends the rod into a circular arc (here of one radian): no force
/// anywhere, the moment M on every element, in the directors a bending moment about d1 only,
/// and the curvature of the arc κ1 = M / (E I1), to round-off (the arc lies in P1 exactly:
/// linear β, chords for x).
#[test]
fn an_end_moment_bends_the_rod_into_a_circle_under_a_constant_moment() {
    let base = cantilever("1e-8");
    let ei = base.props.bend_twist_nm2.x;
    let moment = ei / base.mesh.length_m; // bends the rod by 1 rad
    let text = edit(
        &case_text("timoshenko_10pct"),
        "end_force_n = [0, \"-F\", 0]",
        &format!("end_torque_nm = [{moment:e}, 0, 0]"),
    );
    let text = newton(&text);
    // the case's reference (eq. 63) is the tip force's
    let text = text.split("[reference]").next().expect("case").to_string();
    let case = case_from(&text, "end_moment");
    let r = run_rust(&case, |_, _| {}).expect("end moment converges");
    let res = resultants(&case, &r);
    let m = Vector3::new(moment, 0.0, 0.0);
    // to Newton's increment of 1e-13 (see the cantilever)
    let n_max = amax(res.iter().map(|e| &e.n));
    assert!(n_max < 1e-12 * case.props.shear_stretch_n.amax(), "max |n| = {n_max:e} N");
    let m_err = amax(res.iter().map(|e| e.m - m).collect::<Vec<_>>().iter());
    assert!(m_err < 1e-10 * moment, "max |m − M| = {m_err:e} N m");
    let ml_err = amax(res.iter().map(|e| e.m_local - m).collect::<Vec<_>>().iter());
    assert!(ml_err < 1e-10 * moment, "max |mˡ − (M, 0, 0)| = {ml_err:e} N m");
    eprintln!("end moment M = {moment:.3e} N m: max |n| = {n_max:.2e} N, max |m − M| = {m_err:.2e} N m, max |mˡ − M e1| = {ml_err:.2e} N m");
    let kappa = r.nodes.element_curvature();
    let k_err = kappa.iter().map(|(_, k)| (k - Vector3::new(moment / ei, 0.0, 0.0)).amax()).fold(0.0, f64::max);
    assert!(k_err < 1e-9 * moment / ei, "max |κ − (M/EI, 0, 0)| = {k_err:e} 1/m");
    // the tip: a circle of radius EI/M = L turned by 1 rad about e1
    let tip = r.nodes.x[r.nodes.x.len() - 1];
    let l = case.mesh.length_m;
    let expected = Vector3::new(0.0, -(l - l * 1f64.cos()), l * 1f64.sin());
    let chord_error = (tip - expected).norm() / l;
    eprintln!(
        "  max |κ − M/EI| = {k_err:.2e} 1/m (M/EI = {:.3e}), tip against the arc {chord_error:.2e} L",
        moment / ei
    );
    assert!(chord_error < 1e-5, "tip {tip:?} against the arc's {expected:?}: {chord_error:e}");
}

/// `∫ N_a v_h` over the elements beside node `a` of a P1 field `v` (nodal values) with the
/// load rule of `case` (the rule of the loads in the discrete equations, D4).
fn load_at(case: &Case, v: &[Vector3<f64>], s: &[f64], a: usize) -> Vector3<f64> {
    let rule = case.quadrature.loads();
    let mut sum = Vector3::zeros();
    for e in [a.wrapping_sub(1), a] {
        if e + 1 >= s.len() {
            continue;
        }
        let h = s[e + 1] - s[e];
        for (xi, w) in rule.iter() {
            let (na, nb) = (1.0 - xi, xi);
            let value = v[e] * na + v[e + 1] * nb;
            sum += value * (w * h * if e == a { na } else { nb });
        }
    }
    sum
}

/// Largest imbalance of the force and moment rows at the interior nodes of a state with
/// positions `x`, arc lengths `s`, resultants `res` and P1 loads `f` [N/m], `l` [N m/m], each
/// relative to the largest of its terms: `n̄_e − n̄_{e−1} + ∫ N_a f` and
/// `m̄_e − m̄_{e−1} + ∫ N_a (∂s x × n) + ∫ N_a l`, the last with the midpoint rule of the
/// selective element's stretch–shear integrand.
fn imbalance(
    case: &Case,
    s: &[f64],
    x: &[Vector3<f64>],
    res: &[Resultants],
    (f, l): (&[Vector3<f64>], &[Vector3<f64>]),
) -> (f64, f64) {
    let (mut force, mut moment) = ((0.0f64, 0.0f64), (0.0f64, 0.0f64));
    for a in 1..x.len() - 1 {
        let (fa, la) = (load_at(case, f, s, a), load_at(case, l, s, a));
        let df = res[a].n - res[a - 1].n;
        force.0 = force.0.max((df + fa).amax());
        force.1 = force.1.max(df.amax().max(fa.amax()));
        let arm = (x[a] - x[a - 1]).cross(&res[a - 1].n) * 0.5 + (x[a + 1] - x[a]).cross(&res[a].n) * 0.5;
        let dm = res[a].m - res[a - 1].m;
        moment.0 = moment.0.max((dm + arm + la).amax());
        moment.1 = moment.1.max(dm.amax().max(arm.amax()).max(la.amax()));
    }
    (force.0 / force.1, moment.0 / moment.1)
}

/// An inverse solution balances the controls it found (eq. 52 with f = x̂/λf, l = α̂/λl):
/// the recovered state's n and m and the controls satisfy the discrete force and moment
/// balance at every interior node (the ends carry the data's Dirichlet values).
#[test]
fn an_inverse_solution_balances_its_controls_node_by_node() {
    let text = edit(
        &case_text("inverse_bend"),
        "method = \"fixed_point\"",
        "method = \"newton\"\nwarm_start_tolerance = 1e-4",
    );
    let text = edit(&text, "tolerance = 3e-6", "tolerance = 1e-10");
    let case = case_from(&text, "inverse_bend_newton");
    let r = run_rust(&case, |_, _| {}).expect("inverse converges");
    let inv = r.inverse.as_ref().expect("inverse output");
    let res = resultants(&case, &r);
    let (f, l) = (inv.force(), inv.torque());
    let (force, moment) = imbalance(&case, &r.nodes.s, &r.nodes.x, &res, (&f, &l));
    eprintln!("inverse_bend (Newton): relative imbalance force {force:.2e}, moment {moment:.2e}");
    assert!(force < 1e-8 && moment < 1e-8, "relative imbalance: force {force:e}, moment {moment:e}");
}

/// The frames of a clip solved in rebased charts (`worm_roll_3d`, 16 nodes, 6 frames) give
/// their resultants in space coordinates, as their controls: each frame balances its own
/// controls node by node, and `curvature.csv` holds the same numbers under its unit-named
/// columns.
#[test]
fn clip_frames_balance_their_controls_in_space_coordinates() {
    if !worm_data_present("clip_frames_balance_their_controls_in_space_coordinates") {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let case = Case::from_file(&short_roll_case(dir.path(), "roll.toml", 6, 16)).expect("case");
    let got = Arc::new(Mutex::new(Vec::new()));
    let out = run_clip(&case, clip_frames(&case).as_frames(), &[], Collect(got.clone()), |_, _| {}).expect("clip");
    assert!(out.stopped.is_none(), "{:?}", out.stopped);
    let frames = got.lock().expect("frames").clone();
    assert_eq!(frames.len(), 6);
    assert!(frames.iter().any(|f| !f.nodes.chart.is_identity()), "a rebased chart is exercised");
    for fr in &frames {
        let (force, moment) = imbalance(
            &case,
            &fr.nodes.s,
            &fr.nodes.x,
            &fr.elements.resultants,
            (&fr.controls.force, &fr.controls.torque),
        );
        eprintln!("worm_roll_3d frame {}: relative imbalance force {force:.2e}, moment {moment:.2e}", fr.report.frame);
        assert!(force < 1e-10 && moment < 1e-10, "frame {}: force {force:e}, moment {moment:e}", fr.report.frame);
    }
    let out_dir = dir.path().join("out");
    cosserat::jobs::clip_run::run_clip_case(&case, &out_dir, |_, _| {}).expect("clip to files");
    let text = std::fs::read_to_string(out_dir.join("curvature.csv")).expect("curvature.csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    assert_eq!(header[0], "frame");
    assert_eq!(&header[1..], &CURVATURE_COLUMNS[..]);
    let col = |name: &str| header.iter().position(|h| *h == name).expect("column");
    let last = &frames[5];
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().expect("number")).collect())
        .filter(|r: &Vec<f64>| r[0] == 5.0)
        .collect();
    for (e, row) in rows.iter().enumerate() {
        let want = &last.elements.resultants[e];
        for (k, v) in [("n_x_n", want.n.x), ("m_z_nm", want.m.z), ("n3_n", want.n_local.z), ("m1_nm", want.m_local.x)] {
            assert!((row[col(k)] - v).abs() <= 1e-9 * v.abs().max(1e-30), "element {e} {k}: {} vs {v:e}", row[col(k)]);
        }
    }
}

/// The frames of `case`'s clip, loaded.
struct Loaded(cosserat::clip::Clip, Option<cosserat::clip::synthetic::GroundTruth>);

impl Loaded {
    fn as_frames(&self) -> ClipFrames<'_> {
        ClipFrames::Loaded { clip: &self.0, truth: self.1.as_ref(), start: None }
    }
}

fn clip_frames(case: &Case) -> Loaded {
    let (clip, truth) = cosserat::engine::input::clip_files::load_clip(case).expect("clip");
    Loaded(clip, truth)
}
