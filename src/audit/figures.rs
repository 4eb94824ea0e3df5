//! The audit's figures, laid out like the paper's panels (SVG), from the runs of a spec: see
//! [`PlotKind`] for what each kind shows and which figure of the paper it stands for.
use std::path::Path;

use nalgebra::Vector3;

use super::check::history_of;
use super::measures::modal_tip_history;
use super::spec::{PlotKind, PlotSpec, Selector, Spec};
use super::{PointResult, RunResults};
use crate::case::{Case, Reference};
use crate::engine::metrics::{Metric, INNER_SKIP_ELEMENTS};
use crate::figures::heatmap::{render_heatmaps_svg, Heatmap};
use crate::figures::plot::{render_panels_svg, render_svg, Band, Legend, LinePlot, Mark, Series};
use crate::figures::posture::{render_postures_svg, PosturePanel};
use crate::io::files::write_plot;
use crate::io::OutputError;
use crate::model::loads::LoadFrame;
use crate::reference::{timoshenko_deflection, tip_loaded_cantilever, PlanarRod};

/// Write every figure of `spec` into `dir`; returns the files written. A figure whose runs
/// produced nothing to draw (every point failed) is skipped.
pub fn write_figures(spec: &Spec, runs: &[RunResults], dir: &Path) -> Result<Vec<String>, (String, OutputError)> {
    let mut written = Vec::new();
    for p in &spec.plots {
        let path = dir.join(&p.file);
        let svg = match figure(spec, p, runs) {
            Some(svg) => svg,
            None => continue,
        };
        write_plot(&path, svg).map_err(|e| (p.file.clone(), e))?;
        written.push(p.file.clone());
        // the numbers of a trade-off figure beside it, for tables
        if let PlotKind::Tradeoff { run: name, metric } = &p.show {
            let csv = path.with_extension("csv");
            let text = run(runs, name).map(|r| tradeoff_csv(r, metric)).unwrap_or_default();
            crate::io::files::write_atomic(&csv, text.as_bytes()).map_err(|e| (p.file.clone(), e))?;
        }
    }
    Ok(written)
}

/// `point,status,wall_time_s,METRIC` of every point of a run (a trade-off figure's numbers).
fn tradeoff_csv(r: &RunResults, metric: &str) -> String {
    let num = |v: Option<f64>| v.map(|v| format!("{v:e}")).unwrap_or_default();
    let mut out = format!("point,status,wall_time_s,{metric}\n");
    for p in &r.points {
        out += &format!(
            "\"{}\",{},{},{}\n",
            label(p),
            p.outcome.status.as_str(),
            num(p.value(Metric::WallTime)),
            num(p.metric(metric))
        );
    }
    out
}

type Svg = Result<String, crate::figures::plot::PlotError>;

fn run<'a>(runs: &'a [RunResults], name: &str) -> Option<&'a RunResults> {
    runs.iter().find(|r| r.name == name)
}

fn first_at<'a>(runs: &'a [RunResults], name: &str, at: &Selector) -> Option<&'a PointResult> {
    run(runs, name)?.select(at).find(|p| p.outcome.single.is_some() || p.outcome.clip.is_some())
}

fn line(title: String, x_label: &str, y_label: &str, series: Vec<Series>, log: (bool, bool)) -> LinePlot {
    LinePlot {
        title,
        x_label: x_label.into(),
        y_label: y_label.into(),
        series,
        log_x: log.0,
        log_y: log.1,
        ..Default::default()
    }
}

/// A grid key as the paper writes it: `lambda_kappa3` → `λκ3`.
fn pretty_key(k: &str) -> String {
    k.replace("lambda_kappa", "λκ").replace("lambda_omega", "λω").replace("lambda_", "λ")
}

/// `λd = 0.01, …` of a point's grid values (the point's folder name for a run without a grid),
/// with "(not converged)" for a point that did not converge.
fn label(p: &PointResult) -> String {
    if p.point.is_empty() {
        return p.label.clone();
    }
    let mut l = p.point.iter().map(|(k, v)| format!("{} = {v}", pretty_key(k))).collect::<Vec<_>>().join(", ");
    if !p.converged() {
        l.push_str(" (not converged)");
    }
    l
}

/// The frame interval Δt [s] of a run's clip (1 s if the run is not a clip: then "t" counts
/// frames, which no figure of a clip does).
fn frame_interval_s(spec: &Spec, name: &str) -> f64 {
    spec.run(name).and_then(|r| r.case.inverse()).map_or(1.0, |i| i.params.frame_interval_s)
}

fn figure(spec: &Spec, p: &PlotSpec, runs: &[RunResults]) -> Option<Svg> {
    let title = &p.title;
    match &p.show {
        PlotKind::Convergence { run: name } => convergence(title, run(runs, name)?),
        PlotKind::Recovered { run: name, at } => recovered(title, first_at(runs, name, at)?),
        PlotKind::Controls { run: name, at } => {
            let case = &spec.run(name)?.case;
            controls(title, case, first_at(runs, name, at)?)
        }
        PlotKind::TipHistory { run: name } => {
            let case = &spec.run(name)?.case;
            tip_history(title, case, first_at(runs, name, &Selector::new())?)
        }
        PlotKind::Deflection { runs: names } => {
            let pts: Vec<(&Case, &PointResult)> =
                names.iter().filter_map(|n| Some((&spec.run(n)?.case, first_at(runs, n, &Selector::new())?))).collect();
            deflection(title, &pts)
        }
        PlotKind::Kymograph { run: name, at } => {
            kymograph(title, first_at(runs, name, at)?, frame_interval_s(spec, name))
        }
        PlotKind::Objectives { runs: names } => objectives(spec, title, names, runs),
        PlotKind::Omega { runs: names } => omega(spec, title, names, runs),
        PlotKind::Postures { run: name, frames, at } => {
            postures(title, first_at(runs, name, at)?, frames, run(runs, name)?)
        }
        PlotKind::Tradeoff { run: name, metric } => tradeoff(title, run(runs, name)?, metric),
    }
}

/// Accuracy per second: `metric` against the solve's wall time over the run's converged
/// points (sorted by time), log-log; one curve, each point a marker of its grid values.
fn tradeoff(title: &str, r: &RunResults, metric: &str) -> Option<Svg> {
    let mut pts: Vec<(f64, f64)> = r
        .points
        .iter()
        .filter(|p| p.converged())
        .filter_map(|p| Some((p.value(Metric::WallTime)?, p.metric(metric)?)))
        .filter(|(t, e)| *t > 0.0 && *e > 0.0)
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    if pts.is_empty() {
        return None;
    }
    let series = vec![Series::new(
        format!("{metric} (grid: {})", r.points.iter().map(label).collect::<Vec<_>>().join(", ")),
        pts.iter().map(|p| p.0).collect(),
        pts.iter().map(|p| p.1).collect(),
    )];
    Some(render_svg(&line(title.to_string(), "solve wall time [s]", metric, series, (true, true))))
}

/// Figs. 9–11, 13: log-log histories of every point, one panel per measure.
fn convergence(title: &str, r: &RunResults) -> Option<Svg> {
    let measures = [
        ("x_err_rel", "|x − x_g| / |x_g| [–]"),
        ("kappa_err_rel", "|κ − κ_f| / |κ_f| [–]"),
        ("tangent_misfit", "‖∂s x − d3‖ [m^½]"),
        ("rel_change", "relative change of (x, α) [–]"),
    ];
    let mut panels = Vec::new();
    for (i, (name, y)) in measures.iter().enumerate() {
        let series: Vec<Series> = r
            .points
            .iter()
            .filter_map(|p| {
                let h = history_of(p, name)?;
                (!h.is_empty()).then(|| Series::new(label(p), (1..=h.len()).map(|k| k as f64).collect(), h))
            })
            .enumerate()
            .map(|(i, s)| s.nth_of_many(i))
            .collect();
        if series.is_empty() {
            continue;
        }
        let t = if i == 0 { title.to_string() } else { y.to_string() };
        let mut panel = line(t, "iteration", y, series, (true, true));
        // a run without a grid: one curve, described by the title
        if r.points.iter().all(|p| p.point.is_empty()) {
            panel.legend = Legend::Hidden;
        }
        panels.push(panel);
    }
    (!panels.is_empty()).then(|| render_panels_svg(&panels, 2))
}

/// Figs. 8, 12, 14: the recovered centreline and curvature (solid) against the forward data
/// (markers, under the lines), lengths in mm.
fn recovered(title: &str, p: &PointResult) -> Option<Svg> {
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
    let mut panels = vec![line(format!("{title}: position"), "s [mm]", "x [mm]", pos, (false, false))];
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
        panels.push(line("curvature κ = A ∂sα (eq. 28)".into(), "s [mm]", "κ [1/mm]", k, (false, false)));
    }
    Some(render_panels_svg(&panels, 2))
}

/// Fig. 15: the controls f = x̂/λf and l = α̂/λl (solid) against the loads that made the data
/// (dashed), components in the global frame (e1, e2, e3; the design of a follower load is
/// rotated into it with the data's directors), lengths in mm. The clamped end elements (the
/// [`INNER_SKIP_ELEMENTS`] the audit's inner measures leave out) are shaded; the lower panels
/// show the controls without them, where the design's scale can be seen.
fn controls(title: &str, case: &Case, p: &PointResult) -> Option<Svg> {
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
    let mut force = line(format!("{title}: force, {global}"), "s [mm]", "f [N/mm]", curves(0, 0..n), (false, false));
    force.bands = bands.clone();
    let mut torque = line(format!("torque, {global}"), "s [mm]", "l [N mm/mm]", curves(1, 0..n), (false, false));
    torque.bands = bands;
    let inner = INNER_SKIP_ELEMENTS..n - INNER_SKIP_ELEMENTS;
    let zoom = |which: usize, what: &str, unit: &str| {
        let t = format!("{what} without the {INNER_SKIP_ELEMENTS} elements at each end (shaded above)");
        line(t, "s [mm]", unit, curves(which, inner.clone()), (false, false))
    };
    let (force_inner, torque_inner) = (zoom(0, "force", "f [N/mm]"), zoom(1, "torque", "l [N mm/mm]"));
    Some(render_panels_svg(&[force, torque, force_inner, torque_inner], 2))
}

/// Fig. 5: the tip's displacement (x, y) and rotation (the angles α, β, γ) against time, the
/// Cosserat rod (solid) against the modal solution of the linearised rod (dashed).
fn tip_history(title: &str, case: &Case, p: &PointResult) -> Option<Svg> {
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
        let tt = if c == 0 { format!("{title}: displacement") } else { "displacement".into() };
        panels.push(line(tt, "t [s]", &format!("{name} [mm]"), series, (false, false)));
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
    panels.push(line("rotation: the tip's angles".into(), "t [s]", "angle [rad]", rotation, (false, false)));
    Some(render_panels_svg(&panels, 2))
}

/// Fig. 7: deflection y(s) of tip-loaded cantilevers against eq. (63), the elastica and the
/// Reissner rod, every load on one plot (one colour and mark per model).
fn deflection(title: &str, pts: &[(&Case, &PointResult)]) -> Option<Svg> {
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
    (!series.is_empty())
        .then(|| render_panels_svg(&[line(title.into(), "s [mm]", "y [mm]", series, (false, false))], 1))
}

/// Figs. 17, 23, 25: κ1, κ2, κ3 [1/mm] over time [s] (x) and arc length (y, head at 0), each on
/// its own colour scale (± the 99th percentile of its magnitude, the colour bar beside it); at
/// most ~300 frames and 64 positions drawn.
fn kymograph(title: &str, p: &PointResult, dt_s: f64) -> Option<Svg> {
    let s = p.series.as_ref()?;
    let nf = s.kappa.len();
    if nf < 2 {
        return None;
    }
    let fs = nf.div_ceil(300);
    let frames: Vec<usize> = (0..nf).step_by(fs).collect();
    let ne = s.s_mid.len();
    let es = ne.div_ceil(64);
    let cols: Vec<usize> = (0..ne).step_by(es).collect();
    let x: Vec<f64> = frames.iter().map(|&i| s.frames[i] as f64 * dt_s).collect();
    let y: Vec<f64> = cols.iter().map(|&j| s.s_mid[j] * 1e3).collect();
    let maps: Vec<Heatmap> = (0..3)
        .map(|c| {
            let values: Vec<Vec<f64>> =
                frames.iter().map(|&i| cols.iter().map(|&j| s.kappa[i][j][c] * 1e-3).collect()).collect();
            let limit = Some(crate::output::clip_output::abs_percentile_99(values.iter().flatten().copied()))
                .filter(|v| *v > 0.0)
                .unwrap_or(1.0);
            let t = if c == 0 { format!("{title}: κ{}", c + 1) } else { format!("κ{}", c + 1) };
            Heatmap::kymograph(t, x.clone(), y.clone(), values, limit, format!("κ{} [1/mm]", c + 1))
        })
        .collect();
    Some(render_heatmaps_svg(&maps))
}

/// The weights of the inverse problem of `case` at a grid point, as `(name, value)`.
fn weights_of(case: &Case, point: &crate::case::sweep::Point) -> Vec<(&'static str, String)> {
    let values: Vec<(&str, crate::case::sweep::SweepValue)> =
        point.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
    let Some(w) = case.with_values(&values).ok().and_then(|c| c.inverse().map(|i| i.params.weights)) else {
        return Vec::new();
    };
    let f = crate::case::sweep::fmt_value;
    let diag = |v: Vector3<f64>| format!("diag({}, {}, {})", f(v[0]), f(v[1]), f(v[2]));
    vec![
        ("λf", f(w.lambda_f)),
        ("λl", f(w.lambda_l)),
        ("λd", f(w.lambda_d)),
        ("Λκ", diag(w.lambda_kappa)),
        ("Λω", diag(w.lambda_omega)),
    ]
}

/// Every point of the named runs with its run name and a legend label: the weights in which the
/// curves of the figure differ (all of them for a single curve), "(not converged)" added. A
/// point with the same weights as an earlier one is left out (the same solve).
fn points_of<'a>(spec: &Spec, runs: &'a [RunResults], names: &[String]) -> Vec<(String, String, &'a PointResult)> {
    let mut pts = Vec::new();
    for n in names {
        let Some(r) = run(runs, n) else { continue };
        for p in &r.points {
            let w = spec.run(n).map(|rs| weights_of(&rs.case, &p.point)).unwrap_or_default();
            // a point with the weights of one already shown (Table 1 inside a sweep) is the same run
            if w.is_empty() || !pts.iter().any(|(_, v, _)| *v == w) {
                pts.push((n.clone(), w, p));
            }
        }
    }
    let differs = |k: usize| pts.iter().any(|(_, w, _)| w.get(k).map(|x| &x.1) != pts[0].1.get(k).map(|x| &x.1));
    let shown: Vec<usize> = (0..5).filter(|&k| pts.len() == 1 || differs(k)).collect();
    pts.iter()
        .map(|(n, w, p)| {
            let mut l = shown
                .iter()
                .filter_map(|&k| w.get(k))
                .map(|(k, v)| format!("{k} = {v}"))
                .collect::<Vec<_>>()
                .join(", ");
            if l.is_empty() {
                l = n.clone();
            }
            if !p.converged() {
                l.push_str(" (not converged)");
            }
            (n.clone(), l, *p)
        })
        .collect()
}

/// Figs. 18–20: the terms of the objective (41) per frame against time and the fit, one curve
/// per run (labelled by the weights in which they differ).
fn objectives(spec: &Spec, title: &str, names: &[String], runs: &[RunResults]) -> Option<Svg> {
    /// a panel's title, its y axis and its value of a frame's report (and √L [m^½])
    type Panel = (&'static str, &'static str, fn(&crate::solve::sequence::FrameReport, f64) -> f64);
    let panels_def: [Panel; 8] = [
        ("tracking error", "|x − x_g| / |x_g| [–]", |r, _| r.misfit.x_err_rel),
        ("shear–stretch misfit", "‖∂s x − d3‖ / √L [–]", |r, sqrt_l| r.misfit.tangent_misfit / sqrt_l),
        ("force term of (41)", "λf/2 ∫|f|² ds", |r, _| r.misfit.objective.force),
        ("torque term of (41)", "λl/2 ∫|l|² ds", |r, _| r.misfit.objective.torque),
        ("λd term of (41)", "λd/2 ∫|∂s x − d3|² ds", |r, _| r.misfit.objective.shear),
        ("bending term of (41)", "½ ∫ κᵀ Λκ κ ds", |r, _| r.misfit.objective.bending),
        ("angular velocity term of (41)", "½ ∫ ωᵀ Λω ω ds", |r, _| r.misfit.objective.angular),
        ("total objective (41)", "J", |r, _| r.misfit.objective.total()),
    ];
    let pts = points_of(spec, runs, names);
    let mut panels = Vec::new();
    for (i, (name, y_label, f)) in panels_def.iter().enumerate() {
        let mut series = Vec::new();
        for (run_name, label, p) in &pts {
            let Some(clip) = &p.outcome.clip else { continue };
            let sqrt_l = spec.run(run_name).map(|r| r.case.mesh.length_m.sqrt()).unwrap_or(1.0);
            let dt = frame_interval_s(spec, run_name);
            let x = clip.reports.iter().map(|r| r.frame as f64 * dt).collect();
            let curve = Series::new(label.clone(), x, clip.reports.iter().map(|r| f(r, sqrt_l)).collect());
            series.push(curve.nth_of_many(series.len()));
        }
        let positive = series.iter().any(|s| s.y.iter().any(|v| *v > 0.0));
        if series.is_empty() || !positive {
            continue;
        }
        let t = if i == 0 { format!("{title}: {name}") } else { name.to_string() };
        panels.push(line(t, "t [s]", y_label, series, (false, true)));
    }
    (!panels.is_empty()).then(|| render_panels_svg(&panels, 2))
}

/// Fig. 24: the angular velocity, max over the body per frame against time, one curve per run.
fn omega(spec: &Spec, title: &str, names: &[String], runs: &[RunResults]) -> Option<Svg> {
    let series: Vec<Series> = points_of(spec, runs, names)
        .into_iter()
        .filter_map(|(run_name, label, p)| {
            let s = p.series.as_ref()?;
            let dt = frame_interval_s(spec, &run_name);
            Some(Series::new(
                label,
                s.frames.iter().skip(1).map(|f| *f as f64 * dt).collect(),
                s.omega_max.iter().skip(1).copied().collect(),
            ))
        })
        .filter(|s| !s.x.is_empty())
        .enumerate()
        .map(|(i, s)| s.nth_of_many(i))
        .collect();
    (!series.is_empty()).then(|| {
        render_panels_svg(&[line(title.into(), "t [s]", "max |ω| over the body [rad/s]", series, (false, true))], 1)
    })
}

/// The frames of a clip point to draw: those asked for, else (a clip excerpt in --quick that
/// ends before them) its last frame.
fn shown_frames<'a>(p: &'a PointResult, frames: &[usize]) -> Vec<&'a crate::engine::clip::ClipFrame> {
    let Some(s) = p.series.as_ref() else { return Vec::new() };
    let mut shown: Vec<&crate::engine::clip::ClipFrame> =
        frames.iter().filter_map(|f| s.kept.iter().find(|k| k.report.frame == *f)).collect();
    if shown.is_empty() {
        shown.extend(s.last.as_ref());
    }
    shown
}

/// Figs. 16, 21, 22: the kept frames of a clip run, three projections each, with the directors
/// d1 (ticks), d3 (arrows) and the tangent, the centreline coloured by |κ| [1/mm] (the node
/// average of the element curvatures, `engine::clip::nodal_curvature`). For a run with a grid,
/// beneath them the quantity its swept weight penalises along the body at the first frame
/// shown, one curve per grid point: the angle between d3 and the chord of each element (λd,
/// Fig. 21: the detachment the λd term penalises) or κ3 (λκ3, Fig. 22).
fn postures(title: &str, p: &PointResult, frames: &[usize], all: &RunResults) -> Option<Svg> {
    let panels: Vec<PosturePanel> = shown_frames(p, frames)
        .into_iter()
        .map(|k| {
            let d = k.nodes.directors();
            let colour =
                crate::engine::clip::nodal_curvature(&k.elements.kappa).iter().map(|v| v.norm() * 1e-3).collect();
            PosturePanel {
                label: format!("frame {} (t = {} s)", k.report.frame, crate::figures::plot::format_tick(k.time_s)),
                x: k.nodes.x.clone(),
                d1: d.iter().map(|q| q[0]).collect(),
                d3: d.iter().map(|q| q[2]).collect(),
                colour,
                colour_label: "|κ| [1/mm]".into(),
            }
        })
        .collect();
    if panels.is_empty() {
        return None;
    }
    Some(render_postures_svg(title, &panels, profiles(all, frames).as_ref()))
}

/// The profile beneath a posture figure of a run with a grid (see [`postures`]).
fn profiles(all: &RunResults, frames: &[usize]) -> Option<LinePlot> {
    let key = all.points.first()?.point.first()?.0.clone();
    let mut series = Vec::new();
    let mut frame_no = None;
    for p in &all.points {
        let Some(k) = shown_frames(p, frames).into_iter().next() else { continue };
        frame_no.get_or_insert(k.report.frame);
        let (x, y): (Vec<f64>, Vec<f64>) = match key.as_str() {
            "lambda_d" => {
                // per element: the chord (x_{i+1} − x_i) against the mean of its nodes' d3, the
                // pair the λd term of (41) compares
                let d = k.nodes.directors();
                let (x, s) = (&k.nodes.x, &k.nodes.s);
                (0..x.len() - 1)
                    .map(|i| {
                        let (c, m) = (x[i + 1] - x[i], d[i][2] + d[i + 1][2]);
                        let cos = c.dot(&m) / (c.norm() * m.norm());
                        (0.5 * (s[i] + s[i + 1]) * 1e3, cos.clamp(-1.0, 1.0).acos().to_degrees())
                    })
                    .unzip()
            }
            "lambda_kappa3" => k.elements.kappa.iter().map(|(s, v)| (s * 1e3, v[2] * 1e-3)).unzip(),
            _ => return None,
        };
        series.push(Series::new(label(p), x, y).nth_of_many(series.len()));
    }
    let y_label = if key == "lambda_d" { "∠(d3, ∂s x) per element [°]" } else { "κ3 [1/mm]" };
    let what = if key == "lambda_d" { "the detachment of d3 from the centreline's chord" } else { "the twist κ3" };
    let t = format!("{what} along the body at frame {}, for each {}", frame_no?, pretty_key(&key));
    (!series.is_empty()).then(|| line(t, "arc length s [mm] (0 = head)", y_label, series, (false, key == "lambda_d")))
}
