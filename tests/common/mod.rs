//! Shared helpers of the integration tests.
#![allow(dead_code)]
use std::path::{Path, PathBuf};

use cosserat::case::Case;

pub fn cases_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("cases")
}

pub fn case_text(name: &str) -> String {
    std::fs::read_to_string(cases_dir().join(format!("{name}.toml"))).expect("case file")
}

/// Parse a case from (modified) TOML text.
pub fn case_from(text: &str, name: &str) -> Case {
    Case::from_toml(text, name, Path::new(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// Replace exactly one occurrence of `from` (so a silently unmatched edit fails the test).
pub fn edit(text: &str, from: &str, to: &str) -> String {
    assert_eq!(text.matches(from).count(), 1, "pattern `{from}` must occur once");
    text.replacen(from, to, 1)
}

/// Round to `digits` significant digits (stable snapshot values across machines).
pub fn sig(v: f64, digits: i32) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let p = digits - 1 - v.abs().log10().floor() as i32;
    let f = 10f64.powi(p);
    (v * f).round() / f
}

/// A case file of `cases/` read from disk (relative paths inside it resolve against `cases/`).
pub fn case_file(name: &str) -> Case {
    Case::from_file(&cases_dir().join(format!("{name}.toml"))).unwrap_or_else(|e| panic!("{e}"))
}

/// Are the worm clips of `scripts/fetch_worm_data.sh` present? Prints a notice when not.
pub fn worm_data_present(test: &str) -> bool {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/elegansbot");
    let ok = ["kymogram_omega-turn.npy", "kymogram_delta-turn.npy"].iter().all(|f| dir.join(f).is_file());
    if !ok {
        eprintln!("{test}: SKIPPED: the worm clips are not in {} (run scripts/fetch_worm_data.sh)", dir.display());
    }
    ok
}

/// Is this case a recorded clip (`[clip]`)?
pub fn is_clip(case: &Case) -> bool {
    matches!(case.inverse().map(|i| &i.data), Some(cosserat::case::DataSource::Clip(_)))
}
