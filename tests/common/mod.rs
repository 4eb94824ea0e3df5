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
