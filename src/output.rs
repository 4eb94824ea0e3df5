//! Writing a run to disk: CSV with headers and SI units in the column names, `metrics.json`,
//! and an SVG plot of the headline result. Every file is written to a temporary name in the
//! target directory and renamed into place, so a failure never leaves a half-written file.
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::case::Case;
use crate::metrics::Metrics;
use crate::plot::{write_panels_svg, LinePlot, Series};
use crate::rotation::curvature;
use crate::run::RunResult;

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
    let mut s = header.join(",");
    s.push('\n');
    for r in rows {
        let line: Vec<String> = r.iter().map(|v| format!("{v:.17e}")).collect();
        s.push_str(&line.join(","));
        s.push('\n');
    }
    s
}

/// Element curvature `κˡ = A(α) ∂s α` [1/m] at element midpoints (eq. 28).
pub fn element_curvature(r: &RunResult) -> Vec<(f64, nalgebra::Vector3<f64>)> {
    let n = &r.nodes;
    (0..n.s.len() - 1)
        .map(|e| {
            let h = n.s[e + 1] - n.s[e];
            let mid = (n.alpha[e] + n.alpha[e + 1]) * 0.5;
            ((n.s[e] + n.s[e + 1]) * 0.5, curvature(&mid, &((n.alpha[e + 1] - n.alpha[e]) / h)))
        })
        .collect()
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
        csv_text(&["s_m", "x_m", "y_m", "z_m", "ux_m", "uy_m", "uz_m", "alpha_rad", "beta_rad", "gamma_rad"], rows).into_bytes(),
    )?;
    let kappa = element_curvature(r);
    put(
        "curvature.csv",
        csv_text(&["s_mid_m", "kappa1_per_m", "kappa2_per_m", "kappa3_per_m"], kappa.iter().map(|(s, k)| vec![*s, k[0], k[1], k[2]])).into_bytes(),
    )?;
    if !r.history.is_empty() {
        put("history.csv", csv_text(&["continuation_step", "iteration", "change"], r.history.iter().map(|h| vec![h.step as f64, h.iteration as f64, h.change])).into_bytes())?;
    }
    if !r.tip.is_empty() {
        let rows = r.tip.iter().map(|t| {
            let (x, a) = (t.position_m, t.angles_rad);
            vec![t.time_s, x[0], x[1], x[2], a[0], a[1], a[2], t.newton_iterations as f64]
        });
        put("tip_history.csv", csv_text(&["time_s", "tip_x_m", "tip_y_m", "tip_z_m", "tip_alpha_rad", "tip_beta_rad", "tip_gamma_rad", "newton_iterations"], rows).into_bytes())?;
    }
    let json = serde_json::to_string_pretty(metrics).unwrap_or_else(|_| "{}".into());
    put("metrics.json", json.into_bytes())?;
    let plot_path = dir.join("plot.svg");
    write_panels_svg(&headline_panels(case, r), 2, &plot_path).map_err(|e| OutputError::Plot { path: plot_path.clone(), reason: e.to_string() })?;
    written.push(plot_path);
    Ok(written)
}

/// The headline figure: tip history for dynamic runs (Fig. 5 analogue), deflection and
/// curvature along the rod for static runs (Fig. 7 analogue).
pub fn headline_panels(case: &Case, r: &RunResult) -> Vec<LinePlot> {
    let series = |label: &str, x: Vec<f64>, y: Vec<f64>| Series { label: label.into(), x, y };
    let plot = |title: &str, xl: &str, yl: &str, s: Vec<Series>| LinePlot { title: title.into(), x_label: xl.into(), y_label: yl.into(), series: s, log_x: false, log_y: false };
    if !r.tip.is_empty() {
        let t: Vec<f64> = r.tip.iter().map(|p| p.time_s).collect();
        let comp = |k: usize| r.tip.iter().map(|p| p.position_m[k] - r.tip[0].position_m[k]).collect::<Vec<_>>();
        let ang = |k: usize| r.tip.iter().map(|p| p.angles_rad[k]).collect::<Vec<_>>();
        vec![
            plot(&format!("{}: tip displacement", case.name), "t [s]", "displacement [m]", vec![series("u_x", t.clone(), comp(0)), series("u_y", t.clone(), comp(1)), series("u_z", t.clone(), comp(2))]),
            plot("tip rotation", "t [s]", "angle [rad]", vec![series("alpha", t.clone(), ang(0)), series("beta", t.clone(), ang(1)), series("gamma", t, ang(2))]),
        ]
    } else {
        let s = r.nodes.s.clone();
        let disp = r.nodes.displacement();
        let kappa = element_curvature(r);
        let sk: Vec<f64> = kappa.iter().map(|k| k.0).collect();
        vec![
            plot(&format!("{}: displacement", case.name), "s [m]", "displacement [m]", (0..3).map(|k| series(["u_x", "u_y", "u_z"][k], s.clone(), disp.iter().map(|u| u[k]).collect())).collect()),
            plot("curvature (eq. 28)", "s [m]", "kappa [1/m]", (0..3).map(|k| series(["kappa_1", "kappa_2", "kappa_3"][k], sk.clone(), kappa.iter().map(|c| c.1[k]).collect())).collect()),
        ]
    }
}
