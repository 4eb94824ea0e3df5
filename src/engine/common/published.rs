//! The published values of a case (`[[reference.values]]`, `case::published`) evaluated on a
//! run's result, the same for both engines: one [`PublishedRow`] per value, with the computed
//! number, its error and whether it is within the tolerance. `run` writes the rows to
//! `reference.csv` and `metrics.json` ([`metric_entries`]); [`unavailable`] refuses, before any
//! run, a quantity the case's analysis does not compute.
use std::collections::BTreeMap;

use nalgebra::Vector3;

use super::result::{NodalState, RunResult};
use crate::case::published::{NodeField, PublishedValue, Quantity};
use crate::case::{Analysis, Case, Reference};
use crate::solve::inverse::ObjectiveTerms;

/// Metric name → value, as `metrics.json` (`super::metrics::Metrics`, named here so that the
/// metrics may use this module).
type Metrics = BTreeMap<String, f64>;

/// One published value against one run.
#[derive(Clone, Debug, PartialEq)]
pub struct PublishedRow {
    /// the quantity, as [`Quantity`] prints it
    pub quantity: String,
    pub unit: &'static str,
    pub published: f64,
    /// the run's value, or why it has none
    pub computed: Result<f64, String>,
    /// `computed − published` (NaN without a computed value)
    pub error: f64,
    /// the largest |error| allowed, in the quantity's unit
    pub tolerance: f64,
    pub pass: bool,
    pub source: String,
}

impl PublishedRow {
    pub(crate) fn new(v: &PublishedValue, computed: Result<f64, String>) -> Self {
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

/// The value of a quantity on a run: the evaluator of every family of the vocabulary.
pub fn value(q: &Quantity, r: &RunResult, m: &Metrics) -> Result<f64, String> {
    match q {
        Quantity::Tip(field) => {
            let last = r.nodes.s.len().checked_sub(1).ok_or("the result has no nodes")?;
            Ok(nodal(&r.nodes, *field, last))
        }
        Quantity::Node { s_m, field } => at_arc_length(&r.nodes, *field, *s_m),
        Quantity::Metric(key) => m.get(key).copied().ok_or_else(|| format!("{key} is not in this run's metrics.json")),
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
pub fn at_arc_length(n: &NodalState, field: NodeField, s: f64) -> Result<f64, String> {
    let (first, last) = (n.s.first().copied().unwrap_or(f64::NAN), n.s.last().copied().unwrap_or(f64::NAN));
    if !(first..=last).contains(&s) {
        return Err(format!("s = {s} m lies outside the rod's nodes, [{first}, {last}] m"));
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
        m.insert(key("published"), r.published);
        if let Ok(c) = r.computed {
            m.insert(key("computed"), c);
            m.insert(key("error"), r.error);
        }
        m.insert(key("tolerance"), r.tolerance);
        m.insert(key("pass"), f64::from(u8::from(r.pass)));
    }
    m.insert("reference.rows".into(), rows.len() as f64);
    m.insert("reference.missed".into(), rows.iter().filter(|r| !r.pass).count() as f64);
    m
}

/// The keys of `metrics.json` a single run of `case` writes in either engine
/// (`metrics::all_metrics`): physical values, the dynamic tip's extremes, an inverse run's
/// recovery errors and objective, the `[reference]` theory's errors, and solver statistics
/// (some of which one engine or analysis leaves out: such a row is then not computed).
pub fn metric_keys(case: &Case) -> Vec<String> {
    let mut keys: Vec<String> = ["x", "y", "z"].iter().map(|c| format!("tip_{c}_m")).collect();
    keys.extend(["alpha", "beta", "gamma"].iter().map(|a| format!("tip_{a}_rad")));
    keys.extend(["x", "y", "z"].iter().map(|c| format!("centroid_{c}_m")));
    match &case.analysis {
        Analysis::Static(crate::solve::statics::StaticParams { path: Some(_), .. }) => keys.extend(
            ["final_load_factor", "path_points", "limit_load_factor", "bifurcation_load_factor"].map(String::from),
        ),
        Analysis::Dynamic(_) => keys.extend(
            ["tip_max_abs_x_m", "tip_max_abs_y_m", "tip_max_abs_beta_rad", "tip_max_abs_gamma_rad"].map(String::from),
        ),
        Analysis::Inverse(_) => {
            keys.extend(["x_err_rel", "tangent_misfit_m05", "kappa_err_rel", "kappa_err_rel_inner"].map(String::from));
            keys.extend(ObjectiveTerms::NAMES.iter().map(|n| n.to_string()));
            keys.extend(["force_l2_n_per_m05", "torque_l2_n_m05"].map(String::from));
        }
        Analysis::Static(_) => {}
    }
    if let Analysis::Static(p) = &case.analysis {
        if super::dense_analyses_fit(case) {
            // `stable`: conservative loads only (D27)
            keys.extend(["tangent_smallest_eigenvalue_per_s2", "stable"].map(String::from));
        }
        keys.extend((1..=p.buckling_modes).map(|k| format!("buckling_{k}_load_factor")));
    }
    if let Some(Reference::TipLoadedCantilever { .. }) = case.checks.reference {
        for name in ["eq63", "elastica", "reissner"] {
            keys.extend([format!("{name}_tip_y_m"), format!("{name}_rel_error")]);
        }
    }
    let stats =
        ["iterations", "last_change", "relative_residual", "max_newton_iterations", "certificate", "wall_time_s"];
    keys.extend(stats.map(String::from));
    keys
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
