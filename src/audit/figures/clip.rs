//! The audit's figures of a clip: postures (Figs. 16, 21, 22), kymographs (Figs. 17, 23, 25),
//! the objective's terms (Figs. 18–20) and the angular velocity (Fig. 24).
use std::collections::BTreeMap;

use nalgebra::Vector3;

use super::{frame_interval_s, label, line, pretty_key, run, Axes, Svg};
use crate::audit::spec::{Selector, Spec};
use crate::audit::{PointResult, RunResults};
use crate::case::Case;
use crate::figures::heatmap::{render_figure_heatmaps_svg, Heatmap};
use crate::figures::panels::render_figure_svg;
use crate::figures::plot::{LinePlot, Series};
use crate::figures::posture::{element_angles_deg, render_postures_svg, PosturePanel};

/// Figs. 17, 23, 25: κ1, κ2, κ3 [1/mm] over time [s] (x) and arc length (y, head at 0), each on
/// its own colour scale (± the 99th percentile of its magnitude, the colour bar beside it); at
/// most ~300 frames and 64 positions drawn.
pub(super) fn kymograph(title: &str, p: &PointResult, dt_s: f64) -> Option<Svg> {
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
            Heatmap::kymograph(format!("κ{}", c + 1), x.clone(), y.clone(), values, limit, format!("κ{} [1/mm]", c + 1))
        })
        .collect();
    Some(render_figure_heatmaps_svg(title, &maps))
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

/// Every point of the named runs (those of `at`'s selector for a run it names) with its run
/// name and a legend label: the weights in which the
/// curves of the figure differ (all of them for a single curve), "(not converged)" added. A
/// point with the same weights as an earlier one is left out (the same solve).
fn points_of<'a>(
    spec: &Spec,
    runs: &'a [RunResults],
    names: &[String],
    at: &BTreeMap<String, Selector>,
) -> Vec<(String, String, &'a PointResult)> {
    let mut pts = Vec::new();
    let all = Selector::new();
    for n in names {
        let Some(r) = run(runs, n) else { continue };
        for p in r.select(at.get(n).unwrap_or(&all)) {
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
/// per point of the runs `names` (of `at`'s selector for a run it names), labelled by the
/// weights in which they differ.
///
/// Units: the terms are computed in SI (x [m], f [N/m], l [N m/m], κ [1/m], ω [rad/s]) with the
/// weights as given, and (41) is dimensionless when λg is in 1/m³, as the paper's choice
/// λg ≈ 1/∫|x_g|² ds makes it; each weight then has the unit that makes its term
/// dimensionless, named in its panel's title.
pub(super) fn objectives(
    spec: &Spec,
    title: &str,
    names: &[String],
    at: &BTreeMap<String, Selector>,
    runs: &[RunResults],
) -> Option<Svg> {
    /// a panel's title, its y axis and its value of a frame's report (and √L [m^½])
    type Panel = (&'static str, &'static str, fn(&crate::solve::sequence::FrameReport, f64) -> f64);
    let panels_def: [Panel; 8] = [
        ("tracking error", "|x − x_g| / |x_g| [–]", |r, _| r.misfit.x_err_rel),
        ("shear–stretch misfit", "‖∂s x − d3‖ / √L [–]", |r, sqrt_l| r.misfit.tangent_misfit / sqrt_l),
        ("force term of (41), λf in m/N²", "λf/2 ∫|f|² ds [–]", |r, _| r.misfit.objective.force),
        ("torque term of (41), λl in 1/(N² m)", "λl/2 ∫|l|² ds [–]", |r, _| r.misfit.objective.torque),
        ("λd term of (41), λd in 1/m", "λd/2 ∫|∂s x − d3|² ds [–]", |r, _| r.misfit.objective.shear),
        ("bending term of (41), Λκ in m", "½ ∫ κᵀ Λκ κ ds [–]", |r, _| r.misfit.objective.bending),
        ("angular velocity term of (41), Λω in s²/m", "½ ∫ ωᵀ Λω ω ds [–]", |r, _| {
            r.misfit.objective.angular
        }),
        ("total objective (41), λg in 1/m³ (λg ≈ 1/∫|x_g|² ds)", "J [–]", |r, _| r.misfit.objective.total()),
    ];
    let pts = points_of(spec, runs, names, at);
    let mut panels = Vec::new();
    for (name, y_label, f) in panels_def.iter() {
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
        panels.push(line(name.to_string(), "t [s]", y_label, series, Axes::LOG_Y));
    }
    (!panels.is_empty()).then(|| render_figure_svg(title, &panels, 2))
}

/// Fig. 24: the angular velocity, max over the body per frame against time, one curve per run.
pub(super) fn omega(spec: &Spec, title: &str, names: &[String], runs: &[RunResults]) -> Option<Svg> {
    let series: Vec<Series> = points_of(spec, runs, names, &BTreeMap::new())
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
        let panel = line(
            "max |ω| over the body per frame".into(),
            "t [s]",
            "max |ω| over the body [rad/s]",
            series,
            Axes::LOG_Y,
        );
        render_figure_svg(title, &[panel], 1)
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

/// Figs. 16, 21, 22: the kept frames of a clip run, three projections each on the same axes
/// (positions in the lab frame), with the directors d1 (ticks), d3 (arrows) and ∂s x of the
/// sampled elements, the centreline coloured by |κ| [1/mm] on one scale for all frames (the node
/// average of the element curvatures, `engine::clip::nodal_curvature`). For a run with a grid,
/// beneath them the quantity its swept weight penalises along the body at the first frame
/// shown, one curve per grid point: the angle between d3 and the chord of each element (λd,
/// Fig. 21: the detachment the λd term penalises) or κ3 (λκ3, Fig. 22).
pub(super) fn postures(title: &str, p: &PointResult, frames: &[usize], all: &RunResults) -> Option<Svg> {
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
                // per element: ∂s x (the chord) against the mean of its nodes' d3, the pair the
                // λd term of (41) compares and the postures' captions take their angle from
                let d3: Vec<Vector3<f64>> = k.nodes.directors().iter().map(|q| q[2]).collect();
                let s = &k.nodes.s;
                element_angles_deg(&k.nodes.x, &d3)
                    .into_iter()
                    .enumerate()
                    .filter_map(|(i, a)| Some((0.5 * (s[i] + s[i + 1]) * 1e3, a?)))
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
    let axes = if key == "lambda_d" { Axes::LOG_Y } else { Axes::LINEAR };
    (!series.is_empty()).then(|| line(t, "arc length s [mm] (0 = head)", y_label, series, axes))
}
