//! The frames of a clip collected in memory ([`Collected`], a `FrameSink`) and handed to Python
//! as numpy arrays: what `cosserat run` writes to `fields.npz`/`fields.csv`, `curvature.csv`
//! and `frames.csv`, value for value.
use std::convert::Infallible;

use nalgebra::Vector3;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use cosserat::engine::clip::{ClipFrame, FrameSink};
use cosserat::output::clip_output::{report_row, CLIP_FRAME_COLUMNS, CLIP_FRAME_INTEGER_COLUMNS};

/// The flags of `frames.csv`: booleans in Python.
const FLAG_COLUMNS: [&str; 5] = ["restarted", "flagged", "lost", "filled", "resolved"];

/// Per-node fields: name in the result, then three components per node and frame.
const NODE_FIELDS: [&str; 9] =
    ["x_m", "angles_rad", "d1", "d2", "d3", "f_n_per_m", "l_nm_per_m", "data_m", "omega_rad_per_s"];
/// Per-element fields: curvature κ [1/m], internal force n [N] and moment m [N m] in global
/// components, and n, m on the directors.
const ELEMENT_FIELDS: [&str; 5] = ["kappa_per_m", "n_n", "m_nm", "n_local_n", "m_local_nm"];

/// Every converged frame of a clip, flattened frame-major.
#[derive(Default)]
pub struct Collected {
    /// arc length of the nodes and of the element midpoints [m] (of the first frame)
    s_m: Vec<f64>,
    s_mid_m: Vec<f64>,
    frame: Vec<i64>,
    /// the rows of `frames.csv` ([`CLIP_FRAME_COLUMNS`])
    rows: Vec<Vec<f64>>,
    nodes: [Vec<f64>; 9],
    elements: [Vec<f64>; 5],
}

fn extend(v: &mut Vec<f64>, values: &[Vector3<f64>]) {
    v.extend(values.iter().flat_map(|x| x.iter().copied()));
}

impl FrameSink for Collected {
    type Error = Infallible;

    fn frame(&mut self, f: &ClipFrame) -> Result<(), Infallible> {
        let n = f.nodes.s.len();
        if self.frame.is_empty() {
            self.s_m.clone_from(&f.nodes.s);
            self.s_mid_m = f.elements.kappa.iter().map(|k| k.0).collect();
        }
        let omega = f.omega.clone().unwrap_or_else(|| vec![Vector3::zeros(); n]);
        self.frame.push(f.report.frame as i64);
        self.rows.push(report_row(&f.report, f.time_s, f.planar.roughness, &omega, n));
        let d = f.nodes.directors();
        let [x, angles, d1, d2, d3, force, torque, data, om] = &mut self.nodes;
        extend(x, &f.nodes.x);
        extend(angles, &f.nodes.alpha);
        for (k, dk) in [d1, d2, d3].into_iter().enumerate() {
            dk.extend(d.iter().flat_map(|di| di[k].iter().copied()));
        }
        extend(force, &f.controls.force);
        extend(torque, &f.controls.torque);
        extend(data, &f.data);
        extend(om, &omega);
        let [kappa, nn, mm, nl, ml] = &mut self.elements;
        kappa.extend(f.elements.kappa.iter().flat_map(|k| k.1.iter().copied()));
        for r in &f.elements.resultants {
            nn.extend(r.n.iter());
            mm.extend(r.m.iter());
            nl.extend(r.n_local.iter());
            ml.extend(r.m_local.iter());
        }
        Ok(())
    }

    fn finish(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}

impl Collected {
    /// Frames collected.
    pub fn len(&self) -> usize {
        self.frame.len()
    }

    /// The arrays into `out`: `frame`, `s_m`, `s_mid_m`, the per-node fields (frames × nodes × 3),
    /// the per-element fields (frames × elements × 3) and `frames_table`, a dict of the columns of
    /// `frames.csv` (integers as int64, flags as bool).
    pub fn into_dict(self, out: &Bound<'_, PyDict>) -> PyResult<()> {
        let py = out.py();
        let frames = self.frame.len();
        let (nodes, elements) = (self.s_m.len(), self.s_mid_m.len());
        out.set_item("frame", PyArray1::from_vec(py, self.frame))?;
        out.set_item("s_m", PyArray1::from_vec(py, self.s_m))?;
        out.set_item("s_mid_m", PyArray1::from_vec(py, self.s_mid_m))?;
        for (name, v) in NODE_FIELDS.iter().zip(self.nodes) {
            out.set_item(name, PyArray1::from_vec(py, v).reshape([frames, nodes, 3])?)?;
        }
        for (name, v) in ELEMENT_FIELDS.iter().zip(self.elements) {
            out.set_item(name, PyArray1::from_vec(py, v).reshape([frames, elements, 3])?)?;
        }
        let table = PyDict::new(py);
        for (k, name) in CLIP_FRAME_COLUMNS.iter().enumerate() {
            let column = self.rows.iter().map(|r| r[k]);
            if FLAG_COLUMNS.contains(name) {
                table.set_item(name, PyArray1::from_vec(py, column.map(|v| v != 0.0).collect()))?;
            } else if CLIP_FRAME_INTEGER_COLUMNS.contains(name) {
                table.set_item(name, PyArray1::from_vec(py, column.map(|v| v as i64).collect()))?;
            } else {
                table.set_item(name, PyArray1::from_vec(py, column.collect()))?;
            }
        }
        out.set_item("frames", table)?;
        Ok(())
    }
}
