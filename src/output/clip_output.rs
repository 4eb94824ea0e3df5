//! The files of a clip run: `frames.csv`, `fields.csv`, `curvature.csv`, `truth.csv`
//! (synthetic clips), ParaView `vtk/frame_NNNNN.vtp` + `clip.pvd` streamed frame by frame
//! ([`ClipWriter`], the [`FrameSink`] of `engine::clip`), or in the compact format one
//! `fields.npz` (`crate::io::compact`); the summary figures are `super::clip_figures`.
use std::io::{Seek, Write};
use std::path::{Path, PathBuf};

use nalgebra::Vector3;

pub(crate) use super::clip_figures::abs_percentile_99;
pub use super::clip_figures::{write_clip_kymographs, write_clip_plot, write_omega_kymographs, write_truth_plot};
use super::journal::{Entry, Journal, JournalScan, Offsets, JOURNAL};
use super::run_files::element_row;
use crate::engine::clip::{nodal_curvature, ClipFrame, Controls, FrameSink};
use crate::io::compact::{OutputFormat, CURVATURE_COLUMNS, RAW_CURVATURE, RAW_FIELDS};
use crate::io::compact_write::write_compact;
use crate::io::files::OutputError;
use crate::io::vtk::{write_pvd, write_vtp, PolylineFields};
use crate::model::resultants::Resultants;
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
    /// per frame written: its time [s] and number (its `clip.pvd` entry)
    pvd: Vec<(f64, usize)>,
    /// the resume journal, if kept
    journal: Option<Journal>,
    /// compact: the per-node rows go raw to `fields.f64` / `curvature.f64` (no VTK), and
    /// `fields.npz` is written at the end (`crate::io::compact`); the frame numbers written so far
    compact: Option<Vec<i64>>,
}

/// The names of the streamed per-node and per-element files in `format`.
fn row_files(format: OutputFormat) -> [&'static str; 2] {
    match format {
        OutputFormat::Csv => ["fields.csv", "curvature.csv"],
        OutputFormat::Compact => [RAW_FIELDS, RAW_CURVATURE],
    }
}

/// Columns of `frames.csv`.
/// `min_abs_cos_beta` is the chart's (the angles of `fields.csv` are in the frame's chart
/// `Q = Q_E(α) B`, whose singular axis `n = Bᵀ e2` is `chart_axis_*`; `docs/rotation.md`);
/// `max_abs_omega_rad_per_s` is the largest |ωˡ| over the nodes [rad/s] (eq. 27, 0 on the
/// first frame; `engine::clip::ClipFrame::omega`). `nodes_tracked`: the nodes of the frame that were
/// tracked (`clip.missing`; all of them without missing data); `x_err_rel` and the `fit_*`
/// columns measure the fit over those nodes. `lost`: fewer than 2 nodes tracked, the frame
/// bridged in time from its neighbours; `filled`: some of its nodes filled; `resolved`: solved
/// again from its data guess because its solution from the previous frame was over the gate
/// (`solve::sequence`); `kappa_max_per_m`: the largest |κ| over the element midpoints [1/m],
/// held against `clip.max_curvature_per_m` by the gate.
pub const CLIP_FRAME_COLUMNS: [&str; 33] = [
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
    "certificate",
    "data_noise_m",
    "fit_position_rel_length",
    "fit_tangent_rms",
    "flagged",
    "nodes_tracked",
    "lost",
    "filled",
    "resolved",
    "kappa_max_per_m",
];

/// Columns of `fields.csv`, one row per frame and node: position [m], the angles [rad] in the
/// frame's chart, the directors d1–d3 (rows of Q, eq. 2), the controls f [N/m] and l [N m/m]
/// (eq. 54), the data position [m] and the angular velocity ωˡ [rad/s] in the local frame
/// (eq. 27, as κ; 0 on the first frame; `engine::clip::ClipFrame::omega`).
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

/// What a [`ClipWriter`] writes besides a clip's own files, and in which format.
#[derive(Debug, Clone, Copy, Default)]
pub struct WriterOptions {
    /// `truth.csv` too (a clip with a ground truth)
    pub truth: bool,
    /// the resume journal too (`super::journal`)
    pub journal: bool,
    /// how the per-node fields are written (`crate::io::compact`)
    pub format: OutputFormat,
}

impl ClipWriter {
    /// Create the streamed files of `opts.format` in `dir` (headers written), and `truth.csv`
    /// and the resume journal as `opts` says.
    pub fn create(dir: &Path, opts: WriterOptions) -> Result<Self, OutputError> {
        let WriterOptions { truth, journal, format } = opts;
        let err = |path: PathBuf| move |source| OutputError::Io { path: path.clone(), source };
        let compact = format == OutputFormat::Compact;
        // the folder itself too: a sweep's or an audit's point has none before its first file
        let made = if compact { dir.to_path_buf() } else { dir.join("vtk") };
        std::fs::create_dir_all(&made).map_err(err(made.clone()))?;
        let open = |name: &str, header: &str| -> Result<std::io::BufWriter<std::fs::File>, OutputError> {
            let p = dir.join(name);
            let mut f = std::io::BufWriter::new(std::fs::File::create(&p).map_err(err(p.clone()))?);
            if !header.is_empty() {
                writeln!(f, "{header}").and_then(|_| f.flush()).map_err(err(p))?;
            }
            Ok(f)
        };
        let [fields, curvature] = row_files(format);
        let text = |h: String| if compact { String::new() } else { h };
        Ok(ClipWriter {
            dir: dir.to_path_buf(),
            frames: open("frames.csv", &CLIP_FRAME_COLUMNS.join(","))?,
            fields: open(fields, &text(CLIP_FIELD_COLUMNS.join(",")))?,
            curvature: open(curvature, &text(format!("frame,{}", CURVATURE_COLUMNS.join(","))))?,
            truth: if truth { Some(open("truth.csv", &TRUTH_COLUMNS.join(","))?) } else { None },
            pvd: Vec::new(),
            journal: if journal { Some(Journal::create(dir)?) } else { None },
            compact: compact.then(Vec::new),
        })
    }

    /// Reopen the streamed files of an earlier run in `dir` after the frames of `scan` (its
    /// journal's complete lines): every CSV cut back to its length after the last of them, the
    /// VTK files of later frames removed, the journal continued (whatever `opts.journal`
    /// says). `opts.format` must be the earlier run's.
    pub fn resume(dir: &Path, scan: &JournalScan, opts: WriterOptions) -> Result<Self, OutputError> {
        let Some(o) = scan.last else { return Self::create(dir, WriterOptions { journal: true, ..opts }) };
        let WriterOptions { truth, format, .. } = opts;
        let [fields, curvature] = row_files(format);
        if !dir.join(fields).is_file() {
            return Err(OutputError::Invalid {
                path: dir.join(fields),
                reason: "missing: the run to resume was written in the other --output-format; resume it in its own"
                    .into(),
            });
        }
        let err = |path: PathBuf| move |source| OutputError::Io { path: path.clone(), source };
        let reopen = |name: &str, len: u64| -> Result<std::io::BufWriter<std::fs::File>, OutputError> {
            let p = dir.join(name);
            let f = std::fs::OpenOptions::new().append(true).open(&p).map_err(err(p.clone()))?;
            f.set_len(len).map_err(err(p))?;
            Ok(std::io::BufWriter::new(f))
        };
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
            scan.frames.iter().map(|(frame, _)| format!("frame_{frame:05}.vtp")).collect();
        let vtk = dir.join("vtk");
        let compact = format == OutputFormat::Compact;
        for entry in if compact { Vec::new() } else { std::fs::read_dir(&vtk).map_err(err(vtk.clone()))?.collect() } {
            let name = entry.map_err(err(vtk.clone()))?.file_name().to_string_lossy().into_owned();
            if !kept.contains(&name) {
                std::fs::remove_file(vtk.join(&name)).map_err(err(vtk.join(&name)))?;
            }
        }
        Ok(ClipWriter {
            dir: dir.to_path_buf(),
            frames: reopen("frames.csv", o.frames)?,
            fields: reopen(fields, o.fields)?,
            curvature: reopen(curvature, o.curvature)?,
            truth,
            pvd: scan.frames.iter().map(|&(frame, time_s)| (time_s, frame)).collect(),
            journal: Some(Journal::reopen(dir, scan.bytes)?),
            compact: compact.then(|| scan.frames.iter().map(|&(frame, _)| frame as i64).collect()),
        })
    }

    fn format(&self) -> OutputFormat {
        if self.compact.is_some() {
            OutputFormat::Compact
        } else {
            OutputFormat::Csv
        }
    }

    /// Lengths of the streamed CSVs now (every line flushed).
    fn offsets(&mut self) -> Result<Offsets, OutputError> {
        let dir = &self.dir;
        let len = |name: &str, f: &mut std::io::BufWriter<std::fs::File>| {
            f.flush()
                .and_then(|_| f.get_mut().stream_position())
                .map_err(|source| OutputError::Io { path: dir.join(name), source })
        };
        let [fields, curvature] = row_files(self.format());
        Ok(Offsets {
            frames: len("frames.csv", &mut self.frames)?,
            fields: len(fields, &mut self.fields)?,
            curvature: len(curvature, &mut self.curvature)?,
            truth: match &mut self.truth {
                Some(f) => Some(len("truth.csv", f)?),
                None => None,
            },
        })
    }

    /// Append one converged frame: its report row, nodal fields, element curvature, truth row
    /// and VTK file.
    pub fn write_frame(&mut self, frame: &ClipFrame) -> Result<(), OutputError> {
        let ClipFrame { report, time_s, nodes, controls, data, omega, elements, planar, .. } = frame;
        let Controls { force, torque } = controls;
        let omega = omega.clone().unwrap_or_else(|| vec![Vector3::zeros(); nodes.s.len()]);
        let (time_s, roughness) = (*time_s, planar.roughness);
        let dir = self.dir.clone();
        let err = |name: &str| {
            let p = dir.join(name);
            move |source| OutputError::Io { path: p.clone(), source }
        };
        let r = report;
        let row = report_row(r, time_s, roughness, &omega, nodes.s.len());
        writeln!(self.frames, "{}", frames_row(&row)).and_then(|_| self.frames.flush()).map_err(err("frames.csv"))?;
        let d = nodes.directors();
        let [fields, curvature] = row_files(self.format());
        // each file's rows of the frame are built in one buffer and written at once
        let format = self.format();
        let mut block = Vec::with_capacity(nodes.s.len() * 28 * 18);
        let mut v = Vec::with_capacity(28);
        for i in 0..nodes.s.len() {
            v.clear();
            v.push(nodes.s[i]);
            v.extend(nodes.x[i].iter());
            v.extend(nodes.alpha[i].iter());
            for dk in &d[i] {
                v.extend(dk.iter());
            }
            v.extend(force[i].iter());
            v.extend(torque[i].iter());
            v.extend(data[i].iter());
            v.extend(omega[i].iter());
            push_row(&mut block, format, &[r.frame, i], &v);
        }
        self.fields.write_all(&block).and_then(|_| self.fields.flush()).map_err(err(fields))?;
        block.clear();
        for row in elements.kappa.iter().zip(&elements.resultants).map(element_row) {
            push_row(&mut block, format, &[r.frame], &row);
        }
        self.curvature.write_all(&block).and_then(|_| self.curvature.flush()).map_err(err(curvature))?;
        if let Some(frames) = &mut self.compact {
            frames.push(r.frame as i64);
        } else {
            self.write_vtk(frame, &d, &omega)?;
        }
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
            writeln!(file, "{},{}", r.frame, csv_row(&v)).and_then(|_| file.flush()).map_err(err("truth.csv"))?;
        }
        if self.journal.is_some() {
            let offsets = self.offsets()?;
            if let Some(j) = &mut self.journal {
                j.append(&Entry { time_s, offsets, record: frame.record.clone() })?;
            }
        }
        Ok(())
    }

    /// The frame's ParaView file `vtk/frame_NNNNN.vtp` (and its `clip.pvd` entry).
    fn write_vtk(
        &mut self,
        frame: &ClipFrame,
        d: &[[Vector3<f64>; 3]],
        omega: &[Vector3<f64>],
    ) -> Result<(), OutputError> {
        let (d1, d2, d3): (Vec<_>, Vec<_>, Vec<_>) =
            (d.iter().map(|x| x[0]).collect(), d.iter().map(|x| x[1]).collect(), d.iter().map(|x| x[2]).collect());
        let kn = nodal_curvature(&frame.elements.kappa);
        let resultants = &frame.elements.resultants;
        let nodal = |f: &dyn Fn(&Resultants) -> Vector3<f64>| {
            nodal_curvature(&resultants.iter().map(|r| (0.0, f(r))).collect::<Vec<_>>())
        };
        let (n, m) = (nodal(&|r| r.n), nodal(&|r| r.m));
        let name = format!("frame_{:05}.vtp", frame.report.frame);
        write_vtp(
            &self.dir.join("vtk").join(&name),
            &PolylineFields {
                points: &frame.nodes.x,
                vectors: vec![
                    ("d1", &d1),
                    ("d2", &d2),
                    ("d3", &d3),
                    ("f_n_per_m", &frame.controls.force),
                    ("l_nm_per_m", &frame.controls.torque),
                    ("kappa_per_m", &kn),
                    ("n_n", &n),
                    ("m_nm", &m),
                    ("data_position_m", &frame.data),
                    ("omega_rad_per_s", omega),
                ],
                scalars: vec![],
            },
        )?;
        self.pvd.push((frame.time_s, frame.report.frame));
        Ok(())
    }

    /// Write the ParaView collection of the frames written so far.
    pub fn write_pvd(&mut self) -> Result<PathBuf, OutputError> {
        let p = self.dir.join("clip.pvd");
        let entries: Vec<(f64, String)> =
            self.pvd.iter().map(|&(t, frame)| (t, format!("vtk/frame_{frame:05}.vtp"))).collect();
        write_pvd(&p, &entries)?;
        Ok(p)
    }
}

impl FrameSink for ClipWriter {
    type Error = OutputError;
    fn frame(&mut self, frame: &ClipFrame) -> Result<(), OutputError> {
        self.write_frame(frame)
    }
    fn finish(&mut self) -> Result<(), OutputError> {
        let Some(frames) = &self.compact else { return self.write_pvd().map(|_| ()) };
        if frames.is_empty() {
            return Ok(());
        }
        write_compact(&self.dir, frames, &CLIP_FIELD_COLUMNS[2..])?;
        if self.journal.is_none() {
            remove_raw(&self.dir)?;
        }
        Ok(())
    }
}

/// Remove the raw rows of a compact clip (`crate::io::compact`), once its journal goes.
pub fn remove_raw(dir: &Path) -> Result<(), OutputError> {
    for name in [RAW_FIELDS, RAW_CURVATURE] {
        match std::fs::remove_file(dir.join(name)) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(OutputError::Io { path: dir.join(name), source: e })
            }
            _ => {}
        }
    }
    Ok(())
}

/// Append one row of a per-node or per-element file of `format` to `out`: raw little-endian
/// `values` in the compact format, else the CSV line `index,…,value,…` (values `{:.10e}`,
/// [`crate::io::number::push_exp`]).
fn push_row(out: &mut Vec<u8>, format: OutputFormat, index: &[usize], values: &[f64]) {
    if format == OutputFormat::Compact {
        out.extend(values.iter().flat_map(|x| x.to_le_bytes()));
        return;
    }
    let mut line = String::with_capacity(8 * index.len() + 18 * values.len());
    for i in index {
        line.push_str(itoa::Buffer::new().format(*i));
        line.push(',');
    }
    push_csv(&mut line, values);
    line.push('\n');
    out.extend_from_slice(line.as_bytes());
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

/// The integer columns of `frames.csv` (the frame, its iterations, a node index, a flag).
pub const CLIP_FRAME_INTEGER_COLUMNS: [&str; 9] = [
    "frame",
    "iterations",
    "min_abs_cos_beta_node",
    "restarted",
    "flagged",
    "nodes_tracked",
    "lost",
    "filled",
    "resolved",
];

/// One row of `frames.csv` ([`CLIP_FRAME_COLUMNS`]): the [`CLIP_FRAME_INTEGER_COLUMNS`] as
/// integers, the others `{:.10e}`.
fn frames_row(values: &[f64]) -> String {
    let mut s = String::with_capacity(18 * values.len());
    for (k, v) in values.iter().enumerate() {
        if k > 0 {
            s.push(',');
        }
        if CLIP_FRAME_COLUMNS.get(k).is_some_and(|c| CLIP_FRAME_INTEGER_COLUMNS.contains(c)) {
            crate::io::number::push_integer(&mut s, *v, 10);
        } else {
            crate::io::number::push_exp(&mut s, *v, 10);
        }
    }
    s
}

/// Numbers as one CSV row, `{:.10e}` each ([`crate::io::number::push_exp`]).
fn csv_row(values: &[f64]) -> String {
    let mut s = String::with_capacity(18 * values.len());
    push_csv(&mut s, values);
    s
}

/// Append `values` comma-separated, `{:.10e}` each ([`crate::io::number::push_exp`]).
fn push_csv(s: &mut String, values: &[f64]) {
    for (k, v) in values.iter().enumerate() {
        if k > 0 {
            s.push(',');
        }
        crate::io::number::push_exp(s, *v, 10);
    }
}

/// The row of `frames.csv` of a frame: its report, time [s], roughness and largest |ω| [rad/s]
/// (also the Python package's per-frame table).
pub fn report_row(
    r: &FrameReport,
    time_s: f64,
    roughness: (f64, f64),
    omega: &[Vector3<f64>],
    nodes: usize,
) -> Vec<f64> {
    let mut row = vec![
        r.frame as f64,
        time_s,
        r.convergence.iterations as f64,
        r.convergence.last_change,
        r.misfit.x_err_rel,
        r.misfit.tangent_misfit,
    ];
    row.extend(r.misfit.objective.values());
    row.extend([
        r.conditioning.min_cos_beta,
        r.conditioning.min_cos_beta_node as f64,
        r.conditioning.max_stretch_deviation,
        roughness.0,
        roughness.1,
        f64::from(u8::from(r.restarted)),
    ]);
    row.extend(r.chart_axis.iter());
    row.push(omega.iter().map(|w| w.norm()).fold(0.0, f64::max));
    row.push(r.certificate);
    row.extend([r.fit.noise_m, r.fit.position, r.fit.tangent, f64::from(u8::from(r.fit.flagged))]);
    row.push(r.nodes_tracked as f64);
    let lost = r.nodes_tracked < crate::clip::missing::MIN_TRACKED;
    let filled = !lost && r.nodes_tracked < nodes;
    row.extend([lost, filled, r.fit.resolved].map(|b| f64::from(u8::from(b))));
    row.push(r.fit.curvature_max_per_m);
    row
}
