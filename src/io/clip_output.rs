//! The files of a clip run: `frames.csv`, `fields.csv`, `curvature.csv`, `truth.csv`
//! (synthetic clips), ParaView `vtk/frame_NNNNN.vtp` + `clip.pvd` streamed frame by frame
//! ([`ClipWriter`], the [`FrameSink`] of `run::clip`), and the summary figures written at the
//! end (`plot.svg`, `kymograph.svg`, `omega.svg`, `truth.svg`, `truth_errors.svg`).
use std::io::{Seek, Write};
use std::path::{Path, PathBuf};

use nalgebra::Vector3;

use super::files::{write_plot, OutputError};
use super::journal::{Entry, Journal, Offsets, JOURNAL};
use super::plot::{render_heatmaps_svg, render_panels_svg, Heatmap, LinePlot, Series};
use super::vtk::{write_pvd, write_vtp, PolylineFields};
use crate::case::Case;
use crate::run::clip::{nodal_curvature, ClipFrame, ClipRun, FrameSink};
use crate::solve::sequence::FrameReport;

/// Streams a clip solve to disk, one frame at a time (`frames.csv`, `fields.csv`,
/// `curvature.csv`, ParaView `vtk/frame_NNNNN.vtp` + `clip.pvd`). Every line is flushed with
/// its frame, so a clip that stops keeps every converged frame.
pub struct ClipWriter {
    dir: PathBuf,
    frames: std::io::BufWriter<std::fs::File>,
    fields: std::io::BufWriter<std::fs::File>,
    curvature: std::io::BufWriter<std::fs::File>,
    /// `truth.csv` of a synthetic clip
    truth: Option<std::io::BufWriter<std::fs::File>>,
    pvd: Vec<(f64, String)>,
    /// the resume journal, if kept
    journal: Option<Journal>,
}

/// Columns of `frames.csv`.
/// `min_abs_cos_beta` is the chart's (the angles of `fields.csv` are in the frame's chart
/// `Q = Q_E(α) B`, whose singular axis `n = Bᵀ e2` is `chart_axis_*`; `docs/rotation.md`);
/// `max_abs_omega_rad_per_s` is the largest |ωˡ| over the nodes [rad/s] (eq. 27, 0 on the
/// first frame; `run::clip::ClipFrame::omega`).
pub const CLIP_FRAME_COLUMNS: [&str; 23] = [
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
    "max_abs_omega_rad_per_s",
];

/// Columns of `fields.csv`, one row per frame and node: position [m], the angles [rad] in the
/// frame's chart, the directors d1–d3 (rows of Q, eq. 2), the controls f [N/m] and l [N m/m]
/// (eq. 54), the data position [m] and the angular velocity ωˡ [rad/s] in the local frame
/// (eq. 27, as κ; 0 on the first frame; `run::clip::ClipFrame::omega`).
pub const CLIP_FIELD_COLUMNS: [&str; 30] = [
    "frame",
    "node",
    "s_m",
    "x_m",
    "y_m",
    "z_m",
    "alpha_rad",
    "beta_rad",
    "gamma_rad",
    "d1_x",
    "d1_y",
    "d1_z",
    "d2_x",
    "d2_y",
    "d2_z",
    "d3_x",
    "d3_y",
    "d3_z",
    "f_x_n_per_m",
    "f_y_n_per_m",
    "f_z_n_per_m",
    "l_x_nm_per_m",
    "l_y_nm_per_m",
    "l_z_nm_per_m",
    "data_x_m",
    "data_y_m",
    "data_z_m",
    "omega1_rad_per_s",
    "omega2_rad_per_s",
    "omega3_rad_per_s",
];

impl ClipWriter {
    /// Create the streamed files in `dir` (headers written); `truth`: also `truth.csv`;
    /// `journal`: also the resume journal (`super::journal`).
    pub fn create(dir: &Path, truth: bool, journal: bool) -> Result<Self, OutputError> {
        let err = |path: PathBuf| move |source| OutputError::Io { path: path.clone(), source };
        std::fs::create_dir_all(dir.join("vtk")).map_err(err(dir.join("vtk")))?;
        let open = |name: &str, header: &str| -> Result<std::io::BufWriter<std::fs::File>, OutputError> {
            let p = dir.join(name);
            let mut f = std::io::BufWriter::new(std::fs::File::create(&p).map_err(err(p.clone()))?);
            writeln!(f, "{header}").and_then(|_| f.flush()).map_err(err(p))?;
            Ok(f)
        };
        Ok(ClipWriter {
            dir: dir.to_path_buf(),
            frames: open("frames.csv", &CLIP_FRAME_COLUMNS.join(","))?,
            fields: open("fields.csv", &CLIP_FIELD_COLUMNS.join(","))?,
            curvature: open("curvature.csv", "frame,s_mid_m,kappa1_per_m,kappa2_per_m,kappa3_per_m")?,
            truth: if truth { Some(open("truth.csv", &TRUTH_COLUMNS.join(","))?) } else { None },
            pvd: Vec::new(),
            journal: if journal { Some(Journal::create(dir)?) } else { None },
        })
    }

    /// Reopen the streamed files of an earlier run in `dir` after the frames of `entries` (its
    /// journal's complete lines, `journal_bytes` long): every CSV cut back to its length after
    /// the last of them, the VTK files of later frames removed, the journal continued.
    pub fn resume(dir: &Path, truth: bool, entries: &[Entry], journal_bytes: u64) -> Result<Self, OutputError> {
        let Some(last) = entries.last() else { return Self::create(dir, truth, true) };
        let err = |path: PathBuf| move |source| OutputError::Io { path: path.clone(), source };
        let reopen = |name: &str, len: u64| -> Result<std::io::BufWriter<std::fs::File>, OutputError> {
            let p = dir.join(name);
            let f = std::fs::OpenOptions::new().append(true).open(&p).map_err(err(p.clone()))?;
            f.set_len(len).map_err(err(p))?;
            Ok(std::io::BufWriter::new(f))
        };
        let o = last.offsets;
        let truth = match (truth, o.truth) {
            (true, Some(len)) => Some(reopen("truth.csv", len)?),
            (false, None) => None,
            _ => {
                return Err(OutputError::Invalid {
                    path: dir.join(JOURNAL),
                    reason: "the journal and the case disagree on a ground truth (truth.csv)".into(),
                })
            }
        };
        let kept: std::collections::BTreeSet<String> =
            entries.iter().map(|e| format!("frame_{:05}.vtp", e.record.report.frame)).collect();
        let vtk = dir.join("vtk");
        for entry in std::fs::read_dir(&vtk).map_err(err(vtk.clone()))? {
            let name = entry.map_err(err(vtk.clone()))?.file_name().to_string_lossy().into_owned();
            if !kept.contains(&name) {
                std::fs::remove_file(vtk.join(&name)).map_err(err(vtk.join(&name)))?;
            }
        }
        Ok(ClipWriter {
            dir: dir.to_path_buf(),
            frames: reopen("frames.csv", o.frames)?,
            fields: reopen("fields.csv", o.fields)?,
            curvature: reopen("curvature.csv", o.curvature)?,
            truth,
            pvd: entries.iter().map(|e| (e.time_s, format!("vtk/frame_{:05}.vtp", e.record.report.frame))).collect(),
            journal: Some(Journal::reopen(dir, journal_bytes)?),
        })
    }

    /// Lengths of the streamed CSVs now (every line flushed).
    fn offsets(&mut self) -> Result<Offsets, OutputError> {
        let dir = &self.dir;
        let len = |name: &str, f: &mut std::io::BufWriter<std::fs::File>| {
            f.flush()
                .and_then(|_| f.get_mut().stream_position())
                .map_err(|source| OutputError::Io { path: dir.join(name), source })
        };
        Ok(Offsets {
            frames: len("frames.csv", &mut self.frames)?,
            fields: len("fields.csv", &mut self.fields)?,
            curvature: len("curvature.csv", &mut self.curvature)?,
            truth: match &mut self.truth {
                Some(f) => Some(len("truth.csv", f)?),
                None => None,
            },
        })
    }

    /// Append one converged frame: its report row, nodal fields, element curvature, truth row
    /// and VTK file.
    pub fn write_frame(&mut self, frame: &ClipFrame) -> Result<(), OutputError> {
        let ClipFrame { report, time_s, nodes, force, torque, data, omega, kappa, roughness, .. } = frame;
        let omega = omega.clone().unwrap_or_else(|| vec![Vector3::zeros(); nodes.s.len()]);
        let (time_s, roughness) = (*time_s, *roughness);
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
        row.push(omega.iter().map(|w| w.norm()).fold(0.0, f64::max));
        let line: Vec<String> = row.iter().map(|v| format!("{v:.10e}")).collect();
        writeln!(self.frames, "{}", line.join(",")).and_then(|_| self.frames.flush()).map_err(err("frames.csv"))?;
        let d = nodes.directors();
        for i in 0..nodes.s.len() {
            let mut v = vec![nodes.s[i]];
            v.extend(nodes.x[i].iter());
            v.extend(nodes.alpha[i].iter());
            for dk in &d[i] {
                v.extend(dk.iter());
            }
            v.extend(force[i].iter());
            v.extend(torque[i].iter());
            v.extend(data[i].iter());
            v.extend(omega[i].iter());
            let text: Vec<String> = v.iter().map(|x| format!("{x:.10e}")).collect();
            writeln!(self.fields, "{},{i},{}", r.frame, text.join(",")).map_err(err("fields.csv"))?;
        }
        self.fields.flush().map_err(err("fields.csv"))?;
        for (s, k) in kappa {
            writeln!(self.curvature, "{},{s:.10e},{:.10e},{:.10e},{:.10e}", r.frame, k[0], k[1], k[2])
                .map_err(err("curvature.csv"))?;
        }
        self.curvature.flush().map_err(err("curvature.csv"))?;
        let (d1, d2, d3): (Vec<_>, Vec<_>, Vec<_>) =
            (d.iter().map(|x| x[0]).collect(), d.iter().map(|x| x[1]).collect(), d.iter().map(|x| x[2]).collect());
        let kn = nodal_curvature(kappa);
        let name = format!("frame_{:05}.vtp", r.frame);
        write_vtp(
            &self.dir.join("vtk").join(&name),
            &PolylineFields {
                points: &nodes.x,
                vectors: vec![
                    ("d1", &d1),
                    ("d2", &d2),
                    ("d3", &d3),
                    ("f_n_per_m", force),
                    ("l_nm_per_m", torque),
                    ("kappa_per_m", &kn),
                    ("data_position_m", data),
                    ("omega_rad_per_s", &omega),
                ],
                scalars: vec![],
            },
        )?;
        self.pvd.push((time_s, format!("vtk/{name}")));
        if let (Some(file), Some(t)) = (&mut self.truth, &frame.truth) {
            let c = &t.comparison;
            let v = [
                time_s,
                t.roll_rad,
                t.twist_per_m,
                c.position_rel_l2,
                c.bending_rel_l2,
                c.max_tangent_angle_rad,
                c.twist_mean_per_m,
                c.twist_rms_error_per_m,
                c.roll_offset_rad,
            ];
            let text: Vec<String> = v.iter().map(|x| format!("{x:.10e}")).collect();
            writeln!(file, "{},{}", r.frame, text.join(",")).and_then(|_| file.flush()).map_err(err("truth.csv"))?;
        }
        if self.journal.is_some() {
            let offsets = self.offsets()?;
            if let Some(j) = &mut self.journal {
                j.append(&Entry { time_s, offsets, record: frame.record.clone() })?;
            }
        }
        Ok(())
    }

    /// Write the ParaView collection of the frames written so far.
    pub fn write_pvd(&mut self) -> Result<PathBuf, OutputError> {
        let p = self.dir.join("clip.pvd");
        write_pvd(&p, &self.pvd)?;
        Ok(p)
    }
}

impl FrameSink for ClipWriter {
    type Error = OutputError;
    fn frame(&mut self, frame: &ClipFrame) -> Result<(), OutputError> {
        self.write_frame(frame)
    }
    fn finish(&mut self) -> Result<(), OutputError> {
        self.write_pvd().map(|_| ())
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

/// The frame numbers of a clip run as the x axis of its per-frame figures.
struct FrameAxis(Vec<f64>);

impl FrameAxis {
    fn new(reports: &[FrameReport]) -> Self {
        FrameAxis(reports.iter().map(|r| r.frame as f64).collect())
    }
    fn series(&self, label: &str, y: Vec<f64>) -> Series {
        Series { label: label.into(), x: self.0.clone(), y }
    }
    fn plot(title: String, y_label: &str, series: Vec<Series>, log_y: bool) -> LinePlot {
        LinePlot { title, x_label: "frame".into(), y_label: y_label.into(), series, log_x: false, log_y }
    }
}

/// Recovered vs true for a synthetic clip (`truth.svg`): bending κ1² + κ2² kymographs (true,
/// recovered) and per frame the errors, the roll offset against the true roll, and κ3.
pub fn write_truth_plot(case: &Case, run: &ClipRun, path: &Path) -> Result<(), OutputError> {
    let Some(t) = &run.truth else { return Ok(()) };
    let nf = t.comparisons.len();
    if nf < 2 {
        return Ok(());
    }
    let axis = FrameAxis::new(&run.reports);
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
    write_plot(&lines, render_panels_svg(&panels, 2))?;
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
    write_plot(
        path,
        render_heatmaps_svg(&[
            map(format!("true bending sqrt(k1^2+k2^2) [1/m], colour 0..{limit:.0}"), grid(&t.bending_true)),
            map("recovered sqrt(k1^2+k2^2) [1/m]".into(), grid(&t.bending_recovered)),
        ]),
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
    let axis = FrameAxis::new(reports);
    let (s, plot) = (|l: &str, y| axis.series(l, y), FrameAxis::plot);
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
    write_plot(path, render_panels_svg(&panels, 2))
}

/// Kymographs of a planar clip (Fig. 17 style): the data's curvature and the recovered κ2 over
/// frames (x) and arc length (y), on one colour scale (±the 99th percentile of |data|). At most
/// ~150 frames and 64 positions are drawn (strided) to keep the SVG small.
pub fn write_clip_kymographs(case: &Case, run: &ClipRun, path: &Path) -> Result<(), OutputError> {
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
    let limit = abs_percentile_99(run.data_kappa.iter().flatten().copied());
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
    write_plot(
        path,
        render_heatmaps_svg(&[
            map(format!("{}: data curvature [1/m], colour ±{limit:.0}", case.name), yd, vd),
            map("recovered kappa_2 [1/m]".into(), yr, vr),
        ]),
    )
}

/// The 99th percentile of |v| over the finite values (1 if there are none): the colour limit
/// of a kymograph.
pub(crate) fn abs_percentile_99(values: impl Iterator<Item = f64>) -> f64 {
    let mut all: Vec<f64> = values.map(f64::abs).filter(|v| v.is_finite()).collect();
    all.sort_by(f64::total_cmp);
    all.get((all.len() as f64 * 0.99) as usize).copied().unwrap_or(1.0)
}

/// Kymographs of the angular velocity (Fig. 24 style, `omega.svg`): ω1, ω2, ω3 [rad/s] in the
/// local frame (eq. 27, [`ClipRun::omega`]) over frames (x) and the nodes' arc length (y), each
/// on its own colour scale (±the 99th percentile of its |ω| over the frames after the first,
/// which has none). Strided as [`write_clip_kymographs`]; nothing is written for fewer than two
/// frames.
pub fn write_omega_kymographs(case: &Case, run: &ClipRun, path: &Path) -> Result<(), OutputError> {
    let nf = run.omega.len().min(run.reports.len());
    if nf < 2 {
        return Ok(());
    }
    let frames: Vec<usize> = (0..nf).step_by(nf.div_ceil(150)).collect();
    let x: Vec<f64> = frames.iter().map(|&i| run.reports[i].frame as f64).collect();
    let m = run.omega[0].len();
    let cols: Vec<usize> = (0..m).step_by(m.div_ceil(64).max(1)).collect();
    let y: Vec<f64> = cols.iter().map(|&j| case.mesh.node_s(j) * 1e3).collect();
    let maps: Vec<Heatmap> = (0..3)
        .map(|k| {
            let limit = abs_percentile_99(run.omega[1..nf].iter().flatten().map(|w| w[k]));
            let name = if k == 0 { format!("{}: ", case.name) } else { String::new() };
            Heatmap {
                title: format!("{name}omega_{} [rad/s], colour ±{limit:.3e}", k + 1),
                x_label: "frame".into(),
                y_label: "s [mm]".into(),
                x: x.clone(),
                y: y.clone(),
                values: frames.iter().map(|&i| cols.iter().map(|&j| run.omega[i][j][k]).collect()).collect(),
                limit,
            }
        })
        .collect();
    write_plot(path, render_heatmaps_svg(&maps))
}
