//! The natural frequencies of a static case's rod about its rest state from `freefem/modes.idp`
//! (D28): `ff_modes.csv` (a row per mode: the mode, its ω [rad/s]) read into the
//! [`StabilityOutput::omegas_rad_per_s`](crate::engine::common::result::StabilityOutput) the
//! Rust engine gives.
use std::path::Path;

use super::{read_table, FreeFemError};

/// The output `modes.idp` writes besides `forward.edp`'s.
pub const MODES_OUTPUT: &str = "ff_modes.csv";

/// The `count` lowest ω [rad/s] in `dir`, ascending; `None` when `modes.idp` did not run (a
/// result that did not converge). Fewer than `count` (ARPACK converged on fewer) is an error.
pub(super) fn read_modes(dir: &Path, count: usize) -> Result<Option<Vec<f64>>, FreeFemError> {
    let path = dir.join(MODES_OUTPUT);
    if count == 0 || !path.exists() {
        return Ok(None);
    }
    let rows = read_table(&path, &["mode", "omega_rad_per_s"])?;
    let bad = |reason: String| FreeFemError::BadOutput { path: path.clone(), reason };
    if rows.len() != count {
        return Err(bad(format!("{} modes, {count} asked for (solver.vibration_modes)", rows.len())));
    }
    let mut omegas = Vec::with_capacity(count);
    for (k, r) in rows.iter().enumerate() {
        if r[0] as usize != k + 1 || !(r[1].is_finite() && r[1] >= 0.0) {
            return Err(bad(format!("row {}: mode {}, omega {}", k + 1, r[0], r[1])));
        }
        if omegas.last().is_some_and(|&w| r[1] < w) {
            return Err(bad(format!("mode {}: omega {} below the previous mode's", k + 1, r[1])));
        }
        omegas.push(r[1]);
    }
    Ok(Some(omegas))
}
