//! The §6 rows against the substitute's ground truth (`cases/worm_roll_3d.toml`: its generator,
//! `clip::synthetic`, knows the frames and curvatures that made the centrelines; `truth.csv`
//! of a clip point holds them per frame). Where the paper's sentence is about the
//! reconstruction, the row shows how far the recovered state is from the truth, and where the
//! sentence is about recovering the worm's state, the verdict uses it (the check `with_truth`,
//! `super::check`).
//!
//! The measures of a clip point with a ground truth ([`truth_metrics`]):
//! - `truth_bending_err_rel_mean`: the mean over the frames of `‖b − b_true‖/‖b_true‖`,
//!   `b = κ1² + κ2²` per node without the end nodes (`clip::synthetic::FrameComparison`);
//! - `truth_twist_err_rel`: the RMS over frames and nodes of `κ3 − κ3_true` over the RMS of
//!   the true twist `κ3_true` (1: an error the size of the twist itself);
//! - the bending wave (`super::wave`) of the truth's kymograph `√b_true(s, t)`:
//!   `truth_bending_wave_head_to_tail_share`, `truth_bending_wave_tail_to_head_share`,
//!   `truth_bending_wave_speed_body_per_s`, `truth_bending_wave_clarity`, and
//!   `bending_wave_truth_agreement`: the share of windows in which the recovered `√b(s, t)` at
//!   the same nodes runs the truth's way (both none counts as agreeing).
use super::wave::{propagation, Direction, Propagation};
use crate::clip::synthetic::FrameComparison;
use crate::engine::metrics::Metrics;

/// Per-frame series of a clip point with a ground truth (recorded with `super::measures::ClipSeries`).
#[derive(Clone, Debug, Default)]
pub struct TruthSeries {
    /// per frame: the true and the recovered bending `κ1² + κ2²` per node [1/m²]
    pub bending_true: Vec<Vec<f64>>,
    pub bending_recovered: Vec<Vec<f64>>,
    /// per frame: the comparison of the recovered frame with the truth
    pub comparisons: Vec<FrameComparison>,
    /// per frame: the true twist κ3, mean over the nodes [rad/m]
    pub twist_per_m: Vec<f64>,
}

/// The bending waves of the truth and of the reconstruction at the nodes, `√b(s, t)`.
pub fn bending_waves(t: &TruthSeries) -> Option<(Propagation, Propagation)> {
    let n = t.bending_true.first()?.len();
    if n < 2 {
        return None;
    }
    let s: Vec<f64> = (0..n).map(|i| i as f64 / (n - 1) as f64).collect();
    let root =
        |k: &[Vec<f64>]| k.iter().map(|r| r.iter().map(|b| b.max(0.0).sqrt()).collect()).collect::<Vec<Vec<f64>>>();
    Some((propagation(&root(&t.bending_true), &s), propagation(&root(&t.bending_recovered), &s)))
}

/// The measures of the module documentation; `dt_s` the time between frames [s].
pub fn truth_metrics(t: &TruthSeries, dt_s: f64) -> Metrics {
    let mut m = Metrics::new();
    let n = t.comparisons.len();
    if n == 0 {
        return m;
    }
    let mean = |f: &dyn Fn(&FrameComparison) -> f64| t.comparisons.iter().map(f).sum::<f64>() / n as f64;
    m.insert_named("truth_bending_err_rel_mean", mean(&|c| c.bending_rel_l2));
    let err = mean(&|c| c.twist_rms_error_per_m.powi(2)).sqrt();
    let twist = (t.twist_per_m.iter().map(|x| x * x).sum::<f64>() / t.twist_per_m.len().max(1) as f64).sqrt();
    if twist > 0.0 {
        m.insert_named("truth_twist_err_rel", err / twist);
    }
    if let Some((truth, recovered)) = bending_waves(t).filter(|(w, _)| !w.windows.is_empty()) {
        m.insert_named("truth_bending_wave_head_to_tail_share", truth.share(Direction::HeadToTail));
        m.insert_named("truth_bending_wave_tail_to_head_share", truth.share(Direction::TailToHead));
        m.insert_named("truth_bending_wave_clarity", truth.clarity());
        if let Some(v) = truth.median_speed_body_per_frame() {
            m.insert_named("truth_bending_wave_speed_body_per_s", v / dt_s);
        }
        m.insert_named("bending_wave_truth_agreement", recovered.agreement(&truth));
    }
    m
}
