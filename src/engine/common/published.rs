//! The published values of a case (`[[reference.values]]`, `case::published`) evaluated on a
//! run's result, the same for both engines: one [`PublishedRow`] per value, with the computed
//! number, its error and whether it is within the tolerance. `run` writes the rows to
//! `reference.csv` and `metrics.json` ([`metric_entries`]); [`unavailable`] refuses, before any
//! run, a quantity the case's analysis does not compute.

use nalgebra::Vector3;

use super::result::{NodalState, RunResult};
use crate::case::published::{NodeField, PublishedValue, Quantity};
use crate::case::{Analysis, Case, Reference};

use super::metric::{Metric, Metrics};

/// One published value against one run.
#[derive(Clone, Debug, PartialEq)]
pub struct PublishedRow {
    /// the quantity, as [`Quantity`] prints it
    pub quantity: String,
    pub unit: &'static str,
    pub published: f64,
    /// the run's value, or why it has none
    pub computed: Result<f64, ValueError>,
    /// `computed − published` (NaN without a computed value)
    pub error: f64,
    /// the largest |error| allowed, in the quantity's unit
    pub tolerance: f64,
    pub pass: bool,
    pub source: String,
}

impl PublishedRow {
    pub(crate) fn new(v: &PublishedValue, computed: Result<f64, ValueError>) -> Self {
        let tolerance = v.tolerance.bound(v.value);
        let error = computed.as_ref().map_or(f64::NAN, |c| c - v.value);
        // NaN fails: a value that is not a number is no agreement
        let pass = error.abs() <= tolerance;
        PublishedRow {
            quantity: v.quantity.to_string(),
            unit: v.quantity.unit(),
            published: v.value,
            computed,
            error,
            tolerance,
            pass,
            source: v.source.clone(),
        }
    }

    /// One line for the terminal: the quantity, both values, the error against the tolerance
    /// and the verdict (the source is in `reference.csv`).
    pub fn summary(&self) -> String {
        let u = self.unit;
        let verdict = if self.pass { "pass" } else { "MISS" };
        match &self.computed {
            Ok(c) => format!(
                "{}: computed {c:.6e} {u}, published {:.6e} {u}, error {:+.2e} {u}, tolerance {:.2e} {u}: {verdict}",
                self.quantity, self.published, self.error, self.tolerance
            ),
            Err(why) => {
                format!("{}: not computed ({why}), published {:.6e} {u}: {verdict}", self.quantity, self.published)
            }
        }
    }
}

/// The sources of `rows`, each once, in the order of the rows.
pub fn sources(rows: &[PublishedRow]) -> Vec<&str> {
    let mut out: Vec<&str> = Vec::new();
    for r in rows {
        if !out.contains(&r.source.as_str()) {
            out.push(&r.source);
        }
    }
    out
}

/// Every published value of `case` on the result `r` with its metrics `m`.
pub fn evaluate(case: &Case, r: &RunResult, m: &Metrics) -> Vec<PublishedRow> {
    case.checks.published.values.iter().map(|v| PublishedRow::new(v, value(&v.quantity, r, m))).collect()
}

/// Why a run has no value of a published quantity.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ValueError {
    #[error("the result has no nodes")]
    NoNodes,
    /// `node(s=S)` outside the rod's nodes `[first, last]` [m]
    #[error("s = {s_m} m lies outside the rod's nodes, [{first_m}, {last_m}] m")]
    OutsideRod { s_m: f64, first_m: f64, last_m: f64 },
    #[error("{key} is not in this run's metrics.json")]
    NotInMetrics { key: String },
}

/// The value of a quantity on a run: the evaluator of every family of the vocabulary.
pub fn value(q: &Quantity, r: &RunResult, m: &Metrics) -> Result<f64, ValueError> {
    match q {
        Quantity::Tip(field) => {
            let last = r.nodes.s.len().checked_sub(1).ok_or(ValueError::NoNodes)?;
            Ok(nodal(&r.nodes, *field, last))
        }
        Quantity::Node { s_m, field } => at_arc_length(&r.nodes, *field, *s_m),
        Quantity::Metric(key) => m.named(key).ok_or_else(|| ValueError::NotInMetrics { key: key.clone() }),
    }
}

/// A field at node `i`.
fn nodal(n: &NodalState, field: NodeField, i: usize) -> f64 {
    let vector = |v: Vector3<f64>, k: usize| v[k];
    match field {
        NodeField::Position(a) => vector(n.x[i], a.index()),
        NodeField::Displacement(a) => vector(n.displacement()[i], a.index()),
        NodeField::Angle(k) => vector(n.alpha[i], k),
    }
}

/// A field at reference arc length `s` [m], linear between the two nodes around it (P1, as the
/// discrete solution is).
pub fn at_arc_length(n: &NodalState, field: NodeField, s: f64) -> Result<f64, ValueError> {
    let (first, last) = (n.s.first().copied().unwrap_or(f64::NAN), n.s.last().copied().unwrap_or(f64::NAN));
    if !(first..=last).contains(&s) {
        return Err(ValueError::OutsideRod { s_m: s, first_m: first, last_m: last });
    }
    // the element [s_j, s_j+1] holding s (the last one for s = L)
    let j = n.s.partition_point(|&t| t <= s).clamp(1, n.s.len() - 1) - 1;
    let (a, b) = (n.s[j], n.s[j + 1]);
    let w = if b > a { (s - a) / (b - a) } else { 0.0 };
    Ok((1.0 - w) * nodal(n, field, j) + w * nodal(n, field, j + 1))
}

/// The rows as entries of `metrics.json`: `reference.<quantity>.published`, `.computed` (when
/// there is one), `.error`, `.tolerance`, `.pass` (1 or 0), and `reference.rows`,
/// `reference.missed`. Nothing without published values.
pub fn metric_entries(rows: &[PublishedRow]) -> Metrics {
    let mut m = Metrics::new();
    if rows.is_empty() {
        return m;
    }
    for r in rows {
        let key = |what: &str| format!("reference.{}.{what}", r.quantity);
        m.insert_named(key("published"), r.published);
        if let Ok(c) = r.computed {
            m.insert_named(key("computed"), c);
            m.insert_named(key("error"), r.error);
        }
        m.insert_named(key("tolerance"), r.tolerance);
        m.insert_named(key("pass"), f64::from(u8::from(r.pass)));
    }
    m.insert_named("reference.rows", rows.len() as f64);
    m.insert_named("reference.missed", rows.iter().filter(|r| !r.pass).count() as f64);
    m
}

/// The keys of `metrics.json` a single run of `case` writes in either engine
/// (`metrics::all_metrics`): physical values, the dynamic tip's extremes, an inverse run's
/// recovery errors and objective, the `[reference]` theory's errors, and solver statistics
/// (some of which one engine or analysis leaves out: such a row is then not computed).
pub fn metric_keys(case: &Case) -> Vec<String> {
    use Metric as M;
    let mut keys: Vec<Metric> = [Metric::TIP_POSITION, Metric::TIP_ANGLES, Metric::CENTROID].concat();
    match &case.analysis {
        Analysis::Static(crate::solve::statics::StaticParams { path: Some(_), .. }) => {
            keys.extend([M::FinalLoadFactor, M::PathPoints, M::LimitLoadFactor, M::BifurcationLoadFactor])
        }
        Analysis::Dynamic(_) => {
            keys.extend([M::TipMaxAbsX, M::TipMaxAbsY, M::TipMaxAbsBeta, M::TipMaxAbsGamma]);
            // the balance at the end time, and its change over the trailing unloaded steps (a
            // run whose last step is loaded has none: such a row is then not computed)
            keys.extend([M::KineticEnergy, M::ElasticEnergy]);
            keys.extend(Metric::MOMENTUM);
            keys.extend(Metric::ANGULAR_MOMENTUM);
            keys.extend([M::UnloadedFrom, M::UnloadedEnergyChangeRel, M::UnloadedMomentumChange]);
            keys.push(M::UnloadedAngularMomentumChange);
        }
        Analysis::Inverse(_) => {
            keys.extend([M::XErrRel, M::TangentMisfit, M::KappaErrRel, M::KappaErrRelInner]);
            keys.extend(Metric::OBJECTIVE);
            keys.extend([M::ForceL2, M::TorqueL2]);
        }
        Analysis::Static(_) => {}
    }
    let mut names = Vec::new();
    if let Analysis::Static(p) = &case.analysis {
        if super::dense_analyses_fit(case) {
            // `stable`: conservative loads only (D27)
            keys.extend([M::TangentSmallestEigenvalue, M::Stable]);
        }
        names.extend((1..=p.buckling_modes).map(|k| format!("buckling_{k}_load_factor")));
        names.extend((1..=p.vibration_modes).map(|k| format!("omega_{k}_rad_per_s")));
    }
    let mut after = Vec::new();
    if let Some(Reference::TipLoadedCantilever { .. }) = case.checks.reference {
        after.extend([M::Eq63TipY, M::Eq63RelError, M::ElasticaTipY, M::ElasticaRelError]);
        after.extend([M::ReissnerTipY, M::ReissnerRelError]);
    }
    after.extend([M::Iterations, M::LastChange, M::RelativeResidual, M::MaxNewtonIterations]);
    after.extend([M::Certificate, M::WallTime]);
    let text = |k: &[Metric]| k.iter().map(|k| k.as_str().to_string()).collect::<Vec<_>>();
    [text(&keys), names, text(&after)].concat()
}

/// Why `case` cannot check its published values, if it cannot: a `metric.KEY` that its run
/// does not write (checked before any folder is prepared or any solve starts).
pub fn unavailable(case: &Case) -> Option<String> {
    let keys = metric_keys(case);
    let file = case.origin.source.as_ref().map_or(format!("case {}", case.name), |p| p.display().to_string());
    case.checks.published.values.iter().enumerate().find_map(|(i, v)| match &v.quantity {
        Quantity::Metric(k) if !keys.contains(k) => Some(format!(
            "{file}: key `reference.values[{i}].quantity`: `{}`: a run of this case writes no metric `{k}` (its metrics.json holds: {})",
            v.quantity,
            keys.join(", ")
        )),
        _ => None,
    })
}
