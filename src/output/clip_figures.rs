//! The summary figures of a clip run, written at the end over the frames solved: `plot.svg`,
//! `kymograph.svg`, `omega.svg`, `truth.svg` and `truth_errors.svg`.
use std::path::Path;

use crate::case::Case;
use crate::engine::clip::{ClipRun, KymographColumn};
use crate::figures::decimate::{min_max, MAX_LINE_POINTS};
use crate::figures::heatmap::{render_marked_heatmaps_svg, ColourScale, ColumnMarks, Heatmap};
use crate::figures::panels::render_panels_svg;
use crate::figures::plot::{LinePlot, Scale, Series};
use crate::io::files::{write_plot, OutputError};
use crate::solve::sequence::FrameReport;

/// The times of a clip run's frames [s] (frame number × Δt) as the x axis of its per-frame
/// figures and kymographs; each curve drawn with at most [`MAX_LINE_POINTS`] points
/// ([`min_max`]: an hour of frames is drawn as its envelope).
struct FrameAxis(Vec<f64>);

impl FrameAxis {
    fn new(case: &Case, reports: &[FrameReport]) -> Self {
        let dt = frame_interval_s(case);
        FrameAxis(reports.iter().map(|r| r.frame as f64 * dt).collect())
    }
    fn series(&self, label: &str, y: Vec<f64>) -> Series {
        let (x, y) = min_max(&self.0, &y, MAX_LINE_POINTS);
        Series::new(label, x, y)
    }
    fn plot(title: String, y_label: &str, series: Vec<Series>, y_scale: Scale) -> LinePlot {
        LinePlot { title, x_label: "t [s]".into(), y_label: y_label.into(), series, y_scale, ..Default::default() }
    }
}

/// The columns of a clip run's kymographs: their times [s] and the marks of the frames they
/// stand for (`Kymograph::span`) that were lost (no node tracked: `frames.csv`'s
/// `nodes_tracked` = 0, the frame's data filled from its neighbours, D19) or flagged (over the
/// fit-quality gate: `flagged` = 1).
fn kymograph_columns(case: &Case, run: &ClipRun) -> (Vec<f64>, ColumnMarks) {
    let k = &run.kymograph;
    let axis = FrameAxis::new(case, &run.reports);
    let times = k.columns.iter().map(|c| axis.0[c.index]).collect();
    let nf = run.reports.len();
    let mut marks = ColumnMarks::default();
    let (mut lost, mut flagged) = (0, 0);
    for c in 0..k.columns.len() {
        let span = &run.reports[k.span(c, nf)];
        let l = span.iter().filter(|r| r.nodes_tracked == 0).count();
        let f = span.iter().filter(|r| r.fit.flagged).count();
        (lost, flagged) = (lost + l, flagged + f);
        if l > 0 {
            marks.hatched.push(c);
        }
        if f > 0 {
            marks.barred.push(c);
        }
    }
    let per = if k.stride > 1 { format!(" (a column: {} frames)", k.stride) } else { String::new() };
    let frames = |n: usize| if n == 1 { "1 frame".to_string() } else { format!("{n} frames") };
    marks.hatched_label = format!("lost: {} without a tracked node, filled{per}", frames(lost));
    marks.barred_label = format!("flagged: {} over the fit-quality gate{per}", frames(flagged));
    (times, marks)
}

/// The clip's frame interval Δt [s].
fn frame_interval_s(case: &Case) -> f64 {
    case.inverse().map_or(1.0, |i| i.params.frame_interval_s)
}

/// A kymograph of a clip run: `values` (already in the unit of `colour_label`) over the frames'
/// times and `s_mm`, clipped at ±`limit`.
fn kymograph(
    title: String,
    t: Vec<f64>,
    s_mm: Vec<f64>,
    values: Vec<Vec<f64>>,
    limit: f64,
    colour_label: &str,
) -> Heatmap {
    Heatmap::kymograph(title, t, s_mm, values, limit, colour_label.into())
}

/// Recovered vs true for a synthetic clip (`truth.svg`): bending κ1² + κ2² kymographs (true,
/// recovered) and per frame the errors, the roll offset against the true roll, and κ3.
pub fn write_truth_plot(case: &Case, run: &ClipRun, path: &Path) -> Result<(), OutputError> {
    let Some(t) = &run.truth else { return Ok(()) };
    let nf = t.comparisons.len();
    if nf < 2 {
        return Ok(());
    }
    let axis = FrameAxis::new(case, &run.reports);
    let (s, plot) = (|l: &str, y| axis.series(l, y), FrameAxis::plot);
    let c = &t.comparisons;
    let panels = vec![
        plot(
            format!("{}: errors against the ground truth", case.name),
            "relative error / rad",
            vec![
                s("|x - x_true|/|x_true|", c.iter().map(|v| v.position_rel_l2).collect()),
                s("bending k1^2+k2^2, rel. L2", c.iter().map(|v| v.bending_rel_l2).collect()),
                s("max angle(d3, true d3) [rad]", c.iter().map(|v| v.max_tangent_angle_rad).collect()),
            ],
            Scale::Log,
        ),
        plot(
            "roll of the frame about d3".into(),
            "angle [rad]",
            vec![
                s("true roll psi of the bending plane", t.roll_rad.clone()),
                s("recovered d1 vs true d1 (offset)", c.iter().map(|v| v.roll_offset_rad).collect()),
            ],
            Scale::Linear,
        ),
        plot(
            "twist κ3".into(),
            "κ3 [1/mm]",
            vec![
                s("true", t.twist_per_m.iter().map(|v| v * 1e-3).collect()),
                s("recovered (mean over inner nodes)", c.iter().map(|v| v.twist_mean_per_m * 1e-3).collect()),
                s("rms error", c.iter().map(|v| v.twist_rms_error_per_m * 1e-3).collect()),
            ],
            Scale::Linear,
        ),
        plot(
            "angle chart: min |cos beta| over the nodes".into(),
            "|cos beta|",
            vec![s("rebased chart", run.reports.iter().map(|r| r.conditioning.min_cos_beta).collect())],
            Scale::Linear,
        ),
    ];
    let lines = path.with_file_name("truth_errors.svg");
    write_plot(&lines, render_panels_svg(&panels, 2))?;
    let k = &run.kymograph;
    let bending: Vec<&[Vec<f64>; 2]> = k.columns.iter().filter_map(|c| c.bending.as_ref()).collect();
    if bending.len() < 2 || bending.len() != k.columns.len() {
        return Ok(());
    }
    let (x, marks) = kymograph_columns(case, run);
    let m = bending[0][0].len();
    let cols: Vec<usize> = (0..m).step_by(m.div_ceil(64)).collect();
    let y: Vec<f64> = cols.iter().map(|&j| j as f64 * case.mesh.h() * 1e3).collect();
    // bending √(κ1² + κ2²) [1/mm]
    let grid = |which: usize| -> Vec<Vec<f64>> {
        bending.iter().map(|b| cols.iter().map(|&j| b[which][j].sqrt() * 1e-3).collect()).collect()
    };
    let limit = percentile_99(bending.iter().flat_map(|b| b[0].iter()).map(|v| v.sqrt() * 1e-3).collect());
    let map = |title: &str, values: Vec<Vec<f64>>| Heatmap {
        scale: ColourScale::Sequential,
        ..kymograph(title.into(), x.clone(), y.clone(), values, limit, "√(κ1² + κ2²) [1/mm]")
    };
    write_plot(
        path,
        render_marked_heatmaps_svg(
            &[map(&format!("{}: true bending", case.name), grid(0)), map("recovered bending", grid(1))],
            &marks,
        ),
    )
}

/// Per-frame summary of a clip run: iterations, fit, chart guard and roughness against frame.
pub fn write_clip_plot(
    case: &Case,
    reports: &[FrameReport],
    roughness: &[(f64, f64)],
    path: &Path,
) -> Result<(), OutputError> {
    if reports.is_empty() {
        return Ok(());
    }
    let axis = FrameAxis::new(case, reports);
    let (s, plot) = (|l: &str, y| axis.series(l, y), FrameAxis::plot);
    let panels = vec![
        plot(
            format!("{}: iterations per frame", case.name),
            "iterations",
            vec![s("iterations", reports.iter().map(|r| r.convergence.iterations as f64).collect())],
            Scale::Linear,
        ),
        plot(
            "fit per frame".into(),
            "misfit (units in the legend)",
            vec![
                s("position misfit [body lengths]", reports.iter().map(|r| r.fit.position).collect()),
                s("|x' - d3| [m^1/2]", reports.iter().map(|r| r.misfit.tangent_misfit).collect()),
                s("last relative change", reports.iter().map(|r| r.convergence.last_change).collect()),
            ],
            Scale::Log,
        ),
        plot(
            "angle chart: min |cos beta| over the nodes".into(),
            "|cos beta|",
            vec![s("min |cos beta|", reports.iter().map(|r| r.conditioning.min_cos_beta).collect())],
            Scale::Linear,
        ),
        plot(
            "objective (41)".into(),
            "J (41)",
            vec![
                s("tracking", reports.iter().map(|r| r.misfit.objective.tracking).collect()),
                s("total", reports.iter().map(|r| r.misfit.objective.total()).collect()),
            ],
            Scale::Log,
        ),
        plot(
            "roughness of the curvature (sign alternation of its differences)".into(),
            "fraction of elements [–]",
            vec![
                s("recovered κ2", roughness.iter().map(|r| r.0).collect()),
                s("data", roughness.iter().map(|r| r.1).collect()),
            ],
            Scale::Linear,
        ),
    ];
    write_plot(path, render_panels_svg(&panels, 2))
}

/// Kymographs of a planar clip (Fig. 17 style): the data's curvature and the recovered κ2
/// [1/mm] over time [s] (x) and arc length (y, head at 0), on one colour scale (±the 99th
/// percentile of |data| over the frames drawn, the colour bar beside each), lost and flagged
/// frames marked ([`kymograph_columns`]). At most `KYMOGRAPH_COLUMNS` frames
/// (`ClipRun::kymograph`) and 64 positions are drawn (strided) to keep the SVG small.
pub fn write_clip_kymographs(case: &Case, run: &ClipRun, path: &Path) -> Result<(), OutputError> {
    let k = &run.kymograph;
    if k.columns.len() < 2 {
        return Ok(());
    }
    let (x, marks) = kymograph_columns(case, run);
    let h = case.mesh.h();
    let grid = |field: &dyn Fn(&KymographColumn) -> &[f64], s_of: &dyn Fn(usize) -> f64| {
        let m = field(&k.columns[0]).len();
        let cols: Vec<usize> = (0..m).step_by(m.div_ceil(64)).collect();
        let y: Vec<f64> = cols.iter().map(|&j| s_of(j) * 1e3).collect();
        let values: Vec<Vec<f64>> =
            k.columns.iter().map(|c| cols.iter().map(|&j| field(c)[j] * 1e-3).collect()).collect();
        (y, values)
    };
    let limit = abs_percentile_99(k.columns.iter().flat_map(|c| c.data_kappa.iter()).map(|v| v * 1e-3));
    let (yd, vd) = grid(&|c| &c.data_kappa, &|j| (j + 1) as f64 * h);
    let (yr, vr) = grid(&|c| &c.kappa2, &|j| (j as f64 + 0.5) * h);
    write_plot(
        path,
        render_marked_heatmaps_svg(
            &[
                kymograph(format!("{}: data curvature", case.name), x.clone(), yd, vd, limit, "κ data [1/mm]"),
                kymograph(format!("recovered κ2{}", planar_caption(case)), x, yr, vr, limit, "κ2 [1/mm]"),
            ],
            &marks,
        ),
    )
}

/// The caption of a planar recording's recovered curvature and angular velocity: its twist and
/// roll are the gauge's, not measured (`clip::recording`, run.json's `planar`).
fn planar_caption(case: &Case) -> &'static str {
    match case.clip().and_then(|c| c.recording.data_plane) {
        Some(_) => " (planar data: twist κ3 and roll not observable, set by the gauge)",
        None => "",
    }
}

/// The 99th percentile of |v| over the finite values (1 if there are none): the colour limit
/// of a kymograph.
pub(crate) fn abs_percentile_99(values: impl Iterator<Item = f64>) -> f64 {
    percentile_99(values.map(f64::abs).filter(|v| v.is_finite()).collect())
}

/// The value at rank `⌊0.99 n⌋` of `all` in ascending order (`f64::total_cmp`; 1 for none), by
/// selection rather than a full sort: the same value.
fn percentile_99(mut all: Vec<f64>) -> f64 {
    let k = (all.len() as f64 * 0.99) as usize;
    if k >= all.len() {
        return 1.0;
    }
    *all.select_nth_unstable_by(k, f64::total_cmp).1
}

/// Kymographs of the angular velocity (Fig. 24 style, `omega.svg`): ω1, ω2, ω3 [rad/s] in the
/// local frame (eq. 27, `ClipFrame::omega`) over time [s] (x) and the nodes' arc length (y),
/// each on its own colour scale (±the 99th percentile of its |ω| over the frames drawn after the
/// first, which has none; the colour bar beside it), lost and flagged frames marked. Sampled
/// as [`write_clip_kymographs`]; nothing is written for fewer than two frames drawn.
pub fn write_omega_kymographs(case: &Case, run: &ClipRun, path: &Path) -> Result<(), OutputError> {
    let k = &run.kymograph;
    if k.columns.len() < 2 {
        return Ok(());
    }
    let (x, marks) = kymograph_columns(case, run);
    let m = k.columns[0].omega.len();
    let cols: Vec<usize> = (0..m).step_by(m.div_ceil(64).max(1)).collect();
    let y: Vec<f64> = cols.iter().map(|&j| case.mesh.node_s(j) * 1e3).collect();
    let maps: Vec<Heatmap> = (0..3)
        .map(|i| {
            let after_first = k.columns.iter().filter(|c| c.index > 0);
            let limit = abs_percentile_99(after_first.flat_map(|c| c.omega.iter()).map(|w| w[i]));
            let name = if i == 0 { format!("{}: ", case.name) } else { String::new() };
            let zero = if limit > 0.0 { "" } else { ": 0 everywhere" };
            kymograph(
                format!("{name}ω{} (local frame){zero}", i + 1),
                x.clone(),
                y.clone(),
                k.columns.iter().map(|c| cols.iter().map(|&j| c.omega[j][i]).collect()).collect(),
                limit,
                &format!("ω{} [rad/s]", i + 1),
            )
        })
        .collect();
    write_plot(path, render_marked_heatmaps_svg(&maps, &marks))
}

/// The summary figures of a clip run in `dir`: `plot.svg` (per frame: iterations, fit, chart,
/// objective, roughness), `kymograph.svg` and, for synthetic clips, `truth.svg`.
/// The angular-velocity kymographs (the largest figure: three heatmaps) are drawn on a second
/// thread while this one draws the others (worm_roll_3d: 21 ms against 24 ms).
pub fn write_clip_figures(case: &Case, run: &ClipRun, dir: &Path) -> Result<(), OutputError> {
    std::thread::scope(|s| {
        let omega = s.spawn(|| write_omega_kymographs(case, run, &dir.join("omega.svg")));
        let others = write_clip_kymographs(case, run, &dir.join("kymograph.svg"))
            .and_then(|()| write_clip_plot(case, &run.reports, &run.roughness, &dir.join("plot.svg")))
            .and_then(|()| write_truth_plot(case, run, &dir.join("truth.svg")));
        let omega = omega.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        others.and(omega)
    })
}
