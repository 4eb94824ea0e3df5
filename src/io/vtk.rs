//! ParaView output: one VTK XML PolyData file (`.vtp`) per frame holding the centreline as a
//! polyline with per-node vectors (directors, controls) and scalars, and a `.pvd` collection
//! that lists the frames with their times. Written atomically (`io::files::write_atomic`).
use std::fmt::Write as _;
use std::path::Path;

use nalgebra::Vector3;

use super::files::{write_atomic, OutputError};

/// Per-node fields of one frame.
pub struct PolylineFields<'a> {
    /// node positions [m]
    pub points: &'a [Vector3<f64>],
    /// named 3-vectors per node (e.g. `d1`, `f_n_per_m`)
    pub vectors: Vec<(&'a str, &'a [Vector3<f64>])>,
    /// named scalars per node
    pub scalars: Vec<(&'a str, &'a [f64])>,
}

fn data_array(out: &mut String, name: &str, components: usize, values: impl Iterator<Item = f64>) {
    let _ = write!(out, "        <DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"{components}\" format=\"ascii\">\n          ");
    for v in values {
        super::number::push_exp(out, v, 9);
        out.push(' ');
    }
    out.push_str("\n        </DataArray>\n");
}

/// Text of a `.vtp` file: one polyline through `points` with the given point data.
pub fn vtp_text(f: &PolylineFields) -> String {
    let n = f.points.len();
    // about 16 bytes per number: one allocation
    let arrays = 1 + f.vectors.len();
    let mut s = String::with_capacity(1024 + n * (48 * arrays + 16 * f.scalars.len() + 8));
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <PolyData>\n");
    let _ = writeln!(s, "    <Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"0\" NumberOfLines=\"1\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">");
    s.push_str("      <Points>\n");
    data_array(&mut s, "position_m", 3, f.points.iter().flat_map(|p| [p.x, p.y, p.z]));
    s.push_str("      </Points>\n      <PointData>\n");
    for (name, v) in &f.vectors {
        data_array(&mut s, name, 3, v.iter().flat_map(|p| [p.x, p.y, p.z]));
    }
    for (name, v) in &f.scalars {
        data_array(&mut s, name, 1, v.iter().copied());
    }
    s.push_str("      </PointData>\n      <Lines>\n");
    let _ = write!(s, "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n          ");
    for i in 0..n {
        s.push_str(itoa::Buffer::new().format(i));
        s.push(' ');
    }
    let _ = write!(s, "\n        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n          {n}\n        </DataArray>\n");
    s.push_str("      </Lines>\n    </Piece>\n  </PolyData>\n</VTKFile>\n");
    s
}

/// Write one frame as `.vtp`.
pub fn write_vtp(path: &Path, f: &PolylineFields) -> Result<(), OutputError> {
    write_atomic(path, vtp_text(f).as_bytes())
}

/// Write the `.pvd` collection: `(time [s], file name relative to the .pvd)` per frame.
pub fn write_pvd(path: &Path, frames: &[(f64, String)]) -> Result<(), OutputError> {
    let mut s =
        String::from("<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n");
    for (t, file) in frames {
        let _ = writeln!(s, "    <DataSet timestep=\"{t:.9e}\" part=\"0\" file=\"{file}\"/>");
    }
    s.push_str("  </Collection>\n</VTKFile>\n");
    write_atomic(path, s.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vtp_has_points_fields_and_one_polyline() {
        let pts = [Vector3::new(0.0, 0.0, 0.0), Vector3::new(0.0, 0.0, 0.5), Vector3::new(0.1, 0.0, 1.0)];
        let d3 = [Vector3::z(); 3];
        let k = [1.0, 2.0, 3.0];
        let t =
            vtp_text(&PolylineFields { points: &pts, vectors: vec![("d3", &d3)], scalars: vec![("kappa2_per_m", &k)] });
        assert!(
            t.contains("NumberOfPoints=\"3\"")
                && t.contains("Name=\"d3\" NumberOfComponents=\"3\"")
                && t.contains("Name=\"kappa2_per_m\"")
        );
        assert!(t.contains("1.000000000e-1 0.000000000e0 1.000000000e0"));
        assert!(t.contains("0 1 2 \n") && t.contains("          3\n"), "{t}");
        let dir = tempfile::tempdir().unwrap();
        write_pvd(&dir.path().join("clip.pvd"), &[(0.0, "f0.vtp".into()), (0.04, "f1.vtp".into())]).unwrap();
        let pvd = std::fs::read_to_string(dir.path().join("clip.pvd")).unwrap();
        assert!(pvd.contains("timestep=\"4.000000000e-2\" part=\"0\" file=\"f1.vtp\""));
    }
}
