//! The audit's figures, laid out like the paper's panels (SVG), from the runs of a spec: see
//! [`PlotKind`] for what each kind shows and which figure of the paper it stands for.
use std::path::Path;

use nalgebra::Vector3;

use super::check::history_of;
use super::measures::modal_tip_history;
use super::spec::{PlotKind, PlotSpec, Selector, Spec};
use super::{PointResult, RunResults};
use crate::case::{Case, Reference};
use crate::io::files::write_plot;
use crate::io::plot::{render_heatmaps_svg, render_panels_svg, render_svg, Heatmap, LinePlot, Series};
use crate::io::posture::{render_postures_svg, PosturePanel};
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
            num(p.metric("wall_time_s")),
            num(p.metric(metric))
        );
    }
    out
}

type Svg = Result<String, crate::io::plot::PlotError>;

fn run<'a>(runs: &'a [RunResults], name: &str) -> Option<&'a RunResults> {
    runs.iter().find(|r| r.name == name)
}

fn first_at<'a>(runs: &'a [RunResults], name: &str, at: &Selector) -> Option<&'a PointResult> {
    run(runs, name)?.select(at).find(|p| p.outcome.single.is_some() || p.outcome.clip.is_some())
}

fn label(p: &PointResult) -> String {
    if p.point.is_empty() {
        return p.label.clone();
    }
    let mut l = p.point.iter().map(|(k, v)| format!("{k} = {v}")).collect::<Vec<_>>().join(", ");
    if !p.converged() {
        l.push_str(" (not converged)");
    }
    l
}

fn line(title: String, x_label: &str, y_label: &str, series: Vec<Series>, log: (bool, bool)) -> LinePlot {
    LinePlot {
        title,
        x_label: x_label.into(),
        y_label: y_label.into(),
        series,
        log_x: log.0,
        log_y: log.1,
        legend: Default::default(),
    }
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
        PlotKind::Kymograph { run: name, at } => kymograph(title, first_at(runs, name, at)?),
        PlotKind::Objectives { runs: names } => objectives(spec, title, names, runs),
        PlotKind::Omega { runs: names } => omega(title, names, runs),
        PlotKind::Postures { run: name, frames, at } => postures(title, first_at(runs, name, at)?, frames),
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
        .filter_map(|p| Some((p.metric("wall_time_s")?, p.metric(metric)?)))
        .filter(|(t, e)| *t > 0.0 && *e > 0.0)
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    if pts.is_empty() {
        return None;
    }
    let series = vec![Series {
        label: format!("{metric} (grid: {})", r.points.iter().map(label).collect::<Vec<_>>().join(", ")),
        x: pts.iter().map(|p| p.0).collect(),
        y: pts.iter().map(|p| p.1).collect(),
    }];
    Some(render_svg(&line(title.to_string(), "solve wall time [s]", metric, series, (true, true))))
}

/// Figs. 9–11, 13: log-log histories of every point, one panel per measure.
fn convergence(title: &str, r: &RunResults) -> Option<Svg> {
    let measures = [
        ("x_err_rel", "|x - x_g| / |x_g|"),
        ("kappa_err_rel", "|kappa - kappa_f| / |kappa_f|"),
        ("tangent_misfit", "|d_s x - d3| [m^1/2]"),
        ("rel_change", "relative change of (x, alpha)"),
    ];
    let mut panels = Vec::new();
    for (i, (name, y)) in measures.iter().enumerate() {
        let series: Vec<Series> = r
            .points
            .iter()
            .filter_map(|p| {
                let h = history_of(p, name)?;
                (!h.is_empty()).then(|| Series { label: label(p), x: (1..=h.len()).map(|k| k as f64).collect(), y: h })
            })
            .collect();
        if series.is_empty() {
            continue;
        }
        let t = if i == 0 { title.to_string() } else { y.to_string() };
        panels.push(line(t, "iteration", y, series, (true, true)));
    }
    (!panels.is_empty()).then(|| render_panels_svg(&panels, 2))
}

/// Figs. 8, 12, 14: the recovered centreline and curvature against the forward data.
fn recovered(title: &str, p: &PointResult) -> Option<Svg> {
    let r = p.outcome.single.as_ref()?;
    let inv = r.inverse.as_ref()?;
    let s_mm: Vec<f64> = r.nodes.s.iter().map(|s| s * 1e3).collect();
    let comp = ["x", "y", "z"];
    let mut pos = Vec::new();
    for c in 0..3 {
        pos.push(Series {
            label: format!("{} data", comp[c]),
            x: s_mm.clone(),
            y: inv.data.x.iter().map(|x| x[c] * 1e3).collect(),
        });
        pos.push(Series {
            label: format!("{} recovered", comp[c]),
            x: s_mm.clone(),
            y: r.nodes.x.iter().map(|x| x[c] * 1e3).collect(),
        });
    }
    let mut panels = vec![line(format!("{title}: position"), "s [mm]", "x [mm]", pos, (false, false))];
    if inv.angles_known {
        let (kd, kr) = (inv.data.element_curvature(), r.nodes.element_curvature());
        let sm: Vec<f64> = kd.iter().map(|(s, _)| s * 1e3).collect();
        let mut k = Vec::new();
        for c in 0..3 {
            k.push(Series {
                label: format!("kappa_{} forward", c + 1),
                x: sm.clone(),
                y: kd.iter().map(|(_, v)| v[c]).collect(),
            });
            k.push(Series {
                label: format!("kappa_{} recovered", c + 1),
                x: sm.clone(),
                y: kr.iter().map(|(_, v)| v[c]).collect(),
            });
        }
        panels.push(line("generalised curvature kappa^l (eq. 28)".into(), "s [mm]", "kappa [1/m]", k, (false, false)));
    }
    Some(render_panels_svg(&panels, 2))
}

/// Fig. 15: the controls f = x̂/λf and l = α̂/λl against the loads that made the data.
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
    let mut panels = Vec::new();
    for (which, control, lambda, unit) in
        [(0usize, &inv.xhat, inv.lambda_f, "f [N/m]"), (1, &inv.ahat, inv.lambda_l, "l [N m/m]")]
    {
        let mut series = Vec::new();
        for c in 0..3 {
            series.push(Series {
                label: format!("{}_{} control", if which == 0 { "f" } else { "l" }, c + 1),
                x: s_mm.clone(),
                y: control.iter().map(|v| v[c] / lambda).collect(),
            });
            series.push(Series {
                label: format!("{}_{} design", if which == 0 { "f" } else { "l" }, c + 1),
                x: s_mm.clone(),
                y: design.iter().map(|d| if which == 0 { d.0[c] } else { d.1[c] }).collect(),
            });
        }
        let t = if which == 0 { format!("{title}: force") } else { "torque".into() };
        panels.push(line(t, "s [mm]", unit, series, (false, false)));
    }
    Some(render_panels_svg(&panels, 2))
}

/// Fig. 5: the tip's x and y against time, with the modal solution of the linearised rod.
fn tip_history(title: &str, case: &Case, p: &PointResult) -> Option<Svg> {
    let r = p.outcome.single.as_ref()?;
    let t: Vec<f64> = r.tip.iter().map(|k| k.time_s).collect();
    let modal = modal_tip_history(case, r);
    let mut panels = Vec::new();
    for (c, name) in ["x", "y"].iter().enumerate() {
        let mut series = vec![Series {
            label: format!("{name} tip, Cosserat"),
            x: t.clone(),
            y: r.tip.iter().map(|k| k.position_m[c] * 1e3).collect(),
        }];
        if let Some(m) = &modal {
            series.push(Series {
                label: format!("{name} tip, modal"),
                x: t.clone(),
                y: m.iter().map(|v| v[c] * 1e3).collect(),
            });
        }
        let tt = if c == 0 { title.to_string() } else { String::new() };
        panels.push(line(tt, "t [s]", &format!("{name} [mm]"), series, (false, false)));
    }
    Some(render_panels_svg(&panels, 2))
}

/// Fig. 7: deflection y(s) of tip-loaded cantilevers against eq. (63), the elastica and the
/// Reissner rod, every load on one plot.
fn deflection(title: &str, pts: &[(&Case, &PointResult)]) -> Option<Svg> {
    let mut series = Vec::new();
    for (case, p) in pts {
        let Some(Reference::TipLoadedCantilever { force_n }) = case.reference else { continue };
        let Some(r) = p.outcome.single.as_ref() else { continue };
        let (l, kga, ea, ei) = (
            case.mesh.length_m,
            case.props.shear_stretch_n[0],
            case.props.shear_stretch_n[2],
            case.props.bend_twist_nm2[0],
        );
        let s_mm: Vec<f64> = r.nodes.s.iter().map(|s| s * 1e3).collect();
        let tag = format!("F = {force_n:.0e} N");
        series.push(Series {
            label: format!("Cosserat, {tag}"),
            x: s_mm.clone(),
            y: r.nodes.x.iter().map(|x| x[1] * 1e3).collect(),
        });
        series.push(Series {
            label: format!("eq. (63), {tag}"),
            x: s_mm.clone(),
            y: r.nodes.s.iter().map(|s| timoshenko_deflection(*s, force_n, l, kga, ei) * 1e3).collect(),
        });
        for (name, shear) in [("elastica", false), ("Reissner rod", true)] {
            let rod = PlanarRod {
                length_m: l,
                bending_stiffness_nm2: ei,
                shear_stiffness_n: shear.then_some(kga),
                axial_stiffness_n: shear.then_some(ea),
            };
            if let Ok(sol) = tip_loaded_cantilever(&rod, force_n) {
                series.push(Series {
                    label: format!("{name}, {tag}"),
                    x: sol.curve.iter().map(|c| c.s_m * 1e3).collect(),
                    y: sol.curve.iter().map(|c| c.y_m * 1e3).collect(),
                });
            }
        }
    }
    (!series.is_empty())
        .then(|| render_panels_svg(&[line(title.into(), "s [mm]", "y [mm]", series, (false, false))], 1))
}

/// Figs. 17, 23, 25: κ1, κ2, κ3 over frames (x) and arc length (y), each on its own colour
/// scale (± the 99th percentile of its magnitude); at most ~300 frames and 64 positions drawn.
fn kymograph(title: &str, p: &PointResult) -> Option<Svg> {
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
    let x: Vec<f64> = frames.iter().map(|&i| s.frames[i] as f64).collect();
    let y: Vec<f64> = cols.iter().map(|&j| s.s_mid[j] * 1e3).collect();
    let maps: Vec<Heatmap> = (0..3)
        .map(|c| {
            let values: Vec<Vec<f64>> =
                frames.iter().map(|&i| cols.iter().map(|&j| s.kappa[i][j][c]).collect()).collect();
            let limit = Some(crate::io::clip_output::abs_percentile_99(values.iter().flatten().copied()))
                .filter(|v| *v > 0.0)
                .unwrap_or(1.0);
            let t = if c == 0 { format!("{title}: kappa_1") } else { format!("kappa_{}", c + 1) };
            Heatmap::kymograph(
                format!("{t} [1/m], colour ±{}", super::check::sig2(limit)),
                x.clone(),
                y.clone(),
                values,
                limit,
            )
        })
        .collect();
    Some(render_heatmaps_svg(&maps))
}

/// Figs. 18–20: the terms of the objective (41) per frame and the fit, one curve per run.
fn objectives(spec: &Spec, title: &str, names: &[String], runs: &[RunResults]) -> Option<Svg> {
    /// a panel's title and its value of a frame's report (and √L [m^½])
    type Panel = (&'static str, fn(&crate::solve::sequence::FrameReport, f64) -> f64);
    let panels_def: [Panel; 8] = [
        ("|x - x_g| / |x_g|", |r, _| r.x_err_rel),
        ("|d_s x - d3| / |d3|", |r, sqrt_l| r.tangent_misfit / sqrt_l),
        ("lambda_f/2 |f|^2", |r, _| r.objective.force),
        ("lambda_l/2 |l|^2", |r, _| r.objective.torque),
        ("lambda_d/2 |d_s x - d3|^2", |r, _| r.objective.shear),
        ("1/2 kappa^T Lambda_kappa kappa", |r, _| r.objective.bending),
        ("1/2 omega^T Lambda_omega omega", |r, _| r.objective.angular),
        ("total objective (41)", |r, _| r.objective.total()),
    ];
    let mut panels = Vec::new();
    for (i, (name, f)) in panels_def.iter().enumerate() {
        let mut series = Vec::new();
        for (label, p) in points_of(runs, names) {
            let Some(clip) = &p.outcome.clip else { continue };
            let sqrt_l = spec.run(&label.0).map(|r| r.case.mesh.length_m.sqrt()).unwrap_or(1.0);
            series.push(Series {
                label: label.1,
                x: clip.reports.iter().map(|r| r.frame as f64).collect(),
                y: clip.reports.iter().map(|r| f(r, sqrt_l)).collect(),
            });
        }
        let positive = series.iter().any(|s| s.y.iter().any(|v| *v > 0.0));
        if series.is_empty() || !positive {
            continue;
        }
        let t = if i == 0 { format!("{title}: {name}") } else { name.to_string() };
        panels.push(line(t, "frame", "value", series, (false, true)));
    }
    (!panels.is_empty()).then(|| render_panels_svg(&panels, 2))
}

/// Fig. 24: the angular velocity, max over the body per frame, one curve per run.
fn omega(title: &str, names: &[String], runs: &[RunResults]) -> Option<Svg> {
    let series: Vec<Series> = points_of(runs, names)
        .into_iter()
        .filter_map(|(label, p)| {
            let s = p.series.as_ref()?;
            Some(Series {
                label: label.1,
                x: s.frames.iter().skip(1).map(|f| *f as f64).collect(),
                y: s.omega_max.iter().skip(1).copied().collect(),
            })
        })
        .filter(|s| !s.x.is_empty())
        .collect();
    (!series.is_empty()).then(|| {
        render_panels_svg(&[line(title.into(), "frame", "max |omega| over the body [rad/s]", series, (false, true))], 1)
    })
}

/// Every point of the named runs with `(run name, curve label)`: the run's name, with the
/// point's grid values for a run with a grid.
fn points_of<'a>(runs: &'a [RunResults], names: &[String]) -> Vec<((String, String), &'a PointResult)> {
    let mut out = Vec::new();
    for n in names {
        let Some(r) = run(runs, n) else { continue };
        for p in &r.points {
            let label = if p.point.is_empty() { n.clone() } else { format!("{n} {}", p.label) };
            out.push(((n.clone(), label), p));
        }
    }
    out
}

/// Figs. 16, 21, 22: the kept frames of a clip run, three projections each, with the directors
/// d1 (ticks), d3 (arrows) and the tangent, the centreline coloured by |κ| (the node average of
/// the element curvatures, `run::clip::nodal_curvature`).
fn postures(title: &str, p: &PointResult, frames: &[usize]) -> Option<Svg> {
    let s = p.series.as_ref()?;
    let mut shown: Vec<&crate::run::clip::ClipFrame> =
        frames.iter().filter_map(|f| s.kept.iter().find(|k| k.report.frame == *f)).collect();
    // A clip excerpt (--quick) may end before the frames asked for: its last frame instead.
    if shown.is_empty() {
        shown.extend(s.last.as_ref());
    }
    let panels: Vec<PosturePanel> = shown
        .into_iter()
        .map(|k| {
            let d = k.nodes.directors();
            let colour = crate::run::clip::nodal_curvature(&k.kappa).iter().map(|v| v.norm()).collect();
            PosturePanel {
                label: format!("frame {}", k.report.frame),
                x: k.nodes.x.clone(),
                d1: d.iter().map(|q| q[0]).collect(),
                d3: d.iter().map(|q| q[2]).collect(),
                colour,
                colour_label: "|kappa| [1/m]".into(),
            }
        })
        .collect();
    if panels.is_empty() {
        return None;
    }
    Some(render_postures_svg(title, &panels))
}
