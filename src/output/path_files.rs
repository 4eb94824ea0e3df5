//! The files of an arc-length path (D25): `path.csv` (one row per converged point, the load
//! factor and the displacement at each recorded arc length), `critical_points.csv` (limit and
//! bifurcation points) and the load–displacement panel of `plot.svg`; and a static case's
//! buckling modes (D27), `buckling.csv`.
use nalgebra::Vector3;

use crate::case::Case;
use crate::engine::PathOutput;
use crate::figures::plot::{LinePlot, Mark, Series};
use crate::io::files::csv_text_int;
use crate::model::loads::LoadFrame;
use crate::solve::arclength::Critical;

/// `buckling.csv` (D27): a row per buckling mode and node: the mode (1, 2, …), its critical load
/// factor, the node's arc length and the mode's displacement in space, scaled so that the mode
/// has `‖φ‖_w = 1` (positions over the rod length, RMS over the nodes, with the angles).
pub fn buckling_csv(st: &crate::engine::StabilityOutput, s_m: &[f64]) -> String {
    let h = ["mode", "load_factor", "s_m", "ux_m", "uy_m", "uz_m"];
    let rows = st.modes.iter().enumerate().flat_map(|(k, m)| {
        m.displacement.iter().zip(s_m).map(move |(d, s)| {
            vec![Some((k + 1) as f64), Some(m.load_factor), Some(*s), Some(d[0]), Some(d[1]), Some(d[2])]
        })
    });
    csv_text_int(&h, &["mode"], rows)
}

/// `path.csv`: step, λ, arc length, determinant sign, iterations, certificate, then
/// `u{x,y,z}_m_at_s_{s}` per recorded arc length `s` [m] (each point load's and s = L).
pub fn path_csv(p: &PathOutput) -> String {
    let mut header: Vec<String> =
        ["step", "load_factor", "arc_length", "determinant_sign", "iterations", "certificate"]
            .map(String::from)
            .to_vec();
    for s in &p.record_s_m {
        for c in ["x", "y", "z"] {
            header.push(format!("u{c}_m_at_s_{s}"));
        }
    }
    let h: Vec<&str> = header.iter().map(String::as_str).collect();
    let rows = p.points.iter().map(|q| {
        let mut row = vec![
            Some(q.step as f64),
            Some(q.load_factor),
            Some(q.arc_length),
            Some(f64::from(q.determinant_sign)),
            Some(q.iterations as f64),
            Some(q.certificate),
        ];
        row.extend(q.displacements.iter().flat_map(|d| d.iter().map(|v| Some(*v))));
        row
    });
    csv_text_int(&h, &["step", "determinant_sign", "iterations"], rows)
}

/// `critical_points.csv`: kind (1 limit, 2 bifurcation), the load factor (a limit's parabola
/// vertex, a bifurcation's bracket midpoint), the bracket and the path step after which it lies.
pub fn critical_csv(p: &PathOutput) -> String {
    let rows = p.critical.iter().map(|c| {
        let (kind, lo, hi, after) = match *c {
            Critical::Limit { load_factor, after } => (1.0, load_factor, load_factor, after),
            Critical::Bifurcation { between, after } => (2.0, between.0, between.1, after),
        };
        vec![Some(kind), Some(c.load_factor()), Some(lo), Some(hi), Some(after as f64)]
    });
    csv_text_int(
        &["kind_1limit_2bifurcation", "load_factor", "bracket_low", "bracket_high", "after_step"],
        &["kind_1limit_2bifurcation", "after_step"],
        rows,
    )
}

/// The load factor against the displacement at each recorded arc length that moves: along a
/// dead point force's direction where one acts there, else the component that moves most;
/// critical points marked on the first curve.
pub fn path_panel(case: &Case, p: &PathOutput) -> LinePlot {
    let lambda: Vec<f64> = p.points.iter().map(|q| q.load_factor).collect();
    let mut series: Vec<Series> = Vec::new();
    let mut curves: Vec<Vec<f64>> = Vec::new();
    for (i, s) in p.record_s_m.iter().enumerate() {
        let (label, dir) = direction(case, p, i, *s);
        let d: Vec<f64> = p.points.iter().map(|q| q.displacements[i].dot(&dir)).collect();
        if d.iter().all(|v| *v == 0.0) {
            continue; // a held point
        }
        series.push(Series::new(format!("{label} at s = {s:.4} m"), d.clone(), lambda.clone()));
        curves.push(d);
    }
    let marks: Vec<(f64, f64)> = p
        .critical
        .iter()
        .filter_map(|c| {
            let after = match c {
                Critical::Limit { after, .. } | Critical::Bifurcation { after, .. } => *after,
            };
            let i = p.points.iter().position(|q| q.step == after)?;
            Some((curves.first()?[i], c.load_factor()))
        })
        .collect();
    if !marks.is_empty() {
        let (x, y): (Vec<f64>, Vec<f64>) = marks.into_iter().unzip();
        let mut m = Series::new("limit and bifurcation points", x, y);
        m.mark = Mark::Markers;
        series.push(m);
    }
    LinePlot {
        title: format!("{}: load path (arc length)", case.name),
        x_label: "displacement [m]".into(),
        y_label: "load factor λ [-]".into(),
        series,
        ..Default::default()
    }
}

/// The direction the displacement at recorded point `i` (arc length `s`) is drawn along, with
/// its label: a dead point force's there, else the axis that moves most.
fn direction(case: &Case, p: &PathOutput, i: usize, s: f64) -> (String, Vector3<f64>) {
    let force = case
        .loads
        .point
        .iter()
        .filter(|l| l.s_m == s && l.frame == LoadFrame::Global)
        .map(|l| l.force.at(s, 0.0))
        .fold(Vector3::zeros(), |a, f| a + f);
    if force.norm() > 0.0 {
        return ("u along the force".into(), force.normalize());
    }
    let k = (0..3).max_by(|&a, &b| range(p, i, a).total_cmp(&range(p, i, b))).expect("three components");
    (format!("u_{}", ["x", "y", "z"][k]), Vector3::ith(k, 1.0))
}

/// The range of displacement component `k` at recorded point `i` along the path.
fn range(p: &PathOutput, i: usize, k: usize) -> f64 {
    let v = p.points.iter().map(|q| q.displacements[i][k]);
    let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)));
    hi - lo
}
