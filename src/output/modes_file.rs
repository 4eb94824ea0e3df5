//! `modes.csv`: the natural frequencies of a static case's rod about its rest state
//! (`solver.vibration_modes`, D28), one row per mode, the same from either engine.
use crate::engine::StabilityOutput;
use crate::io::files::csv_text_int;

/// `modes.csv`: the mode (1, 2, …, ascending; a double frequency, as a round section's bending
/// ones, takes two rows), its circular frequency ω [rad/s], its frequency f = ω/2π [Hz] and its
/// period 1/f [s].
pub fn modes_csv(st: &StabilityOutput) -> String {
    let h = ["mode", "omega_rad_per_s", "frequency_hz", "period_s"];
    let rows = st.omegas_rad_per_s.iter().enumerate().map(|(k, &w)| {
        let f = w / (2.0 * std::f64::consts::PI);
        vec![Some((k + 1) as f64), Some(w), Some(f), Some(1.0 / f)]
    });
    csv_text_int(&h, &["mode"], rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ω = 2π rad/s is 1 Hz and a period of 1 s; the header carries the units.
    #[test]
    fn one_row_per_mode_with_its_frequency_and_period() {
        let st = StabilityOutput { omegas_rad_per_s: vec![2.0 * std::f64::consts::PI, 4.0], ..Default::default() };
        let text = modes_csv(&st);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "mode,omega_rad_per_s,frequency_hz,period_s");
        let row: Vec<f64> = lines[1].split(',').map(|v| v.parse().unwrap()).collect();
        assert_eq!(row[0], 1.0);
        assert!((row[2] - 1.0).abs() < 1e-15 && (row[3] - 1.0).abs() < 1e-15);
        let row: Vec<f64> = lines[2].split(',').map(|v| v.parse().unwrap()).collect();
        assert!((row[2] * row[3] - 1.0).abs() < 1e-15 && (row[1] / row[2] - 2.0 * std::f64::consts::PI).abs() < 1e-14);
        assert_eq!(lines.len(), 3);
    }
}
