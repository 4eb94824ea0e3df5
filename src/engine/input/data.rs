//! Data I/O of the inverse problem: the forward data file `data.csv` (docs/inverse.md, I7)
//! that both engines' inverse runs read.
//!
//! Format: CSV, header `s_m,x_m,y_m,z_m,alpha_rad,beta_rad,gamma_rad`, one row per mesh node in
//! order of the reference arc length `s` [m]; positions [m], angles of eq. (1) [rad]; every
//! value written with 17 significant digits so that the file round-trips `f64` exactly.
use std::path::Path;

use nalgebra::Vector3;

use crate::engine::common::result::NodalState;
use crate::io::files::{csv_reader_capped, write_atomic, InputError, OutputError};
use crate::model::chart::Chart;
use crate::model::mesh::Mesh;

/// Column names of `data.csv`.
pub const DATA_HEADER: [&str; 7] = ["s_m", "x_m", "y_m", "z_m", "alpha_rad", "beta_rad", "gamma_rad"];

/// Largest `data.csv` read [bytes]: 256 MiB. A row is at most ~170 bytes (7 values with 17
/// significant digits), so the largest mesh a case may have (`case::MAX_ELEMENTS`, 10⁶
/// elements) writes ~170 MB; the committed cases (100 elements) write ~17 KB.
pub const DATA_FILE_CAP_BYTES: u64 = 256 << 20;

/// Text of `data.csv` for nodal fields (exact round trip).
pub fn data_csv_text(nodes: &NodalState) -> String {
    let mut s = DATA_HEADER.join(",");
    s.push('\n');
    for i in 0..nodes.s.len() {
        let (x, a) = (nodes.x[i], nodes.alpha[i]);
        let row = [nodes.s[i], x[0], x[1], x[2], a[0], a[1], a[2]];
        s.push_str(&row.iter().map(|v| format!("{v:.16e}")).collect::<Vec<_>>().join(","));
        s.push('\n');
    }
    s
}

/// Write `data.csv` atomically.
pub fn write_data(path: &Path, nodes: &NodalState) -> Result<(), OutputError> {
    write_atomic(path, data_csv_text(nodes).as_bytes())
}

/// Read `data.csv` (at most [`DATA_FILE_CAP_BYTES`]) and check it against the mesh: one row
/// per node, `s` at the node positions (to 1e-9 L), every value finite. Rows beyond the mesh's
/// node count are counted, not kept.
pub fn read_data(path: &Path, mesh: &Mesh) -> Result<NodalState, InputError> {
    let mut rdr = csv_reader_capped(path, DATA_FILE_CAP_BYTES, "data file", &DATA_HEADER)?;
    let mut nodes =
        NodalState { s: Vec::new(), x: Vec::new(), alpha: Vec::new(), chart: Chart::default(), reference_x: None };
    let mut rows = 0;
    for (i, rec) in rdr.records().enumerate() {
        let row = i + 1;
        rows = row;
        let bad = |reason: String| InputError::Row { path: path.to_path_buf(), row, reason };
        let rec = rec.map_err(|e| bad(e.to_string()))?;
        if nodes.s.len() == mesh.nodes() {
            continue;
        }
        let v: Vec<f64> =
            rec.iter().map(|t| t.parse::<f64>().map_err(|e| bad(format!("`{t}`: {e}")))).collect::<Result<_, _>>()?;
        if v.len() != 7 {
            return Err(bad(format!("{} columns, expected 7", v.len())));
        }
        if let Some(k) = v.iter().position(|x| !x.is_finite()) {
            return Err(bad(format!("column {} is not finite ({})", DATA_HEADER[k], v[k])));
        }
        nodes.s.push(v[0]);
        nodes.x.push(Vector3::new(v[1], v[2], v[3]));
        nodes.alpha.push(Vector3::new(v[4], v[5], v[6]));
    }
    let shape = |reason: String| InputError::Shape { path: path.to_path_buf(), reason };
    if rows != mesh.nodes() {
        return Err(shape(format!("{rows} node rows, but the case's mesh has {} nodes", mesh.nodes())));
    }
    for (i, &s) in nodes.s.iter().enumerate() {
        if (s - mesh.node_s(i)).abs() > 1e-9 * mesh.length_m {
            return Err(InputError::Row {
                path: path.to_path_buf(),
                row: i + 1,
                reason: format!("s = {s} m, but mesh node {i} is at {} m", mesh.node_s(i)),
            });
        }
    }
    Ok(nodes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(mesh: &Mesh) -> NodalState {
        let n = mesh.nodes();
        NodalState {
            s: (0..n).map(|i| mesh.node_s(i)).collect(),
            x: (0..n).map(|i| Vector3::new(0.1 / 3.0 * i as f64, (i as f64).sin() * 1e-4, mesh.node_s(i))).collect(),
            alpha: (0..n).map(|i| Vector3::new(std::f64::consts::PI / 7.0, -0.3 * i as f64, 0.25)).collect(),
            chart: Chart::default(),
            reference_x: None,
        }
    }

    #[test]
    fn data_file_round_trips_exactly() {
        let mesh = Mesh::new(1e-3, 7);
        let d = sample(&mesh);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("data.csv");
        write_data(&p, &d).unwrap();
        assert_eq!(read_data(&p, &mesh).unwrap(), d);
    }

    #[test]
    fn malformed_data_names_file_and_row() {
        let mesh = Mesh::new(1e-3, 3);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("data.csv");
        let good = data_csv_text(&sample(&mesh));
        std::fs::write(&p, good.replacen("e-4,", "e-4x,", 1)).unwrap();
        assert!(matches!(read_data(&p, &mesh), Err(InputError::Row { row: 2, .. })), "{:?}", read_data(&p, &mesh));
        let lines: Vec<&str> = good.lines().collect();
        std::fs::write(&p, lines[..3].join("\n")).unwrap();
        let e = read_data(&p, &mesh).unwrap_err().to_string();
        assert!(e.contains("2 node rows") && e.contains("4 nodes"), "{e}");
        std::fs::write(&p, good.replace("2.5000000000000000e-1", "NaN")).unwrap();
        let e = read_data(&p, &mesh).unwrap_err().to_string();
        assert!(e.contains("gamma_rad is not finite"), "{e}");
        assert!(matches!(read_data(&dir.path().join("missing.csv"), &mesh), Err(InputError::Open { .. })));
    }

    /// Rows beyond the mesh are counted, not kept; a file beyond the cap is not read.
    #[test]
    fn extra_rows_and_oversized_files_are_refused() {
        let mesh = Mesh::new(1e-3, 3);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("data.csv");
        let good = data_csv_text(&sample(&mesh));
        let row = good.lines().nth(1).unwrap().to_string() + "\n";
        std::fs::write(&p, good.clone() + &row.repeat(1000)).unwrap();
        let e = read_data(&p, &mesh).unwrap_err().to_string();
        assert!(e.ends_with("data.csv: 1004 node rows, but the case's mesh has 4 nodes"), "{e}");
        let f = std::fs::File::create(&p).unwrap();
        f.set_len(DATA_FILE_CAP_BYTES + 1).unwrap();
        let e = read_data(&p, &mesh).unwrap_err().to_string();
        assert!(
            e.ends_with("data.csv: data file of 268435457 bytes is larger than 268435456 bytes (256 MiB), the cap for data files"),
            "{e}"
        );
    }
}
