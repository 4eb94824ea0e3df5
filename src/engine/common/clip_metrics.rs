//! Metrics of a whole clip run (the row of a clip in `cosserat sweep`'s summary and in the
//! audit): per-frame numbers of [`FrameReport`] reduced over the frames, with SI units in
//! their names.
use super::clip_summary::ClipRun;
use super::metric::{Metric, Metrics};
use crate::case::Case;
use crate::solve::sequence::FrameReport;

/// Median of `v` (NaN for an empty slice); non-finite values sort last.
fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn max(v: impl Iterator<Item = f64>) -> f64 {
    v.fold(0.0, f64::max)
}

/// The metrics of a clip run of `case`:
/// - `frames`, `iterations` (total), `iterations_mean`, `iterations_max`, `restarts`;
/// - `x_err_rel_max`, `x_err_rel_median` (`‖x − x_g‖/‖x_g‖`, I2);
/// - `tangent_misfit_rel_max`: `max ‖∂s x − d3‖/‖d3‖` over the frames, L² norms over the rod
///   (`‖d3‖ = √L`), the measure of the paper's Fig. 20;
/// - `max_abs_j_minus_1`: the data's stretch `|j − 1|` (Remark 9, Remark 12), max over frames;
/// - the objective terms of (41), median over the frames (`j_tracking_median`, …), and
///   `shear_share_median`: the median share of the λd term in the total (Fig. 18);
/// - `certificate`: the largest residual certificate of the frames (`docs/certificate.md`);
/// - the fit-quality gate (`solve::fit`): `flagged_frames`, `fit_position_rel_length_max`,
///   `fit_tangent_rms_max` and `data_noise_m_median` (the data's noise level [m]);
/// - `min_abs_cos_beta`: the angle chart's margin, min over frames;
/// - `kappa_roughness_mean`, `data_kappa_roughness_mean` (sign alternation, D13);
/// - synthetic clips, against the ground truth (max over frames): `truth_x_err_rel_max`,
///   `truth_bending_err_rel_max`, `truth_tangent_angle_max_rad`, `truth_twist_rms_err_max_per_m`;
/// - `wall_time_s`.
pub fn clip_metrics(case: &Case, run: &ClipRun) -> Metrics {
    let r: &[FrameReport] = &run.reports;
    let mut m = Metrics::new();
    let n = r.len();
    m.insert(Metric::Frames, n as f64);
    let its: Vec<f64> = r.iter().map(|f| f.convergence.iterations as f64).collect();
    m.insert(Metric::Iterations, its.iter().sum());
    m.insert(Metric::IterationsMean, its.iter().sum::<f64>() / n.max(1) as f64);
    m.insert(Metric::IterationsMax, max(its.iter().copied()));
    m.insert(Metric::Restarts, r.iter().filter(|f| f.restarted).count() as f64);
    m.insert(Metric::XErrRelMax, max(r.iter().map(|f| f.misfit.x_err_rel)));
    m.insert(Metric::XErrRelMedian, median(r.iter().map(|f| f.misfit.x_err_rel).collect()));
    let d3_norm = case.mesh.length_m.sqrt();
    m.insert(Metric::TangentMisfitRelMax, max(r.iter().map(|f| f.misfit.tangent_misfit / d3_norm)));
    m.insert(Metric::MaxAbsJMinus1, max(r.iter().map(|f| f.conditioning.max_stretch_deviation)));
    m.insert(Metric::Certificate, max(r.iter().map(|f| f.certificate)));
    m.insert(Metric::FlaggedFrames, r.iter().filter(|f| f.fit.flagged).count() as f64);
    m.insert(Metric::FitPositionRelLengthMax, max(r.iter().map(|f| f.fit.position)));
    m.insert(Metric::FitTangentRmsMax, max(r.iter().map(|f| f.fit.tangent)));
    m.insert(Metric::DataNoiseMedian, median(r.iter().map(|f| f.fit.noise_m).collect()));
    m.insert(Metric::MinAbsCosBeta, r.iter().map(|f| f.conditioning.min_cos_beta).fold(f64::INFINITY, f64::min));
    let terms = |f: &FrameReport| {
        let o = &f.misfit.objective;
        [o.tracking, o.force, o.torque, o.shear, o.bending, o.angular, o.total()]
    };
    for (k, key) in Metric::OBJECTIVE_MEDIAN.into_iter().enumerate() {
        m.insert(key, median(r.iter().map(|f| terms(f)[k]).collect()));
    }
    m.insert(
        Metric::ShearShareMedian,
        median(r.iter().map(|f| f.misfit.objective.shear / f.misfit.objective.total()).collect()),
    );
    let mean = |v: &mut dyn Iterator<Item = f64>| {
        let (s, c) = v.fold((0.0, 0usize), |(s, c), x| (s + x, c + 1));
        s / c.max(1) as f64
    };
    m.insert(Metric::KappaRoughnessMean, mean(&mut run.roughness.iter().map(|r| r.0)));
    m.insert(Metric::DataKappaRoughnessMean, mean(&mut run.roughness.iter().map(|r| r.1)));
    if let Some(t) = &run.truth {
        let c = &t.comparisons;
        m.insert(Metric::TruthXErrRelMax, max(c.iter().map(|c| c.position_rel_l2)));
        m.insert(Metric::TruthBendingErrRelMax, max(c.iter().map(|c| c.bending_rel_l2)));
        m.insert(Metric::TruthTangentAngleMax, max(c.iter().map(|c| c.max_tangent_angle_rad)));
        m.insert(Metric::TruthTwistRmsErrMax, max(c.iter().map(|c| c.twist_rms_error_per_m)));
    }
    m.insert(Metric::WallTime, run.wall_time_s);
    m
}

#[cfg(test)]
mod tests {
    use super::median;

    #[test]
    fn median_of_odd_and_even_lengths() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(Vec::new()).is_nan());
    }
}
