//! The keys of a run's metrics ([`Metric`]) and the metrics themselves ([`Metrics`]): a map
//! from a key's name to its value, written as `metrics.json` (names with their SI units,
//! sorted), read in code by a [`Metric`] so that a misspelt key does not compile. Names made at
//! run time (a buckling mode's `buckling_{k}_load_factor`, the published values'
//! `reference.…`, the audit's derived metrics) go in by [`Metrics::insert_named`]; names read
//! from a file (an audit spec's metric, a published `metric.KEY`) come out by
//! [`Metrics::named`].
use std::collections::BTreeMap;

/// Declares [`Metric`]: each variant with its name in `metrics.json`.
macro_rules! metric_keys {
    ($($(#[$doc:meta])* $variant:ident => $name:literal,)*) => {
        /// A metric computed here, by the name it has in `metrics.json`.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Metric {
            $($(#[$doc])* $variant,)*
        }

        impl Metric {
            /// Every key, in the order declared.
            pub const ALL: &'static [Metric] = &[$(Metric::$variant,)*];

            /// The key's name in `metrics.json` and the summaries.
            pub fn as_str(self) -> &'static str {
                match self {
                    $(Metric::$variant => $name,)*
                }
            }
        }
    };
}

metric_keys! {
    // a run's tip and centreline (`metrics::physical_metrics`)
    TipX => "tip_x_m",
    TipY => "tip_y_m",
    TipZ => "tip_z_m",
    TipAlpha => "tip_alpha_rad",
    TipBeta => "tip_beta_rad",
    TipGamma => "tip_gamma_rad",
    TipMaxAbsX => "tip_max_abs_x_m",
    TipMaxAbsY => "tip_max_abs_y_m",
    TipMaxAbsBeta => "tip_max_abs_beta_rad",
    TipMaxAbsGamma => "tip_max_abs_gamma_rad",
    CentroidX => "centroid_x_m",
    CentroidY => "centroid_y_m",
    CentroidZ => "centroid_z_m",
    // a dynamic run's energy and momenta (`metrics::balance_metrics`): at the end time, and their
    // largest change over the trailing steps in which no load acts and no end moves
    /// [J]
    KineticEnergy => "kinetic_energy_j",
    /// [J]
    ElasticEnergy => "elastic_energy_j",
    MomentumX => "momentum_x_n_s",
    MomentumY => "momentum_y_n_s",
    MomentumZ => "momentum_z_n_s",
    /// about the origin
    AngularMomentumX => "angular_momentum_x_n_m_s",
    AngularMomentumY => "angular_momentum_y_n_m_s",
    AngularMomentumZ => "angular_momentum_z_n_m_s",
    /// the start of the trailing unloaded steps [s]
    UnloadedFrom => "unloaded_from_s",
    /// `max |E(t) − E(t₀)| / E(t₀)` over them, `E = T + V`
    UnloadedEnergyChangeRel => "unloaded_energy_change_rel",
    /// `max |p(t) − p(t₀)|` over them [N s] (conserved where no end is held)
    UnloadedMomentumChange => "unloaded_momentum_change_n_s",
    /// `max |h(t) − h(t₀)|` over them [N m s] (conserved where no end is held)
    UnloadedAngularMomentumChange => "unloaded_angular_momentum_change_n_m_s",
    // a static state's stability and an arc-length path (D25, D27)
    /// `min Re ω²` of the tangent against the mass [1/s²]
    TangentSmallestEigenvalue => "tangent_smallest_eigenvalue_per_s2",
    /// 1 stable, 0 not (conservative loads only)
    Stable => "stable",
    FinalLoadFactor => "final_load_factor",
    PathPoints => "path_points",
    LimitLoadFactor => "limit_load_factor",
    BifurcationLoadFactor => "bifurcation_load_factor",
    // an inverse run (`metrics::inverse_metrics`) and the objective's terms (41)
    XErrRel => "x_err_rel",
    TangentMisfit => "tangent_misfit_m05",
    KappaErrRel => "kappa_err_rel",
    KappaErrRelInner => "kappa_err_rel_inner",
    ForceL2 => "force_l2_n_per_m05",
    TorqueL2 => "torque_l2_n_m05",
    JTracking => "j_tracking",
    JForce => "j_force",
    JTorque => "j_torque",
    JShear => "j_shear",
    JBending => "j_bending",
    JAngular => "j_angular",
    JTotal => "j_total",
    // the independent theories of a `[reference]` (`metrics::reference_metrics`)
    Eq63TipY => "eq63_tip_y_m",
    Eq63RelError => "eq63_rel_error",
    ElasticaTipY => "elastica_tip_y_m",
    ElasticaRelError => "elastica_rel_error",
    ReissnerTipY => "reissner_tip_y_m",
    ReissnerRelError => "reissner_rel_error",
    // the solver (`metrics::all_metrics`; a clip's: its frames' total)
    Iterations => "iterations",
    LastChange => "last_change",
    RelativeResidual => "relative_residual",
    MaxNewtonIterations => "max_newton_iterations",
    /// the residual certificate (a clip: the largest of its frames)
    Certificate => "certificate",
    /// [s]
    WallTime => "wall_time_s",
    // a clip (`clip_metrics::clip_metrics`)
    Frames => "frames",
    IterationsMean => "iterations_mean",
    IterationsMax => "iterations_max",
    Restarts => "restarts",
    XErrRelMax => "x_err_rel_max",
    XErrRelMedian => "x_err_rel_median",
    TangentMisfitRelMax => "tangent_misfit_rel_max",
    MaxAbsJMinus1 => "max_abs_j_minus_1",
    FlaggedFrames => "flagged_frames",
    FitPositionRelLengthMax => "fit_position_rel_length_max",
    FitTangentRmsMax => "fit_tangent_rms_max",
    DataNoiseMedian => "data_noise_m_median",
    MinAbsCosBeta => "min_abs_cos_beta",
    JTrackingMedian => "j_tracking_median",
    JForceMedian => "j_force_median",
    JTorqueMedian => "j_torque_median",
    JShearMedian => "j_shear_median",
    JBendingMedian => "j_bending_median",
    JAngularMedian => "j_angular_median",
    JTotalMedian => "j_total_median",
    ShearShareMedian => "shear_share_median",
    KappaRoughnessMean => "kappa_roughness_mean",
    DataKappaRoughnessMean => "data_kappa_roughness_mean",
    TruthXErrRelMax => "truth_x_err_rel_max",
    TruthBendingErrRelMax => "truth_bending_err_rel_max",
    TruthTangentAngleMax => "truth_tangent_angle_max_rad",
    TruthTwistRmsErrMax => "truth_twist_rms_err_max_per_m",
}

impl Metric {
    /// The tip's position x, y, z [m].
    pub const TIP_POSITION: [Metric; 3] = [Metric::TipX, Metric::TipY, Metric::TipZ];
    /// The tip's angles α, β, γ [rad].
    pub const TIP_ANGLES: [Metric; 3] = [Metric::TipAlpha, Metric::TipBeta, Metric::TipGamma];
    /// The centreline's mean position x, y, z [m].
    pub const CENTROID: [Metric; 3] = [Metric::CentroidX, Metric::CentroidY, Metric::CentroidZ];
    /// The linear momentum [N s] at the end time.
    pub const MOMENTUM: [Metric; 3] = [Metric::MomentumX, Metric::MomentumY, Metric::MomentumZ];
    /// The angular momentum about the origin [N m s] at the end time.
    pub const ANGULAR_MOMENTUM: [Metric; 3] =
        [Metric::AngularMomentumX, Metric::AngularMomentumY, Metric::AngularMomentumZ];
    /// The objective's terms, in the order of `ObjectiveTerms::NAMES`.
    pub const OBJECTIVE: [Metric; 7] = [
        Metric::JTracking,
        Metric::JForce,
        Metric::JTorque,
        Metric::JShear,
        Metric::JBending,
        Metric::JAngular,
        Metric::JTotal,
    ];
    /// The objective's terms of a clip, median over its frames (as [`Metric::OBJECTIVE`]).
    pub const OBJECTIVE_MEDIAN: [Metric; 7] = [
        Metric::JTrackingMedian,
        Metric::JForceMedian,
        Metric::JTorqueMedian,
        Metric::JShearMedian,
        Metric::JBendingMedian,
        Metric::JAngularMedian,
        Metric::JTotalMedian,
    ];
}

impl std::fmt::Display for Metric {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A run's metrics: name → value (`metrics.json`, its keys sorted by name). Names carry SI
/// units.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
pub struct Metrics(BTreeMap<String, f64>);

impl Metrics {
    pub fn new() -> Self {
        Metrics::default()
    }
    pub fn insert(&mut self, key: Metric, value: f64) {
        self.0.insert(key.as_str().to_string(), value);
    }
    pub fn get(&self, key: Metric) -> Option<f64> {
        self.0.get(key.as_str()).copied()
    }
    pub fn contains(&self, key: Metric) -> bool {
        self.0.contains_key(key.as_str())
    }
    /// A metric whose name is made at run time (not a [`Metric`]).
    pub fn insert_named(&mut self, name: impl Into<String>, value: f64) {
        self.0.insert(name.into(), value);
    }
    /// A metric by a name read from a file (an audit spec, a published `metric.KEY`).
    pub fn named(&self, name: &str) -> Option<f64> {
        self.0.get(name).copied()
    }
    /// Every metric, sorted by name.
    pub fn iter(&self) -> impl Iterator<Item = (&str, f64)> + '_ {
        self.0.iter().map(|(k, v)| (k.as_str(), *v))
    }
    pub fn names(&self) -> impl Iterator<Item = &str> + '_ {
        self.0.keys().map(String::as_str)
    }
    pub fn len(&self) -> usize {
        self.0.len()
    }
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
    /// Add (or replace) every metric of `other`.
    pub fn extend(&mut self, other: Metrics) {
        self.0.extend(other.0);
    }
}

impl std::ops::Index<Metric> for Metrics {
    type Output = f64;

    /// The value of `key`; panics when the run has none (as a map's index).
    fn index(&self, key: Metric) -> &f64 {
        &self.0[key.as_str()]
    }
}

impl IntoIterator for Metrics {
    type Item = (String, f64);
    type IntoIter = std::collections::btree_map::IntoIter<String, f64>;

    /// Every metric, sorted by name.
    fn into_iter(self) -> Self::IntoIter {
        self.0.into_iter()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::inverse::ObjectiveTerms;

    #[test]
    fn names_are_distinct_and_the_objective_in_order() {
        let names: std::collections::BTreeSet<_> = Metric::ALL.iter().map(|m| m.as_str()).collect();
        assert_eq!(names.len(), Metric::ALL.len());
        for (k, name) in ObjectiveTerms::NAMES.iter().enumerate() {
            assert_eq!(Metric::OBJECTIVE[k].as_str(), *name);
            assert_eq!(Metric::OBJECTIVE_MEDIAN[k].as_str(), format!("{name}_median"));
        }
    }

    #[test]
    fn serialised_as_a_sorted_map() {
        let mut m = Metrics::new();
        m.insert(Metric::WallTime, 1.5);
        m.insert_named("buckling_1_load_factor", 2.0);
        m.insert(Metric::Certificate, 0.5);
        let json = serde_json::to_string(&m).unwrap();
        assert_eq!(json, r#"{"buckling_1_load_factor":2.0,"certificate":0.5,"wall_time_s":1.5}"#);
        assert_eq!(serde_json::from_str::<Metrics>(&json).unwrap(), m);
    }
}
