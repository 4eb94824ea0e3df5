//! A recording's noise level σ̂ [m] from its frames' own estimates ([`super::fit::noise_level_in`]):
//! their median (`docs/noise.md` N2; in the plane of a planar recording, N12).
use nalgebra::Vector3;

use super::fit::noise_level_in;

/// The noise level σ̂ of a recording [m]: the median of the frames' [`crate::recorded::fit::noise_level`].
pub fn recording_noise(frames: &[Vec<Vector3<f64>>]) -> f64 {
    recording_noise_in(frames, None)
}

/// [`recording_noise`] of a recording whose noise lies in the plane normal to `plane` (a planar
/// recording: the two coordinates that carry data, [`noise_level_in`]).
pub fn recording_noise_in(frames: &[Vec<Vector3<f64>>], plane: Option<&Vector3<f64>>) -> f64 {
    median_noise(frames.iter().map(|f| noise_level_in(f, plane)))
}

/// [`recording_noise_in`] of the frames' noise levels [m] (each [`noise_level_in`]), taken as
/// they come: their median, the non-finite ones left out; 0 where none is finite.
pub fn median_noise(levels: impl IntoIterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = levels.into_iter().filter(|v| v.is_finite()).collect();
    if v.is_empty() {
        return 0.0;
    }
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}
