//! Recordings as trackers write them: units, 2D data, empty cells, frame numbers from any start
//! with dropped frames, WCON; every number checked against the positions written.
use super::*;
use crate::clip::recording::LengthUnit;
use crate::io::npy::write_npy;

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A 2D midline of 4 points in micrometres per frame `f`: exact binary fractions, so that the
/// metres read are the micrometres × 1e-6 to the last bit of the product.
fn point(f: usize, i: usize) -> (f64, f64) {
    (1000.0 + 8.0 * i as f64 + 0.5 * f as f64, 2000.0 - 4.0 * i as f64)
}

fn spec(missing: MissingData) -> ReadSpec {
    ReadSpec { missing, dt_s: 0.04, ..ReadSpec::default() }
}

#[test]
fn a_2d_csv_in_micrometres_is_planar_in_metres_from_its_first_frame() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("frame,node,x_um,y_um\n");
    for f in 7..10 {
        for i in 0..4 {
            let (x, y) = point(f, i);
            text += &format!("{f},{i},{x},{y}\n");
        }
    }
    let p = write(dir.path(), "r.csv", &text);
    let r = read_positions(&p, &spec(MissingData::Error)).unwrap();
    assert_eq!(r.info.first_frame, 7);
    assert_eq!(r.info.unit, LengthUnit::Micrometre);
    assert_eq!(r.info.plane_normal, Some(Vector3::z()));
    assert_eq!(r.frames.len(), 3);
    for (k, frame) in r.frames.iter().enumerate() {
        for (i, p) in frame.iter().enumerate() {
            let (x, y) = point(k + 7, i);
            assert_eq!(*p, Vector3::new(x * 1e-6, y * 1e-6, 0.0));
        }
    }
    // the case's unit must agree with the header's
    let s =
        ReadSpec { units: UnitSpec { unit: Some(LengthUnit::Millimetre), m_per_px: None }, ..spec(MissingData::Error) };
    let e = read_positions(&p, &s).unwrap_err().to_string();
    assert!(e.contains("the CSV header says the positions are in `um`") && e.contains("clip.unit = \"mm\""), "{e}");
    // pixels need a scale, and take it
    let px = write(dir.path(), "px.csv", &text.replace("x_um,y_um", "x_px,y_px"));
    let e = read_positions(&px, &spec(MissingData::Error)).unwrap_err().to_string();
    assert!(e.contains("clip.scale_m_per_px"), "{e}");
    let s = ReadSpec { units: UnitSpec { unit: None, m_per_px: Some(0.25e-5) }, ..spec(MissingData::Error) };
    let r = read_positions(&px, &s).unwrap();
    assert_eq!(r.frames[0][1], Vector3::new(point(7, 1).0 * 0.25e-5, point(7, 1).1 * 0.25e-5, 0.0));
    // a header without a known unit says what it expects
    let bad = write(dir.path(), "bad.csv", &text.replace("x_um,y_um", "x_inch,y_inch"));
    let e = read_positions(&bad, &spec(MissingData::Error)).unwrap_err().to_string();
    assert!(e.contains("unknown unit `inch`") && e.contains("frame,node,x_um,y_um"), "{e}");
}

/// Empty cells, `NaN` and a frame with no rows at all are untracked with `missing = "nan"`;
/// without it, each is an error naming the row or frame with the key to set.
#[test]
fn empty_cells_nan_and_dropped_frames_are_missing_data() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("frame,node,x_mm,y_mm\n");
    for f in 1..6 {
        if f == 3 {
            continue; // dropped
        }
        for i in 0..4 {
            let (x, y) = point(f, i);
            let cells = match (f, i) {
                (2, 3) => ",".to_string(),
                (4, 0) => "NaN,nan".to_string(),
                _ => format!("{x},{y}"),
            };
            text += &format!("{f},{i},{cells}\n");
        }
    }
    let p = write(dir.path(), "gaps.csv", &text);
    let r = read_positions(&p, &spec(MissingData::Nan)).unwrap();
    assert_eq!((r.info.first_frame, r.frames.len()), (1, 5));
    assert!(r.frames[1][3].iter().all(|v| v.is_nan()) && r.frames[3][0].iter().all(|v| v.is_nan()));
    assert!(r.frames[2].iter().flatten().all(|v| v.is_nan()), "the dropped frame is lost");
    assert_eq!(r.frames[4][2], Vector3::new(point(5, 2).0 * 1e-3, point(5, 2).1 * 1e-3, 0.0));
    assert_eq!(r.frames.iter().flatten().filter(|p| p.x.is_finite()).count(), 4 * 5 - 4 - 2);
    let e = read_positions(&p, &spec(MissingData::Error)).unwrap_err().to_string();
    assert!(e.contains("row 8: frame 2, node 3: x_mm is empty") && e.contains("clip.missing = \"nan\""), "{e}");
    let no_empty = write(dir.path(), "drop.csv", &text.replace("2,3,,", "2,3,1,1").replace("4,0,NaN,nan", "4,0,1,1"));
    let e = read_positions(&no_empty, &spec(MissingData::Error)).unwrap_err().to_string();
    assert!(e.contains("frame 4 comes where frame 3 was expected"), "{e}");
}

#[test]
fn npy_recordings_of_two_coordinates_are_planar_in_the_case_unit() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("r.npy");
    let data: Vec<f64> = (0..2).flat_map(|f| (0..3).flat_map(move |i| [point(f, i).0, point(f, i).1])).collect();
    write_npy(&p, &[2, 3, 2], &data).unwrap();
    let s =
        ReadSpec { units: UnitSpec { unit: Some(LengthUnit::Micrometre), m_per_px: None }, ..spec(MissingData::Error) };
    let r = read_positions(&p, &s).unwrap();
    assert_eq!(r.info.plane_normal, Some(Vector3::z()));
    assert_eq!(r.frames[1][2], Vector3::new(point(1, 2).0 * 1e-6, point(1, 2).1 * 1e-6, 0.0));
    // three columns with a constant one: planar about that axis
    let p3 = dir.path().join("r3.npy");
    let data3: Vec<f64> = (0..2).flat_map(|f| (0..3).flat_map(move |i| [point(f, i).0, 5.0, point(f, i).1])).collect();
    write_npy(&p3, &[2, 3, 3], &data3).unwrap();
    assert_eq!(read_positions(&p3, &spec(MissingData::Error)).unwrap().info.plane_normal, Some(Vector3::y()));
}

/// The format's own examples (WCON_format.md of openworm/tracker-commons): units, several
/// records of one worm merged by time, the origin `ox, oy`, `head = "R"`, `null` points, and
/// times numbered as frames of the case's interval.
#[test]
fn wcon_records_of_one_worm_become_frames_of_its_times() {
    let dir = tempfile::tempdir().unwrap();
    let text = r#"{
        "units": {"t": "s", "x": "mm", "y": "mm", "ox": "mm", "oy": "mm"},
        "metadata": {"strain": "N2"},
        "data": [
            {"id": "1", "t": [0.08, 0.12], "x": [[1, 2, 3], [1.5, 2.5, 3.5]], "y": [[0, 0, 0], [1, null, 1]],
             "ox": [10, 10], "oy": 20},
            {"id": "2", "t": [0.08], "x": [[9, 9, 9]], "y": [[9, 9, 9]]},
            {"id": "1", "t": [0.2], "x": [[3, 2, 1]], "y": [[5, 6, 7]], "head": "R", "@XJ": {"speed": [1]}}
        ]
    }"#;
    let p = write(dir.path(), "w.wcon", text);
    let e = read_positions(&p, &spec(MissingData::Nan)).unwrap_err().to_string();
    assert!(e.contains("2 worms") && e.contains("clip.worm_id"), "{e}");
    let s = ReadSpec { worm_id: Some("1".into()), ..spec(MissingData::Nan) };
    let r = read_positions(&p, &s).unwrap();
    // t = 0.08, 0.12, 0.2 s at Δt = 0.04 s: frames 2, 3 and 5; frame 4 was not recorded
    assert_eq!((r.info.first_frame, r.frames.len(), r.info.unit), (2, 4, LengthUnit::Millimetre));
    let mm = |x: f64, y: f64| Vector3::new(x * 1e-3, y * 1e-3, 0.0);
    assert_eq!(r.frames[0], vec![mm(11.0, 20.0), mm(12.0, 20.0), mm(13.0, 20.0)]);
    assert!(r.frames[1][1].x.is_nan() && r.frames[1][0] == mm(11.5, 21.0));
    assert!(r.frames[2].iter().all(|p| p.x.is_nan()), "frame 4: lost");
    assert_eq!(r.frames[3], vec![mm(1.0, 7.0), mm(2.0, 6.0), mm(3.0, 5.0)], "head = R: reversed");
    let e = read_positions(&p, &ReadSpec { worm_id: Some("1".into()), ..spec(MissingData::Error) }).unwrap_err();
    assert!(e.to_string().contains("frame 3, node 1: x = NaN"), "{e}");
    let off = ReadSpec { dt_s: 0.03, worm_id: Some("1".into()), ..spec(MissingData::Nan) };
    let e = read_positions(&p, &off).unwrap_err().to_string();
    assert!(e.contains("t = 0.08 s is 2.667 frame intervals"), "{e}");
}

/// A recording held in memory is read as the NPY file of the same array: the same positions
/// (units, planar placement, NaN nodes) and what it says of itself; the same refusals.
#[test]
fn a_recording_in_memory_reads_as_its_npy_file() {
    let dir = tempfile::tempdir().unwrap();
    let name = dir.path().join("memory.npy");
    let mut data: Vec<f64> =
        (0..3).flat_map(|f| (0..4).flat_map(move |i| [point(f, i).0, 7.0 + f as f64, point(f, i).1])).collect();
    data[12 + 4] = f64::NAN; // frame 1, node 1: y untracked
    write_npy(&name, &[3, 4, 3], &data).unwrap();
    let s =
        ReadSpec { units: UnitSpec { unit: Some(LengthUnit::Micrometre), m_per_px: None }, ..spec(MissingData::Nan) };
    let from_file = read_positions(&name, &s).unwrap();
    let in_memory = memory_recorded(&name, &data, (3, 4, 3), &s).unwrap();
    assert_eq!(in_memory.info, from_file.info);
    assert!(in_memory.frames[1][1].iter().all(|v| v.is_nan()));
    let bits = |r: &Recorded| r.frames.iter().flatten().flat_map(|p| p.iter().map(|v| v.to_bits())).collect::<Vec<_>>();
    assert_eq!(bits(&in_memory), bits(&from_file));
    // a NaN without clip.missing = "nan", an infinity, a shape that does not hold the values
    let refused = |r: Result<Recorded, InputError>| r.unwrap_err().to_string();
    assert!(refused(memory_recorded(&name, &data, (3, 4, 3), &spec(MissingData::Error))).contains("frame 1, node 1"));
    data[2] = f64::INFINITY;
    assert!(refused(memory_recorded(&name, &data, (3, 4, 3), &s)).contains("frame 0, node 0: z = inf"));
    assert!(refused(memory_recorded(&name, &data, (3, 4, 2), &s)).contains("expected frames × nodes × 3"));
}
