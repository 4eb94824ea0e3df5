//! Noisy recordings (`docs/noise.md`): `[inverse] weights = "auto"` against the truth and
//! against the generic baseline, a GCV smoothing spline of the same noisy frames, scored the same
//! way in one run of the noise study.
use std::path::Path;

use cosserat::case::Case;
use cosserat::study::{run_study, Depth, StudyRow, StudySpec, SPLINE};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A study of one recording of `frames` frames of `nodes` nodes at each noise level of
/// `noise_m`.
fn study(noise_m: &[f64], frames: usize, nodes: usize) -> Vec<StudyRow> {
    study_of(Corpus { noise_m, frames, nodes, recordings: 1, seed: 11, shape_noise_m: 0.0 })
}

/// What a test's study reconstructs.
struct Corpus<'a> {
    noise_m: &'a [f64],
    frames: usize,
    nodes: usize,
    recordings: usize,
    seed: u64,
    /// `[[meshes]] shape_noise_m`: smooth changes of shape per frame [m]
    shape_noise_m: f64,
}

fn study_of(c: Corpus) -> Vec<StudyRow> {
    let Corpus { noise_m, frames, nodes, recordings, seed, shape_noise_m } = c;
    let dir = tempfile::tempdir().expect("temp dir");
    let levels = noise_m.iter().map(|s| format!("{s:e}")).collect::<Vec<_>>().join(", ");
    let text = format!(
        r#"title = "test"
noise_m = [{levels}]
recordings = {recordings}
frames = {frames}
seed = {seed}
skip_elements = 5
kymogram = "{kymo}"
quick = {{ noise_m = [0.0], recordings = 1, frames = 2 }}
[[meshes]]
nodes = {nodes}
case = "{case}"
shape_noise_m = {shape_noise_m:e}
[[variants]]
name = "table1"
label = "Table 1"
set = {{ "inverse.weights" = "fixed" }}
[[variants]]
name = "auto"
label = "auto"
"#,
        kymo = root().join("data/elegansbot/kymogram_omega-turn.npy").display(),
        case = root().join("cases/batch/roll_recording.toml").display(),
    );
    let spec_path = dir.path().join("spec.toml");
    std::fs::write(&spec_path, text).expect("spec");
    let spec = StudySpec::read(&spec_path).expect("spec reads");
    run_study(&spec, &dir.path().join("out"), Depth::Full, |_| {}).expect("study runs")
}

fn find<'a>(rows: &'a [StudyRow], method: &str, noise_m: f64) -> &'a StudyRow {
    rows.iter().find(|r| r.method == method && r.noise_m == noise_m).expect("row")
}

/// At 1 µm and 3 µm of noise on a 1 mm body (33 nodes): the noise level is estimated within
/// 10 % of the truth; every frame reconstructs; with the λg the discrepancy principle chose, the
/// median and the worst frame's bending error are below the smoothing spline's, and far below
/// those of the paper's fixed λg = 1e9, which follows the noise.
#[test]
fn automatic_weights_beat_the_smoothing_spline_on_noisy_recordings() {
    let levels = [1e-6, 3e-6];
    let rows = study(&levels, 12, 33);
    for &s in &levels {
        let (auto, spline, fixed) = (find(&rows, "auto", s), find(&rows, SPLINE, s), find(&rows, "table1", s));
        let est = auto.noise_estimate_m.expect("auto records its noise estimate");
        assert!((est / s - 1.0).abs() < 0.1, "σ = {s:e}: estimated {est:e}");
        assert_eq!(auto.frames_reconstructed, auto.frames, "σ = {s:e}: {auto:?}");
        let lg = auto.lambda_g.expect("auto records λg");
        assert!(lg < 1e9 && lg > 1e3, "σ = {s:e}: λg = {lg:e}");
        assert!(auto.bending_err_median < spline.bending_err_median, "σ = {s:e}: {auto:?} vs {spline:?}");
        assert!(auto.bending_err_worst < spline.bending_err_worst, "σ = {s:e}: {auto:?} vs {spline:?}");
        assert!(auto.bending_err_median * 5.0 < fixed.bending_err_median, "σ = {s:e}: {auto:?} vs {fixed:?}");
    }
}

/// 10 µm of noise on 128 nodes of a 1 mm body: the noise exceeds the node spacing (7.9 µm), so a
/// raw chord's direction is noise. Every frame reconstructs (the chart and the data guess come
/// from the smoothed centreline, docs/noise.md N8), the estimate is within 10 % of the truth,
/// and the median and the worst frame's bending error are below the smoothing spline's.
#[test]
fn automatic_weights_reconstruct_noise_larger_than_the_node_spacing() {
    let s = 1e-5;
    let rows = study(&[s], 8, 128);
    let (auto, spline) = (find(&rows, "auto", s), find(&rows, SPLINE, s));
    let est = auto.noise_estimate_m.expect("auto records its noise estimate");
    assert!((est / s - 1.0).abs() < 0.1, "estimated {est:e}");
    assert_eq!(auto.frames_reconstructed, auto.frames, "{auto:?}");
    assert!(auto.bending_err_median < spline.bending_err_median, "{auto:?} vs {spline:?}");
    assert!(auto.bending_err_worst < spline.bending_err_worst, "{auto:?} vs {spline:?}");
}

/// On a clean recording the estimated noise is the 33-node mesh's own fourth-difference floor
/// (h⁴ x'''' of the body's curvature, far below 1 µm) and automatic weights stay close to the
/// paper's: the bending error is within the clean element's own error (0.05–0.11 at 33 nodes,
/// docs/noise.md N5), not above it.
#[test]
fn automatic_weights_on_a_clean_recording_stay_within_the_element_floor() {
    let rows = study(&[0.0], 12, 33);
    let auto = find(&rows, "auto", 0.0);
    assert!(auto.noise_estimate_m.expect("estimate") < 2e-7, "{auto:?}");
    assert!(auto.lambda_g.expect("λg") >= 1e6, "{auto:?}");
    assert_eq!(auto.frames_reconstructed, auto.frames);
    assert!(auto.bending_err_worst < 0.15, "{auto:?}");
}

/// Recordings whose frames differ from the clean ones by smooth, independent changes of shape
/// (5 µm RMS, 0.5 % of the body: the first three sine and cosine modes along it) stretch the
/// body by up to 8 % between nodes, which the rod cannot follow exactly; its twist is then held
/// by the weak load terms only and changes branch in a band of λg, where Newton stalls
/// (docs/noise.md N13). Every frame of every recording reconstructs (at 1 µm of noise,
/// recording 3 stalled at frame 30 of 60 from every start below its λg; it is now continued
/// from above), and on the recordings without added noise, where even the cap's fit is
/// farther from the data than the noise, the discrepancy principle's choice is the cap (a
/// stalled calibration solve at 1e8 was read as a fit that follows the noise: recording 6
/// then got λg = 9.96e7 and a twist of −35,000 rad/m on every frame).
///
/// The frame's curvature against the smoothing spline's, recording by recording: without
/// added noise the worst frame at or below the spline's and the median within 1.25× of it (the
/// issue's target; the stabilisation ε = 0.1 of automatic weights gives 0.85–0.98× and
/// 0.81–1.04×, where the earlier ε = 1e-3 gave up to 2.12× and 1.48×); at 1 µm of noise both
/// within 1.5× (0.68–1.17× and 0.73–1.25× measured; 4.42× and 1.93× with ε = 1e-3).
#[test]
fn recordings_with_smooth_changes_of_shape_reconstruct_every_frame() {
    let levels = [0.0, 1e-6];
    let rows =
        study_of(Corpus { noise_m: &levels, frames: 60, nodes: 33, recordings: 8, seed: 1, shape_noise_m: 5e-6 });
    let auto: Vec<&StudyRow> = rows.iter().filter(|r| r.method == "auto").collect();
    assert_eq!(auto.len(), 16);
    for r in &auto {
        assert_eq!(r.frames_reconstructed, r.frames, "{r:?}");
        let spline = rows
            .iter()
            .find(|s| s.method == SPLINE && s.noise_m == r.noise_m && s.recording == r.recording)
            .expect("the spline's row");
        let (median, worst) = if r.noise_m == 0.0 { (1.25, 1.0) } else { (1.5, 1.5) };
        assert!(r.bending_err_median <= median * spline.bending_err_median, "{r:?} against {spline:?}");
        assert!(r.bending_err_worst <= worst * spline.bending_err_worst, "{r:?} against {spline:?}");
        if r.noise_m == 0.0 {
            assert_eq!(r.lambda_g, Some(1e9), "{r:?}");
        }
    }
}

/// `weights = "auto"` needs a recording's noise: a case with forward data refuses it, naming
/// the key.
#[test]
fn automatic_weights_need_a_clip() {
    let text = std::fs::read_to_string(root().join("cases/inverse_bend_twist_newton.toml")).expect("case");
    let text = text.replacen("[inverse]", "[inverse]\nweights = \"auto\"", 1);
    let err = Case::from_toml(&text, "auto", Path::new("auto.toml")).expect_err("refused").to_string();
    assert!(err.contains("inverse.weights") && err.contains("clip"), "{err}");
}
