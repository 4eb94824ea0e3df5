//! Writing a run to disk: CSV with headers and SI units in the column names, `metrics.json`,
//! and an SVG plot of the headline result, each written atomically (`io::files`).
use std::path::{Path, PathBuf};

use crate::case::Case;
use crate::engine::metrics::Metrics;
use crate::engine::{InverseOutput, RunResult};
use crate::figures::panels::render_panels_svg;
use crate::figures::plot::{LinePlot, Mark, Scale, Series};
use crate::io::compact::CURVATURE_COLUMNS;
use crate::io::files::{csv_text, csv_text_int, write_atomic, write_plot, OutputError};
use crate::model::resultants::Resultants;
use crate::solve::inverse::ObjectiveTerms;

/// Write every output of a run into `dir`; returns the written paths.
pub fn write_run(case: &Case, r: &RunResult, metrics: &Metrics, dir: &Path) -> Result<Vec<PathBuf>, OutputError> {
    let mut written = Vec::new();
    let mut put = |name: &str, bytes: Vec<u8>| -> Result<(), OutputError> {
        let p = dir.join(name);
        write_atomic(&p, &bytes)?;
        written.push(p);
        Ok(())
    };
    let disp = r.nodes.displacement();
    let rows = (0..r.nodes.s.len()).map(|i| {
        let (x, a, u) = (r.nodes.x[i], r.nodes.alpha[i], disp[i]);
        vec![r.nodes.s[i], x[0], x[1], x[2], u[0], u[1], u[2], a[0], a[1], a[2]]
    });
    put(
        "nodes.csv",
        csv_text(&["s_m", "x_m", "y_m", "z_m", "ux_m", "uy_m", "uz_m", "alpha_rad", "beta_rad", "gamma_rad"], rows)
            .into_bytes(),
    )?;
    put("curvature.csv", curvature_csv(case, r).into_bytes())?;
    if !r.history.is_empty() {
        put(
            "history.csv",
            csv_text_int(
                &["continuation_step", "iteration", "change", "certificate"],
                &["continuation_step", "iteration"],
                r.history
                    .iter()
                    .map(|h| vec![Some(h.step as f64), Some(h.iteration as f64), Some(h.change), Some(h.certificate)]),
            )
            .into_bytes(),
        )?;
    }
    if !r.tip.is_empty() {
        let rows = r.tip.iter().map(|t| {
            let (x, a) = (t.position_m, t.angles_rad);
            [t.time_s, x[0], x[1], x[2], a[0], a[1], a[2], t.newton_iterations as f64, t.certificate]
                .into_iter()
                .map(Some)
                .collect()
        });
        put(
            "tip_history.csv",
            csv_text_int(
                &[
                    "time_s",
                    "tip_x_m",
                    "tip_y_m",
                    "tip_z_m",
                    "tip_alpha_rad",
                    "tip_beta_rad",
                    "tip_gamma_rad",
                    "newton_iterations",
                    "certificate",
                ],
                &["newton_iterations"],
                rows,
            )
            .into_bytes(),
        )?;
        put("balance.csv", balance_csv(&r.tip).into_bytes())?;
        if let Some(text) = charts_csv(&r.tip) {
            put("charts.csv", text.into_bytes())?;
        }
    }
    if let Some(inv) = &r.inverse {
        write_inverse(r, inv, &mut put)?;
    }
    if let Some(p) = &r.path {
        put("path.csv", super::path_files::path_csv(p).into_bytes())?;
        put("critical_points.csv", super::path_files::critical_csv(p).into_bytes())?;
    }
    if let Some(st) = &r.stability {
        write_eigen(r, st, &mut put)?;
    }
    write_metrics(case, r, metrics, &mut put)?;
    let plot_path = dir.join("plot.svg");
    write_plot(&plot_path, render_panels_svg(&headline_panels(case, r), 2))?;
    written.push(plot_path);
    Ok(written)
}

/// A static result's eigen-analyses: `buckling.csv` with buckling modes (D27), `modes.csv` with
/// natural frequencies (D28).
fn write_eigen(
    r: &RunResult,
    st: &crate::engine::StabilityOutput,
    put: &mut impl FnMut(&str, Vec<u8>) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    if !st.modes.is_empty() {
        put("buckling.csv", super::path_files::buckling_csv(st, &r.nodes.s).into_bytes())?;
    }
    if !st.omegas_rad_per_s.is_empty() {
        put("modes.csv", super::modes_file::modes_csv(st).into_bytes())?;
    }
    Ok(())
}

/// `metrics.json` and, for a case with published values, `reference.csv`.
fn write_metrics(
    case: &Case,
    r: &RunResult,
    metrics: &Metrics,
    put: &mut impl FnMut(&str, Vec<u8>) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    let json = serde_json::to_string_pretty(metrics).unwrap_or_else(|_| "{}".into());
    put("metrics.json", json.into_bytes())?;
    let published = crate::engine::published::evaluate(case, r, metrics);
    if !published.is_empty() {
        put("reference.csv", super::reference_file::run_csv(&published).into_bytes())?;
    }
    Ok(())
}

/// One row of `curvature.csv` ([`CURVATURE_COLUMNS`]): an element's midpoint [m], curvature
/// [1/m] and stress resultants [N, N m].
pub fn element_row(((s, k), r): (&(f64, nalgebra::Vector3<f64>), &Resultants)) -> Vec<f64> {
    let mut row = vec![*s, k[0], k[1], k[2]];
    for v in [r.n, r.m, r.n_local, r.m_local] {
        row.extend(v.iter());
    }
    row
}

/// The inverse-specific files: recovered frame and controls along the rod, curvature against
/// the data's, and the per-iteration history.
fn write_inverse(
    r: &RunResult,
    inv: &InverseOutput,
    put: &mut impl FnMut(&str, Vec<u8>) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    let d = r.nodes.directors();
    let (f, l) = (inv.force(), inv.torque());
    let mut header: Vec<String> =
        ["s_m", "x_m", "y_m", "z_m", "alpha_rad", "beta_rad", "gamma_rad"].iter().map(|s| s.to_string()).collect();
    for i in 1..=3 {
        header.extend(["x", "y", "z"].iter().map(|c| format!("d{i}_{c}")));
    }
    header.extend(["x", "y", "z"].iter().map(|c| format!("f_{c}_n_per_m")));
    header.extend(["x", "y", "z"].iter().map(|c| format!("l_{c}_nm_per_m")));
    header.extend(["x", "y", "z"].iter().map(|c| format!("data_{c}_m")));
    let rows = (0..r.nodes.s.len()).map(|i| {
        let mut row = vec![r.nodes.s[i]];
        row.extend(r.nodes.x[i].iter());
        row.extend(r.nodes.alpha[i].iter());
        for dk in &d[i] {
            row.extend(dk.iter());
        }
        row.extend(f[i].iter());
        row.extend(l[i].iter());
        row.extend(inv.data.x[i].iter());
        row
    });
    let h: Vec<&str> = header.iter().map(String::as_str).collect();
    put("inverse_nodes.csv", csv_text(&h, rows).into_bytes())?;
    let (k, kf) = (r.nodes.element_curvature(), inv.data.element_curvature());
    let rows = k.iter().zip(&kf).map(|((s, a), (_, b))| vec![*s, a[0], a[1], a[2], b[0], b[1], b[2]]);
    put(
        "inverse_curvature.csv",
        csv_text(
            &[
                "s_mid_m",
                "kappa1_per_m",
                "kappa2_per_m",
                "kappa3_per_m",
                "data_kappa1_per_m",
                "data_kappa2_per_m",
                "data_kappa3_per_m",
            ],
            rows,
        )
        .into_bytes(),
    )?;
    let mut header = vec!["iteration", "rel_change", "x_err_rel", "tangent_misfit_m05"];
    header.extend(ObjectiveTerms::NAMES);
    // Newton runs add the equilibrated residual ‖D_r R‖/‖D_r R₀‖ of I8 (empty on the rows of
    // the fixed-point warm start).
    let newton = inv.history.iter().any(|h| h.residual.is_some());
    if newton {
        header.push("newton_residual_rel");
    }
    header.push("certificate");
    header.extend(["kappa_err_rel", "kappa_err_rel_inner"]);
    let rows = inv.history.iter().enumerate().map(|(i, h)| {
        let mut row: Vec<Option<f64>> =
            [h.iteration as f64, h.rel_change, h.x_err_rel, h.tangent_misfit].into_iter().map(Some).collect();
        row.extend(h.objective.values().into_iter().map(Some));
        if newton {
            row.push(h.residual);
        }
        row.push(h.certificate);
        let k = inv.kappa_err.get(i);
        row.extend([k.map(|k| k[0]), k.map(|k| k[1])]);
        row
    });
    put("inverse_history.csv", csv_text_int(&header, &["iteration"], rows).into_bytes())?;
    Ok(())
}

/// The headline figure: tip history for dynamic runs (Fig. 5 analogue), deflection and
/// curvature along the rod for static runs (Fig. 7 analogue).
pub fn headline_panels(case: &Case, r: &RunResult) -> Vec<LinePlot> {
    let series = |label: &str, x: Vec<f64>, y: Vec<f64>| Series::new(label, x, y);
    let plot = |title: &str, xl: &str, yl: &str, s: Vec<Series>| LinePlot {
        title: title.into(),
        x_label: xl.into(),
        y_label: yl.into(),
        series: s,
        ..Default::default()
    };
    if let Some(inv) = &r.inverse {
        return inverse_panels(case, r, inv);
    }
    if let Some(p) = &r.path {
        return vec![super::path_files::path_panel(case, p)];
    }
    if !r.tip.is_empty() {
        let t: Vec<f64> = r.tip.iter().map(|p| p.time_s).collect();
        let comp = |k: usize| r.tip.iter().map(|p| p.position_m[k] - r.tip[0].position_m[k]).collect::<Vec<_>>();
        let ang = |k: usize| r.tip.iter().map(|p| p.angles_rad[k]).collect::<Vec<_>>();
        vec![
            plot(
                &format!("{}: tip displacement", case.name),
                "t [s]",
                "displacement [m]",
                vec![
                    series("u_x", t.clone(), comp(0)),
                    series("u_y", t.clone(), comp(1)),
                    series("u_z", t.clone(), comp(2)),
                ],
            ),
            plot(
                "tip rotation",
                "t [s]",
                "angle [rad]",
                vec![series("alpha", t.clone(), ang(0)), series("beta", t.clone(), ang(1)), series("gamma", t, ang(2))],
            ),
        ]
    } else {
        let s = r.nodes.s.clone();
        let disp = r.nodes.displacement();
        let kappa = r.nodes.element_curvature();
        let sk: Vec<f64> = kappa.iter().map(|k| k.0).collect();
        vec![
            plot(
                &format!("{}: displacement", case.name),
                "s [m]",
                "displacement [m]",
                (0..3)
                    .map(|k| series(["u_x", "u_y", "u_z"][k], s.clone(), disp.iter().map(|u| u[k]).collect()))
                    .collect(),
            ),
            plot(
                "curvature (eq. 28)",
                "s [m]",
                "kappa [1/m]",
                (0..3)
                    .map(|k| {
                        series(["kappa_1", "kappa_2", "kappa_3"][k], sk.clone(), kappa.iter().map(|c| c.1[k]).collect())
                    })
                    .collect(),
            ),
        ]
    }
}

/// Figs. 8/12/14 analogues (position and curvature, data vs recovered), Fig. 15 (controls f, l)
/// and the convergence history (Figs. 9–11 style, log-log).
fn inverse_panels(case: &Case, r: &RunResult, inv: &InverseOutput) -> Vec<LinePlot> {
    let series = |label: String, x: Vec<f64>, y: Vec<f64>| Series::new(label, x, y);
    // the data as markers under the inverse solution (solid), in the same colour
    let data =
        |label: String, x: Vec<f64>, y: Vec<f64>, c: usize| series(label, x, y).marked(Mark::Markers).coloured(c);
    let plot = |title: String, xl: &str, yl: &str, s: Vec<Series>, scale: Scale| LinePlot {
        title,
        x_label: xl.into(),
        y_label: yl.into(),
        series: s,
        x_scale: scale,
        y_scale: scale,
        ..Default::default()
    };
    // one length unit per figure: mm for a rod shorter than 10 cm (the worm's scale), else m
    let (unit, to) = if case.mesh.length_m < 0.1 { ("mm", 1e3) } else { ("m", 1.0) };
    let s: Vec<f64> = r.nodes.s.iter().map(|s| s * to).collect();
    let comp = ["x", "y", "z"];
    let mut pos = Vec::new();
    for k in 0..3 {
        let d = inv.data.x.iter().map(|v| v[k] * to).collect();
        pos.push(data(format!("{} data", comp[k]), s.clone(), d, k));
        let x = r.nodes.x.iter().map(|v| v[k] * to).collect();
        pos.push(series(format!("{} inverse", comp[k]), s.clone(), x).coloured(k));
    }
    let (k, kf) = (r.nodes.element_curvature(), inv.data.element_curvature());
    let sk: Vec<f64> = k.iter().map(|p| p.0 * to).collect();
    let mut curv = Vec::new();
    for c in 0..3 {
        curv.push(data(format!("κ{} data", c + 1), sk.clone(), kf.iter().map(|p| p.1[c] / to).collect(), c));
        let rec = k.iter().map(|p| p.1[c] / to).collect();
        curv.push(series(format!("κ{} inverse", c + 1), sk.clone(), rec).coloured(c));
    }
    // f [N/m] → [N/unit]; l [N m/m] = [N unit/unit]
    let (f, l) = (inv.force(), inv.torque());
    let ctrl = |v: &[nalgebra::Vector3<f64>], name: &str, scale: f64| {
        (0..3)
            .map(|c| series(format!("{name}{}", c + 1), s.clone(), v.iter().map(|x| x[c] * scale).collect()))
            .collect::<Vec<_>>()
    };
    let it: Vec<f64> = inv.history.iter().map(|h| h.iteration as f64).collect();
    let hist = vec![
        series("relative change".into(), it.clone(), inv.history.iter().map(|h| h.rel_change).collect()),
        series("|x - x_g|/|x_g|".into(), it.clone(), inv.history.iter().map(|h| h.x_err_rel).collect()),
        series("|x' - d3| [m^1/2]".into(), it.clone(), inv.history.iter().map(|h| h.tangent_misfit).collect()),
    ];
    let mut hist = hist;
    if inv.kappa_err.len() == it.len() {
        hist.push(series("|kappa - kappa_f|/|kappa_f|".into(), it, inv.kappa_err.iter().map(|k| k[0]).collect()));
    }
    let s_label = format!("s [{unit}]");
    vec![
        plot(
            format!("{}: centreline, data vs inverse", case.name),
            &s_label,
            &format!("position [{unit}]"),
            pos,
            Scale::Linear,
        ),
        plot("curvature (eq. 28), data vs inverse".into(), &s_label, &format!("κ [1/{unit}]"), curv, Scale::Linear),
        plot(
            "recovered force f = x̂/λf (eq. 54), global frame".into(),
            &s_label,
            &format!("f [N/{unit}]"),
            ctrl(&f, "f", 1.0 / to),
            Scale::Linear,
        ),
        plot(
            "recovered torque l = α̂/λl (eq. 54), global frame".into(),
            &s_label,
            &format!("l [N {unit}/{unit}]"),
            ctrl(&l, "l", 1.0),
            Scale::Linear,
        ),
        plot("convergence history".into(), "iteration", "change, error [–]; ‖x' − d3‖ [m^½]", hist, Scale::Log),
    ]
}

/// Convergence histories of several runs in one figure (Figs. 9–11 style, log-log): for inverse
/// runs ‖x − x_g‖/‖x_g‖, the curvature error and the relative change per iteration, for static
/// runs the change.
pub fn write_convergence_plot(runs: &[(&String, &RunResult)], path: &Path) -> Result<(), OutputError> {
    let plot = |title: &str, yl: &str, series: Vec<Series>| LinePlot {
        title: title.into(),
        x_label: "iteration".into(),
        y_label: yl.into(),
        series,
        x_scale: Scale::Log,
        y_scale: Scale::Log,
        ..Default::default()
    };
    let mut xerr = Vec::new();
    let mut kerr = Vec::new();
    let mut change = Vec::new();
    for (name, r) in runs {
        if let Some(inv) = &r.inverse {
            let it: Vec<f64> = inv.history.iter().map(|h| h.iteration as f64).collect();
            if inv.kappa_err.len() == it.len() {
                kerr.push(Series::new(name.to_string(), it.clone(), inv.kappa_err.iter().map(|k| k[0]).collect()));
            }
            xerr.push(Series::new(name.to_string(), it.clone(), inv.history.iter().map(|h| h.x_err_rel).collect()));
            change.push(Series::new(name.to_string(), it, inv.history.iter().map(|h| h.rel_change).collect()));
        } else if !r.history.is_empty() {
            change.push(Series::new(
                name.to_string(),
                (1..=r.history.len()).map(|k| k as f64).collect(),
                r.history.iter().map(|h| h.change).collect(),
            ));
        }
    }
    // the runs' curves may lie on each other: each narrower than the one before
    let many = |v: Vec<Series>| v.into_iter().enumerate().map(|(i, s)| s.nth_of_many(i)).collect::<Vec<_>>();
    let (xerr, kerr, change) = (many(xerr), many(kerr), many(change));
    let mut panels = Vec::new();
    if !xerr.is_empty() {
        panels.push(plot("|x - x_g| / |x_g|", "relative error", xerr));
    }
    if !kerr.is_empty() {
        panels.push(plot("|kappa - kappa_f| / |kappa_f| (eq. 28)", "relative error", kerr));
    }
    if !change.is_empty() {
        panels.push(plot("relative change of (x, alpha)", "relative change", change));
    }
    if panels.is_empty() {
        return Ok(());
    }
    write_plot(path, render_panels_svg(&panels, 2))
}

/// `balance.csv` of a dynamic run: the rod's energy and momenta per time step
/// (`model::balance`; momenta in space coordinates, angular momentum about the origin) and
/// whether the step is loaded (a load acts or an end moves: 1) or free (0).
fn balance_csv(tip: &[crate::solve::dynamics::TipRecord]) -> String {
    let rows = tip.iter().map(|t| {
        let (b, p, h) = (&t.balance, t.balance.momentum_n_s, t.balance.angular_momentum_n_m_s);
        let loaded = if t.loaded { 1.0 } else { 0.0 };
        [t.time_s, b.kinetic_j, b.elastic_j, b.energy_j(), p[0], p[1], p[2], h[0], h[1], h[2], loaded]
            .into_iter()
            .map(Some)
            .collect()
    });
    csv_text_int(&BALANCE_COLUMNS, &["loaded"], rows)
}

/// The columns of `balance.csv`.
const BALANCE_COLUMNS: [&str; 11] = [
    "time_s",
    "kinetic_energy_j",
    "elastic_energy_j",
    "energy_j",
    "momentum_x_n_s",
    "momentum_y_n_s",
    "momentum_z_n_s",
    "angular_momentum_x_n_m_s",
    "angular_momentum_y_n_m_s",
    "angular_momentum_z_n_m_s",
    "loaded",
];

/// `curvature.csv`: the element curvatures and resultants of the state, with the reference strains
/// posed in the state's chart (a dynamic run may have changed it, D32).
fn curvature_csv(case: &Case, r: &RunResult) -> String {
    let kappa = r.nodes.element_curvature();
    let rechart = case.rod.general.as_ref().filter(|g| g.rest.chart != r.nodes.chart);
    let rest_in_chart = rechart.map(|g| g.rest.in_chart(&case.mesh, r.nodes.chart));
    let rest = match &rest_in_chart {
        Some(rest) => Some(rest.strains.as_slice()),
        None => case.rod.general.as_ref().map(|g| g.rest.strains.as_slice()),
    };
    let loads = r.nodes.resultants(&case.props, case.quadrature, rest);
    csv_text(&CURVATURE_COLUMNS, kappa.iter().zip(&loads).map(element_row))
}

/// `charts.csv` of a dynamic run that changed its chart (D32): the chart at t = 0 and at every
/// step that starts in a new one (`step`: the first record in it, `time_s`: when the change was
/// made, the time of the record before), `B` row by row (`x̃ = B x`; the frame of the angles α of
/// that record and the later ones is `Q = Q_E(α) B`). `None` for a run in one chart.
fn charts_csv(tip: &[crate::solve::dynamics::TipRecord]) -> Option<String> {
    let first = tip.first()?.chart;
    if tip.iter().all(|t| t.chart == first) {
        return None;
    }
    let mut columns = vec!["step".to_string(), "time_s".to_string()];
    columns.extend((0..9).map(|k| format!("b{}{}", k / 3 + 1, k % 3 + 1)));
    let columns: Vec<&str> = columns.iter().map(String::as_str).collect();
    let rows = tip.iter().enumerate().filter(|(i, t)| *i == 0 || tip[i - 1].chart != t.chart).map(|(i, t)| {
        // the change is made at the start of step i, at the time of the record before it
        let made_at = if i == 0 { 0.0 } else { tip[i - 1].time_s };
        let mut row = vec![Some(i as f64), Some(made_at)];
        row.extend((0..9).map(|k| Some(t.chart.base[(k / 3, k % 3)])));
        row
    });
    Some(csv_text_int(&columns, &["step"], rows))
}
