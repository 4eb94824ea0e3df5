//! Tests of case files: parsing, validation, derived settings.
use super::*;
use crate::solve::statics::Method;

const GOOD: &str = r#"
description = "test"
[constants]
F = 1e-8
L0 = 1e-3
[rod]
length_m = "L0"
elements = 10
[material]
young_modulus_pa = 1.1e5
shear_modulus_pa = 5e4
shear_correction = "4/3"
[cross_section]
shape = "circle"
radius_m = "L0/40"
[loads]
end_force_n = [0, "-F", 0]
[solver]
analysis = "static"
relaxation = 0.5
tolerance = 1e-10
max_iterations = 100
[compare]
frames = 4
"#;

fn parse(text: &str) -> Result<Case, CaseError> {
    Case::from_toml(text, "t", Path::new("t.toml"))
}

#[test]
fn good_case_parses() {
    let c = parse(GOOD).unwrap();
    assert_eq!(c.mesh.elements, 10);
    assert!((c.mesh.length_m - 1e-3).abs() < 1e-18);
    assert!((c.rod.material.expect("a material").shear_correction - 4.0 / 3.0).abs() < 1e-15);
    assert!(
        matches!(c.analysis, Analysis::Static(StaticParams { method: Method::FixedPoint { relaxation }, .. }) if relaxation == 0.5)
    );
    assert_eq!(c.checks.compare.frames, 4);
    assert_eq!(c.checks.compare.overrides, CompareOverrides::default());
}

#[test]
fn compare_overrides_need_a_reason() {
    let text = GOOD.replace("frames = 4", "frames = 4\nangles_rel = 1e-6");
    expect_key(&text, "compare.angles_rel");
    let ok = parse(&text.replace("frames = 4", "frames = 4\nreason = \"measured: the twist is held by 1e-10 only\""));
    assert_eq!(ok.unwrap().checks.compare.overrides.angles_rel, Some(1e-6));
    expect_key(&GOOD.replace("frames = 4", "frames = 0"), "compare.frames");
    expect_key(&GOOD.replace("frames = 4", "metric_abs = -1\nreason = \"x\""), "compare.metric_abs");
}

fn expect_key(text: &str, key: &str) {
    match parse(text) {
        Err(CaseError::Invalid { key: k, .. }) => assert_eq!(k, key),
        other => panic!("expected invalid {key}, got {other:?}"),
    }
}

#[test]
fn bad_values_name_the_key() {
    expect_key(&GOOD.replace("elements = 10", "elements = 1"), "rod.elements");
    expect_key(&GOOD.replace("young_modulus_pa = 1.1e5", "young_modulus_pa = -1"), "material.young_modulus_pa");
    expect_key(&GOOD.replace("\"-F\"", "\"-G*s\""), "loads.end_force_n[1]");
    expect_key(&GOOD.replace("relaxation = 0.5", "relaxation = 1.5"), "solver.relaxation");
    expect_key(&GOOD.replace("radius_m = \"L0/40\"", "radius_m = \"L0/(\""), "cross_section.radius_m");
    expect_key(&GOOD.replace("analysis = \"static\"", "analysis = \"dynamic\""), "material.density_kg_m3");
}

#[test]
fn unknown_keys_are_rejected() {
    let e = parse(&GOOD.replace("elements = 10", "elements = 10\nelement = 3")).unwrap_err();
    assert!(e.to_string().contains("unknown field `element`"), "{e}");
}

fn reason(text: &str) -> String {
    match parse(text) {
        Err(e @ CaseError::Invalid { .. }) => e.to_string(),
        other => panic!("expected an invalid key, got {other:?}"),
    }
}

#[test]
fn case_files_are_read_within_the_cap() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("big.toml");
    std::fs::File::create(&p).unwrap().set_len(CASE_FILE_CAP_BYTES + 1).unwrap();
    let e = Case::from_file(&p).unwrap_err().to_string();
    let cap = "1048576 bytes (1 MiB), the cap for case files";
    assert_eq!(e, format!("{}: case file of 1048577 bytes is larger than {cap}", p.display()));
    if cfg!(unix) {
        let e = Case::from_file(Path::new("/dev/zero")).unwrap_err().to_string();
        assert!(e.starts_with("/dev/zero: the case file is a character device, not a regular file"), "{e}");
        // a named pipe with no writer: refused at once, never opened (the open would block)
        let fifo = dir.path().join("pipe.toml");
        if std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success()) {
            let e = Case::from_file(&fifo).unwrap_err().to_string();
            assert!(e.contains("is a named pipe (FIFO), not a regular file"), "{e}");
        }
        let e = Case::from_file(dir.path()).unwrap_err().to_string();
        assert!(e.contains("the case file is a folder"), "{e}");
    }
}

/// A load that is not finite on the mesh (or at a time step) is refused at load, naming the
/// key, the expression as written, s and t.
#[test]
fn non_finite_loads_are_refused_at_load() {
    let with_force = |f: &str| GOOD.replace("[loads]", &format!("[loads]\nforce_n_per_m = [0, \"{f}\", 0]"));
    let tail = "a load must be finite at every node and load quadrature point of the rod";
    assert_eq!(
        reason(&with_force("1/(s-s)")),
        format!("t.toml: key `loads.force_n_per_m[1]`: `1/(s-s)` is not finite (inf) at s = 0 m, t = 0 s: {tail}")
    );
    assert_eq!(
        reason(&with_force("1/(s - L0)")),
        format!(
            "t.toml: key `loads.force_n_per_m[1]`: `1/(s - L0)` is not finite (inf) at s = 0.001 m, t = 0 s: {tail}"
        )
    );
    // A load quadrature point, not a node: the first Gauss point of element 3.
    let mesh = Mesh::new(1e-3, 10);
    let s = mesh.node_s(3) + crate::model::mesh::GAUSS2.points[0] * mesh.h();
    let e = reason(&with_force(&format!("1/(s - {s:e})")));
    assert!(e.contains(&format!("is not finite (inf) at s = {s} m, t = 0 s")), "{e}");
    let dynamic = GOOD
        .replace("analysis = \"static\"\nrelaxation = 0.5", "analysis = \"dynamic\"\nmethod = \"newton\"")
        .replace("[compare]", "[time]\nend_s = 1\nsteps = 10\n[compare]")
        .replace("shear_correction", "density_kg_m3 = 1e3\nshear_correction");
    assert!(parse(&dynamic).is_ok());
    let e = reason(&dynamic.replace("end_force_n = [0, \"-F\", 0]", "end_force_n = [0, \"-F*sqrt(0.35 - t)\", 0]"));
    assert_eq!(
        e,
        format!(
            "t.toml: key `loads.end_force_n[1]`: `-F*sqrt(0.35 - t)` is not finite (NaN) at s = L = 0.001 m, t = 0.4 s: {tail} \
             and at every time step"
        )
    );
    let e = reason(&dynamic.replace("[loads]", "[loads]\ntorque_nm_per_m = [\"s/(t - 0.5)\", 0, 0]"));
    assert!(e.contains("`loads.torque_nm_per_m[0]`: `s/(t - 0.5)` is not finite (NaN) at s = 0 m, t = 0.5 s"), "{e}");
}

/// NaN and infinity, as TOML numbers or as names, and names a key does not have.
#[test]
fn non_numbers_and_unknown_names_say_what_is_allowed() {
    let e = reason(&GOOD.replace("end_force_n = [0, \"-F\", 0]", "end_force_n = [0, nan, 0]"));
    assert_eq!(
        e,
        "t.toml: key `loads.end_force_n[1]`: NaN is not a number of the expression language (NaN and infinity \
         are not: every load must be finite); write a finite number or an expression of pi and the [constants] \
         F, L0"
    );
    let e = reason(&GOOD.replace("[loads]", "[loads]\nforce_n_per_m = [\"NaN\", 0, 0]"));
    assert_eq!(
        e,
        "t.toml: key `loads.force_n_per_m[0]`: unknown name `NaN` in `NaN` (NaN and infinity are not numbers of \
         the expression language: every value must be finite); allowed names: s, pi and the [constants] F, L0"
    );
    let e = reason(&GOOD.replace("\"-F\"", "\"-F*s\""));
    assert!(
        e.ends_with(
            "unknown name `s` in `-F*s` (s, the arc length [m], is defined in distributed loads only: end loads \
             act at s = L); allowed names: pi and the [constants] F, L0"
        ),
        "{e}"
    );
    let e = reason(
        &GOOD.replace("[constants]\nF = 1e-8\nL0 = 1e-3", "").replace("L0", "1e-3").replace("\"-F\"", "\"inf\""),
    );
    assert!(e.ends_with("every value must be finite); allowed names: pi (no [constants] are defined)"), "{e}");
    let e = reason(&GOOD.replace("radius_m = \"L0/40\"", "radius_m = \"L0/t\""));
    assert!(e.contains("`cross_section.radius_m`: unknown name `t` in `L0/t` (t, the time [s], is defined in the loads of a dynamic analysis only); allowed names: pi and the [constants] F, L0"), "{e}");
}

#[test]
fn constants_resolve_in_dependency_order_and_cycles_are_named() {
    let c = parse(&GOOD.replace("F = 1e-8", "F = 1e-8\nza = 2\nyb = \"za*2\"\nxc = \"yb*2\"")).unwrap();
    assert_eq!(c.origin.constants["xc"], 8.0);
    let e = reason(&GOOD.replace("F = 1e-8", "F = \"G\"\nG = \"2*F\""));
    let cycle = "refer to themselves or to one another in a cycle";
    assert_eq!(e, format!("t.toml: key `constants.F`: cannot be evaluated: the constants F, G {cycle}"));
    let e = reason(&GOOD.replace("F = 1e-8", "F = \"2*F\""));
    assert_eq!(e, format!("t.toml: key `constants.F`: cannot be evaluated: the constants F {cycle}"));
    let e = reason(&GOOD.replace("F = 1e-8", "F = 1e-8\nk = \"x*2\""));
    assert_eq!(
        e,
        "t.toml: key `constants.k`: unknown name `x` in `x*2`; allowed names: pi and the [constants] F, L0, k"
    );
    for name in ["\"(a)\"", "\"-a\"", "sin", "pi", "s"] {
        let e = reason(&GOOD.replace("F = 1e-8", &format!("F = 1e-8\n{name} = 1")));
        assert!(e.contains("not a valid constant name"), "{name}: {e}");
    }
}

#[test]
fn meshes_clip_meshes_and_clip_vectors_are_bounded() {
    let e = reason(&GOOD.replace("elements = 10", "elements = 1000001"));
    assert_eq!(e, "t.toml: key `rod.elements`: at most 1000000 elements, got 1000001");
    let worm =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/worm_omega_turn.toml")).unwrap();
    let e = reason(&worm.replace("elements = 127", "elements = 2"));
    assert_eq!(
        e,
        "t.toml: key `rod.elements`: a clip case needs at least 11 elements (12 nodes per frame of clip.file \
         `../data/elegansbot/kymogram_omega-turn.npy`), got 2 (3 nodes): the clip's measures leave out 5 elements at \
         each end (curvature errors, ground truth) and the roughness needs 3 curvature values"
    );
    assert!(parse(&worm.replace("elements = 127", "elements = 11")).is_ok());
    let e = reason(&worm.replace("start = \"data_guess\"", "start = \"data_guess\"\ngauge = [1e308, 1e308, 0]"));
    assert!(e.contains("key `clip.gauge`: must be a finite non-zero vector"), "{e}");
    let e =
        reason(&worm.replace("start = \"data_guess\"", "start = \"data_guess\"\norientation = [1e308, 1e308, 1e308]"));
    assert!(e.contains("key `clip.orientation`: rotation vector"), "{e}");
}

/// `rod.length_m = "from_data"` is a typed variant of a recorded clip case, with the mesh's
/// placeholder length until the recording is read; any other case refuses it, naming what it is.
#[test]
fn length_from_data_is_for_recordings_only() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let batch = std::fs::read_to_string(root.join("cases/batch/roll_recording.toml")).unwrap();
    let c = parse(&batch.replace("length_m = \"L\"", "length_m = \"from_data\"")).unwrap();
    assert_eq!(
        (c.rod.length, c.mesh.length_m, c.body_length()),
        (RodLength::FromData(None), FROM_DATA_PLACEHOLDER_M, None)
    );
    assert_eq!(parse(&batch).unwrap().rod.length, RodLength::Given);
    let tail = "\"from_data\" estimates the body length from a recording: only for an inverse case with [clip] kind = \
                \"recording\", but this is";
    let e = reason(&GOOD.replace("length_m = \"L0\"", "length_m = \"from_data\""));
    assert_eq!(e, format!("t.toml: key `rod.length_m`: {tail} a static case; give the length in metres"));
    let worm = std::fs::read_to_string(root.join("cases/worm_omega_turn.toml")).unwrap();
    let e = reason(&worm.replace("length_m = \"L\"", "length_m = \"from_data\""));
    assert!(e.contains(&format!("{tail} a kymogram clip")), "{e}");
    // a misspelt word is an expression with an unknown name
    let e = reason(&batch.replace("length_m = \"L\"", "length_m = \"from-data\""));
    assert!(e.contains("key `rod.length_m`"), "{e}");
}

/// `clip.missing` is a typed key: "nan" on a recording, refused on a kymogram, any other value
/// unknown; without it a recording's NaN is an error (`MissingData::Error`).
#[test]
fn clip_missing_is_validated_once() {
    use crate::clip::missing::MissingData;
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let batch = std::fs::read_to_string(root.join("cases/batch/roll_recording.toml")).unwrap();
    let with = |v: &str| batch.replace("rotation = \"rebased\"", &format!("rotation = \"rebased\"\nmissing = {v}"));
    assert_eq!(parse(&batch).unwrap().clip().unwrap().missing, MissingData::Error);
    assert_eq!(parse(&with("\"nan\"")).unwrap().clip().unwrap().missing, MissingData::Nan);
    let e = parse(&with("\"zero\"")).unwrap_err().to_string();
    assert!(e.contains("unknown variant `zero`") && e.contains("nan"), "{e}");
    let worm = std::fs::read_to_string(root.join("cases/worm_omega_turn.toml")).unwrap();
    let e = reason(&worm.replace("start = \"data_guess\"", "start = \"data_guess\"\nmissing = \"nan\""));
    assert!(e.contains("key `clip.missing`: applies to kind = \"recording\" only"), "{e}");
}
