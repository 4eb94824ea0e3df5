//! The audit's figures of a rod: the tip history (Fig. 5), the deflection (Fig. 7), the
//! recovered centreline and curvature (Figs. 8, 12, 14) and the controls (Fig. 15).
use nalgebra::Vector3;

use super::{line, Axes, Svg};
use crate::audit::measures::modal_tip_history;
use crate::audit::PointResult;
use crate::case::{Case, Reference};
use crate::engine::metrics::INNER_SKIP_ELEMENTS;
use crate::figures::panels::render_figure_svg;
use crate::figures::plot::{Band, Mark, Series};
use crate::model::loads::LoadFrame;
use crate::reference::{timoshenko_deflection, tip_loaded_cantilever, PlanarRod};

/// Figs. 8, 12, 14: the recovered centreline and curvature (solid) against the forward data
/// (markers, under the lines), lengths in mm.
pub(super) fn recovered(title: &str, p: &PointResult) -> Option<Svg> {
    let r = p.outcome.single.as_ref()?;
    let inv = r.inverse.as_ref()?;
    let s_mm: Vec<f64> = r.nodes.s.iter().map(|s| s * 1e3).collect();
    let comp = ["x", "y", "z"];
    let mut pos = Vec::new();
    for c in 0..3 {
        let data = inv.data.x.iter().map(|x| x[c] * 1e3).collect();
        pos.push(Series::new(format!("{} data", comp[c]), s_mm.clone(), data).marked(Mark::Markers).coloured(c));
        let rec = r.nodes.x.iter().map(|x| x[c] * 1e3).collect();
        pos.push(Series::new(format!("{} recovered", comp[c]), s_mm.clone(), rec).coloured(c));
    }
    let mut panels = vec![line("position".into(), "s [mm]", "x [mm]", pos, Axes::LINEAR)];
    if inv.angles_known {
        let (kd, kr) = (inv.data.element_curvature(), r.nodes.element_curvature());
        let sm: Vec<f64> = kd.iter().map(|(s, _)| s * 1e3).collect();
        let mut k = Vec::new();
        for c in 0..3 {
            let fwd = kd.iter().map(|(_, v)| v[c] * 1e-3).collect();
            k.push(Series::new(format!("κ{} forward", c + 1), sm.clone(), fwd).marked(Mark::Markers).coloured(c));
            let rec = kr.iter().map(|(_, v)| v[c] * 1e-3).collect();
            k.push(Series::new(format!("κ{} recovered", c + 1), sm.clone(), rec).coloured(c));
        }
        panels.push(line("curvature κ = A ∂sα (eq. 28)".into(), "s [mm]", "κ [1/mm]", k, Axes::LINEAR));
    }
    Some(render_figure_svg(title, &panels, 2))
}

/// The lower panels of Fig. 15 draw the controls within this many times the design's largest
/// component (over the same nodes).
const DESIGN_WINDOW: f64 = 3.0;

/// Fig. 15: the controls f = x̂/λf and l = α̂/λl (solid) against the loads that made the data
/// (dashed), components in the global frame (e1, e2, e3; the design of a follower load is
/// rotated into it with the data's directors), lengths in mm. The clamped end elements (the
/// [`INNER_SKIP_ELEMENTS`] the audit's inner measures leave out) are shaded; the lower panels
/// show the controls over the nodes those measures use, within [`DESIGN_WINDOW`] times the
/// design's largest component there: the clamp's boundary layer reaches a few elements past
/// the shaded ones and would set their scale otherwise.
pub(super) fn controls(title: &str, case: &Case, p: &PointResult) -> Option<Svg> {
    let r = p.outcome.single.as_ref()?;
    let inv = r.inverse.as_ref()?;
    let data = case.data_case()?;
    let s_mm: Vec<f64> = r.nodes.s.iter().map(|s| s * 1e3).collect();
    let directors = inv.data.directors();
    let design: Vec<(Vector3<f64>, Vector3<f64>)> = r
        .nodes
        .s
        .iter()
        .zip(&directors)
        .map(|(s, d)| {
            let (f, l) = data.loads.distributed(*s, 0.0);
            match data.loads.frame {
                LoadFrame::Global => (f, l),
                LoadFrame::Local => (d[0] * f[0] + d[1] * f[1] + d[2] * f[2], d[0] * l[0] + d[1] * l[1] + d[2] * l[2]),
            }
        })
        .collect();
    let n = s_mm.len();
    let h_mm = case.mesh.h() * 1e3;
    let clamp = (INNER_SKIP_ELEMENTS as f64 * h_mm, (n - 1 - INNER_SKIP_ELEMENTS) as f64 * h_mm);
    let bands = vec![
        Band { from: 0.0, to: clamp.0, label: format!("clamp, {INNER_SKIP_ELEMENTS} el.") },
        Band { from: clamp.1, to: s_mm[n - 1], label: format!("end, {INNER_SKIP_ELEMENTS} el.") },
    ];
    // force [N/m] → [N/mm]; torque per length [N m/m] = [N mm/mm]
    let curves = |which: usize, nodes: std::ops::Range<usize>| {
        let (name, control, lambda, scale) =
            if which == 0 { ("f", &inv.xhat, inv.lambda_f, 1e-3) } else { ("l", &inv.ahat, inv.lambda_l, 1.0) };
        let x: Vec<f64> = s_mm[nodes.clone()].to_vec();
        let mut series = Vec::new();
        for c in 0..3 {
            let y = control[nodes.clone()].iter().map(|v| v[c] / lambda * scale).collect();
            series.push(Series::new(format!("{name}{} recovered", c + 1), x.clone(), y).coloured(c));
            let d = design[nodes.clone()].iter().map(|d| if which == 0 { d.0[c] } else { d.1[c] } * scale).collect();
            series.push(
                Series::new(format!("{name}{} design (65)", c + 1), x.clone(), d).marked(Mark::Dashed).coloured(c),
            );
        }
        series
    };
    let global = "global frame e1, e2, e3";
    let mut force = line(format!("force, {global}"), "s [mm]", "f [N/mm]", curves(0, 0..n), Axes::LINEAR);
    force.bands = bands.clone();
    let mut torque = line(format!("torque, {global}"), "s [mm]", "l [N mm/mm]", curves(1, 0..n), Axes::LINEAR);
    torque.bands = bands;
    let inner = INNER_SKIP_ELEMENTS..n - INNER_SKIP_ELEMENTS;
    let zoom = |which: usize, what: &str, unit: &str| {
        let t = format!(
            "{what} without the {INNER_SKIP_ELEMENTS} end elements, within {DESIGN_WINDOW}× the design's largest"
        );
        let mut panel = line(t, "s [mm]", unit, curves(which, inner.clone()), Axes::LINEAR);
        // the clamp's boundary layer reaches past the end elements: the window keeps the
        // design's scale readable (the upper panels draw every value)
        let scale = if which == 0 { 1e-3 } else { 1.0 };
        let largest =
            design[inner.clone()].iter().map(|d| if which == 0 { d.0.amax() } else { d.1.amax() }).fold(0.0, f64::max);
        let w = DESIGN_WINDOW * largest * scale;
        panel.y_window = (w > 0.0).then_some((-w, w));
        panel
    };
    let (force_inner, torque_inner) = (zoom(0, "force", "f [N/mm]"), zoom(1, "torque", "l [N mm/mm]"));
    Some(render_figure_svg(title, &[force, torque, force_inner, torque_inner], 2))
}

/// Fig. 5: the tip's displacement (x, y) and rotation (the angles α, β, γ) against time, the
/// Cosserat rod (solid) against the modal solution of the linearised rod (dashed).
pub(super) fn tip_history(title: &str, case: &Case, p: &PointResult) -> Option<Svg> {
    let r = p.outcome.single.as_ref()?;
    let t: Vec<f64> = r.tip.iter().map(|k| k.time_s).collect();
    let modal = modal_tip_history(case, r);
    let mut panels = Vec::new();
    for (c, name) in ["x", "y"].iter().enumerate() {
        let mut series = vec![Series::new(
            format!("{name} tip, Cosserat"),
            t.clone(),
            r.tip.iter().map(|k| k.position_m[c] * 1e3).collect(),
        )];
        if let Some(m) = &modal {
            let y = m.iter().map(|v| v.position_m[c] * 1e3).collect();
            series.push(Series::new(format!("{name} tip, modal"), t.clone(), y).marked(Mark::Dashed));
        }
        panels.push(line(format!("displacement {name}"), "t [s]", &format!("{name} [mm]"), series, Axes::LINEAR));
    }
    let mut rotation = Vec::new();
    for (c, name) in ["α", "β", "γ"].iter().enumerate() {
        rotation.push(
            Series::new(format!("{name}, Cosserat"), t.clone(), r.tip.iter().map(|k| k.angles_rad[c]).collect())
                .coloured(c),
        );
        if let Some(m) = &modal {
            let y = m.iter().map(|v| v.angles_rad[c]).collect();
            rotation.push(Series::new(format!("{name}, modal"), t.clone(), y).marked(Mark::Dashed).coloured(c));
        }
    }
    panels.push(line("rotation: the tip's angles".into(), "t [s]", "angle [rad]", rotation, Axes::LINEAR));
    Some(render_figure_svg(title, &panels, 2))
}

/// Fig. 7: deflection y(s) of tip-loaded cantilevers against eq. (63), the elastica and the
/// Reissner rod, every load on one plot (one colour and mark per model).
pub(super) fn deflection(title: &str, pts: &[(&Case, &PointResult)]) -> Option<Svg> {
    let mut series = Vec::new();
    for (case, p) in pts {
        let Some(Reference::TipLoadedCantilever { force_n }) = case.checks.reference else { continue };
        let Some(r) = p.outcome.single.as_ref() else { continue };
        let (l, kga, ea, ei) = (
            case.mesh.length_m,
            case.props.shear_stretch_n[0],
            case.props.shear_stretch_n[2],
            case.props.bend_twist_nm2[0],
        );
        let s_mm: Vec<f64> = r.nodes.s.iter().map(|s| s * 1e3).collect();
        let tag = format!("F = {force_n:.0e} N");
        series.push(Series::new(
            format!("Cosserat, {tag}"),
            s_mm.clone(),
            r.nodes.x.iter().map(|x| x[1] * 1e3).collect(),
        ));
        let eq63 = r.nodes.s.iter().map(|s| timoshenko_deflection(*s, force_n, l, kga, ei) * 1e3).collect();
        series.push(Series::new(format!("eq. (63), {tag}"), s_mm.clone(), eq63).marked(Mark::Dashed).coloured(1));
        for (k, (name, shear)) in [("elastica", false), ("Reissner rod", true)].into_iter().enumerate() {
            let rod = PlanarRod {
                length_m: l,
                bending_stiffness_nm2: ei,
                shear_stiffness_n: shear.then_some(kga),
                axial_stiffness_n: shear.then_some(ea),
            };
            if let Ok(sol) = tip_loaded_cantilever(&rod, force_n) {
                let mark = if shear { Mark::Dashed } else { Mark::Markers };
                series.push(
                    Series::new(
                        format!("{name}, {tag}"),
                        sol.curve.iter().map(|c| c.s_m * 1e3).collect(),
                        sol.curve.iter().map(|c| c.y_m * 1e3).collect(),
                    )
                    .marked(mark)
                    .coloured(2 + k),
                );
            }
        }
    }
    for s in series.iter_mut().filter(|s| s.colour.is_none()) {
        s.colour = Some(0);
    }
    (!series.is_empty()).then(|| {
        render_figure_svg(title, &[line("deflection y(s)".into(), "s [mm]", "y [mm]", series, Axes::LINEAR)], 1)
    })
}
