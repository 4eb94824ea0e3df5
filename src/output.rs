//! Writing a run to disk: CSV with headers and SI units in the column names, `metrics.json`,
//! and an SVG plot of the headline result. Every file is written to a temporary name in the
//! target directory and renamed into place, so a failure never leaves a half-written file.
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::case::Case;
use crate::metrics::Metrics;
use crate::plot::{write_panels_svg, LinePlot, Series};
use crate::run::{InverseOutput, RunResult};
use crate::solve::inverse::ObjectiveTerms;

/// Errors while writing outputs.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot write {path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("cannot write plot {path}: {reason}")]
    Plot { path: PathBuf, reason: String },
}

/// Write `bytes` to `path` atomically (temporary file + rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let err = |source| OutputError::Io { path: path.to_path_buf(), source };
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(err)?;
    let mut tmp = tempfile::NamedTempFile::new_in(dir).map_err(err)?;
    tmp.write_all(bytes).map_err(err)?;
    tmp.persist(path).map_err(|e| err(e.error))?;
    Ok(())
}

fn csv_text(header: &[&str], rows: impl Iterator<Item = Vec<f64>>) -> String {
    csv_text_opt(header, rows.map(|r| r.into_iter().map(Some).collect()))
}

/// CSV with empty fields where a value does not apply.
fn csv_text_opt(header: &[&str], rows: impl Iterator<Item = Vec<Option<f64>>>) -> String {
    let mut s = header.join(",");
    s.push('\n');
    for r in rows {
        let line: Vec<String> = r.iter().map(|v| v.map(|v| format!("{v:.17e}")).unwrap_or_default()).collect();
        s.push_str(&line.join(","));
        s.push('\n');
    }
    s
}

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
    let kappa = r.nodes.element_curvature();
    put(
        "curvature.csv",
        csv_text(
            &["s_mid_m", "kappa1_per_m", "kappa2_per_m", "kappa3_per_m"],
            kappa.iter().map(|(s, k)| vec![*s, k[0], k[1], k[2]]),
        )
        .into_bytes(),
    )?;
    if !r.history.is_empty() {
        put(
            "history.csv",
            csv_text(
                &["continuation_step", "iteration", "change"],
                r.history.iter().map(|h| vec![h.step as f64, h.iteration as f64, h.change]),
            )
            .into_bytes(),
        )?;
    }
    if !r.tip.is_empty() {
        let rows = r.tip.iter().map(|t| {
            let (x, a) = (t.position_m, t.angles_rad);
            vec![t.time_s, x[0], x[1], x[2], a[0], a[1], a[2], t.newton_iterations as f64]
        });
        put(
            "tip_history.csv",
            csv_text(
                &[
                    "time_s",
                    "tip_x_m",
                    "tip_y_m",
                    "tip_z_m",
                    "tip_alpha_rad",
                    "tip_beta_rad",
                    "tip_gamma_rad",
                    "newton_iterations",
                ],
                rows,
            )
            .into_bytes(),
        )?;
    }
    if let Some(inv) = &r.inverse {
        write_inverse(r, inv, &mut put)?;
    }
    let json = serde_json::to_string_pretty(metrics).unwrap_or_else(|_| "{}".into());
    put("metrics.json", json.into_bytes())?;
    let plot_path = dir.join("plot.svg");
    write_panels_svg(&headline_panels(case, r), 2, &plot_path)
        .map_err(|e| OutputError::Plot { path: plot_path.clone(), reason: e.to_string() })?;
    written.push(plot_path);
    Ok(written)
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
        for k in 0..3 {
            row.extend(d[i][k].iter());
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
    header.extend(["kappa_err_rel", "kappa_err_rel_inner"]);
    let rows = inv.history.iter().enumerate().map(|(i, h)| {
        let mut row: Vec<Option<f64>> =
            [h.iteration as f64, h.rel_change, h.x_err_rel, h.tangent_misfit].into_iter().map(Some).collect();
        row.extend(h.objective.values().into_iter().map(Some));
        if newton {
            row.push(h.residual);
        }
        let k = inv.kappa_err.get(i);
        row.extend([k.map(|k| k[0]), k.map(|k| k[1])]);
        row
    });
    put("inverse_history.csv", csv_text_opt(&header, rows).into_bytes())?;
    Ok(())
}

/// The headline figure: tip history for dynamic runs (Fig. 5 analogue), deflection and
/// curvature along the rod for static runs (Fig. 7 analogue).
pub fn headline_panels(case: &Case, r: &RunResult) -> Vec<LinePlot> {
    let series = |label: &str, x: Vec<f64>, y: Vec<f64>| Series { label: label.into(), x, y };
    let plot = |title: &str, xl: &str, yl: &str, s: Vec<Series>| LinePlot {
        title: title.into(),
        x_label: xl.into(),
        y_label: yl.into(),
        series: s,
        log_x: false,
        log_y: false,
    };
    if let Some(inv) = &r.inverse {
        return inverse_panels(case, r, inv);
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
    let series = |label: String, x: Vec<f64>, y: Vec<f64>| Series { label, x, y };
    let plot = |title: String, xl: &str, yl: &str, s: Vec<Series>, log: bool| LinePlot {
        title,
        x_label: xl.into(),
        y_label: yl.into(),
        series: s,
        log_x: log,
        log_y: log,
    };
    let s = r.nodes.s.clone();
    let comp = ["x", "y", "z"];
    let mut pos = Vec::new();
    for k in 0..3 {
        pos.push(series(format!("{} data", comp[k]), s.clone(), inv.data.x.iter().map(|v| v[k]).collect()));
        pos.push(series(format!("{} inverse", comp[k]), s.clone(), r.nodes.x.iter().map(|v| v[k]).collect()));
    }
    let (k, kf) = (r.nodes.element_curvature(), inv.data.element_curvature());
    let sk: Vec<f64> = k.iter().map(|p| p.0).collect();
    let mut curv = Vec::new();
    for c in 0..3 {
        curv.push(series(format!("kappa_{} data", c + 1), sk.clone(), kf.iter().map(|p| p.1[c]).collect()));
        curv.push(series(format!("kappa_{} inverse", c + 1), sk.clone(), k.iter().map(|p| p.1[c]).collect()));
    }
    let (f, l) = (inv.force(), inv.torque());
    let ctrl = |v: &[nalgebra::Vector3<f64>], name: &str| {
        (0..3)
            .map(|c| series(format!("{name}_{}", comp[c]), s.clone(), v.iter().map(|x| x[c]).collect()))
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
    vec![
        plot(format!("{}: centreline, data vs inverse", case.name), "s [m]", "position [m]", pos, false),
        plot("curvature (eq. 28), data vs inverse".into(), "s [m]", "kappa [1/m]", curv, false),
        plot("recovered force f = x^/lambda_f (eq. 54)".into(), "s [m]", "f [N/m]", ctrl(&f, "f"), false),
        plot("recovered torque l = a^/lambda_l (eq. 54)".into(), "s [m]", "l [N m/m]", ctrl(&l, "l"), false),
        plot("convergence history".into(), "iteration", "value", hist, true),
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
        log_x: true,
        log_y: true,
    };
    let mut xerr = Vec::new();
    let mut kerr = Vec::new();
    let mut change = Vec::new();
    for (name, r) in runs {
        if let Some(inv) = &r.inverse {
            let it: Vec<f64> = inv.history.iter().map(|h| h.iteration as f64).collect();
            if inv.kappa_err.len() == it.len() {
                kerr.push(Series {
                    label: name.to_string(),
                    x: it.clone(),
                    y: inv.kappa_err.iter().map(|k| k[0]).collect(),
                });
            }
            xerr.push(Series {
                label: name.to_string(),
                x: it.clone(),
                y: inv.history.iter().map(|h| h.x_err_rel).collect(),
            });
            change.push(Series {
                label: name.to_string(),
                x: it,
                y: inv.history.iter().map(|h| h.rel_change).collect(),
            });
        } else if !r.history.is_empty() {
            change.push(Series {
                label: name.to_string(),
                x: (1..=r.history.len()).map(|k| k as f64).collect(),
                y: r.history.iter().map(|h| h.change).collect(),
            });
        }
    }
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
    write_panels_svg(&panels, 2, path)
        .map_err(|e| OutputError::Plot { path: path.to_path_buf(), reason: e.to_string() })
}

/// Planar curvature of a centreline in the x–z plane at interior nodes [1/m]:
/// `(θ_e − θ_{e−1})/h`, θ the tangent angle from e3 towards e1. For a frame with α = β = 0 this
/// is κ2 of eq. (28) (κ = A ∂sα with A(0) gives κ2 = −∂sγ = ∂sθ).
pub fn planar_xz_curvature(x: &[nalgebra::Vector3<f64>], h: f64) -> Vec<f64> {
    let theta: Vec<f64> = x.windows(2).map(|w| (w[1][0] - w[0][0]).atan2(w[1][2] - w[0][2])).collect();
    theta
        .windows(2)
        .map(|t| {
            let d = t[1] - t[0];
            let d = (d + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI;
            d / h
        })
        .collect()
}

/// Roughness of a sequence: the fraction of interior points where the first difference changes
/// sign (a local extremum). A smooth curvature profile of a worm has a handful of extrema; a
/// nodal zig-zag has one at almost every point (roughness → 1).
pub fn sign_alternation(k: &[f64]) -> f64 {
    if k.len() < 3 {
        return 0.0;
    }
    let d: Vec<f64> = k.windows(2).map(|w| w[1] - w[0]).collect();
    let flips = d.windows(2).filter(|w| w[0] * w[1] < 0.0).count();
    flips as f64 / (k.len() - 2) as f64
}

/// Streams a clip solve to disk, one frame at a time (`frames.csv`, `fields.csv`,
/// `curvature.csv`, ParaView `vtk/frame_NNNNN.vtp` + `clip.pvd`). Every line is flushed with
/// its frame, so a clip that stops keeps every converged frame.
pub struct ClipWriter {
    dir: PathBuf,
    frames: std::io::BufWriter<std::fs::File>,
    fields: std::io::BufWriter<std::fs::File>,
    curvature: std::io::BufWriter<std::fs::File>,
    pvd: Vec<(f64, String)>,
}

/// Columns of `frames.csv`.
/// `min_abs_cos_beta` is the chart's (the angles of `fields.csv` are in the frame's chart
/// `Q = Q_E(α) B`, whose singular axis `n = Bᵀ e2` is `chart_axis_*`; `docs/rotation.md`).
pub const CLIP_FRAME_COLUMNS: [&str; 22] = [
    "frame",
    "time_s",
    "iterations",
    "rel_change",
    "x_err_rel",
    "tangent_misfit_m05",
    "j_tracking",
    "j_force",
    "j_torque",
    "j_shear",
    "j_bending",
    "j_angular",
    "j_total",
    "min_abs_cos_beta",
    "min_abs_cos_beta_node",
    "max_abs_j_minus_1",
    "kappa_roughness",
    "data_kappa_roughness",
    "restarted",
    "chart_axis_x",
    "chart_axis_y",
    "chart_axis_z",
];

impl ClipWriter {
    /// Create the streamed files in `dir` (headers written).
    pub fn create(dir: &Path) -> Result<Self, OutputError> {
        let err = |path: PathBuf| move |source| OutputError::Io { path: path.clone(), source };
        std::fs::create_dir_all(dir.join("vtk")).map_err(err(dir.join("vtk")))?;
        let open = |name: &str, header: &str| -> Result<std::io::BufWriter<std::fs::File>, OutputError> {
            let p = dir.join(name);
            let mut f = std::io::BufWriter::new(std::fs::File::create(&p).map_err(err(p.clone()))?);
            writeln!(f, "{header}").map_err(err(p))?;
            Ok(f)
        };
        let mut fields_header = vec!["frame", "node", "s_m", "x_m", "y_m", "z_m", "alpha_rad", "beta_rad", "gamma_rad"];
        fields_header.extend(["d1_x", "d1_y", "d1_z", "d2_x", "d2_y", "d2_z", "d3_x", "d3_y", "d3_z"]);
        fields_header.extend([
            "f_x_n_per_m",
            "f_y_n_per_m",
            "f_z_n_per_m",
            "l_x_nm_per_m",
            "l_y_nm_per_m",
            "l_z_nm_per_m",
            "data_x_m",
            "data_y_m",
            "data_z_m",
        ]);
        Ok(ClipWriter {
            dir: dir.to_path_buf(),
            frames: open("frames.csv", &CLIP_FRAME_COLUMNS.join(","))?,
            fields: open("fields.csv", &fields_header.join(","))?,
            curvature: open("curvature.csv", "frame,s_mid_m,kappa1_per_m,kappa2_per_m,kappa3_per_m")?,
            pvd: Vec::new(),
        })
    }

    /// Append one converged frame: its report row, nodal fields, element curvature and VTK file.
    /// `nodes`: the recovered state; `xhat`, `ahat`: adjoint; `data`: the frame's positions.
    #[allow(clippy::too_many_arguments)]
    pub fn frame(
        &mut self,
        report: &crate::solve::sequence::FrameReport,
        time_s: f64,
        nodes: &crate::run::NodalState,
        force: &[nalgebra::Vector3<f64>],
        torque: &[nalgebra::Vector3<f64>],
        data: &[nalgebra::Vector3<f64>],
        roughness: (f64, f64),
    ) -> Result<(), OutputError> {
        let err = |name: &str| {
            let p = self.dir.join(name);
            move |source| OutputError::Io { path: p.clone(), source }
        };
        let r = report;
        let mut row = vec![r.frame as f64, time_s, r.iterations as f64, r.last_change, r.x_err_rel, r.tangent_misfit];
        row.extend(r.objective.values());
        row.extend([
            r.min_cos_beta,
            r.min_cos_beta_node as f64,
            r.max_stretch_deviation,
            roughness.0,
            roughness.1,
            f64::from(u8::from(r.restarted)),
        ]);
        row.extend(r.chart_axis.iter());
        let line: Vec<String> = row.iter().map(|v| format!("{v:.10e}")).collect();
        writeln!(self.frames, "{}", line.join(",")).and_then(|_| self.frames.flush()).map_err(err("frames.csv"))?;
        let d = nodes.directors();
        for i in 0..nodes.s.len() {
            let mut v = vec![nodes.s[i]];
            v.extend(nodes.x[i].iter());
            v.extend(nodes.alpha[i].iter());
            for k in 0..3 {
                v.extend(d[i][k].iter());
            }
            v.extend(force[i].iter());
            v.extend(torque[i].iter());
            v.extend(data[i].iter());
            let text: Vec<String> = v.iter().map(|x| format!("{x:.10e}")).collect();
            writeln!(self.fields, "{},{i},{}", r.frame, text.join(",")).map_err(err("fields.csv"))?;
        }
        self.fields.flush().map_err(err("fields.csv"))?;
        let kappa = nodes.element_curvature();
        for (s, k) in &kappa {
            writeln!(self.curvature, "{},{s:.10e},{:.10e},{:.10e},{:.10e}", r.frame, k[0], k[1], k[2])
                .map_err(err("curvature.csv"))?;
        }
        self.curvature.flush().map_err(err("curvature.csv"))?;
        let (d1, d2, d3): (Vec<_>, Vec<_>, Vec<_>) =
            (d.iter().map(|x| x[0]).collect(), d.iter().map(|x| x[1]).collect(), d.iter().map(|x| x[2]).collect());
        let kn = crate::run::nodal_curvature(&kappa);
        let name = format!("frame_{:05}.vtp", r.frame);
        crate::vtk::write_vtp(
            &self.dir.join("vtk").join(&name),
            &crate::vtk::PolylineFields {
                points: &nodes.x,
                vectors: vec![
                    ("d1", &d1),
                    ("d2", &d2),
                    ("d3", &d3),
                    ("f_n_per_m", force),
                    ("l_nm_per_m", torque),
                    ("kappa_per_m", &kn),
                    ("data_position_m", data),
                ],
                scalars: vec![],
            },
        )?;
        self.pvd.push((time_s, format!("vtk/{name}")));
        Ok(())
    }

    /// Write the ParaView collection of the frames written so far.
    pub fn finish(&mut self) -> Result<PathBuf, OutputError> {
        let p = self.dir.join("clip.pvd");
        crate::vtk::write_pvd(&p, &self.pvd)?;
        Ok(p)
    }
}

/// Columns of `truth.csv` (synthetic clips, `clip::synthetic::FrameComparison`).
pub const TRUTH_COLUMNS: [&str; 10] = [
    "frame",
    "time_s",
    "true_roll_rad",
    "true_twist_per_m",
    "x_err_rel_l2",
    "bending_err_rel_l2",
    "max_tangent_angle_rad",
    "twist_mean_per_m",
    "twist_rms_err_per_m",
    "roll_offset_rad",
];

/// `truth.csv`, streamed frame by frame like [`ClipWriter`].
pub struct TruthWriter {
    path: PathBuf,
    file: std::io::BufWriter<std::fs::File>,
}

impl TruthWriter {
    pub fn create(dir: &Path) -> Result<Self, OutputError> {
        let path = dir.join("truth.csv");
        let err = |source| OutputError::Io { path: dir.join("truth.csv"), source };
        let mut file = std::io::BufWriter::new(std::fs::File::create(&path).map_err(err)?);
        writeln!(file, "{}", TRUTH_COLUMNS.join(",")).map_err(err)?;
        Ok(TruthWriter { path, file })
    }

    pub fn frame(
        &mut self,
        frame: usize,
        time_s: f64,
        roll_rad: f64,
        twist_per_m: f64,
        c: &crate::clip::synthetic::FrameComparison,
    ) -> Result<(), OutputError> {
        let v = [
            time_s,
            roll_rad,
            twist_per_m,
            c.position_rel_l2,
            c.bending_rel_l2,
            c.max_tangent_angle_rad,
            c.twist_mean_per_m,
            c.twist_rms_error_per_m,
            c.roll_offset_rad,
        ];
        let text: Vec<String> = v.iter().map(|x| format!("{x:.10e}")).collect();
        writeln!(self.file, "{frame},{}", text.join(","))
            .and_then(|_| self.file.flush())
            .map_err(|source| OutputError::Io { path: self.path.clone(), source })
    }
}

/// Recovered vs true for a synthetic clip (`truth.svg`): bending κ1² + κ2² kymographs (true,
/// recovered) and per frame the errors, the roll offset against the true roll, and κ3.
pub fn write_truth_plot(case: &Case, run: &crate::run::ClipRun, path: &Path) -> Result<(), OutputError> {
    use crate::plot::{write_heatmaps_svg, Heatmap};
    let Some(t) = &run.truth else { return Ok(()) };
    let nf = t.comparisons.len();
    if nf < 2 {
        return Ok(());
    }
    let to_err =
        |e: crate::plot::PlotError, p: &Path| OutputError::Plot { path: p.to_path_buf(), reason: e.to_string() };
    let f: Vec<f64> = run.reports.iter().map(|r| r.frame as f64).collect();
    let s = |label: &str, y: Vec<f64>| Series { label: label.into(), x: f.clone(), y };
    let plot = |title: String, yl: &str, series: Vec<Series>, log_y: bool| LinePlot {
        title,
        x_label: "frame".into(),
        y_label: yl.into(),
        series,
        log_x: false,
        log_y,
    };
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
            true,
        ),
        plot(
            "roll of the frame about d3".into(),
            "angle [rad]",
            vec![
                s("true roll psi of the bending plane", t.roll_rad.clone()),
                s("recovered d1 vs true d1 (offset)", c.iter().map(|v| v.roll_offset_rad).collect()),
            ],
            false,
        ),
        plot(
            "twist kappa_3".into(),
            "kappa_3 [rad/m]",
            vec![
                s("true", t.twist_per_m.clone()),
                s("recovered (mean over inner nodes)", c.iter().map(|v| v.twist_mean_per_m).collect()),
                s("rms error", c.iter().map(|v| v.twist_rms_error_per_m).collect()),
            ],
            false,
        ),
        plot(
            "angle chart: min |cos beta| over the nodes".into(),
            "|cos beta|",
            vec![s("rebased chart", run.reports.iter().map(|r| r.min_cos_beta).collect())],
            false,
        ),
    ];
    let lines = path.with_file_name("truth_errors.svg");
    write_panels_svg(&panels, 2, &lines).map_err(|e| to_err(e, &lines))?;
    let fs = nf.div_ceil(150);
    let frames: Vec<usize> = (0..nf).step_by(fs).collect();
    let x: Vec<f64> = frames.iter().map(|&i| run.reports[i].frame as f64).collect();
    let m = t.bending_true[0].len();
    let cols: Vec<usize> = (0..m).step_by(m.div_ceil(64)).collect();
    let y: Vec<f64> = cols.iter().map(|&j| j as f64 * case.mesh.h() * 1e3).collect();
    let grid = |field: &Vec<Vec<f64>>| -> Vec<Vec<f64>> {
        frames.iter().map(|&i| cols.iter().map(|&j| field[i][j].sqrt()).collect()).collect()
    };
    let mut all: Vec<f64> = t.bending_true.iter().flatten().map(|v| v.sqrt()).collect();
    all.sort_by(f64::total_cmp);
    let limit = all.get((all.len() as f64 * 0.99) as usize).copied().unwrap_or(1.0);
    let map = |title: String, values: Vec<Vec<f64>>| Heatmap {
        title,
        x_label: "frame".into(),
        y_label: "s [mm]".into(),
        x: x.clone(),
        y: y.clone(),
        values,
        limit,
    };
    write_heatmaps_svg(
        &[
            map(format!("true bending sqrt(k1^2+k2^2) [1/m], colour 0..{limit:.0}"), grid(&t.bending_true)),
            map("recovered sqrt(k1^2+k2^2) [1/m]".into(), grid(&t.bending_recovered)),
        ],
        path,
    )
    .map_err(|e| to_err(e, path))
}

/// Per-frame summary of a clip run: iterations, fit, chart guard and roughness against frame.
pub fn write_clip_plot(
    case: &Case,
    reports: &[crate::solve::sequence::FrameReport],
    roughness: &[(f64, f64)],
    path: &Path,
) -> Result<(), OutputError> {
    if reports.is_empty() {
        return Ok(());
    }
    let f: Vec<f64> = reports.iter().map(|r| r.frame as f64).collect();
    let s = |label: &str, y: Vec<f64>| Series { label: label.into(), x: f.clone(), y };
    let plot = |title: String, yl: &str, series: Vec<Series>, log_y: bool| LinePlot {
        title,
        x_label: "frame".into(),
        y_label: yl.into(),
        series,
        log_x: false,
        log_y,
    };
    let panels = vec![
        plot(
            format!("{}: iterations per frame", case.name),
            "iterations",
            vec![s("iterations", reports.iter().map(|r| r.iterations as f64).collect())],
            false,
        ),
        plot(
            "fit per frame".into(),
            "value",
            vec![
                s("|x - x_g|/|x_g|", reports.iter().map(|r| r.x_err_rel).collect()),
                s("|x' - d3| [m^1/2]", reports.iter().map(|r| r.tangent_misfit).collect()),
                s("last relative change", reports.iter().map(|r| r.last_change).collect()),
            ],
            true,
        ),
        plot(
            "angle chart: min |cos beta| over the nodes".into(),
            "|cos beta|",
            vec![s("min |cos beta|", reports.iter().map(|r| r.min_cos_beta).collect())],
            false,
        ),
        plot(
            "objective (41)".into(),
            "J",
            vec![
                s("tracking", reports.iter().map(|r| r.objective.tracking).collect()),
                s("total", reports.iter().map(|r| r.objective.total()).collect()),
            ],
            true,
        ),
        plot(
            "roughness of the curvature (sign alternation of its differences)".into(),
            "fraction of elements",
            vec![
                s("recovered kappa_2", roughness.iter().map(|r| r.0).collect()),
                s("data", roughness.iter().map(|r| r.1).collect()),
            ],
            false,
        ),
    ];
    write_panels_svg(&panels, 2, path)
        .map_err(|e| OutputError::Plot { path: path.to_path_buf(), reason: e.to_string() })
}

/// Kymographs of a planar clip (Fig. 17 style): the data's curvature and the recovered κ2 over
/// frames (x) and arc length (y), on one colour scale (±the 99th percentile of |data|). At most
/// ~150 frames and 64 positions are drawn (strided) to keep the SVG small.
pub fn write_clip_kymographs(case: &Case, run: &crate::run::ClipRun, path: &Path) -> Result<(), OutputError> {
    use crate::plot::{write_heatmaps_svg, Heatmap};
    let nf = run.kappa2.len();
    if nf < 2 {
        return Ok(());
    }
    let fs = nf.div_ceil(150);
    let frames: Vec<usize> = (0..nf).step_by(fs).collect();
    let x: Vec<f64> = frames.iter().map(|&i| run.reports[i].frame as f64).collect();
    let h = case.mesh.h();
    let grid = |field: &Vec<Vec<f64>>, s_of: &dyn Fn(usize) -> f64| {
        let m = field[0].len();
        let ss = m.div_ceil(64);
        let cols: Vec<usize> = (0..m).step_by(ss).collect();
        let y: Vec<f64> = cols.iter().map(|&j| s_of(j) * 1e3).collect();
        let values: Vec<Vec<f64>> = frames.iter().map(|&i| cols.iter().map(|&j| field[i][j]).collect()).collect();
        (y, values)
    };
    let mut all: Vec<f64> = run.data_kappa.iter().flatten().map(|v| v.abs()).filter(|v| v.is_finite()).collect();
    all.sort_by(f64::total_cmp);
    let limit = all.get((all.len() as f64 * 0.99) as usize).copied().unwrap_or(1.0);
    let (yd, vd) = grid(&run.data_kappa, &|j| (j + 1) as f64 * h);
    let (yr, vr) = grid(&run.kappa2, &|j| (j as f64 + 0.5) * h);
    let map = |title: String, y: Vec<f64>, values: Vec<Vec<f64>>| Heatmap {
        title,
        x_label: "frame".into(),
        y_label: "s [mm]".into(),
        x: x.clone(),
        y,
        values,
        limit,
    };
    write_heatmaps_svg(
        &[
            map(format!("{}: data curvature [1/m], colour ±{limit:.0}", case.name), yd, vd),
            map("recovered kappa_2 [1/m]".into(), yr, vr),
        ],
        path,
    )
    .map_err(|e| OutputError::Plot { path: path.to_path_buf(), reason: e.to_string() })
}
