//! Regression snapshots of each case's metrics (Rust engine; a clip case as `cosserat run` and
//! `cosserat compare` solve it alone, its first frame), one test per case of `cases/`, rounded
//! to stated significant digits and written as text, so that they are stable across machines
//! and show no binary round-off. The physics behind the numbers is asserted independently in
//! `tests/forward.rs`; these guard against silent drift.
mod common;

use std::collections::BTreeMap;

use cosserat::case::{case_files, Case};
use cosserat::engine::clip::solve_frames;
use cosserat::engine::input::clip_files::load_clip;
use cosserat::engine::metrics::all_metrics;
use cosserat::engine::{run_case, EngineError};
use cosserat::engine::{Engine, RunError, RunResult};
use cosserat::solve::SolveError;

/// Significant digits kept for physical metrics of static cases (deterministic to ~1e-10).
const DIGITS: usize = 7;
/// Dynamic histories amplify round-off ~1e9-fold over 1000 steps (docs/decisions.md, D12):
/// another CPU's SIMD path can move the final tip by ~1e-5 relative, so keep 4 digits.
const DYNAMIC_DIGITS: usize = 4;
/// The inverse fixed point stops on a plateau where round-off-sized changes of the data move
/// the angles by ~1e-5 and can shift the stop by one iteration (docs/inverse.md, I9): keep 4
/// digits and leave the iteration count to the cross-engine test.
const INVERSE_DIGITS: usize = 4;
/// Errors against theory are differences of nearly equal numbers: 3 digits.
const ERROR_DIGITS: usize = 3;

/// `v` to `digits` significant digits in scientific notation (`-9.787287e-5`), `0` for a zero
/// of either sign: the text is the snapshot, so no binary round-off (`2.6990000000000003e-20`)
/// shows in it.
fn rounded(v: f64, digits: usize) -> String {
    if v == 0.0 {
        "0".into()
    } else {
        format!("{:.*e}", digits - 1, v)
    }
}

/// The rounded metrics of the case `cases/<name>.toml`, snapshot `snapshots__<name>.snap`.
fn case_metrics_snapshot(name: &str) {
    let case = Case::from_file(&common::cases_dir().join(format!("{name}.toml"))).unwrap_or_else(|e| panic!("{e}"));
    let Some(case) = common::with_clip_data(case) else { return };
    let dir = tempfile::tempdir().expect("tempdir");
    // the paper's fixed point ends stalled (docs/certificate.md C4): its last iterate is what
    // the snapshot guards
    let r = match run_case(&case, Engine::Rust, dir.path(), |_, _| {}) {
        Ok(r) => r,
        // a planar recording's frames are solved in the chart of its gauge (along the plane's
        // normal), which the single-frame path refuses: its first frame in that chart
        Err(EngineError::Run(RunError::Chart { .. })) if planar(&case) => first_clip_frame(&case),
        Err(EngineError::Run(RunError::Incomplete { source: SolveError::Stalled(_), partial })) => *partial,
        Err(e) => panic!("{}: {e}", case.name),
    };
    let inverse = case.inverse().is_some();
    let digits = if case.is_dynamic() {
        DYNAMIC_DIGITS
    } else if inverse {
        INVERSE_DIGITS
    } else {
        DIGITS
    };
    let m: BTreeMap<String, String> = all_metrics(&case, &r)
        .expect("reference metrics")
        .into_iter()
        // the certificate is round-off near a root (asserted in tests/certificate.rs)
        .filter(|(k, _)| !matches!(k.as_str(), "wall_time_s" | "last_change" | "relative_residual" | "certificate"))
        // Total Newton count of a dynamic run depends on increments near the threshold.
        .filter(|(k, _)| !((case.is_dynamic() || inverse) && k == "iterations"))
        .map(|(k, v)| {
            let v = if k.contains("iterations") {
                format!("{v}")
            } else if k.ends_with("rel_error") {
                rounded(v, ERROR_DIGITS)
            } else {
                rounded(v, digits)
            };
            (k, v)
        })
        .collect();
    insta::assert_yaml_snapshot!(name, m);
}

/// Is `case` a planar recording (`clip.data_plane`)?
fn planar(case: &Case) -> bool {
    case.clip().is_some_and(|c| c.recording.data_plane.is_some())
}

/// The first frame of the clip case `case` in its chart, as `cosserat run` starts the clip
/// (`solve_frames`), with the case's weights as given (as the single-frame path takes them).
fn first_clip_frame(case: &Case) -> RunResult {
    let (clip, _) = load_clip(case).unwrap_or_else(|e| panic!("{}: {e}", case.name));
    let solved = solve_frames(case, &clip.frames[..1]).unwrap_or_else(|e| panic!("{}: {e}", case.name));
    solved.frames.into_iter().next().unwrap_or_else(|| panic!("{}: no frame solved", case.name)).result
}

/// One `#[test]` per case, so that every case that drifts is reported, and the list of the
/// cases tested ([`CASES`]).
macro_rules! case_snapshots {
    ($($name:ident)*) => {
        $(
            #[test]
            fn $name() {
                case_metrics_snapshot(stringify!($name));
            }
        )*
        /// The cases with a snapshot test.
        const CASES: &[&str] = &[$(stringify!($name)),*];
    };
}

case_snapshots!(
    cantilever_dynamic
    follower_bend_64
    follower_bend_twist_65
    inverse_bend
    inverse_bend_twist
    inverse_bend_twist_newton
    timoshenko_10pct
    timoshenko_5pct
    worm_2d_recording
    worm_delta_turn
    worm_delta_turn_ld1
    worm_omega_turn
    worm_omega_turn_ld1
    worm_roll_3d
);

/// A case added to `cases/` needs its line in `case_snapshots!` (and a removed one leaves it).
#[test]
fn every_case_has_a_snapshot_test() {
    let files: Vec<String> = case_files(&common::cases_dir())
        .expect("cases dir")
        .iter()
        .map(|f| f.file_stem().expect("case file name").to_string_lossy().into_owned())
        .collect();
    let mut tested: Vec<String> = CASES.iter().map(|s| s.to_string()).collect();
    tested.sort();
    let mut files = files;
    files.sort();
    assert_eq!(files, tested, "cases/*.toml and the tests of case_snapshots!");
}
