//! The audit's figures, laid out like the paper's panels (SVG), from the runs of a spec: see
//! [`PlotKind`] for what each kind shows and which figure of the paper it stands for. Every
//! figure's title is written in a strip of its own above its panels. The figures of a rod
//! (Figs. 5, 7, 8, 12, 14, 15) are in [`rod`], those of a clip (Figs. 16–25) in [`clip`].
use std::path::Path;

use super::check::history_of;
use super::spec::{PlotKind, PlotSpec, Selector, Spec};
use super::{PointResult, RunResults};
use crate::case::Case;
use crate::engine::metrics::Metric;
use crate::figures::panels::render_figure_svg;
use crate::figures::plot::{render_svg, Legend, LinePlot, Mark, Scale, Series};
use crate::io::files::write_plot;
use crate::io::OutputError;
use crate::solve::inverse::InverseMethod;
use crate::solve::Outcome;

mod clip;
mod rod;

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

/// The scales of a line plot's two axes.
#[derive(Debug, Clone, Copy)]
struct Axes {
    x: Scale,
    y: Scale,
}

impl Axes {
    /// both axes linear
    const LINEAR: Axes = Axes { x: Scale::Linear, y: Scale::Linear };
    /// a linear x axis, a logarithmic y axis
    const LOG_Y: Axes = Axes { x: Scale::Linear, y: Scale::Log };
    /// both axes logarithmic
    const LOG_LOG: Axes = Axes { x: Scale::Log, y: Scale::Log };
}

fn line(title: String, x_label: &str, y_label: &str, series: Vec<Series>, axes: Axes) -> LinePlot {
    LinePlot {
        title,
        x_label: x_label.into(),
        y_label: y_label.into(),
        series,
        x_scale: axes.x,
        y_scale: axes.y,
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
    let mut l = grid_label(p);
    if !p.converged() {
        l.push_str(" (not converged)");
    }
    l
}

/// `λd = 0.01, …` of a point's grid values; the point's folder name for a run without a grid.
fn grid_label(p: &PointResult) -> String {
    if p.point.is_empty() {
        return p.label.clone();
    }
    p.point.iter().map(|(k, v)| format!("{} = {v}", pretty_key(k))).collect::<Vec<_>>().join(", ")
}

/// How a fixed point's history ended, in the paper's sense, for its legend entry: a run whose
/// relative change met the stopping rule converged (outcome `ok`, or `stalled`: the rule met
/// with a residual certificate above our tolerance, `docs/certificate.md`), and its entry
/// says nothing; the others say why they stopped.
fn history_end(outcome: Outcome) -> &'static str {
    match outcome {
        Outcome::Converged | Outcome::CompleteWithWarnings | Outcome::Stalled => "",
        Outcome::IterationLimit => " (not converged: iteration limit)",
        Outcome::Failed => " (failed)",
        Outcome::Interrupted => " (interrupted)",
    }
}

/// The frame interval Δt [s] of a run's clip (1 s if the run is not a clip: then "t" counts
/// frames, which no figure of a clip does).
fn frame_interval_s(spec: &Spec, name: &str) -> f64 {
    spec.run(name).and_then(|r| r.case.inverse()).map_or(1.0, |i| i.params.frame_interval_s)
}

fn figure(spec: &Spec, p: &PlotSpec, runs: &[RunResults]) -> Option<Svg> {
    let title = &p.title;
    match &p.show {
        PlotKind::Convergence { run: name } => {
            let rule = spec.run(name).and_then(|r| stopping_rule(&r.case));
            convergence(title, run(runs, name)?, rule)
        }
        PlotKind::Recovered { run: name, at } => rod::recovered(title, first_at(runs, name, at)?),
        PlotKind::Controls { run: name, at } => {
            let case = &spec.run(name)?.case;
            rod::controls(title, case, first_at(runs, name, at)?)
        }
        PlotKind::TipHistory { run: name } => {
            let case = &spec.run(name)?.case;
            rod::tip_history(title, case, first_at(runs, name, &Selector::new())?)
        }
        PlotKind::Deflection { runs: names } => {
            let pts: Vec<(&Case, &PointResult)> =
                names.iter().filter_map(|n| Some((&spec.run(n)?.case, first_at(runs, n, &Selector::new())?))).collect();
            rod::deflection(title, &pts)
        }
        PlotKind::Kymograph { run: name, at } => {
            clip::kymograph(title, first_at(runs, name, at)?, frame_interval_s(spec, name))
        }
        PlotKind::Objectives { runs: names, at } => clip::objectives(spec, title, names, at, runs),
        PlotKind::Omega { runs: names } => clip::omega(spec, title, names, runs),
        PlotKind::Postures { run: name, frames, at } => {
            clip::postures(title, first_at(runs, name, at)?, frames, run(runs, name)?)
        }
        PlotKind::Tradeoff { run: name, metric } => tradeoff(title, run(runs, name)?, metric),
    }
}

/// The stopping rule of the paper's fixed point in `case`: its tolerance on the relative change
/// of (x, α) (D5; `None` for a case that is not solved by the fixed point).
fn stopping_rule(case: &Case) -> Option<f64> {
    let params = case.inverse()?.params;
    matches!(params.method, InverseMethod::FixedPoint).then_some(params.tolerance)
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
    Some(render_svg(&line(title.to_string(), "solve wall time [s]", metric, series, Axes::LOG_LOG)))
}

/// Figs. 9–11, 13: log-log histories of every point, one panel per measure. Each curve is
/// labelled by its grid values and how it ended ([`history_end`]); the relative change's panel
/// draws the stopping rule `rule` (its tolerance) as a dashed horizontal line.
fn convergence(title: &str, r: &RunResults, rule: Option<f64>) -> Option<Svg> {
    let measures = [
        ("x_err_rel", "|x − x_g| / |x_g| [–]"),
        ("kappa_err_rel", "|κ − κ_f| / |κ_f| [–]"),
        ("tangent_misfit", "‖∂s x − d3‖ [m^½]"),
        ("rel_change", "relative change of (x, α) [–]"),
    ];
    let single = r.points.iter().all(|p| p.point.is_empty());
    let mut panels = Vec::new();
    for (name, y) in measures {
        let mut series: Vec<Series> = r
            .points
            .iter()
            .filter_map(|p| {
                let h = history_of(p, name)?;
                let name = if single { "fixed point".to_string() } else { grid_label(p) };
                let l = format!("{name}{}", history_end(p.outcome.status));
                (!h.is_empty()).then(|| Series::new(l, (1..=h.len()).map(|k| k as f64).collect(), h))
            })
            .enumerate()
            .map(|(i, s)| s.nth_of_many(i))
            .collect();
        if series.is_empty() {
            continue;
        }
        let rule_line = rule.filter(|_| name == "rel_change").map(|tol| {
            let last = series.iter().map(|s| s.x.len()).max().unwrap_or(1).max(2) as f64;
            Series::new(
                format!("stopping rule: {}", crate::figures::plot::format_tick(tol)),
                vec![1.0, last],
                vec![tol, tol],
            )
            .marked(Mark::Dashed)
            .coloured(7)
        });
        series.extend(rule_line.clone());
        let mut panel = line(y.to_string(), "iteration", y, series, Axes::LOG_LOG);
        // a run without a grid: one curve, described by the figure's title (and the rule's line)
        if single && rule_line.is_none() {
            panel.legend = Legend::Hidden;
        }
        panels.push(panel);
    }
    (!panels.is_empty()).then(|| render_figure_svg(title, &panels, 2))
}
